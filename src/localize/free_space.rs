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
