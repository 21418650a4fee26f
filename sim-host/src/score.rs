//! Scoring a robot's map (as the onboard binary and `papillon-sim mission` save it) against a
//! world's ground truth, with the same coverage measure as a simulated mission
//! ([`crate::world::truth`]).
//!
//! Alignment: the robot map's frame and the world's map frame are tied by the start pose. The
//! robot started at `robot_start` in its map's frame (the onboard binary's map frame has the
//! robot's start pose at its origin, so `papillon-sim score` defaults to (0, 0, 0)) and at the
//! world's start in the world. Each observable world cell's centre `p` is looked up in the
//! robot map at `robot_start ⊕ world_start⁻¹ ⊕ p`; cells outside the robot map count as
//! unknown.

use papillon::geometry::{Point2, Pose2};
use papillon::grid::CellClass;
use papillon::mapfile::MapImage;

use crate::world::World;

/// The score of a robot map.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Score {
    /// Known observable cells / observable cells (0..1).
    pub coverage: f32,
    /// Size of the observable set \[cells\].
    pub observable_cells: usize,
    /// Observable cells the robot map knows \[cells\].
    pub known_cells: usize,
}

/// The pose `(x, y, theta)` from 2 or 3 numbers (theta 0 when absent).
pub fn pose_from(values: &[f32]) -> Pose2 {
    Pose2::new(
        values.first().copied().unwrap_or(0.0),
        values.get(1).copied().unwrap_or(0.0),
        values.get(2).copied().unwrap_or(0.0),
    )
}

/// Checks a start pose given as 2 or 3 finite numbers; `name` (the option or field that gave
/// them) starts the error.
pub fn parse_pose(name: &str, values: &[f32]) -> Result<Pose2, String> {
    if !(2..=3).contains(&values.len()) || values.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "{name}: expected X Y [THETA] as finite numbers, got {values:?}"
        ));
    }
    // A heading of more than a turn is a mistake.
    if values
        .get(2)
        .is_some_and(|t| t.abs() > std::f32::consts::TAU)
    {
        return Err(format!(
            "{name}: expected THETA within ±2π rad, got {values:?}"
        ));
    }
    Ok(pose_from(values))
}

/// The inverse of a rigid transform.
fn inverse(p: Pose2) -> Pose2 {
    let (s, c) = p.theta.sin_cos();
    Pose2::new(-(c * p.x + s * p.y), -(-s * p.x + c * p.y), -p.theta)
}

/// Scores `map` against `world`'s truth, the robot having started at `robot_start` in the
/// map's frame and at `world.start()` in the world.
pub fn score(world: &World, map: &MapImage, robot_start: Pose2) -> Score {
    let truth = world.truth();
    let g = *world.geometry();
    let robot_from_world = robot_start.compose(inverse(world.start()));
    let identity = robot_from_world.x.abs() < 1e-6
        && robot_from_world.y.abs() < 1e-6
        && robot_from_world.theta.abs() < 1e-6;
    let known_cells = if identity && map.geometry == g {
        truth.known_cells_by(|i| map.cells[i].is_known())
    } else {
        truth.known_cells_by(|i| {
            let p = robot_from_world.transform_point(g.cell_center(g.cell(i)));
            class_at(map, p).is_known()
        })
    };
    let observable_cells = truth.len();
    Score {
        coverage: if observable_cells == 0 {
            0.0
        } else {
            known_cells as f32 / observable_cells as f32
        },
        observable_cells,
        known_cells,
    }
}

fn class_at(map: &MapImage, p: Point2) -> CellClass {
    map.geometry
        .cell_at(p)
        .and_then(|c| map.geometry.index(c))
        .and_then(|i| map.cells.get(i).copied())
        .unwrap_or(CellClass::Unknown)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::builtin;

    #[test]
    fn a_perfect_map_scores_one_and_an_empty_map_zero() {
        let w = builtin::lab(0.1).unwrap();
        let s = score(&w, &w.perfect_map(), w.start());
        assert_eq!(s.coverage, 1.0);
        assert_eq!(s.known_cells, s.observable_cells);
        assert_eq!(s.observable_cells, w.truth().len());
        let empty = MapImage {
            geometry: *w.geometry(),
            cells: vec![CellClass::Unknown; w.geometry().cell_count()],
        };
        let s = score(&w, &empty, w.start());
        assert_eq!((s.coverage, s.known_cells), (0.0, 0));
    }

    #[test]
    fn maps_are_aligned_by_the_start_pose() {
        // A robot whose map frame has its start at the origin, facing north (+90°): world
        // point q maps to robot-frame R(+90°)·(q - start).
        let w = builtin::lab(0.1).unwrap();
        let robot_start = Pose2::new(0.0, 0.0, core::f32::consts::FRAC_PI_2);
        let g = *w.geometry();
        // Robot map: 8 m x 8 m rotated, so x in [-8, 0] (well, -7..1) and y in [-1, 7].
        let rg = papillon::grid::GridGeometry::new(100, 100, 0.1, Point2::new(-8.0, -2.0)).unwrap();
        let robot_from_world = robot_start.compose(inverse(w.start()));
        let mut cells = vec![CellClass::Unknown; rg.cell_count()];
        for (i, c) in cells.iter_mut().enumerate() {
            let p = rg.cell_center(rg.cell(i));
            // Back to the world.
            let q = inverse(robot_from_world).transform_point(p);
            if let Some(wc) = g.cell_at(q) {
                *c = if w.is_blocked(wc) {
                    CellClass::Occupied
                } else {
                    CellClass::Free
                };
            }
        }
        let map = MapImage {
            geometry: rg,
            cells,
        };
        let s = score(&w, &map, robot_start);
        assert!(s.coverage > 0.99, "{s:?}");
        // Without alignment (start taken as the world's), the rotated map mostly misses.
        let s = score(&w, &map, w.start());
        assert!(s.coverage < 0.5, "{s:?}");
    }
}
