//! Driving the errand's path: starting a path, following it with the waypoint follower,
//! watching it for new obstacles and for progress, computing the next decision ahead, and
//! planning a fresh path when it is blocked.

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::{Controller, FollowStatus};
use crate::explore::Outcome;
use crate::geometry::{Point2, Pose2};
use crate::planner::Planner;
use crate::planner::waypoints::supercover;

use super::super::shared::{MAX_SHARED_WAYPOINTS, SharedMap, Workspace};
use super::super::{MissionError, MissionEvent, ReplanCause};
use super::{Events, Mission, Phase, secs};

/// Progress toward a waypoint smaller than this does not count \[m\].
const PROGRESS_M: f32 = 0.05;

/// The path being followed: when it was planned, whether a scan arrived since it was last
/// checked, and the progress made toward the current waypoint.
#[derive(Clone, Copy, Debug)]
pub(super) struct PathWatch {
    /// When the path was planned.
    pub(super) plan_time: Option<Time>,
    /// A scan arrived since the path was last checked.
    pub(super) path_dirty: bool,
    /// The plan was made after the last hold; acknowledge the monitor when it allows.
    pub(super) ack_pending: bool,
    progress_index: usize,
    progress_best_m: f32,
    progress_time: Time,
}

impl PathWatch {
    pub(super) fn new() -> Self {
        Self {
            plan_time: None,
            path_dirty: false,
            ack_pending: false,
            progress_index: 0,
            progress_best_m: f32::INFINITY,
            progress_time: Time::ZERO,
        }
    }
}

impl<const N: usize> Mission<N> {
    /// Starts following `waypoints`; the first is dropped when the robot already stands on
    /// it.
    pub(super) fn start_path(&mut self, now: Time, waypoints: &[Point2]) -> bool {
        let tol = self.config.follower.position_tolerance_m;
        let here = self.senses.pose_map.position();
        let skip = waypoints.len() > 1 && waypoints[0].distance(here) <= tol;
        let path = if skip { &waypoints[1..] } else { waypoints };
        if self.follower.set_path(path).is_err() {
            return false;
        }
        self.phase = Phase::Rotating;
        self.errand.last_path.clear();
        self.watch.plan_time = Some(now);
        self.watch.progress_index = usize::MAX;
        self.watch.path_dirty = false;
        self.watch.ack_pending = self.monitor.acknowledge_replan().is_err();
        true
    }

    /// A fresh path to the remaining targets from the current pose.
    pub(super) fn replan<P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        events: &mut Events<'_>,
    ) {
        if self.errand.targets.is_empty() {
            self.phase = Phase::Deciding;
            return;
        }
        if self.count_replan() {
            self.abandon(map, events);
            return;
        }
        let targets = self.errand.targets.clone();
        match self.plan_to(self.senses.pose_map, &targets, map, ws) {
            Ok(waypoints) if self.start_path(now, &waypoints) => {
                events.stats.replans += 1;
                events.push(MissionEvent::Replanned {
                    cause: self.errand.replan_cause,
                });
                self.errand.conflict = None;
            }
            _ => {
                // No way to the targets. If a robot is what blocks it, wait for it to step
                // aside (a higher id steps aside; a lower id is waited for in the same way,
                // as it will move on); else give the targets up.
                let other = self.errand.conflict.or_else(|| self.robot_on_way(map, now));
                if let Some(other) = other {
                    self.hold_for(now, other, events);
                    return;
                }
                // A target that turned out to be in a wall is not a failure to reach it.
                let geom = *map.trav.geometry();
                let in_wall = self
                    .errand
                    .targets
                    .last()
                    .is_some_and(|&t| !map.trav.is_passable(geom.cell_at_unchecked(t)));
                if in_wall && !self.errand.from_goal {
                    // Given up without a blacklist entry: the map says the target is a wall.
                    events.stats.abandoned_targets += 1;
                    self.errand.targets.clear();
                    self.phase = Phase::Deciding;
                    return;
                }
                self.abandon(map, events);
            }
        }
    }

    /// Cells this close to the robot are its own surroundings, which the safety monitor
    /// watches, not a blocked path \[m\].
    pub(super) fn clear_radius(&self) -> f32 {
        self.config.safety.footprint.radius_m + 0.1
    }

    /// One period of path following; `None` when the state changed.
    pub(super) fn follow<R: rand_core::Rng, P: Planner<N>>(
        &mut self,
        now: Time,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) -> Option<MotionCommand> {
        let here = self.senses.pose_map.position();
        // New obstacles across the remaining path (a door that closed, another robot).
        if self.watch.path_dirty {
            self.watch.path_dirty = false;
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
        let w = &mut self.watch;
        if index != w.progress_index || dist < w.progress_best_m - PROGRESS_M {
            w.progress_index = index;
            w.progress_best_m = dist;
            w.progress_time = now;
        } else if now.saturating_since(w.progress_time) > secs(self.config.stuck_timeout_s) {
            self.enter_replanning(ReplanCause::Stuck);
            return None;
        }
        // The next decision, computed ahead near the end of the path.
        if self.config.decide_while_driving
            && self.ahead.is_none()
            && !self.goal.is_pending()
            && self.phase == Phase::Driving
        {
            self.decide_ahead(here, map, ws, rng, events);
        }
        let (cmd, status) = self.follower.update(now, self.senses.pose_map);
        match status {
            FollowStatus::WaypointReached(i) => {
                self.holds.reset();
                events.stats.waypoints_reached += 1;
                events.push(MissionEvent::WaypointReached { index: i });
                let w = self.follower.path()[i];
                let targets = &mut self.errand.targets;
                if targets.first().is_some_and(|t| t.distance(w) < 1e-3) {
                    targets.remove(0);
                }
            }
            FollowStatus::Arrived => {
                self.holds.reset();
                let last = self.follower.path().len().saturating_sub(1);
                events.stats.waypoints_reached += 1;
                events.push(MissionEvent::WaypointReached { index: last });
                self.errand.targets.clear();
                self.follower.clear();
                self.phase = Phase::Deciding;
                return None;
            }
            FollowStatus::Rotating => self.phase = Phase::Rotating,
            FollowStatus::Idle => {
                self.phase = Phase::Deciding;
                return None;
            }
            _ => self.phase = Phase::Driving,
        }
        Some(cmd)
    }

    /// Once less than [`MissionConfig::decide_ahead_m`](super::super::MissionConfig) of the
    /// path is left, the next decision from the path's end pose.
    fn decide_ahead<R: rand_core::Rng, P: Planner<N>>(
        &mut self,
        here: Point2,
        map: &SharedMap<N>,
        ws: &mut Workspace<N, P>,
        rng: &mut R,
        events: &mut Events<'_>,
    ) {
        let path = self.follower.path();
        let from = self.follower.current_index().min(path.len());
        let remaining = polyline_length(here, &path[from..]);
        let near_end = remaining <= self.config.decide_ahead_m && !path.is_empty();
        if !near_end {
            return;
        }
        let end = path[path.len() - 1];
        let before = if path.len() >= 2 {
            path[path.len() - 2]
        } else {
            here
        };
        let heading = if before.distance(end) > 1e-3 {
            before.bearing_to(end)
        } else {
            self.senses.pose_map.theta
        };
        let pose = Pose2::new(end.x, end.y, heading);
        if let Ok(Outcome::Go(d)) = self.run_selector(pose, map, ws, rng) {
            events.stats.decisions_ahead += 1;
            events.stats.fitness_evals += u64::from(d.evaluations);
            self.ahead = Some(d);
        }
    }

    /// Keeps the remaining waypoints of the path being dropped.
    pub(super) fn remember_path(&mut self) {
        let path = self.follower.path();
        if path.is_empty() {
            return;
        }
        let from = self.follower.current_index().min(path.len());
        let n = (path.len() - from).min(MAX_SHARED_WAYPOINTS);
        self.errand.last_path.clear();
        let _ = self
            .errand
            .last_path
            .extend_from_slice(&path[from..from + n]);
    }

    /// Writes this robot's mark (pose and remaining path) on the shared map.
    pub(super) fn publish(&self, now: Time, map: &mut SharedMap<N>) -> Result<(), MissionError> {
        let path = self.follower.path();
        let from = self.follower.current_index().min(path.len());
        let e = &self.errand;
        let remaining: &[Point2] = if from < path.len() {
            &path[from..]
        } else if !e.last_path.is_empty() && !e.targets.is_empty() {
            &e.last_path
        } else {
            &e.targets
        };
        map.mark(self.id, self.senses.pose_map, now, remaining)
    }
}

/// Length of the polyline from `from` through `points` \[m\].
pub(super) fn polyline_length(from: Point2, points: &[Point2]) -> f32 {
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
pub(super) fn first_blocked<const N: usize>(
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
