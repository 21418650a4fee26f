//! One-to-all shortest paths: a Dijkstra sweep from one source over the whole reachable grid.
//!
//! Dijkstra, "A note on two problems in connexion with graphs", Numerische Mathematik 1, 1959.
//! Same moves and costs as A* (8-connected, diagonal sqrt(2), no corner cutting, cost factor of
//! the entered cell; see the [module root](super)). After one [`DistanceField::compute`], the
//! cost to any cell is an O(1) lookup and the path to it is extracted by following parent links
//! (O(path length)): the exploration objective sweeps once per decision and then asks about
//! hundreds of candidate targets.
//!
//! Working memory of capacity `N` is reused across sweeps through generation stamps.

use super::search::{SearchMemory, Zero};
use super::{PlanError, PlannedPath, Planner, Traversability, path_length_m};
use crate::grid::{Cell, GridGeometry};

/// Shortest-path costs from one source cell to every reachable cell of a grid of up to `N`
/// cells.
pub struct DistanceField<const N: usize> {
    memory: SearchMemory<N>,
    /// Geometry of the last sweep; `None` before the first.
    geometry: Option<GridGeometry>,
    source: Cell,
    reached: u32,
}

impl<const N: usize> core::fmt::Debug for DistanceField<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DistanceField")
            .field("capacity", &N)
            .field("source", &self.source)
            .field("reached", &self.reached)
            .finish()
    }
}

impl<const N: usize> Default for DistanceField<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> DistanceField<N> {
    /// An empty field built on the stack (28 bytes per cell). For large `N` on a host
    /// prefer [`Self::new_boxed`].
    pub const fn new() -> Self {
        Self {
            memory: SearchMemory::new(),
            geometry: None,
            source: Cell::new(0, 0),
            reached: 0,
        }
    }

    /// An empty field built directly on the heap.
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        // SAFETY: `DistanceField` is integers, floats, arrays of structs of them, and an
        // `Option<GridGeometry>`. The all-zero pattern may not be a valid `Option`, so the field
        // is written through a raw pointer before the box is formed (GridGeometry has no drop
        // glue, so nothing is dropped); every other field is valid at zero.
        unsafe {
            let layout = std::alloc::Layout::new::<Self>();
            let raw = std::alloc::alloc_zeroed(layout) as *mut Self;
            if raw.is_null() {
                std::alloc::handle_alloc_error(layout);
            }
            core::ptr::addr_of_mut!((*raw).geometry).write(None);
            std::boxed::Box::from_raw(raw)
        }
    }

    /// Sweeps from `source` over every cell reachable from it. Returns the number of cells
    /// reached (the source included).
    ///
    /// Errors: [`PlanError::OutOfBounds`] or [`PlanError::StartBlocked`] for a bad source,
    /// [`PlanError::CapacityExceeded`] if the grid is larger than `N`. On error the previous
    /// field is forgotten.
    pub fn compute<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        source: Cell,
    ) -> Result<u32, PlanError> {
        self.geometry = None;
        self.reached = 0;
        let n = trav.geometry().cell_count();
        if n > N {
            return Err(PlanError::CapacityExceeded {
                needed: n,
                capacity: N,
            });
        }
        let (s, _) = trav.check_endpoints(source, source)?;
        let (reached, _) = self.memory.search(trav, s, usize::MAX, Zero);
        self.geometry = Some(*trav.geometry());
        self.source = source;
        self.reached = reached;
        Ok(reached)
    }

    /// Source of the last sweep (meaningless before the first).
    pub fn source(&self) -> Cell {
        self.source
    }

    /// Cells reached by the last sweep (0 before the first).
    pub fn reached(&self) -> u32 {
        self.reached
    }

    #[inline]
    fn index(&self, cell: Cell) -> Option<usize> {
        let i = self.geometry?.index(cell)?;
        self.memory
            .is_closed_in(i, self.memory.generation())
            .then_some(i)
    }

    /// Cost of the shortest path from the source to `cell` \[m\]; `None` if the cell is
    /// unreachable, outside the grid, or no sweep was made. O(1).
    #[inline]
    pub fn distance_to(&self, cell: Cell) -> Option<f32> {
        let i = self.index(cell)?;
        Some(self.memory.g(i) * self.geometry?.resolution_m)
    }

    /// Whether `cell` was reached by the last sweep.
    #[inline]
    pub fn is_reachable(&self, cell: Cell) -> bool {
        self.index(cell).is_some()
    }

    /// The first step from the source towards `cell` (the cell itself if adjacent, the source
    /// if `cell` is the source); `None` if unreachable. O(path length).
    pub fn first_step_towards(&self, cell: Cell) -> Option<Cell> {
        let g = self.geometry?;
        let mut i = self.index(cell)?;
        let mut prev = i;
        while let Some(p) = self.memory.parent(i) {
            prev = i;
            i = p;
        }
        Some(g.cell(prev))
    }

    /// Writes the shortest path from the source to `cell` into `path` (source first).
    ///
    /// Errors: [`PlanError::OutOfBounds`] outside the grid, [`PlanError::NoPath`] if
    /// unreachable or no sweep was made, [`PlanError::CapacityExceeded`] if `path` is too
    /// short.
    pub fn path_to(&self, cell: Cell, path: &mut [Cell]) -> Result<PlannedPath, PlanError> {
        let no_path = PlanError::NoPath {
            start: self.source,
            goal: cell,
        };
        let g = self.geometry.ok_or(no_path)?;
        if !g.contains(cell) {
            return Err(PlanError::OutOfBounds {
                cell,
                width: g.width,
                height: g.height,
            });
        }
        let i = self.index(cell).ok_or(no_path)?;
        let len = self.memory.write_path(i, g.width, path)?;
        Ok(PlannedPath {
            len,
            length_m: path_length_m(&path[..len], g.resolution_m),
            cost_m: self.memory.g(i) * g.resolution_m,
            expansions: self.reached,
        })
    }
}

/// Plans by sweeping from `start` and extracting the path to `goal` (a slow but exact
/// planner; mostly useful to cross-check A*).
impl<const N: usize> Planner<N> for DistanceField<N> {
    fn plan(
        &mut self,
        trav: &Traversability<N>,
        start: Cell,
        goal: Cell,
        path: &mut [Cell],
    ) -> Result<PlannedPath, PlanError> {
        trav.check_endpoints(start, goal)?;
        self.compute(trav, start)?;
        self.path_to(goal, path)
    }
}
