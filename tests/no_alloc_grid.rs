//! Integrating scans, tracing rays and finding frontiers allocate nothing: a counting global
//! allocator watches the thread doing the work.

mod alloc_count;

use std::ops::ControlFlow;

use alloc_count::allocations_in;
use papillon::frontier::{FrontierConfig, FrontierWorkspace, find_frontiers};
use papillon::geometry::{Point2, Pose2};
use papillon::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::random::{range_f32, seeded};
use papillon::raycast::traverse;
use papillon::sensor::{Beam, LaserConfig, Scan, SensorModel, integrate_scan};

#[test]
fn integrating_scans_tracing_rays_and_finding_frontiers_allocate_nothing() {
    const CELLS: usize = 240 * 240;
    let geom = GridGeometry::new(240, 240, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(geom, LogOddsBounds::default()).unwrap();
    let mut frontiers = FrontierWorkspace::<8192, 256>::new_boxed();
    let laser = LaserConfig::thesis();
    let model = SensorModel::default();
    let mut rng = seeded(9);
    let mut scans = Vec::new();
    for _ in 0..20 {
        let mut scan = Scan::new();
        for i in 0..laser.beam_count as usize {
            let r = range_f32(&mut rng, 0.1, 5.0);
            scan.push(Beam {
                angle_rad: laser.beam_angle(i),
                range_m: (r < 4.8).then_some(r),
            })
            .unwrap();
        }
        let pose = Pose2::new(
            range_f32(&mut rng, 6.0, 18.0),
            range_f32(&mut rng, 6.0, 18.0),
            range_f32(&mut rng, -3.0, 3.0),
        );
        scans.push((scan, pose));
    }

    let mut known = 0;
    let mut traced = 0;
    let mut frontier_count = 0;
    let ((), n) = allocations_in(|| {
        for (scan, pose) in &scans {
            let r = integrate_scan(&mut grid, scan, *pose, &laser, &model, &mut ()).unwrap();
            known += r.newly_known;
            let t = traverse(
                grid.geometry(),
                pose.position(),
                Point2::new(0.0, 0.0),
                |_, _| ControlFlow::Continue(()),
            );
            traced += t.visited;
        }
        let found = find_frontiers(
            &grid,
            Point2::new(12.0, 12.0),
            &FrontierConfig::default(),
            &mut frontiers,
        )
        .unwrap();
        frontier_count = found.len();
    });
    assert_eq!(n, 0, "allocations while integrating scans");
    assert!(known > 1000, "{known} cells learnt");
    assert_eq!(known, grid.counts().known());
    assert!(traced > 100);
    assert!(frontier_count > 0);
}
