//! Working memory shared by A* and the distance field: per-cell g-values, parents and
//! generation stamps, and an indexed binary min-heap with decrease-key (Williams, "Algorithm
//! 232: Heapsort", CACM 7(6), 1964). Nothing is cleared between queries: a cell's entries are
//! valid only if its stamp carries the current generation.

use super::traversability::{CODE_BLOCKED, Traversability};

/// Diagonal step [cells].
pub(crate) const DIAGONAL: f32 = core::f32::consts::SQRT_2;

const NO_PARENT: u32 = u32::MAX;

pub(crate) struct SearchMemory<const N: usize> {
    /// `2 * generation` when the cell was reached this query, `+ 1` once it is closed.
    stamp: [u32; N],
    g: [f32; N],
    parent: [u32; N],
    /// Position in the heap while open.
    pos: [u32; N],
    heap_key: [u64; N],
    heap_idx: [u32; N],
    heap_len: usize,
    generation: u32,
}

impl<const N: usize> SearchMemory<N> {
    pub(crate) const fn new() -> Self {
        Self {
            stamp: [0; N],
            g: [0.0; N],
            parent: [0; N],
            pos: [0; N],
            heap_key: [0; N],
            heap_idx: [0; N],
            heap_len: 0,
            generation: 0,
        }
    }

    /// Starts a query: new generation, empty heap.
    pub(crate) fn begin(&mut self) {
        self.heap_len = 0;
        if self.generation >= u32::MAX / 2 - 1 {
            self.stamp.fill(0);
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
        self.stamp[i] == 2 * generation + 1
    }

    #[inline]
    pub(crate) fn g(&self, i: usize) -> f32 {
        self.g[i]
    }

    #[inline]
    pub(crate) fn parent(&self, i: usize) -> Option<usize> {
        let p = self.parent[i];
        (p != NO_PARENT).then_some(p as usize)
    }

    /// Opens the source cell with g = 0.
    pub(crate) fn open_source(&mut self, i: usize, key: f32) {
        self.stamp[i] = 2 * self.generation;
        self.g[i] = 0.0;
        self.parent[i] = NO_PARENT;
        self.push(i, make_key(key, 0.0));
    }

    /// Relaxes the edge `from -> to` with tentative cost `g`; `h` is the heuristic of `to`.
    #[inline]
    pub(crate) fn relax(&mut self, from: usize, to: usize, g: f32, h: f32) {
        let seen = 2 * self.generation;
        let s = self.stamp[to];
        if s == seen + 1 {
            return; // closed
        }
        if s == seen {
            if g >= self.g[to] {
                return;
            }
            self.g[to] = g;
            self.parent[to] = from as u32;
            let p = self.pos[to] as usize;
            self.heap_key[p] = make_key(g + h, g);
            self.sift_up(p);
        } else {
            self.stamp[to] = seen;
            self.g[to] = g;
            self.parent[to] = from as u32;
            self.push(to, make_key(g + h, g));
        }
    }

    /// Removes the best open cell and closes it.
    #[inline]
    pub(crate) fn pop_and_close(&mut self) -> Option<usize> {
        if self.heap_len == 0 {
            return None;
        }
        let top = self.heap_idx[0] as usize;
        self.heap_len -= 1;
        if self.heap_len > 0 {
            self.heap_key[0] = self.heap_key[self.heap_len];
            self.heap_idx[0] = self.heap_idx[self.heap_len];
            self.pos[self.heap_idx[0] as usize] = 0;
            self.sift_down(0);
        }
        self.stamp[top] = 2 * self.generation + 1;
        Some(top)
    }

    #[inline]
    fn push(&mut self, i: usize, key: u64) {
        // Each cell is in the heap at most once, so `heap_len < N` here.
        let p = self.heap_len;
        self.heap_len += 1;
        self.heap_key[p] = key;
        self.heap_idx[p] = i as u32;
        self.pos[i] = p as u32;
        self.sift_up(p);
    }

    #[inline]
    fn sift_up(&mut self, mut p: usize) {
        let key = self.heap_key[p];
        let idx = self.heap_idx[p];
        while p > 0 {
            let parent = (p - 1) / 2;
            if self.heap_key[parent] <= key {
                break;
            }
            self.heap_key[p] = self.heap_key[parent];
            self.heap_idx[p] = self.heap_idx[parent];
            self.pos[self.heap_idx[p] as usize] = p as u32;
            p = parent;
        }
        self.heap_key[p] = key;
        self.heap_idx[p] = idx;
        self.pos[idx as usize] = p as u32;
    }

    #[inline]
    fn sift_down(&mut self, mut p: usize) {
        let key = self.heap_key[p];
        let idx = self.heap_idx[p];
        let len = self.heap_len;
        loop {
            let mut child = 2 * p + 1;
            if child >= len {
                break;
            }
            if child + 1 < len && self.heap_key[child + 1] < self.heap_key[child] {
                child += 1;
            }
            if self.heap_key[child] >= key {
                break;
            }
            self.heap_key[p] = self.heap_key[child];
            self.heap_idx[p] = self.heap_idx[child];
            self.pos[self.heap_idx[p] as usize] = p as u32;
            p = child;
        }
        self.heap_key[p] = key;
        self.heap_idx[p] = idx;
        self.pos[idx as usize] = p as u32;
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

/// Calls `visit(neighbour, step)` for every legal move out of cell `i` = (`col`, `row`):
/// orthogonal steps into passable cells, diagonal steps into passable cells whose two
/// orthogonal neighbours are passable too (no corner cutting). `step` is the move's cost in
/// cells, already multiplied by the entered cell's cost factor.
#[inline(always)]
pub(crate) fn for_each_move<const N: usize>(
    trav: &Traversability<N>,
    i: usize,
    mut visit: impl FnMut(usize, f32),
) {
    let codes = trav.codes();
    let w = trav.geometry().width;
    let h = trav.geometry().height;
    let col = i % w;
    let row = i / w;
    let uf = trav.unknown_factor();
    let factor = |c: u8| if c == super::traversability::CODE_FREE { 1.0 } else { uf };
    let west = col > 0 && codes[i - 1] != CODE_BLOCKED;
    let east = col + 1 < w && codes[i + 1] != CODE_BLOCKED;
    let south = row > 0 && codes[i - w] != CODE_BLOCKED;
    let north = row + 1 < h && codes[i + w] != CODE_BLOCKED;
    if west {
        visit(i - 1, factor(codes[i - 1]));
    }
    if east {
        visit(i + 1, factor(codes[i + 1]));
    }
    if south {
        visit(i - w, factor(codes[i - w]));
        if west && codes[i - w - 1] != CODE_BLOCKED {
            visit(i - w - 1, DIAGONAL * factor(codes[i - w - 1]));
        }
        if east && codes[i - w + 1] != CODE_BLOCKED {
            visit(i - w + 1, DIAGONAL * factor(codes[i - w + 1]));
        }
    }
    if north {
        visit(i + w, factor(codes[i + w]));
        if west && codes[i + w - 1] != CODE_BLOCKED {
            visit(i + w - 1, DIAGONAL * factor(codes[i + w - 1]));
        }
        if east && codes[i + w + 1] != CODE_BLOCKED {
            visit(i + w + 1, DIAGONAL * factor(codes[i + w + 1]));
        }
    }
}

/// Octile distance between two flat indices [cells]: the exact cost on an empty grid, a lower
/// bound whenever cost factors are at least 1.
#[inline(always)]
pub(crate) fn octile(a: usize, b: usize, width: usize) -> f32 {
    let dc = (a % width).abs_diff(b % width) as f32;
    let dr = (a / width).abs_diff(b / width) as f32;
    let (lo, hi) = if dc < dr { (dc, dr) } else { (dr, dc) };
    (hi - lo) + DIAGONAL * lo
}

#[cfg(feature = "std")]
impl<const N: usize> SearchMemory<N> {
    /// Memory built on the heap.
    pub(crate) fn new_boxed() -> std::boxed::Box<Self> {
        let zeroed = std::boxed::Box::<Self>::new_zeroed();
        // SAFETY: all fields are integers, floats and arrays of them; all-zero is valid and is
        // what `new` produces.
        unsafe { zeroed.assume_init() }
    }
}
