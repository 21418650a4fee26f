//! Pruning a cell path to line-of-sight waypoints.
//!
//! A greedy string-pulling pass: from the current anchor, the path is followed as far as the
//! straight segment from the anchor stays clear; the last clear cell becomes the next waypoint.
//! Clearance is tested on the segment between cell centres with a conservative supercover
//! traversal: every cell the segment touches, including both side cells where it passes
//! exactly through a cell corner (the grid traversal of Amanatides & Woo, "A Fast Voxel
//! Traversal Algorithm for Ray Tracing", Eurographics 1987, in the exact integer form of
//! Bresenham, "Algorithm for computer control of a digital plotter", IBM Systems Journal 4(1),
//! 1965). No segment may cross a blocked or inflated cell, nor a cell of a wall band closer to
//! the walls than the path itself went between its ends (a shortcut would bring the robot
//! nearer the walls than the planner chose to). A path from A* or the distance field never cuts
//! corners, so consecutive cells always see each other and the pass always advances.
//!
//! The robot turns in place at a waypoint, so a waypoint is put where it can
//! ([`Traversability::can_turn`]): where the line of sight ends inside the no-turn band (a
//! door), the waypoint goes back to the last cell of the path before it where the robot can
//! turn, if there is one since the previous waypoint.
//!
//! A segment that enters the no-turn band (a door, a narrow aisle) must run along the path's
//! own cells there: every cell it touches is a cell of the path. A shortcut may otherwise cross
//! a one-cell channel at a slant, and a P3-DX with 6 cm to spare on each side of a 0.5 m
//! door, entering it 6° off its axis, brings a front corner 2 cm nearer one frame (the safety
//! monitor stops it). The path's cells through a narrow place run along its axis, and the
//! waypoint before it is then the last cell, where the robot can still turn, on that line.
//!
//! A leg that would reach that last cell askew to the passage's axis gets an approach point
//! first: a cell on the axis, back from the passage, where the swing circle fits (clear of
//! the wall bands where there is room). The robot turns there and drives in along the axis;
//! coming at the last cell at a slant, its front corner and the safety monitor's corridor ahead
//! pointed at the passage's jamb and the monitor stopped it in front of the door again and
//! again (issue 17; see `approach_point`).

use super::traversability::{BAND_NEAR, BAND_NO_TURN};
use super::{BlockedBoxes, PlanError, Traversability};
use crate::geometry::Point2;
use crate::grid::Cell;

/// Whether the segment between the centres of `a` and `b` touches only passable cells (and
/// stays inside the grid). Cells touched only at a corner count as touched.
pub fn has_line_of_sight<const N: usize>(trav: &Traversability<N>, a: Cell, b: Cell) -> bool {
    supercover(a, b, |c| trav.is_passable(c))
}

/// Visits every cell the segment between the centres of `a` and `b` touches, in order, until
/// `visit` returns `false`. Returns whether every visit returned `true`.
pub fn supercover(a: Cell, b: Cell, mut visit: impl FnMut(Cell) -> bool) -> bool {
    let nx = (b.col - a.col).unsigned_abs() as i64;
    let ny = (b.row - a.row).unsigned_abs() as i64;
    let sx = (b.col - a.col).signum();
    let sy = (b.row - a.row).signum();
    let (mut x, mut y) = (a.col, a.row);
    if !visit(Cell::new(x, y)) {
        return false;
    }
    let (mut ix, mut iy) = (0i64, 0i64);
    while ix < nx || iy < ny {
        // Compare where the segment crosses the next vertical and horizontal cell borders:
        // (1 + 2 ix) / nx against (1 + 2 iy) / ny, cross-multiplied.
        let decision = (1 + 2 * ix) * ny - (1 + 2 * iy) * nx;
        if decision == 0 {
            // Exactly through a corner: both side cells are touched.
            if !visit(Cell::new(x + sx, y)) || !visit(Cell::new(x, y + sy)) {
                return false;
            }
            x += sx;
            y += sy;
            ix += 1;
            iy += 1;
        } else if decision < 0 {
            x += sx;
            ix += 1;
        } else {
            y += sy;
            iy += 1;
        }
        if !visit(Cell::new(x, y)) {
            return false;
        }
    }
    true
}

/// Prunes `path` to waypoints: the map-frame centres \[m\] of the first cell, the cells where
/// the line of sight from the previous waypoint ends, and the last cell. Writes them into
/// `out` and returns how many.
///
/// Errors: [`PlanError::CapacityExceeded`] if `out` is too short; [`PlanError::NoPath`] if
/// two consecutive cells of `path` do not see each other (not a valid path on this layer). An
/// empty path gives no waypoints.
pub fn prune_to_waypoints<const N: usize>(
    trav: &Traversability<N>,
    path: &[Cell],
    out: &mut [Point2],
) -> Result<usize, PlanError> {
    prune_with(trav, path, out, |a, b, band| sight_within(trav, a, b, band))
}

/// Whether the segment between the centres of `a` and `b` touches only passable cells whose
/// wall band is at most `band`.
fn sight_within<const N: usize>(trav: &Traversability<N>, a: Cell, b: Cell, band: u8) -> bool {
    supercover(a, b, |c| trav.wall_band(c).is_some_and(|x| x <= band))
}

/// Halvings of a segment when covering it with boxes ([`BlockedBoxes::is_segment_clear`]):
/// pieces down to 1/128 of the segment, about a cell for the legs of a house-sized map, so
/// that a segment passing close to a wall is still proven clear without being walked (on the
/// House snapshot, 7 halvings instead of 3 walk a tenth of the cells for 15 % more box
/// look-ups; the recursion stops at the first piece that fails, so a blocked segment costs at
/// most `2^(BOX_DEPTH + 1)` look-ups before its walk).
const BOX_DEPTH: u32 = 7;

/// [`prune_to_waypoints`] with the line of sight first checked on `boxes` (built from `trav`):
/// a segment covered by boxes without blocked cells is clear without being walked. Same
/// result, faster in open space.
pub fn prune_to_waypoints_with_boxes<const N: usize>(
    trav: &Traversability<N>,
    boxes: &BlockedBoxes,
    path: &[Cell],
    out: &mut [Point2],
) -> Result<usize, PlanError> {
    prune_with(trav, path, out, |a, b, band| {
        boxes.is_segment_clear(a, b, BOX_DEPTH) || sight_within(trav, a, b, band)
    })
}

/// `sees(a, b, band)`: whether `b` is in sight of `a` through cells of wall band at most
/// `band`.
fn prune_with<const N: usize>(
    trav: &Traversability<N>,
    path: &[Cell],
    out: &mut [Point2],
    sees: impl Fn(Cell, Cell, u8) -> bool,
) -> Result<usize, PlanError> {
    let geometry = trav.geometry();
    let mut count = 0usize;
    let mut push = |cell: Cell, count: &mut usize| -> Result<(), PlanError> {
        if *count == out.len() {
            return Err(PlanError::CapacityExceeded {
                needed: *count + 1,
                capacity: out.len(),
            });
        }
        out[*count] = geometry.cell_center(cell);
        *count += 1;
        Ok(())
    };
    let Some(&first) = path.first() else {
        return Ok(0);
    };
    push(first, &mut count)?;
    let band_at = |c: Cell| trav.wall_band(c).unwrap_or(u8::MAX);
    // The highest wall band the step into `path[k]` touches: the cell, and for a diagonal
    // step the two cells beside its corner.
    let step_band = |k: usize| {
        let (a, b) = (path[k - 1], path[k]);
        let mut band = band_at(b);
        if a.col != b.col && a.row != b.row {
            band = band
                .max(band_at(Cell::new(b.col, a.row)))
                .max(band_at(Cell::new(a.col, b.row)));
        }
        band
    };
    // Whether the segment from `path[a]` to `path[b]` touches only cells of `path[a..=b]`,
    // in the path's order (a straight run of the path).
    let along_path = |a: usize, b: usize| {
        let mut j = a;
        supercover(path[a], path[b], |c| {
            while j <= b && path[j] != c {
                j += 1;
            }
            j <= b
        })
    };
    let mut anchor = 0usize;
    // The highest wall band of the path's cells from the anchor to `k`.
    let mut band = band_at(first);
    let mut k = 1usize;
    while k < path.len() {
        let with_k = band.max(step_band(k));
        if sees(path[anchor], path[k], with_k)
            && (with_k < BAND_NO_TURN || k == anchor + 1 || along_path(anchor, k))
        {
            band = with_k;
            k += 1;
            continue;
        }
        if k - 1 == anchor {
            return Err(PlanError::NoPath {
                start: path[anchor],
                goal: path[k],
            });
        }
        // Turn where the robot can: the last such cell since the anchor, else where the
        // sight ends. Every cell up to `k - 1` was in sight of the anchor.
        let turn = (anchor + 1..k)
            .rev()
            .find(|&j| trav.can_turn(path[j]))
            .unwrap_or(k - 1);
        // Into a narrow passage at a slant: first the approach point on its axis.
        if step_band(k) >= BAND_NO_TURN
            && let Some(dock) = approach_point(trav, path, anchor, turn, &along_path, &sees)
        {
            push(dock, &mut count)?;
        }
        anchor = turn;
        push(path[anchor], &mut count)?;
        band = band_at(path[anchor]);
        k = anchor + 1;
    }
    if path.len() > 1 {
        push(path[path.len() - 1], &mut count)?;
    }
    Ok(count)
}

/// Farthest the approach point before a narrow passage lies back along the passage's axis,
/// from the last cell of the path where the robot can turn \[m\].
const APPROACH_MAX_M: f32 = 1.0;

/// Most cells of the path's straight run into a narrow passage that give its axis.
const AXIS_CELLS: usize = 12;

/// A leg that comes at a narrow passage more askew than this to its axis gets an approach
/// point \[rad\] (the follower's default heading tolerance: less is driven straight anyway).
const APPROACH_SKEW_RAD: f32 = 0.1;

/// The approach point before a narrow passage the path enters at `turn` (the last cell before
/// the no-turn band where the robot can turn, a waypoint): a cell on the passage's axis (the
/// path's straight run from `turn` into the band) back from `turn`, the first clear of both
/// wall bands, else the farthest where the robot can still turn, at most [`APPROACH_MAX_M`]
/// back, in sight of `turn` and of the previous waypoint `path[anchor]` without crossing the
/// no-turn band. `None` when the leg from the anchor already runs along the axis, when the
/// run is too short to give an axis, or when no such cell exists.
///
/// Why: a robot that reaches `turn` askew turns there, but on the way its front corner and
/// the safety monitor's corridor ahead point at the passage's jamb, not into the passage; a
/// 0.455 m x 0.381 m body 0.34 rad off a 0.5 m door's axis spans 0.51 m across it, and the
/// monitor stops it in front of the door again and again (gen-10, seed 25, exact odometry).
/// From the approach point the robot turns where its swing circle fits and then drives
/// straight along the axis, the way a robot docks: a staging pose on the dock's axis first,
/// then straight in (the staging pose of the ROS 2 Navigation docking server,
/// `opennav_docking`; here for the turn-then-drive motions of the follower).
fn approach_point<const N: usize>(
    trav: &Traversability<N>,
    path: &[Cell],
    anchor: usize,
    turn: usize,
    along_path: &impl Fn(usize, usize) -> bool,
    sees: &impl Fn(Cell, Cell, u8) -> bool,
) -> Option<Cell> {
    if !trav.can_turn(path[turn]) {
        return None;
    }
    // The axis: the path's straight run from `turn` into the passage.
    let last = (turn + AXIS_CELLS).min(path.len() - 1);
    let mut end = turn;
    while end < last && along_path(turn, end + 1) {
        end += 1;
    }
    if end < turn + 2 {
        return None;
    }
    let geometry = trav.geometry();
    let from = geometry.cell_center(path[turn]);
    let to = geometry.cell_center(path[end]);
    let run_m = from.distance(to);
    let (ux, uy) = ((to.x - from.x) / run_m, (to.y - from.y) / run_m);
    // Already coming along the axis: nothing to add.
    let a = geometry.cell_center(path[anchor]);
    let leg_m = a.distance(from);
    if leg_m > 1e-6 {
        let (dx, dy) = ((from.x - a.x) / leg_m, (from.y - a.y) / leg_m);
        let sin_skew = dx * uy - dy * ux;
        if dx * ux + dy * uy > 0.0 && sin_skew.abs() <= crate::math::sin(APPROACH_SKEW_RAD) {
            return None;
        }
    }
    let step_m = 0.5 * geometry.resolution_m;
    let mut best = None;
    let mut seen = path[turn];
    let mut back_m = step_m;
    while back_m <= APPROACH_MAX_M {
        let p = Point2::new(from.x - ux * back_m, from.y - uy * back_m);
        let Some(c) = geometry.cell_at(p) else {
            break;
        };
        if c != seen {
            if !trav.can_turn(c) || !sees(c, path[turn], BAND_NEAR) {
                break;
            }
            seen = c;
            best = Some(c);
            if trav.wall_band(c) == Some(0) {
                break;
            }
        }
        back_m += step_m;
    }
    let q = best?;
    let band = trav
        .wall_band(path[anchor])
        .unwrap_or(u8::MAX)
        .max(BAND_NEAR);
    (q != path[anchor] && sees(path[anchor], q, band)).then_some(q)
}
