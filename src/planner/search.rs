//! Working memory shared by A* and the distance field: per-cell g-values, parents and
//! generation stamps, and an indexed 4-ary min-heap with decrease-key (the d-ary heap of
//! Johnson, "Priority queues with update and finding minimum spanning trees", Information
//! Processing Letters 4(3), 1975). Nothing is cleared between queries: a cell's entries are
//! valid only if its stamp carries the current generation.

use super::traversability::{MOVES, Traversability};

/// Diagonal step \[cells\].
pub(crate) const DIAGONAL: f32 = core::f32::consts::SQRT_2;

const NO_PARENT: u32 = u32::MAX;

/// Per-cell state read on every relaxation: kept to 8 bytes so that the cells a search
/// touches stay in cache.
#[derive(Clone, Copy)]
struct Node {
    /// `2 * generation` when the cell was reached this query, `+ 1` once it is closed.
    stamp: u32,
    g: f32,
}

/// Per-cell state written when a cell is opened or improved.
#[derive(Clone, Copy)]
struct Link {
    /// Parent cell times 8 plus the index in [`MOVES`] of the step from it
    /// (`NO_PARENT` for the source).
    parent: u32,
    /// Heap position while open (or `ON_STACK`).
    pos: u32,
}

/// An open-list entry: the cell and its row (its column follows from the index without a
/// division).
#[derive(Clone, Copy)]
struct Entry {
    key: u64,
    idx: u32,
    row: u32,
}

const ZERO_NODE: Node = Node { stamp: 0, g: 0.0 };

const ZERO_LINK: Link = Link { parent: 0, pos: 0 };

const ZERO_ENTRY: Entry = Entry {
    key: 0,
    idx: 0,
    row: 0,
};

/// Relative slack of the bypass test, one unit in the last place of an f32. Along a straight
/// diagonal run f stays constant in exact arithmetic but wobbles by rounding; the slack lets
/// such cells bypass the heap too. Every cell taken from the stack then has f at most
/// `BYPASS_SLACK` times the open list's minimum, so a path found costs at most that factor
/// times the optimum (1.2e-7 relative, the size of the rounding of the f32 sums themselves).
const BYPASS_SLACK: f32 = 1.0 + f32::EPSILON;

/// `pos` of a cell waiting on the bypass stack rather than in the heap.
const ON_STACK: u32 = u32::MAX;

/// A lower bound on the cost from a cell to the goal \[cells\].
pub(crate) trait Heuristic: Copy {
    fn at(self, col: usize, row: usize) -> f32;
}

/// Octile distance to a goal cell (A*).
#[derive(Clone, Copy)]
pub(crate) struct Octile {
    pub(crate) col: usize,
    pub(crate) row: usize,
}

impl Heuristic for Octile {
    #[inline(always)]
    fn at(self, col: usize, row: usize) -> f32 {
        octile(col, row, self.col, self.row)
    }
}

/// No heuristic (Dijkstra).
#[derive(Clone, Copy)]
pub(crate) struct Zero;

impl Heuristic for Zero {
    #[inline(always)]
    fn at(self, _: usize, _: usize) -> f32 {
        0.0
    }
}

/// What a search reads of the grid: its width, each cell's legal moves and step code, and the
/// Unknown cost factor (a view of a [`Traversability`] layer, or of a copy of it).
#[derive(Clone, Copy)]
pub(crate) struct StepCosts<'a> {
    pub(crate) width: usize,
    /// Move masks, flat-index order (bit `k`: step [`MOVES`]`[k]` is legal).
    pub(crate) masks: &'a [u8],
    /// Step codes, flat-index order.
    pub(crate) codes: &'a [u8],
    pub(crate) unknown_factor: f32,
    /// Every legal step costs its plain length.
    pub(crate) uniform: bool,
}

impl<'a> StepCosts<'a> {
    pub(crate) fn of<const M: usize>(trav: &'a Traversability<M>) -> Self {
        Self {
            width: trav.geometry().width,
            masks: trav.move_masks(),
            codes: trav.codes(),
            unknown_factor: trav.unknown_factor(),
            uniform: trav.uniform_costs(),
        }
    }
}

/// Open list: a 4-ary heap growing from the front of `heap`, plus a bypass stack of cells
/// growing from its back. A cell opened with f no greater than the open list's minimum (up to
/// [`BYPASS_SLACK`]) would go straight to the top of the heap; it is pushed on the stack
/// instead and expanded next, skipping two heap operations (one of the optimisations of Sun,
/// Yeoh, Chen & Koenig, "Simple optimization techniques for A*-based search", AAMAS 2009). It
/// pays on open ground, where straight runs keep f constant. Heap and stack never hold more
/// than the open cells, fewer than `N`, so they share one array.
pub(crate) struct SearchMemory<const N: usize> {
    nodes: [Node; N],
    links: [Link; N],
    heap: [Entry; N],
    heap_len: usize,
    stack_len: usize,
    /// New cells with f up to this bypass the heap: the f of the last cell taken from the
    /// heap (the open list's minimum then) times [`BYPASS_SLACK`].
    bypass_limit: f32,
    generation: u32,
}

impl<const N: usize> SearchMemory<N> {
    pub(crate) const fn new() -> Self {
        const {
            assert!(
                N < 1 << 29,
                "parent links hold a cell index times 8 in a u32"
            )
        };
        Self {
            nodes: [ZERO_NODE; N],
            links: [ZERO_LINK; N],
            heap: [ZERO_ENTRY; N],
            heap_len: 0,
            stack_len: 0,
            bypass_limit: 0.0,
            generation: 0,
        }
    }

    /// Starts a query: new generation, empty heap.
    fn begin(&mut self) {
        self.heap_len = 0;
        self.stack_len = 0;
        self.bypass_limit = 0.0;
        if self.generation >= u32::MAX / 2 - 1 {
            self.nodes.fill(ZERO_NODE);
            self.generation = 0;
        }
        self.generation += 1;
    }

    #[inline]
    pub(crate) fn generation(&self) -> u32 {
        self.generation
    }

    #[inline]
    pub(crate) fn is_closed_in(&self, i: usize, generation: u32) -> bool {
        self.nodes[i].stamp == 2 * generation + 1
    }

    #[inline]
    pub(crate) fn g(&self, i: usize) -> f32 {
        self.nodes[i].g
    }

    #[inline]
    pub(crate) fn parent(&self, i: usize) -> Option<usize> {
        let p = self.links[i].parent;
        (p != NO_PARENT).then_some((p >> 3) as usize)
    }

    /// Best-first search from `source` over `trav`, guided by `h`, until `target` is closed
    /// (`Some` of the number of cells closed) or every reachable cell is (`None`; pass an
    /// index outside the grid to sweep them all). `source` must be a passable cell of `trav`,
    /// and the grid must have at most `N` cells.
    pub(crate) fn search<const M: usize>(
        &mut self,
        trav: &Traversability<M>,
        source: usize,
        target: usize,
        h: impl Heuristic,
    ) -> (u32, bool) {
        self.start(source, trav.geometry().width, h);
        self.resume(&StepCosts::of(trav), target, h)
    }

    /// Starts a search from `source` (a passable cell of a grid `width` cells wide): new
    /// generation, only the source open. [`Self::resume`] runs it.
    pub(crate) fn start(&mut self, source: usize, width: usize, h: impl Heuristic) {
        self.begin();
        let (sc, sr) = (source % width, source / width);
        self.open_source(source, sr, h.at(sc, sr));
    }

    /// Runs the search started by [`Self::start`] (or left by an earlier call) until `target`
    /// is closed or nothing is open; returns the number of cells closed by this call and
    /// whether `target` was reached. Every closed cell is expanded before the call returns,
    /// so a search stopped at one target and resumed later closes cells in the same order as
    /// one that never stopped. `costs` must describe the same grid on every call of one
    /// search.
    pub(crate) fn resume(
        &mut self,
        costs: &StepCosts<'_>,
        target: usize,
        h: impl Heuristic,
    ) -> (u32, bool) {
        if costs.uniform {
            self.run::<true>(costs, target, h)
        } else {
            self.run::<false>(costs, target, h)
        }
    }

    /// [`Self::resume`]; `UNIFORM`: every step costs its plain length (no cost factor to
    /// look up).
    #[inline(always)]
    fn run<const UNIFORM: bool>(
        &mut self,
        costs: &StepCosts<'_>,
        target: usize,
        h: impl Heuristic,
    ) -> (u32, bool) {
        let w = costs.width;
        let masks = costs.masks;
        let codes = costs.codes;
        // Cost factor by step code: blocked (never entered), Free, Unknown.
        let factors = [0.0, 1.0, costs.unknown_factor];
        let offsets = MOVES.map(|(dc, dr)| (dc as isize + dr as isize * w as isize) as usize);
        let steps = MOVES.map(|(dc, dr)| if dc != 0 && dr != 0 { DIAGONAL } else { 1.0 });
        let mut closed = 0u32;
        while let Some(Entry { idx, row, .. }) = self.pop_and_close() {
            closed += 1;
            let i = idx as usize;
            let row = row as usize;
            let col = i - row * w;
            let gi = self.nodes[i].g;
            let parent = self.links[i].parent;
            // Steps into the parent's neighbourhood cannot improve anything: see
            // [`SKIP_AFTER`].
            let mask = if parent == NO_PARENT {
                masks[i]
            } else {
                let p_mask = masks[(parent >> 3) as usize];
                let p_mask = if UNIFORM { p_mask } else { p_mask & ORTHOGONAL };
                masks[i] & !SKIP_AFTER[(parent & 7) as usize][p_mask as usize]
            };
            // One block per direction, unrolled so that offsets and step lengths are
            // constants of the block.
            macro_rules! step {
                ($k:expr) => {
                    if mask & (1 << $k) != 0 {
                        let to = i.wrapping_add(offsets[$k]);
                        let step = if UNIFORM {
                            steps[$k]
                        } else {
                            steps[$k] * factors[codes[to] as usize]
                        };
                        let (dc, dr) = MOVES[$k];
                        let tc = col.wrapping_add(dc as usize);
                        let tr = row.wrapping_add(dr as usize);
                        self.relax(idx << 3 | $k, to, tr, gi + step, || h.at(tc, tr));
                    }
                };
            }
            step!(0);
            step!(1);
            step!(2);
            step!(3);
            step!(4);
            step!(5);
            step!(6);
            step!(7);
            if i == target {
                return (closed, true);
            }
        }
        (closed, false)
    }

    /// Opens the source cell with g = 0.
    fn open_source(&mut self, i: usize, row: usize, key: f32) {
        self.nodes[i] = Node {
            stamp: 2 * self.generation,
            g: 0.0,
        };
        self.links[i] = Link {
            parent: NO_PARENT,
            pos: 0,
        };
        self.push(make_key(key, 0.0), i, row);
    }

    /// Relaxes the edge `from -> to` with tentative cost `g`; `h` gives the heuristic of `to`
    /// (called only when `to` is opened or improved). `from` is the parent link: the cell
    /// index times 8 plus the step's index in [`MOVES`].
    #[inline(always)]
    fn relax(&mut self, from: u32, to: usize, row: usize, g: f32, h: impl FnOnce() -> f32) {
        let seen = 2 * self.generation;
        let node = &mut self.nodes[to];
        if node.stamp == seen {
            if g >= node.g {
                return;
            }
            node.g = g;
            let link = &mut self.links[to];
            link.parent = from;
            if link.pos == ON_STACK {
                return; // expanded before any heap entry anyway
            }
            let p = link.pos as usize;
            self.heap[p].key = make_key(g + h(), g);
            self.sift_up(p);
        } else if node.stamp != seen + 1 {
            let f = g + h();
            if f <= self.bypass_limit {
                *node = Node { stamp: seen, g };
                self.links[to] = Link {
                    parent: from,
                    pos: ON_STACK,
                };
                self.stack_len += 1;
                self.heap[N - self.stack_len] = Entry {
                    key: 0,
                    idx: to as u32,
                    row: row as u32,
                };
            } else {
                *node = Node { stamp: seen, g };
                self.links[to] = Link {
                    parent: from,
                    pos: 0,
                };
                self.push(make_key(f, g), to, row);
            }
        }
    }

    /// Removes the best open cell and closes it.
    #[inline(always)]
    fn pop_and_close(&mut self) -> Option<Entry> {
        let top = if self.stack_len > 0 {
            let top = self.heap[N - self.stack_len];
            self.stack_len -= 1;
            top
        } else {
            if self.heap_len == 0 {
                return None;
            }
            let top = self.heap[0];
            self.bypass_limit = f32::from_bits((top.key >> 32) as u32) * BYPASS_SLACK;
            self.heap_len -= 1;
            if self.heap_len > 0 {
                self.heap[0] = self.heap[self.heap_len];
                self.sift_down(0);
            }
            top
        };
        self.nodes[top.idx as usize].stamp = 2 * self.generation + 1;
        Some(top)
    }

    #[inline(always)]
    fn push(&mut self, key: u64, i: usize, row: usize) {
        // Each cell is in the heap at most once, so `heap_len < N` here.
        let p = self.heap_len;
        self.heap_len += 1;
        self.heap[p] = Entry {
            key,
            idx: i as u32,
            row: row as u32,
        };
        self.sift_up(p);
    }

    #[inline(always)]
    fn sift_up(&mut self, p: usize) {
        let len = self.heap_len;
        sift_up(&mut self.heap[..len], &mut self.links, p);
    }

    /// Fills the hole at `p` with the entry moved there: Floyd's bottom-up variant (the hole
    /// sinks to a leaf along the smallest children, then the entry rises), which saves the
    /// comparisons against the entry on the way down.
    #[inline]
    fn sift_down(&mut self, mut p: usize) {
        let len = self.heap_len;
        // Working on the slice of live entries lets the compiler drop the bounds checks that
        // the `< heap.len()` tests already imply.
        let heap = &mut self.heap[..len];
        let links = &mut self.links;
        let e = heap[p];
        loop {
            let first = 4 * p + 1;
            let child = if let Some(c) = heap.get(first..first + 4) {
                // Smallest of four, as two independent pairs then their winners.
                let a = (c[1].key < c[0].key) as usize;
                let b = 2 + (c[3].key < c[2].key) as usize;
                first + if c[b].key < c[a].key { b } else { a }
            } else if first < heap.len() {
                let mut child = first;
                for c in first + 1..heap.len() {
                    if heap[c].key < heap[child].key {
                        child = c;
                    }
                }
                child
            } else {
                break;
            };
            // SAFETY: `child < heap.len()` (tested above); `p` is the start, checked by the
            // read of `e`, or an earlier child; the cell index of every heap entry passed a
            // checked access to `links` when it was pushed (`open_source`, `relax`).
            unsafe {
                let down = *heap.get_unchecked(child);
                *heap.get_unchecked_mut(p) = down;
                links.get_unchecked_mut(down.idx as usize).pos = p as u32;
            }
            p = child;
        }
        heap[p] = e;
        sift_up(heap, links, p);
    }

    /// Writes the path ending at `end` (following parents back to the source) into `out`,
    /// source first. Returns the number of cells.
    pub(crate) fn write_path(
        &self,
        end: usize,
        width: usize,
        out: &mut [crate::grid::Cell],
    ) -> Result<usize, super::PlanError> {
        let mut len = 1usize;
        let mut i = end;
        while let Some(p) = self.parent(i) {
            len += 1;
            i = p;
        }
        if len > out.len() {
            return Err(super::PlanError::CapacityExceeded {
                needed: len,
                capacity: out.len(),
            });
        }
        let mut i = end;
        let mut k = len;
        loop {
            k -= 1;
            out[k] = crate::grid::Cell::new((i % width) as i32, (i / width) as i32);
            match self.parent(i) {
                Some(p) => i = p,
                None => break,
            }
        }
        Ok(len)
    }
}

/// The orthogonal steps of a move mask (west, east, south, north).
const ORTHOGONAL: u8 = 0b0010_0111;

/// `SKIP_AFTER[k][m]`: the steps out of a cell `i` not worth relaxing when `i` was reached by
/// step `k` from its parent `p` and `m` holds (some of) `p`'s legal steps: the step back into
/// `p` (closed) and every step into a cell `t` that `p` reaches by a step in `m`. When `p` was
/// expanded it relaxed `t` with `g(p) + c(p, t)`, and `t`'s cost only falls after that; through
/// `i` the cost is `g(p) + c(p, i) + c(i, t)`, which is no smaller when the step costs obey the
/// triangle inequality `c(p, i) + c(i, t) >= c(p, t)`. With plain lengths they do for every
/// step (the smallest gap, 2 - sqrt(2) cells, dwarfs the f32 rounding of g below 2^21 cells).
/// With cost factors `>= 1` on the entered cell they do when `p -> t` is orthogonal
/// (`c(i, t) >= c(p, t)` already), not always when it is diagonal, so the search then passes
/// only `p`'s orthogonal steps. Such relaxations would change nothing, so skipping them leaves
/// the search step for step the same, only cheaper: about half of a cell's eight neighbours
/// are the parent's neighbours. (The same neighbourhood argument is the basis of the pruning
/// in Harabor & Grastien, "Online graph pruning for pathfinding on grid maps", AAAI 2011; here
/// it only removes relaxations that cannot succeed, with no change to what A* expands.)
static SKIP_AFTER: [[u8; 256]; 8] = skip_after();

const fn skip_after() -> [[u8; 256]; 8] {
    let mut table = [[0u8; 256]; 8];
    let mut k = 0;
    while k < 8 {
        let mut m = 0;
        while m < 256 {
            let mut skip = 0u8;
            let mut j = 0;
            while j < 8 {
                // t - p = step k + step j.
                let dc = MOVES[k].0 + MOVES[j].0;
                let dr = MOVES[k].1 + MOVES[j].1;
                if dc == 0 && dr == 0 {
                    skip |= 1 << j;
                } else {
                    let mut s = 0;
                    while s < 8 {
                        if MOVES[s].0 == dc && MOVES[s].1 == dr && m & (1 << s) != 0 {
                            skip |= 1 << j;
                        }
                        s += 1;
                    }
                }
                j += 1;
            }
            table[k][m] = skip;
            m += 1;
        }
        k += 1;
    }
    table
}

/// Moves the entry at `p` up `heap` until its parent's key is no larger, recording every
/// entry's new position in `links`.
#[inline(always)]
fn sift_up(heap: &mut [Entry], links: &mut [Link], mut p: usize) {
    let e = heap[p];
    while p > 0 {
        let parent = (p - 1) / 4;
        // SAFETY: `parent < p < heap.len()` (`p` was checked by the read of `e`), and the
        // cell index of every heap entry passed a checked access to `links` when it was
        // pushed (`open_source`, `relax`).
        let up = unsafe { *heap.get_unchecked(parent) };
        if up.key <= e.key {
            break;
        }
        unsafe {
            *heap.get_unchecked_mut(p) = up;
            links.get_unchecked_mut(up.idx as usize).pos = p as u32;
        }
        p = parent;
    }
    heap[p] = e;
    links[e.idx as usize].pos = p as u32;
}

/// Heap key: f first (non-negative floats order like their bits), then larger g first.
#[inline]
fn make_key(f: f32, g: f32) -> u64 {
    ((f.to_bits() as u64) << 32) | (!g.to_bits()) as u64
}

/// Octile distance between cells `(c0, r0)` and `(c1, r1)` \[cells\]: the exact cost on an
/// empty grid, a lower bound whenever cost factors are at least 1.
#[inline(always)]
pub(crate) fn octile(c0: usize, r0: usize, c1: usize, r1: usize) -> f32 {
    // Cells number fewer than 2^29 (see `SearchMemory::new`), so the differences fit an
    // i32, whose conversion to f32 is one instruction (a u64's is several).
    let dc = (c0 as i32 - c1 as i32).abs() as f32;
    let dr = (r0 as i32 - r1 as i32).abs() as f32;
    let (lo, hi) = if dc < dr { (dc, dr) } else { (dr, dc) };
    (hi - lo) + DIAGONAL * lo
}

#[cfg(feature = "std")]
impl<const N: usize> SearchMemory<N> {
    /// Memory built on the heap.
    pub(crate) fn new_boxed() -> std::boxed::Box<Self> {
        // SAFETY: all fields are integers, floats and arrays of structs of them; all-zero is
        // valid and is what `new` produces.
        unsafe { boxed_zeroed() }
    }
}

/// A `T` allocated on the heap with every byte zero, never built on the stack.
///
/// # Safety
/// The all-zero bit pattern must be a valid `T`.
#[cfg(feature = "std")]
pub(crate) unsafe fn boxed_zeroed<T>() -> std::boxed::Box<T> {
    let layout = std::alloc::Layout::new::<T>();
    if layout.size() == 0 {
        // SAFETY: a zero-sized `T` needs no memory; the caller vouches that zero is valid.
        return unsafe { std::boxed::Box::new(core::mem::zeroed()) };
    }
    // SAFETY: the layout has a non-zero size.
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) } as *mut T;
    if ptr.is_null() {
        std::alloc::handle_alloc_error(layout);
    }
    // SAFETY: `ptr` was allocated by the global allocator with `T`'s layout and holds a valid
    // `T` (all zero, valid per the caller).
    unsafe { std::boxed::Box::from_raw(ptr) }
}
