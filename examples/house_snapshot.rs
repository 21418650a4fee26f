//! Regenerates the mid-mission House snapshot `fixtures/house-mid-mission.{yaml,pgm}` that the
//! exploration tests and `benches/explore.rs` load.
//!
//! The thesis's House map (`map-house.csv`: 24 x 24 one-metre blocks, `1` = wall, row 0 north)
//! is drawn at 10 cm cells (a 240 x 240 grid); cells within 6 m of the robot at (1.5 m, 1.5 m)
//! are known with their true class, the rest Unknown, as after the first scans of a mission.
//!
//! Run from the project root:
//! `cargo run --example house_snapshot --no-default-features --features std --
//! ../shared/data/thesis-maps/map-house.csv fixtures/house-mid-mission.yaml`

use std::path::Path;

use papillon::geometry::Point2;
use papillon::grid::{CellClass, GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::mapfile::write_map;

const SIDE: usize = 240;
/// Robot position of the snapshot \[m\].
const ROBOT: Point2 = Point2::new(1.5, 1.5);
/// Radius of the known disc around the robot \[m\].
const KNOWN_RADIUS_M: f32 = 6.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, csv, yaml] = args.as_slice() else {
        return Err("usage: house_snapshot <map-house.csv> <out.yaml>".into());
    };
    let text =
        std::fs::read_to_string(csv).map_err(|e| format!("cannot read House map {csv}: {e}"))?;
    let rows: Vec<Vec<bool>> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|v| v.trim() == "1").collect())
        .collect();
    if rows.len() != 24 || rows.iter().any(|r| r.len() != 24) {
        return Err(format!("{csv}: expected 24 rows of 24 values").into());
    }
    let g = GridGeometry::new(SIDE, SIDE, 0.1, Point2::new(0.0, 0.0))?;
    let mut grid = OccupancyGrid::<{ SIDE * SIDE }>::new_boxed(g, LogOddsBounds::default())?;
    for i in 0..g.cell_count() {
        let c = g.cell(i);
        // Row 0 of the file is the north edge; grid row 0 is the south edge.
        let wall = rows[23 - (c.row as usize / 10)][c.col as usize / 10];
        if g.cell_center(c).distance(ROBOT) <= KNOWN_RADIUS_M {
            let class = if wall {
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
