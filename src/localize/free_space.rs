//! The free-space half of a match's evidence: a laser does not see through walls, so a pose
//! that puts a scan's returns behind walls the map holds is not where the scan was taken,
//! however well the returns pair with surfaces there. The point-to-line fit ([`super::ndt`])
//! and the likelihood field ([`super::likelihood`]) read the map only at the returns; a beam
//! model scores the cells each beam crossed as well (Thrun, Burgard and Fox, *Probabilistic
//! Robotics*, 2005, §6.3; Hähnel, Burgard, Fox and Thrun, *An efficient FastSLAM algorithm*,
//! IROS 2003). Used where two basins compete and their returns' fit alone cannot tell them
//! apart: the far face of a wall seen from both sides lies a wall's thickness behind the near
//! one.

use crate::geometry::{Point2, Pose2};
use crate::grid::{CellClass, OccupancyGrid};
use crate::sensor::LaserConfig;

/// The share of `points` (robot frame, the returns a match used) whose beam from the laser
/// at `pose` crosses a cell `grid` holds Occupied more than `margin_m` before the return (the
/// margin keeps a return's own wall out of the count). 0 when no return is farther than the
/// margin.
pub fn seen_through<const N: usize>(
    grid: &OccupancyGrid<N>,
    points: &[Point2],
    laser: &LaserConfig,
    pose: Pose2,
    margin_m: f32,
) -> f32 {
    let geom = *grid.geometry();
    let origin = pose.transform_point(laser.mount.position());
    let mut through = 0usize;
    let mut counted = 0usize;
    for &p in points {
        let end = pose.transform_point(p);
        let range = origin.distance(end);
        if !range.is_finite() || range <= margin_m {
            continue;
        }
        let k = (range - margin_m) / range;
        let stop = Point2::new(
            origin.x + (end.x - origin.x) * k,
            origin.y + (end.y - origin.y) * k,
        );
        counted += 1;
        let mut hit = false;
        crate::raycast::traverse(&geom, origin, stop, |_, index| {
            if grid.class(index) == CellClass::Occupied {
                hit = true;
                core::ops::ControlFlow::Break(())
            } else {
                core::ops::ControlFlow::Continue(())
            }
        });
        through += usize::from(hit);
    }
    if counted == 0 {
        0.0
    } else {
        through as f32 / counted as f32
    }
}

/// A beam counts as seen through when it crosses a wall more than this many cells before its
/// return ([`crosses_more_walls`]'s default margin): a cell and a half, so a return's own
/// wall cell and the one beside it do not count, while a wall two cells thick does.
pub const MARGIN_CELLS: f32 = 1.5;

/// How much larger a share of beams through walls must be to count as more
/// ([`crosses_more_walls`]'s default slack): 2 % of the returns.
pub const SLACK: f32 = 0.02;

/// Whether `candidate` puts more of `points`' beams through `grid`'s walls than `other` does
/// by more than `slack` (a share of the returns), a beam counting from `margin_cells` cells
/// before its return ([`seen_through`]): `Some(share at candidate)` when it does. Where two
/// poses fit a scan's returns about as well, the one that sees through walls is not where the
/// scan was taken.
pub fn crosses_more_walls<const N: usize>(
    grid: &OccupancyGrid<N>,
    points: &[Point2],
    laser: &LaserConfig,
    candidate: Pose2,
    other: Pose2,
    margin_cells: f32,
    slack: f32,
) -> Option<f32> {
    let margin_m = margin_cells * grid.geometry().resolution_m;
    let through = seen_through(grid, points, laser, candidate, margin_m);
    (through > seen_through(grid, points, laser, other, margin_m) + slack).then_some(through)
}
