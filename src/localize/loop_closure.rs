//! Loop closure by scan-to-local-map matching: when the robot comes back within a few metres
//! of a keyframe taken many metres of path ago, the current keyframe's scan is matched against
//! a small map drawn from that old keyframe and its neighbours along the path only (not from
//! the scans since, which carry the drift to be measured), with a wider search window than
//! the tracker's. A confident match that constrains all three directions gives the relative
//! pose between the old keyframe and the current one: a loop-closure edge of the pose graph.
//!
//! This is Karto's / slam_toolbox's loop search (Konolige et al., *Efficient sparse pose
//! adjustment for 2D mapping*, IROS 2010, §V: "scan matching against a local map made of the
//! scans near the candidate node"; Macenski & Jambrecic, JOSS 2021, `loop_search_maximum_distance`
//! and `loop_match_minimum_response_fine`), with the matcher of [`super`] in place of theirs:
//! Olson's correlative search over the whole window (*Real-time correlative scan matching*,
//! ICRA 2009), always run for a closure, then the point-to-line refinement ([`super::ndt`]).
//! A closure is accepted only when the point-to-line fit itself vouches for it:
//! - the matcher's own refusals (too few returns, mostly unknown, poor fit);
//! - all three directions constrained by the fit's information matrix (each pinned to 10 cm
//!   or better and at least 1 % of the strongest, the information its map's uncertain
//!   normals could fake taken off: [`super::constraint`]), not only two (a corridor);
//! - an inlier test at the matched pose: at least [`ClosureConfig::min_score`] of the returns
//!   on known ground lie on a surface of the local map within the fit's gate (4 σ of their
//!   range noise and the surface's thickness; [`MatchQuality::score`]);
//! - at least [`ClosureConfig::min_known_fraction`] of the returns on ground the local map
//!   knows;
//! - no second basin: the refinement started again from the prediction must not end elsewhere
//!   pairing about as many returns ([`ClosureConfig::ambiguity`], Olson's "local uniqueness");
//! - and when it ends elsewhere pairing fewer, the match must not put more of its beams
//!   through the local map's walls than that pose does ([`ClosureConfig::see_through`], the
//!   free space a beam crossed as evidence, as in a beam model);
//! - and, in [`super::graph`], consistency with the graph's prediction over the path between
//!   the two keyframes ([`ClosureConfig::gate_sigmas`]).
//!
//! (On the sixth matcher these checks let through closures up to 0.84 m off until the returns
//! layer's `clear` also forgot the per-cell statistics the point-to-line fit reads: each local
//! map kept the surfaces of the attempts before it, drawn on another lattice.
//! `closure_tests.rs` probes 112 drifted returns to a furnished room.)
//!
//! The local map is a fixed grid of `L` cells (occupancy for "known", returns for the field)
//! around the current pose. No allocation.

use crate::geometry::{Point2, Pose2};
use crate::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use crate::sensor::{LaserConfig, Scan, SensorModel, integrate_scan};

use super::keyframes::KeyframeStore;
use super::{HitMap, MatchConfig, MatchQuality, ScanMatcher, WINDOW_CELLS};

/// Side of the local map \[cells\]: 16 m at 10 cm, the matcher's window (a 4 m laser, the
/// search margins) with room to spare.
pub const LOCAL_SIDE: usize = 160;
/// Cells of the local map.
pub const LOCAL_CELLS: usize = LOCAL_SIDE * LOCAL_SIDE;

/// When and how a loop closure is looked for and accepted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosureConfig {
    /// Only keyframes at least this much path older than the current one are candidates \[m\].
    pub min_path_m: f32,
    /// ... and only those within this distance of the current pose \[m\].
    pub max_distance_m: f32,
    /// Keyframes drawn into the local map on each side of the candidate (along the path).
    pub neighbours: usize,
    /// Translation searched each way \[m\].
    pub search_xy_m: f32,
    /// Rotation searched each way \[rad\].
    pub search_theta_rad: f32,
    /// Fraction of the returns on known ground that the point-to-line fit pairs with a surface
    /// within its gate at the matched pose ([`MatchQuality::score`]) below this: refused.
    pub min_score: f32,
    /// Fraction of the returns on ground the local map knows below this: refused.
    pub min_known_fraction: f32,
    /// Standard deviation given to an accepted closure's position \[m\] ...
    pub sigma_m: f32,
    /// ... and heading \[rad\].
    pub sigma_rad: f32,
    /// A match is refused when it differs from the pose the graph predicts by more than this
    /// many standard deviations of the closure and of the path between the two keyframes
    /// (the squared Mahalanobis distance over the three axes under the steps' covariance
    /// compounded along the path, [`super::path_uncertainty`], plus the closure's; 0: no
    /// test), a consistency check as Olson's, *Recognizing
    /// places using spectrally clustered local matches*, RAS 2009, rejects matches that
    /// disagree with the odometry of the loop.
    pub gate_sigmas: f32,
    /// After the optimisation, a closure whose residual exceeds this many of its standard
    /// deviations (on the three axes together) is taken out again (0: kept).
    pub residual_sigmas: f32,
    /// Ambiguity test ([`LocalMap::close`]): the refinement is started again from the
    /// prediction; when it ends more than [`Self::ambiguity_distance_m`] from the match pairing
    /// at least [`Self::ambiguity_ratio`] of its inliers, the closure is refused (off: no test).
    pub ambiguity: bool,
    /// See [`Self::ambiguity`] \[m, with rotation as [`MatchConfig::length_scale_m`] times the
    /// angle\].
    pub ambiguity_distance_m: f32,
    /// See [`Self::ambiguity`].
    pub ambiguity_ratio: f32,
    /// Free-space test between two basins: when the refinement from the prediction ends more
    /// than [`Self::ambiguity_distance_m`] from the match (pairing fewer returns than the
    /// ambiguity test refuses), the match is refused if more of its beams pass through a
    /// wall of the local map before their returns than at the pose that refinement ends at,
    /// by more than [`Self::see_through_slack`] of the returns
    /// ([`super::free_space::crosses_more_walls`]; off: no test).
    pub see_through: bool,
    /// See [`Self::see_through`]: a beam counts when it crosses an Occupied cell more than
    /// this many cells before its return \[cells\].
    pub see_through_margin_cells: f32,
    /// See [`Self::see_through`] (a fraction of the returns).
    pub see_through_slack: f32,
}

impl Default for ClosureConfig {
    /// Candidates 10 m of path older and within 2.5 m; ±20 keyframes drawn; search ±0.5 m and
    /// ±0.2 rad; accepted when the fit constrains all three directions, pairs half the returns
    /// on known ground with a surface, 70 % of the returns are on known ground, and the match
    /// is within 3 σ of the graph's prediction, unless the refinement from the prediction ends
    /// more than 10 cm away pairing 90 % as many returns (ambiguous), or ends there with the
    /// match putting more than 2 % more of its beams through a wall of the local map than
    /// that pose does (counted from 1.5 cells before the return); as σ 2 cm and 0.57° (the
    /// sixth matcher's closures are within 2 cm and 0.6° of the true relative pose but for a
    /// few; σ 5 cm and
    /// 1.15°, about the fourth matcher's spread, let the worst of 20 house missions end 47 cm
    /// off against 11.8 cm: docs/experiments.md, tenth measurement).
    fn default() -> Self {
        Self {
            min_path_m: 10.0,
            max_distance_m: 2.5,
            neighbours: 20,
            search_xy_m: 0.5,
            search_theta_rad: 0.2,
            min_score: 0.5,
            min_known_fraction: 0.7,
            sigma_m: 0.02,
            sigma_rad: 0.01,
            gate_sigmas: 3.0,
            residual_sigmas: 0.0,
            ambiguity: true,
            ambiguity_distance_m: 0.1,
            ambiguity_ratio: 0.9,
            see_through: true,
            see_through_margin_cells: super::free_space::MARGIN_CELLS,
            see_through_slack: super::free_space::SLACK,
        }
    }
}

/// Why a closure was not made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refusal {
    /// The matcher did not trust the match (its reason).
    Distrusted(super::Distrust),
    /// Fewer than three directions constrained.
    Unconstrained(u8),
    /// Inlier fraction below [`ClosureConfig::min_score`].
    LowScore(f32),
    /// Known fraction below [`ClosureConfig::min_known_fraction`].
    LittleKnown(f32),
    /// The local map's geometry could not be built.
    NoMap,
    /// The match disagrees with the graph by more than the path between the two keyframes
    /// can have drifted ([`ClosureConfig::gate_sigmas`]); the squared normalised distance.
    Inconsistent(f32),
    /// Another pose more than [`ClosureConfig::ambiguity_distance_m`] away pairs about as many
    /// returns ([`ClosureConfig::ambiguity_ratio`]); that pose's fraction of the match's inliers.
    Ambiguous(f32),
    /// Another pose more than [`ClosureConfig::ambiguity_distance_m`] away leaves fewer of
    /// the beams passing through walls ([`ClosureConfig::see_through`]); the match's share.
    SeesThrough(f32),
}

/// Another basin a closure's scan fits ([`LocalMap::rival`]).
#[derive(Clone, Copy, Debug)]
struct Rival {
    /// Where the refinement from the prediction ended.
    pose: Pose2,
    /// Its inliers as a share of the match's.
    ratio: f32,
}

/// The candidate for a closure: the keyframe nearest `pose` among those at least
/// `config.min_path_m` of path before `path_m` and within `config.max_distance_m`.
pub fn candidate<const K: usize>(
    store: &KeyframeStore<K>,
    pose_of: impl Fn(usize) -> Option<Pose2>,
    pose: Pose2,
    path_m: f32,
    config: &ClosureConfig,
) -> Option<usize> {
    let mut best: Option<(usize, f32)> = None;
    for i in 0..store.len() {
        let Some(k) = store.get(i) else { break };
        if k.path_m > path_m - config.min_path_m {
            break;
        }
        let Some(p) = pose_of(i) else { break };
        let d = p.position().distance(pose.position());
        if d <= config.max_distance_m && best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// The local map a closure is matched against, and a scan buffer.
#[derive(bytemuck::Zeroable)]
pub struct LocalMap<const L: usize> {
    grid: OccupancyGrid<L>,
    hits: HitMap<L>,
}

impl<const L: usize> core::fmt::Debug for LocalMap<L> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("LocalMap")
            .field("grid", &self.grid)
            .finish_non_exhaustive()
    }
}

impl<const L: usize> LocalMap<L> {
    /// Draws keyframes `from..to` of `store` at their poses (`pose_of`) into a square map of
    /// `L` cells at `resolution_m` centred on `centre`. Errors when the geometry does not fit.
    #[allow(clippy::too_many_arguments)]
    pub fn render<const K: usize>(
        &mut self,
        store: &KeyframeStore<K>,
        pose_of: impl Fn(usize) -> Option<Pose2>,
        range: core::ops::Range<usize>,
        centre: Point2,
        resolution_m: f32,
        laser: &LaserConfig,
        sensor: &SensorModel,
        bounds: LogOddsBounds,
    ) -> Result<(), Refusal> {
        let side = L.isqrt().max(1);
        let half = side as f32 * resolution_m * 0.5;
        // Cell borders on the same lattice as the mission's grid (multiples of the cell).
        let snap = |v: f32| crate::math::floor(v / resolution_m) * resolution_m;
        let geometry = GridGeometry::new(
            side,
            side,
            resolution_m,
            Point2::new(snap(centre.x - half), snap(centre.y - half)),
        )
        .map_err(|_| Refusal::NoMap)?;
        self.grid
            .set_up_zeroed(geometry, bounds)
            .map_err(|_| Refusal::NoMap)?;
        self.grid.reset(geometry).map_err(|_| Refusal::NoMap)?;
        self.hits.set_up_zeroed(geometry);
        self.hits.clear();
        let mut scan = Scan::new();
        for i in range {
            let (Some(k), Some(pose)) = (store.get(i), pose_of(i)) else {
                continue;
            };
            k.scan_into(laser, &mut scan);
            // A keyframe whose scan cannot be drawn is left out of the local map.
            let _ = integrate_scan(&mut self.grid, &scan, pose, laser, sensor, &mut ());
            self.hits.add_scan(&scan, laser, pose);
        }
        Ok(())
    }

    /// Matches `scan` at about `predicted` against the local map with `tracker`'s settings
    /// widened by `config`; the matched pose when the closure is accepted.
    pub fn close(
        &mut self,
        matcher: &mut ScanMatcher<WINDOW_CELLS>,
        scan: &Scan,
        laser: &LaserConfig,
        predicted: Pose2,
        tracker: &MatchConfig,
        config: &ClosureConfig,
    ) -> (Result<Pose2, Refusal>, MatchQuality) {
        let wide = MatchConfig {
            search_xy_m: config.search_xy_m,
            search_theta_rad: config.search_theta_rad,
            // A closure starts from a drifted prediction: always run the correlative search
            // over the whole window before the refinement (the tracker's match runs it only
            // when the refinement from the prediction pairs too few returns).
            search_below_fit: f32::INFINITY,
            ..*tracker
        };
        let result = matcher.match_scan(&self.grid, &self.hits, scan, laser, predicted, &wide);
        let q = result.quality;
        let verdict = if let Some(why) = q.distrust {
            Err(Refusal::Distrusted(why))
        } else if q.constrained < 3 {
            Err(Refusal::Unconstrained(q.constrained))
        } else if q.score < config.min_score {
            Err(Refusal::LowScore(q.score))
        } else if q.known_fraction < config.min_known_fraction {
            Err(Refusal::LittleKnown(q.known_fraction))
        } else if let Some(why) = self.second_basin(
            &matcher.points[..matcher.len],
            laser,
            predicted,
            result.pose,
            tracker,
            config,
        ) {
            Err(why)
        } else {
            Ok(result.pose)
        };
        (verdict, q)
    }

    /// The tests of a match at `matched` of `points` (robot frame, the returns the match used)
    /// against the basin the prediction lies in ([`Self::rival`]): refused as ambiguous when
    /// that basin pairs about as many returns ([`ClosureConfig::ambiguity`]), or as seeing
    /// through walls when more of the match's beams pass through the local map's walls than
    /// that basin's do ([`ClosureConfig::see_through`]). A wall the old keyframes saw from
    /// both sides has two faces a wall's thickness apart, and a scan of one face fits the
    /// other as well: on the generated floor plans' 0.2 m walls the closures that passed the
    /// ambiguity test with exactly 0.2 m of error (their rival, the true pose, pairing 65-89
    /// % as many returns) all put their beams through the near face (docs/experiments.md,
    /// "Issue 18: closures through a wall").
    pub(super) fn second_basin(
        &self,
        points: &[Point2],
        laser: &LaserConfig,
        predicted: Pose2,
        matched: Pose2,
        tracker: &MatchConfig,
        config: &ClosureConfig,
    ) -> Option<Refusal> {
        if !(config.ambiguity || config.see_through) {
            return None;
        }
        let rival = self.rival(points, laser, predicted, matched, tracker, config)?;
        if config.ambiguity && rival.ratio >= config.ambiguity_ratio {
            return Some(Refusal::Ambiguous(rival.ratio));
        }
        if !config.see_through {
            return None;
        }
        super::free_space::crosses_more_walls(
            &self.grid,
            points,
            laser,
            matched,
            rival.pose,
            config.see_through_margin_cells,
            config.see_through_slack,
        )
        .map(Refusal::SeesThrough)
    }

    /// The second basin of a match at `matched` of `points` (robot frame, the returns the
    /// match used): the refinement ([`super::ndt`]) started again from `predicted`, when it
    /// ends more than [`ClosureConfig::ambiguity_distance_m`] from the refinement at
    /// `matched` (with its share of the match's inliers). The ambiguity test refuses a match
    /// whose rival pairs about as many returns. The
    /// closure's search looks over a window wider than the tracker's; when the basin the
    /// prediction lies in explains the scan about as well as the one the search jumped to, the
    /// scan does not tell the two places apart, however confident each fit is. A place match
    /// must be unique, not only good: Olson (*Recognizing places using spectrally clustered
    /// local matches*, Robotics and Autonomous Systems 57(12), 2009) accepts a match only when
    /// no other hypothesis explains the data nearly as well ("local uniqueness"). Only the
    /// prediction's basin is tried: starts moved ±0.3 m along `x` and `y` as well refused 166
    /// closures in 20 house missions (up to 17 in one), nearly all true ones
    /// (docs/experiments.md, branch `loc18`).
    fn rival(
        &self,
        points: &[Point2],
        laser: &LaserConfig,
        predicted: Pose2,
        matched: Pose2,
        tracker: &MatchConfig,
        config: &ClosureConfig,
    ) -> Option<Rival> {
        let mut fine = tracker.fine;
        fine.noise_fraction = laser.noise_fraction.max(0.0);
        fine.length_scale_m = tracker.length_scale_m;
        let origin = laser.mount.position();
        let best = super::ndt::refine(&self.hits, points, origin, matched, &fine);
        let other = super::ndt::refine(&self.hits, points, origin, predicted, &fine);
        let l = tracker.length_scale_m;
        let dt = crate::geometry::normalize_angle(other.pose.theta - best.pose.theta) * l;
        let d = crate::math::hypot(
            crate::math::hypot(other.pose.x - best.pose.x, other.pose.y - best.pose.y),
            dt,
        );
        let ratio = other.inliers as f32 / best.inliers.max(1) as f32;
        (d > config.ambiguity_distance_m).then_some(Rival {
            pose: other.pose,
            ratio,
        })
    }

    /// The local grid (for tests and pictures).
    pub fn grid(&self) -> &OccupancyGrid<L> {
        &self.grid
    }
}
