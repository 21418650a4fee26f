//! Working memory shared by A* and the distance field: per-cell g-values, parents and
//! generation stamps, and the open list. A* keeps a monotone radix heap with decrease-key
//! (Ahuja, Mehlhorn, Orlin & Tarjan, "Faster algorithms for the shortest path problem", JACM
//! 37(2), 1990); the distance field's Dijkstra sweep keeps a bucket queue of unit width
//! (Dial, "Algorithm 360: shortest-path forest with topological ordering", CACM 12(11),
//! 1969). Nothing is cleared between queries: a cell's entries are valid only if its stamp
//! carries the current generation.

use super::traversability::{CODE_COUNT, MOVES, Traversability};

/// Diagonal step \[cells\].
pub(crate) const DIAGONAL: f32 = core::f32::consts::SQRT_2;

const NO_PARENT: u32 = u32::MAX;

/// Per-cell state read on every relaxation: kept to 8 bytes so that the cells a search
/// touches stay in cache.
#[derive(Clone, Copy, bytemuck::Zeroable)]
struct Node {
    /// `2 * generation` when the cell was reached this query, `+ 1` once it is closed.
    stamp: u32,
    g: f32,
}

/// Per-cell state written when a cell is opened or improved.
#[derive(Clone, Copy, bytemuck::Zeroable)]
struct Link {
    /// Parent cell times 8 plus the index in [`MOVES`] of the step from it
    /// (`NO_PARENT` for the source).
    parent: u32,
    /// The cell's row (its column follows from the index without a division).
    row: u32,
}

/// Open-list links of a cell: its key and its neighbours in a bucket list of the radix heap
/// (or in the bypass stack).
#[derive(Clone, Copy, bytemuck::Zeroable)]
struct QLink {
    key: u32,
    next: u32,
    /// Previous cell in the bucket list, `NIL` at the head, `ON_STACK` on the bypass stack.
    prev: u32,
}

const ZERO_NODE: Node = Node { stamp: 0, g: 0.0 };

const ZERO_LINK: Link = Link { parent: 0, row: 0 };

const ZERO_QLINK: QLink = QLink {
    key: 0,
    next: 0,
    prev: 0,
};

/// End of a list.
const NIL: u32 = u32::MAX;

/// What a cell did with a cost offered to it ([`SearchMemory::offer`]).
enum Offer {
    /// Closed, or reached at no higher cost: nothing changed.
    Refused,
    /// Open, and the cost is lower: its cost and parent changed.
    Improved,
    /// Reached for the first time this query.
    Opened,
}

/// Buckets of the radix heap: bucket 0 holds keys equal to the last key taken, bucket `b > 0`
/// keys whose highest bit differing from it is bit `b - 1`.
const BUCKETS: usize = 33;

/// Relative slack of the bypass test, one unit in the last place of an f32. Along a straight
/// diagonal run f stays constant in exact arithmetic but wobbles by rounding; the slack lets
/// such cells bypass the heap too. Every cell taken from the stack then has f at most
/// `BYPASS_SLACK` times the open list's minimum, so a path found costs at most that factor
/// times the optimum (1.2e-7 relative, the size of the rounding of the f32 sums themselves).
const BYPASS_SLACK: f32 = 1.0 + f32::EPSILON;

/// `prev` of a cell waiting on the bypass stack rather than in the heap.
const ON_STACK: u32 = u32::MAX - 1;

/// Slots of the bucket queue, a power of two: bucket `b` (costs in `[b, b + 1)` cells) lives
/// in slot `b % SLOTS`. The open cells' costs span less than the largest step plus one, so
/// steps of up to `SLOTS - 2` cells keep every open bucket in its own slot.
const SLOTS: usize = 64;

/// Largest step cost \[cells\] the bucket queue takes; beyond it the sweep keeps the radix
/// heap.
const MAX_BUCKET_STEP: f32 = (SLOTS - 2) as f32;

/// Largest cost \[cells\] a bucket index may reach (it is a `u32`, kept well clear of the
/// top).
const MAX_BUCKET_COST: f32 = (1u32 << 31) as f32;

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
/// cost factor of each code (a view of a [`Traversability`] layer, or of a copy of it).
#[derive(Clone, Copy)]
pub(crate) struct StepCosts<'a> {
    pub(crate) width: usize,
    /// Move masks, flat-index order (bit `k`: step [`MOVES`]`[k]` is legal).
    pub(crate) masks: &'a [u8],
    /// Step codes, flat-index order.
    pub(crate) codes: &'a [u8],
    /// Cost factor by step code.
    pub(crate) factors: [f32; CODE_COUNT],
    /// Every legal step costs its plain length.
    pub(crate) uniform: bool,
}

impl<'a> StepCosts<'a> {
    pub(crate) fn of<const M: usize>(trav: &'a Traversability<M>) -> Self {
        Self {
            width: trav.geometry().width,
            masks: trav.move_masks(),
            codes: trav.codes(),
            factors: trav.step_factors(),
            uniform: trav.uniform_costs(),
        }
    }
}

/// Open list: a monotone radix heap (Ahuja, Mehlhorn, Orlin & Tarjan, "Faster algorithms for
/// the shortest path problem", JACM 37(2), 1990) over the f32 bits of f, plus a bypass stack.
/// The heap's buckets and the stack are intrusive lists through per-cell links, so insert and
/// decrease-key are O(1) (unlink, relink) and taking the minimum scans only the lowest
/// non-empty bucket, spreading it over the buckets below. A radix heap needs every key
/// entering it to be at least the last key taken; the bypass guarantees that (see
/// [`Self::relax`]). A cell opened with f no greater than the open list's minimum (up to
/// [`BYPASS_SLACK`]) would be the next one taken anyway; it is pushed on the stack instead and
/// expanded next (one of the optimisations of Sun, Yeoh, Chen & Koenig, "Simple optimization
/// techniques for A*-based search", AAMAS 2009). It pays on open ground, where straight runs
/// keep f constant.
#[derive(bytemuck::Zeroable)]
pub(crate) struct SearchMemory<const N: usize> {
    nodes: [Node; N],
    links: [Link; N],
    queue: [QLink; N],
    /// First cell of each bucket list (`NIL` when empty).
    buckets: [u32; BUCKETS],
    /// A lower bound on each bucket's keys: the smallest key linked into it since it was
    /// last empty (a cell may have left since).
    mins: [u32; BUCKETS],
    /// Bit `b` set when bucket `b` is not empty.
    occupied: u64,
    /// The last key taken from the heap; every key in it is at least this.
    last: u32,
    /// First cell of the bypass stack (`NIL` when empty).
    stack: u32,
    /// New cells with f up to this bypass the heap: the f of the last cell taken from the
    /// heap (the open list's minimum then) times [`BYPASS_SLACK`].
    bypass_limit: f32,
    /// The open list is the bucket queue ([`Self::start_sweep`]), not the radix heap.
    bucketed: bool,
    /// First cell of each bucket-queue slot (`NIL` when empty).
    slots: [u32; SLOTS],
    /// Bucket the queue takes cells from: no open cell lies in a lower one.
    cursor: u32,
    /// Cells in the bucket queue.
    queued: u32,
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
            queue: [ZERO_QLINK; N],
            buckets: [NIL; BUCKETS],
            mins: [u32::MAX; BUCKETS],
            occupied: 0,
            last: 0,
            stack: NIL,
            bypass_limit: 0.0,
            bucketed: false,
            slots: [NIL; SLOTS],
            cursor: 0,
            queued: 0,
            generation: 0,
        }
    }

    /// Starts a query: new generation, empty heap.
    fn begin(&mut self) {
        self.buckets = [NIL; BUCKETS];
        self.mins = [u32::MAX; BUCKETS];
        self.occupied = 0;
        self.last = 0;
        self.stack = NIL;
        self.bypass_limit = 0.0;
        self.bucketed = false;
        self.slots = [NIL; SLOTS];
        self.cursor = 0;
        self.queued = 0;
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
        self.open_source(source, sr);
        self.insert(source, make_key(h.at(sc, sr)));
    }

    /// Starts a Dijkstra sweep from `source` (a passable cell of a grid of `cells` cells,
    /// `width` wide) whose steps cost at most `max_step` cells. The open list is then a
    /// bucket queue of unit width (Dial 1969): every step costs at least one cell, so the
    /// cells of the lowest bucket are final when it is reached and each queue operation is
    /// O(1), with no heap to reorder. The costs found are those of any Dijkstra sweep, bit
    /// for bit (a cell's cost is the least sum over its final neighbours); among equally
    /// short paths the parents may differ from the radix heap's. Falls back to the radix heap
    /// when the steps or the grid are too large for the buckets.
    pub(crate) fn start_sweep(&mut self, source: usize, width: usize, cells: usize, max_step: f32) {
        self.begin();
        self.open_source(source, source / width);
        self.bucketed = max_step <= MAX_BUCKET_STEP && (cells as f32) * max_step < MAX_BUCKET_COST;
        if self.bucketed {
            self.bucket_link(source, 0);
        } else {
            self.insert(source, make_key(0.0));
        }
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
        match (costs.uniform, self.bucketed) {
            (true, false) => self.run::<true, false>(costs, target, h),
            (false, false) => self.run::<false, false>(costs, target, h),
            (true, true) => self.run::<true, true>(costs, target, h),
            (false, true) => self.run::<false, true>(costs, target, h),
        }
    }

    /// [`Self::resume`]; `UNIFORM`: every step costs its plain length (no cost factor to
    /// look up); `BUCKETED`: the open list is the bucket queue.
    #[inline(always)]
    fn run<const UNIFORM: bool, const BUCKETED: bool>(
        &mut self,
        costs: &StepCosts<'_>,
        target: usize,
        h: impl Heuristic,
    ) -> (u32, bool) {
        let w = costs.width;
        let masks = costs.masks;
        let codes = costs.codes;
        // Cost factor by step code: blocked (never entered), Free, Unknown, and both in each
        // wall band.
        let factors = costs.factors;
        let offsets = MOVES.map(|(dc, dr)| (dc as isize + dr as isize * w as isize) as usize);
        let steps = MOVES.map(|(dc, dr)| if dc != 0 && dr != 0 { DIAGONAL } else { 1.0 });
        let mut closed = 0u32;
        while let Some((idx, row)) = if BUCKETED {
            self.bucket_pop_and_close()
        } else {
            self.pop_and_close()
        } {
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
                        if BUCKETED {
                            self.bucket_relax(idx << 3 | $k, to, tr, gi + step);
                        } else {
                            self.relax(idx << 3 | $k, to, tr, gi + step, || h.at(tc, tr));
                        }
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

    /// Reaches the source cell with g = 0 (the caller puts it in its open list).
    fn open_source(&mut self, i: usize, row: usize) {
        self.nodes[i] = Node {
            stamp: 2 * self.generation,
            g: 0.0,
        };
        self.links[i] = Link {
            parent: NO_PARENT,
            row: row as u32,
        };
    }

    /// Closes cell `i`, just taken from the open list; returns its index and row.
    #[inline(always)]
    fn close(&mut self, i: usize) -> (u32, u32) {
        self.nodes[i].stamp = 2 * self.generation + 1;
        (i as u32, self.links[i].row)
    }

    /// Relaxes the edge `from -> to` with tentative cost `g`; `h` gives the heuristic of `to`
    /// (called only when `to` is opened or improved). `from` is the parent link: the cell
    /// index times 8 plus the step's index in [`MOVES`].
    ///
    /// A cell goes to the heap only with f above `bypass_limit`, which is at least the f of
    /// the last key taken from the heap (the key is f's bits), so its key is larger, as the
    /// radix heap needs. Any other cell, new or improved (f rounding can put a child's f just
    /// below its parent's), goes on the stack.
    #[inline(always)]
    fn relax(&mut self, from: u32, to: usize, row: usize, g: f32, h: impl FnOnce() -> f32) {
        match self.offer(from, to, row, g) {
            Offer::Refused => {}
            Offer::Improved => {
                if self.queue[to].prev == ON_STACK {
                    return; // expanded before any heap entry anyway
                }
                let f = g + h();
                if f <= self.bypass_limit {
                    self.unlink(to);
                    self.push_stack(to);
                } else {
                    self.decrease(to, make_key(f));
                }
            }
            Offer::Opened => {
                let f = g + h();
                if f <= self.bypass_limit {
                    self.push_stack(to);
                } else {
                    self.insert(to, make_key(f));
                }
            }
        }
    }

    /// [`Self::relax`] for the bucket queue (no heuristic: the key is g).
    #[inline(always)]
    fn bucket_relax(&mut self, from: u32, to: usize, row: usize, g: f32) {
        match self.offer(from, to, row, g) {
            Offer::Refused => {}
            Offer::Improved => {
                let b = g as u32;
                if b != self.queue[to].key {
                    self.bucket_unlink(to);
                    self.bucket_link(to, b);
                }
            }
            Offer::Opened => self.bucket_link(to, g as u32),
        }
    }

    /// Offers cost `g` through the parent link `from` to cell `to` (in row `row`): an open
    /// cell takes it if lower, a cell not reached yet this query is opened with it, a closed
    /// cell refuses it. The caller then updates the open list.
    #[inline(always)]
    fn offer(&mut self, from: u32, to: usize, row: usize, g: f32) -> Offer {
        let seen = 2 * self.generation;
        let node = &mut self.nodes[to];
        if node.stamp == seen {
            if g >= node.g {
                return Offer::Refused;
            }
            node.g = g;
            self.links[to].parent = from;
            Offer::Improved
        } else if node.stamp != seen + 1 {
            *node = Node { stamp: seen, g };
            self.links[to] = Link {
                parent: from,
                row: row as u32,
            };
            Offer::Opened
        } else {
            Offer::Refused
        }
    }

    /// Puts cell `i` in bucket `b` (at least the cursor's).
    #[inline(always)]
    fn bucket_link(&mut self, i: usize, b: u32) {
        push_front(&mut self.queue, &mut self.slots[b as usize % SLOTS], i, b);
        self.queued += 1;
    }

    /// Takes cell `i` out of its bucket.
    #[inline(always)]
    fn bucket_unlink(&mut self, i: usize) {
        if let Some(next) = remove(&mut self.queue, i) {
            self.slots[self.queue[i].key as usize % SLOTS] = next;
        }
        self.queued -= 1;
    }

    /// Removes a cell of the lowest non-empty bucket and closes it; returns its index and
    /// row.
    #[inline(always)]
    fn bucket_pop_and_close(&mut self) -> Option<(u32, u32)> {
        if self.queued == 0 {
            return None;
        }
        let mut slot = self.cursor as usize % SLOTS;
        while self.slots[slot] == NIL {
            self.cursor = self.cursor.wrapping_add(1);
            slot = self.cursor as usize % SLOTS;
        }
        let i = pop_front(&mut self.queue, &mut self.slots[slot]);
        self.queued -= 1;
        Some(self.close(i))
    }

    #[inline(always)]
    fn push_stack(&mut self, i: usize) {
        self.queue[i] = QLink {
            key: 0,
            next: self.stack,
            prev: ON_STACK,
        };
        self.stack = i as u32;
    }

    /// Bucket of `key` relative to the last key taken.
    #[inline(always)]
    fn bucket(&self, key: u32) -> usize {
        (32 - (key ^ self.last).leading_zeros()) as usize
    }

    /// Puts cell `i` with `key` (at least the last key taken) in the heap.
    #[inline(always)]
    fn insert(&mut self, i: usize, key: u32) {
        let b = self.bucket(key);
        self.link(i, key, b);
    }

    #[inline(always)]
    fn link(&mut self, i: usize, key: u32, b: usize) {
        push_front(&mut self.queue, &mut self.buckets[b], i, key);
        self.mins[b] = self.mins[b].min(key);
        self.occupied |= 1 << b;
    }

    /// Takes cell `i` out of its bucket.
    #[inline(always)]
    fn unlink(&mut self, i: usize) {
        if let Some(next) = remove(&mut self.queue, i) {
            let b = self.bucket(self.queue[i].key);
            self.buckets[b] = next;
            if next == NIL {
                self.occupied &= !(1 << b);
                self.mins[b] = u32::MAX;
            }
        }
    }

    /// Lowers the key of heap cell `i` to `key` (at least the last key taken).
    #[inline(always)]
    fn decrease(&mut self, i: usize, key: u32) {
        let b = self.bucket(key);
        if b == self.bucket(self.queue[i].key) {
            self.queue[i].key = key;
            self.mins[b] = self.mins[b].min(key);
        } else {
            self.unlink(i);
            self.link(i, key, b);
        }
    }

    /// Removes the best open cell and closes it; returns its index and row.
    #[inline(always)]
    fn pop_and_close(&mut self) -> Option<(u32, u32)> {
        let i = if self.stack != NIL {
            let i = self.stack as usize;
            self.stack = self.queue[i].next;
            i
        } else {
            if self.occupied == 0 {
                return None;
            }
            while self.occupied & 1 == 0 {
                self.redistribute();
            }
            let i = pop_front(&mut self.queue, &mut self.buckets[0]);
            if self.buckets[0] == NIL {
                self.occupied &= !1;
                self.mins[0] = u32::MAX;
            }
            self.bypass_limit = f32::from_bits(self.last) * BYPASS_SLACK;
            i
        };
        Some(self.close(i))
    }

    /// Makes the lower bound of the lowest non-empty bucket's keys the last key taken and
    /// spreads that bucket over the lower ones (the cells with that key, if any, land in
    /// bucket 0). The bound is at least the previous last key and shares its bits above the
    /// bucket's, as every key of the bucket does, so keys in higher buckets keep their
    /// buckets and this bucket's keys all fall lower.
    #[cold]
    #[inline(never)]
    fn redistribute(&mut self) {
        let b = self.occupied.trailing_zeros() as usize;
        self.last = self.mins[b];
        let mut c = self.buckets[b];
        self.buckets[b] = NIL;
        self.mins[b] = u32::MAX;
        self.occupied &= !(1 << b);
        while c != NIL {
            let q = self.queue[c as usize];
            let to = self.bucket(q.key);
            self.link(c as usize, q.key, to);
            c = q.next;
        }
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

/// Prepends cell `i`, with `key`, to the open-list bucket whose first cell is `head`.
#[inline(always)]
fn push_front(queue: &mut [QLink], head: &mut u32, i: usize, key: u32) {
    queue[i] = QLink {
        key,
        next: *head,
        prev: NIL,
    };
    if *head != NIL {
        queue[*head as usize].prev = i as u32;
    }
    *head = i as u32;
}

/// Takes cell `i` out of its bucket; if it was the first cell, returns the bucket's new
/// first cell for the caller to store.
#[inline(always)]
fn remove(queue: &mut [QLink], i: usize) -> Option<u32> {
    let QLink { next, prev, .. } = queue[i];
    if next != NIL {
        queue[next as usize].prev = prev;
    }
    if prev != NIL {
        queue[prev as usize].next = next;
        None
    } else {
        Some(next)
    }
}

/// Takes the first cell of the (non-empty) bucket whose first cell is `head`.
#[inline(always)]
fn pop_front(queue: &mut [QLink], head: &mut u32) -> usize {
    let i = *head as usize;
    let next = queue[i].next;
    *head = next;
    if next != NIL {
        queue[next as usize].prev = NIL;
    }
    i
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

/// Heap key: the bits of f (non-negative floats order like their bits). Cells with equal keys
/// leave in the reverse order of arrival in their bucket, which favours the cells opened
/// last, the deeper ones. (A tie-break on g in the low half of a 64-bit key, as a comparison
/// heap would use, spreads equal-f cells over up to 32 more buckets and costs more in moves
/// between buckets than it saves in expansions.)
#[inline]
fn make_key(f: f32) -> u32 {
    f.to_bits()
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
