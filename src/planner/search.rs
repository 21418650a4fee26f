//! Working memory shared by A* and the distance field: per-cell g-values, parents and
//! generation stamps, and an indexed 4-ary min-heap with decrease-key (the d-ary heap of
//! Johnson, "Priority queues with update and finding minimum spanning trees", Information
//! Processing Letters 4(3), 1975). Nothing is cleared between queries: a cell's entries are
//! valid only if its stamp carries the current generation.

use super::traversability::{CODE_BLOCKED, CODE_FREE, Traversability};

/// Diagonal step \[cells\].
pub(crate) const DIAGONAL: f32 = core::f32::consts::SQRT_2;

const NO_PARENT: u32 = u32::MAX;

/// Per-cell state read on every relaxation.
#[derive(Clone, Copy)]
struct Node {
    /// `2 * generation` when the cell was reached this query, `+ 1` once it is closed.
    stamp: u32,
    g: f32,
}

/// An open-list entry.
#[derive(Clone, Copy)]
struct Entry {
    key: u64,
    idx: u32,
}

const ZERO_NODE: Node = Node { stamp: 0, g: 0.0 };

const ZERO_ENTRY: Entry = Entry { key: 0, idx: 0 };

/// Relative slack of the bypass test, one unit in the last place of an f32. Along a straight
/// diagonal run f stays constant in exact arithmetic but wobbles by rounding; the slack lets
/// such cells bypass the heap too. Every cell taken from the stack then has f at most
/// `BYPASS_SLACK` times the open list's minimum, so a path found costs at most that factor
/// times the optimum (1.2e-7 relative, the size of the rounding of the f32 sums themselves).
const BYPASS_SLACK: f32 = 1.0 + f32::EPSILON;

/// `pos` of a cell waiting on the bypass stack rather than in the heap.
const ON_STACK: u32 = u32::MAX;

/// Open list: a 4-ary heap growing from the front of `heap`, plus a bypass stack of cell
/// indices growing from its back. A cell opened with f no greater than the open list's minimum
/// (up to [`BYPASS_SLACK`]) would go straight to the top of the heap; it is pushed on the stack
/// instead and expanded next, skipping two heap operations (one of the optimisations of Sun,
/// Yeoh, Chen & Koenig, "Simple optimization techniques for A*-based search", AAMAS 2009). It
/// pays on open ground, where straight runs keep f constant. Heap and stack never hold more
/// than the open cells, fewer than `N`, so they share one array.
pub(crate) struct SearchMemory<const N: usize> {
    /// Read on every relaxation: kept small.
    nodes: [Node; N],
    /// Parent of each reached cell (`NO_PARENT` for the source).
    parents: [u32; N],
    /// Heap position of each open cell (or `ON_STACK`).
    pos: [u32; N],
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
        Self {
            nodes: [ZERO_NODE; N],
            parents: [0; N],
            pos: [0; N],
            heap: [ZERO_ENTRY; N],
            heap_len: 0,
            stack_len: 0,
            bypass_limit: 0.0,
            generation: 0,
        }
    }

    /// Starts a query: new generation, empty heap.
    pub(crate) fn begin(&mut self) {
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
        let p = self.parents[i];
        (p != NO_PARENT).then_some(p as usize)
    }

    /// Opens the source cell with g = 0.
    pub(crate) fn open_source(&mut self, i: usize, key: f32) {
        self.nodes[i] = Node {
            stamp: 2 * self.generation,
            g: 0.0,
        };
        self.parents[i] = NO_PARENT;
        self.push(i, make_key(key, 0.0));
    }

    /// Relaxes the edge `from -> to` with tentative cost `g`; `h` gives the heuristic of `to`
    /// (called only when `to` is opened or improved).
    #[inline(always)]
    pub(crate) fn relax(&mut self, from: usize, to: usize, g: f32, h: impl FnOnce() -> f32) {
        let seen = 2 * self.generation;
        let node = &mut self.nodes[to];
        if node.stamp == seen + 1 {
            return; // closed
        }
        if node.stamp == seen {
            if g >= node.g {
                return;
            }
            node.g = g;
            self.parents[to] = from as u32;
            if self.pos[to] == ON_STACK {
                return; // expanded before any heap entry anyway
            }
            let p = self.pos[to] as usize;
            self.heap[p].key = make_key(g + h(), g);
            self.sift_up(p);
        } else {
            node.stamp = seen;
            node.g = g;
            self.parents[to] = from as u32;
            let f = g + h();
            if f <= self.bypass_limit {
                self.pos[to] = ON_STACK;
                self.stack_len += 1;
                self.heap[N - self.stack_len].idx = to as u32;
            } else {
                self.push(to, make_key(f, g));
            }
        }
    }

    /// Removes the best open cell and closes it.
    #[inline]
    pub(crate) fn pop_and_close(&mut self) -> Option<usize> {
        let top = if self.stack_len > 0 {
            let top = self.heap[N - self.stack_len].idx as usize;
            self.stack_len -= 1;
            top
        } else {
            if self.heap_len == 0 {
                return None;
            }
            let Entry { key, idx } = self.heap[0];
            let top = idx as usize;
            self.bypass_limit = f32::from_bits((key >> 32) as u32) * BYPASS_SLACK;
            self.heap_len -= 1;
            if self.heap_len > 0 {
                self.heap[0] = self.heap[self.heap_len];
                self.sift_down(0);
            }
            top
        };
        self.nodes[top].stamp = 2 * self.generation + 1;
        Some(top)
    }

    #[inline]
    fn push(&mut self, i: usize, key: u64) {
        // Each cell is in the heap at most once, so `heap_len < N` here.
        let p = self.heap_len;
        self.heap_len += 1;
        self.heap[p] = Entry { key, idx: i as u32 };
        self.sift_up(p);
    }

    #[inline]
    fn sift_up(&mut self, mut p: usize) {
        let e = self.heap[p];
        while p > 0 {
            let parent = (p - 1) / 4;
            let up = self.heap[parent];
            if up.key <= e.key {
                break;
            }
            self.heap[p] = up;
            self.pos[up.idx as usize] = p as u32;
            p = parent;
        }
        self.heap[p] = e;
        self.pos[e.idx as usize] = p as u32;
    }

    /// Fills the hole at `p` with the entry moved there: Floyd's bottom-up variant (the hole
    /// sinks to a leaf along the smallest children, then the entry rises), which saves the
    /// comparisons against the entry on the way down.
    #[inline]
    fn sift_down(&mut self, mut p: usize) {
        let e = self.heap[p];
        let len = self.heap_len;
        loop {
            let first = 4 * p + 1;
            if first >= len {
                break;
            }
            let mut child = first;
            let mut best = self.heap[first].key;
            for c in first + 1..(first + 4).min(len) {
                let k = self.heap[c].key;
                if k < best {
                    best = k;
                    child = c;
                }
            }
            let down = self.heap[child];
            self.heap[p] = down;
            self.pos[down.idx as usize] = p as u32;
            p = child;
        }
        self.heap[p] = e;
        self.sift_up(p);
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

/// Heap key: f first (non-negative floats order like their bits), then larger g first.
#[inline]
fn make_key(f: f32, g: f32) -> u64 {
    ((f.to_bits() as u64) << 32) | (!g.to_bits()) as u64
}

/// One legal move: the entered cell's index and coordinates, and the step cost \[cells\]
/// already multiplied by the entered cell's cost factor.
#[derive(Clone, Copy, Default)]
pub(crate) struct Move {
    pub(crate) to: usize,
    pub(crate) col: usize,
    pub(crate) row: usize,
    pub(crate) step: f32,
}

/// Writes into `out` every legal move out of cell `i` = (`col`, `row`) and returns how many:
/// orthogonal steps into passable cells, diagonal steps into passable cells whose two
/// orthogonal neighbours are passable too (no corner cutting).
#[inline(always)]
pub(crate) fn moves<const N: usize>(
    trav: &Traversability<N>,
    i: usize,
    col: usize,
    row: usize,
    out: &mut [Move; 8],
) -> usize {
    let codes = trav.codes();
    let w = trav.geometry().width;
    let h = trav.geometry().height;
    let uf = trav.unknown_factor();
    let factor = |c: u8| if c == CODE_FREE { 1.0 } else { uf };
    let mut n = 0;
    let mut add = |to: usize, col: usize, row: usize, step: f32| {
        out[n] = Move { to, col, row, step };
        n += 1;
    };
    let west = col > 0 && codes[i - 1] != CODE_BLOCKED;
    let east = col + 1 < w && codes[i + 1] != CODE_BLOCKED;
    let south = row > 0 && codes[i - w] != CODE_BLOCKED;
    let north = row + 1 < h && codes[i + w] != CODE_BLOCKED;
    if west {
        add(i - 1, col - 1, row, factor(codes[i - 1]));
    }
    if east {
        add(i + 1, col + 1, row, factor(codes[i + 1]));
    }
    if south {
        add(i - w, col, row - 1, factor(codes[i - w]));
        if west && codes[i - w - 1] != CODE_BLOCKED {
            add(
                i - w - 1,
                col - 1,
                row - 1,
                DIAGONAL * factor(codes[i - w - 1]),
            );
        }
        if east && codes[i - w + 1] != CODE_BLOCKED {
            add(
                i - w + 1,
                col + 1,
                row - 1,
                DIAGONAL * factor(codes[i - w + 1]),
            );
        }
    }
    if north {
        add(i + w, col, row + 1, factor(codes[i + w]));
        if west && codes[i + w - 1] != CODE_BLOCKED {
            add(
                i + w - 1,
                col - 1,
                row + 1,
                DIAGONAL * factor(codes[i + w - 1]),
            );
        }
        if east && codes[i + w + 1] != CODE_BLOCKED {
            add(
                i + w + 1,
                col + 1,
                row + 1,
                DIAGONAL * factor(codes[i + w + 1]),
            );
        }
    }
    n
}

/// Octile distance between cells `(c0, r0)` and `(c1, r1)` \[cells\]: the exact cost on an
/// empty grid, a lower bound whenever cost factors are at least 1.
#[inline(always)]
pub(crate) fn octile(c0: usize, r0: usize, c1: usize, r1: usize) -> f32 {
    let dc = c0.abs_diff(c1) as f32;
    let dr = r0.abs_diff(r1) as f32;
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
