//! Deciding where to go: the configured selector (or a pending go-to goal), the errand that
//! a decision starts, and giving an errand up.

use crate::control::Time;
use crate::control::follower::{Controller, MAX_WAYPOINTS};
use crate::explore::{
    CandidateStatus, DecideError, Decision, DecisionRequest, ExploreConfig, FrontierUtility,
    MAX_TARGETS, NearestFrontier, Optimized, Outcome, TargetSelector,
};
use crate::geometry::{Point2, Pose2};
use crate::grid::Cell;
use crate::math;
use crate::planner::Planner;
use crate::units;

use super::super::shared::{MAX_SHARED_WAYPOINTS, SharedMap, Workspace};
use super::super::{DoneReason, MissionEvent, ReplanCause, SelectorKind};
use super::following::{first_blocked, polyline_length};
use super::{Events, Mission, Phase, RETRY_S, secs};

/// The energy a plan back to the start may use \[steps\]: the way back is not limited by the
/// budget (it is what the reserve is for).
const HOMING_BUDGET_STEPS: f32 = 1.0e6;
/// Search for a passable start cell up to this far from the robot \[m\].
const START_SNAP_M: f32 = 0.6;
/// A robot that moved this far since the first replan counted against its errand has made
/// progress: its replans count afresh \[m\].
const REPLAN_PROGRESS_M: f32 = 1.0;

/// The decision being driven: the targets still to reach and what driving to them has cost.
#[derive(Clone, Debug)]
pub(super) struct Errand {
    /// Targets still to reach, in order.
    pub(super) targets: heapless::Vec<Point2, MAX_TARGETS>,
    /// The targets came from [`Mission::go_to`].
    pub(super) from_goal: bool,
    /// Replans counted against this errand, without progress.
    pub(super) replans: u32,
    /// Where the robot stood at the first of them.
    pub(super) replans_from: Point2,
    /// Why the path was last planned again.
    pub(super) replan_cause: ReplanCause,
    /// A robot involved in the conflict being resolved.
    pub(super) conflict: Option<u8>,
    /// The remaining waypoints of the last path given up (for telling whether a robot is in
    /// the way, and for publishing while the robot holds).
    pub(super) last_path: heapless::Vec<Point2, MAX_SHARED_WAYPOINTS>,
}

impl Errand {
    pub(super) fn new() -> Self {
        Self {
            targets: heapless::Vec::new(),
            from_goal: false,
            replans: 0,
            replans_from: Point2::new(0.0, 0.0),
            replan_cause: ReplanCause::ObstacleAhead,
            conflict: None,
            last_path: heapless::Vec::new(),
        }
    }
}

/// Targets given by [`Mission::go_to`], waiting for the next decision.
#[derive(Clone, Debug, Default)]
pub(super) struct GoalRequest {
    targets: Option<heapless::Vec<Point2, MAX_TARGETS>>,
    failures: u32,
    retry_at: Time,
}

impl GoalRequest {
    /// A fresh goal (at most [`MAX_TARGETS`] targets, checked by the caller).
    pub(super) fn set(&mut self, targets: &[Point2]) {
        let mut goal = heapless::Vec::new();
        let _ = goal.extend_from_slice(targets);
        self.targets = Some(goal);
        self.failures = 0;
        self.retry_at = Time::ZERO;
    }

    pub(super) fn is_pending(&self) -> bool {
        self.targets.is_some()
    }
}

impl<const N: usize> Mission<N> {
    /// A decision (or the pending go-to goal). Returns whether the robot now has a path (or
    /// the mission ended); `false`: try again next period.
    pub(super) fn decide<R: rand_core::Rng, P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> bool {
        self.errand.conflict = None;
        // Blacklist entries lapse once the map around them changed.
        self.blacklist.forget_changed(&map.grid);
        if let Some(goal) = self.goal.targets.take() {
            return self.decide_goal(now, goal, map, ws, events);
        }
        if let Some(reason) = self.homing {
            // Back at the start, or the way back was given up: the mission ends.
            self.finish(reason, events);
            return true;
        }
        if now < self.decide_at {
            // The last decision failed: wait for fresh scans before the next.
            return false;
        }
        // A decision computed ahead, if its path is still clear.
        if let Some(mut d) = self.ahead.take() {
            let here = self.senses.pose_map.position();
            if let Some(first) = d.waypoints.first_mut() {
                *first = here;
            }
            if first_blocked(map, here, &d.waypoints, self.clear_radius()).is_none() {
                events.stats.decisions_ahead_used += 1;
                return self.adopt(now, &d, events);
            }
        }
        self.errand.from_goal = false;
        let outcome = self.run_selector(self.senses.pose_map, map, ws, rng);
        // Whether this decision saw frontier it could reach (it ends "nothing reachable" only
        // if not).
        self.frontier_left = matches!(
            outcome,
            Ok(Outcome::Go(_)) | Err(DecideError::AllBlacklisted { .. })
        );
        match outcome {
            Ok(Outcome::Go(d)) => {
                let last = d.targets.last().copied();
                let listed = self.config.selector != SelectorKind::FrontierUtility
                    && last.is_some_and(|t| self.blacklist.contains(t));
                if listed {
                    return self.failed(now, events);
                }
                if let Some(t) = last
                    && self.gains_nothing_again(map, t)
                {
                    // Chosen again and again from a map that its arrival does not change:
                    // its predicted gain is not to be had (cells seen through a wall's gap
                    // the laser's noise leaves, say). Listed until the map around it changes.
                    self.blacklist.push_forgetting_oldest(&map.grid, t);
                    events.stats.abandoned_targets += 1;
                    self.idle_repeats.0 = 0;
                    return self.failed(now, events);
                }
                events.stats.fitness_evals += u64::from(d.evaluations);
                self.adopt(now, &d, events)
            }
            Ok(Outcome::Done) => {
                // No frontier reachable from here on this map. One look can be wrong: a return
                // the safety monitor just stopped for, or the robot standing in a wall's band,
                // can cut it off for a moment, and fresh scans clear that. Ended only after
                // `max_failed_decisions` such looks in a row (as `failed` counts them).
                self.forget_contacts();
                // A passage the robot looked through may be shut on the map only: look
                // through it again from close by, once per passage.
                if let Some(decided) = self.look_at_shut_mouth(now, map, ws, events) {
                    return decided;
                }
                self.failed(now, events)
            }
            Err(DecideError::NoFeasibleTarget { .. }) if self.battery_low() => {
                self.finish(DoneReason::BatteryExhausted, events);
                true
            }
            Err(DecideError::AllBlacklisted { .. }) => {
                self.forget_contacts();
                if self.failed_in_row + 1 >= self.config.max_failed_decisions {
                    // Every frontier left is one the robot failed to reach: reachable on
                    // the map, but the robot does not get there.
                    self.finish(DoneReason::Stuck, events);
                    return true;
                }
                self.failed(now, events)
            }
            Err(_) => self.failed(now, events),
        }
    }

    /// The pending go-to goal as the next errand, once its retry time has come.
    fn decide_goal<P: Planner<N>>(
        &mut self,
        now: Time,
        goal: heapless::Vec<Point2, MAX_TARGETS>,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        events: &mut Events<'_>,
    ) -> bool {
        if now < self.goal.retry_at {
            self.goal.targets = Some(goal);
            return false;
        }
        match self.plan_to(self.senses.pose_map, &goal, map, ws) {
            Ok(waypoints) => {
                let decision = self.errand_decision(goal, waypoints);
                let ok = self.adopt(now, &decision, events);
                self.errand.from_goal = true;
                ok
            }
            Err(_) => {
                // Another robot in the way: wait for it, with the goal as targets.
                self.errand.targets.clear();
                let _ = self.errand.targets.extend_from_slice(&goal);
                if let Some(other) = self.robot_on_way(map, now) {
                    self.errand.from_goal = true;
                    self.errand.replans = 0;
                    self.hold_for(now, other, events);
                    return true;
                }
                self.errand.targets.clear();
                // Retry a little later; after too many failures, explore instead.
                events.stats.failed_decisions += 1;
                self.goal.failures += 1;
                if self.goal.failures < self.config.max_failed_decisions {
                    self.goal.targets = Some(goal);
                    self.goal.retry_at = now + secs(RETRY_S);
                }
                false
            }
        }
    }

    /// When no frontier is reachable: an errand to the mouth of the nearest passage open in
    /// Free cells but shut in the planning layer that the robot has not looked from yet
    /// ([`crate::explore::shut_mouth`]), with the distance field the selector just swept from
    /// the robot. `None`: no such mouth (or no path to it); else what adopting the errand
    /// returned (`false`: the failure is counted already).
    fn look_at_shut_mouth<P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        events: &mut Events<'_>,
    ) -> Option<bool> {
        if self.mouths_looked.is_full() || self.battery_low() {
            return None;
        }
        let (field, search) = ws.mouth_parts();
        let found = search.find(&map.grid, &map.trav, field, &self.mouths_looked)?;
        let geom = *map.grid.geometry();
        let mouth = geom.cell_center(found.stand);
        // Remembered whether or not the robot gets there: it is not chosen again.
        let _ = self.mouths_looked.push(mouth);
        let waypoints = self.plan_to(self.senses.pose_map, &[mouth], map, ws).ok()?;
        // The passage's walls are decided again by the scans of the way there and the look.
        crate::explore::shut_mouth::doubt_walls(
            &mut map.grid,
            geom.cell_center(found.mouth),
            crate::explore::shut_mouth::DOUBT_RADIUS_M,
            self.config.sensor.occupied_log_odds,
            &mut map.trav,
        );
        let mut targets = heapless::Vec::new();
        let _ = targets.push(mouth);
        let decision = self.errand_decision(targets, waypoints);
        let adopted = self.adopt(now, &decision, events);
        if adopted {
            events.stats.mouth_looks += 1;
        }
        Some(adopted)
    }

    /// An errand the optimizer did not choose (a go-to goal, a look from a passage's mouth):
    /// its route from where the robot is, priced in energy steps, with no predicted gain.
    fn errand_decision(
        &self,
        targets: heapless::Vec<Point2, MAX_TARGETS>,
        waypoints: heapless::Vec<Point2, MAX_WAYPOINTS>,
    ) -> Decision {
        let length = polyline_length(self.senses.pose_map.position(), &waypoints);
        Decision {
            targets,
            waypoints,
            path_length_m: length,
            predicted_gain_cells: 0,
            energy_steps: units::steps(length, 0.0),
            evaluations: 0,
            history: heapless::Vec::new(),
        }
    }

    /// Whether target `t`, just chosen by the selector, repeats the previous choice with the
    /// map around it unchanged for the `max_failed_decisions`-th time in a row.
    fn gains_nothing_again(&mut self, map: &SharedMap<N>, t: Point2) -> bool {
        let known = crate::explore::blacklist::known_around(&map.grid, t);
        let (count, place, known_then) = &mut self.idle_repeats;
        if *count > 0
            && place.distance(t) <= self.blacklist.radius_m
            && !crate::explore::blacklist::changed_around(*known_then, known)
        {
            *count += 1;
        } else {
            *count = 1;
            *place = t;
            *known_then = known;
        }
        *count > self.config.max_failed_decisions
    }

    /// Too little energy above the reserve to insist on a decision.
    fn battery_low(&self) -> bool {
        self.senses.battery_steps - self.config.explore.reserve_steps
            < self.config.low_battery_steps
    }

    /// Counts a failed decision; after too many in a row the mission ends. The next decision
    /// waits [`RETRY_S`]: a failure read from a map that fresh scans may change (a return the
    /// safety monitor just stopped for cutting the robot off, a band it stands in) is looked
    /// at again on a later map, not on the same one every period.
    fn failed(&mut self, now: Time, events: &mut Events<'_>) -> bool {
        events.stats.failed_decisions += 1;
        self.failed_in_row += 1;
        self.decide_at = now + secs(RETRY_S);
        if self.failed_in_row >= self.config.max_failed_decisions {
            let reason = if self.battery_low() {
                DoneReason::BatteryExhausted
            } else if self.frontier_left {
                // The last decision had frontier to go to and could not start there.
                DoneReason::Stuck
            } else {
                DoneReason::NothingReachable
            };
            self.finish(reason, events);
            return true;
        }
        self.phase = Phase::Deciding;
        false
    }

    /// Forgets the bumper contacts remembered across the bumper's width (the grid keeps the
    /// cell each contact marked): stamped into every decision's map for two minutes, a
    /// contact beside a wall can shut a corridor, and a mission must not end "nothing
    /// reachable" for a mark that is not in its map.
    fn forget_contacts(&mut self) {
        self.contacts.clear();
    }

    /// Starts driving decision `d`: its targets become the errand.
    fn adopt(&mut self, now: Time, d: &Decision, events: &mut Events<'_>) -> bool {
        if !self.start_path(now, &d.waypoints) {
            return self.failed(now, events);
        }
        self.errand.targets.clear();
        let _ = self.errand.targets.extend_from_slice(&d.targets);
        self.last_history.clone_from(&d.history);
        self.errand.replans = 0;
        self.failed_in_row = 0;
        events.stats.decisions += 1;
        let here = self.senses.pose_map.position();
        if here.distance(self.abandoned_in_row.1) >= REPLAN_PROGRESS_M {
            self.abandoned_in_row.0 = 0;
        }
        events.push(MissionEvent::Decided {
            targets: d.targets.clone(),
            path_length_m: d.path_length_m,
            predicted_gain_cells: d.predicted_gain_cells,
            energy_steps: d.energy_steps,
            evaluations: d.evaluations,
        });
        true
    }

    /// Gives up the errand: blacklists its last target and decides again (a go-to goal is
    /// tried again later instead).
    pub(super) fn abandon(&mut self, map: &SharedMap<N>, events: &mut Events<'_>) {
        let targets = &self.errand.targets;
        if self.errand.from_goal && !targets.is_empty() {
            self.goal.targets = Some(targets.clone());
            self.goal.failures += 1;
            if self.goal.failures >= self.config.max_failed_decisions {
                self.goal.targets = None;
            }
        } else if let Some(&t) = targets.last() {
            self.blacklist.push_forgetting_oldest(&map.grid, t);
            events.stats.abandoned_targets += 1;
        }
        self.errand.targets.clear();
        self.follower.clear();
        self.ahead = None;
        self.phase = Phase::Deciding;
        let here = self.senses.pose_map.position();
        let (count, from) = &mut self.abandoned_in_row;
        if *count == 0 || here.distance(*from) >= REPLAN_PROGRESS_M {
            *count = 0;
            *from = here;
        }
        *count += 1;
        if *count >= self.config.max_failed_decisions {
            // Every errand of the last ones was dropped where it started: the robot does not
            // get on from here, though its map has frontier it could reach (the selector chose
            // each errand), so the end is `Stuck`, not "nothing reachable".
            let _ = self.finish(DoneReason::Stuck, events);
        }
    }

    /// Counts one more replan against the errand; `true` when that is more than
    /// [`MissionConfig::max_replans_per_decision`](super::super::MissionConfig) and the
    /// errand must be dropped. Replans count only while the robot gets nowhere: one that
    /// moved on since the first counted replan starts a fresh count.
    pub(super) fn count_replan(&mut self) -> bool {
        let here = self.senses.pose_map.position();
        let e = &mut self.errand;
        if e.replans == 0 || here.distance(e.replans_from) >= REPLAN_PROGRESS_M {
            e.replans = 0;
            e.replans_from = here;
        }
        e.replans += 1;
        e.replans > self.config.max_replans_per_decision
    }

    /// The decision request from `pose`, with the start moved onto the nearest passable cell
    /// if the robot's own cell is inflated.
    pub(super) fn start_pose(&self, map: &SharedMap<N>, pose: Pose2) -> Pose2 {
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

    /// The decision request from `pose` on the current map.
    pub(super) fn request<'a>(
        &'a self,
        map: &'a SharedMap<N>,
        pose: Pose2,
    ) -> DecisionRequest<'a, N> {
        DecisionRequest {
            grid: &map.grid,
            trav: &map.trav,
            pose: self.start_pose(map, pose),
            // The way back to the start is driven whatever energy is left.
            battery_steps: if self.homing.is_some() {
                HOMING_BUDGET_STEPS
            } else {
                self.senses.battery_steps
            },
            laser: &self.config.laser,
        }
    }

    /// Runs the configured selector from `pose`, avoiding the blacklisted places.
    pub(super) fn run_selector<R: rand_core::Rng, P: Planner<N>>(
        &self,
        pose: Pose2,
        map: &SharedMap<N>,
        ws: &mut Workspace<N, P>,
        rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        let req = self.request(map, pose);
        let config = self.config.explore;
        let (mut objective, frontier) = ws.parts();
        match self.config.selector {
            SelectorKind::Optimized(method) => {
                let mut s = Optimized::new(method, config, &mut objective);
                s.blacklist.clone_from(&self.blacklist);
                s.decide(&req, rng)
            }
            SelectorKind::NearestFrontier => {
                let mut s = NearestFrontier::new(config, &mut objective, frontier);
                s.blacklist.clone_from(&self.blacklist);
                s.decide(&req, rng)
            }
            SelectorKind::FrontierUtility => {
                let mut s = FrontierUtility::new(config, &mut objective, frontier);
                s.blacklist.clone_from(&self.blacklist);
                s.decide(&req, rng)
            }
        }
    }

    /// Plans a path from `pose` through `targets` on the current map.
    pub(super) fn plan_to<P: Planner<N>>(
        &self,
        pose: Pose2,
        targets: &[Point2],
        map: &SharedMap<N>,
        ws: &mut Workspace<N, P>,
    ) -> Result<heapless::Vec<Point2, MAX_WAYPOINTS>, CandidateStatus> {
        let req = self.request(map, pose);
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
}
