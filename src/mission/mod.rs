//! The mission state machine: one per robot, sans-IO, `no_std`, no allocation.
//!
//! A [`Mission`] is fed time, odometry with the robot's flags ([`Mission::on_odometry`]),
//! laser scans ([`Mission::on_scan`], integrated into the [`SharedMap`]) and, optionally, the
//! coverage the caller measures ([`Mission::set_coverage`]). Once per control period
//! [`Mission::step`] returns the command to send (always through the
//! [`SafetyMonitor`](crate::control::safety::SafetyMonitor), so always within
//! [`MissionConfig::limits`]) and what happened ([`MissionEvent`]s).
//!
//! # States
//!
//! ```text
//!  Starting ──(odometry + first scan)──► Deciding ──(Go)──► Rotating ⇄ Driving
//!                                            ▲   │                 │
//!               (arrived, or too many        │   └─(Done / battery)─┼──► Done(reason)
//!                replans for one decision) ──┘                     │
//!  Replanning ◄──(obstacle ahead, contact after back-off, path cut)─┘
//!  Yielding   ◄──(another robot in the way) ──(wait, step aside)──► Replanning
//!  Fault(reason) ◄──(e-stop, motors off, stale inputs: from any state) ──(cleared)──► Replanning
//! ```
//!
//! - **Starting**: commands zero until the first odometry (which fixes the map-from-odom
//!   transform at the start pose) and the first scan integrated.
//! - **Looking around** (reported as Rotating; [`MissionConfig::look_around`], off by
//!   default): before the first decision, a turn in place at 15 deg/s by the laser's blind
//!   sector plus 10°, ended early when the safety monitor refuses it.
//! - **Deciding**: a decision by the configured selector ([`SelectorKind`]), computed inside
//!   [`Mission::step`] from the [`Workspace`]. `Outcome::Done` (no frontier reachable) first
//!   sends the robot to look from the mouth of a passage open in Free cells but shut in the
//!   planning layer, once per passage, its walls there first lowered to one return's evidence
//!   so that the look draws them again ([`crate::explore::shut_mouth`]); with none left it counts
//!   as a failed decision: [`MissionConfig::max_failed_decisions`] of them in a row end the
//!   mission with [`DoneReason::NothingReachable`] (one look can be cut off for a moment by a
//!   return the monitor just stopped for, which fresh scans clear). A failed decision is
//!   retried one second later, not at the next period, so the looks that end a mission are
//!   taken on maps several seconds apart; and a look that finds nothing reachable forgets the
//!   bumper contacts remembered across the bumper's width (their own cells stay in the map),
//!   which otherwise shut a corridor for two minutes. `NoFeasibleTarget` with the battery low
//!   ends it with [`DoneReason::BatteryExhausted`].
//! - **Rotating / Driving**: the [`WaypointFollower`](crate::control::follower::WaypointFollower)
//!   turns in place then drives to each waypoint ([`MissionEvent::WaypointReached`]).
//!   After every scan the remaining segments are checked against the traversability layer;
//!   an Occupied or inflated cell across them (a door that closed) means a replan.
//! - **Replanning**: a fresh path from the current pose to the decision's remaining targets.
//!   Caused by the safety monitor (obstacle ahead: the return is added to the map with one
//!   return's evidence, so free space seen through it later clears it; contact or
//!   stall: once the monitor has backed off), by a cut path, or by the end of a fault. A
//!   decision that needed more than [`MissionConfig::max_replans_per_decision`] replans
//!   without the robot getting anywhere (less than 1 m from where the first of them was
//!   made: a robot that moved on counts afresh), or whose targets can no longer be reached,
//!   is dropped: its target is blacklisted and the mission decides again.
//!   After two obstacle holds in a row without progress (no waypoint reached, less than
//!   0.3 m moved: typically a robot too close to a wall to turn, whose every plan starts with
//!   a command the monitor refuses), the robot first escapes, then replans
//!   ([`MissionStats::escapes`]). The escape is chosen as the monitor will check it (the
//!   scan, and the map's obstacles the 180° laser cannot see): a straight drive at 100 mm/s,
//!   forward or back, to the nearest cell where the planning layer lets the body turn (at
//!   most 0.8 m; between walls on both sides it steers to the middle), the direction that
//!   does not undo the previous escape first, then the direction of the path given up; else
//!   a 60° turn in place at 20 deg/s away from the nearest return; else a 0.25 m drive. Each
//!   command is still checked by the monitor.
//! - **Yielding**: the thing in the way is another robot (its mark on the shared map is at
//!   the obstacle). The robot with the higher id waits [`MissionConfig::yield_wait_s`], then
//!   replans around; if no way around exists it steps out of the other robot's path and waits
//!   there until it has passed. The lower id replans at once (and, while the other robot
//!   still blocks the only way, waits for it to step aside). This is the thesis's "solve
//!   conflict" routine.
//! - **Done(reason)**: coverage target reached, battery exhausted, nothing reachable left, the
//!   battery voltage low ([`voltage`]: below a threshold for a hold time, with hysteresis), or
//!   ended by the caller ([`Mission::end`]).
//! - **Returning**: with [`MissionConfig::return_to_start`], an end first sends the robot
//!   back to its start position as a go-to goal (same planner, follower, replans and safety
//!   monitor; the energy budget and coverage no longer end it); Done follows on arrival, or
//!   when the way back cannot be found ([`MissionConfig::max_failed_decisions`] attempts).
//!   The heading is not restored. Reported as Rotating/Driving/Replanning, with
//!   [`Mission::returning`] giving the reason.
//! - **Fault(reason)**: e-stop, motors disabled, stale odometry or scan: zero velocity. When
//!   it clears the mission replans from the current pose; the old path is never resumed.
//!
//! Energy: the battery starts at [`MissionConfig::battery_steps`] and decreases with the
//! motion actually driven, measured on odometry, 1 m or 45° per step
//! ([`crate::units::steps`]); at the reserve the mission is done.
//!
//! Events: at most [`MAX_EVENTS`] per step; on overflow the oldest are kept and the number
//! dropped is counted in [`MissionStats::events_dropped`].
//!
//! # Several robots
//!
//! Missions share one [`SharedMap`] and one [`Workspace`] in process and are stepped one after
//! the other; they exchange no messages. Each writes a [`RobotMark`] (pose and remaining
//! waypoints) on the shared map. While a robot plans, its own body is lifted off the map
//! (other robots' scans put it there) and the robots within 3 m are stamped on it from their
//! marks; the cells are put back after the period. Each robot also weakens Occupied evidence
//! along the last metre it drove, so it leaves no ghost behind.
//!
//! # Deciding while driving
//!
//! With [`MissionConfig::decide_while_driving`], once less than
//! [`MissionConfig::decide_ahead_m`] of the last leg is left the next decision is computed from
//! the path's end pose and used on arrival if its path is still clear. Measured with the
//! kinematic double on the two-room test world (8 seeds each, thesis slip; the decision's
//! compute time modelled from docs/benchmarks.md: 0.6 s for xBOA, 3.5 ms for nearest
//! frontier; `cargo test -p papillon --lib mission::tests::report_decide_while_driving --
//! --ignored --nocapture`):
//!
//! | selector | ahead | mean mission | mean time stopped | decisions used from ahead |
//! |---|---|---|---|---|
//! | nearest frontier | off | 51.1 s | 1.7 s | 0 |
//! | nearest frontier | on | 51.1 s | 1.7 s | 16 |
//! | xBOA | off | 65.3 s | 3.8 s | 0 |
//! | xBOA | on | 73.0 s | 3.8 s | 7 |
//!
//! It does not reduce the time stopped (most stops are the follower settling on a waypoint,
//! and most decisions computed ahead are dropped because the map changed on the last metre),
//! and with xBOA the decisions taken from the predicted end pose lead to longer missions. It
//! is therefore off by default.

pub mod footprint;
mod machine;
pub mod motion_filter;
mod shared;
pub mod voltage;
mod window;

#[cfg(all(test, feature = "std"))]
mod tests;

pub use machine::Mission;
pub use motion_filter::MotionFilterConfig;
pub use shared::{
    MAX_FRONTIERS, MAX_ROBOTS, MAX_SHARED_WAYPOINTS, RobotMark, SharedMap, Workspace,
};
pub use voltage::{VoltageConfig, VoltageWatch};

use crate::control::command::{Limits, RobotCommand};
use crate::control::follower::{FollowerConfig, FollowerError};
use crate::control::safety::SafetyConfig;
use crate::explore::{DecideError, ExploreConfig, MAX_TARGETS};
use crate::geometry::Point2;
use crate::grid::{GridError, LogOddsBounds};
use crate::optim::Method;
use crate::planner::{TraversabilityConfig, TraversabilityError, UnknownPolicy};
use crate::sensor::{IntegrationError, LaserConfig, SensorModel};

/// Most events one step reports.
pub const MAX_EVENTS: usize = 8;

/// Obstacle inflation of the thesis set-up's disc planning \[m\]: the P3-DX's turning radius
/// (0.25 m) plus the safety monitor's turning margin (0.05 m) plus a margin for path
/// tracking. The default plans with the body's footprint instead ([`footprint`]).
pub const DEFAULT_PLANNING_RADIUS_M: f32 = 0.38;

/// Cell size the default configuration's planning layer is sized for \[m\]; a mission on
/// another resolution derives its layer with [`footprint::planning_layer`].
pub const DEFAULT_RESOLUTION_M: f32 = 0.1;

/// Which target selector decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SelectorKind {
    /// A population optimizer on the energy-constrained objective (xBOA in the thesis).
    Optimized(Method),
    /// Yamauchi's nearest frontier.
    NearestFrontier,
    /// explore_lite's frontier utility, with a blacklist of places the robot failed to reach.
    FrontierUtility,
}

/// Everything a mission needs, plain data. `Default` is the thesis set-up: xBOA, population
/// 5, 30 generations, k = 1, coverage target 0.99, P3-DX limits, the thesis laser.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionConfig {
    /// The target selector.
    pub selector: SelectorKind,
    /// Decision settings (k, reserve, population, generations, ...).
    pub explore: ExploreConfig,
    /// Energy at the start \[steps\].
    pub battery_steps: f32,
    /// Coverage (0..=1) at which the mission is done, when the caller reports coverage.
    pub coverage_target: f32,
    /// The laser.
    pub laser: LaserConfig,
    /// The inverse sensor model (default the thesis's; the mission maps with
    /// [`MissionConfig::map_sensor`]).
    pub sensor: SensorModel,
    /// Log-odds saturation of the shared grid.
    pub grid_bounds: LogOddsBounds,
    /// Inflation and Unknown policy of the planning layer.
    pub traversability: TraversabilityConfig,
    /// Path follower tuning.
    pub follower: FollowerConfig,
    /// Safety distances and timeouts.
    pub safety: SafetyConfig,
    /// Motion limits every command is clamped to.
    pub limits: Limits,
    /// How long the robot with the higher id waits when another robot blocks it \[s\].
    pub yield_wait_s: f32,
    /// Replans one decision may need without progress (within 1 m of where the first of them
    /// was made) before it is dropped and the mission decides again.
    pub max_replans_per_decision: u32,
    /// Without progress toward the current waypoint for this long, the path counts as blocked
    /// \[s\].
    pub stuck_timeout_s: f32,
    /// The robot must get this far from where it last made progress \[m\] ...
    pub progress_distance_m: f32,
    /// ... within this long \[s\] (starts, faults and waits for another robot aside), or the
    /// mission ends [`DoneReason::Stuck`]: the last line of defence against any loop that
    /// gets nowhere (`machine/progress.rs`).
    pub progress_timeout_s: f32,
    /// Decisions in a row that may fail (no feasible target, every frontier blacklisted)
    /// before the mission gives up.
    pub max_failed_decisions: u32,
    /// Below this much energy above the reserve, a decision without a feasible target ends
    /// the mission with [`DoneReason::BatteryExhausted`] \[steps\].
    pub low_battery_steps: f32,
    /// Compute the next decision while driving, from the end of the current path, once less
    /// than [`Self::decide_ahead_m`] of it is left.
    pub decide_while_driving: bool,
    /// Remaining path length below which the next decision is computed ahead \[m\].
    pub decide_ahead_m: f32,
    /// Scan-to-map matching before each scan is integrated (off by default).
    pub localize: crate::localize::LocalizeConfig,
    /// The battery-voltage watch, fed by [`Mission::on_battery_voltage`] (a caller that
    /// reports no voltage, as the simulator's runner, is never stopped by it).
    pub voltage: VoltageConfig,
    /// When the mission ends (coverage, battery, nothing reachable, low voltage, or
    /// [`Mission::end`]), drive back to the start position first, with the same planner and
    /// safety monitor, then report [`MissionEvent::Done`].
    pub return_to_start: bool,
    /// Before the first decision, turn in place by the laser's blind sector (plus 10°) at
    /// 15 deg/s, when the safety monitor lets the robot turn: the first decision then sees
    /// behind the start pose (`machine/look_around.rs`). Only with an optimizer on the
    /// efficient objective; the thesis objective and the frontier rules never turn. Default
    /// off: on the lab (board pump) it saves a quarter to a half of the steps, on the
    /// simulator's default house missions (seeds 25..34) it costs 10 steps on average
    /// (`docs/experiments.md`, issue 26).
    pub look_around: bool,
    /// Which scans are integrated into the map ([`motion_filter`]): off by default, every
    /// scan is (the thesis); on, only a scan taken after the robot moved or turned enough
    /// since the last integrated one, or after a time. The others still feed the safety
    /// monitor and the localisation.
    pub motion_filter: MotionFilterConfig,
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self {
            selector: SelectorKind::Optimized(Method::Xboa),
            explore: ExploreConfig::default(),
            battery_steps: 500.0,
            coverage_target: 0.99,
            laser: LaserConfig::thesis(),
            sensor: SensorModel::default(),
            grid_bounds: LogOddsBounds::default(),
            traversability: footprint::planning_layer(
                &SafetyConfig::default(),
                footprint::DEFAULT_CLEARANCE_M,
                DEFAULT_RESOLUTION_M,
                UnknownPolicy::Traversable {
                    cost_factor: crate::planner::traversability::DEFAULT_UNKNOWN_COST_FACTOR,
                },
            ),
            follower: FollowerConfig::default(),
            safety: SafetyConfig::default(),
            limits: Limits::p3dx_exploration(),
            yield_wait_s: 3.0,
            max_replans_per_decision: 5,
            stuck_timeout_s: 20.0,
            progress_distance_m: 0.5,
            progress_timeout_s: 300.0,
            max_failed_decisions: 8,
            low_battery_steps: 10.0,
            decide_while_driving: false,
            decide_ahead_m: 0.6,
            localize: crate::localize::LocalizeConfig::default(),
            voltage: VoltageConfig::default(),
            return_to_start: false,
            look_around: false,
            motion_filter: MotionFilterConfig::off(),
        }
    }
}

impl MissionConfig {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), MissionError> {
        let bad = |field: &'static str, value: f32| Err(MissionError::BadConfig { field, value });
        let finite_non_negative = [
            ("battery_steps", self.battery_steps),
            ("yield_wait_s", self.yield_wait_s),
            ("low_battery_steps", self.low_battery_steps),
            ("decide_ahead_m", self.decide_ahead_m),
            ("explore.reserve_steps", self.explore.reserve_steps),
            (
                "localize.grazing_miss_offset_cells",
                self.localize.grazing_miss_offset_cells.unwrap_or(0.0),
            ),
        ];
        for (field, value) in finite_non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return bad(field, value);
            }
        }
        if !(self.coverage_target > 0.0 && self.coverage_target <= 1.0) {
            return bad("coverage_target", self.coverage_target);
        }
        let v = &self.voltage;
        for (field, value) in [
            ("voltage.low_v", v.low_v),
            ("voltage.hysteresis_v", v.hysteresis_v),
            ("voltage.hold_s", v.hold_s),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(field, value);
            }
        }
        for (field, value) in [
            ("stuck_timeout_s", self.stuck_timeout_s),
            ("progress_distance_m", self.progress_distance_m),
            ("progress_timeout_s", self.progress_timeout_s),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return bad(field, value);
            }
        }
        if self.explore.targets == 0 || self.explore.targets > MAX_TARGETS {
            return bad("explore.targets", self.explore.targets as f32);
        }
        if self.explore.population < crate::optim::MIN_POP
            || self.explore.population > crate::optim::MAX_POP
        {
            return bad("explore.population", self.explore.population as f32);
        }
        if let Some((field, value)) = self.motion_filter.invalid_field() {
            return bad(field, value);
        }
        self.sensor.validate().map_err(MissionError::Sensor)?;
        Ok(())
    }

    /// The sensor model the mission maps with: [`Self::sensor`], with
    /// [`crate::localize::LocalizeConfig::grazing_miss_offset_cells`] when the localisation
    /// is on.
    pub fn map_sensor(&self) -> SensorModel {
        match self.localize.grazing_miss_offset_cells {
            Some(cells) if self.localize.enabled => self.sensor.with_occupied_miss_offset(cells),
            _ => self.sensor,
        }
    }
}

/// What the mission is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionState {
    /// Waiting for the first odometry and scan.
    Starting,
    /// About to decide where to go.
    Deciding,
    /// Turning in place toward a waypoint.
    Rotating,
    /// Driving toward a waypoint.
    Driving,
    /// About to plan a fresh path to the current targets.
    Replanning,
    /// Waiting for, or stepping out of the way of, another robot.
    Yielding,
    /// Finished.
    Done(DoneReason),
    /// Stopped by a fault.
    Fault(FaultReason),
}

/// Why a mission ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DoneReason {
    /// The coverage target was reached.
    CoverageReached,
    /// The battery (minus the reserve) is used up, or too low for any feasible target.
    BatteryExhausted,
    /// No Unknown cell is reachable any more.
    NothingReachable,
    /// The robot could not get on while its map still had frontier it could reach: the last
    /// errands were all dropped where they started, or every target chosen was refused
    /// (listed, gaining nothing, no path to drive) [`MissionConfig::max_failed_decisions`]
    /// times in a row. A robot wedged where the safety monitor allows no motion ends here,
    /// not with [`Self::NothingReachable`] (issue 17: a mission ends "nothing reachable"
    /// only when no frontier is reachable by the footprint). Also when the robot stayed
    /// within [`MissionConfig::progress_distance_m`] of one place for
    /// [`MissionConfig::progress_timeout_s`] while exploring.
    Stuck,
    /// The battery voltage stayed below [`VoltageConfig::low_v`] for [`VoltageConfig::hold_s`].
    VoltageLow,
    /// The caller ended the mission ([`Mission::end`]).
    Requested,
}

/// Why the robot is stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaultReason {
    /// The robot's emergency stop is engaged.
    EmergencyStop,
    /// The robot's motors are disabled.
    MotorsDisabled,
    /// Odometry or scans stopped arriving.
    StaleInputs,
}

/// Why a path was planned again.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ReplanCause {
    /// The laser saw an obstacle in the direction of travel.
    ObstacleAhead,
    /// A bumper or a stalled wheel (after backing off).
    Contact,
    /// New Occupied or inflated cells cut the remaining path.
    PathBlocked,
    /// No progress toward the waypoint for [`MissionConfig::stuck_timeout_s`].
    Stuck,
    /// A fault cleared.
    FaultCleared,
    /// Another robot was in the way.
    Robot,
}

/// Something the caller may log or count.
#[derive(Clone, Debug, PartialEq)]
pub enum MissionEvent {
    /// A decision was made.
    Decided {
        /// Targets, in visiting order, map frame \[m\].
        targets: heapless::Vec<Point2, MAX_TARGETS>,
        /// Planned path length \[m\].
        path_length_m: f32,
        /// Unknown cells predicted to become known \[cells\].
        predicted_gain_cells: u32,
        /// Planned energy \[steps\].
        energy_steps: f32,
        /// Objective evaluations used.
        evaluations: u32,
    },
    /// Waypoint `index` of the current path was reached.
    WaypointReached {
        /// Index into [`Mission::path`].
        index: usize,
    },
    /// A fresh path to the current targets was planned.
    Replanned {
        /// Why.
        cause: ReplanCause,
    },
    /// The robot gives way to another robot.
    Yielding {
        /// `true` while it waits for the robot ahead; `false` when it steps aside.
        to_robot_ahead: bool,
    },
    /// A fault stopped the robot.
    Fault(FaultReason),
    /// The fault cleared; the mission replans.
    FaultCleared,
    /// The mission has ended for `reason` and drives back to its start position
    /// ([`MissionConfig::return_to_start`]); [`MissionEvent::Done`] follows on arrival, or
    /// once the way back is found blocked too often.
    Returning(DoneReason),
    /// The mission ended.
    Done(DoneReason),
}

/// Counters over the mission.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MissionStats {
    /// Decisions made.
    pub decisions: u32,
    /// Decisions that failed (no feasible target, all blacklisted, planning errors).
    pub failed_decisions: u32,
    /// Objective evaluations over all decisions.
    pub fitness_evals: u64,
    /// Replans.
    pub replans: u32,
    /// Times the robot gave way to another.
    pub yields: u32,
    /// Faults.
    pub faults: u32,
    /// Waypoints reached.
    pub waypoints_reached: u32,
    /// Energy used \[steps\].
    pub steps: f32,
    /// Distance driven, from odometry \[m\].
    pub distance_m: f32,
    /// Control periods stepped.
    pub periods: u64,
    /// Time with a zero command while the mission was running (not Done) \[s\].
    pub stopped_s: f32,
    /// Events dropped because a step had more than [`MAX_EVENTS`].
    pub events_dropped: u32,
    /// Targets given up (blacklisted, or found inside a wall when replanning).
    pub abandoned_targets: u32,
    /// Decisions computed ahead while driving, and how many of them were used.
    pub decisions_ahead: u32,
    /// Decisions computed ahead that were used.
    pub decisions_ahead_used: u32,
    /// Escapes: slow manoeuvres out of a place where the plans' first commands keep being
    /// refused (repeated obstacle holds without progress).
    pub escapes: u32,
    /// Errands to the mouth of a passage shut on the map, to look through it again when no
    /// frontier was reachable ([`crate::explore::shut_mouth`]).
    pub mouth_looks: u32,
}

/// The result of one control period.
#[derive(Clone, Debug, PartialEq)]
pub struct StepOutput {
    /// The command to send, always within the configured limits.
    pub command: RobotCommand,
    /// What happened (oldest first).
    pub events: heapless::Vec<MissionEvent, MAX_EVENTS>,
}

/// Errors of the mission layer.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MissionError {
    /// A configuration value is out of range.
    BadConfig {
        /// The field.
        field: &'static str,
        /// The value given.
        value: f32,
    },
    /// The grid could not be built.
    Grid(GridError),
    /// The traversability layer could not be built.
    Map(TraversabilityError),
    /// The follower refused its configuration.
    Follower(FollowerError),
    /// The sensor model or laser is invalid, or the scan could not be integrated.
    Sensor(IntegrationError),
    /// More robots than [`MAX_ROBOTS`] share the map.
    TooManyRobots {
        /// The capacity.
        capacity: usize,
    },
    /// A value passed in is not finite.
    NotFinite {
        /// What it was.
        what: &'static str,
    },
    /// A decision failed for a reason that retrying cannot fix.
    Decide(DecideError),
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MissionError::BadConfig { field, value } => {
                write!(f, "mission config {field} = {value} is out of range")
            }
            MissionError::Grid(e) => write!(f, "shared grid: {e}"),
            MissionError::Map(e) => write!(f, "traversability layer: {e}"),
            MissionError::Follower(e) => write!(f, "path follower: {e}"),
            MissionError::Sensor(e) => write!(f, "scan integration: {e}"),
            MissionError::TooManyRobots { capacity } => {
                write!(f, "at most {capacity} robots can share one map")
            }
            MissionError::NotFinite { what } => write!(f, "{what} is not finite"),
            MissionError::Decide(e) => write!(f, "decision: {e}"),
        }
    }
}

impl core::error::Error for MissionError {}
