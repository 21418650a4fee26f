//! Localisation: aligning a laser scan to the occupancy grid before it is integrated, so the
//! map stays true while the odometry drifts.
//!
//! Scans are matched not to the occupancy grid but to where earlier returns landed
//! ([`hits`], a layer of the shared map written at the corrected pose after every match): the
//! grid's free-space clearing moves and erodes walls in ways that bias a match (see there).
//!
//! A match ([`ScanMatcher::match_scan`]) starts from the odometry prediction and runs in up to
//! four parts, one file each:
//! 1. [`ndt`]: point-to-line refinement of the prediction against the per-cell statistics of
//!    the returns ([`hits`], a normal distributions transform, Biber & Straßer, IROS 2003),
//!    with a robust kernel; it gives the pose to a fraction of the range noise and the fit's
//!    information matrix;
//! 2. only when that pairs too few returns with the map (the prediction is poor):
//!    [`likelihood`], a blurred local copy of the returns around the scan, and [`correlative`],
//!    Olson's exhaustive search of a small pose window around the prediction on it (*Real-time
//!    correlative scan matching*, ICRA 2009), which finds the right basin; the refinement
//!    starts again from there if its beams pass through no more of the map's walls than at
//!    the prediction ([`MatchConfig::search_see_through`], [`free_space`]);
//! 3. [`constraint`]: the eigen-analysis of the information; the correction is kept only along
//!    directions the scan constrains, and the odometry prediction along the others (a
//!    featureless corridor).
//!
//! A match knows when not to trust itself ([`Distrust`]): too few returns, a scan that falls
//! mostly on cells the map does not know yet, a window larger than its memory, or a poor fit.
//! Then the prediction is returned unchanged. [`MatchQuality`] reports what the decision was
//! based on.
//!
//! [`tracker`] applies matches to the mission's map-from-odometry transform; with
//! [`odometry_calibration`] (on by default) it also estimates the odometry's systematic
//! errors from them and corrects each odometry increment before the prediction.
//!
//! [`graph`] (off by default, [`graph::GraphConfig`]) keeps keyframes ([`keyframes`]) in a pose
//! graph ([`pose_graph`]), closes loops when a place is seen again ([`loop_closure`]) and then
//! draws the reference and the grid again from the corrected keyframes; a closure whose scan
//! also fits the prediction's basin is refused when it puts more beams through the walls of
//! the old keyframes' map ([`free_space`]).
//!
//! `no_std`, allocation-free (the working memory is [`ScanMatcher`], sized by its const
//! generic), sans-IO and deterministic: the same grid, scan and prediction give the same pose.

pub mod constraint;
pub mod correlative;
pub mod free_space;
pub mod graph;
pub mod hits;
pub mod keyframes;
pub mod likelihood;
pub mod loop_closure;
pub mod ndt;
pub mod odometry_calibration;
pub mod path_uncertainty;
pub mod pose_graph;
pub mod tracker;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod closure_tests;

#[cfg(test)]
mod graph_tests;

use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::grid::OccupancyGrid;
use crate::math;
use crate::sensor::{LaserConfig, MAX_BEAMS, Scan};

use constraint::Constraint;
use correlative::SearchWindow;
use likelihood::LikelihoodField;

pub use hits::HitMap;
pub use tracker::{LocalizeConfig, Tracker};

/// Cells of the likelihood window a mission's matcher holds: 120 x 120, enough for a 4 m laser
/// on a 10 cm grid with the search margins (57.6 KB).
pub const WINDOW_CELLS: usize = 120 * 120;

/// Side of the square likelihood window a match may need \[cells\]: a scan reaching
/// `reach_m` from the robot's centre on every side, grown by the search and the blur as
/// [`ScanMatcher::match_scan`] grows it, on a grid of `resolution_m` cells (one cell more each
/// way for the cell boundaries). A board whose window exceeds [`WINDOW_CELLS`] would have every
/// match refused ([`Distrust::WindowTooLarge`]); the board check refuses it instead.
pub fn window_side_cells(reach_m: f32, resolution_m: f32, config: &MatchConfig) -> usize {
    let res = resolution_m.max(1e-3);
    let margin = window_margin_m(reach_m, res, config);
    math::ceil((2.0 * reach_m + 2.0 * margin) / res) as usize + 2
}

/// How far the likelihood window reaches beyond the scan's extent at the prediction \[m\]:
/// the translation searched (whole cells), the arc the farthest return (`reach_m` from the
/// robot's centre) sweeps over the rotation searched, twice the blur, and two cells.
fn window_margin_m(reach_m: f32, res: f32, config: &MatchConfig) -> f32 {
    math::ceil(config.search_xy_m / res).max(0.0) * res
        + reach_m * math::sin(config.search_theta_rad.min(1.5))
        + 2.0 * config.sigma_m
        + 2.0 * res
}

/// Whether the basin Olson's search found (`search`: the refined pose and the returns it
/// pairs) replaces the one the refinement from the prediction ended in (`kept`): when it pairs
/// more returns and, with `see_through`, puts no more than 2 % more of `points`' beams (robot
/// frame) through the map's walls, counted from 1.5 cells before each return
/// ([`free_space::crosses_more_walls`]). A scan of a wall's near face fits its far face, a wall's
/// thickness behind, about as well; the beams to the far face cross the near one.
fn search_basin_wins<const N: usize>(
    grid: &OccupancyGrid<N>,
    points: &[Point2],
    laser: &LaserConfig,
    search: (Pose2, u32),
    kept: (Pose2, u32),
    see_through: bool,
) -> bool {
    if search.1 <= kept.1 {
        return false;
    }
    !see_through
        || free_space::crosses_more_walls(
            grid,
            points,
            laser,
            search.0,
            kept.0,
            free_space::MARGIN_CELLS,
            free_space::SLACK,
        )
        .is_none()
}

/// Settings of a match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchConfig {
    /// Translation searched around the prediction, each way \[m\].
    pub search_xy_m: f32,
    /// Rotation searched around the prediction, each way \[rad\].
    pub search_theta_rad: f32,
    /// Heading step of the search \[rad\].
    pub theta_step_rad: f32,
    /// Blur of the likelihood field \[m\] (about the laser's range noise).
    pub sigma_m: f32,
    /// Returns used at most (the scan is thinned evenly to this many).
    pub max_points: usize,
    /// Fewer usable returns than this: no match.
    pub min_points: usize,
    /// Fewer returns than this fraction on known cells or near known walls (at the
    /// prediction): no match.
    pub min_known_fraction: f32,
    /// Returns farther than this count less, as `(weight_range_m / range)²`: the range noise
    /// grows with the range \[m\].
    pub weight_range_m: f32,
    /// Length that turns a rotation into a distance for the eigen-analysis \[m\].
    pub length_scale_m: f32,
    /// Motion prior: mean likelihood taken off at the edge of the search window.
    pub prior_at_edge: f32,
    /// The search's best pose replaces the prediction as the refinement's start only when it
    /// scores this much more (mean likelihood).
    pub min_search_gain: f32,
    /// Fewer than this fraction of the returns on known ground paired with a surface after
    /// the fit: no match.
    pub min_fit_fraction: f32,
    /// The refinement from the prediction pairs fewer than this fraction: Olson's search
    /// looks for a better start.
    pub search_below_fit: f32,
    /// The point-to-line refinement ([`ndt`]; its `noise_fraction` and `length_scale_m` are
    /// taken from the laser and from this configuration).
    pub fine: ndt::NdtConfig,
    /// A cell of the returns layer is a wall cell (scores 1) at this fraction of the largest
    /// weight within the blur's reach ([`likelihood::WALL_FRACTION`]).
    pub wall_fraction: f32,
    /// A match's error is taken as at least this \[m\] in every constrained direction of
    /// `(x, y, θ·L)`, whatever its residuals say: the fit's information counts each return's
    /// noise as independent, but the map it fits was drawn at poses that were themselves a
    /// few millimetres off, an error shared by every return on a wall (0: the fit as it is).
    /// An experiment, off: with exact odometry it halves the closed-loop error, with the
    /// realistic odometry's it makes it worse (docs/experiments.md, seventh measurement).
    pub min_sigma_m: f32,
    /// The search's basin replaces the prediction's only when no more than 2 % more of its
    /// beams pass through a wall of the map (counted from 1.5 cells before the return) than
    /// at the prediction's ([`free_space::seen_through`]). On by default: with the realistic
    /// odometry and the odometry self-calibration it took the house's 100 seeds from 8 to 5
    /// end errors above 15 cm (docs/experiments.md, "Issue 18: the tracker's search through a
    /// wall" and "the self-calibration and the search's free-space test by default").
    pub search_see_through: bool,
    /// Blur the returns by a Gaussian sum (a density of returns) before normalising, instead
    /// of by Olson's max-convolution after (an experiment, off: measured no better,
    /// docs/experiments.md).
    pub smooth: bool,
}

impl Default for MatchConfig {
    /// ±0.3 m and ±0.1 rad (5.7°) at 0.01 rad, σ 0.1 m, at most 270 returns, at least 30,
    /// half of them on known cells, returns beyond 1 m weighted by 1/r² in the search, L = 1 m,
    /// prior 0.02, search gain 0.03; at least 30 % of the returns paired after the fit, the
    /// search only when fewer than 60 % are; the refinement's defaults ([`ndt::NdtConfig`]);
    /// wall cells at half the local peak, max-convolution; the search's basin only if its
    /// beams cross no more walls.
    fn default() -> Self {
        Self {
            search_xy_m: 0.3,
            search_theta_rad: 0.1,
            theta_step_rad: 0.01,
            sigma_m: 0.1,
            max_points: 270,
            min_points: 30,
            min_known_fraction: 0.5,
            weight_range_m: 1.0,
            length_scale_m: 1.0,
            prior_at_edge: 0.02,
            min_search_gain: 0.03,
            min_fit_fraction: 0.3,
            search_below_fit: 0.6,
            fine: ndt::NdtConfig::default(),
            wall_fraction: likelihood::WALL_FRACTION,
            min_sigma_m: 0.0,
            search_see_through: true,
            smooth: false,
        }
    }
}

/// Why a match was not trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distrust {
    /// Fewer usable returns than [`MatchConfig::min_points`].
    TooFewReturns,
    /// Most returns fall on cells the map does not know.
    MostlyUnknown,
    /// The window around the scan needs more cells than the matcher holds.
    WindowTooLarge,
    /// The best fit explains too little of the scan.
    PoorFit,
    /// No direction is constrained.
    Degenerate,
}

/// What a match was based on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchQuality {
    /// Returns used.
    pub points: u16,
    /// Fraction of them on known cells or near known walls at the prediction (only those
    /// take part in the fit).
    pub known_fraction: f32,
    /// Mean likelihood of the returns at the result, 0..=1.
    pub score: f32,
    /// Eigenvalues of the information per unit weight of returns, ascending \[1/m²\] (rotation scaled by
    /// [`MatchConfig::length_scale_m`]).
    pub eigenvalues: [f32; 3],
    /// Directions constrained (0..=3): 3 is a full fix, 2 a corridor.
    pub constrained: u8,
    /// Correction applied (result minus prediction) \[m, m, rad\].
    pub correction: [f32; 3],
    /// Why the match was refused, if it was.
    pub distrust: Option<Distrust>,
}

impl MatchQuality {
    /// Whether any of the correction was applied.
    pub fn trusted(&self) -> bool {
        self.distrust.is_none()
    }
}

/// A match's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchResult {
    /// The corrected robot pose (the prediction when not trusted) \[m, rad\].
    pub pose: Pose2,
    /// What it was based on.
    pub quality: MatchQuality,
    /// The fit's information (inverse covariance) along the constrained directions, in
    /// `(x [m], y [m], θ [rad])` (zero when not trusted).
    pub information: [[f32; 3]; 3],
}

/// The working memory of a scan matcher: the likelihood window of `T` cells and the scan's
/// returns.
#[derive(bytemuck::Zeroable)]
pub struct ScanMatcher<const T: usize> {
    field: LikelihoodField<T>,
    /// The returns in use, robot frame \[m\]: the first `len`.
    points: [Point2; MAX_BEAMS],
    /// Their weights: the first `len`.
    weights: [f32; MAX_BEAMS],
    len: usize,
    scratch: [(u32, f32); MAX_BEAMS],
}

impl<const T: usize> core::fmt::Debug for ScanMatcher<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ScanMatcher")
            .field("capacity", &T)
            .finish_non_exhaustive()
    }
}

impl<const T: usize> Default for ScanMatcher<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const T: usize> ScanMatcher<T> {
    /// Empty working memory.
    pub const fn new() -> Self {
        Self {
            field: LikelihoodField::new(),
            points: [Point2::new(0.0, 0.0); MAX_BEAMS],
            weights: [0.0; MAX_BEAMS],
            len: 0,
            scratch: [(0, 0.0); MAX_BEAMS],
        }
    }

    /// Aligns `scan`, taken by `laser` at about `predicted` (map frame, from odometry), to
    /// the returns in `hits`; `grid` (same geometry) tells which cells the map knows.
    /// Returns the corrected pose, or `predicted` when the match is not trusted.
    /// Allocation-free.
    pub fn match_scan<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        hits: &HitMap<N>,
        scan: &Scan,
        laser: &LaserConfig,
        predicted: Pose2,
        config: &MatchConfig,
    ) -> MatchResult {
        let mut quality = MatchQuality {
            points: 0,
            known_fraction: 0.0,
            score: 0.0,
            eigenvalues: [0.0; 3],
            constrained: 0,
            correction: [0.0; 3],
            distrust: None,
        };
        let refuse = |mut q: MatchQuality, why| {
            q.distrust = Some(why);
            MatchResult {
                pose: predicted,
                quality: q,
                information: [[0.0; 3]; 3],
            }
        };

        // The returns in the robot frame, thinned evenly.
        let usable = |r: Option<f32>| {
            r.filter(|r| r.is_finite() && *r >= laser.min_range_m && *r < laser.max_range_m)
        };
        let total = scan
            .beams()
            .iter()
            .filter(|b| usable(b.range_m).is_some())
            .count();
        let stride = total.div_ceil(config.max_points.max(1)).max(1);
        self.len = 0;
        let near = config.weight_range_m.max(1e-3);
        let mut reach = 0.0f32;
        for b in scan
            .beams()
            .iter()
            .filter(|b| usable(b.range_m).is_some())
            .step_by(stride)
        {
            let r = usable(b.range_m).unwrap_or(0.0);
            let (sin, cos) = math::sin_cos(b.angle_rad);
            let p = laser.mount.transform_point(Point2::new(r * cos, r * sin));
            reach = reach.max(math::hypot(p.x, p.y));
            // At most MAX_BEAMS points from a scan of at most MAX_BEAMS beams.
            if self.len < MAX_BEAMS {
                let w = near / r.max(near);
                self.points[self.len] = p;
                self.weights[self.len] = w * w;
                self.len += 1;
            }
        }
        quality.points = self.len as u16;
        if self.len < config.min_points.max(1) {
            return refuse(quality, Distrust::TooFewReturns);
        }

        // The scan's extent at the prediction.
        let geom = grid.geometry();
        let (mut lo, mut hi) = (
            Point2::new(f32::INFINITY, f32::INFINITY),
            Point2::new(f32::NEG_INFINITY, f32::NEG_INFINITY),
        );
        for &p in &self.points[..self.len] {
            let q = predicted.transform_point(p);
            lo = Point2::new(lo.x.min(q.x), lo.y.min(q.y));
            hi = Point2::new(hi.x.max(q.x), hi.y.max(q.y));
        }

        // The window: the scan at the prediction, grown by the search and the blur.
        let res = geom.resolution_m;
        let cells = math::ceil(config.search_xy_m / res).max(0.0) as i32;
        let margin = window_margin_m(reach, res, config);
        lo = Point2::new(lo.x - margin, lo.y - margin);
        hi = Point2::new(hi.x + margin, hi.y + margin);
        if LikelihoodField::<T>::window_size(hits.geometry(), lo, hi).is_none() {
            return refuse(quality, Distrust::WindowTooLarge);
        }
        // The likelihood field over the window, built on first need: most scans need it
        // neither for the returns' test below nor for the search (a build is most of a
        // match's cost when the refinement starts in the basin).
        let mut field_built = false;
        let mut build_field = |field: &mut LikelihoodField<T>| {
            if !field_built {
                field_built = true;
                // The window fits (tested above), so the build succeeds.
                field.build(
                    hits,
                    lo,
                    hi,
                    config.sigma_m,
                    config.wall_fraction,
                    config.smooth,
                );
            }
        };

        // Only returns on a part of the world the map has seen take part: the cell the beam
        // crosses just before its return (by a cell and two range-noise σ) must be known, and
        // the return must land on a known cell or near returns the map holds. A return on
        // the continuation of a wall seen only in part so far would otherwise be pulled back
        // onto the seen part, a bias in the direction the robot turns or drives; and testing
        // the return's own cell alone would keep the short returns of a wall (in front of it,
        // known free) and drop the long ones (behind it, unknown), a bias toward the laser.
        let total = self.len;
        let mut kept = 0;
        let origin = laser.mount.position();
        let known_at = |q: Point2| {
            grid.class_of(geom.cell_at_unchecked(q))
                .is_some_and(|c| c.is_known())
        };
        for i in 0..total {
            let p = self.points[i];
            let r = math::hypot(p.x - origin.x, p.y - origin.y).max(1e-6);
            let back = (res + 2.0 * laser.noise_fraction * r).min(r);
            let t = 1.0 - back / r;
            let before = Point2::new(
                origin.x + (p.x - origin.x) * t,
                origin.y + (p.y - origin.y) * t,
            );
            let q = predicted.transform_point(p);
            if known_at(predicted.transform_point(before))
                && (known_at(q) || {
                    build_field(&mut self.field);
                    self.field.sample(q).0 > 0.0
                })
            {
                self.points[kept] = self.points[i];
                self.weights[kept] = self.weights[i];
                kept += 1;
            }
        }
        self.len = kept;
        quality.known_fraction = kept as f32 / total as f32;
        if quality.known_fraction < config.min_known_fraction || kept < config.min_points.max(1) {
            return refuse(quality, Distrust::MostlyUnknown);
        }

        // The point-to-line refinement from the prediction ([`ndt`]); when it pairs too few
        // returns with the map (the prediction is poor), Olson's search finds the basin and
        // the refinement starts again from its best pose.
        let mut fine_cfg = config.fine;
        fine_cfg.noise_fraction = laser.noise_fraction.max(0.0);
        fine_cfg.length_scale_m = config.length_scale_m;
        let fraction = |f: &ndt::Fitted| f.inliers as f32 / self.len.max(1) as f32;
        let mut fine = ndt::refine(hits, &self.points[..self.len], origin, predicted, &fine_cfg);
        if fraction(&fine) < config.search_below_fit {
            let steps = if config.theta_step_rad > 0.0 {
                math::floor(config.search_theta_rad / config.theta_step_rad) as i32
            } else {
                0
            };
            let window = SearchWindow {
                cells,
                steps,
                step_rad: config.theta_step_rad,
                prior_at_edge: config.prior_at_edge,
            };
            build_field(&mut self.field);
            let coarse = correlative::search(
                &self.field,
                &self.points[..self.len],
                &self.weights[..self.len],
                predicted,
                &window,
                &mut self.scratch,
            );
            if coarse.score - coarse.score_at_prediction > config.min_search_gain {
                let again = ndt::refine(
                    hits,
                    &self.points[..self.len],
                    origin,
                    coarse.pose,
                    &fine_cfg,
                );
                if search_basin_wins(
                    grid,
                    &self.points[..self.len],
                    laser,
                    (again.pose, again.inliers),
                    (fine.pose, fine.inliers),
                    config.search_see_through,
                ) {
                    fine = again;
                }
            }
        }
        let min_eig = 1.0 / (fine_cfg.max_sigma_m * fine_cfg.max_sigma_m).max(1e-12);
        let constraint = Constraint::analyse(
            &fine.information,
            &fine.position_test,
            min_eig,
            fine_cfg.min_information_ratio,
        );
        quality.eigenvalues = constraint.eigenvalues;
        quality.constrained = constraint.constrained_count();
        quality.score = fraction(&fine);
        if quality.score < config.min_fit_fraction || (fine.inliers as usize) < config.min_points {
            return refuse(quality, Distrust::PoorFit);
        }
        if quality.constrained == 0 {
            return refuse(quality, Distrust::Degenerate);
        }

        // Keep the correction along the constrained directions only.
        let l = config.length_scale_m;
        let delta = [
            fine.pose.x - predicted.x,
            fine.pose.y - predicted.y,
            normalize_angle(fine.pose.theta - predicted.theta) * l,
        ];
        let kept = constraint.project(delta);
        quality.correction = [kept[0], kept[1], kept[2] / l];
        // The information along the constrained directions, in (x, y, θ).
        let mut information = [[0.0f32; 3]; 3];
        let d = [1.0, 1.0, l];
        for k in 0..3 {
            if constraint.constrained[k] {
                let v = constraint.directions[k];
                let floor2 = config.min_sigma_m * config.min_sigma_m;
                let lambda = 1.0 / (1.0 / constraint.eigenvalues[k].max(1e-12) + floor2);
                for (a, row) in information.iter_mut().enumerate() {
                    for (b, cell) in row.iter_mut().enumerate() {
                        *cell += lambda * v[a] * d[a] * v[b] * d[b];
                    }
                }
            }
        }
        MatchResult {
            pose: Pose2::new(
                predicted.x + kept[0],
                predicted.y + kept[1],
                predicted.theta + kept[2] / l,
            ),
            quality,
            information,
        }
    }
}
