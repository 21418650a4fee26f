//! The run's coverage of the world's observable cells, kept up to date cheaply after each scan
//! ([`CoverageCounter`]).

use papillon::geometry::{Point2, Pose2};
use papillon::grid::{GridGeometry, OccupancyGrid};
use papillon::sensor::{LaserConfig, Scan};

use crate::world::Truth;

/// Coverage of the shared map against the truth, kept up to date cheaply: after each scan only
/// the cells it may have changed are re-read (its laser's field of view and the cells near the
/// robot); a full recount every second catches the rest.
pub(super) struct CoverageCounter {
    truth: Truth,
    /// Per cell, 1 when it is observable (the truth's mask, in 32-bit lanes like the
    /// log-odds, so that the count vectorises without widening or narrowing).
    observable: Vec<u32>,
    /// Per cell, 1 when it is observable and was known at its last reading.
    known: Vec<u32>,
    pub(super) count: usize,
}

impl CoverageCounter {
    pub(super) fn new(truth: Truth) -> Self {
        let n = truth.mask().len();
        Self {
            observable: truth.mask().iter().map(|&m| u32::from(m)).collect(),
            truth,
            known: vec![0; n],
            count: 0,
        }
    }

    /// Recounts every cell (the same sum as counting the observable cells that are known).
    pub(super) fn recount<const N: usize>(&mut self, grid: &OccupancyGrid<N>) {
        let g = *grid.geometry();
        let all = CellRect {
            cols: 0..g.width,
            rows: 0..g.height,
        };
        self.update(grid, [all]);
    }

    /// Re-reads the cells a scan integrated at `pose_map` may have changed: the cells the
    /// beams can reach (the bounding box of the laser's field of view out to its range), and
    /// those within [`NEAR_ROBOT_M`] of the robot (its own trail, cleared at each scan, and the
    /// obstacles marked in front of it).
    pub(super) fn update_after_scan<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        pose_map: Pose2,
        laser: &LaserConfig,
        scan: &Scan,
    ) {
        let g = *grid.geometry();
        let near = CellRect::around(&g, pose_map.position(), NEAR_ROBOT_M, NEAR_ROBOT_M);
        let (lo, hi) = field_of_view_box(pose_map, laser, scan);
        let seen = CellRect::around(
            &g,
            Point2::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y)),
            0.5 * (hi.x - lo.x) + FIELD_MARGIN_M,
            0.5 * (hi.y - lo.y) + FIELD_MARGIN_M,
        );
        self.update(grid, [near, seen]);
    }

    /// Re-reads the cells of the union of `rects`: row by row, the columns between the first
    /// and the last a rectangle covers in that row.
    ///
    /// Only the parts inside the grid's known box are read: outside it no cell has ever been
    /// known, so none counts now or did at its last reading (a recount then costs what the
    /// explored region holds, not the map).
    fn update<const N: usize, const M: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        rects: [CellRect; M],
    ) {
        let k = grid.known_box();
        // Clipped in place (no allocation per scan); an emptied rectangle takes no part.
        let rects = rects.map(|r| CellRect {
            cols: r.cols.start.max(k.col_min)..r.cols.end.min(k.col_end),
            rows: r.rows.start.max(k.row_min)..r.rows.end.min(k.row_end),
        });
        let rects = || {
            rects
                .iter()
                .filter(|r| !r.cols.is_empty() && !r.rows.is_empty())
        };
        let width = grid.geometry().width;
        let rows_from = rects().map(|r| r.rows.start).min().unwrap_or(0);
        let rows_to = rects().map(|r| r.rows.end).max().unwrap_or(0);
        let log_odds = grid.log_odds();
        // Branch-free over each row (the compiler vectorises it): a cell counts when it is
        // observable and known; `known` only ever holds observable cells.
        let (mut now_known, mut was_known) = (0usize, 0usize);
        for row in rows_from..rows_to {
            let in_row = || rects().filter(|r| r.rows.contains(&row));
            let (Some(c0), Some(c1)) = (
                in_row().map(|r| r.cols.start).min(),
                in_row().map(|r| r.cols.end).max(),
            ) else {
                continue;
            };
            let span = row * width + c0..row * width + c1;
            let (mut now_row, mut was_row) = (0u32, 0u32);
            for ((known, &observable), &l) in self.known[span.clone()]
                .iter_mut()
                .zip(&self.observable[span.clone()])
                .zip(&log_odds[span])
            {
                let k = observable & u32::from((l > 0.0) | (l < 0.0));
                now_row += k;
                was_row += *known;
                *known = k;
            }
            now_known += now_row as usize;
            was_known += was_row as usize;
        }
        self.count = self.count + now_known - was_known;
    }

    pub(super) fn truth(&self) -> &Truth {
        &self.truth
    }

    pub(super) fn coverage(&self) -> f32 {
        if self.truth.is_empty() {
            0.0
        } else {
            self.count as f32 / self.truth.len() as f32
        }
    }
}

/// Cells within this distance \[m\] of a robot are re-read after each of its scans, whatever
/// its laser's field of view: its trail (the last metre, cleared of Occupied evidence at each
/// scan, out to its body's radius) and the obstacles marked just in front of it.
const NEAR_ROBOT_M: f32 = 2.5;

/// Margin \[m\] around a laser's field of view for the cells its beams' ends round into.
const FIELD_MARGIN_M: f32 = 0.3;

/// A rectangle of cells, clipped to the grid.
#[derive(Clone, Debug)]
struct CellRect {
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
}

impl CellRect {
    /// The cells within `half_x` and `half_y` \[m\] of `p` along each axis.
    fn around(g: &GridGeometry, p: Point2, half_x: f32, half_y: f32) -> Self {
        let r = g.resolution_m;
        let lo = |v: f32, o: f32, h: f32| (((v - h - o) / r).floor() as i64).max(0) as usize;
        let hi = |v: f32, o: f32, h: f32, n: usize| {
            (((v + h - o) / r).ceil() as i64).clamp(0, n as i64) as usize
        };
        let cols = lo(p.x, g.origin.x, half_x)..hi(p.x, g.origin.x, half_x, g.width);
        let rows = lo(p.y, g.origin.y, half_y)..hi(p.y, g.origin.y, half_y, g.height);
        Self { cols, rows }
    }
}

/// Corners (south-west, north-east) of the box holding every beam of `scan` taken at
/// `pose_map` by `laser`, out to its usable range: the laser's position, the ends of its first
/// and last beams, and the points due east, north, west and south of it when the field of view
/// faces them.
fn field_of_view_box(pose_map: Pose2, laser: &LaserConfig, scan: &Scan) -> (Point2, Point2) {
    let pose = pose_map.compose(laser.mount);
    let o = pose.position();
    let range = laser.max_range_m;
    let (mut lo, mut hi) = (o, o);
    let mut grow = |x: f32, y: f32| {
        lo = Point2::new(lo.x.min(x), lo.y.min(y));
        hi = Point2::new(hi.x.max(x), hi.y.max(y));
    };
    let angles = scan.beams().iter().map(|b| b.angle_rad);
    let first = angles.clone().fold(f32::INFINITY, f32::min);
    let last = angles.fold(f32::NEG_INFINITY, f32::max);
    if !(first <= last && range.is_finite()) {
        // No beam with a finite angle, or a range the scan cannot be integrated with.
        return (lo, hi);
    }
    let (a0, span) = (pose.theta + first, last - first);
    for a in [a0, a0 + span] {
        grow(o.x + range * a.cos(), o.y + range * a.sin());
    }
    for (k, (dx, dy)) in [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let axis = k as f32 * std::f32::consts::FRAC_PI_2;
        if (axis - a0).rem_euclid(std::f32::consts::TAU) <= span || span >= std::f32::consts::TAU {
            grow(o.x + range * dx, o.y + range * dy);
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::random;

    #[test]
    fn the_field_of_view_box_holds_every_beam() {
        let mut rng = random::seeded(12);
        for (layout, laser) in [LaserConfig::thesis(), LaserConfig::lms1xx()]
            .into_iter()
            .enumerate()
        {
            let mut scan = Scan::new();
            for i in 0..laser.beam_count as usize {
                scan.push(papillon::sensor::Beam {
                    angle_rad: laser.beam_angle(i),
                    range_m: None,
                })
                .unwrap();
            }
            for case in 0..500 {
                let pose = Pose2::new(
                    random::range_f32(&mut rng, -5.0, 5.0),
                    random::range_f32(&mut rng, -5.0, 5.0),
                    random::range_f32(&mut rng, -4.0, 4.0),
                );
                let (lo, hi) = field_of_view_box(pose, &laser, &scan);
                let eye = pose.compose(laser.mount);
                let mut touched = [false; 4];
                for b in scan.beams() {
                    let a = eye.theta + b.angle_rad;
                    let end = Point2::new(
                        eye.x + laser.max_range_m * a.cos(),
                        eye.y + laser.max_range_m * a.sin(),
                    );
                    let slack = 1e-4;
                    assert!(
                        end.x >= lo.x - slack
                            && end.x <= hi.x + slack
                            && end.y >= lo.y - slack
                            && end.y <= hi.y + slack,
                        "layout {layout} case {case}: {end:?} outside {lo:?}..{hi:?}"
                    );
                    // How close the beams come to each side of the box.
                    let near = 0.01 * laser.max_range_m;
                    touched[0] |= end.x - lo.x < near;
                    touched[1] |= hi.x - end.x < near;
                    touched[2] |= end.y - lo.y < near;
                    touched[3] |= hi.y - end.y < near;
                }
                // The box is tight: each side is reached by a beam or is the laser itself.
                for (side, &t) in touched.iter().enumerate() {
                    let at_eye = [lo.x == eye.x, hi.x == eye.x, lo.y == eye.y, hi.y == eye.y];
                    assert!(
                        t || at_eye[side],
                        "layout {layout} case {case}: side {side}"
                    );
                }
            }
        }
    }
}
