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
//!
//! Beside coverage, the map's accuracy against the truth ([`crate::map_accuracy`]'s
//! measures, on the aligned maps): of the known observable cells, the fraction whose class
//! matches the truth (and of the truly free and truly blocked ones apart), and the mean
//! distance from a cell the robot map calls Occupied to the nearest true wall.

use papillon::geometry::{Point2, Pose2};
use papillon::grid::CellClass;
use papillon::mapfile::MapImage;

use crate::map_accuracy::{Agreement, ratio};
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
    /// Known observable cells whose class (Free or Occupied) matches the truth, over known
    /// observable cells (0..1; 0 when none is known).
    pub accuracy: f32,
    /// Known truly free observable cells the map calls Free, over known truly free ones.
    pub free_agreement: f32,
    /// Known truly blocked observable cells the map calls Occupied, over known blocked ones.
    pub occupied_agreement: f32,
    /// Mean distance from a cell the robot map calls Occupied to the nearest true wall \[m\]
    /// (capped at [`crate::map_accuracy::WALL_SEARCH_CELLS`] cells; a cell beyond the world's
    /// edge is measured to the nearest wall inside it).
    pub wall_error_m: f32,
    /// Cells the robot map calls Occupied.
    pub occupied_cells: usize,
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
    let aligned = identity && map.geometry == g;
    let class_of = |i: usize| {
        if aligned {
            map.cells[i]
        } else {
            class_at(
                map,
                robot_from_world.transform_point(g.cell_center(g.cell(i))),
            )
        }
    };
    let mut agreement = Agreement::default();
    for (i, _) in truth.mask().iter().enumerate().filter(|(_, m)| **m) {
        let class = class_of(i);
        if class.is_known() {
            agreement.add(class == CellClass::Occupied, world.is_blocked_index(i));
        }
    }
    let known_cells = agreement.known();
    // Every cell the robot map calls Occupied, wherever it is, against the nearest true wall.
    let world_from_robot = inverse(robot_from_world);
    for (i, _) in map
        .cells
        .iter()
        .enumerate()
        .filter(|(_, c)| **c == CellClass::Occupied)
    {
        let p = world_from_robot.transform_point(map.geometry.cell_center(map.geometry.cell(i)));
        // A cell beyond the world's edge (a wall on the edge drawn a cell too far) is measured
        // to the nearest wall inside it all the same.
        agreement.add_occupied(crate::map_accuracy::nearest_wall_cells(
            world,
            g.cell_at_unchecked(p),
        ));
    }
    let observable_cells = truth.len();
    Score {
        coverage: ratio(known_cells, observable_cells),
        observable_cells,
        known_cells,
        accuracy: agreement.accuracy(),
        free_agreement: agreement.free_agreement(),
        occupied_agreement: agreement.occupied_agreement(),
        wall_error_m: agreement.wall_error_m(g.resolution_m),
        occupied_cells: agreement.occupied_cells(),
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
        assert_eq!(
            (s.accuracy, s.free_agreement, s.occupied_agreement),
            (1.0, 1.0, 1.0)
        );
        assert_eq!(s.wall_error_m, 0.0);
        assert!(s.occupied_cells > 0);
        // An all-occupied map knows everything (coverage 1) but is wrong on the free space.
        let all = MapImage {
            geometry: *w.geometry(),
            cells: vec![CellClass::Occupied; w.geometry().cell_count()],
        };
        let s = score(&w, &all, w.start());
        assert_eq!(s.coverage, 1.0);
        assert!(s.accuracy < 0.5, "{s:?}");
        assert_eq!(s.free_agreement, 0.0);
        assert!(s.wall_error_m > 0.1, "{s:?}");
        let empty = MapImage {
            geometry: *w.geometry(),
            cells: vec![CellClass::Unknown; w.geometry().cell_count()],
        };
        let s = score(&w, &empty, w.start());
        assert_eq!((s.coverage, s.known_cells), (0.0, 0));
    }

    /// A robot map larger than the world, its walls on the world's edge drawn one cell
    /// beyond it: those cells are a cell from the wall, not the search's cap.
    #[test]
    fn occupied_cells_beyond_the_worlds_edge_are_measured_to_the_nearest_wall() {
        let w = builtin::lab(0.1).unwrap();
        let g = *w.geometry();
        let pad = 10;
        let big = papillon::grid::GridGeometry::new(
            g.width + 2 * pad,
            g.height + 2 * pad,
            g.resolution_m,
            Point2::new(g.origin.x - 1.0, g.origin.y - 1.0),
        )
        .unwrap();
        let mut cells = vec![CellClass::Unknown; big.cell_count()];
        let perfect = w.perfect_map();
        for (i, c) in perfect.cells.iter().enumerate() {
            let p = g.cell_center(g.cell(i));
            let j = big.index(big.cell_at(p).unwrap()).unwrap();
            cells[j] = *c;
        }
        // The row just south of the world, under its southern edge.
        let mut beyond = 0;
        for col in pad..pad + g.width {
            let j = big
                .index(papillon::grid::Cell::new(col as i32, pad as i32 - 1))
                .unwrap();
            cells[j] = CellClass::Occupied;
            beyond += 1;
        }
        let map = MapImage {
            geometry: big,
            cells,
        };
        let s = score(&w, &map, w.start());
        assert_eq!(s.coverage, 1.0);
        let share = beyond as f32 / s.occupied_cells as f32;
        // Each of them one cell (0.1 m) from the edge wall: the mean grows by about
        // 0.1 m times their share, far below the 2 m cap times it.
        assert!(
            s.wall_error_m <= 0.1 * share + 1e-3,
            "{s:?}, {beyond} cells beyond"
        );
        assert!(s.wall_error_m > 0.0, "{s:?}");
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
        // Aligned, the rotated map is as true as the world (up to the resampling at cell
        // edges).
        assert!(s.accuracy > 0.97 && s.wall_error_m < 0.05, "{s:?}");
        // Without alignment (start taken as the world's), the rotated map mostly misses.
        let s = score(&w, &map, w.start());
        assert!(s.coverage < 0.5, "{s:?}");
    }
}
