//! Scan matching applied to a robot's odometry: scans are matched at the pose the odometry
//! predicts, and a trusted match moves the map-from-odometry transform so that the odometry pose
//! of that instant maps to the corrected pose. Later odometry then carries the correction
//! forward, and the map, the planner and the controller all see the corrected pose.
//!
//! One match of a noisy scan is a noisy measurement: with the thesis's 5 % range noise the
//! information of one scan pins the heading to about half a degree and the position to a few
//! centimetres (Cramér-Rao: a return at range `r` with noise `0.05 r` whose surface it sees at
//! incidence `α` carries `(sin α / 0.05)²` of heading information, whatever `r`;
//! docs/experiments.md, fifth measurement). So matches are fused with the odometry by an
//! extended Kalman filter in information form (Thrun, Burgard & Fox, *Probabilistic Robotics*,
//! 2005, §3.3, §3.5): the prediction's covariance grows with the distance and rotation the
//! odometry reports (propagated through the motion's Jacobian, so a heading error becomes a
//! lateral position error as the robot drives), the match's is the inverse of its fit's
//! information ([`super::MatchResult::information`], inflated by
//! [`LocalizeConfig::information_scale`]), and the update
//! `P⁺ = (P⁻¹ + H)⁻¹, x⁺ = x⁻ + P⁺ H δ` keeps the odometry along directions the scan does not
//! constrain (`H` is zero there) and follows a precise match where it does.
//!
//! A scan may be matched only after a minimum travel or turn since the last match, as gmapping
//! (`linearUpdate`, `angularUpdate`) and slam_toolbox (`minimum_travel_distance`,
//! `minimum_travel_heading`) do (0 and 0, the default: every scan).

use crate::control::odometry::MapFromOdom;
use crate::geometry::{Pose2, normalize_angle};
use crate::grid::OccupancyGrid;
use crate::math;
use crate::sensor::{LaserConfig, Scan};
use nalgebra::{Matrix3, Vector3};

use super::odometry_calibration::OdometryCalibration;
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
    /// The fit's information is multiplied by this before it is fused (below 1: the fit is
    /// trusted less than its residuals say, for the map's own errors).
    pub information_scale: f32,
    /// A scan is matched only once the odometry has moved this far \[m\] ...
    pub min_travel_m: f32,
    /// ... or turned this much \[rad\] since the last match (0 and 0: every scan).
    pub min_turn_rad: f32,
    /// Keyframes in a pose graph with loop closure ([`super::graph`]; off by default).
    pub graph: super::graph::GraphConfig,
    /// A scan whose match was refused because it disagrees with the map at the predicted
    /// pose ([`super::Distrust::PoorFit`]) is not written into the matcher's reference (the
    /// returns layer), so a pose gone wrong does not draw a second copy of the walls that the
    /// next matches would then fit (Hector SLAM and Cartographer insert a scan only at a
    /// pose the matcher found). An experiment, off: measured worse (docs/experiments.md,
    /// seventh measurement).
    pub map_only_agreeing: bool,
    /// The same for the occupancy grid (the safety monitor still sees every scan). An
    /// experiment, off: measured no better.
    pub grid_only_agreeing: bool,
    /// A cell of the matcher's reference takes no more returns once its statistics weigh
    /// this much ([`super::HitMap::add_scan_capped`]; a return with 1 cm of noise weighs 1).
    /// An experiment, off (infinite): measured worse.
    pub max_cell_weight: f32,
    /// A trusted match whose correction lies farther than this squared Mahalanobis
    /// distance from the prediction (under the prediction's covariance) scales that
    /// covariance up until it does not, before the update: a fading-memory filter (Jazwinski,
    /// *Stochastic processes and filtering theory*, 1970, §8.6) for what the odometry model
    /// does not say (the slide at the end of a move is not reported by the wheels).
    /// Negative: such a match is refused instead (a validation gate, Bar-Shalom & Fortmann,
    /// *Tracking and data association*, 1988), its distance taken under the prediction's
    /// covariance plus (3 mm)² in every direction. 0: off. An experiment, off: both measured
    /// worse (docs/experiments.md, seventh measurement); the gate at -100 measured again on
    /// the matcher with its pose graph (2026-12-07: house, realistic odometry, 20 seeds, end
    /// position error median 8.4 → 6.6 cm, largest 202.7 → 25.0 cm; docs/experiments.md,
    /// "the validation gate on the innovation, measured again"), but on the generated plans
    /// with the realistic odometry it lost runs at 99 % (37 → 33; docs/experiments.md,
    /// "closures through a wall, and the innovation gate on the generated set"): still off.
    pub innovation_gate: f32,
    /// Only the scans that were matched (keyframes: the first, then one each
    /// [`Self::min_travel_m`] or [`Self::min_turn_rad`]) are written into the matcher's
    /// reference (the returns layer), at their corrected pose; the scans between them go to
    /// the occupancy grid only. Without it, with a minimum travel, the scans between two
    /// matches are drawn into the reference at the odometry's drifting pose and the next
    /// match fits that drift (as Karto and slam_toolbox do, whose map is built from the
    /// matched scans only: Konolige et al., *Efficient sparse pose adjustment for 2D
    /// mapping*, IROS 2010; Macenski & Jambrecic, JOSS 2021). An experiment, off.
    pub reference_keyframes_only: bool,
    /// With a minimum travel or turn: also match the first scan after the odometry comes to
    /// rest away from the last match (one match a stop, not one a scan while standing), for
    /// what the wheels do not report when a move ends (the robot slides on).
    /// An experiment, off.
    pub match_at_rest: bool,
    /// Position variance \[m²\] and heading variance \[rad²\] added to the prediction when
    /// the odometry comes to rest (the first scan with no odometry motion since the scan
    /// before), along the heading and in heading: the slide at the end of a move that no
    /// wheel reports (the thesis measured 1-2 cm on a P3-DX; `papillon-sim`'s slip models
    /// draw 1.5 cm and 0.5°, 1 σ). Without it the filter takes a robot at rest to be where
    /// the odometry says and refuses most of the first match's correction (unit test: 12 % of the slide's position taken, 49 % with
    /// the term), and the scans of the stop are drawn between the two poses. Default
    /// (1.5 cm)² and (0.5°)², the slide's size: on 20 house seeds with the realistic odometry
    /// it took the median final error from 8.8 to 5.9 cm and the worst from 96 to 31 cm, and
    /// changed nothing with exact odometry (docs/experiments.md, ninth measurement); 0 and 0:
    /// no such term.
    pub stop_var_m2: f32,
    /// Heading variance added when the odometry comes to rest \[rad²\] (see
    /// [`Self::stop_var_m2`]).
    pub stop_var_rad2: f32,
    /// Online estimation of the odometry's systematic errors (turn gain and curvature per
    /// metre, [`super::odometry_calibration`]): each odometry increment is corrected with the
    /// estimate before the prediction. On by default: on the house's 100 seeds with the
    /// realistic odometry, map accuracy at 97 % on 84 against 73 and coverage at 99 % on 95
    /// against 87 (docs/experiments.md, "the self-calibration and the search's free-space test
    /// by default"); off, the prediction is the odometry as reported. While on,
    /// [`Self::innovation_gate`]'s fading memory (> 0) is not applied; its validation gate
    /// (< 0) is.
    pub calibration: super::odometry_calibration::CalibrationConfig,
    /// How far past each return the grid's Occupied evidence reaches, for the pose's own
    /// error ([`crate::sensor::integrate_scan_banded`]; at most half a cell is used): this
    /// floor \[m\] plus [`Self::wall_band_sigmas`] times the tracker's position σ
    /// ([`Tracker::position_sigma_m`]). 0 and 0: each return marks the one cell holding it.
    /// Default 5 cm and 0: the pose the localisation leaves is 2-3 cm off the truth even with
    /// exact odometry (median; the filter's own σ says 6 mm), and with a band of half a cell
    /// the house missions with the matcher and the graph on reach 99 % coverage in 16 of 20
    /// seeds instead of 7 (a band of 3 σ: 13); docs/experiments.md, branch `wall18`. The cost:
    /// an obstacle thinner than a cell is drawn a cell deeper on the side away from the laser
    /// when the band crosses a cell edge. With the localisation off there is no band.
    pub wall_band_floor_m: f32,
    /// See [`Self::wall_band_floor_m`].
    pub wall_band_sigmas: f32,
    /// With the localisation on, a miss through a cell the map holds Occupied with confidence
    /// counts only within this many cells of its centre
    /// ([`crate::sensor::SensorModel::occupied_miss_offset_cells`]: at a centimetre of pose error, beams
    /// passing along a wall's face wear it away). Default a quarter of a cell
    /// ([`crate::sensor::GRAZING_MISS_OFFSET_CELLS`]); `None`: the mission's sensor model as
    /// it is.
    pub grazing_miss_offset_cells: Option<f32>,
}

impl Default for LocalizeConfig {
    /// Off; when on, every scan matched with the default matcher; odometry variances of
    /// (2 cm)² per metre, (1.1°)² per radian and (0.6°)² per metre; the fit's information
    /// taken as it is (halved, the closed-loop heading error was larger where matches were
    /// refused and the odometry's heading pulled: docs/experiments.md, sixth measurement);
    /// every scan mapped, with no cap on a cell's weight (the experiments
    /// `map_only_agreeing`, `grid_only_agreeing` and `max_cell_weight` measured no better:
    /// docs/experiments.md, seventh measurement).
    fn default() -> Self {
        Self {
            enabled: false,
            every_n_scans: 1,
            matcher: MatchConfig::default(),
            odometry_var_m2_per_m: 4e-4,
            odometry_var_rad2_per_rad: 4e-4,
            odometry_var_rad2_per_m: 1e-4,
            information_scale: 1.0,
            min_travel_m: 0.0,
            min_turn_rad: 0.0,
            map_only_agreeing: false,
            grid_only_agreeing: false,
            max_cell_weight: f32::INFINITY,
            innovation_gate: 0.0,
            reference_keyframes_only: false,
            match_at_rest: false,
            stop_var_m2: 0.015 * 0.015,
            stop_var_rad2: 0.5f32.to_radians() * 0.5f32.to_radians(),
            graph: super::graph::GraphConfig::default(),
            calibration: super::odometry_calibration::CalibrationConfig::default(),
            wall_band_floor_m: 0.05,
            wall_band_sigmas: 0.0,
            grazing_miss_offset_cells: Some(crate::sensor::GRAZING_MISS_OFFSET_CELLS),
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
    /// Covariance of the pose estimate (map frame, `x, y, θ`) \[m², m·rad, rad²\].
    cov: Matrix3<f64>,
    /// The last scan's match was refused because the scan disagrees with the map.
    disagrees: bool,
    /// The last scan was matched (a keyframe) or came before the odometry frame was set.
    keyframe: bool,
    /// The odometry moved between the last two scans.
    moving: bool,
    /// The estimate of the odometry's systematic errors ([`LocalizeConfig::calibration`]).
    calibration: OdometryCalibration,
    /// The last trusted match's information as fused, `(x, y, θ)` (zero before one).
    last_information: [[f32; 3]; 3],
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
            cov: Matrix3::new(1e-6, 0.0, 0.0, 0.0, 1e-6, 0.0, 0.0, 0.0, 1e-6),
            disagrees: false,
            keyframe: false,
            moving: false,
            calibration: OdometryCalibration::new(),
            last_information: [[0.0; 3]; 3],
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
        self.disagrees = false;
        self.keyframe = false;
        if !config.enabled {
            return None;
        }
        // The odometry has not moved since the last scan.
        let at_rest = self.last_odom.is_some_and(|p| {
            p.position().distance(pose_odom.position()) < 1e-4
                && math::abs(normalize_angle(pose_odom.theta - p.theta)) < 1e-4
        });
        if let Some(prev) = self.last_odom
            && config.calibration.enabled
        {
            // The increment corrected by the estimate; the pose and the parameters predicted
            // together, with the random part of the odometry's noise.
            let scale = config.calibration.random_scale.max(0.0) as f64;
            let q = odometry_noise(config, prev, pose_odom, scale);
            let to = self.calibration.predict(
                &config.calibration,
                map_from_odom.map_pose(prev),
                pose_odom.in_frame_of(prev),
                &mut self.cov,
                &q,
            );
            *map_from_odom = MapFromOdom::from_start(to, pose_odom);
        } else if let Some(prev) = self.last_odom {
            // The motion in the map frame, and its Jacobian with respect to the heading.
            let from = map_from_odom.map_pose(prev);
            let to = map_from_odom.map_pose(pose_odom);
            let f = Matrix3::new(
                1.0,
                0.0,
                -(to.y - from.y) as f64,
                0.0,
                1.0,
                (to.x - from.x) as f64,
                0.0,
                0.0,
                1.0,
            );
            self.cov = f * self.cov * f.transpose() + odometry_noise(config, prev, pose_odom, 1.0);
        }
        if self.last_odom.is_some() {
            if at_rest && self.moving {
                // The slide is along the robot's heading.
                let th = map_from_odom.map_pose(pose_odom).theta;
                let (c, s) = (math::cos(th) as f64, math::sin(th) as f64);
                let v = config.stop_var_m2 as f64;
                self.cov += Matrix3::new(
                    v * c * c,
                    v * c * s,
                    0.0,
                    v * c * s,
                    v * s * s,
                    0.0,
                    0.0,
                    0.0,
                    config.stop_var_rad2 as f64,
                );
            }
            self.moving = !at_rest;
        }
        self.last_odom = Some(pose_odom);
        self.scans += 1;
        if !(self.scans - 1).is_multiple_of(config.every_n_scans.max(1)) {
            return None;
        }
        // Like gmapping's linearUpdate/angularUpdate and slam_toolbox's
        // minimum_travel_distance/minimum_travel_heading: between matches the odometry alone
        // carries the pose.
        if let Some(at) = self.matched_odom {
            let moved = at.position().distance(pose_odom.position());
            let turned = math::abs(normalize_angle(pose_odom.theta - at.theta));
            let stopped_elsewhere =
                config.match_at_rest && at_rest && (moved > 1e-4 || turned > 1e-4);
            if moved < config.min_travel_m && turned < config.min_turn_rad && !stopped_elsewhere {
                return None;
            }
        }
        self.matched_odom = Some(pose_odom);
        self.keyframe = true;
        let predicted = map_from_odom.map_pose(pose_odom);
        let result = matcher.match_scan(grid, hits, scan, laser, predicted, &config.matcher);
        self.matches += 1;
        self.last = Some(result.quality);
        self.disagrees = result.quality.distrust == Some(super::Distrust::PoorFit);
        if !result.quality.trusted() {
            return None;
        }
        self.trusted += 1;
        // Information-form update with the match's information along what it constrains.
        let scale = config.information_scale.max(0.0) as f64;
        let h = Matrix3::from_fn(|a, b| result.information[a][b] as f64 * scale);
        self.last_information =
            core::array::from_fn(|a| core::array::from_fn(|b| h[(a, b)] as f32));
        let c = result.quality.correction;
        let delta = Vector3::new(c[0] as f64, c[1] as f64, c[2] as f64);
        let mut prior_info = self.cov.try_inverse()?;
        let gate = config.innovation_gate as f64;
        if gate < 0.0 {
            let slack = self.cov + Matrix3::from_diagonal_element(9e-6);
            let d2 = slack
                .try_inverse()
                .map_or(f64::INFINITY, |i| delta.dot(&(i * delta)));
            if d2.is_nan() || d2 > -gate {
                self.trusted -= 1;
                return None;
            }
        }
        let step = if config.calibration.enabled {
            self.calibration.update(&mut self.cov, &h, &delta)?
        } else {
            if gate > 0.0 {
                let d2 = delta.dot(&(prior_info * delta));
                if d2.is_finite() && d2 > gate {
                    self.cov *= d2 / gate;
                    prior_info /= d2 / gate;
                }
            }
            let cov = (prior_info + h).try_inverse()?;
            let step = cov * h * delta;
            if !step.iter().all(|v| v.is_finite()) {
                return None;
            }
            self.cov = 0.5 * (cov + cov.transpose());
            step
        };
        let pose = Pose2::new(
            predicted.x + step[0] as f32,
            predicted.y + step[1] as f32,
            normalize_angle(predicted.theta + step[2] as f32),
        );
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
        // Before the odometry frame is set the scan is drawn at the start pose: a keyframe.
        self.keyframe = map_from_odom.is_none();
        if let Some(transform) = map_from_odom.as_mut() {
            if let Some(corrected) = self.on_scan(
                config, grid, hits, matcher, scan, laser, pose_odom, transform,
            ) {
                *pose_map = corrected;
            } else if config.enabled && config.calibration.enabled {
                // The prediction from the corrected increment moved the transform.
                *pose_map = transform.map_pose(pose_odom);
            }
        }
    }

    /// The estimate of the odometry's systematic errors ([`LocalizeConfig::calibration`];
    /// turn gain 1 and curvature 0 until calibrating starts).
    pub fn calibration(&self) -> &OdometryCalibration {
        &self.calibration
    }

    /// Whether the last scan may be written into the matcher's reference
    /// ([`LocalizeConfig::map_only_agreeing`]
    /// and [`LocalizeConfig::reference_keyframes_only`]).
    pub fn maps_scan(&self, config: &LocalizeConfig) -> bool {
        !(config.map_only_agreeing && self.disagrees)
            && (self.keyframe || !config.reference_keyframes_only)
    }

    /// Whether the last scan was matched (or came before the odometry frame was set).
    pub fn keyframe(&self) -> bool {
        self.keyframe
    }

    /// Whether the last scan may be written into the occupancy grid
    /// ([`LocalizeConfig::grid_only_agreeing`]).
    pub fn grids_scan(&self, config: &LocalizeConfig) -> bool {
        !(config.grid_only_agreeing && self.disagrees)
    }

    /// The covariance of the pose estimate, map frame `(x, y, θ)` \[m², m·rad, rad²\] (the
    /// filter's own figure, not the true error).
    pub fn covariance(&self) -> [[f32; 3]; 3] {
        core::array::from_fn(|a| core::array::from_fn(|b| self.cov[(a, b)] as f32))
    }

    /// The last trusted match's information as it was fused, `(x, y, θ)` \[1/m², 1/(m·rad),
    /// 1/rad²\] (zero before the first; for diagnostics).
    pub fn last_information(&self) -> [[f32; 3]; 3] {
        self.last_information
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

    /// The band past each return that the grid's Occupied evidence reaches under `config`
    /// \[m\] ([`LocalizeConfig::wall_band_floor_m`]; 0 with the localisation off).
    pub fn wall_band_m(&self, config: &LocalizeConfig) -> f32 {
        if !config.enabled {
            return 0.0;
        }
        let band = config.wall_band_floor_m + config.wall_band_sigmas * self.position_sigma_m();
        if band.is_finite() { band.max(0.0) } else { 0.0 }
    }

    /// The standard deviation \[m\] of the position estimate along its least certain
    /// direction: the square root of the larger eigenvalue of the covariance's `x, y` block
    /// (0 before the first odometry reading; the filter's own figure, not the true error).
    pub fn position_sigma_m(&self) -> f32 {
        let (a, b, c) = (
            self.cov[(0, 0)] as f32,
            self.cov[(0, 1)] as f32,
            self.cov[(1, 1)] as f32,
        );
        let largest = 0.5 * (a + c) + math::sqrt(0.25 * (a - c) * (a - c) + b * b);
        if largest.is_finite() && largest > 0.0 {
            math::sqrt(largest)
        } else {
            0.0
        }
    }
}

/// The odometry's noise over its step from `prev` to `now` (odometry frame), as a covariance in
/// `(x, y, θ)`: the model's variances per metre driven and per radian turned
/// ([`LocalizeConfig::odometry_var_m2_per_m`] and the two heading terms), times `scale`.
fn odometry_noise(config: &LocalizeConfig, prev: Pose2, now: Pose2, scale: f64) -> Matrix3<f64> {
    let d = prev.position().distance(now.position()) as f64;
    let turn = math::abs(normalize_angle(now.theta - prev.theta)) as f64;
    let q_m2 = config.odometry_var_m2_per_m as f64 * d * scale;
    let q_rad2 = (config.odometry_var_rad2_per_rad as f64 * turn
        + config.odometry_var_rad2_per_m as f64 * d)
        * scale;
    Matrix3::from_diagonal(&Vector3::new(q_m2, q_m2, q_rad2))
}
