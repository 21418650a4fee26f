//! Test doubles for the control and mission layers (test builds only).
//!
//! - [`Unicycle`]: a kinematic differential-drive robot that integrates the commanded speed
//!   and turn rate with the board's acceleration limits, multiplicative speed noise, and the
//!   slide at the end of each move that the thesis's PID had to correct (1–2 cm on the real
//!   P3-DX). It can report its pose the way ARCOS does (15-bit mm counters, 4096 units per
//!   turn), so odometry can be tested end to end.
//! - [`ScriptedController`]: a [`Controller`] that answers a fixed command and status.

use crate::control::Time;
use crate::control::command::{MotionCommand, RobotCommand};
use crate::control::follower::{Controller, FollowStatus, FollowerError};
use crate::geometry::{Point2, Pose2};
use crate::math;
use crate::random::{ProjectRng, gaussian, range_f32, seeded};
use crate::units::{deg_to_rad, m_to_mm, mm_to_m, rad_to_arcos_angle};

/// Slip injected into the [`Unicycle`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slip {
    /// Standard deviation of the multiplicative error on the achieved speed (0.05 = 5 %).
    pub speed_noise_fraction: f32,
    /// Standard deviation of the multiplicative error on the achieved turn rate.
    pub turn_noise_fraction: f32,
    /// When the robot is told to stop after driving, it slides on for this many seconds at
    /// its last speed, drawn uniformly from the range \[s\].
    pub stop_slide_s: (f32, f32),
    /// Extra slide distance drawn uniformly from the range at every stop after driving \[m\].
    pub stop_slide_m: (f32, f32),
}

impl Slip {
    /// No slip: the robot does exactly what it is told, within its accelerations.
    pub const fn none() -> Self {
        Self {
            speed_noise_fraction: 0.0,
            turn_noise_fraction: 0.0,
            stop_slide_s: (0.0, 0.0),
            stop_slide_m: (0.0, 0.0),
        }
    }

    /// The slip the thesis reports on the P3-DX: 1–2 cm at the end of each move, with 5 %
    /// speed and turn-rate errors along the way.
    pub const fn thesis() -> Self {
        Self {
            speed_noise_fraction: 0.05,
            turn_noise_fraction: 0.05,
            stop_slide_s: (0.0, 0.0),
            stop_slide_m: (0.01, 0.02),
        }
    }
}

/// A kinematic unicycle robot with acceleration limits and injected slip.
#[derive(Clone, Debug)]
pub struct Unicycle {
    pose: Pose2,
    speed_m_s: f32,
    turn_rate_rad_s: f32,
    /// Translational acceleration and deceleration limit [m/s²].
    pub accel_m_s2: f32,
    /// Rotational acceleration limit [rad/s²].
    pub turn_accel_rad_s2: f32,
    slip: Slip,
    rng: ProjectRng,
    commanded_speed_m_s: f32,
    /// Distance driven \[m\].
    pub distance_m: f32,
    /// Time driven \[s\].
    pub elapsed_s: f32,
}

impl Unicycle {
    /// A robot at rest at `pose` with P3-DX accelerations (300 mm/s², 100 deg/s²).
    pub fn new(pose: Pose2, slip: Slip, seed: u64) -> Self {
        Self {
            pose,
            speed_m_s: 0.0,
            turn_rate_rad_s: 0.0,
            accel_m_s2: 0.3,
            turn_accel_rad_s2: deg_to_rad(100.0),
            slip,
            rng: seeded(seed),
            commanded_speed_m_s: 0.0,
            distance_m: 0.0,
            elapsed_s: 0.0,
        }
    }

    /// The true pose.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// Moves the robot to `pose` (as if pushed).
    pub fn set_pose(&mut self, pose: Pose2) {
        self.pose = pose;
    }

    /// The actual speed [m/s] and turn rate [rad/s].
    pub fn velocity(&self) -> (f32, f32) {
        (self.speed_m_s, self.turn_rate_rad_s)
    }

    /// The pose as ARCOS reports it: (XPOS, YPOS, THPOS).
    pub fn arcos_raw(&self) -> (u16, u16, i16) {
        let x = (math::round(m_to_mm(self.pose.x)) as i64).rem_euclid(0x8000) as u16;
        let y = (math::round(m_to_mm(self.pose.y)) as i64).rem_euclid(0x8000) as u16;
        let th = (math::round(rad_to_arcos_angle(self.pose.theta)) as i32 + 2048).rem_euclid(4096)
            - 2048;
        (x, y, th as i16)
    }

    /// Applies a robot command for `dt_s` seconds (non-velocity commands keep the motion).
    pub fn apply(&mut self, cmd: RobotCommand, dt_s: f32) {
        let motion = cmd.velocity().map_or(
            MotionCommand::from_si(self.commanded_speed_m_s, self.turn_rate_rad_s),
            |v| v.as_motion(),
        );
        self.step(motion, dt_s);
    }

    /// Drives for `dt_s` seconds with `cmd`.
    pub fn step(&mut self, cmd: MotionCommand, dt_s: f32) {
        let v_cmd = mm_to_m(f32::from(cmd.speed_mm_s));
        let w_cmd = deg_to_rad(f32::from(cmd.turn_rate_deg_s));
        if v_cmd == 0.0 && self.commanded_speed_m_s != 0.0 && self.speed_m_s != 0.0 {
            // The end-of-move slide, along the direction of motion.
            let (lo, hi) = self.slip.stop_slide_s;
            let (dlo, dhi) = self.slip.stop_slide_m;
            let t = if hi > lo {
                range_f32(&mut self.rng, lo, hi)
            } else {
                lo
            };
            let extra = if dhi > dlo {
                range_f32(&mut self.rng, dlo, dhi)
            } else {
                dlo
            };
            let slide = self.speed_m_s * t + extra * self.speed_m_s.signum();
            self.translate(slide);
        }
        self.commanded_speed_m_s = v_cmd;
        let dv = self.accel_m_s2 * dt_s;
        self.speed_m_s += (v_cmd - self.speed_m_s).clamp(-dv, dv);
        let dw = self.turn_accel_rad_s2 * dt_s;
        self.turn_rate_rad_s += (w_cmd - self.turn_rate_rad_s).clamp(-dw, dw);
        let v = self.speed_m_s * (1.0 + self.slip.speed_noise_fraction * gaussian(&mut self.rng));
        let w =
            self.turn_rate_rad_s * (1.0 + self.slip.turn_noise_fraction * gaussian(&mut self.rng));
        let mid = self.pose.theta + 0.5 * w * dt_s;
        let d = v * dt_s;
        self.pose = Pose2::new(
            self.pose.x + d * math::cos(mid),
            self.pose.y + d * math::sin(mid),
            self.pose.theta + w * dt_s,
        );
        self.distance_m += math::abs(d);
        self.elapsed_s += dt_s;
    }

    fn translate(&mut self, d: f32) {
        self.pose.x += d * math::cos(self.pose.theta);
        self.pose.y += d * math::sin(self.pose.theta);
        self.distance_m += math::abs(d);
    }
}

/// A [`Controller`] that always answers the same command and status, and counts its calls.
#[derive(Clone, Debug)]
pub struct ScriptedController {
    /// The command returned by every update.
    pub command: MotionCommand,
    /// The status returned by every update.
    pub status: FollowStatus,
    /// `set_path` calls so far.
    pub paths_set: u32,
    /// `update` calls so far.
    pub updates: u32,
    /// Time of the last update.
    pub last_update: Option<Time>,
    /// The last path's first waypoint, if any.
    pub first_waypoint: Option<Point2>,
}

impl ScriptedController {
    /// A controller answering `command` and `status`.
    pub fn new(command: MotionCommand, status: FollowStatus) -> Self {
        Self {
            command,
            status,
            paths_set: 0,
            updates: 0,
            last_update: None,
            first_waypoint: None,
        }
    }
}

impl Controller for ScriptedController {
    fn set_path(&mut self, waypoints: &[Point2]) -> Result<(), FollowerError> {
        if waypoints.is_empty() {
            return Err(FollowerError::EmptyPath);
        }
        self.paths_set += 1;
        self.first_waypoint = waypoints.first().copied();
        Ok(())
    }

    fn clear(&mut self) {
        self.first_waypoint = None;
    }

    fn update(&mut self, now: Time, _pose_map: Pose2) -> (MotionCommand, FollowStatus) {
        self.updates += 1;
        self.last_update = Some(now);
        (self.command, self.status)
    }
}
