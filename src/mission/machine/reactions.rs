//! What the mission does when the safety monitor intervenes: an obstacle ahead goes on the
//! map and the path is planned again (or the robot yields, when the obstacle is another
//! robot); a bumper contact is remembered; repeated holds without progress start an escape,
//! a slow manoeuvre out of the place, the way the body fits (straight to where it can turn).

use core::time::Duration;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::Controller;
use crate::control::safety::{SafetyEvent, SafetyState};
use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::grid::CellClass;
use crate::math;

use super::super::ReplanCause;
use super::super::shared::SharedMap;
use super::robots::Yield;
use super::{Events, Mission, Phase, secs};

/// How long a bumper contact is remembered while planning.
const CONTACT_MEMORY: Duration = Duration::from_secs(120);
/// After this many obstacle holds in a row without progress, the robot backs or turns away
/// from the nearest laser return before planning again.
const ESCAPE_AFTER_HOLDS: u32 = 2;
/// Moving this far from where the holds began counts as progress \[m\].
const ESCAPE_PROGRESS_M: f32 = 0.3;
/// Distance driven (forward or backward) by one escape \[m\].
const ESCAPE_DISTANCE_M: f32 = 0.25;
/// Angle turned in place by one escape \[rad\] (60°).
const ESCAPE_TURN_RAD: f32 = 1.047;
/// Farthest a straight escape drives to reach a place where the body can turn \[m\]: out
/// of a door frame (0.1–0.3 m deep) or a corridor's mouth, with room to spare.
const ESCAPE_MAX_M: f32 = 0.8;
/// Walls closer than this on both sides of the body make a straight escape keep to the
/// middle between them \[m\] (half a 0.9 m door).
const CENTRING_REACH_M: f32 = 0.45;
/// Turn rate per metre off the middle, and its bound, of an escape keeping to the middle
/// \[deg/s per m, deg/s\]: 5 cm off turns at 5 deg/s, so that the body comes back to the
/// middle within its own length at the escape speed.
const CENTRING_GAIN_DEG_S_PER_M: f32 = 100.0;
const CENTRING_MAX_DEG_S: i16 = 10;
/// Escape speeds: slow, well inside any board's limits.
pub(super) const ESCAPE_SPEED_MM_S: i16 = 100;
const ESCAPE_TURN_DEG_S: i16 = 20;
/// Longest escape manoeuvre.
const ESCAPE_TIMEOUT: Duration = Duration::from_secs(6);

/// A slow manoeuvre out of a place where the plans kept starting with a command the safety
/// monitor refuses (the robot too close to a wall to turn), after repeated obstacle holds.
/// Every command still goes through the monitor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Escape {
    command: MotionCommand,
    /// Distance \[m\] (a drive) or angle \[rad\] (a turn) to cover.
    goal: f32,
    start_odom: Pose2,
    until: Time,
}

/// Obstacle holds in a row without progress, and where the first of them happened.
#[derive(Clone, Copy, Debug)]
pub(super) struct Holds {
    in_row: u32,
    anchor: Point2,
    /// The direction of the last straight escape since the robot last reached a waypoint
    /// (+1 forward, -1 back): the next escape does not undo it if it has a choice.
    last_drive: Option<i8>,
}

impl Holds {
    pub(super) fn new(anchor: Point2) -> Self {
        Self {
            in_row: 0,
            anchor,
            last_drive: None,
        }
    }

    /// The robot made progress (it reached a waypoint).
    pub(super) fn reset(&mut self) {
        self.in_row = 0;
        self.last_drive = None;
    }

    /// Counts a hold at `here`: the number in a row since the robot last made progress
    /// (reached a waypoint, or moved [`ESCAPE_PROGRESS_M`] from where the holds began).
    fn count(&mut self, here: Point2) -> u32 {
        if self.in_row == 0 || self.anchor.distance(here) >= ESCAPE_PROGRESS_M {
            self.in_row = 0;
            self.anchor = here;
        }
        self.in_row += 1;
        self.in_row
    }
}

impl<const N: usize> Mission<N> {
    /// Reacts to what the safety monitor did this period.
    pub(super) fn on_safety(
        &mut self,
        now: Time,
        event: SafetyEvent,
        map: &mut SharedMap<N>,
        events: &mut Events<'_>,
    ) {
        let pose = self.senses.pose_map;
        match event {
            SafetyEvent::ObstacleAhead { point_base_m, .. } => {
                let p = pose.transform_point(point_base_m);
                mark_occupied(map, p, self.config.sensor.occupied_log_odds);
                match self.phase {
                    Phase::Escaping(_) => {
                        // The escape itself was refused: plan again; the next hold picks
                        // another manoeuvre from the scan.
                        self.enter_replanning(ReplanCause::ObstacleAhead);
                    }
                    // The turn at the start does not fit: the mission decides from here.
                    Phase::LookingAround(_) => self.phase = Phase::Deciding,
                    Phase::Yielding(Yield::SteppingAside { other, .. }) => {
                        self.follower.clear();
                        self.phase = Phase::Yielding(Yield::Waiting {
                            other,
                            until: now + secs(self.config.yield_wait_s),
                        });
                    }
                    phase if phase.is_running() => match self.robot_at(map, now, p) {
                        Some(other) => self.begin_conflict(now, other, events),
                        None => {
                            self.enter_replanning(ReplanCause::ObstacleAhead);
                            if self.holds.count(pose.position()) >= ESCAPE_AFTER_HOLDS {
                                self.begin_escape(now, map, events);
                            }
                        }
                    },
                    _ => {}
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
                    let a = pose.transform_point(Point2::new(x, -half));
                    let b = pose.transform_point(Point2::new(x, half));
                    mark_occupied(
                        map,
                        pose.transform_point(Point2::new(x, 0.0)),
                        map.grid.bounds().max,
                    );
                    if self.contacts.is_full() {
                        self.contacts.pop_front();
                    }
                    let _ = self.contacts.push_back((a, b, now + CONTACT_MEMORY));
                }
                // Whatever the robot was doing (yielding, escaping), it plans again.
                if !matches!(self.phase, Phase::Done(_) | Phase::Fault(_)) {
                    self.enter_replanning(ReplanCause::Contact);
                }
            }
            SafetyEvent::RequiresReplan { .. } => {
                if self.watch.plan_time == Some(now) {
                    // The plan was made this very period, after the cause: it is fresh.
                    self.watch.ack_pending = true;
                } else if matches!(self.phase, Phase::Rotating | Phase::Driving) {
                    self.enter_replanning(self.errand.replan_cause);
                }
            }
            SafetyEvent::InputsStale { .. } | SafetyEvent::Fault { .. } => {
                // `run` reports these faults itself; the monitor saw them at the same time.
                self.follower.clear();
            }
        }
    }

    /// Starts a slow manoeuvre out of the place where the plans keep being refused, checked
    /// as the safety monitor will check it (the latest scan, and the map's Occupied cells
    /// around the body that the laser cannot see: [`SafetyMonitor::remembered_in_path`]), so
    /// that it is not refused at once. In order of preference:
    ///
    /// 1. driving straight, forward or back, to the nearest place where the planning layer
    ///    lets the body turn ([`Traversability::can_turn`], at most [`ESCAPE_MAX_M`] away):
    ///    out of a door frame or a corridor's mouth the way the body fits;
    /// 2. turning in place, away from the nearest return;
    /// 3. driving [`ESCAPE_DISTANCE_M`] straight.
    ///
    /// Among drives, the one that does not undo the previous escape of this wedge comes first
    /// (two escapes undoing each other leave the robot where it was: branch `reach`'s
    /// forward-and-back in a door), then the one toward the path that was given up. Nothing
    /// allowed: the mission just replans.
    ///
    /// [`SafetyMonitor::remembered_in_path`]: crate::control::safety::SafetyMonitor::remembered_in_path
    /// [`Traversability::can_turn`]: crate::planner::Traversability::can_turn
    fn begin_escape(&mut self, now: Time, map: &SharedMap<N>, events: &mut Events<'_>) {
        let senses = &self.senses;
        if senses.scan_time.is_none() {
            return;
        }
        let laser = &self.config.laser;
        let mut nearest: Option<(f32, Point2)> = None;
        for beam in senses.scan.beams() {
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
        let remembered = self.remembered_around(map);
        let limits = *self.monitor.limits();
        let allowed = |c: MotionCommand| {
            let v = limits.clamp(c);
            self.monitor
                .obstacle_in_path(v, &senses.scan, laser)
                .is_none()
                && self.monitor.remembered_in_path(v, &remembered).is_none()
        };
        let pose = senses.pose_map;
        // The way the path that was given up went, in the base frame: +1 ahead, -1 behind.
        let here = pose.position();
        let toward = self
            .errand
            .last_path
            .iter()
            .chain(self.errand.targets.iter())
            .find(|w| w.distance(here) > 0.1)
            .map(|w| {
                let along =
                    (w.x - here.x) * math::cos(pose.theta) + (w.y - here.y) * math::sin(pose.theta);
                if along >= 0.0 { 1 } else { -1 }
            });
        let (v, w) = (ESCAPE_SPEED_MM_S, ESCAPE_TURN_DEG_S);
        let drive = |sign: i8| MotionCommand {
            speed_mm_s: v * i16::from(sign),
            turn_rate_deg_s: 0,
        };
        let turn = |turn_rate_deg_s: i16| MotionCommand {
            speed_mm_s: 0,
            turn_rate_deg_s,
        };
        // Drives: (rank, sign, distance); lower rank first.
        let last = self.holds.last_drive;
        let mut best: Option<(u8, MotionCommand, f32)> = None;
        let mut offer = |rank: u8, c: MotionCommand, d: f32| {
            if best.is_none_or(|(r, _, _)| rank < r) {
                best = Some((rank, c, d));
            }
        };
        for sign in [1i8, -1] {
            if !allowed(drive(sign)) {
                continue;
            }
            let undoes = last == Some(-sign);
            let ahead = toward == Some(sign);
            let order = u8::from(undoes) * 2 + u8::from(!ahead);
            match turn_room_along(map, pose, sign) {
                Some(d) => offer(order, drive(sign), d),
                None => offer(8 + order, drive(sign), ESCAPE_DISTANCE_M),
            }
        }
        // Turns: away from the nearest return first.
        let away = match nearest {
            Some((_, p)) if p.y > 0.0 => -w,
            _ => w,
        };
        for (k, rate) in [away, -away].into_iter().enumerate() {
            if allowed(turn(rate)) {
                offer(4 + k as u8, turn(rate), ESCAPE_TURN_RAD);
            }
        }
        let Some((_, command, goal)) = best else {
            return;
        };
        if command.speed_mm_s != 0 {
            self.holds.last_drive = Some(command.speed_mm_s.signum() as i8);
        }
        self.phase = Phase::Escaping(Escape {
            command,
            goal,
            start_odom: senses.pose_odom,
            until: now + ESCAPE_TIMEOUT,
        });
        events.stats.escapes += 1;
    }

    /// One period of escape `e`; `None` once it is over (the mission then replans).
    pub(super) fn escape_step(
        &mut self,
        now: Time,
        e: Escape,
        map: &SharedMap<N>,
    ) -> Option<MotionCommand> {
        let pose_odom = self.senses.pose_odom;
        let travelled = e.start_odom.position().distance(pose_odom.position());
        let turned = math::abs(normalize_angle(pose_odom.theta - e.start_odom.theta));
        let done = if e.command.speed_mm_s != 0 {
            travelled >= e.goal
        } else {
            turned >= e.goal
        };
        if done || now >= e.until || matches!(self.monitor.state(), SafetyState::BackingOff { .. })
        {
            self.enter_replanning(ReplanCause::ObstacleAhead);
            return None;
        }
        // The manoeuvre is a fresh decision of its own, taken after the hold.
        let _ = self.monitor.acknowledge_replan();
        self.watch.ack_pending = false;
        if e.command.speed_mm_s == 0 {
            return Some(e.command);
        }
        Some(MotionCommand {
            turn_rate_deg_s: self.centring_turn_deg_s(e.command.speed_mm_s, map),
            ..e.command
        })
    }

    /// A straight escape between walls on both sides (a door frame, a narrow passage) keeps
    /// to the middle: the turn rate \[deg/s\] that steers the body away from the nearer side,
    /// from the walls beside the body (the latest scan, and the map's Occupied cells for what
    /// the 180° laser cannot see beside and behind it). Driving straight at an angle to the
    /// passage would bring a flank the laser does not watch onto its wall; 0 in the open.
    fn centring_turn_deg_s(&self, speed_mm_s: i16, map: &SharedMap<N>) -> i16 {
        let fp = self.config.safety.footprint;
        let laser = &self.config.laser;
        let beside = |p: Point2| p.x >= -fp.rear_m && p.x <= fp.front_m + 0.1;
        let (mut left, mut right) = (CENTRING_REACH_M, CENTRING_REACH_M);
        let mut see = |p: Point2| {
            if beside(p) {
                if p.y > 0.0 {
                    left = left.min(p.y);
                } else {
                    right = right.min(-p.y);
                }
            }
        };
        if self.senses.scan_time.is_some() {
            for beam in self.senses.scan.beams() {
                let Some(r) = beam.range_m else { continue };
                if !(r.is_finite() && r >= self.config.safety.min_valid_range_m) {
                    continue;
                }
                let (c, s) = (math::cos(beam.angle_rad), math::sin(beam.angle_rad));
                see(laser.mount.transform_point(Point2::new(r * c, r * s)));
            }
        }
        for &p in self.remembered_around(map).iter() {
            see(p);
        }
        if left >= CENTRING_REACH_M || right >= CENTRING_REACH_M {
            return 0;
        }
        // Nearer the left wall (left - right < 0): move right, i.e. turn right (clockwise)
        // driving forward and left backing.
        let error_m = left - right;
        let sign = if speed_mm_s > 0 { 1.0 } else { -1.0 };
        let rate = (sign * CENTRING_GAIN_DEG_S_PER_M * error_m).clamp(
            -f32::from(CENTRING_MAX_DEG_S),
            f32::from(CENTRING_MAX_DEG_S),
        );
        rate as i16
    }
}

/// Makes the cell holding map point `p` Occupied with log-odds `l` at least (a bumper contact:
/// the bound; a return the safety monitor stopped for: one return's evidence,
/// `occupied_log_odds`, so that free space seen through it later clears it as it clears any
/// return; saturating it made one noisy return in a doorway shut the door for good).
fn mark_occupied<const N: usize>(map: &mut SharedMap<N>, p: Point2, l: f32) {
    if let Some(i) = map
        .grid
        .geometry()
        .cell_at(p)
        .and_then(|c| map.grid.geometry().index(c))
    {
        let l = map.grid.log_odds_at(i).max(l);
        map.grid.set_log_odds(i, l, &mut map.trav);
    }
}

/// Driving straight from `pose`, forward (`sign` +1) or back (-1): the distance \[m\] after
/// which the robot's centre first stands in a cell where the planning layer lets it turn
/// (at least [`ESCAPE_PROGRESS_M`], at most [`ESCAPE_MAX_M`]), with no Occupied cell of the
/// map on the way; `None` if there is none.
fn turn_room_along<const N: usize>(map: &SharedMap<N>, pose: Pose2, sign: i8) -> Option<f32> {
    let geom = *map.grid.geometry();
    let step = 0.5 * geom.resolution_m;
    let (c, s) = (math::cos(pose.theta), math::sin(pose.theta));
    let dir = f32::from(sign);
    let mut d = step;
    while d <= ESCAPE_MAX_M {
        let p = Point2::new(pose.x + dir * d * c, pose.y + dir * d * s);
        let cell = geom.cell_at(p)?;
        let i = geom.index(cell)?;
        if map.grid.class(i) == CellClass::Occupied {
            return None;
        }
        if d >= ESCAPE_PROGRESS_M && map.trav.can_turn(cell) {
            return Some(d);
        }
        d += step;
    }
    None
}
