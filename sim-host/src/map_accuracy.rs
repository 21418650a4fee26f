//! How true a map is, against the world it was drawn from: the measures a mapping paper
//! reports beside coverage (coverage alone counts known cells, so an all-occupied map would
//! score 100 %).
//!
//! Over the observable cells ([`crate::world::Truth`]: the free space reachable from the start
//! and the walls that bound it) that the map knows:
//! - **accuracy**: the fraction whose class (Free or Occupied) matches the truth;
//! - **free agreement**: of the truly free ones, the fraction the map calls Free;
//! - **occupied agreement**: of the truly blocked ones, the fraction the map calls Occupied.
//!
//! And over every cell the map calls Occupied, wherever it is, the **wall position error**: the
//! mean distance from its centre to the centre of the nearest truly blocked cell (0 for a
//! blocked cell), searched within [`WALL_SEARCH_CELLS`] cells (a cell with no wall that near
//! counts at that distance). This is the cell-level form of the map-to-truth distance used to
//! score SLAM maps (e.g. the "map score" and nearest-neighbour measures of Santos, Portugal &
//! Rocha, *An evaluation of 2D SLAM techniques available in ROS*, SSRR 2013).

use papillon::grid::{Cell, CellClass, OccupancyGrid};

use crate::world::{Truth, World};

/// Largest distance searched for a true wall around a map-occupied cell \[cells\].
pub const WALL_SEARCH_CELLS: i32 = 20;

/// The map's agreement with the truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MapAccuracy {
    /// Known observable cells whose class matches the truth, over known observable cells.
    pub accuracy: f32,
    /// Known truly free observable cells the map calls Free, over known truly free ones.
    pub free_agreement: f32,
    /// Known truly blocked observable cells the map calls Occupied, over known blocked ones.
    pub occupied_agreement: f32,
    /// Mean distance from a map-occupied cell to the nearest true wall \[m\].
    pub wall_error_m: f32,
    /// Map-occupied cells.
    pub occupied_cells: usize,
}

/// Measures `grid` against `world` (same geometry) and its observable set `truth`.
pub fn measure<const N: usize>(
    grid: &OccupancyGrid<N>,
    world: &World,
    truth: &Truth,
) -> MapAccuracy {
    let geom = *grid.geometry();
    let mask = truth.mask();
    let mut agreement = Agreement::default();
    for (i, &observable) in mask.iter().enumerate().take(geom.cell_count()) {
        let class = grid.class(i);
        let blocked = world.is_blocked_index(i);
        if class == CellClass::Occupied {
            agreement.add_occupied(nearest_wall_cells(world, geom.cell(i)));
        }
        if !observable || class == CellClass::Unknown {
            continue;
        }
        agreement.add(class == CellClass::Occupied, blocked);
    }
    MapAccuracy {
        accuracy: agreement.accuracy(),
        free_agreement: agreement.free_agreement(),
        occupied_agreement: agreement.occupied_agreement(),
        wall_error_m: agreement.wall_error_m(geom.resolution_m),
        occupied_cells: agreement.occupied_cells(),
    }
}

/// The tallies behind [`MapAccuracy`]'s measures: one known observable cell at a time, what
/// the map says (Occupied or not) against what the world has there; and one map-occupied cell
/// at a time, its distance to the nearest true wall.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Agreement {
    known: usize,
    right: usize,
    free_known: usize,
    free_right: usize,
    wall_known: usize,
    wall_right: usize,
    occupied: usize,
    distance_cells: f64,
}

impl Agreement {
    /// One known observable cell: the map calls it Occupied (`says_blocked`) or Free; the world
    /// has it `blocked` or not.
    pub(crate) fn add(&mut self, says_blocked: bool, blocked: bool) {
        self.known += 1;
        self.right += usize::from(says_blocked == blocked);
        if blocked {
            self.wall_known += 1;
            self.wall_right += usize::from(says_blocked);
        } else {
            self.free_known += 1;
            self.free_right += usize::from(!says_blocked);
        }
    }

    /// One cell the map calls Occupied, `distance_cells` from the nearest true wall.
    pub(crate) fn add_occupied(&mut self, distance_cells: f32) {
        self.occupied += 1;
        self.distance_cells += f64::from(distance_cells);
    }

    /// Map-occupied cells counted.
    pub(crate) fn occupied_cells(&self) -> usize {
        self.occupied
    }

    /// Mean distance from a map-occupied cell to the nearest true wall \[m\] on cells of
    /// `resolution_m` (0 with none).
    pub(crate) fn wall_error_m(&self, resolution_m: f32) -> f32 {
        if self.occupied == 0 {
            0.0
        } else {
            (self.distance_cells / self.occupied as f64) as f32 * resolution_m
        }
    }

    /// Known cells counted.
    pub(crate) fn known(&self) -> usize {
        self.known
    }

    /// Cells whose class matches, over known cells (0 with none).
    pub(crate) fn accuracy(&self) -> f32 {
        ratio(self.right, self.known)
    }

    /// Truly free cells called Free, over truly free known cells.
    pub(crate) fn free_agreement(&self) -> f32 {
        ratio(self.free_right, self.free_known)
    }

    /// Truly blocked cells called Occupied, over truly blocked known cells.
    pub(crate) fn occupied_agreement(&self) -> f32 {
        ratio(self.wall_right, self.wall_known)
    }
}

/// `a / b`, 0 when `b` is 0.
pub(crate) fn ratio(a: usize, b: usize) -> f32 {
    if b == 0 { 0.0 } else { a as f32 / b as f32 }
}

/// Distance \[cells\] from `cell` to the nearest blocked cell of `world`, searched in growing
/// square rings (a ring at Chebyshev radius `r` cannot hold anything nearer than `r`), capped
/// at [`WALL_SEARCH_CELLS`].
pub(crate) fn nearest_wall_cells(world: &World, cell: Cell) -> f32 {
    let mut best = WALL_SEARCH_CELLS as f32;
    for r in 0..=WALL_SEARCH_CELLS {
        if r as f32 >= best {
            break;
        }
        for dr in -r..=r {
            for dc in -r..=r {
                if dr.abs() != r && dc.abs() != r {
                    continue;
                }
                if world.is_blocked(Cell::new(cell.col + dc, cell.row + dr))
                    && world
                        .geometry()
                        .contains(Cell::new(cell.col + dc, cell.row + dr))
                {
                    best = best.min(((dr * dr + dc * dc) as f32).sqrt());
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::LogOddsBounds;

    fn grid_of(world: &World) -> Box<OccupancyGrid<{ 240 * 240 }>> {
        OccupancyGrid::new_boxed(*world.geometry(), LogOddsBounds::default()).unwrap()
    }

    #[test]
    fn the_true_map_scores_perfectly_and_an_all_occupied_map_does_not() {
        let world = World::load("house", 0.1).unwrap();
        let truth = world.truth();
        let mut grid = grid_of(&world);
        for i in 0..grid.cell_count() {
            if truth.mask()[i] {
                let class = if world.is_blocked_index(i) {
                    CellClass::Occupied
                } else {
                    CellClass::Free
                };
                grid.set_class(i, class, &mut ());
            }
        }
        let a = measure(&grid, &world, &truth);
        assert_eq!(
            (a.accuracy, a.free_agreement, a.occupied_agreement),
            (1.0, 1.0, 1.0)
        );
        assert_eq!(a.wall_error_m, 0.0);
        assert!(a.occupied_cells > 100);

        for i in 0..grid.cell_count() {
            grid.set_class(i, CellClass::Occupied, &mut ());
        }
        let a = measure(&grid, &world, &truth);
        assert!(a.accuracy < 0.5, "{a:?}");
        assert_eq!(a.free_agreement, 0.0);
        assert_eq!(a.occupied_agreement, 1.0);
        assert!(a.wall_error_m > 0.2, "{a:?}");
    }

    #[test]
    fn a_wall_drawn_one_cell_off_is_one_cell_wrong() {
        let world = World::load("house", 0.1).unwrap();
        let truth = world.truth();
        let mut grid = grid_of(&world);
        let g = *world.geometry();
        // Every observable wall cell drawn one cell east, where the truth is free.
        let mut moved = 0;
        for i in 0..g.cell_count() {
            let c = g.cell(i);
            let east = Cell::new(c.col + 1, c.row);
            if truth.mask()[i]
                && world.is_blocked_index(i)
                && g.index(east).is_some_and(|j| !world.is_blocked_index(j))
            {
                grid.set_class(g.index(east).unwrap(), CellClass::Occupied, &mut ());
                moved += 1;
            }
        }
        assert!(moved > 10);
        let a = measure(&grid, &world, &truth);
        assert!((a.wall_error_m - 0.1).abs() < 1e-4, "{a:?}");
        assert_eq!(a.free_agreement, 0.0);
    }
}
