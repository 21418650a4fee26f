//! What a run is made of ([`RunConfig`]), why it cannot start ([`RunError`]), and the seeds of
//! its random streams ([`derive_seed`]).

use std::fmt;

use papillon::geometry::Pose2;
use papillon::mission::{MissionConfig, MissionError};

use super::{MAP_CAPACITY, MAX_ROBOTS};
use crate::physics::{BodyConfig, SlipConfig};

/// A seed for stream `stream` of robot `robot`, derived from the run's seed (SplitMix64's
/// finaliser over the three, Steele, Lea & Flood 2014), so that streams do not overlap.
pub fn derive_seed(seed: u64, robot: usize, stream: u64) -> u64 {
    let mut z =
        seed.wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(1 + robot as u64 * 8 + stream));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

pub(super) const STREAM_BODY: u64 = 1;
pub(super) const STREAM_LASER: u64 = 2;
pub(super) const STREAM_DECIDE: u64 = 3;

/// Settings of one run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// The missions' configuration (the same for every robot); its laser is also the
    /// simulated laser.
    pub mission: MissionConfig,
    /// Number of robots (1..=[`MAX_ROBOTS`]).
    pub robots: usize,
    /// The run's seed.
    pub seed: u64,
    /// The simulated robots' body.
    pub body: BodyConfig,
    /// Start poses, one per robot; `None`: robot 0 at the world's start, the others placed
    /// next to it ([`crate::placement::start_poses`]).
    pub starts: Option<Vec<Pose2>>,
    /// Simulated-time limit \[s\].
    pub max_sim_time_s: f64,
    /// How the missions are pumped: as the runner always did, or as `papillon run` does.
    pub pump: PumpModel,
    /// The simulated laser's range noise that does not grow with the range, standard
    /// deviation \[m\] ([`crate::laser::LaserSim::with_range_sigma_m`]; the mission's laser
    /// configuration knows only its fraction of the range). 0: none.
    pub laser_range_sigma_m: f32,
}

/// What the mission sees of time and of the world beyond its sensors: the runner's ideal
/// pump ([`PumpModel::ideal`], the default) or the onboard binary's ([`PumpModel::onboard`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PumpModel {
    /// The mission is told the coverage of the world's truth and ends at its target
    /// (`CoverageReached`). `papillon run` cannot know it: its mission ends when no reachable
    /// frontier is left, or on the battery.
    pub coverage_known: bool,
    /// Simulated time a decision takes \[s\]: the robot stands (stopped, its mission not
    /// stepped) while the scans go on into the map, as while `papillon run`'s mission thread
    /// decides. 0: decisions take no simulated time.
    pub decision_latency_s: f64,
    /// End the run, as `papillon run` ends its mission, when [`STALL_DECISIONS`] decisions
    /// in a row added fewer than [`STALL_NEW_CELLS`] known cells to the map while the robot
    /// spent at least [`STALL_STEPS`] on them, or when [`STALL_IDLE_DECISIONS`] decisions in
    /// a row added fewer than [`STALL_NEW_CELLS`] however little it drove
    /// (`papillon::onboard::mission::Stall`: what is left Unknown next to Free cells cannot
    /// be seen).
    pub nothing_observable_end: bool,
    /// Above this turn rate a scan only feeds the safety monitor, it is not mapped
    /// (`papillon run` maps no scan between two status packets whose headings differ by more
    /// than 2°: its scans are timed by their arrival) \[deg/s\]. `None`: every scan is mapped.
    pub unmapped_turn_deg_s: Option<f32>,
    /// Robot `k`'s decisions draw from a generator seeded with the run's seed plus `k`, as
    /// `papillon run` seeds its own with the board's `mission.seed` (instead of a stream
    /// derived from the run's seed, [`derive_seed`]): on the same seed the runner's optimizer
    /// then draws what the binary's draws.
    pub board_seeded_decisions: bool,
    /// Which draw of the world's randomness (laser range noise, wheel slip) the run makes:
    /// 0 is the run's seed's own streams, `k > 0` other streams of the same seed, the
    /// decisions unchanged. `papillon run` meets one draw of its simulator's (or its
    /// building's) noise; the runner's prediction of it is the median over several draws
    /// (`tests/onboard_compare.rs`), not one arbitrary draw.
    pub noise_draw: u64,
    /// How far the simulated laser's beams reach \[m\], when more than the mission's usable
    /// range (`laser.max_range_m`): a reading beyond the usable range is no return, as
    /// `papillon run` treats the readings of `papillon-sim serve`'s LMS1xx (20 m,
    /// [`crate::emulator::lms1xx::MAX_RANGE_M`]) or of a real one. With range noise, a
    /// surface just beyond the usable range then reads within it now and then (occupied
    /// evidence in front of it), which a laser cast only to the usable range never shows.
    /// `None`: the beams end at the usable range (the runner's own laser).
    pub laser_reach_m: Option<f32>,
}

/// See [`PumpModel::nothing_observable_end`] (the same values as `papillon run`'s).
pub const STALL_DECISIONS: usize = 5;
/// See [`PumpModel::nothing_observable_end`].
pub const STALL_NEW_CELLS: usize = 100;
/// See [`PumpModel::nothing_observable_end`] \[steps\].
pub const STALL_STEPS: f32 = 15.0;
/// See [`PumpModel::nothing_observable_end`].
pub const STALL_IDLE_DECISIONS: usize = 50;

impl PumpModel {
    /// The runner's pump: the coverage is known, decisions take no simulated time.
    pub const fn ideal() -> Self {
        Self {
            coverage_known: true,
            decision_latency_s: 0.0,
            nothing_observable_end: false,
            unmapped_turn_deg_s: None,
            board_seeded_decisions: false,
            noise_draw: 0,
            laser_reach_m: None,
        }
    }

    /// `papillon run`'s pump: no coverage from the truth, a decision takes
    /// `decision_latency_s` (what its `decision` telemetry's `compute_ms` says), no scan is
    /// mapped while the robot turns faster than 20 deg/s, the run ends when decisions stop
    /// adding to the map, decisions draw from the board's seed, and the laser reaches as far
    /// as `serve`'s LMS1xx (its readings kept up to the usable range).
    pub const fn onboard(decision_latency_s: f64) -> Self {
        Self {
            coverage_known: false,
            decision_latency_s,
            nothing_observable_end: true,
            unmapped_turn_deg_s: Some(20.0),
            board_seeded_decisions: true,
            noise_draw: 0,
            laser_reach_m: Some(crate::emulator::lms1xx::MAX_RANGE_M),
        }
    }
}

impl Default for PumpModel {
    fn default() -> Self {
        Self::ideal()
    }
}

impl RunConfig {
    /// A run of `robots` robots with `mission`, seed `seed`, P3-DX bodies with the thesis's
    /// odometry slip ([`SlipConfig::thesis`]: a slide at the end of each move; the full
    /// default slip adds heading random walks that the core, without scan matching, cannot
    /// correct) and a time limit of [`default_time_limit_s`].
    pub fn new(mission: MissionConfig, robots: usize, seed: u64) -> Self {
        let max_sim_time_s = default_time_limit_s(mission.battery_steps);
        Self {
            mission,
            robots,
            seed,
            body: BodyConfig {
                slip: SlipConfig::thesis(),
                ..BodyConfig::default()
            },
            starts: None,
            max_sim_time_s,
            pump: PumpModel::ideal(),
            laser_range_sigma_m: 0.0,
        }
    }
}

/// The default simulated-time limit for a battery of `battery_steps`: 10 s per step (a step
/// takes 2.5 s at the exploration speed of 0.4 m/s) plus 10 minutes.
pub fn default_time_limit_s(battery_steps: f32) -> f64 {
    600.0 + 10.0 * battery_steps.max(0.0) as f64
}

/// Why a run cannot start or could not go on.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum RunError {
    /// Robot count outside 1..=[`MAX_ROBOTS`].
    Robots(usize),
    /// The world has more cells than the runner's map holds.
    MapTooLarge {
        /// Cells of the world.
        cells: usize,
        /// Cells the runner's map holds.
        capacity: usize,
    },
    /// A start pose puts the robot in or against an obstacle, or outside the world.
    StartBlocked {
        /// Which robot.
        robot: usize,
        /// The pose.
        pose: Pose2,
    },
    /// Fewer start poses than robots were given, or no free place was found for a robot.
    NoStart {
        /// Which robot.
        robot: usize,
    },
    /// The core mission refused its configuration or input.
    Mission(MissionError),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Robots(n) => write!(f, "robots must be 1 to {MAX_ROBOTS}, got {n}"),
            RunError::MapTooLarge { cells, capacity } if *capacity < MAP_CAPACITY => write!(
                f,
                "the world has {cells} cells, more than the {capacity} this runner's map holds (a runner sized to the map holds up to {MAP_CAPACITY})"
            ),
            RunError::MapTooLarge { cells, .. } => write!(
                f,
                "the world has {cells} cells, more than the {MAP_CAPACITY} the simulator's largest map holds (use a coarser resolution or a smaller world)"
            ),
            RunError::StartBlocked { robot, pose } => write!(
                f,
                "start of robot {robot} at ({:.2} m, {:.2} m) is inside or against an obstacle or outside the map",
                pose.x, pose.y
            ),
            RunError::NoStart { robot } => {
                write!(f, "no free start pose for robot {robot} near the start")
            }
            RunError::Mission(e) => write!(f, "mission: {e:?}"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<MissionError> for RunError {
    fn from(e: MissionError) -> Self {
        RunError::Mission(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_differ_per_robot_and_stream() {
        let a = derive_seed(25, 0, STREAM_BODY);
        assert_ne!(a, derive_seed(25, 1, STREAM_BODY));
        assert_ne!(a, derive_seed(25, 0, STREAM_LASER));
        assert_ne!(a, derive_seed(26, 0, STREAM_BODY));
        assert_eq!(a, derive_seed(25, 0, STREAM_BODY));
    }
}
