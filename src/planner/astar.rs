//! A* search on the traversability grid.
//!
//! Hart, Nilsson & Raphael, "A Formal Basis for the Heuristic Determination of Minimum Cost
//! Paths", IEEE Trans. Systems Science and Cybernetics SSC-4(2), 1968. Moves: 8-connected,
//! diagonal sqrt(2), no corner cutting, step cost times the entered cell's cost factor (see the
//! [module root](super)). Heuristic: octile distance, consistent for these moves when every
//! cost factor is at least 1, so the first time the goal is closed its cost is optimal and no
//! cell is reopened. Ties on f go to the cell opened last (deeper nodes first), and cells
//! opened at the open list's minimum f bypass the heap (a stack, expanded first); both cut work
//! on open ground. Steps into cells that the expanded cell's parent reaches by a legal step
//! are not relaxed when the step costs make that useless (see the search module), which
//! changes nothing A* does but halves the relaxations. The bypass test allows one f32 ulp of
//! slack, so the cost found is optimal up to float rounding (relative 1.2e-7); the Moving AI
//! acceptance test checks lengths to 1e-3.
//!
//! Working memory (radix heap open list, g-values, parents, closed flags) has capacity `N`
//! and is reused across queries through generation stamps: a query neither clears nor
//! allocates anything.

use super::search::{Octile, SearchMemory};
use super::{PlanError, PlannedPath, Planner, Traversability, path_length_m};
use crate::grid::Cell;

/// An A* planner with working memory for grids of up to `N` cells.
#[repr(transparent)]
#[derive(bytemuck::Zeroable)]
pub struct AStar<const N: usize> {
    memory: SearchMemory<N>,
}

impl<const N: usize> core::fmt::Debug for AStar<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("AStar").field("capacity", &N).finish()
    }
}

impl<const N: usize> Default for AStar<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> AStar<N> {
    /// A planner built on the stack (28 bytes per cell). For large `N` on a host prefer
    /// [`Self::new_boxed`].
    pub const fn new() -> Self {
        Self {
            memory: SearchMemory::new(),
        }
    }

    /// A planner built directly on the heap.
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        // All-zero memory is what `SearchMemory::new` produces.
        crate::heap::boxed_zeroed()
    }

    /// Shortest path from `start` to `goal`, cells written into `path` (start first).
    ///
    /// Errors: [`PlanError::OutOfBounds`], [`PlanError::StartBlocked`],
    /// [`PlanError::GoalBlocked`], [`PlanError::NoPath`], and
    /// [`PlanError::CapacityExceeded`] if the grid is larger than `N` or the path does not fit
    /// in `path` (the search itself still ran; a larger buffer would receive the path).
    pub fn find_path<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        start: Cell,
        goal: Cell,
        path: &mut [Cell],
    ) -> Result<PlannedPath, PlanError> {
        let (cost, expansions, goal_index) = self.search(trav, start, goal)?;
        let w = trav.geometry().width;
        let len = self.memory.write_path(goal_index, w, path)?;
        let res = trav.geometry().resolution_m;
        Ok(PlannedPath {
            len,
            length_m: path_length_m(&path[..len], res),
            cost_m: cost * res,
            expansions,
        })
    }

    /// Cost of the shortest path \[m\] and the number of expansions, without writing the path.
    pub fn path_cost<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        start: Cell,
        goal: Cell,
    ) -> Result<(f32, u32), PlanError> {
        let (cost, expansions, _) = self.search(trav, start, goal)?;
        Ok((cost * trav.geometry().resolution_m, expansions))
    }

    /// Runs the search; returns cost \[cells\], expansions and the goal's index.
    fn search<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        start: Cell,
        goal: Cell,
    ) -> Result<(f32, u32, usize), PlanError> {
        let n = trav.geometry().cell_count();
        if n > N {
            return Err(PlanError::CapacityExceeded {
                needed: n,
                capacity: N,
            });
        }
        let (s, t) = trav.check_endpoints(start, goal)?;
        let w = trav.geometry().width;
        let goal_cell = Octile {
            col: t % w,
            row: t / w,
        };
        let mem = &mut self.memory;
        match mem.search(trav, s, t, goal_cell) {
            (expansions, true) => Ok((mem.g(t), expansions, t)),
            (_, false) => Err(PlanError::NoPath { start, goal }),
        }
    }
}

impl<const N: usize> Planner<N> for AStar<N> {
    fn plan(
        &mut self,
        trav: &Traversability<N>,
        start: Cell,
        goal: Cell,
        path: &mut [Cell],
    ) -> Result<PlannedPath, PlanError> {
        self.find_path(trav, start, goal, path)
    }
}
