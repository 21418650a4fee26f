//! One-to-all shortest paths: a Dijkstra sweep from one source over the reachable grid.
//!
//! Dijkstra, "A note on two problems in connexion with graphs", Numerische Mathematik 1, 1959.
//! Same moves and costs as A* (8-connected, diagonal sqrt(2), no corner cutting, cost factor of
//! the entered cell; see the [module root](super)). After the sweep, the cost to any cell is an
//! O(1) lookup and the path to it is extracted by following parent links (O(path length)): the
//! exploration objective sweeps once per decision and then asks about hundreds of candidate
//! targets.
//!
//! The sweep can run lazily ([`DistanceField::start`]): it settles cells only until the cell
//! asked about is settled (or nothing reachable is left), and goes on from there at the next
//! question. Dijkstra settles cells in the same order whenever it stops, so every answer is
//! bit for bit the one of a full sweep ([`DistanceField::compute`]); a question about a nearby
//! cell (a replan towards the current target) costs only the cells closer than it. The step
//! codes and move masks of the traversability layer are copied at the start, so later changes
//! to the layer do not leak into a sweep in progress.
//!
//! The open list is a bucket queue of unit width (Dial, "Algorithm 360: shortest-path forest
//! with topological ordering", CACM 12(11), 1969): every step costs at least one cell, so the
//! lowest bucket's cells are final and no heap has to be kept in order. Working memory of
//! capacity `N` is reused across sweeps through generation stamps.

use core::cell::UnsafeCell;

use super::search::{DIAGONAL, SearchMemory, StepCosts, Zero};
use super::traversability::{CODE_BLOCKED, CODE_COUNT};
use super::{PlanError, PlannedPath, Planner, Traversability, path_length_m};
use crate::grid::{Cell, GridGeometry};

/// The state of a sweep: search memory, the copy of the layer it runs on and how far it got.
#[derive(bytemuck::Zeroable)]
struct Sweep<const N: usize> {
    memory: SearchMemory<N>,
    /// Step codes of the traversability layer at the start of the sweep.
    codes: [u8; N],
    /// Move masks of the layer at the start of the sweep.
    masks: [u8; N],
    cells: usize,
    width: usize,
    factors: [f32; CODE_COUNT],
    uniform: bool,
    /// Cells settled so far.
    reached: u32,
    /// Every reachable cell is settled.
    done: bool,
}

impl<const N: usize> Sweep<N> {
    /// Settles cells until `target` is settled, or until every reachable cell is (`None`, or
    /// an unreachable target).
    fn run_until(&mut self, target: Option<usize>) {
        if self.done {
            return;
        }
        if let Some(t) = target
            && self.memory.is_closed_in(t, self.memory.generation())
        {
            return;
        }
        let n = self.cells;
        let costs = StepCosts {
            width: self.width,
            masks: &self.masks[..n],
            codes: &self.codes[..n],
            factors: self.factors,
            uniform: self.uniform,
        };
        let (closed, found) = self
            .memory
            .resume(&costs, target.unwrap_or(usize::MAX), Zero);
        self.reached += closed;
        if !found {
            self.done = true;
        }
    }
}

/// Shortest-path costs from one source cell to every reachable cell of a grid of up to `N`
/// cells.
///
/// The queries take `&self` yet may advance a lazy sweep: the sweep state sits in an
/// [`UnsafeCell`], so a field is not `Sync`.
#[derive(bytemuck::Zeroable)]
pub struct DistanceField<const N: usize> {
    sweep: UnsafeCell<Sweep<N>>,
    /// Geometry of the current sweep; [`NO_GEOMETRY`] (no cells) before the first.
    geometry: GridGeometry,
    source: Cell,
}

/// The geometry of a field that has not swept: no cells, so no cell has an index.
const NO_GEOMETRY: GridGeometry = GridGeometry {
    width: 0,
    height: 0,
    resolution_m: 0.0,
    origin: crate::geometry::Point2::new(0.0, 0.0),
};

impl<const N: usize> core::fmt::Debug for DistanceField<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DistanceField")
            .field("capacity", &N)
            .field("source", &self.source)
            .field("reached", &self.reached())
            .finish()
    }
}

impl<const N: usize> Default for DistanceField<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> DistanceField<N> {
    /// An empty field built on the stack (30 bytes per cell). For large `N` on a host
    /// prefer [`Self::new_boxed`].
    pub const fn new() -> Self {
        Self {
            sweep: UnsafeCell::new(Sweep {
                memory: SearchMemory::new(),
                codes: [CODE_BLOCKED; N],
                masks: [0; N],
                cells: 0,
                width: 0,
                factors: [1.0; CODE_COUNT],
                uniform: true,
                reached: 0,
                done: true,
            }),
            geometry: NO_GEOMETRY,
            source: Cell::new(0, 0),
        }
    }

    /// An empty field built directly on the heap.
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        // Zero reached cells, not done, no geometry: nothing is answered before a sweep
        // starts.
        crate::heap::boxed_zeroed()
    }

    /// The geometry of the current sweep; `None` before the first (or after a failed start).
    #[inline]
    fn swept(&self) -> Option<GridGeometry> {
        (self.geometry.width > 0).then_some(self.geometry)
    }

    /// The sweep state, for reading.
    #[inline]
    fn state(&self) -> &Sweep<N> {
        // SAFETY: the only mutable accesses through `&self` are in `settle`, whose borrow ends
        // before it returns; no reference handed out by this type points into the sweep, and
        // the type is not `Sync`, so no other thread can be settling meanwhile.
        unsafe { &*self.sweep.get() }
    }

    /// Advances the sweep until `target` is settled (or everything reachable is, for `None`).
    #[inline]
    fn settle(&self, target: Option<usize>) {
        // SAFETY: the type is not `Sync` (`UnsafeCell`), so only this thread reaches the
        // sweep; every reference made by `state` or `settle` lives only within one method
        // call of this type and none is alive here (no method calls back into the field while
        // holding one), so this is the only reference to the sweep while it lives.
        let sweep = unsafe { &mut *self.sweep.get() };
        sweep.run_until(target);
    }

    /// Starts a lazy sweep from `source` over the cells `trav` lets the robot enter: the
    /// cells are settled as questions need them (see the [module documentation](self)).
    ///
    /// Errors: [`PlanError::OutOfBounds`] or [`PlanError::StartBlocked`] for a bad source,
    /// [`PlanError::CapacityExceeded`] if the grid is larger than `N`. On error the previous
    /// field is forgotten.
    pub fn start<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        source: Cell,
    ) -> Result<(), PlanError> {
        self.geometry = NO_GEOMETRY;
        let sweep = self.sweep.get_mut();
        sweep.reached = 0;
        sweep.done = true;
        let n = trav.geometry().cell_count();
        if n > N {
            return Err(PlanError::CapacityExceeded {
                needed: n,
                capacity: N,
            });
        }
        let (s, _) = trav.check_endpoints(source, source)?;
        sweep.codes[..n].copy_from_slice(trav.codes());
        sweep.masks[..n].copy_from_slice(trav.move_masks());
        sweep.cells = n;
        sweep.width = trav.geometry().width;
        sweep.factors = trav.step_factors();
        sweep.uniform = trav.uniform_costs();
        sweep.done = false;
        // The longest step: a diagonal into a cell of the largest cost factor (at least 1).
        sweep
            .memory
            .start_sweep(s, sweep.width, n, DIAGONAL * trav.max_factor());
        self.geometry = *trav.geometry();
        self.source = source;
        Ok(())
    }

    /// Sweeps from `source` over every cell reachable from it, at once. Returns the number of
    /// cells reached (the source included).
    ///
    /// Errors: as [`Self::start`].
    pub fn compute<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        source: Cell,
    ) -> Result<u32, PlanError> {
        self.start(trav, source)?;
        let sweep = self.sweep.get_mut();
        sweep.run_until(None);
        Ok(sweep.reached)
    }

    /// Source of the last sweep (meaningless before the first).
    pub fn source(&self) -> Cell {
        self.source
    }

    /// Cells settled so far by the current sweep: all the reachable cells after
    /// [`Self::compute`] (0 before the first sweep).
    pub fn reached(&self) -> u32 {
        self.state().reached
    }

    /// Flat index of `cell` once settled; `None` if outside the grid, unreachable, or no
    /// sweep was made. A cell the robot may not enter (blocked in the layer the sweep copied)
    /// is answered at once: it is never settled, so asking the sweep would settle every
    /// reachable cell of the map before saying so.
    #[inline]
    fn index(&self, cell: Cell) -> Option<usize> {
        let i = self.swept()?.index(cell)?;
        if self.state().codes[i] == CODE_BLOCKED {
            return None;
        }
        self.settle(Some(i));
        let memory = &self.state().memory;
        memory.is_closed_in(i, memory.generation()).then_some(i)
    }

    /// Cost of the shortest path from the source to `cell` \[m\]; `None` if the cell is
    /// unreachable, outside the grid, or no sweep was made. O(1) once the sweep has passed
    /// the cell.
    #[inline]
    pub fn distance_to(&self, cell: Cell) -> Option<f32> {
        let i = self.index(cell)?;
        Some(self.state().memory.g(i) * self.swept()?.resolution_m)
    }

    /// Whether `cell` is reachable from the source.
    #[inline]
    pub fn is_reachable(&self, cell: Cell) -> bool {
        self.index(cell).is_some()
    }

    /// The first step from the source towards `cell` (the cell itself if adjacent, the source
    /// if `cell` is the source); `None` if unreachable. O(path length).
    pub fn first_step_towards(&self, cell: Cell) -> Option<Cell> {
        let g = self.swept()?;
        let mut i = self.index(cell)?;
        let memory = &self.state().memory;
        let mut prev = i;
        while let Some(p) = memory.parent(i) {
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
        let g = self.swept().ok_or(no_path)?;
        if !g.contains(cell) {
            return Err(PlanError::OutOfBounds {
                cell,
                width: g.width,
                height: g.height,
            });
        }
        let i = self.index(cell).ok_or(no_path)?;
        let sweep = self.state();
        let len = sweep.memory.write_path(i, g.width, path)?;
        Ok(PlannedPath {
            len,
            length_m: path_length_m(&path[..len], g.resolution_m),
            cost_m: sweep.memory.g(i) * g.resolution_m,
            expansions: sweep.reached,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::{CellClass, LogOddsBounds, OccupancyGrid};
    use crate::planner::{TraversabilityConfig, UnknownPolicy};
    use crate::random;

    const W: usize = 30;
    const H: usize = 20;
    const CAP: usize = W * H;

    /// Random walls (Occupied), Unknown and Free cells; Unknown costs `unknown_cost`.
    fn random_trav(rng: &mut random::ProjectRng, density: f32) -> Traversability<CAP> {
        let g = GridGeometry::new(W, H, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
        let config = TraversabilityConfig {
            robot_radius_m: 0.0,
            unknown_policy: UnknownPolicy::Traversable {
                cost_factor: 1.0 + random::unit_f32(rng),
            },
            bands: crate::planner::WallBands::NONE,
        };
        let mut trav = Traversability::<CAP>::new(g, config).unwrap();
        for i in 0..CAP {
            let u = random::unit_f32(rng);
            let class = if u < density {
                CellClass::Occupied
            } else if u < density + 0.3 {
                CellClass::Unknown
            } else {
                CellClass::Free
            };
            grid.set_class(i, class, &mut trav);
        }
        trav
    }

    fn passable_cell(rng: &mut random::ProjectRng, trav: &Traversability<CAP>) -> Cell {
        loop {
            let c = trav.geometry().cell(random::below(rng, CAP));
            if trav.is_passable(c) {
                return c;
            }
        }
    }

    /// Asks `lazy` and `full` the same questions about `cell` and checks the answers agree to
    /// the bit.
    fn same_answers(lazy: &DistanceField<CAP>, full: &DistanceField<CAP>, cell: Cell) {
        let (a, b) = (lazy.distance_to(cell), full.distance_to(cell));
        assert_eq!(
            a.map(f32::to_bits),
            b.map(f32::to_bits),
            "distance to {cell:?}"
        );
        assert_eq!(lazy.is_reachable(cell), full.is_reachable(cell));
        assert_eq!(lazy.first_step_towards(cell), full.first_step_towards(cell));
        let mut pa = [Cell::default(); CAP];
        let mut pb = [Cell::default(); CAP];
        match (lazy.path_to(cell, &mut pa), full.path_to(cell, &mut pb)) {
            (Ok(x), Ok(y)) => {
                assert_eq!(pa[..x.len], pb[..y.len], "path to {cell:?}");
                assert_eq!(x.cost_m.to_bits(), y.cost_m.to_bits());
                assert_eq!(x.length_m.to_bits(), y.length_m.to_bits());
            }
            (x, y) => assert_eq!(x.err(), y.err()),
        }
    }

    #[test]
    fn a_lazy_sweep_answers_exactly_as_a_full_one() {
        let mut rng = random::seeded(11);
        let mut lazy = DistanceField::<CAP>::new();
        let mut full = DistanceField::<CAP>::new();
        for case in 0..60 {
            let trav = random_trav(&mut rng, [0.1, 0.25, 0.4][case % 3]);
            let source = passable_cell(&mut rng, &trav);
            lazy.start(&trav, source).unwrap();
            let total = full.compute(&trav, source).unwrap();
            assert_eq!(full.reached(), total);
            for _ in 0..40 {
                let cell = Cell::new(
                    random::below(&mut rng, W + 2) as i32 - 1,
                    random::below(&mut rng, H + 2) as i32 - 1,
                );
                same_answers(&lazy, &full, cell);
                assert!(lazy.reached() <= total);
            }
            // Every cell, in index order: the sweep ends where the full one did.
            for i in 0..CAP {
                same_answers(&lazy, &full, trav.geometry().cell(i));
            }
            assert_eq!(lazy.reached(), total);
        }
    }

    #[test]
    fn a_question_about_a_near_cell_settles_only_the_cells_closer_than_it() {
        let trav = Traversability::<CAP>::from_blocked(W, H, |_| false).unwrap();
        let mut field = DistanceField::<CAP>::new();
        let source = Cell::new(2, 2);
        field.start(&trav, source).unwrap();
        assert_eq!(field.reached(), 0);
        let step_m = trav.geometry().resolution_m;
        assert_eq!(field.distance_to(Cell::new(3, 2)), Some(step_m));
        // The source and at most its 8 neighbours.
        assert!((1..=9).contains(&field.reached()), "{}", field.reached());
        assert!(field.is_reachable(Cell::new(12, 2)));
        assert!(field.reached() < CAP as u32 / 2, "{}", field.reached());
        // Outside the grid: no answer, and the sweep did not move.
        let before = field.reached();
        assert_eq!(field.distance_to(Cell::new(-1, 0)), None);
        assert_eq!(field.reached(), before);
    }

    #[test]
    fn a_lazy_sweep_keeps_the_traversability_it_started_on() {
        let mut rng = random::seeded(4);
        let mut trav = random_trav(&mut rng, 0.15);
        let source = passable_cell(&mut rng, &trav);
        let mut lazy = DistanceField::<CAP>::new();
        let mut full = DistanceField::<CAP>::new();
        lazy.start(&trav, source).unwrap();
        full.compute(&trav, source).unwrap();
        // Walls everywhere once the lazy sweep has started: its answers stay those of the
        // layer it started on.
        let mut grid =
            OccupancyGrid::<CAP>::new(*trav.geometry(), LogOddsBounds::default()).unwrap();
        for i in 0..CAP {
            grid.set_class(i, CellClass::Occupied, &mut trav);
        }
        assert!(!trav.is_passable(source));
        for i in 0..CAP {
            same_answers(&lazy, &full, trav.geometry().cell(i));
        }
        assert!(lazy.reached() > 1);
    }

    #[test]
    fn a_failed_start_forgets_the_previous_sweep() {
        let trav = Traversability::<CAP>::from_blocked(W, H, |c| c == Cell::new(0, 0)).unwrap();
        let mut field = DistanceField::<CAP>::new();
        field.start(&trav, Cell::new(5, 5)).unwrap();
        assert!(field.is_reachable(Cell::new(6, 5)));
        assert_eq!(
            field.start(&trav, Cell::new(0, 0)),
            Err(PlanError::StartBlocked {
                cell: Cell::new(0, 0)
            })
        );
        assert!(!field.is_reachable(Cell::new(6, 5)));
        assert_eq!(field.reached(), 0);
    }
}
