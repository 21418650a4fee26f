//! Regenerates the mid-mission House snapshot `fixtures/house-mid-mission.{yaml,pgm}` that the
//! exploration tests and `benches/explore.rs` load.
//!
//! The project's own `house` world (24 m x 24 m, rooms, doors and corridors, about 27 %
//! occupied, like the thesis's House map) is drawn at 10 cm cells (a 240 x 240 grid); cells
//! within 6 m of the robot at (1.5 m, 1.5 m) are known with their true class, the rest
//! Unknown, as after the first scans of a mission.
//!
//! Run from the project root:
//! `cargo run -p papillon-sim --example house_snapshot -- fixtures/house-mid-mission.yaml`

use std::path::Path;

use papillon::geometry::Point2;
use papillon::grid::{CellClass, LogOddsBounds, OccupancyGrid};
use papillon::mapfile::write_map;
use papillon_sim::world::World;

const CELLS: usize = 240 * 240;
/// Robot position of the snapshot \[m\].
const ROBOT: Point2 = Point2::new(1.5, 1.5);
/// Radius of the known disc around the robot \[m\].
const KNOWN_RADIUS_M: f32 = 6.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, yaml] = args.as_slice() else {
        return Err("usage: house_snapshot <out.yaml>".into());
    };
    let world = World::load("house", 0.1)?;
    let g = *world.geometry();
    if g.cell_count() != CELLS {
        return Err(format!(
            "the house world has {} cells, expected {CELLS}",
            g.cell_count()
        )
        .into());
    }
    if world.disc_hits_blocked(ROBOT, 0.25) {
        return Err(format!("the snapshot's robot position {ROBOT:?} is inside a wall").into());
    }
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(g, LogOddsBounds::default())?;
    for i in 0..g.cell_count() {
        let c = g.cell(i);
        if g.cell_center(c).distance(ROBOT) <= KNOWN_RADIUS_M {
            let class = if world.is_blocked_index(i) {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            grid.set_class(i, class, &mut ());
        }
    }
    write_map(&grid, Path::new(yaml))?;
    println!(
        "wrote {yaml}: {} known of {} cells",
        grid.counts().known(),
        g.cell_count()
    );
    Ok(())
}
