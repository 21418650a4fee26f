//! Scan matching applied to a robot's odometry: every N-th scan is matched at the pose the
//! odometry predicts, and a trusted match moves the map-from-odometry transform so that the
//! odometry pose of that instant maps to the matched pose. Later odometry then carries the
//! correction forward, and the map, the planner and the controller all see the corrected pose.
//!
//! A match is a noisy measurement (a few centimetres and tenths of a degree for one scan with
//! the thesis's 5 % range noise), and the map it is matched to was drawn from earlier matched
//! poses: applied in full, every scan's own noise would be written into the map and the pose
//! would random-walk even with perfect odometry. So the correction is blended with the
//! prediction as a Kalman filter does for independent axes (Thrun, Burgard & Fox,
//! *Probabilistic Robotics*, 2005, §3.2): the prediction's variance grows with the distance and
//! rotation the odometry reports since the last match, the match's is fixed, and the gain
//! `K = P / (P + R)` decides how much of the correction is kept. A robot standing still keeps
//! its pose; one that has driven far takes most of the correction.
//!
//! A scan is matched only after a minimum travel or turn since the last match, as gmapping
//! (`linearUpdate`, `angularUpdate`) and slam_toolbox (`minimum_travel_distance`,
//! `minimum_travel_heading`) do: every match injects its own error, and over a short motion the
//! odometry is more precise than a match. With exact odometry in the house (seeds 25-34) this
//! brought the final error from a median of 1.97 m to 0.36 m; it is still not centimetres
//! (docs/experiments.md).

use crate::control::odometry::MapFromOdom;
use crate::geometry::{Pose2, normalize_angle};
use crate::grid::OccupancyGrid;
use crate::math;
use crate::sensor::{LaserConfig, Scan};

use super::{HitMap, MatchConfig, MatchQuality, ScanMatcher, WINDOW_CELLS};

/// When and how a mission matches its scans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalizeConfig {
    /// Match scans at all (off: the map is drawn at the odometry pose).
    pub enabled: bool,
    /// Match every this many scans (1: every scan).
    pub every_n_scans: u32,
    /// The matcher's settings.
    pub matcher: MatchConfig,
    /// Variance the odometry adds to the position per metre driven \[m²/m\].
    pub odometry_var_m2_per_m: f32,
    /// Variance the odometry adds to the heading per radian turned \[rad²/rad\].
    pub odometry_var_rad2_per_rad: f32,
    /// Variance the odometry adds to the heading per metre driven \[rad²/m\].
    pub odometry_var_rad2_per_m: f32,
    /// Standard deviation of one match's position \[m\].
    pub match_sigma_m: f32,
    /// Standard deviation of one match's heading \[rad\].
    pub match_sigma_rad: f32,
    /// A scan is matched only once the odometry has moved this far \[m\] ...
    pub min_travel_m: f32,
    /// ... or turned this much \[rad\] since the last match (0 and 0: every scan).
    pub min_turn_rad: f32,
    /// Keyframes in a pose graph with loop closure ([`super::graph`]; off by default).
    pub graph: super::graph::GraphConfig,
}

impl Default for LocalizeConfig {
    /// Off; when on, the default matcher, once the odometry has moved 0.5 m or turned 0.5 rad
    /// since the last match (slam_toolbox's `minimum_travel_distance` and
    /// `minimum_travel_heading` defaults); odometry variances of (2 cm)² per metre, (1.1°)² per
    /// radian and (0.6°)² per metre; matches of σ 5 cm and 1.15° (about the spread of one
    /// match measured open loop in a house mission, `examples/localize_open.rs` in the
    /// simulator, docs/experiments.md).
    fn default() -> Self {
        Self {
            enabled: false,
            every_n_scans: 1,
            matcher: MatchConfig::default(),
            odometry_var_m2_per_m: 4e-4,
            odometry_var_rad2_per_rad: 4e-4,
            odometry_var_rad2_per_m: 1e-4,
            match_sigma_m: 0.05,
            match_sigma_rad: 0.02,
            min_travel_m: 0.5,
            min_turn_rad: 0.5,
            graph: super::graph::GraphConfig::default(),
        }
    }
}

/// A robot's localisation state and counters (the matcher's working memory is borrowed per
/// scan, so robots that take turns share one).
pub struct Tracker {
    scans: u32,
    matches: u32,
    trusted: u32,
    last: Option<MatchQuality>,
    /// Odometry pose at the last call, for the motion since.
    last_odom: Option<Pose2>,
    /// Odometry pose at the last match.
    matched_odom: Option<Pose2>,
    /// Variance of the predicted position \[m²\] and heading \[rad²\].
    var_m2: f32,
    var_rad2: f32,
}

impl core::fmt::Debug for Tracker {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Tracker")
            .field("scans", &self.scans)
            .field("matches", &self.matches)
            .field("trusted", &self.trusted)
            .field("last", &self.last)
            .finish_non_exhaustive()
    }
}

impl Default for Tracker {
    fn default() -> Self {
        Self::new()
    }
}

impl Tracker {
    /// A tracker that has seen no scan.
    pub const fn new() -> Self {
        Self {
            scans: 0,
            matches: 0,
            trusted: 0,
            last: None,
            last_odom: None,
            matched_odom: None,
            var_m2: 0.0,
            var_rad2: 0.0,
        }
    }

    /// Matches `scan` (taken at odometry pose `pose_odom`) against `grid` with `matcher` when
    /// `config` says so, and corrects `map_from_odom`. Returns the corrected map pose when a match was
    /// trusted, `None` otherwise (the transform is then unchanged).
    #[allow(clippy::too_many_arguments)]
    pub fn on_scan<const N: usize>(
        &mut self,
        config: &LocalizeConfig,
        grid: &OccupancyGrid<N>,
        hits: &HitMap<N>,
        matcher: &mut ScanMatcher<WINDOW_CELLS>,
        scan: &Scan,
        laser: &LaserConfig,
        pose_odom: Pose2,
        map_from_odom: &mut MapFromOdom,
    ) -> Option<Pose2> {
        if !config.enabled {
            return None;
        }
        if let Some(prev) = self.last_odom {
            let d = prev.position().distance(pose_odom.position());
            let turn = math::abs(normalize_angle(pose_odom.theta - prev.theta));
            self.var_m2 += config.odometry_var_m2_per_m * d;
            self.var_rad2 +=
                config.odometry_var_rad2_per_rad * turn + config.odometry_var_rad2_per_m * d;
        }
        self.last_odom = Some(pose_odom);
        self.scans += 1;
        if !(self.scans - 1).is_multiple_of(config.every_n_scans.max(1)) {
            return None;
        }
        // Like gmapping's linearUpdate/angularUpdate and slam_toolbox's
        // minimum_travel_distance/minimum_travel_heading: between matches the odometry alone
        // carries the pose.
        if let Some(at) = self.matched_odom
            && at.position().distance(pose_odom.position()) < config.min_travel_m
            && math::abs(normalize_angle(pose_odom.theta - at.theta)) < config.min_turn_rad
        {
            return None;
        }
        self.matched_odom = Some(pose_odom);
        let predicted = map_from_odom.map_pose(pose_odom);
        let result = matcher.match_scan(grid, hits, scan, laser, predicted, &config.matcher);
        self.matches += 1;
        self.last = Some(result.quality);
        if !result.quality.trusted() {
            return None;
        }
        self.trusted += 1;
        let r_m2 = config.match_sigma_m * config.match_sigma_m;
        let r_rad2 = config.match_sigma_rad * config.match_sigma_rad;
        let k_m = self.var_m2 / (self.var_m2 + r_m2).max(f32::MIN_POSITIVE);
        let k_rad = self.var_rad2 / (self.var_rad2 + r_rad2).max(f32::MIN_POSITIVE);
        let c = result.quality.correction;
        let pose = Pose2::new(
            predicted.x + k_m * c[0],
            predicted.y + k_m * c[1],
            predicted.theta + k_rad * c[2],
        );
        // The heading is pinned down by any match that constrains two directions; the position
        // only by a full fix (a corridor leaves it uncertain along its axis).
        self.var_rad2 *= 1.0 - k_rad;
        if result.quality.constrained == 3 {
            self.var_m2 *= 1.0 - k_m;
        }
        *map_from_odom = MapFromOdom::from_start(pose, pose_odom);
        Some(pose)
    }

    /// [`Self::on_scan`] for a mission: matches once the odometry frame is set
    /// (`map_from_odom` is `Some`), and on a trusted match moves `pose_map` to the corrected
    /// pose.
    #[allow(clippy::too_many_arguments)]
    pub fn correct<const N: usize>(
        &mut self,
        config: &LocalizeConfig,
        grid: &OccupancyGrid<N>,
        hits: &HitMap<N>,
        matcher: &mut ScanMatcher<WINDOW_CELLS>,
        scan: &Scan,
        laser: &LaserConfig,
        pose_odom: Pose2,
        map_from_odom: &mut Option<MapFromOdom>,
        pose_map: &mut Pose2,
    ) {
        if let Some(transform) = map_from_odom.as_mut()
            && let Some(corrected) = self.on_scan(
                config, grid, hits, matcher, scan, laser, pose_odom, transform,
            )
        {
            *pose_map = corrected;
        }
    }

    /// Scans matched so far.
    pub fn matches(&self) -> u32 {
        self.matches
    }

    /// Matches trusted (at least partly applied) so far.
    pub fn trusted(&self) -> u32 {
        self.trusted
    }

    /// The last match's quality.
    pub fn last(&self) -> Option<&MatchQuality> {
        self.last.as_ref()
    }
}
