//! Several robots on one map: telling another robot from a wall, giving way (the thesis's
//! "solve conflict": the higher id waits, then replans around or steps out of the other
//! robot's path; the lower id replans at once), and keeping the shared map honest about
//! where the robots are (a robot's own body lifted off the map while it plans, the robots
//! near it stamped on from their marks, the places it left cleared of its own image).

use core::time::Duration;

use crate::control::Time;
use crate::control::command::MotionCommand;
use crate::control::follower::{Controller, FollowStatus, MAX_WAYPOINTS};
use crate::explore::{CandidateStatus, ExploreConfig};
use crate::geometry::Point2;
use crate::grid::{Cell, CellBox, CellClass};
use crate::math;
use crate::planner::Planner;

use super::super::shared::{RobotMark, SharedMap, Workspace};
use super::super::{MissionEvent, ReplanCause};
use super::{Events, Mission, Phase, RETRY_S, secs};

/// An obstacle this close to another robot's mark is that robot \[m\].
pub(super) const ROBOT_MATCH_M: f32 = 0.8;
/// Marks older than this are ignored when telling robots from walls.
pub(super) const MARK_MAX_AGE: Duration = Duration::from_secs(2);
/// A place to step aside to keeps this far from the other robot's path \[m\].
pub(super) const ASIDE_CLEARANCE_M: f32 = 0.8;
/// ... and this far from the other robot itself \[m\].
pub(super) const ASIDE_DISTANCE_M: f32 = 1.2;
/// Most cells lifted off (own body) or stamped on (other robots) the map while planning.
pub(super) const MAX_LIFTED: usize = 256;
/// The robot's body on the map: its turning radius plus this \[m\].
pub(super) const BODY_MARGIN_M: f32 = 0.1;
/// Other robots within this distance are stamped on the map while planning \[m\].
pub(super) const STAMP_RANGE_M: f32 = 3.0;
/// Poses remembered along the way, for clearing the robot's own trail on the shared map.
pub(super) const TRAIL_LEN: usize = 12;
/// Spacing of the remembered poses \[m\].
pub(super) const TRAIL_SPACING_M: f32 = 0.1;

/// What a yielding robot is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Yield {
    /// Higher id: waiting before replanning around the robot ahead.
    Waiting { other: u8, until: Time },
    /// Higher id: driving out of the other robot's path.
    SteppingAside { other: u8, since: Time },
    /// Higher id: standing aside until the other robot has passed.
    Clearing { other: u8, since: Time },
    /// Lower id: no way past the other robot; retrying until it steps aside.
    Holding {
        other: u8,
        retry_at: Time,
        give_up_at: Time,
    },
}

impl<const N: usize> Mission<N> {
    /// Which other robot, if any, stands at map point `p`.
    pub(super) fn robot_at(&self, map: &SharedMap<N>, now: Time, p: Point2) -> Option<u8> {
        map.robots()
            .iter()
            .filter(|m| m.id != self.id && now.saturating_since(m.time) <= MARK_MAX_AGE)
            .find(|m| m.pose.position().distance(p) <= ROBOT_MATCH_M)
            .map(|m| m.id)
    }

    /// Another robot whose mark lies on the way from here along the last path (or straight
    /// to the targets).
    pub(super) fn robot_on_way(&self, map: &SharedMap<N>, now: Time) -> Option<u8> {
        let here = self.senses.pose_map.position();
        let e = &self.errand;
        let way: &[Point2] = if e.last_path.is_empty() {
            &e.targets
        } else {
            &e.last_path
        };
        map.robots()
            .iter()
            .filter(|m| m.id != self.id && now.saturating_since(m.time) <= MARK_MAX_AGE)
            .find(|m| {
                let p = m.pose.position();
                let mut a = here;
                let mut near = p.distance(a) <= ROBOT_MATCH_M;
                for &b in way {
                    near |= distance_to_segment(p, a, b) <= ROBOT_MATCH_M;
                    a = b;
                }
                near
            })
            .map(|m| m.id)
    }

    /// Waits for robot `other` to step aside, retrying the plan every second.
    pub(super) fn hold_for(&mut self, now: Time, other: u8, events: &mut Events<'_>) {
        self.phase = Phase::Yielding(Yield::Holding {
            other,
            retry_at: now + secs(RETRY_S),
            give_up_at: now + secs(4.0 * self.config.yield_wait_s + 10.0),
        });
        events.push(MissionEvent::Yielding {
            to_robot_ahead: true,
        });
    }

    /// Another robot blocks the way: the higher id waits, the lower replans at once.
    pub(super) fn begin_conflict(&mut self, now: Time, other: u8, events: &mut Events<'_>) {
        self.remember_path();
        self.follower.clear();
        self.ahead = None;
        self.errand.conflict = Some(other);
        if self.id > other {
            events.stats.yields += 1;
            events.push(MissionEvent::Yielding {
                to_robot_ahead: true,
            });
            self.phase = Phase::Yielding(Yield::Waiting {
                other,
                until: now + secs(self.config.yield_wait_s),
            });
        } else {
            self.enter_replanning(ReplanCause::Robot);
        }
    }

    /// Weakens any Occupied evidence at the places the robot has just left (its last metre,
    /// away from where its body is now): it stood there, so what another robot's scan saw
    /// there was this robot, not a wall. Its current body stays as the others saw it.
    pub(super) fn clear_own_trail(&self, map: &mut SharedMap<N>) {
        let geom = *map.grid.geometry();
        let r = self.config.safety.footprint.radius_m + 0.5 * geom.resolution_m;
        let span = math::ceil(r / geom.resolution_m) as i32;
        let weak_free = self.config.sensor.free_log_odds;
        let here = self.senses.pose_map.position();
        // Never the current body: the other robots must keep seeing it.
        let keep = r + geom.resolution_m;
        for p in self.senses.trail.iter().copied() {
            if p.distance(here) < r {
                continue;
            }
            let c = geom.cell_at_unchecked(p);
            for row in c.row - span..=c.row + span {
                for col in c.col - span..=c.col + span {
                    let cell = Cell::new(col, row);
                    let Some(i) = geom.index(cell) else { continue };
                    // Most cells are already Free at least as surely as weak Free: look at the
                    // evidence before measuring distances.
                    if map.grid.log_odds_at(i) <= weak_free {
                        continue;
                    }
                    let centre = geom.cell_center(cell);
                    if centre.distance(p) > r || centre.distance(here) < keep {
                        continue;
                    }
                    map.grid.set_log_odds(i, weak_free, &mut map.trav);
                }
            }
        }
    }

    /// A box holding every cell [`Self::lift_own_body`] and [`Self::stamp_others`] may change
    /// at `now`, grown by the traversability layer's reach (and one cell for rounding) and
    /// clipped to the grid: the window to save before them and put back after.
    pub(super) fn stamp_area(&self, map: &SharedMap<N>, now: Time) -> CellBox {
        let geom = *map.grid.geometry();
        let mut lo = (i32::MAX, i32::MAX);
        let mut hi = (i32::MIN, i32::MIN);
        let mut add = |c: Cell, span: i32| {
            lo = (lo.0.min(c.col - span), lo.1.min(c.row - span));
            hi = (hi.0.max(c.col + span), hi.1.max(c.row + span));
        };
        let here = self.senses.pose_map.position();
        let r_body = self.config.safety.footprint.radius_m + BODY_MARGIN_M;
        add(
            geom.cell_at_unchecked(here),
            math::ceil(r_body / geom.resolution_m) as i32,
        );
        for &(a, b, until) in &self.contacts {
            if now <= until {
                add(geom.cell_at_unchecked(a), 0);
                add(geom.cell_at_unchecked(b), 0);
            }
        }
        let r = self.config.safety.footprint.radius_m;
        let span = math::ceil(r / geom.resolution_m) as i32;
        for m in map.robots() {
            let p = m.pose.position();
            if m.id == self.id
                || now.saturating_since(m.time) > MARK_MAX_AGE
                || p.distance(here) > STAMP_RANGE_M
            {
                continue;
            }
            add(geom.cell_at_unchecked(p), span);
        }
        let grow = map.trav.change_reach_cells() as i32 + 1;
        let clip = |v: i32, end: usize| v.clamp(0, end as i32) as usize;
        let (w, h) = (geom.width, geom.height);
        CellBox {
            col_min: clip(lo.0.saturating_sub(grow), w),
            col_end: clip(hi.0.saturating_add(grow + 1), w),
            row_min: clip(lo.1.saturating_sub(grow), h),
            row_end: clip(hi.1.saturating_add(grow + 1), h),
        }
    }

    /// Sets every Occupied cell under the robot's body to weak Free evidence; returns the
    /// cells and their values, for putting them back.
    pub(super) fn lift_own_body(
        &self,
        map: &mut SharedMap<N>,
    ) -> heapless::Vec<(usize, f32), MAX_LIFTED> {
        let mut lifted = heapless::Vec::new();
        let geom = *map.grid.geometry();
        let r = self.config.safety.footprint.radius_m + BODY_MARGIN_M;
        let span = math::ceil(r / geom.resolution_m) as i32;
        let here = self.senses.pose_map.position();
        let c = geom.cell_at_unchecked(here);
        let weak_free = self.config.sensor.free_log_odds;
        // One batch: the layer's codes refreshed once per cell (it only removes Occupied).
        let mut batch = map.trav.deferred();
        'rows: for row in c.row - span..=c.row + span {
            for col in c.col - span..=c.col + span {
                let cell = Cell::new(col, row);
                let Some(i) = geom.index(cell) else { continue };
                if geom.cell_center(cell).distance(here) > r
                    || map.grid.class(i) != CellClass::Occupied
                {
                    continue;
                }
                if lifted.push((i, map.grid.log_odds_at(i))).is_err() {
                    break 'rows;
                }
                map.grid.set_log_odds(i, weak_free, &mut batch);
            }
        }
        batch.finish();
        lifted
    }

    /// Sets the cells under the other robots nearby (by their marks), and across the
    /// bumper where it recently touched something, Occupied, recording the old values in
    /// `saved`.
    pub(super) fn stamp_others(
        &self,
        map: &mut SharedMap<N>,
        now: Time,
        saved: &mut heapless::Vec<(usize, f32), MAX_LIFTED>,
    ) {
        let geom = *map.grid.geometry();
        let r = self.config.safety.footprint.radius_m;
        let span = math::ceil(r / geom.resolution_m) as i32;
        let here = self.senses.pose_map.position();
        let occupied = map.grid.bounds().max;
        // What the bumpers found lately, across the bumper's width. Each batch only adds
        // Occupied cells: the layer's codes refreshed once per cell.
        let mut batch = map.trav.deferred();
        for &(a, b, until) in &self.contacts {
            if now > until {
                continue;
            }
            let n = math::ceil(a.distance(b) / (0.5 * geom.resolution_m)) as usize;
            for k in 0..=n {
                let f = k as f32 / n.max(1) as f32;
                let p = Point2::new(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f);
                let Some(i) = geom.cell_at(p).and_then(|c| geom.index(c)) else {
                    continue;
                };
                if map.grid.class(i) == CellClass::Occupied {
                    continue;
                }
                if saved.push((i, map.grid.log_odds_at(i))).is_err() {
                    batch.finish();
                    return;
                }
                map.grid.set_log_odds(i, occupied, &mut batch);
            }
        }
        batch.finish();
        for k in 0..map.robots().len() {
            let m = &map.robots()[k];
            let p = m.pose.position();
            if m.id == self.id
                || now.saturating_since(m.time) > MARK_MAX_AGE
                || p.distance(here) > STAMP_RANGE_M
            {
                continue;
            }
            let c = geom.cell_at_unchecked(p);
            let mut batch = map.trav.deferred();
            for row in c.row - span..=c.row + span {
                for col in c.col - span..=c.col + span {
                    let cell = Cell::new(col, row);
                    let Some(i) = geom.index(cell) else { continue };
                    if geom.cell_center(cell).distance(p) > r
                        || map.grid.class(i) == CellClass::Occupied
                    {
                        continue;
                    }
                    if saved.push((i, map.grid.log_odds_at(i))).is_err() {
                        batch.finish();
                        return;
                    }
                    map.grid.set_log_odds(i, occupied, &mut batch);
                }
            }
            batch.finish();
        }
    }

    /// One period of yielding; `None` when the state changed and the machine should go on.
    pub(super) fn yield_step<P: Planner<N>>(
        &mut self,
        now: Time,
        y: Yield,
        map: &mut SharedMap<N>,
        ws: &mut Workspace<N, P>,
        events: &mut Events<'_>,
    ) -> Option<MotionCommand> {
        let pose = self.senses.pose_map;
        match y {
            Yield::Waiting { other, until } => {
                if now < until {
                    return Some(MotionCommand::ZERO);
                }
                // Around the other robot, if there is a way.
                let targets = self.errand.targets.clone();
                if let Ok(waypoints) = self.plan_to(pose, &targets, map, ws)
                    && !targets.is_empty()
                    && self.start_path(now, &waypoints)
                {
                    self.errand.conflict = None;
                    events.stats.replans += 1;
                    events.push(MissionEvent::Replanned {
                        cause: ReplanCause::Robot,
                    });
                    return None;
                }
                // No way around: step out of its path.
                let mark = map.robot(other).cloned();
                let aside = mark.and_then(|m| self.place_aside(&m, map, ws));
                match aside {
                    Some(waypoints) if self.start_path(now, &waypoints) => {
                        self.phase = Phase::Yielding(Yield::SteppingAside { other, since: now });
                        events.push(MissionEvent::Yielding {
                            to_robot_ahead: false,
                        });
                        None
                    }
                    _ => {
                        // Nowhere to go: wait some more, the other robot may move.
                        self.phase = Phase::Yielding(Yield::Waiting {
                            other,
                            until: now + secs(self.config.yield_wait_s),
                        });
                        if self.count_replan() {
                            self.abandon(map, events);
                            return None;
                        }
                        Some(MotionCommand::ZERO)
                    }
                }
            }
            Yield::SteppingAside { other, since } => {
                let (cmd, status) = self.follower.update(now, pose);
                let timeout = secs(self.config.stuck_timeout_s);
                if status == FollowStatus::Arrived || now.saturating_since(since) > timeout {
                    self.follower.clear();
                    self.phase = Phase::Yielding(Yield::Clearing { other, since: now });
                    return Some(MotionCommand::ZERO);
                }
                Some(cmd)
            }
            Yield::Clearing { other, since } => {
                let passed = map.robot(other).is_none_or(|m| {
                    let here = self.senses.pose_map.position();
                    m.pose.position().distance(here) >= ASIDE_DISTANCE_M
                        && distance_to_path(here, m) >= ASIDE_CLEARANCE_M
                });
                let timeout =
                    now.saturating_since(since) > secs(4.0 * self.config.yield_wait_s + 10.0);
                if (passed && now.saturating_since(since) > secs(self.config.yield_wait_s))
                    || timeout
                {
                    self.errand.replans = 0;
                    self.enter_replanning(ReplanCause::Robot);
                    return None;
                }
                Some(MotionCommand::ZERO)
            }
            Yield::Holding {
                other,
                retry_at,
                give_up_at,
            } => {
                if now >= give_up_at {
                    self.abandon(map, events);
                    return None;
                }
                if now < retry_at {
                    return Some(MotionCommand::ZERO);
                }
                let targets = self.errand.targets.clone();
                match self.plan_to(pose, &targets, map, ws) {
                    Ok(waypoints) if self.start_path(now, &waypoints) => {
                        self.errand.conflict = None;
                        events.stats.replans += 1;
                        events.push(MissionEvent::Replanned {
                            cause: ReplanCause::Robot,
                        });
                        None
                    }
                    _ => {
                        self.phase = Phase::Yielding(Yield::Holding {
                            other,
                            retry_at: now + secs(RETRY_S),
                            give_up_at,
                        });
                        Some(MotionCommand::ZERO)
                    }
                }
            }
        }
    }

    /// A path to the nearest reachable place out of `other`'s way: at least
    /// `ASIDE_CLEARANCE_M` from its remaining path and `ASIDE_DISTANCE_M` from it.
    pub(super) fn place_aside<P: Planner<N>>(
        &self,
        other: &RobotMark,
        map: &SharedMap<N>,
        ws: &mut Workspace<N, P>,
    ) -> Option<heapless::Vec<Point2, MAX_WAYPOINTS>> {
        let req = self.request(map, self.senses.pose_map);
        let config = ExploreConfig {
            targets: 1,
            reserve_steps: 0.0,
            ..self.config.explore
        };
        let (mut objective, _) = ws.parts();
        objective.prepare_plan(&req, &config).ok()?;
        let geom = *map.grid.geometry();
        let mut best: Option<(f32, Point2)> = None;
        for i in 0..geom.cell_count() {
            let cell = geom.cell(i);
            let Some(d) = objective.field().distance_to(cell) else {
                continue;
            };
            if best.is_some_and(|(b, _)| d >= b) || map.grid.class(i) != CellClass::Free {
                continue;
            }
            let p = geom.cell_center(cell);
            if p.distance(other.pose.position()) >= ASIDE_DISTANCE_M
                && distance_to_path(p, other) >= ASIDE_CLEARANCE_M
            {
                best = Some((d, p));
            }
        }
        let (_, target) = best?;
        let eval = objective.plan_targets(&req, &[target]);
        if eval.status != CandidateStatus::Feasible {
            return None;
        }
        let mut out = heapless::Vec::new();
        let _ = out.extend_from_slice(objective.waypoints());
        Some(out)
    }
}

/// Distance from `p` to the other robot's pose-and-path polyline \[m\].
pub(super) fn distance_to_path(p: Point2, other: &RobotMark) -> f32 {
    let mut best = p.distance(other.pose.position());
    let mut a = other.pose.position();
    for &b in other.path() {
        best = best.min(distance_to_segment(p, a, b));
        a = b;
    }
    best
}

pub(super) fn distance_to_segment(p: Point2, a: Point2, b: Point2) -> f32 {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    if len2 <= 1e-12 {
        return p.distance(a);
    }
    let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0);
    p.distance(Point2::new(a.x + t * dx, a.y + t * dy))
}
