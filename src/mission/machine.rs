//! The per-robot mission state machine (see the [module documentation](super) for the states
//! and transitions). What concerns several robots on one map is in [`robots`].

use core::time::Duration;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::{Controller, FollowStatus, MAX_WAYPOINTS, WaypointFollower};
use crate::control::odometry::MapFromOdom;
use crate::control::safety::{RobotFlags, SafetyEvent, SafetyInputs, SafetyMonitor, SafetyState};
use crate::explore::frontier_utility::{MAX_BLACKLIST, known_around};
use crate::explore::{
    Blacklist, CandidateStatus, DecideError, Decision, DecisionRequest, ExploreConfig,
    FrontierUtility, MAX_DECISION_HISTORY, MAX_TARGETS, NearestFrontier, Optimized, Outcome,
    TargetSelector,
};
use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::grid::{Cell, CellClass};
use crate::math;
use crate::planner::waypoints::supercover;
use crate::sensor::{Scan, integrate_scan};
use crate::units;

use super::shared::{MAX_SHARED_WAYPOINTS, SharedMap, Workspace};

mod robots;

use super::{
    DoneReason, FaultReason, MAX_EVENTS, MissionConfig, MissionError, MissionEvent, MissionState,
    MissionStats, ReplanCause, SelectorKind, StepOutput,
};
use robots::{TRAIL_LEN, TRAIL_SPACING_M, Yield};

/// A blacklisted place covers targets within this distance \[m\].
const BLACKLIST_RADIUS_M: f32 = 0.5;
/// Search for a passable start cell up to this far from the robot \[m\].
const START_SNAP_M: f32 = 0.6;
/// A robot waiting for another to step aside retries its plan this often \[s\].
const RETRY_S: f32 = 1.0;
/// Bumper contacts remembered.
const MAX_CONTACTS: usize = 16;
/// How long a bumper contact is remembered while planning.
const CONTACT_MEMORY: Duration = Duration::from_secs(120);
/// Progress toward a waypoint smaller than this does not count \[m\].
const PROGRESS_M: f32 = 0.05;
/// After this many obstacle holds in a row without progress, the robot backs or turns away
/// from the nearest laser return before planning again.
const ESCAPE_AFTER_HOLDS: u32 = 2;
/// A robot that moved this far since the first replan counted against its decision has made
/// progress: its replans count afresh \[m\].
const REPLAN_PROGRESS_M: f32 = 1.0;
/// Moving this far from where the holds began counts as progress \[m\].
const ESCAPE_PROGRESS_M: f32 = 0.3;
/// Distance driven (forward or backward) by one escape \[m\].
const ESCAPE_DISTANCE_M: f32 = 0.25;
/// Angle turned in place by one escape \[rad\] (60°).
const ESCAPE_TURN_RAD: f32 = 1.047;
/// Escape speeds: slow, well inside any board's limits.
const ESCAPE_SPEED_MM_S: i16 = 100;
const ESCAPE_TURN_DEG_S: i16 = 20;
/// Longest escape manoeuvre.
const ESCAPE_TIMEOUT: Duration = Duration::from_secs(6);

/// A slow manoeuvre away from the nearest laser return, after repeated obstacle holds: the
/// plans kept starting with a command the safety monitor refuses (the robot too close to a
/// wall to turn, facing it). Every command still goes through the monitor.
#[derive(Clone, Copy, Debug)]
struct Escape {
    command: MotionCommand,
    start_odom: Pose2,
    until: Time,
}

/// A decision computed ahead, from the end of the current path.
#[derive(Clone, Debug)]
struct Ahead {
    decision: Decision,
}

/// One robot's mission.
pub struct Mission<const N: usize> {
    id: u8,
    config: MissionConfig,
    start_map: Pose2,
    state: MissionState,
    map_from_odom: Option<MapFromOdom>,
    pose_odom: Pose2,
    pose_map: Pose2,
    flags: RobotFlags,
    odometry_time: Option<Time>,
    scan: Scan,
    scan_time: Option<Time>,
    scans_integrated: u32,
    coverage: Option<f32>,
    follower: WaypointFollower,
    monitor: SafetyMonitor,
    battery_steps: f32,
    stats: MissionStats,
    /// Targets of the current decision still to reach, in order.
    targets: heapless::Vec<Point2, MAX_TARGETS>,
    /// Targets given by [`Mission::go_to`], planned at the next decision.
    goal: Option<heapless::Vec<Point2, MAX_TARGETS>>,
    /// The current targets came from [`Mission::go_to`].
    goal_active: bool,
    goal_failures: u32,
    goal_retry_at: Time,
    replans_this_decision: u32,
    /// Where the robot stood at the first replan counted in `replans_this_decision`.
    replans_from: Point2,
    failed_in_row: u32,
    replan_cause: ReplanCause,
    /// A robot involved in the conflict being resolved.
    conflict_robot: Option<u8>,
    yielding: Option<Yield>,
    /// A scan arrived since the path was last checked.
    path_dirty: bool,
    /// The plan was made after the last hold; acknowledge the monitor when it allows.
    ack_pending: bool,
    plan_time: Option<Time>,
    progress_index: usize,
    progress_best_m: f32,
    progress_time: Time,
    blacklist: heapless::Vec<(Point2, u32), MAX_BLACKLIST>,
    ahead: Option<Ahead>,
    /// Best fitness per generation of the last decision adopted.
    last_history: heapless::Vec<f32, MAX_DECISION_HISTORY>,
    /// The remaining waypoints of the last path given up (for telling whether a robot is in
    /// the way, and for publishing while the robot holds).
    last_path: heapless::Vec<Point2, MAX_SHARED_WAYPOINTS>,
    /// Where the bumpers found something (a segment across the bumper, map frame) and until
    /// when it is remembered: obstacles the laser may not see (glass, low objects).
    contacts: heapless::Deque<(Point2, Point2, Time), MAX_CONTACTS>,
    trail: heapless::Deque<Point2, TRAIL_LEN>,
    last_step: Option<Time>,
    /// Obstacle holds in a row without progress, and where the first of them happened.
    holds_in_row: u32,
    hold_anchor: Point2,
    escape: Option<Escape>,
    localizer: crate::localize::Tracker,
}

impl<const N: usize> core::fmt::Debug for Mission<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Mission")
            .field("id", &self.id)
            .field("state", &self.state)
            .field("pose_map", &self.pose_map)
            .field("battery_steps", &self.battery_steps)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// Events of one step: pushes past the capacity keep the oldest and count the rest.
struct Events<'s> {
    list: heapless::Vec<MissionEvent, MAX_EVENTS>,
    stats: &'s mut MissionStats,
}

impl Events<'_> {
    fn push(&mut self, e: MissionEvent) {
        if self.list.push(e).is_err() {
            self.stats.events_dropped += 1;
        }
    }
}

impl<const N: usize> Mission<N> {
    /// A mission for robot `id` (lower ids have priority in conflicts), starting at
    /// `start_map` in the map frame.
    pub fn new(id: u8, config: MissionConfig, start_map: Pose2) -> Result<Self, MissionError> {
        config.validate()?;
        if !(start_map.x.is_finite() && start_map.y.is_finite() && start_map.theta.is_finite()) {
            return Err(MissionError::NotFinite { what: "start pose" });
        }
        let follower = WaypointFollower::new(config.follower).map_err(MissionError::Follower)?;
        let monitor = SafetyMonitor::new(config.safety, config.limits);
        Ok(Self {
            id,
            battery_steps: config.battery_steps,
            start_map,
            state: MissionState::Starting,
            map_from_odom: None,
            pose_odom: Pose2::default(),
            pose_map: start_map,
            flags: RobotFlags::nominal(),
            odometry_time: None,
            scan: Scan::new(),
            scan_time: None,
            scans_integrated: 0,
            coverage: None,
            follower,
            monitor,
            stats: MissionStats::default(),
            targets: heapless::Vec::new(),
            goal: None,
            goal_active: false,
            goal_failures: 0,
            goal_retry_at: Time::ZERO,
            replans_this_decision: 0,
            replans_from: Point2::new(0.0, 0.0),
            failed_in_row: 0,
            replan_cause: ReplanCause::ObstacleAhead,
            conflict_robot: None,
            yielding: None,
            path_dirty: false,
            ack_pending: false,
            plan_time: None,
            progress_index: 0,
            progress_best_m: f32::INFINITY,
            progress_time: Time::ZERO,
            blacklist: heapless::Vec::new(),
            ahead: None,
            last_history: heapless::Vec::new(),
            last_path: heapless::Vec::new(),
            contacts: heapless::Deque::new(),
            trail: heapless::Deque::new(),
            last_step: None,
            holds_in_row: 0,
            hold_anchor: start_map.position(),
            escape: None,
            localizer: crate::localize::Tracker::new(),
            config,
        })
    }

    /// The robot's id.
    pub fn id(&self) -> u8 {
        self.id
    }

    /// The configuration.
    pub fn config(&self) -> &MissionConfig {
        &self.config
    }

    /// Latest odometry (`odom` frame, as the robot reports it) and robot flags. The first
    /// reading is aligned to the start pose.
    pub fn on_odometry(&mut self, now: Time, pose_odom: Pose2, flags: RobotFlags) {
        if !(pose_odom.x.is_finite() && pose_odom.y.is_finite() && pose_odom.theta.is_finite()) {
            // A corrupt reading is no reading: the inputs go stale.
            self.flags = flags;
            return;
        }
        let transform = *self
            .map_from_odom
            .get_or_insert_with(|| MapFromOdom::from_start(self.start_map, pose_odom));
        if self.odometry_time.is_some() {
            let d = self.pose_odom.position().distance(pose_odom.position());
            let turn = math::abs(normalize_angle(pose_odom.theta - self.pose_odom.theta));
            let used = units::steps(d, turn);
            self.battery_steps = (self.battery_steps - used).max(0.0);
            self.stats.steps += used;
            self.stats.distance_m += d;
        }
        self.pose_odom = pose_odom;
        self.pose_map = transform.map_pose(pose_odom);
        self.flags = flags;
        self.odometry_time = Some(now);
        let p = self.pose_map.position();
        if self
            .trail
            .back()
            .is_none_or(|q| q.distance(p) >= TRAIL_SPACING_M)
        {
            if self.trail.is_full() {
                self.trail.pop_front();
            }
            let _ = self.trail.push_back(p);
        }
    }

    /// A scan taken at `now` from the current pose: integrated into the shared map (before
    /// the first odometry, at the start pose). With [`MissionConfig::localize`] on, the scan
    /// is first matched to the map at the odometry pose and a trusted match corrects the
    /// map-from-odometry transform ([`crate::localize::tracker`]). Occupied evidence along the robot's last metre
    /// (not under its current body) is weakened to a weak Free value: the robot stood there,
    /// so what another robot's scan saw there was this robot, not a wall.
    ///
    /// Errors: the scan cannot be integrated (bad sensor model or pose), or this is a ninth
    /// robot on the map ([`MissionError::TooManyRobots`]; the scan was integrated).
    pub fn on_scan(
        &mut self,
        now: Time,
        scan: &Scan,
        map: &mut SharedMap<N>,
    ) -> Result<(), MissionError> {
        self.localizer.correct(
            &self.config.localize,
            &map.grid,
            &mut map.matcher,
            scan,
            &self.config.laser,
            self.pose_odom,
            &mut self.map_from_odom,
            &mut self.pose_map,
        );
        integrate_scan(
            &mut map.grid,
            scan,
            self.pose_map,
            &self.config.laser,
            &self.config.sensor,
            &mut map.trav,
        )
        .map_err(MissionError::Sensor)?;
        self.clear_own_trail(map);
        self.scan.clone_from(scan);
        self.scan_time = Some(now);
        self.scans_integrated += 1;
        self.path_dirty = true;
        self.publish(now, map)
    }

    /// A scan the caller does not trust for mapping (taken while the robot turned fast, when
    /// a small error in the scan's time puts its walls in the wrong place): it keeps the
    /// safety monitor's view fresh, and nothing else.
    pub fn on_scan_unmapped(&mut self, now: Time, scan: &Scan) {
        self.scan.clone_from(scan);
        self.scan_time = Some(now);
    }

    /// Coverage measured by the caller (0..=1); the mission is done once it reaches the
    /// target. Without it the mission ends only when nothing reachable is unknown or the
    /// battery is out.
    pub fn set_coverage(&mut self, coverage: f32) {
        if coverage.is_finite() {
            self.coverage = Some(coverage);
        }
    }

    /// Sends the robot to `targets` (map frame \[m\], in order) instead of the next
    /// exploration decision; once there it goes back to exploring.
    pub fn go_to(&mut self, targets: &[Point2]) -> Result<(), MissionError> {
        if targets.is_empty() || targets.len() > MAX_TARGETS {
            return Err(MissionError::BadConfig {
                field: "go_to targets",
                value: targets.len() as f32,
            });
        }
        if targets
            .iter()
            .any(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(MissionError::NotFinite {
                what: "go_to target",
            });
        }
        let mut goal = heapless::Vec::new();
        let _ = goal.extend_from_slice(targets);
        self.goal = Some(goal);
        self.goal_failures = 0;
        self.goal_retry_at = Time::ZERO;
        if matches!(
            self.state,
            MissionState::Rotating | MissionState::Driving | MissionState::Replanning
        ) {
            self.follower.clear();
            self.state = MissionState::Deciding;
        }
        Ok(())
    }

    /// What the mission is doing.
    pub fn state(&self) -> MissionState {
        self.state
    }

    /// The current map-frame pose estimate.
    pub fn pose_map(&self) -> Pose2 {
        self.pose_map
    }

    /// The scan matcher's counters and last match ([`MissionConfig::localize`]).
    pub fn localizer(&self) -> &crate::localize::Tracker {
        &self.localizer
    }

    /// The current waypoints (map frame \[m\]).
    pub fn path(&self) -> &[Point2] {
        self.follower.path()
    }

    /// The targets of the current decision still to reach.
    pub fn targets(&self) -> &[Point2] {
        &self.targets
    }

    /// Counters.
    pub fn stats(&self) -> &MissionStats {
        &self.stats
    }

    /// Energy left \[steps\].
    pub fn battery_steps(&self) -> f32 {
        self.battery_steps
    }

    /// Best fitness per generation (initial population first) of the last decision adopted:
    /// the optimizer's convergence curve; empty for the frontier rules and go-to goals.
    pub fn last_decision_history(&self) -> &[f32] {
        &self.last_history
    }

    /// The safety monitor (read only).
    pub fn monitor(&self) -> &SafetyMonitor {
        &self.monitor
    }

    /// One control period at `now`. Decisions are computed here when needed.
    pub fn step<R: rand_core::Rng>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N>,
        rng: &mut R,
    ) -> StepOutput {
        let mut stats = self.stats;
        let mut events = Events {
            list: heapless::Vec::new(),
            stats: &mut stats,
        };
        events.stats.periods += 1;
        let dt_s = self.last_step.map_or(0.0, |t| now.secs_since(t));
        self.last_step = Some(now);
        if self.ack_pending && self.monitor.acknowledge_replan().is_ok() {
            self.ack_pending = false;
        }

        // The robot's own body, as other robots' scans put it on the map, must not block its
        // own plans, and the robots near it block them wherever the scans have got to: both
        // for the decisions of this period, then the cells are put back.
        let mut lifted = self.lift_own_body(map);
        self.stamp_others(map, now, &mut lifted);
        let proposed = self.run(now, map, ws, rng, &mut events);
        for &(i, value) in lifted.iter().rev() {
            map.grid.set_log_odds(i, value, &mut map.trav);
        }

        let inputs = SafetyInputs {
            pose_odom: self.pose_odom,
            odometry_time: self.odometry_time,
            scan: self.scan_time.map(|_| &self.scan),
            scan_time: self.scan_time,
            laser: &self.config.laser,
            flags: self.flags,
        };
        let (command, safety) = self.monitor.filter(now, proposed, &inputs);
        if let Some(event) = safety {
            self.on_safety(now, event, map, &mut events);
        }
        let moving = command
            .velocity()
            .is_some_and(|v| v.as_motion() != MotionCommand::ZERO);
        if !moving && !matches!(self.state, MissionState::Done(_)) {
            events.stats.stopped_s += dt_s;
        }
        let list = events.list;
        self.stats = stats;
        // The map only rejects a ninth robot; that robot is simply not seen by the others'
        // conflict rule (it still appears in their scans).
        let _ = self.publish(now, map);
        StepOutput {
            command,
            events: list,
        }
    }

    /// The state machine proper: the follower's proposal for this period.
    fn run<R: rand_core::Rng>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> MotionCommand {
        if let MissionState::Done(_) = self.state {
            return MotionCommand::ZERO;
        }
        if self.state == MissionState::Starting {
            if self.map_from_odom.is_none() || self.scans_integrated == 0 {
                return MotionCommand::ZERO;
            }
            self.state = MissionState::Deciding;
        }
        // Faults first: zero velocity, forget the path.
        if let Some(reason) = self.fault_now(now) {
            if self.state != MissionState::Fault(reason) {
                if !matches!(self.state, MissionState::Fault(_)) {
                    events.stats.faults += 1;
                }
                events.push(MissionEvent::Fault(reason));
                self.state = MissionState::Fault(reason);
            }
            self.follower.clear();
            self.ahead = None;
            self.yielding = None;
            self.escape = None;
            self.ack_pending = false;
            return MotionCommand::ZERO;
        }
        if let MissionState::Fault(_) = self.state {
            events.push(MissionEvent::FaultCleared);
            self.enter_replanning(ReplanCause::FaultCleared);
        }
        // The end of the mission.
        if self.battery_steps <= self.config.explore.reserve_steps {
            return self.finish(DoneReason::BatteryExhausted, events);
        }
        if self
            .coverage
            .is_some_and(|c| c >= self.config.coverage_target)
        {
            return self.finish(DoneReason::CoverageReached, events);
        }
        if self.escape.is_some()
            && let Some(cmd) = self.escape_step(now)
        {
            return cmd;
        }
        // Up to a few transitions in one period, so that arriving and deciding, or replanning
        // and driving, do not cost a period each.
        for _ in 0..4 {
            match self.state {
                MissionState::Deciding => {
                    if !self.decide(now, map, ws, rng, events) {
                        return MotionCommand::ZERO;
                    }
                }
                MissionState::Replanning => {
                    if matches!(self.monitor.state(), SafetyState::BackingOff { .. }) {
                        return MotionCommand::ZERO;
                    }
                    self.replan(now, map, ws, events);
                }
                MissionState::Yielding => match self.yield_step(now, map, ws, events) {
                    Some(cmd) => return cmd,
                    None => continue,
                },
                MissionState::Rotating | MissionState::Driving => {
                    match self.follow(now, map, ws, rng, events) {
                        Some(cmd) => return cmd,
                        None => continue,
                    }
                }
                _ => return MotionCommand::ZERO,
            }
        }
        MotionCommand::ZERO
    }

    fn finish(&mut self, reason: DoneReason, events: &mut Events<'_>) -> MotionCommand {
        self.state = MissionState::Done(reason);
        self.follower.clear();
        self.targets.clear();
        self.ahead = None;
        self.yielding = None;
        self.escape = None;
        events.push(MissionEvent::Done(reason));
        MotionCommand::ZERO
    }

    /// The fault in force, if any: e-stop, motors disabled, stale inputs.
    fn fault_now(&self, now: Time) -> Option<FaultReason> {
        if self.flags.estop {
            return Some(FaultReason::EmergencyStop);
        }
        if !self.flags.motors_enabled {
            return Some(FaultReason::MotorsDisabled);
        }
        let max_age = self.config.safety.max_input_age;
        let fresh = |t: Option<Time>| t.is_some_and(|t| now.saturating_since(t) <= max_age);
        if !(fresh(self.odometry_time) && fresh(self.scan_time)) {
            return Some(FaultReason::StaleInputs);
        }
        None
    }

    fn enter_replanning(&mut self, cause: ReplanCause) {
        self.remember_path();
        self.follower.clear();
        self.ahead = None;
        self.replan_cause = cause;
        self.state = MissionState::Replanning;
    }

    /// Reacts to what the safety monitor did this period.
    fn on_safety(
        &mut self,
        now: Time,
        event: SafetyEvent,
        map: &mut SharedMap<N>,
        events: &mut Events<'_>,
    ) {
        let running = matches!(
            self.state,
            MissionState::Rotating | MissionState::Driving | MissionState::Replanning
        );
        match event {
            SafetyEvent::ObstacleAhead { point_base_m, .. } => {
                let p = self.pose_map.transform_point(point_base_m);
                self.mark_occupied(map, p);
                if self.escape.take().is_some() {
                    // The escape itself was refused: plan again; the next hold picks another
                    // manoeuvre from the scan.
                    self.enter_replanning(ReplanCause::ObstacleAhead);
                    return;
                }
                if let Some(Yield::SteppingAside { other, .. }) = self.yielding {
                    self.follower.clear();
                    self.yielding = Some(Yield::Waiting {
                        other,
                        until: now + secs(self.config.yield_wait_s),
                    });
                    return;
                }
                if running {
                    match self.robot_at(map, now, p) {
                        Some(other) => self.begin_conflict(now, other, events),
                        None => {
                            self.enter_replanning(ReplanCause::ObstacleAhead);
                            if self.count_hold() >= ESCAPE_AFTER_HOLDS {
                                self.begin_escape(now, events);
                            }
                        }
                    }
                }
            }
            SafetyEvent::Contact {
                front_bumper,
                rear_bumper,
                ..
            } => {
                let fp = self.config.safety.footprint;
                let res = map.grid.geometry().resolution_m;
                let half = 0.5 * fp.width_m;
                for (pressed, x) in [
                    (front_bumper, fp.front_m + 0.5 * res),
                    (rear_bumper, -fp.rear_m - 0.5 * res),
                ] {
                    if !pressed {
                        continue;
                    }
                    let a = self.pose_map.transform_point(Point2::new(x, -half));
                    let b = self.pose_map.transform_point(Point2::new(x, half));
                    self.mark_occupied(map, self.pose_map.transform_point(Point2::new(x, 0.0)));
                    if self.contacts.is_full() {
                        self.contacts.pop_front();
                    }
                    let _ = self.contacts.push_back((a, b, now + CONTACT_MEMORY));
                }
                self.yielding = None;
                self.escape = None;
                if !matches!(self.state, MissionState::Done(_) | MissionState::Fault(_)) {
                    self.enter_replanning(ReplanCause::Contact);
                }
            }
            SafetyEvent::RequiresReplan { .. } => {
                if self.plan_time == Some(now) {
                    // The plan was made this very period, after the cause: it is fresh.
                    self.ack_pending = true;
                } else if matches!(self.state, MissionState::Rotating | MissionState::Driving) {
                    self.enter_replanning(self.replan_cause);
                }
            }
            SafetyEvent::InputsStale { .. } | SafetyEvent::Fault { .. } => {
                // `run` reports these faults itself; the monitor saw them at the same time.
                self.follower.clear();
            }
        }
    }

    /// Counts an obstacle hold: the number in a row since the robot last made progress
    /// (reached a waypoint, or moved [`ESCAPE_PROGRESS_M`] from where the holds began).
    fn count_hold(&mut self) -> u32 {
        let here = self.pose_map.position();
        if self.holds_in_row == 0 || self.hold_anchor.distance(here) >= ESCAPE_PROGRESS_M {
            self.holds_in_row = 0;
            self.hold_anchor = here;
        }
        self.holds_in_row += 1;
        self.holds_in_row
    }

    /// Starts a slow manoeuvre away from the nearest laser return, the first of backing
    /// away, turning away, turning the other way or driving away that the safety monitor's
    /// corridor check allows on the latest scan. Nothing allowed: the mission just replans.
    fn begin_escape(&mut self, now: Time, events: &mut Events<'_>) {
        if self.scan_time.is_none() {
            return;
        }
        let laser = &self.config.laser;
        let mut nearest: Option<(f32, Point2)> = None;
        for beam in self.scan.beams() {
            let Some(r) = beam.range_m else { continue };
            if !(r.is_finite() && r >= self.config.safety.min_valid_range_m) {
                continue;
            }
            let in_laser =
                Point2::new(r * math::cos(beam.angle_rad), r * math::sin(beam.angle_rad));
            let p = laser.mount.transform_point(in_laser);
            let d = math::hypot(p.x, p.y);
            if nearest.is_none_or(|(best, _)| d < best) {
                nearest = Some((d, p));
            }
        }
        let Some((_, p)) = nearest else { return };
        let (v, w) = (ESCAPE_SPEED_MM_S, ESCAPE_TURN_DEG_S);
        // Turn so that the return ends up behind: away from the side it is on.
        let away = if p.y > 0.0 { -w } else { w };
        let drive = |speed_mm_s: i16| MotionCommand {
            speed_mm_s,
            turn_rate_deg_s: 0,
        };
        let turn = |turn_rate_deg_s: i16| MotionCommand {
            speed_mm_s: 0,
            turn_rate_deg_s,
        };
        let order = if p.x >= 0.0 {
            [drive(-v), turn(away), turn(-away), drive(v)]
        } else {
            [drive(v), turn(away), turn(-away), drive(-v)]
        };
        let limits = *self.monitor.limits();
        let Some(command) = order.into_iter().find(|&c| {
            self.monitor
                .obstacle_in_path(limits.clamp(c), &self.scan, laser)
                .is_none()
        }) else {
            return;
        };
        self.escape = Some(Escape {
            command,
            start_odom: self.pose_odom,
            until: now + ESCAPE_TIMEOUT,
        });
        events.stats.escapes += 1;
    }

    /// One period of the escape; `None` once it is over (the mission then replans).
    fn escape_step(&mut self, now: Time) -> Option<MotionCommand> {
        let e = self.escape?;
        let travelled = e.start_odom.position().distance(self.pose_odom.position());
        let turned = math::abs(normalize_angle(self.pose_odom.theta - e.start_odom.theta));
        let done = if e.command.speed_mm_s != 0 {
            travelled >= ESCAPE_DISTANCE_M
        } else {
            turned >= ESCAPE_TURN_RAD
        };
        if done || now >= e.until || matches!(self.monitor.state(), SafetyState::BackingOff { .. })
        {
            self.escape = None;
            self.enter_replanning(ReplanCause::ObstacleAhead);
            return None;
        }
        // The manoeuvre is a fresh decision of its own, taken after the hold.
        let _ = self.monitor.acknowledge_replan();
        self.ack_pending = false;
        self.state = MissionState::Replanning;
        Some(e.command)
    }

    /// Keeps the remaining waypoints of the path being dropped.
    fn remember_path(&mut self) {
        let path = self.follower.path();
        if path.is_empty() {
            return;
        }
        let from = self.follower.current_index().min(path.len());
        let n = (path.len() - from).min(MAX_SHARED_WAYPOINTS);
        self.last_path.clear();
        let _ = self.last_path.extend_from_slice(&path[from..from + n]);
    }

    /// Sets the cell holding map point `p` Occupied (an obstacle the laser or a bumper found).
    fn mark_occupied(&self, map: &mut SharedMap<N>, p: Point2) {
        if let Some(i) = map
            .grid
            .geometry()
            .cell_at(p)
            .and_then(|c| map.grid.geometry().index(c))
        {
            map.grid.set_class(i, CellClass::Occupied, &mut map.trav);
        }
    }

    /// Writes this robot's mark (pose and remaining path) on the shared map.
    fn publish(&self, now: Time, map: &mut SharedMap<N>) -> Result<(), MissionError> {
        let path = self.follower.path();
        let from = self.follower.current_index().min(path.len());
        let remaining: &[Point2] = if from < path.len() {
            &path[from..]
        } else if !self.last_path.is_empty() && !self.targets.is_empty() {
            &self.last_path
        } else {
            &self.targets
        };
        map.mark(self.id, self.pose_map, now, remaining)
    }

    /// The decision request from `pose`, with the start moved onto the nearest passable cell
    /// if the robot's own cell is inflated.
    fn start_pose(&self, map: &SharedMap<N>, pose: Pose2) -> Pose2 {
        let geom = *map.trav.geometry();
        let c = geom.cell_at_unchecked(pose.position());
        if map.trav.is_passable(c) {
            return pose;
        }
        let span = math::ceil(START_SNAP_M / geom.resolution_m) as i32;
        let mut best: Option<(f32, Cell)> = None;
        for row in c.row - span..=c.row + span {
            for col in c.col - span..=c.col + span {
                let cell = Cell::new(col, row);
                if !map.trav.is_passable(cell) {
                    continue;
                }
                let d = geom.cell_center(cell).distance(pose.position());
                if d <= START_SNAP_M && best.is_none_or(|(b, _)| d < b) {
                    best = Some((d, cell));
                }
            }
        }
        match best {
            Some((_, cell)) => {
                let p = geom.cell_center(cell);
                Pose2::new(p.x, p.y, pose.theta)
            }
            None => pose,
        }
    }

    fn explore_config(&self) -> ExploreConfig {
        self.config.explore
    }

    /// Runs the configured selector from `pose`.
    fn run_selector<R: rand_core::Rng>(
        &self,
        pose: Pose2,
        map: &SharedMap<N>,
        ws: &mut Workspace<N>,
        rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        let req = DecisionRequest {
            grid: &map.grid,
            trav: &map.trav,
            pose: self.start_pose(map, pose),
            battery_steps: self.battery_steps,
            laser: &self.config.laser,
        };
        let config = self.explore_config();
        let (mut objective, frontier) = ws.parts();
        match self.config.selector {
            SelectorKind::Optimized(method) => {
                let mut s = Optimized::new(method, config, &mut objective);
                self.fill_blacklist(&mut s.blacklist)?;
                s.decide(&req, rng)
            }
            SelectorKind::NearestFrontier => {
                let mut s = NearestFrontier::new(config, &mut objective, frontier);
                self.fill_blacklist(&mut s.blacklist)?;
                s.decide(&req, rng)
            }
            SelectorKind::FrontierUtility => {
                let mut s = FrontierUtility::new(config, &mut objective, frontier);
                s.blacklist_radius_m = BLACKLIST_RADIUS_M;
                for &(p, _) in &self.blacklist {
                    s.blacklist(&map.grid, p)?;
                }
                s.decide(&req, rng)
            }
        }
    }

    /// Plans a path from `pose` through `targets` on the current map.
    fn plan_to(
        &self,
        pose: Pose2,
        targets: &[Point2],
        map: &SharedMap<N>,
        ws: &mut Workspace<N>,
    ) -> Result<heapless::Vec<Point2, MAX_WAYPOINTS>, CandidateStatus> {
        let req = DecisionRequest {
            grid: &map.grid,
            trav: &map.trav,
            pose: self.start_pose(map, pose),
            battery_steps: self.battery_steps,
            laser: &self.config.laser,
        };
        let config = ExploreConfig {
            targets: targets.len().clamp(1, MAX_TARGETS),
            // A replan must only fit the battery, not keep the reserve a new decision keeps.
            reserve_steps: 0.0,
            ..self.config.explore
        };
        let (mut objective, _) = ws.parts();
        objective
            .prepare_plan(&req, &config)
            .map_err(|_| CandidateStatus::Unreachable)?;
        let eval = objective.plan_targets(&req, targets);
        if eval.status != CandidateStatus::Feasible {
            return Err(eval.status);
        }
        let mut out = heapless::Vec::new();
        let _ = out.extend_from_slice(objective.waypoints());
        Ok(out)
    }

    /// Starts following `waypoints`; the first is dropped when the robot already stands on
    /// it.
    fn start_path(&mut self, now: Time, waypoints: &[Point2]) -> bool {
        let tol = self.config.follower.position_tolerance_m;
        let skip = waypoints.len() > 1 && waypoints[0].distance(self.pose_map.position()) <= tol;
        let path = if skip { &waypoints[1..] } else { waypoints };
        if self.follower.set_path(path).is_err() {
            return false;
        }
        self.state = MissionState::Rotating;
        self.last_path.clear();
        self.plan_time = Some(now);
        self.progress_index = usize::MAX;
        self.path_dirty = false;
        self.ack_pending = self.monitor.acknowledge_replan().is_err();
        true
    }

    /// A decision (or the pending go-to goal). Returns whether the robot now has a path (or
    /// the mission ended); `false`: try again next period.
    fn decide<R: rand_core::Rng>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> bool {
        self.yielding = None;
        self.conflict_robot = None;
        // Blacklist entries lapse once the map around them changed.
        self.blacklist
            .retain(|&(p, known)| known_around(&map.grid, p) == known);
        if let Some(goal) = self.goal.take() {
            if now < self.goal_retry_at {
                self.goal = Some(goal);
                return false;
            }
            return match self.plan_to(self.pose_map, &goal, map, ws) {
                Ok(waypoints) => {
                    let length = polyline_length(self.pose_map.position(), &waypoints);
                    let decision = Decision {
                        targets: goal,
                        waypoints,
                        path_length_m: length,
                        predicted_gain_cells: 0,
                        energy_steps: units::steps(length, 0.0),
                        evaluations: 0,
                        history: heapless::Vec::new(),
                    };
                    let ok = self.adopt(now, &decision, events);
                    self.goal_active = true;
                    ok
                }
                Err(_) => {
                    // Another robot in the way: wait for it, with the goal as targets.
                    self.targets.clear();
                    let _ = self.targets.extend_from_slice(&goal);
                    if let Some(other) = self.robot_on_way(map, now) {
                        self.goal_active = true;
                        self.replans_this_decision = 0;
                        self.hold_for(now, other, events);
                        return true;
                    }
                    self.targets.clear();
                    // Retry a little later; after too many failures, explore instead.
                    events.stats.failed_decisions += 1;
                    self.goal_failures += 1;
                    if self.goal_failures < self.config.max_failed_decisions {
                        self.goal = Some(goal);
                        self.goal_retry_at = now + secs(RETRY_S);
                    }
                    false
                }
            };
        }
        // A decision computed ahead, if its path is still clear.
        if let Some(ahead) = self.ahead.take() {
            let mut d = ahead.decision;
            if let Some(first) = d.waypoints.first_mut() {
                *first = self.pose_map.position();
            }
            if first_blocked(
                map,
                self.pose_map.position(),
                &d.waypoints,
                self.clear_radius(),
            )
            .is_none()
            {
                events.stats.decisions_ahead_used += 1;
                return self.adopt(now, &d, events);
            }
        }
        self.goal_active = false;
        let outcome = self.run_selector(self.pose_map, map, ws, rng);
        match outcome {
            Ok(Outcome::Go(d)) => {
                let last = d.targets.last().copied();
                let listed = self.config.selector != SelectorKind::FrontierUtility
                    && last.is_some_and(|t| self.is_blacklisted(t));
                if listed {
                    return self.failed(events);
                }
                events.stats.fitness_evals += u64::from(d.evaluations);
                self.adopt(now, &d, events)
            }
            Ok(Outcome::Done) => {
                self.finish(DoneReason::NothingReachable, events);
                true
            }
            Err(DecideError::NoFeasibleTarget { .. })
                if self.battery_steps - self.config.explore.reserve_steps
                    < self.config.low_battery_steps =>
            {
                self.finish(DoneReason::BatteryExhausted, events);
                true
            }
            Err(DecideError::AllBlacklisted { .. }) => {
                if self.failed_in_row + 1 >= self.config.max_failed_decisions {
                    // Every frontier left is one the robot failed to reach.
                    self.finish(DoneReason::NothingReachable, events);
                    return true;
                }
                self.failed(events)
            }
            Err(_) => self.failed(events),
        }
    }

    /// Counts a failed decision; after too many in a row the mission ends.
    fn failed(&mut self, events: &mut Events<'_>) -> bool {
        events.stats.failed_decisions += 1;
        self.failed_in_row += 1;
        if self.failed_in_row >= self.config.max_failed_decisions {
            let low = self.battery_steps - self.config.explore.reserve_steps
                < self.config.low_battery_steps;
            let reason = if low {
                DoneReason::BatteryExhausted
            } else {
                DoneReason::NothingReachable
            };
            self.finish(reason, events);
            return true;
        }
        self.state = MissionState::Deciding;
        false
    }

    fn adopt(&mut self, now: Time, d: &Decision, events: &mut Events<'_>) -> bool {
        if !self.start_path(now, &d.waypoints) {
            return self.failed(events);
        }
        self.targets.clear();
        let _ = self.targets.extend_from_slice(&d.targets);
        self.last_history.clone_from(&d.history);
        self.replans_this_decision = 0;
        self.failed_in_row = 0;
        events.stats.decisions += 1;
        events.push(MissionEvent::Decided {
            targets: d.targets.clone(),
            path_length_m: d.path_length_m,
            predicted_gain_cells: d.predicted_gain_cells,
            energy_steps: d.energy_steps,
            evaluations: d.evaluations,
        });
        true
    }

    /// The places this mission failed to reach, for a selector to avoid.
    fn fill_blacklist(&self, list: &mut Blacklist) -> Result<(), DecideError> {
        list.radius_m = BLACKLIST_RADIUS_M;
        for &(p, _) in &self.blacklist {
            list.push(p)?;
        }
        Ok(())
    }

    fn is_blacklisted(&self, p: Point2) -> bool {
        self.blacklist
            .iter()
            .any(|&(q, _)| q.distance(p) <= BLACKLIST_RADIUS_M)
    }

    /// Gives up the current targets: blacklists the last one and decides again (a go-to
    /// goal is tried again later instead).
    fn abandon(&mut self, map: &SharedMap<N>, events: &mut Events<'_>) {
        if self.goal_active && !self.targets.is_empty() {
            self.goal = Some(self.targets.clone());
            self.goal_failures += 1;
            if self.goal_failures >= self.config.max_failed_decisions {
                self.goal = None;
            }
        } else if let Some(&t) = self.targets.last() {
            if self.blacklist.is_full() {
                self.blacklist.remove(0);
            }
            let _ = self.blacklist.push((t, known_around(&map.grid, t)));
            events.stats.abandoned_targets += 1;
        }
        self.targets.clear();
        self.follower.clear();
        self.ahead = None;
        self.state = MissionState::Deciding;
    }

    /// Counts one more replan against the current decision; `true` when that is more than
    /// [`MissionConfig::max_replans_per_decision`] and the decision must be dropped. Replans
    /// count only while the robot gets nowhere: one that moved on since the first counted
    /// replan starts a fresh count.
    fn count_replan(&mut self) -> bool {
        let here = self.pose_map.position();
        if self.replans_this_decision == 0 || here.distance(self.replans_from) >= REPLAN_PROGRESS_M
        {
            self.replans_this_decision = 0;
            self.replans_from = here;
        }
        self.replans_this_decision += 1;
        self.replans_this_decision > self.config.max_replans_per_decision
    }

    /// A fresh path to the remaining targets from the current pose.
    fn replan(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N>,
        events: &mut Events<'_>,
    ) {
        if self.targets.is_empty() {
            self.state = MissionState::Deciding;
            return;
        }
        if self.count_replan() {
            self.abandon(map, events);
            return;
        }
        let targets = self.targets.clone();
        match self.plan_to(self.pose_map, &targets, map, ws) {
            Ok(waypoints) if self.start_path(now, &waypoints) => {
                events.stats.replans += 1;
                events.push(MissionEvent::Replanned {
                    cause: self.replan_cause,
                });
                self.conflict_robot = None;
            }
            _ => {
                // No way to the targets. If a robot is what blocks it, wait for it to step
                // aside (a higher id steps aside; a lower id is waited for in the same way,
                // as it will move on); else give the targets up.
                let other = self.conflict_robot.or_else(|| self.robot_on_way(map, now));
                if let Some(other) = other {
                    self.hold_for(now, other, events);
                    return;
                }
                // A target that turned out to be in a wall is not a failure to reach it.
                let geom = *map.trav.geometry();
                let in_wall = self
                    .targets
                    .last()
                    .is_some_and(|&t| !map.trav.is_passable(geom.cell_at_unchecked(t)));
                if in_wall && !self.goal_active {
                    self.targets.clear();
                    self.state = MissionState::Deciding;
                    return;
                }
                self.abandon(map, events);
            }
        }
    }

    fn clear_radius(&self) -> f32 {
        self.config.safety.footprint.radius_m + 0.1
    }

    /// One period of path following; `None` when the state changed.
    fn follow<R: rand_core::Rng>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> Option<MotionCommand> {
        let here = self.pose_map.position();
        // New obstacles across the remaining path (a door that closed, another robot).
        if self.path_dirty {
            self.path_dirty = false;
            let from = self
                .follower
                .current_index()
                .min(self.follower.path().len());
            let remaining = &self.follower.path()[from..];
            if let Some(p) = first_blocked(map, here, remaining, self.clear_radius()) {
                match self.robot_at(map, now, p) {
                    Some(other) => self.begin_conflict(now, other, events),
                    None => self.enter_replanning(ReplanCause::PathBlocked),
                }
                return None;
            }
        }
        // Progress toward the current waypoint.
        let index = self.follower.current_index();
        let dist = self
            .follower
            .current_waypoint()
            .map_or(0.0, |w| w.distance(here));
        if index != self.progress_index || dist < self.progress_best_m - PROGRESS_M {
            self.progress_index = index;
            self.progress_best_m = dist;
            self.progress_time = now;
        } else if now.saturating_since(self.progress_time) > secs(self.config.stuck_timeout_s) {
            self.enter_replanning(ReplanCause::Stuck);
            return None;
        }
        // The next decision, computed ahead near the end of the path.
        if self.config.decide_while_driving
            && self.ahead.is_none()
            && self.goal.is_none()
            && self.state == MissionState::Driving
        {
            let path = self.follower.path();
            let from = self.follower.current_index().min(path.len());
            let remaining = polyline_length(here, &path[from..]);
            if remaining <= self.config.decide_ahead_m && !path.is_empty() {
                let end = path[path.len() - 1];
                let before = if path.len() >= 2 {
                    path[path.len() - 2]
                } else {
                    here
                };
                let heading = if before.distance(end) > 1e-3 {
                    before.bearing_to(end)
                } else {
                    self.pose_map.theta
                };
                let pose = Pose2::new(end.x, end.y, heading);
                if let Ok(Outcome::Go(d)) = self.run_selector(pose, map, ws, rng) {
                    events.stats.decisions_ahead += 1;
                    events.stats.fitness_evals += u64::from(d.evaluations);
                    self.ahead = Some(Ahead { decision: d });
                }
            }
        }
        let (cmd, status) = self.follower.update(now, self.pose_map);
        match status {
            FollowStatus::WaypointReached(i) => {
                self.holds_in_row = 0;
                events.stats.waypoints_reached += 1;
                events.push(MissionEvent::WaypointReached { index: i });
                let w = self.follower.path()[i];
                if self.targets.first().is_some_and(|t| t.distance(w) < 1e-3) {
                    self.targets.remove(0);
                }
            }
            FollowStatus::Arrived => {
                self.holds_in_row = 0;
                let last = self.follower.path().len().saturating_sub(1);
                events.stats.waypoints_reached += 1;
                events.push(MissionEvent::WaypointReached { index: last });
                self.targets.clear();
                self.follower.clear();
                self.state = MissionState::Deciding;
                return None;
            }
            FollowStatus::Rotating => self.state = MissionState::Rotating,
            FollowStatus::Idle => {
                self.state = MissionState::Deciding;
                return None;
            }
            _ => self.state = MissionState::Driving,
        }
        Some(cmd)
    }
}

/// `s` seconds as a duration; negative or NaN gives zero, too large the longest duration.
fn secs(s: f32) -> Duration {
    Duration::try_from_secs_f32(s.max(0.0)).unwrap_or(Duration::MAX)
}

/// Length of the polyline from `from` through `points` \[m\].
fn polyline_length(from: Point2, points: &[Point2]) -> f32 {
    let mut last = from;
    let mut sum = 0.0;
    for &p in points {
        sum += last.distance(p);
        last = p;
    }
    sum
}

/// The first blocked (Occupied or inflated) cell along the path from `here` through
/// `waypoints`, ignoring cells within `clear_radius_m` of the robot (its own surroundings,
/// which the safety monitor watches). Returns the cell's centre.
fn first_blocked<const N: usize>(
    map: &SharedMap<N>,
    here: Point2,
    waypoints: &[Point2],
    clear_radius_m: f32,
) -> Option<Point2> {
    let geom = *map.trav.geometry();
    let mut from = here;
    for &to in waypoints {
        let a = geom.cell_at_unchecked(from);
        let b = geom.cell_at_unchecked(to);
        let mut hit = None;
        supercover(a, b, |c| {
            let centre = geom.cell_center(c);
            if centre.distance(here) <= clear_radius_m || !geom.contains(c) {
                return true;
            }
            if map.trav.is_passable(c) {
                true
            } else {
                hit = Some(centre);
                false
            }
        });
        if hit.is_some() {
            return hit;
        }
        from = to;
    }
    None
}
