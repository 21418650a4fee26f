//! The pose graph's redraw ([`super::graph::KeyframeGraph::redraw`]) on the furnished room of
//! [`super::tests`]: what only the scans between keyframes saw is kept, at one observation's
//! evidence, and nothing the keyframes draw is changed.

use super::HitMap;
use super::graph::{GraphConfig, KeyframeGraph};
use super::tests::{config, matcher, room, scan_at};
use crate::geometry::Pose2;
use crate::grid::{CellClass, LogOddsBounds, OccupancyGrid};
use crate::sensor::{LaserConfig, SensorModel, integrate_scan_banded};

/// The room's 90 x 70 cells.
const CELLS: usize = 90 * 70;

#[test]
fn a_redraw_keeps_what_only_the_scans_between_keyframes_saw() {
    let (walls, geometry) = room();
    let laser = LaserConfig::lms1xx();
    let sensor = SensorModel::default();
    let bounds = LogOddsBounds::default();
    let graph_config = GraphConfig {
        enabled: true,
        ..GraphConfig::default()
    };
    let mut graph: Box<KeyframeGraph<8, 16>> = bytemuck::zeroed_box();
    let mut m = matcher();
    // The keyframe looks west from the room's west half; its 270° leave the east wall behind
    // it. A scan after it (not a keyframe: the graph never sees it) looks at the east wall.
    let keyframe = Pose2::new(1.5, 3.0, core::f32::consts::PI);
    let between = Pose2::new(7.5, 2.0, 0.0);
    let keyframe_scan = scan_at(&walls, keyframe, &laser, 0.0, 1);
    let between_scan = scan_at(&walls, between, &laser, 0.0, 2);
    let moved = graph.on_scan(
        &graph_config,
        &config(),
        &keyframe_scan,
        &laser,
        &sensor,
        bounds,
        0.1,
        keyframe,
        &mut m,
    );
    assert!(moved.is_none());
    assert_eq!(graph.keyframes().len(), 1);

    let mut before = OccupancyGrid::<CELLS>::new(geometry, bounds).unwrap();
    for (scan, pose) in [(&keyframe_scan, keyframe), (&between_scan, between)] {
        integrate_scan_banded(&mut before, scan, pose, 0.0, &laser, &sensor, &mut ()).unwrap();
    }
    let mut hits = HitMap::<CELLS>::new_boxed(geometry);
    let redraw = |graph: &mut KeyframeGraph<8, 16>, hits: &mut HitMap<CELLS>, keep: bool| {
        let mut grid = before.clone();
        let mut scratch = [0i8; CELLS];
        graph
            .redraw(
                &mut grid,
                hits,
                0.0,
                &laser,
                &sensor,
                keep.then_some(&mut scratch[..]),
            )
            .unwrap();
        grid
    };
    let forgetting = redraw(&mut graph, &mut hits, false);
    let keeping = redraw(&mut graph, &mut hits, true);

    let mut kept = 0;
    for i in 0..geometry.cell_count() {
        let (old, new) = (before.class(i), forgetting.class(i));
        if new != CellClass::Unknown {
            // What the keyframe draws is the keyframe's, carried or not.
            assert_eq!(
                keeping.log_odds_at(i),
                forgetting.log_odds_at(i),
                "cell {i}"
            );
        } else if old != CellClass::Unknown {
            // Seen only between keyframes: its class kept, one observation's evidence.
            assert_eq!(keeping.class(i), old, "cell {i}");
            let one = match old {
                CellClass::Free => sensor.free_log_odds,
                _ => sensor.occupied_log_odds,
            };
            assert_eq!(keeping.log_odds_at(i), one, "cell {i}");
            kept += 1;
        } else {
            assert_eq!(keeping.class(i), CellClass::Unknown, "cell {i}");
        }
    }
    // The east strip behind the keyframe: a few square metres, its wall among them.
    assert!(kept > 300, "{kept} cells kept");
    let east_wall = geometry
        .index(
            geometry
                .cell_at(crate::geometry::Point2::new(8.5, 3.0))
                .unwrap(),
        )
        .unwrap();
    assert_eq!(forgetting.class(east_wall), CellClass::Unknown);
    assert_eq!(keeping.class(east_wall), CellClass::Occupied);
}
