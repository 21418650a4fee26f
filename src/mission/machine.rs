//! The per-robot mission state machine (see the [module documentation](super) for the states
//! and transitions).
//!
//! A [`Mission`] is its [`Phase`] (the state, carrying the data only that state has) and a few
//! parts, one concept each:
//! - [`senses`]: what the robot reports (odometry, flags, scans) and the energy used;
//! - [`deciding`]: decisions, go-to goals and the [`Errand`] being driven (its targets and
//!   replans);
//! - [`following`]: driving the path, watching it for new obstacles and for progress;
//! - [`reactions`]: what the mission does when the safety monitor intervenes, the escape
//!   manoeuvre included;
//! - [`robots`]: what concerns several robots on one map.

use core::time::Duration;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::{Controller, WaypointFollower};
use crate::control::safety::{RobotFlags, SafetyInputs, SafetyMonitor, SafetyState};
use crate::explore::{Blacklist, Decision, MAX_DECISION_HISTORY, MAX_MOUTHS, MAX_TARGETS};
use crate::geometry::{Point2, Pose2};
use crate::planner::Planner;
use crate::sensor::{Scan, integrate_scan_banded};

use super::shared::{SharedMap, Workspace};
use super::{
    DoneReason, FaultReason, MAX_EVENTS, MissionConfig, MissionError, MissionEvent, MissionState,
    MissionStats, ReplanCause, StepOutput, footprint,
};

mod deciding;
mod following;
mod look_around;
mod progress;
mod reactions;
mod robots;
mod senses;

use deciding::{Errand, GoalRequest};
use following::PathWatch;
use look_around::LookAround;
use progress::ProgressWatch;
use reactions::{Escape, Holds};
use robots::Yield;
use senses::Senses;

/// A robot waiting for another to step aside retries its plan this often \[s\].
const RETRY_S: f32 = 1.0;
/// Bumper contacts remembered.
const MAX_CONTACTS: usize = 16;

/// What the mission is doing, with the data of that state. [`MissionState`] is its public
/// face.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Waiting for the first odometry and scan.
    Starting,
    /// About to decide where to go.
    Deciding,
    /// Following the path, turning in place toward a waypoint.
    Rotating,
    /// Following the path, driving toward a waypoint.
    Driving,
    /// About to plan a fresh path to the errand's remaining targets.
    Replanning,
    /// Driving or turning out of a place where the plans keep being refused, then replanning
    /// (reported as [`MissionState::Replanning`]).
    Escaping(Escape),
    /// Waiting for, or stepping out of the way of, another robot.
    Yielding(Yield),
    /// Turning in place before the first decision ([`MissionConfig::look_around`]; reported
    /// as [`MissionState::Rotating`]).
    LookingAround(LookAround),
    /// Finished.
    Done(DoneReason),
    /// Stopped by a fault.
    Fault(FaultReason),
}

impl Phase {
    fn public(self) -> MissionState {
        match self {
            Phase::Starting => MissionState::Starting,
            Phase::Deciding => MissionState::Deciding,
            Phase::Rotating | Phase::LookingAround(_) => MissionState::Rotating,
            Phase::Driving => MissionState::Driving,
            Phase::Replanning | Phase::Escaping(_) => MissionState::Replanning,
            Phase::Yielding(_) => MissionState::Yielding,
            Phase::Done(reason) => MissionState::Done(reason),
            Phase::Fault(reason) => MissionState::Fault(reason),
        }
    }

    /// Following a path (or about to plan one) for the errand.
    fn is_running(self) -> bool {
        matches!(
            self,
            Phase::Rotating | Phase::Driving | Phase::Replanning | Phase::Escaping(_)
        )
    }
}

/// One robot's mission.
pub struct Mission<const N: usize> {
    id: u8,
    config: MissionConfig,
    phase: Phase,
    senses: Senses,
    follower: WaypointFollower,
    monitor: SafetyMonitor,
    stats: MissionStats,
    /// The decision being driven.
    errand: Errand,
    /// Targets given by [`Mission::go_to`], planned at the next decision.
    goal: GoalRequest,
    /// Decisions in a row that failed.
    failed_in_row: u32,
    /// The latest decision found frontier to go to (whatever became of it).
    frontier_left: bool,
    /// After a failed decision, the next one waits until this time (see `failed`).
    decide_at: Time,
    /// Errands dropped in a row while the robot got nowhere (less than 1 m from where the
    /// first of them was dropped), and that place: a robot that cannot get anywhere, whatever
    /// it chooses, ends the mission instead of choosing again for ever.
    abandoned_in_row: (u32, Point2),
    /// Optimizer decisions in a row that chose the place of the one before while the map
    /// around it stayed the same (nothing gained in between), that place, and the known cells
    /// around it then: a target whose predicted gain never comes is blacklisted after
    /// `max_failed_decisions` of them instead of being chosen for ever.
    idle_repeats: (u32, Point2, u32),
    /// Places this robot failed to reach.
    blacklist: Blacklist,
    /// Mouths of passages shut on the map that this robot went to look through
    /// ([`crate::explore::shut_mouth`]).
    mouths_looked: heapless::Vec<Point2, MAX_MOUTHS>,
    /// A decision computed ahead, from the end of the current path.
    ahead: Option<Decision>,
    /// Best fitness per generation of the last decision adopted.
    last_history: heapless::Vec<f32, MAX_DECISION_HISTORY>,
    /// The path being followed: when it was planned and whether it is still clear.
    watch: PathWatch,
    /// Obstacle holds in a row without progress.
    holds: Holds,
    /// Where the bumpers found something (a segment across the bumper, map frame) and until
    /// when it is remembered: obstacles the laser may not see (glass, low objects).
    contacts: heapless::Deque<(Point2, Point2, Time), MAX_CONTACTS>,
    last_step: Option<Time>,
    localizer: crate::localize::Tracker,
    /// The battery-voltage watch ([`MissionConfig::voltage`]).
    voltage: super::VoltageWatch,
    /// An end asked for by [`Mission::end`], taken at the next step.
    end_request: Option<DoneReason>,
    /// The mission has ended for this reason and drives back to the start position
    /// ([`MissionConfig::return_to_start`]).
    homing: Option<DoneReason>,
    /// Which scans are mapped ([`MissionConfig::motion_filter`]).
    motion_filter: super::motion_filter::MotionFilter,
    /// Whether the last scan given to [`Self::on_scan`] was integrated into the map.
    last_scan_mapped: bool,
    /// Where the robot last made progress ([`MissionConfig::progress_timeout_s`]).
    progress: ProgressWatch,
}

impl<const N: usize> core::fmt::Debug for Mission<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Mission")
            .field("id", &self.id)
            .field("phase", &self.phase)
            .field("pose_map", &self.senses.pose_map)
            .field("battery_steps", &self.senses.battery_steps)
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
            phase: Phase::Starting,
            senses: Senses::new(start_map, config.battery_steps),
            follower,
            monitor,
            stats: MissionStats::default(),
            errand: Errand::new(),
            goal: GoalRequest::default(),
            failed_in_row: 0,
            frontier_left: false,
            decide_at: Time::ZERO,
            abandoned_in_row: (0, start_map.position()),
            idle_repeats: (0, start_map.position(), 0),
            blacklist: Blacklist::default(),
            mouths_looked: heapless::Vec::new(),
            ahead: None,
            last_history: heapless::Vec::new(),
            watch: PathWatch::new(),
            holds: Holds::new(start_map.position()),
            contacts: heapless::Deque::new(),
            last_step: None,
            localizer: crate::localize::Tracker::new(),
            voltage: super::VoltageWatch::new(),
            end_request: None,
            homing: None,
            motion_filter: super::motion_filter::MotionFilter::new(),
            last_scan_mapped: false,
            progress: ProgressWatch::default(),
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
        self.senses
            .on_odometry(now, pose_odom, flags, &mut self.stats);
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
            &map.hits,
            &mut map.matcher,
            scan,
            &self.config.laser,
            self.senses.pose_odom,
            &mut self.senses.map_from_odom,
            &mut self.senses.pose_map,
        );
        if !self.admit_to_map(now, self.senses.pose_map, scan) {
            return self.publish(now, map);
        }
        if self.localizer.grids_scan(&self.config.localize) {
            integrate_scan_banded(
                &mut map.grid,
                scan,
                self.senses.pose_map,
                self.localizer.wall_band_m(&self.config.localize),
                &self.config.laser,
                &self.config.map_sensor(),
                &mut map.trav,
            )
            .map_err(MissionError::Sensor)?;
        }
        if self.config.localize.enabled {
            let graph = &self.config.localize.graph;
            if self.localizer.maps_scan(&self.config.localize)
                && !(graph.enabled && graph.reference_keyframes_only)
            {
                map.hits.add_scan_capped(
                    scan,
                    &self.config.laser,
                    self.senses.pose_map,
                    self.config.localize.max_cell_weight,
                );
            }
            self.keyframe_graph(scan, map)?;
        }
        self.clear_own_trail(map);
        self.senses.on_scan(now, scan, true);
        self.watch.path_dirty = true;
        self.publish(now, map)
    }

    /// With the localisation's pose graph on ([`crate::localize::graph`]): keeps keyframes,
    /// closes loops, and after an optimisation that moved the keyframes draws the grid and
    /// the returns layer again from them and moves the estimate with the last keyframe.
    fn keyframe_graph(&mut self, scan: &Scan, map: &mut SharedMap<N>) -> Result<(), MissionError> {
        let loc = &self.config.localize;
        if !loc.graph.enabled {
            return Ok(());
        }
        let keyframes = map.graph.keyframes().len();
        let Some(moved) = map.graph.on_scan(
            &loc.graph,
            &loc.matcher,
            scan,
            &self.config.laser,
            &self.config.map_sensor(),
            map.grid.bounds(),
            map.grid.geometry().resolution_m,
            self.senses.pose_map,
            &mut map.matcher,
        ) else {
            if loc.graph.reference_keyframes_only && map.graph.keyframes().len() > keyframes {
                map.hits
                    .add_scan(scan, &self.config.laser, self.senses.pose_map);
            }
            return Ok(());
        };
        let keep = loc
            .graph
            .redraw_keeps_unseen
            .then_some(&mut map.known_before_redraw[..]);
        map.graph
            .redraw(
                &mut map.grid,
                &mut map.hits,
                self.localizer.wall_band_m(&self.config.localize),
                &self.config.laser,
                &self.config.map_sensor(),
                keep,
            )
            .map_err(MissionError::Sensor)?;
        map.rebuild_traversability()?;
        let pose = moved.apply(self.senses.pose_map);
        self.senses.pose_map = pose;
        if self.senses.map_from_odom.is_some() {
            self.senses.map_from_odom = Some(crate::control::odometry::MapFromOdom::from_start(
                pose,
                self.senses.pose_odom,
            ));
        }
        Ok(())
    }

    /// A scan read after a later odometry reading than its own time (a real-time pump that
    /// reads the laser late): integrated at `pose_odom`, the odometry pose of the scan's
    /// time, mapped with the mission's odometry-to-map transform, while the robot's pose,
    /// battery and distance stay those of the latest reading. Handing such a scan in through
    /// [`Self::on_odometry`] and [`Self::on_scan`] would move the robot back to the scan's
    /// pose and forward again, each time charging the way twice. With
    /// [`MissionConfig::localize`] on, the scan is matched at `pose_odom` (its own time's
    /// odometry, not the latest): a trusted match corrects the map-from-odometry transform,
    /// which is rigid, so the correction found at the scan's pose carries to the latest one
    /// (the robot's pose is recomputed from the latest odometry with it). Before the first
    /// odometry reading it is [`Self::on_scan`].
    ///
    /// Errors: as [`Self::on_scan`].
    pub fn on_late_scan(
        &mut self,
        now: Time,
        scan: &Scan,
        pose_odom: Pose2,
        map: &mut SharedMap<N>,
    ) -> Result<(), MissionError> {
        let Some(mut transform) = self.senses.map_from_odom else {
            return self.on_scan(now, scan, map);
        };
        if self
            .localizer
            .on_scan(
                &self.config.localize,
                &map.grid,
                &map.hits,
                &mut map.matcher,
                scan,
                &self.config.laser,
                pose_odom,
                &mut transform,
            )
            .is_some()
        {
            self.senses.map_from_odom = Some(transform);
            self.senses.pose_map = transform.map_pose(self.senses.pose_odom);
        }
        let pose = transform.map_pose(pose_odom);
        if !self.admit_to_map(now, pose, scan) {
            return self.publish(now, map);
        }
        integrate_scan_banded(
            &mut map.grid,
            scan,
            pose,
            self.localizer.wall_band_m(&self.config.localize),
            &self.config.laser,
            &self.config.map_sensor(),
            &mut map.trav,
        )
        .map_err(MissionError::Sensor)?;
        if self.config.localize.enabled {
            map.hits.add_scan(scan, &self.config.laser, pose);
        }
        self.clear_own_trail(map);
        self.senses.on_scan(now, scan, true);
        self.watch.path_dirty = true;
        self.publish(now, map)
    }

    /// Whether a scan taken at `now` from `pose` goes into the map
    /// ([`MissionConfig::motion_filter`]), remembered for [`Self::last_scan_mapped`]. A scan
    /// held back leaves the map (and so this robot's path) as it was; the safety monitor still
    /// sees it.
    fn admit_to_map(&mut self, now: Time, pose: Pose2, scan: &Scan) -> bool {
        self.last_scan_mapped = self
            .motion_filter
            .admit(&self.config.motion_filter, now, pose);
        if !self.last_scan_mapped {
            self.senses.on_scan(now, scan, false);
        }
        self.last_scan_mapped
    }

    /// Whether the last scan given to [`Self::on_scan`] or [`Self::on_late_scan`] went into
    /// the map: `false` when the
    /// motion filter ([`MissionConfig::motion_filter`]) held it back.
    pub fn last_scan_mapped(&self) -> bool {
        self.last_scan_mapped
    }

    /// A scan the caller does not trust for mapping (taken while the robot turned fast, when
    /// a small error in the scan's time puts its walls in the wrong place): it keeps the
    /// safety monitor's view fresh, and nothing else.
    pub fn on_scan_unmapped(&mut self, now: Time, scan: &Scan) {
        self.senses.on_scan(now, scan, false);
    }

    /// Coverage measured by the caller (0..=1); the mission is done once it reaches the
    /// target. Without it the mission ends only when nothing reachable is unknown or the
    /// battery is out.
    pub fn set_coverage(&mut self, coverage: f32) {
        if coverage.is_finite() {
            self.senses.coverage = Some(coverage);
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
        self.goal.set(targets);
        match self.phase {
            Phase::Rotating | Phase::Driving | Phase::Replanning => {
                self.follower.clear();
                self.phase = Phase::Deciding;
            }
            // The escape finishes first; the goal is planned at the next decision.
            Phase::Escaping(_) => self.follower.clear(),
            _ => {}
        }
        Ok(())
    }

    /// The battery voltage the robot reports at `now` \[V\] (every status packet): the
    /// mission ends with [`DoneReason::VoltageLow`] once it stays low
    /// ([`MissionConfig::voltage`]). Returns `true` at the reading that trips the watch, so
    /// that the caller can log it.
    pub fn on_battery_voltage(&mut self, now: Time, volts: f32) -> bool {
        self.voltage.update(&self.config.voltage, now, volts)
    }

    /// The battery-voltage watch (latest reading, tripped).
    pub fn voltage(&self) -> &super::VoltageWatch {
        &self.voltage
    }

    /// Ends the mission for `reason` at the next step (after driving back to the start with
    /// [`MissionConfig::return_to_start`]). Ignored once the mission is done or returning.
    pub fn end(&mut self, reason: DoneReason) {
        if self.homing.is_none() && !matches!(self.phase, Phase::Done(_)) {
            self.end_request.get_or_insert(reason);
        }
    }

    /// Why the mission ended, while it drives back to its start position.
    pub fn returning(&self) -> Option<DoneReason> {
        self.homing
    }

    /// The start pose (map frame).
    pub fn start_pose_map(&self) -> Pose2 {
        self.senses.start_map
    }

    /// What the mission is doing.
    pub fn state(&self) -> MissionState {
        self.phase.public()
    }

    /// The current map-frame pose estimate.
    pub fn pose_map(&self) -> Pose2 {
        self.senses.pose_map
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
        &self.errand.targets
    }

    /// Counters.
    pub fn stats(&self) -> &MissionStats {
        &self.stats
    }

    /// Energy left \[steps\].
    pub fn battery_steps(&self) -> f32 {
        self.senses.battery_steps
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
    pub fn step<R: rand_core::Rng, P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
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
        if self.watch.ack_pending && self.monitor.acknowledge_replan().is_ok() {
            self.watch.ack_pending = false;
        }

        // The robot's own body, as other robots' scans put it on the map, must not block its
        // own plans, and the robots near it block them wherever the scans have got to: both
        // for the decisions of this period, then the cells are put back.
        let area = self.stamp_area(map, now);
        let saved = ws.stamp_window().save(map, area);
        let mut lifted = self.lift_own_body(map);
        self.stamp_others(map, now, &mut lifted);
        let mut proposed = self.run(now, map, ws, rng, &mut events);
        // Slow through narrow places; and what the map knows around the body (its own body
        // still lifted, the robots near it stamped), for turns and back-offs the laser cannot
        // see.
        if let Some(cap) = footprint::narrow_speed_cap(&map.trav, self.senses.pose_map) {
            proposed.speed_mm_s = proposed.speed_mm_s.clamp(-cap, cap);
        }
        // Slow down rather than be stopped: a return the safety monitor would stop for at
        // this speed but not at the creep speed (a frame beside the body in a door, a wall
        // ahead of a waypoint near it) brings the speed down to the creep speed.
        if self.senses.scan_time.is_some() {
            proposed = footprint::creep_near_obstacles(
                &self.monitor,
                proposed,
                &self.senses.scan,
                &self.config.laser,
            );
        }
        let remembered = self.remembered_around(map);
        if saved {
            ws.stamp_window().restore(map);
        } else {
            for &(i, value) in lifted.iter().rev() {
                map.grid.set_log_odds(i, value, &mut map.trav);
            }
        }

        let s = &self.senses;
        let inputs = SafetyInputs {
            pose_odom: s.pose_odom,
            odometry_time: s.odometry_time,
            scan: s.scan_time.map(|_| &s.scan),
            scan_time: s.scan_time,
            laser: &self.config.laser,
            flags: s.flags,
            remembered: &remembered,
        };
        let (command, safety) = self.monitor.filter(now, proposed, &inputs);
        if let Some(event) = safety {
            self.on_safety(now, event, map, &mut events);
        }
        let moving = command
            .velocity()
            .is_some_and(|v| v.as_motion() != MotionCommand::ZERO);
        if !moving && !matches!(self.phase, Phase::Done(_)) {
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
    fn run<R: rand_core::Rng, P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> MotionCommand {
        if let Phase::Done(_) = self.phase {
            return MotionCommand::ZERO;
        }
        if self.phase == Phase::Starting {
            if !self.senses.ready() {
                return MotionCommand::ZERO;
            }
            self.phase = self.after_start(now);
        }
        // Faults first: zero velocity, forget the path.
        if let Some(reason) = self.senses.fault_now(now, self.config.safety.max_input_age) {
            if self.phase != Phase::Fault(reason) {
                if !matches!(self.phase, Phase::Fault(_)) {
                    events.stats.faults += 1;
                }
                events.push(MissionEvent::Fault(reason));
                self.phase = Phase::Fault(reason);
            }
            self.follower.clear();
            self.ahead = None;
            self.watch.ack_pending = false;
            self.progress.reset();
            return MotionCommand::ZERO;
        }
        if let Phase::Fault(_) = self.phase {
            events.push(MissionEvent::FaultCleared);
            self.enter_replanning(ReplanCause::FaultCleared);
        }
        // The end of the mission (on the way back to the start it has ended already).
        if self.homing.is_none() {
            if self.voltage.tripped() {
                return self.finish(DoneReason::VoltageLow, events);
            }
            if let Some(reason) = self.end_request.take() {
                return self.finish(reason, events);
            }
            if self.senses.battery_steps <= self.config.explore.reserve_steps {
                return self.finish(DoneReason::BatteryExhausted, events);
            }
            if self
                .senses
                .coverage
                .is_some_and(|c| c >= self.config.coverage_target)
            {
                return self.finish(DoneReason::CoverageReached, events);
            }
        }
        // A robot that gets nowhere, whatever it does, ends the mission.
        if let Phase::Yielding(_) = self.phase {
            self.progress.reset();
        } else if self.progress.stalled(
            now,
            self.senses.pose_odom.position(),
            self.config.progress_distance_m,
            secs(self.config.progress_timeout_s),
        ) {
            self.progress.reset();
            return self.finish(DoneReason::Stuck, events);
        }
        if let Phase::Escaping(escape) = self.phase
            && let Some(cmd) = self.escape_step(now, escape, map)
        {
            return cmd;
        }
        if let Phase::LookingAround(look) = self.phase
            && let Some(cmd) = self.look_around_step(now, look)
        {
            return cmd;
        }
        // Up to a few transitions in one period, so that arriving and deciding, or replanning
        // and driving, do not cost a period each.
        for _ in 0..4 {
            match self.phase {
                Phase::Deciding => {
                    if !self.decide(now, map, ws, rng, events) {
                        return MotionCommand::ZERO;
                    }
                }
                Phase::Replanning => {
                    if matches!(self.monitor.state(), SafetyState::BackingOff { .. }) {
                        return MotionCommand::ZERO;
                    }
                    self.replan(now, map, ws, events);
                }
                Phase::Yielding(y) => match self.yield_step(now, y, map, ws, events) {
                    Some(cmd) => return cmd,
                    None => continue,
                },
                Phase::Rotating | Phase::Driving => match self.follow(now, map, ws, rng, events) {
                    Some(cmd) => return cmd,
                    None => continue,
                },
                _ => return MotionCommand::ZERO,
            }
        }
        MotionCommand::ZERO
    }

    /// Ends the mission for `reason`; with [`MissionConfig::return_to_start`] (and the robot
    /// away from its start), first drives back: the start becomes a go-to goal and the
    /// mission decides again (the caller's loop plans it in this period when it can).
    fn finish(&mut self, reason: DoneReason, events: &mut Events<'_>) -> MotionCommand {
        let start = self.senses.start_map.position();
        let away = self.senses.pose_map.position().distance(start)
            > self.config.follower.position_tolerance_m;
        let reason = match self.homing {
            // The way back ended (there, or given up): the end is the one that sent it back.
            Some(first) => first,
            None if self.config.return_to_start && away => {
                self.homing = Some(reason);
                self.end_request = None;
                self.follower.clear();
                self.errand.targets.clear();
                self.ahead = None;
                self.goal.set(&[start]);
                self.phase = Phase::Deciding;
                events.push(MissionEvent::Returning(reason));
                return MotionCommand::ZERO;
            }
            None => reason,
        };
        self.homing = None;
        self.phase = Phase::Done(reason);
        self.follower.clear();
        self.errand.targets.clear();
        self.ahead = None;
        events.push(MissionEvent::Done(reason));
        MotionCommand::ZERO
    }

    /// The map's Occupied cells around the robot that a turn in place or a back-off could run
    /// into, in the base frame, for the safety monitor ([`SafetyInputs::remembered`]): out to
    /// the corners of the corridor it watches when backing at the fastest backing speed the
    /// mission commands (the escape, the monitor's own back-off, the follower's back-up).
    fn remembered_around(
        &self,
        map: &SharedMap<N>,
    ) -> heapless::Vec<Point2, { footprint::MAX_REMEMBERED }> {
        let backing_mm_s = reactions::ESCAPE_SPEED_MM_S
            .max(self.config.safety.backoff_speed_mm_s.saturating_abs())
            .max(self.config.follower.backup_speed_mm_s as i16);
        let mut remembered = heapless::Vec::new();
        footprint::remembered_obstacles(
            &map.grid,
            self.senses.pose_map,
            self.monitor.remembered_reach_m(backing_mm_s),
            &mut remembered,
        );
        remembered
    }

    fn enter_replanning(&mut self, cause: ReplanCause) {
        self.remember_path();
        self.follower.clear();
        self.ahead = None;
        self.errand.replan_cause = cause;
        self.phase = Phase::Replanning;
    }
}

/// `s` seconds as a duration; negative or NaN gives zero, too large the longest duration.
fn secs(s: f32) -> Duration {
    Duration::try_from_secs_f32(s.max(0.0)).unwrap_or(Duration::MAX)
}
