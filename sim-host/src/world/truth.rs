//! Ground truth for scoring an exploration: the observable set and coverage.
//!
//! The observable set is every Free cell 8-connected to the start cell (through Free cells),
//! plus every blocked cell 8-adjacent to one of them: the cells a robot could ever see from
//! where it can go. Coverage of a robot's map is the number of cells of that set that the map
//! knows (Free or Occupied, [`CellClass::is_known`]) divided by the size of the set. This makes
//! the thesis's "exploration rate" (Bendahmane 2023) precise: cells behind walls or in closed
//! rooms do not count. If the start cell is blocked (or outside the grid) the set is empty and
//! coverage is defined as 0.

use papillon::grid::{Cell, CellClass, OccupancyGrid};

use super::World;

/// The observable set of a world, precomputed for fast repeated coverage queries.
#[derive(Clone, Debug)]
pub struct Truth {
    geometry: papillon::grid::GridGeometry,
    mask: Vec<bool>,
    cells: Vec<usize>,
    free_count: usize,
}

impl Truth {
    /// Flood-fills the world's free space from its start cell (8-connected) and adds the
    /// blocked cells that touch it (8-adjacent).
    pub fn new(world: &World) -> Self {
        let g = *world.geometry();
        let mut mask = vec![false; g.cell_count()];
        let mut cells = Vec::new();
        let mut free_count = 0;
        if let Some(start) = world.start_cell().and_then(|c| g.index(c))
            && !world.is_blocked_index(start)
        {
            let mut stack = vec![start];
            mask[start] = true;
            while let Some(i) = stack.pop() {
                cells.push(i);
                free_count += 1;
                let c = g.cell(i);
                for dr in -1..=1 {
                    for dc in -1..=1 {
                        let Some(j) = g.index(Cell::new(c.col + dc, c.row + dr)) else {
                            continue;
                        };
                        if mask[j] {
                            continue;
                        }
                        mask[j] = true;
                        if world.is_blocked_index(j) {
                            cells.push(j);
                        } else {
                            stack.push(j);
                        }
                    }
                }
            }
        }
        cells.sort_unstable();
        Self {
            geometry: g,
            mask,
            cells,
            free_count,
        }
    }

    /// Membership per cell, flat-index order.
    pub fn mask(&self) -> &[bool] {
        &self.mask
    }

    /// Flat indices of the observable cells, ascending.
    pub fn cells(&self) -> &[usize] {
        &self.cells
    }

    /// Size of the observable set \[cells\].
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether the set is empty (start blocked or outside the grid).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Free cells in the set (those reached by the flood fill).
    pub fn free_count(&self) -> usize {
        self.free_count
    }

    /// Observable cells for which `known(index)` holds.
    pub fn known_cells_by(&self, mut known: impl FnMut(usize) -> bool) -> usize {
        self.cells.iter().filter(|&&i| known(i)).count()
    }

    /// Observable cells the robot map knows. The map must be in the world's map frame; when its
    /// geometry differs from the world's, each observable cell is looked up at its centre.
    pub fn known_cells<const N: usize>(&self, map: &OccupancyGrid<N>) -> usize {
        if *map.geometry() == self.geometry {
            self.known_cells_by(|i| map.class(i).is_known())
        } else {
            self.known_cells_by(|i| {
                let p = self.geometry.cell_center(self.geometry.cell(i));
                map.geometry()
                    .cell_at(p)
                    .and_then(|c| map.class_of(c))
                    .is_some_and(CellClass::is_known)
            })
        }
    }

    /// Coverage of a robot map: known observable cells / observable cells (0..1).
    pub fn coverage<const N: usize>(&self, map: &OccupancyGrid<N>) -> f32 {
        if self.cells.is_empty() {
            return 0.0;
        }
        self.known_cells(map) as f32 / self.cells.len() as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::geometry::Point2;
    use papillon::grid::{GridGeometry, LogOddsBounds};

    fn boxed_room() -> World {
        // 10 x 10 cells at 1 m: a 1-cell wall ring, a closed 2x2 room in the north-east.
        let g = GridGeometry::new(10, 10, 1.0, Point2::default()).unwrap();
        let mut w = World::new("t", g).with_start(papillon::geometry::Pose2::new(1.5, 1.5, 0.0));
        w.fill_rect(0.0, 0.0, 10.0, 1.0, true);
        w.fill_rect(0.0, 9.0, 10.0, 10.0, true);
        w.fill_rect(0.0, 0.0, 1.0, 10.0, true);
        w.fill_rect(9.0, 0.0, 10.0, 10.0, true);
        // Closed room: walls at x 5..6 / y 5..6 enclosing 6..9 x 6..9.
        w.fill_rect(5.0, 5.0, 9.0, 6.0, true);
        w.fill_rect(5.0, 5.0, 6.0, 9.0, true);
        w
    }

    #[test]
    fn observable_set_excludes_closed_rooms_and_far_walls() {
        let w = boxed_room();
        let t = w.truth();
        // Free inside the ring: 8x8 = 64 minus the room walls (7 cells) minus the closed
        // room (3x3 = 9) = 48.
        assert_eq!(t.free_count(), 48);
        // Blocked cells adjacent to free ones: the ring without its 4 corners... corners are
        // diagonal-adjacent to inner corner cells, so the whole inner boundary ring of 36
        // counts, except ring cells only next to the closed room: (9,6),(9,7),(9,8),(6,9),
        // (7,9),(8,9) and the corner (9,9) are not adjacent to reachable free cells.
        let ring = 36 - 7;
        assert_eq!(t.len(), 48 + ring + 7);
        let mask = w.truth_mask();
        let g = *w.geometry();
        assert!(!mask[g.index(Cell::new(7, 7)).unwrap()]);
        assert!(mask[g.index(Cell::new(5, 5)).unwrap()]);
        assert!(mask[g.index(Cell::new(0, 0)).unwrap()]);
        assert!(!mask[g.index(Cell::new(9, 9)).unwrap()]);
    }

    #[test]
    fn coverage_counts_known_cells_in_the_set_only() {
        let w = boxed_room();
        let t = w.truth();
        let mut map = OccupancyGrid::<100>::new(*w.geometry(), LogOddsBounds::default()).unwrap();
        assert_eq!(t.coverage(&map), 0.0);
        // Knowing the closed room changes nothing.
        let inside = map.geometry().index(Cell::new(7, 7)).unwrap();
        map.set_class(inside, CellClass::Free, &mut ());
        assert_eq!(t.known_cells(&map), 0);
        for &i in t.cells() {
            let class = if w.is_blocked_index(i) {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            map.set_class(i, class, &mut ());
        }
        assert_eq!(t.coverage(&map), 1.0);
        let first = t.cells()[0];
        map.set_class(first, CellClass::Unknown, &mut ());
        let want = (t.len() - 1) as f32 / t.len() as f32;
        assert!((t.coverage(&map) - want).abs() < 1e-6);
    }

    #[test]
    fn coverage_works_across_geometries() {
        let w = boxed_room();
        let t = w.truth();
        // A finer map of the same area, fully known.
        let g = GridGeometry::new(20, 20, 0.5, Point2::default()).unwrap();
        let mut map = OccupancyGrid::<400>::new(g, LogOddsBounds::default()).unwrap();
        for i in 0..400 {
            map.set_class(i, CellClass::Free, &mut ());
        }
        assert_eq!(t.coverage(&map), 1.0);
    }

    #[test]
    fn blocked_start_gives_an_empty_set() {
        let w = boxed_room().with_start(papillon::geometry::Pose2::new(0.5, 0.5, 0.0));
        let t = w.truth();
        assert!(t.is_empty());
        let map = OccupancyGrid::<100>::new(*w.geometry(), LogOddsBounds::default()).unwrap();
        assert_eq!(t.coverage(&map), 0.0);
    }
}
