//! Exact grid traversal of a segment: every cell it crosses, in order, none skipped, none twice.
//!
//! Source: J. Amanatides and A. Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing",
//! Eurographics 1987. The walk steps from cell to cell across whichever grid line (vertical or
//! horizontal) the segment meets first.
//!
//! # Which cells count as crossed
//!
//! Cells are half-open squares: cell `(col, row)` covers `[col, col + 1) x [row, row + 1)` in
//! grid units (the same rule as [`GridGeometry::cell_at_unchecked`]), so every point of the
//! plane lies in exactly one cell. A cell is crossed when it contains at least one point of the
//! closed segment. Consequences:
//! - the first cell is the cell of `from` and the last is the cell of `to` (when inside the
//!   grid), exactly as [`GridGeometry::cell_at_unchecked`] computes them;
//! - at an exact grid corner the corner point belongs to the cell north-east of it: moving
//!   north-east or south-west the walk steps diagonally (8-adjacent); moving north-west or
//!   south-east it first steps along the axis it moves along in the positive direction, then
//!   along the other (4-adjacent), visiting the cell that holds the corner point;
//! - a segment running along a grid line belongs to the cells north of (or east of) that line.
//!
//! Consecutive cells are 4-adjacent, or 8-adjacent at an exact corner crossing.
//!
//! # Exactness and cost
//!
//! Points are converted to grid units in `f32` (as [`GridGeometry::cell_at_unchecked`] does);
//! the walk then compares the crossing times of the next vertical and horizontal lines by
//! cross-multiplication in `f64` instead of dividing, so a tie (an exact corner) is detected
//! exactly whenever the coordinates have a short binary expansion (grid-aligned points, the
//! usual test input). The number of steps along each axis is fixed up front from the end cell,
//! so the walk always ends in the cell of `to` whatever the rounding.
//!
//! Only cells inside the grid are reported. A segment starting outside is fast-forwarded to
//! one step short of the grid on each axis, so the work is bounded by the grid's width plus
//! height, not by the segment's length. No allocation, no recursion; non-finite end points
//! visit nothing.

use core::ops::ControlFlow;

use crate::geometry::Point2;
use crate::grid::{Cell, GridGeometry};
use crate::math;

/// How a traversal ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraversalEnd {
    /// The cell of the end point was visited (it lies inside the grid).
    Reached,
    /// The visitor asked to stop.
    Stopped,
    /// The segment left the grid before its end, or never entered it, or an end point was not
    /// finite.
    Clipped,
}

/// Summary of a traversal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Traversal {
    /// Cells handed to the visitor.
    pub visited: usize,
    /// Why the walk ended.
    pub end: TraversalEnd,
}

/// Visits, in order, every grid cell the segment `from`–`to` (map frame \[m\]) crosses, handing
/// each cell and its flat index to `visit`; `visit` returns [`ControlFlow::Break`] to stop
/// early (a laser ray stopping at an occupied cell). See the module documentation for the exact
/// rule.
#[inline]
pub fn traverse(
    geom: &GridGeometry,
    from: Point2,
    to: Point2,
    mut visit: impl FnMut(Cell, usize) -> ControlFlow<()>,
) -> Traversal {
    let mut ray = RayCells::new(geom, from, to);
    // A walk that stays inside the grid skips the checks for leaving it.
    if ray.stays_inside() {
        return ray.walk_inside(visit);
    }
    let mut visited = 0;
    for (cell, index) in ray.by_ref() {
        visited += 1;
        if visit(cell, index).is_break() {
            return Traversal {
                visited,
                end: TraversalEnd::Stopped,
            };
        }
    }
    Traversal {
        visited,
        end: if ray.reached_end() {
            TraversalEnd::Reached
        } else {
            TraversalEnd::Clipped
        },
    }
}

/// Iterator over the grid cells a segment crosses, as `(cell, flat index)`; the allocation-free
/// engine behind [`traverse`].
#[derive(Clone, Debug)]
pub struct RayCells {
    width: i64,
    height: i64,
    col: i64,
    row: i64,
    step_col: i64,
    step_row: i64,
    /// Steps left along each axis.
    left_col: i64,
    left_row: i64,
    /// Crossing "times" of the next vertical / horizontal grid line, both scaled by
    /// `|dx| * |dy|` so they compare without division.
    next_x: f64,
    next_y: f64,
    /// Increments of `next_x` / `next_y` per step: `|dy|` and `|dx|`.
    inc_x: f64,
    inc_y: f64,
    entered: bool,
    finished: bool,
    reached: bool,
}

impl RayCells {
    /// The walk from `from` to `to` (map frame \[m\]) over `geom`.
    pub fn new(geom: &GridGeometry, from: Point2, to: Point2) -> Self {
        let mut ray = RayCells {
            width: geom.width as i64,
            height: geom.height as i64,
            col: 0,
            row: 0,
            step_col: 0,
            step_row: 0,
            left_col: 0,
            left_row: 0,
            next_x: 0.0,
            next_y: 0.0,
            inc_x: 0.0,
            inc_y: 0.0,
            entered: false,
            finished: true,
            reached: false,
        };
        if !(from.x.is_finite() && from.y.is_finite() && to.x.is_finite() && to.y.is_finite()) {
            return ray;
        }
        // Grid units, computed exactly as `GridGeometry::cell_at_unchecked` does.
        let gx0 = (from.x - geom.origin.x) / geom.resolution_m;
        let gy0 = (from.y - geom.origin.y) / geom.resolution_m;
        let gx1 = (to.x - geom.origin.x) / geom.resolution_m;
        let gy1 = (to.y - geom.origin.y) / geom.resolution_m;
        if !(gx0.is_finite() && gy0.is_finite() && gx1.is_finite() && gy1.is_finite()) {
            return ray;
        }
        let (fx0, fy0) = (math::floor(gx0), math::floor(gy0));
        let (c0, r0) = (fx0 as i64, fy0 as i64);
        let (c1, r1) = (math::floor(gx1) as i64, math::floor(gy1) as i64);
        let (x0, y0, x1, y1) = (gx0 as f64, gy0 as f64, gx1 as f64, gy1 as f64);
        let (adx, ady) = ((x1 - x0).abs(), (y1 - y0).abs());

        ray.col = c0;
        ray.row = r0;
        ray.step_col = (c1 - c0).signum();
        ray.step_row = (r1 - r0).signum();
        ray.left_col = (c1 - c0).abs();
        ray.left_row = (r1 - r0).abs();
        // Distance (in grid units along the axis) to the first line crossed: moving east the
        // line at col + 1; moving west the cell's own west edge, which may be at distance 0
        // (the start lies on it and belongs to this cell; the next point is already west).
        let dist_x = if ray.step_col > 0 {
            (fx0 as f64 + 1.0) - x0
        } else {
            x0 - fx0 as f64
        };
        let dist_y = if ray.step_row > 0 {
            (fy0 as f64 + 1.0) - y0
        } else {
            y0 - fy0 as f64
        };
        ray.next_x = dist_x * ady;
        ray.next_y = dist_y * adx;
        ray.inc_x = ady;
        ray.inc_y = adx;
        ray.finished = false;

        if !ray.in_grid() && !ray.fast_forward(x0, y0, x1, y1) {
            ray.finished = true;
        }
        ray
    }

    /// Whether the walk visited the cell of the end point.
    pub fn reached_end(&self) -> bool {
        self.reached
    }

    #[inline(always)]
    fn in_grid(&self) -> bool {
        self.col >= 0 && self.row >= 0 && self.col < self.width && self.row < self.height
    }

    /// The start lies outside the grid: check the segment meets the grid (Liang–Barsky on the
    /// closed grid rectangle, with a little slack; a miss is also caught while walking) and
    /// skip the steps that cannot reach it. Skipping to one step short of the grid on each
    /// axis keeps every cell before the grid outside it, so no wrong cell is reported.
    fn fast_forward(&mut self, x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
        let (w, h) = (self.width as f64, self.height as f64);
        let (dx, dy) = (x1 - x0, y1 - y0);
        let slack = 1e-6;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-dx, x0 + slack),
            (dx, w + slack - x0),
            (-dy, y0 + slack),
            (dy, h + slack - y0),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return false;
                }
            } else {
                let t = q / p;
                if p < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
            }
        }
        if t0 > t1 {
            return false;
        }
        // Steps needed before the column (row) is inside the grid.
        let need_col = if self.col < 0 {
            -self.col
        } else if self.col >= self.width {
            self.col - (self.width - 1)
        } else {
            0
        };
        let need_row = if self.row < 0 {
            -self.row
        } else if self.row >= self.height {
            self.row - (self.height - 1)
        } else {
            0
        };
        let skip_col = (need_col - 1).clamp(0, self.left_col);
        let skip_row = (need_row - 1).clamp(0, self.left_row);
        self.col += self.step_col * skip_col;
        self.left_col -= skip_col;
        self.next_x += skip_col as f64 * self.inc_x;
        self.row += self.step_row * skip_row;
        self.left_row -= skip_row;
        self.next_y += skip_row as f64 * self.inc_y;
        true
    }

    /// Whether every cell still to visit lies inside the grid: the walk moves monotonically
    /// from the current cell to the end cell along each axis, so it stays within their
    /// bounding box.
    #[inline]
    fn stays_inside(&self) -> bool {
        let end_col = self.col + self.step_col * self.left_col;
        let end_row = self.row + self.step_row * self.left_row;
        !self.finished
            && self.in_grid()
            && (0..self.width).contains(&end_col)
            && (0..self.height).contains(&end_row)
    }

    /// The rest of a walk that [stays inside](Self::stays_inside) the grid, handed to `visit`:
    /// the cells [`Iterator::next`] would give, in the same order and by the same choices as
    /// [`Self::advance`], without the checks for leaving the grid. While both axes have steps
    /// left, each step compares the two crossings; once one axis is done, the rest is a
    /// straight run along the other. The walk keeps only the flat index and the steps left;
    /// the cell is worked out from them (for free when `visit` does not look at it).
    #[inline(always)]
    fn walk_inside(&mut self, mut visit: impl FnMut(Cell, usize) -> ControlFlow<()>) -> Traversal {
        let width = self.width;
        let (step_col, step_row) = (self.step_col, self.step_row);
        let (mut left_col, mut left_row) = (self.left_col, self.left_row);
        let (end_col, end_row) = (
            self.col + step_col * left_col,
            self.row + step_row * left_row,
        );
        let cell = |left_col: i64, left_row: i64| {
            Cell::new(
                (end_col - step_col * left_col) as i32,
                (end_row - step_row * left_row) as i32,
            )
        };
        let mut index = (self.row * width + self.col) as usize;
        let (index_step_x, index_step_y) = (step_col as isize, (step_row * width) as isize);
        let (inc_x, inc_y) = (self.inc_x, self.inc_y);
        let (mut next_x, mut next_y) = (self.next_x, self.next_y);
        // At an exact corner (equal crossings): moving north-east or south-west the walk
        // steps diagonally; south-east the corner belongs to the east neighbour, north-west
        // to the north one (see `advance`).
        let (corner_x, corner_y) = (
            step_col == step_row || step_col > 0,
            step_col == step_row || step_col < 0,
        );
        let stopped = |visited| Traversal {
            visited,
            end: TraversalEnd::Stopped,
        };
        let mut visited = 0;
        self.finished = true;
        while left_col > 0 && left_row > 0 {
            visited += 1;
            if visit(cell(left_col, left_row), index).is_break() {
                return stopped(visited);
            }
            let (step_x, step_y) = if next_x < next_y {
                (true, false)
            } else if next_y < next_x {
                (false, true)
            } else {
                (corner_x, corner_y)
            };
            if step_x {
                index = index.wrapping_add_signed(index_step_x);
                left_col -= 1;
                next_x += inc_x;
            }
            if step_y {
                index = index.wrapping_add_signed(index_step_y);
                left_row -= 1;
                next_y += inc_y;
            }
        }
        // At most one axis has steps left.
        let (mut left, index_step) = if left_col > 0 {
            (left_col, index_step_x)
        } else {
            (left_row, index_step_y)
        };
        loop {
            visited += 1;
            let here = if left_col > 0 {
                cell(left, 0)
            } else {
                cell(0, left)
            };
            if visit(here, index).is_break() {
                return stopped(visited);
            }
            if left == 0 {
                break;
            }
            index = index.wrapping_add_signed(index_step);
            left -= 1;
        }
        self.reached = true;
        Traversal {
            visited,
            end: TraversalEnd::Reached,
        }
    }

    /// Whether the current (outside) cell can no longer lead into the grid.
    #[inline(always)]
    fn beyond_grid(&self) -> bool {
        let col_lost = (self.col < 0 && (self.step_col <= 0 || self.col + self.left_col < 0))
            || (self.col >= self.width
                && (self.step_col >= 0 || self.col - self.left_col >= self.width));
        let row_lost = (self.row < 0 && (self.step_row <= 0 || self.row + self.left_row < 0))
            || (self.row >= self.height
                && (self.step_row >= 0 || self.row - self.left_row >= self.height));
        col_lost || row_lost
    }

    /// Moves to the next cell along the segment.
    #[inline(always)]
    fn advance(&mut self) {
        let (step_x, step_y) = if self.left_col == 0 {
            (false, true)
        } else if self.left_row == 0 || self.next_x < self.next_y {
            (true, false)
        } else if self.next_y < self.next_x {
            (false, true)
        } else if self.step_col == self.step_row {
            // Exact corner, moving north-east or south-west: the corner point belongs to the
            // diagonal cell (north-east) or to the current one (south-west).
            (true, true)
        } else if self.step_col > 0 {
            // Exact corner, moving south-east: the corner belongs to the east neighbour.
            (true, false)
        } else {
            // Exact corner, moving north-west: the corner belongs to the north neighbour.
            (false, true)
        };
        if step_x {
            self.col += self.step_col;
            self.left_col -= 1;
            self.next_x += self.inc_x;
        }
        if step_y {
            self.row += self.step_row;
            self.left_row -= 1;
            self.next_y += self.inc_y;
        }
    }
}

impl Iterator for RayCells {
    type Item = (Cell, usize);

    #[inline(always)]
    fn next(&mut self) -> Option<(Cell, usize)> {
        loop {
            if self.finished {
                return None;
            }
            let inside = self.in_grid();
            if !inside && (self.entered || self.beyond_grid()) {
                self.finished = true;
                return None;
            }
            let (col, row) = (self.col, self.row);
            if self.left_col == 0 && self.left_row == 0 {
                self.finished = true;
                self.reached = inside;
            } else {
                self.advance();
            }
            if inside {
                self.entered = true;
                let index = row as usize * self.width as usize + col as usize;
                return Some((Cell::new(col as i32, row as i32), index));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{below, range_f32, seeded};

    /// Exact brute force in integer units of 1/`S` cell: does the closed segment contain a
    /// point of the half-open square of cell `(c, r)`? Each bound on `x(t)`, `y(t)` and `t` is a
    /// linear inequality in `t`; the feasible set is an interval with open or closed ends.
    const S: i64 = 4096;

    fn crosses(p0: (i64, i64), p1: (i64, i64), c: i64, r: i64) -> bool {
        // t in [lo, hi] as rationals num/den (den > 0) with strictness flags.
        let mut lo = (0i128, 1i128, false);
        let mut hi = (1i128, 1i128, false);
        // Constraint a + b t >= 0 (strict: > 0).
        let mut constrain = |a: i128, b: i128, strict: bool| -> bool {
            if b == 0 {
                return if strict { a > 0 } else { a >= 0 };
            }
            // t >= -a/b if b > 0; t <= -a/b if b < 0.
            let (num, den) = if b > 0 { (-a, b) } else { (a, -b) };
            if b > 0 {
                // Tighter lower bound?
                let cmp = (num * lo.1).cmp(&(lo.0 * den));
                if cmp == core::cmp::Ordering::Greater || (cmp.is_eq() && strict) {
                    lo = (num, den, strict || (cmp.is_eq() && lo.2));
                }
            } else {
                let cmp = (num * hi.1).cmp(&(hi.0 * den));
                if cmp == core::cmp::Ordering::Less || (cmp.is_eq() && strict) {
                    hi = (num, den, strict || (cmp.is_eq() && hi.2));
                }
            }
            true
        };
        let (x0, y0) = (p0.0 as i128, p0.1 as i128);
        let (dx, dy) = ((p1.0 - p0.0) as i128, (p1.1 - p0.1) as i128);
        let (c, r, s) = (c as i128, r as i128, S as i128);
        // x >= c S ; x < (c+1) S ; y >= r S ; y < (r+1) S.
        let ok = constrain(x0 - c * s, dx, false)
            & constrain((c + 1) * s - x0, -dx, true)
            & constrain(y0 - r * s, dy, false)
            & constrain((r + 1) * s - y0, -dy, true);
        if !ok {
            return false;
        }
        let cmp = (lo.0 * hi.1).cmp(&(hi.0 * lo.1));
        cmp.is_lt() || (cmp.is_eq() && !lo.2 && !hi.2)
    }

    fn brute_force(geom: &GridGeometry, p0: (i64, i64), p1: (i64, i64)) -> Vec<Cell> {
        let mut out = Vec::new();
        for r in 0..geom.height as i64 {
            for c in 0..geom.width as i64 {
                if crosses(p0, p1, c, r) {
                    out.push(Cell::new(c as i32, r as i32));
                }
            }
        }
        out.sort();
        out
    }

    /// A point given in 1/S grid units, in the map frame of `geom` (exact: S and the
    /// resolution are powers of two).
    fn to_map(geom: &GridGeometry, p: (i64, i64)) -> Point2 {
        Point2::new(
            geom.origin.x + p.0 as f32 / S as f32 * geom.resolution_m,
            geom.origin.y + p.1 as f32 / S as f32 * geom.resolution_m,
        )
    }

    fn walk(geom: &GridGeometry, a: Point2, b: Point2) -> (Vec<Cell>, Traversal) {
        let mut cells = Vec::new();
        let t = traverse(geom, a, b, |c, i| {
            assert_eq!(geom.index(c), Some(i));
            cells.push(c);
            ControlFlow::Continue(())
        });
        (cells, t)
    }

    #[test]
    fn random_segments_visit_exactly_the_crossed_cells_in_order() {
        let geom = GridGeometry::new(23, 17, 0.25, Point2::new(-2.0, 1.5)).unwrap();
        let mut rng = seeded(2);
        let mut corner_cases = 0;
        for case in 0..4000 {
            // Fine end points, or coarse ones (multiples of half a cell) that hit grid corners
            // and run along grid lines; some start or end outside the grid.
            let quantum = if case % 2 == 0 { 1 } else { S / 2 };
            let point = |rng: &mut _| {
                let x = range_f32(rng, -6.0, 29.0);
                let y = range_f32(rng, -6.0, 23.0);
                let q = |v: f32| ((v * S as f32) as i64 / quantum) * quantum;
                (q(x), q(y))
            };
            let p0 = point(&mut rng);
            let p1 = if below(&mut rng, 10) == 0 {
                p0
            } else {
                point(&mut rng)
            };
            let want = brute_force(&geom, p0, p1);
            let (got, t) = walk(&geom, to_map(&geom, p0), to_map(&geom, p1));
            let mut sorted = got.clone();
            sorted.sort();
            assert_eq!(sorted, want, "case {case}: {p0:?} -> {p1:?}, walk {got:?}");
            for pair in got.windows(2) {
                let (dc, dr) = (pair[1].col - pair[0].col, pair[1].row - pair[0].row);
                assert!(dc.abs() <= 1 && dr.abs() <= 1 && (dc, dr) != (0, 0));
                if dc != 0 && dr != 0 {
                    corner_cases += 1;
                }
            }
            // Order: monotone along the segment's direction.
            for pair in got.windows(2) {
                let (dc, dr) = (pair[1].col - pair[0].col, pair[1].row - pair[0].row);
                assert!(dc * (p1.0 - p0.0).signum() as i32 >= 0);
                assert!(dr * (p1.1 - p0.1).signum() as i32 >= 0);
            }
            let end = Cell::new(p1.0.div_euclid(S) as i32, p1.1.div_euclid(S) as i32);
            let want_end = if geom.contains(end) {
                TraversalEnd::Reached
            } else {
                TraversalEnd::Clipped
            };
            assert_eq!(t.end, want_end, "case {case}");
            assert_eq!(t.visited, got.len());
            if t.end == TraversalEnd::Reached {
                assert_eq!(got.last(), Some(&end));
            }
        }
        assert!(
            corner_cases > 50,
            "only {corner_cases} diagonal steps exercised"
        );
    }

    #[test]
    fn traverse_visits_what_the_iterator_yields_and_stops_where_asked() {
        // `traverse` walks segments that stay inside the grid without the iterator's checks
        // for leaving it; both must give the same cells, in the same order.
        let geom = GridGeometry::new(40, 30, 0.1, Point2::new(-1.0, 0.5)).unwrap();
        let mut rng = seeded(5);
        for case in 0..3000 {
            let point =
                |rng: &mut _| Point2::new(range_f32(rng, -1.2, 3.2), range_f32(rng, 0.3, 3.7));
            let (a, b) = (point(&mut rng), point(&mut rng));
            let want: Vec<(Cell, usize)> = RayCells::new(&geom, a, b).collect();
            let (got, t) = walk(&geom, a, b);
            assert_eq!(
                got,
                want.iter().map(|w| w.0).collect::<Vec<_>>(),
                "case {case}"
            );
            let mut ray = RayCells::new(&geom, a, b);
            ray.by_ref().count();
            let end = if ray.reached_end() {
                TraversalEnd::Reached
            } else {
                TraversalEnd::Clipped
            };
            assert_eq!(t.end, end, "case {case}");
            // Stopping at the k-th cell.
            if !want.is_empty() {
                let k = below(&mut rng, want.len());
                let mut seen = 0;
                let t = traverse(&geom, a, b, |_, i| {
                    assert_eq!(i, want[seen].1);
                    seen += 1;
                    if seen == k + 1 {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                });
                assert_eq!((t.visited, t.end), (k + 1, TraversalEnd::Stopped));
            }
        }
    }

    #[test]
    fn walks_inside_the_grid_take_the_iterators_corner_steps() {
        // End points on the half-cell lattice, inside the grid: many segments pass exactly
        // through grid corners, in all four directions, and run along grid lines.
        let geom = GridGeometry::new(16, 12, 0.25, Point2::new(-2.0, 1.5)).unwrap();
        let mut rng = seeded(8);
        let mut diagonal = 0;
        for case in 0..3000 {
            let point = |rng: &mut _| {
                Point2::new(
                    -2.0 + below(rng, 32) as f32 * 0.125,
                    1.5 + below(rng, 24) as f32 * 0.125,
                )
            };
            let (a, b) = (point(&mut rng), point(&mut rng));
            let want: Vec<Cell> = RayCells::new(&geom, a, b).map(|(c, _)| c).collect();
            let (got, t) = walk(&geom, a, b);
            assert_eq!(got, want, "case {case}: {a:?} -> {b:?}");
            assert_eq!(t.end, TraversalEnd::Reached);
            diagonal += got
                .windows(2)
                .filter(|p| p[0].col != p[1].col && p[0].row != p[1].row)
                .count();
        }
        assert!(diagonal > 100, "only {diagonal} diagonal steps");
    }

    #[test]
    fn corner_crossings_follow_the_half_open_rule() {
        let geom = GridGeometry::new(4, 4, 1.0, Point2::new(0.0, 0.0)).unwrap();
        let cells = |a: (f32, f32), b: (f32, f32)| {
            walk(&geom, Point2::new(a.0, a.1), Point2::new(b.0, b.1)).0
        };
        // North-east through the corner (1, 1): diagonal step.
        assert_eq!(
            cells((0.5, 0.5), (1.5, 1.5)),
            [Cell::new(0, 0), Cell::new(1, 1)]
        );
        // South-west through the same corner: diagonal step.
        assert_eq!(
            cells((1.5, 1.5), (0.5, 0.5)),
            [Cell::new(1, 1), Cell::new(0, 0)]
        );
        // North-west: the corner point belongs to the cell north of the start.
        assert_eq!(
            cells((1.5, 0.5), (0.5, 1.5)),
            [Cell::new(1, 0), Cell::new(1, 1), Cell::new(0, 1)]
        );
        // South-east: the corner point belongs to the cell east of the start.
        assert_eq!(
            cells((0.5, 1.5), (1.5, 0.5)),
            [Cell::new(0, 1), Cell::new(1, 1), Cell::new(1, 0)]
        );
        // Along the grid line y = 2: the row north of it.
        assert_eq!(
            cells((0.5, 2.0), (2.5, 2.0)),
            [Cell::new(0, 2), Cell::new(1, 2), Cell::new(2, 2)]
        );
    }

    #[test]
    fn walks_stop_when_asked_and_clip_at_the_grid() {
        let geom = GridGeometry::new(10, 10, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut seen = 0;
        let t = traverse(
            &geom,
            Point2::new(0.05, 0.05),
            Point2::new(0.95, 0.05),
            |c, _| {
                seen += 1;
                if c.col == 3 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        );
        assert_eq!((t.visited, t.end, seen), (4, TraversalEnd::Stopped, 4));
        // From far outside, through the grid and out again.
        let (cells, t) = walk(&geom, Point2::new(-100.0, 0.55), Point2::new(100.0, 0.55));
        assert_eq!(cells.len(), 10);
        assert_eq!(t.end, TraversalEnd::Clipped);
        assert!(cells.iter().all(|c| c.row == 5));
        // Missing the grid entirely, and non-finite input.
        assert_eq!(
            walk(&geom, Point2::new(-1.0, -1.0), Point2::new(2.0, -0.5)).0,
            []
        );
        assert_eq!(
            walk(&geom, Point2::new(f32::NAN, 0.0), Point2::new(0.5, 0.5))
                .1
                .end,
            TraversalEnd::Clipped
        );
    }

    #[test]
    fn fine_resolution_segments_agree_with_a_floating_point_brute_force() {
        // The onboard geometry (10 cm, arbitrary origin): compare with closed-square
        // Liang–Barsky in f64, ignoring touches of a single point (measure zero for random
        // segments).
        let geom = GridGeometry::new(60, 40, 0.1, Point2::new(-3.7, 1.3)).unwrap();
        let mut rng = seeded(11);
        for _ in 0..500 {
            let mut p = || {
                Point2::new(
                    range_f32(&mut rng, -4.5, 3.0),
                    range_f32(&mut rng, 0.5, 6.0),
                )
            };
            let (a, b) = (p(), p());
            let (mut got, _) = walk(&geom, a, b);
            got.sort();
            let mut want = Vec::new();
            for r in 0..geom.height as i32 {
                for c in 0..geom.width as i32 {
                    let g = |v: f32, o: f32| ((v - o) / geom.resolution_m) as f64;
                    let (x0, y0) = (g(a.x, geom.origin.x), g(a.y, geom.origin.y));
                    let (x1, y1) = (g(b.x, geom.origin.x), g(b.y, geom.origin.y));
                    let (dx, dy) = (x1 - x0, y1 - y0);
                    let (mut t0, mut t1) = (0.0f64, 1.0f64);
                    let mut ok = true;
                    for (p, q) in [
                        (-dx, x0 - c as f64),
                        (dx, c as f64 + 1.0 - x0),
                        (-dy, y0 - r as f64),
                        (dy, r as f64 + 1.0 - y0),
                    ] {
                        if p == 0.0 {
                            ok &= q >= 0.0;
                        } else if p < 0.0 {
                            t0 = t0.max(q / p);
                        } else {
                            t1 = t1.min(q / p);
                        }
                    }
                    if ok && t1 - t0 > 1e-9 {
                        want.push(Cell::new(c, r));
                    }
                }
            }
            want.sort();
            assert_eq!(got, want, "{a:?} -> {b:?}");
        }
    }
}
