//! Mouths of passages shut on the map: where to look again when no frontier is reachable.
//!
//! A passage can be free in truth, and seen through, yet shut in the planning layer: a door's
//! jamb mapped a cell too wide by range noise, a wall mapped thick and offset by odometry
//! drift, one return's evidence at the log-odds bound in a door's edge cell. The room behind
//! is then partly known (its Free cells were seen through the passage) and its frontier is
//! *cut*: passable cells next to it that the robot's distance field does not reach. Nothing
//! the robot could choose reaches it, and a frontier rule would end the mission "nothing
//! reachable" with unknown space it can drive to (issue 17, the *cut* clusters of
//! `coverage_gaps`).
//!
//! What opens such a passage is a look from close by: the laser's range noise grows with the
//! range (5 % of it by default), so returns from a door 0.5 m away land within a few
//! centimetres of the jambs, and the beams through the door clear the cells that far-away
//! returns marked in it (Thrun, Burgard & Fox, *Probabilistic Robotics*, 2005, §9.2: every
//! cell a beam passes before its return gets Free evidence). [`MouthSearch::find`] finds
//! where to look from: a breadth-first flood (4-connected, so it does not leak through the
//! diagonal steps of a mapped wall) over **Free** cells from the cut frontier's passable cells,
//! which crosses a passage that is open in Free cells however narrow the planning layer makes
//! it, and stops at the first cell the robot's distance field reaches: the mouth of the
//! passage on the robot's side. The target is the nearest cell there where the robot can turn
//! in place (so that it can face the passage and leave again).
//!
//! Mouths already looked from are remembered by the caller (at most [`MAX_MOUTHS`]); the flood
//! does not pass within [`MOUTH_MEMORY_M`] of one, so a passage a look did not open is not
//! looked at again and again, and the next search finds the next passage, or none: the robot
//! then really has nothing left it can reach. Frontier cells in the wall band (a wall's
//! unknown interior behind its Free face) are not cut: their Free neighbours are not passable,
//! and a look at a wall opens nothing.

use crate::geometry::Point2;
use crate::grid::{Cell, CellClass, OccupancyGrid};
use crate::planner::{DistanceField, Traversability};

/// Most mouths a mission remembers having looked from.
pub const MAX_MOUTHS: usize = 16;
/// The flood does not pass within this distance of a mouth looked from \[m\]: a 0.5–0.9 m
/// door's whole mouth, and the wall band beside it.
pub const MOUTH_MEMORY_M: f32 = 1.0;
/// The target is the nearest turnable reached cell within this distance of the mouth \[m\].
pub const MOUTH_STAND_M: f32 = 0.6;

/// The flood's working memory: a queue and a mark per cell (about 5 bytes per cell).
#[derive(bytemuck::Zeroable)]
pub struct MouthSearch<const N: usize> {
    queue: [u32; N],
    seen: [u8; N],
}

impl<const N: usize> Default for MouthSearch<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> core::fmt::Debug for MouthSearch<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("MouthSearch")
            .field("capacity", &N)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> MouthSearch<N> {
    /// Empty working memory (built on the stack or in a `static`).
    pub const fn new() -> Self {
        Self {
            queue: [0; N],
            seen: [0; N],
        }
    }

    /// The cell to look from at the nearest passage that is open in Free cells but shut in
    /// the planning layer `trav`, from the robot's distance field `field`; `None` if there is
    /// none (or none farther than [`MOUTH_MEMORY_M`] from every point of `looked`). A grid of
    /// more cells than the memory holds has no answer.
    pub fn find(
        &mut self,
        grid: &OccupancyGrid<N>,
        trav: &Traversability<N>,
        field: &DistanceField<N>,
        looked: &[Point2],
    ) -> Option<Cell> {
        let geom = *grid.geometry();
        let cells = grid.cell_count();
        if cells > N || trav.geometry() != grid.geometry() {
            return None;
        }
        self.seen[..cells].fill(0);
        let remembered = |c: Cell| -> bool {
            looked
                .iter()
                .any(|m| m.distance(geom.cell_center(c)) < MOUTH_MEMORY_M)
        };
        let (mut head, mut tail) = (0usize, 0usize);
        // Seeds: the passable Free 4-neighbours of frontier cells that the robot cannot reach.
        let area = crate::frontier::frontier_box(grid);
        for row in area.row_min..area.row_end {
            for col in area.col_min..area.col_end {
                let i = row * geom.width + col;
                if !crate::frontier::is_frontier_cell(grid, i) {
                    continue;
                }
                let c = geom.cell(i);
                for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    let n = Cell::new(c.col + dc, c.row + dr);
                    let Some(j) = geom.index(n) else { continue };
                    if self.seen[j] != 0
                        || grid.class(j) != CellClass::Free
                        || !trav.is_passable(n)
                        || field.is_reachable(n)
                        || remembered(n)
                    {
                        continue;
                    }
                    self.seen[j] = 1;
                    self.queue[tail] = j as u32;
                    tail += 1;
                }
            }
        }
        // The flood over Free cells, nearest the cut frontier first.
        while head < tail {
            let c = geom.cell(self.queue[head] as usize);
            head += 1;
            for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let n = Cell::new(c.col + dc, c.row + dr);
                let Some(j) = geom.index(n) else { continue };
                if self.seen[j] != 0 {
                    continue;
                }
                self.seen[j] = 1;
                if grid.class(j) != CellClass::Free || remembered(n) {
                    continue;
                }
                if field.is_reachable(n) {
                    // The robot's side of the passage: stand near it where it can turn.
                    if let Some(stand) = stand_near(trav, field, n, &remembered) {
                        return Some(stand);
                    }
                    continue;
                }
                self.queue[tail] = j as u32;
                tail += 1;
            }
        }
        None
    }
}

/// The reached cell nearest `mouth` (within [`MOUTH_STAND_M`]) where the robot can turn in
/// place, not near a mouth looked from.
fn stand_near<const N: usize>(
    trav: &Traversability<N>,
    field: &DistanceField<N>,
    mouth: Cell,
    remembered: &impl Fn(Cell) -> bool,
) -> Option<Cell> {
    let geom = trav.geometry();
    let span = (MOUTH_STAND_M / geom.resolution_m) as i32;
    let mut best: Option<(i32, Cell)> = None;
    for dr in -span..=span {
        for dc in -span..=span {
            let d2 = dc * dc + dr * dr;
            if d2 > span * span || best.is_some_and(|(b, _)| d2 >= b) {
                continue;
            }
            let c = Cell::new(mouth.col + dc, mouth.row + dr);
            if trav.can_turn(c) && field.is_reachable(c) && !remembered(c) {
                best = Some((d2, c));
            }
        }
    }
    best.map(|(_, c)| c)
}
