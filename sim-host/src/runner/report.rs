//! What a run reports: how it ended ([`EndReason`]), per robot ([`RobotReport`]) and in all
//! ([`RunReport`]).

use std::fmt;

use papillon::geometry::{Point2, Pose2};
use papillon::mission::{DoneReason, MissionEvent};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndReason {
    /// The coverage target was reached.
    CoverageReached,
    /// Every mission ran out of energy (or the last one to finish did).
    BatteryExhausted,
    /// Nothing reachable was left unknown (for the last mission to finish).
    NothingReachable,
    /// The robot could not get on with frontier still reachable on its map
    /// ([`DoneReason::Stuck`]).
    Stuck,
    /// The simulated-time limit was hit with missions still running.
    TimeLimit,
    /// Decisions stopped adding to the map ([`super::PumpModel::nothing_observable_end`],
    /// `papillon run`'s end of an explored building).
    NothingObservable,
    /// The battery voltage stayed low (a mission fed voltages; the runner feeds none).
    VoltageLow,
}

impl EndReason {
    /// Name in reports: `coverage-reached`, `battery-exhausted`, `nothing-reachable`, `stuck`,
    /// `time-limit`, `nothing-observable`, `voltage-low`.
    pub fn name(self) -> &'static str {
        match self {
            EndReason::CoverageReached => "coverage-reached",
            EndReason::BatteryExhausted => "battery-exhausted",
            EndReason::NothingReachable => "nothing-reachable",
            EndReason::Stuck => "stuck",
            EndReason::TimeLimit => "time-limit",
            EndReason::NothingObservable => "nothing-observable",
            EndReason::VoltageLow => "voltage-low",
        }
    }
}

impl From<DoneReason> for EndReason {
    fn from(r: DoneReason) -> Self {
        match r {
            DoneReason::CoverageReached => EndReason::CoverageReached,
            DoneReason::BatteryExhausted => EndReason::BatteryExhausted,
            DoneReason::NothingReachable => EndReason::NothingReachable,
            DoneReason::Stuck => EndReason::Stuck,
            DoneReason::VoltageLow => EndReason::VoltageLow,
            // The runner ends a mission itself only when decisions stop adding to the map.
            DoneReason::Requested => EndReason::NothingObservable,
        }
    }
}

impl fmt::Display for EndReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One recorded mission event.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedEvent {
    /// Simulated time \[s\].
    pub time_s: f64,
    /// Robot index.
    pub robot: usize,
    /// The event.
    pub event: MissionEvent,
}

/// What one robot did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotReport {
    /// Energy used, from odometry \[steps\] (1 m of travel or 45° of rotation each).
    pub steps: f32,
    /// Distance travelled, from odometry \[m\].
    pub distance_m: f64,
    /// Rotation, absolute, summed, from odometry \[rad\].
    pub rotation_rad: f64,
    /// True distance travelled (physics) \[m\].
    pub true_distance_m: f64,
    /// Decisions made.
    pub decisions: u32,
    /// Objective (fitness) evaluations over all decisions.
    pub fitness_evals: u64,
    /// Wall-clock compute time of each decision \[ms\]: the `step` call that emitted it.
    pub decision_ms: Vec<f64>,
    /// Best fitness per generation of each decision, initial population first (the
    /// optimizer's convergence curve; empty for the frontier rules).
    pub decision_histories: Vec<Vec<f32>>,
    /// Replans.
    pub replans: u32,
    /// Times the robot gave way to another.
    pub yields: u32,
    /// Faults.
    pub faults: u32,
    /// Contacts: times the body's stall flag rose (a wall, door, robot or person hit).
    pub collisions: u32,
    /// Energy left \[steps\].
    pub battery_steps: f32,
    /// How the robot's mission ended, if it did.
    pub done: Option<DoneReason>,
    /// True positions, every 5 cm of motion.
    pub trajectory: Vec<Point2>,
    /// Targets chosen, in order.
    pub targets: Vec<Point2>,
    /// Final true pose.
    pub final_pose: Pose2,
    /// Final distance between the true and the estimated position \[m\].
    pub pose_error_m: f32,
    /// Final poses and pose errors of the estimate and of the raw odometry.
    pub localization: crate::localization_report::LocalizationReport,
}

/// What the run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunReport {
    /// Final coverage of the shared map (0..1).
    pub coverage: f32,
    /// Observable cells.
    pub observable_cells: usize,
    /// Known observable cells at the end.
    pub known_cells: usize,
    /// Per robot.
    pub robots: Vec<RobotReport>,
    /// Simulated time \[s\].
    pub sim_time_s: f64,
    /// Wall-clock time of the run \[s\], not counting the observer's (pictures).
    pub wall_time_s: f64,
    /// Why it ended (`None` while running).
    pub reason: Option<EndReason>,
    /// Coverage over steps: (steps summed over robots, coverage), sampled every second of
    /// simulated time when something changed, at each decision and at the end.
    pub coverage_curve: Vec<(f32, f32)>,
    /// Coverage over simulated time: (time \[s\], coverage), same samples.
    pub coverage_time_curve: Vec<(f64, f32)>,
    /// Coverage over distance travelled: (metres summed over robots, coverage), same samples.
    pub coverage_distance_curve: Vec<(f32, f32)>,
    /// Decisions, replans, yields, faults and ends, in order.
    pub events: Vec<LoggedEvent>,
    /// The final map against the truth.
    pub map_accuracy: crate::map_accuracy::MapAccuracy,
}

impl RunReport {
    /// Steps summed over robots.
    pub fn steps(&self) -> f32 {
        self.robots.iter().map(|r| r.steps).sum()
    }

    /// Metres summed over robots (odometry).
    pub fn distance_m(&self) -> f64 {
        self.robots.iter().map(|r| r.distance_m).sum()
    }

    /// Rotation summed over robots (odometry) \[rad\].
    pub fn rotation_rad(&self) -> f64 {
        self.robots.iter().map(|r| r.rotation_rad).sum()
    }

    /// Decisions summed over robots.
    pub fn decisions(&self) -> u32 {
        self.robots.iter().map(|r| r.decisions).sum()
    }

    /// Fitness evaluations summed over robots.
    pub fn fitness_evals(&self) -> u64 {
        self.robots.iter().map(|r| r.fitness_evals).sum()
    }

    /// Contacts summed over robots.
    pub fn collisions(&self) -> u32 {
        self.robots.iter().map(|r| r.collisions).sum()
    }

    /// Every decision's compute time \[ms\], sorted ascending.
    pub fn decision_ms_sorted(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .robots
            .iter()
            .flat_map(|r| r.decision_ms.iter().copied())
            .collect();
        v.sort_by(f64::total_cmp);
        v
    }

    /// The `q`-quantile (0..=1, nearest rank) of the decision times \[ms\]; 0 without decisions.
    pub fn decision_ms_quantile(&self, q: f64) -> f64 {
        let v = self.decision_ms_sorted();
        if v.is_empty() {
            return 0.0;
        }
        let rank = (q.clamp(0.0, 1.0) * v.len() as f64).ceil().max(1.0) as usize;
        v[rank.min(v.len()) - 1]
    }

    /// Total decision compute time \[ms\].
    pub fn decision_ms_total(&self) -> f64 {
        self.robots.iter().flat_map(|r| r.decision_ms.iter()).sum()
    }

    /// Replans summed over robots.
    pub fn replans(&self) -> u32 {
        self.robots.iter().map(|r| r.replans).sum()
    }
}
