//! Counts of blocked cells (and cells in a wall band) in any axis-aligned box in O(1): a
//! summed-area table (Crow, "Summed-Area Tables for Texture Mapping", SIGGRAPH 1984) over the
//! traversability layer.
//!
//! The segment between two cell centres only touches cells inside the two cells' bounding box,
//! so a box without such cells proves a line of sight, clear of every wall band, without
//! walking it. Waypoint pruning
//! ([`super::waypoints::prune_to_waypoints_with_boxes`]) tests the line of sight from its
//! anchor to every following cell of a path; in open space this turns each test into four
//! look-ups, and the result is the same as walking every segment.

use super::Traversability;
use super::traversability::{CODE_BLOCKED, band_of_code};
use crate::grid::{Cell, CellBox};

/// Largest table \[entries\]: `(width + 1) * (height + 1)` of the grid.
pub const MAX_BOX_TABLE: usize = (1 << 20) + (1 << 12);

/// Summed-area table of the blocked cells of a traversability layer.
///
/// The table covers only the layer's [marked box](Traversability::marked_box) (the cells
/// that are known, inflated or in a wall band; the whole grid if Unknown cells are blocked):
/// outside it no cell is blocked, so building the table costs what the explored region holds,
/// not the map, and a box query is clipped to it.
#[derive(bytemuck::Zeroable)]
pub struct BlockedBoxes {
    width: usize,
    height: usize,
    ready: bool,
    /// The table's window: columns `col0..col0 + cols`, rows `row0..row0 + rows`.
    col0: usize,
    row0: usize,
    cols: usize,
    rows: usize,
    /// `sums[r * (cols + 1) + c]`: blocked cells of the window in its rows `< r` and columns
    /// `< c`.
    sums: [u32; MAX_BOX_TABLE],
}

impl core::fmt::Debug for BlockedBoxes {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("BlockedBoxes")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("ready", &self.ready)
            .finish_non_exhaustive()
    }
}

impl Default for BlockedBoxes {
    fn default() -> Self {
        Self::new()
    }
}

impl BlockedBoxes {
    /// An empty table, for a `static` without an allocator (4.2 MB: on a host prefer
    /// [`Self::new_boxed`]).
    pub const fn new() -> Self {
        Self {
            width: 0,
            height: 0,
            ready: false,
            col0: 0,
            row0: 0,
            cols: 0,
            rows: 0,
            sums: [0; MAX_BOX_TABLE],
        }
    }

    /// An empty table built directly on the heap (4.2 MB).
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        // Zero sizes, not ready: what `new` produces.
        crate::heap::boxed_zeroed()
    }

    /// Counts the blocked cells of `trav`. Returns `false` (and answers no box query) if the
    /// table of its marked box exceeds [`MAX_BOX_TABLE`].
    pub fn build<const N: usize>(&mut self, trav: &Traversability<N>) -> bool {
        let g = trav.geometry();
        let (w, h) = (g.width, g.height);
        self.ready = false;
        let window = if trav.unknown_is_blocked() {
            CellBox::all(g)
        } else {
            trav.marked_box()
        };
        let (cols, rows) = if window.is_empty() {
            (0, 0)
        } else {
            (
                window.col_end - window.col_min,
                window.row_end - window.row_min,
            )
        };
        if (cols + 1) * (rows + 1) > MAX_BOX_TABLE {
            return false;
        }
        let codes = trav.codes();
        let stride = cols + 1;
        self.sums[..stride].fill(0);
        for r in 0..rows {
            let start = (window.row_min + r) * w + window.col_min;
            let row = &codes[start..start + cols];
            let (below, this) = self.sums[r * stride..(r + 2) * stride].split_at_mut(stride);
            this[0] = 0;
            let mut row_sum = 0u32;
            for ((sum, &under), &code) in this[1..].iter_mut().zip(&below[1..]).zip(row) {
                row_sum += (code == CODE_BLOCKED || band_of_code(code) != 0) as u32;
                *sum = under + row_sum;
            }
        }
        self.width = w;
        self.height = h;
        self.col0 = window.col_min;
        self.row0 = window.row_min;
        self.cols = cols;
        self.rows = rows;
        self.ready = true;
        true
    }

    /// Whether the bounding box of cells `a` and `b` (inclusive) lies in the grid and holds no
    /// blocked cell; `false` whenever the table is not built.
    #[inline]
    pub fn is_clear(&self, a: Cell, b: Cell) -> bool {
        self.is_range_clear(
            a.col.min(b.col),
            a.row.min(b.row),
            a.col.max(b.col),
            a.row.max(b.row),
        )
    }

    /// Whether the segment between the centres of `a` and `b` is proven clear by covering it
    /// with boxes: the whole segment's bounding box, else (up to `depth` halvings) the boxes
    /// of its halves. Every cell the segment touches (corners included) lies in the boxes, so
    /// `true` implies [`super::has_line_of_sight`]; `false` proves nothing.
    pub fn is_segment_clear(&self, a: Cell, b: Cell, depth: u32) -> bool {
        // Coordinates in units of 1 / 2^(depth + 1) cell, so that the centres and every
        // midpoint are integers.
        let depth = depth.min(20);
        let bits = depth + 1;
        let half = 1i64 << depth;
        let centre = |c: Cell| ((c.col as i64) << bits | half, (c.row as i64) << bits | half);
        self.cover(centre(a), centre(b), bits, depth)
    }

    /// `cover` on coordinates in units of `1 / 2^bits` cell.
    fn cover(&self, p: (i64, i64), q: (i64, i64), bits: u32, depth: u32) -> bool {
        // A point on the line x = X touches the cells on both sides of it: columns from
        // ceil(min x) - 1 to floor(max x) hold every touched cell (likewise rows). (An
        // arithmetic shift right is a division rounding down.)
        let scale = 1i64 << bits;
        let lo = |a: i64, b: i64| ((a.min(b) + scale - 1) >> bits) - 1;
        let hi = |a: i64, b: i64| a.max(b) >> bits;
        let (c0, c1) = (lo(p.0, q.0), hi(p.0, q.0));
        let (r0, r1) = (lo(p.1, q.1), hi(p.1, q.1));
        let fits = |v: i64| v >= i32::MIN as i64 && v <= i32::MAX as i64;
        if [c0, c1, r0, r1].into_iter().all(fits)
            && self.is_range_clear(c0 as i32, r0 as i32, c1 as i32, r1 as i32)
        {
            return true;
        }
        if depth == 0 {
            return false;
        }
        let m = ((p.0 + q.0) / 2, (p.1 + q.1) / 2);
        self.cover(p, m, bits, depth - 1) && self.cover(m, q, bits, depth - 1)
    }

    /// Whether columns `c0..=c1` x rows `r0..=r1` lie in the grid and hold no blocked cell.
    #[inline]
    fn is_range_clear(&self, c0: i32, r0: i32, c1: i32, r1: i32) -> bool {
        if !self.ready {
            return false;
        }
        if c0 < 0 || r0 < 0 || c1 as usize >= self.width || r1 as usize >= self.height {
            return false;
        }
        // Clipped to the window (no cell outside it is blocked), half-open, then in window
        // coordinates.
        let lo_c = (c0 as usize).max(self.col0);
        let hi_c = (c1 as usize + 1).min(self.col0 + self.cols);
        let lo_r = (r0 as usize).max(self.row0);
        let hi_r = (r1 as usize + 1).min(self.row0 + self.rows);
        if hi_c <= lo_c || hi_r <= lo_r {
            return true;
        }
        let (c0, c1) = (lo_c - self.col0, hi_c - self.col0);
        let (r0, r1) = (lo_r - self.row0, hi_r - self.row0);
        let stride = self.cols + 1;
        let at = |r: usize, c: usize| self.sums[r * stride + c];
        at(r1, c1) + at(r0, c0) == at(r0, c1) + at(r1, c0)
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::planner::{DistanceField, prune_to_waypoints, prune_to_waypoints_with_boxes};
    use crate::random::{range_f32, seeded};

    const W: usize = 50;
    const H: usize = 30;

    /// Random walls (about 12 % of the cells), seeded.
    fn layer(seed: u64) -> std::boxed::Box<Traversability<{ W * H }>> {
        let mut rng = seeded(seed);
        let walls: Vec<bool> = (0..W * H)
            .map(|_| range_f32(&mut rng, 0.0, 1.0) < 0.12)
            .collect();
        Traversability::from_blocked_boxed(W, H, |c| walls[c.row as usize * W + c.col as usize])
            .unwrap()
    }

    #[test]
    fn box_queries_match_counting_the_cells() {
        let trav = layer(1);
        let mut boxes = BlockedBoxes::new_boxed();
        assert!(boxes.build(&*trav));
        let mut rng = seeded(2);
        let clear = random_boxes_answer_as_counting(&boxes, &*trav, &mut rng, 2000);
        assert!(clear > 20, "{clear}");
    }

    /// Asks `boxes` about `queries` random boxes (corners up to 2 cells outside the grid),
    /// asserts each answer equals counting the blocked cells of `trav`, and returns how many
    /// were clear.
    fn random_boxes_answer_as_counting<const N: usize>(
        boxes: &BlockedBoxes,
        trav: &Traversability<N>,
        rng: &mut crate::random::ProjectRng,
        queries: usize,
    ) -> u32 {
        let mut clear = 0;
        for _ in 0..queries {
            let mut cell = || {
                Cell::new(
                    range_f32(rng, -2.0, W as f32 + 2.0) as i32,
                    range_f32(rng, -2.0, H as f32 + 2.0) as i32,
                )
            };
            let (a, b) = (cell(), cell());
            let inside = trav.geometry().contains(a) && trav.geometry().contains(b);
            let none_blocked = (a.row.min(b.row)..=a.row.max(b.row)).all(|r| {
                (a.col.min(b.col)..=a.col.max(b.col)).all(|c| trav.is_passable(Cell::new(c, r)))
            });
            assert_eq!(boxes.is_clear(a, b), inside && none_blocked, "{a:?} {b:?}");
            clear += boxes.is_clear(a, b) as u32;
        }
        clear
    }

    #[test]
    fn a_table_of_the_marked_box_answers_as_counting_the_cells() {
        use crate::grid::{CellClass, LogOddsBounds, OccupancyGrid};
        use crate::planner::TraversabilityConfig;
        let g = crate::grid::GridGeometry::new(W, H, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut rng = seeded(9);
        let mut boxes = BlockedBoxes::new_boxed();
        let mut clear = 0;
        for case in 0..20 {
            // Known cells (a fifth Occupied) in a random part of an Unknown grid; Unknown
            // cells are passable, so only the marked box holds blocked cells.
            let mut grid = OccupancyGrid::<{ W * H }>::new(g, LogOddsBounds::default()).unwrap();
            let mut trav =
                Traversability::<{ W * H }>::new_boxed(g, TraversabilityConfig::default()).unwrap();
            let c0 = range_f32(&mut rng, 0.0, W as f32 - 10.0) as usize;
            let r0 = range_f32(&mut rng, 0.0, H as f32 - 10.0) as usize;
            for _ in 0..60 {
                let c = c0 + range_f32(&mut rng, 0.0, 10.0) as usize;
                let r = r0 + range_f32(&mut rng, 0.0, 10.0) as usize;
                let class = if range_f32(&mut rng, 0.0, 1.0) < 0.2 {
                    CellClass::Occupied
                } else {
                    CellClass::Free
                };
                grid.set_class(r * W + c, class, &mut *trav);
            }
            let marked = trav.marked_box();
            assert!(
                !marked.is_empty() && marked.col_end - marked.col_min < W,
                "case {case}"
            );
            assert!(boxes.build(&*trav));
            clear += random_boxes_answer_as_counting(&boxes, &*trav, &mut rng, 500);
        }
        assert!(clear > 200, "{clear}");
    }

    #[test]
    fn a_segment_covered_by_clear_boxes_has_a_line_of_sight() {
        let mut rng = seeded(4);
        let mut boxes = BlockedBoxes::new_boxed();
        let (mut proven, mut clear) = (0, 0);
        for seed in 0..5 {
            let trav = layer(200 + seed);
            assert!(boxes.build(&*trav));
            for _ in 0..2000 {
                let mut cell = || {
                    Cell::new(
                        range_f32(&mut rng, 0.0, W as f32) as i32,
                        range_f32(&mut rng, 0.0, H as f32) as i32,
                    )
                };
                let (a, b) = (cell(), cell());
                let sees = crate::planner::has_line_of_sight(&*trav, a, b);
                clear += sees as u32;
                if boxes.is_segment_clear(a, b, 4) {
                    assert!(sees, "{a:?} {b:?}");
                    proven += 1;
                }
            }
        }
        // Most clear segments are proven so by the boxes.
        assert!(proven * 2 > clear, "{proven} of {clear}");
    }

    #[test]
    fn pruning_with_boxes_gives_the_same_waypoints() {
        let mut field = DistanceField::<{ W * H }>::new_boxed();
        let mut boxes = BlockedBoxes::new_boxed();
        let mut path = [Cell::new(0, 0); W * H];
        let mut rng = seeded(3);
        let mut compared = 0;
        for seed in 0..10 {
            let trav = layer(100 + seed);
            assert!(boxes.build(&*trav));
            let start = Cell::new(W as i32 / 2, H as i32 / 2);
            if field.compute(&*trav, start).is_err() {
                continue;
            }
            for _ in 0..50 {
                let goal = Cell::new(
                    range_f32(&mut rng, 0.0, W as f32) as i32,
                    range_f32(&mut rng, 0.0, H as f32) as i32,
                );
                let Ok(p) = field.path_to(goal, &mut path) else {
                    continue;
                };
                let mut plain = [Point2::new(0.0, 0.0); 64];
                let mut fast = [Point2::new(0.0, 0.0); 64];
                let n = prune_to_waypoints(&*trav, &path[..p.len], &mut plain).unwrap();
                let m = prune_to_waypoints_with_boxes(&*trav, &boxes, &path[..p.len], &mut fast)
                    .unwrap();
                assert_eq!(plain[..n], fast[..m]);
                compared += 1;
            }
        }
        assert!(compared > 200, "{compared}");
    }

    #[test]
    fn an_unbuilt_table_proves_nothing() {
        let trav = Traversability::<{ W * H }>::from_blocked_boxed(W, H, |_| false).unwrap();
        let mut boxes = BlockedBoxes::new_boxed();
        assert!(!boxes.is_clear(Cell::new(0, 0), Cell::new(1, 1)));
        assert!(boxes.build(&*trav));
        assert!(boxes.is_clear(Cell::new(0, 0), Cell::new(W as i32 - 1, H as i32 - 1)));
    }
}
