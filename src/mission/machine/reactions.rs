//! What the mission does when the safety monitor intervenes: an obstacle ahead goes on the
//! map and the path is planned again (or the robot yields, when the obstacle is another
//! robot); a bumper contact is remembered; repeated holds without progress start an escape,
//! a slow manoeuvre away from the nearest laser return.

use core::time::Duration;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::Controller;
use crate::control::safety::{SafetyEvent, SafetyState};
use crate::geometry::{Point2, Pose2, normalize_angle};
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
/// Escape speeds: slow, well inside any board's limits.
const ESCAPE_SPEED_MM_S: i16 = 100;
const ESCAPE_TURN_DEG_S: i16 = 20;
/// Longest escape manoeuvre.
const ESCAPE_TIMEOUT: Duration = Duration::from_secs(6);

/// A slow manoeuvre away from the nearest laser return, after repeated obstacle holds: the
/// plans kept starting with a command the safety monitor refuses (the robot too close to a
/// wall to turn, facing it). Every command still goes through the monitor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Escape {
    command: MotionCommand,
    start_odom: Pose2,
    until: Time,
}

/// Obstacle holds in a row without progress, and where the first of them happened.
#[derive(Clone, Copy, Debug)]
pub(super) struct Holds {
    in_row: u32,
    anchor: Point2,
}

impl Holds {
    pub(super) fn new(anchor: Point2) -> Self {
        Self { in_row: 0, anchor }
    }

    /// The robot made progress (it reached a waypoint).
    pub(super) fn reset(&mut self) {
        self.in_row = 0;
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
                                self.begin_escape(now, events);
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

    /// Starts a slow manoeuvre away from the nearest laser return, the first of backing
    /// away, turning away, turning the other way or driving away that the safety monitor's
    /// corridor check allows on the latest scan. Nothing allowed: the mission just replans.
    fn begin_escape(&mut self, now: Time, events: &mut Events<'_>) {
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
                .obstacle_in_path(limits.clamp(c), &senses.scan, laser)
                .is_none()
        }) else {
            return;
        };
        self.phase = Phase::Escaping(Escape {
            command,
            start_odom: senses.pose_odom,
            until: now + ESCAPE_TIMEOUT,
        });
        events.stats.escapes += 1;
    }

    /// One period of escape `e`; `None` once it is over (the mission then replans).
    pub(super) fn escape_step(&mut self, now: Time, e: Escape) -> Option<MotionCommand> {
        let pose_odom = self.senses.pose_odom;
        let travelled = e.start_odom.position().distance(pose_odom.position());
        let turned = math::abs(normalize_angle(pose_odom.theta - e.start_odom.theta));
        let done = if e.command.speed_mm_s != 0 {
            travelled >= ESCAPE_DISTANCE_M
        } else {
            turned >= ESCAPE_TURN_RAD
        };
        if done || now >= e.until || matches!(self.monitor.state(), SafetyState::BackingOff { .. })
        {
            self.enter_replanning(ReplanCause::ObstacleAhead);
            return None;
        }
        // The manoeuvre is a fresh decision of its own, taken after the hold.
        let _ = self.monitor.acknowledge_replan();
        self.watch.ack_pending = false;
        Some(e.command)
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
