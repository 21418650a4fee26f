//! What the robot reports: odometry aligned to the map at the start pose, the robot's flags,
//! the latest scan, the trail of places it drove through, and the energy it used.

use core::time::Duration;

use crate::control::Time;
use crate::control::odometry::MapFromOdom;
use crate::control::safety::RobotFlags;
use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::math;
use crate::sensor::Scan;
use crate::units;

use super::super::{FaultReason, MissionStats};
use super::robots::{TRAIL_LEN, TRAIL_SPACING_M};

/// The robot as its inputs describe it.
pub(super) struct Senses {
    pub(super) start_map: Pose2,
    pub(super) map_from_odom: Option<MapFromOdom>,
    pub(super) pose_odom: Pose2,
    pub(super) pose_map: Pose2,
    pub(super) flags: RobotFlags,
    pub(super) odometry_time: Option<Time>,
    pub(super) scan: Scan,
    pub(super) scan_time: Option<Time>,
    pub(super) scans_integrated: u32,
    /// Coverage reported by the caller.
    pub(super) coverage: Option<f32>,
    /// Energy left \[steps\].
    pub(super) battery_steps: f32,
    /// Poses remembered along the way, for clearing the robot's own trail on the shared map.
    pub(super) trail: heapless::Deque<Point2, TRAIL_LEN>,
}

impl Senses {
    pub(super) fn new(start_map: Pose2, battery_steps: f32) -> Self {
        Self {
            start_map,
            map_from_odom: None,
            pose_odom: Pose2::default(),
            pose_map: start_map,
            flags: RobotFlags::nominal(),
            odometry_time: None,
            scan: Scan::new(),
            scan_time: None,
            scans_integrated: 0,
            coverage: None,
            battery_steps,
            trail: heapless::Deque::new(),
        }
    }

    /// Latest odometry and flags; the motion since the last reading is charged to the
    /// battery and counted in `stats`.
    pub(super) fn on_odometry(
        &mut self,
        now: Time,
        pose_odom: Pose2,
        flags: RobotFlags,
        stats: &mut MissionStats,
    ) {
        if !(pose_odom.x.is_finite() && pose_odom.y.is_finite() && pose_odom.theta.is_finite()) {
            // A corrupt reading is no reading: the inputs go stale.
            self.flags = flags;
            return;
        }
        let start_map = self.start_map;
        let transform = *self
            .map_from_odom
            .get_or_insert_with(|| MapFromOdom::from_start(start_map, pose_odom));
        if self.odometry_time.is_some() {
            let d = self.pose_odom.position().distance(pose_odom.position());
            let turn = math::abs(normalize_angle(pose_odom.theta - self.pose_odom.theta));
            let used = units::steps(d, turn);
            self.battery_steps = (self.battery_steps - used).max(0.0);
            stats.steps += used;
            stats.distance_m += d;
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

    /// The latest scan; `mapped` when it was integrated into the map.
    pub(super) fn on_scan(&mut self, now: Time, scan: &Scan, mapped: bool) {
        self.scan.clone_from(scan);
        self.scan_time = Some(now);
        if mapped {
            self.scans_integrated += 1;
        }
    }

    /// The first odometry fixed the map frame and a scan is on the map.
    pub(super) fn ready(&self) -> bool {
        self.map_from_odom.is_some() && self.scans_integrated > 0
    }

    /// The fault in force, if any: e-stop, motors disabled, inputs older than `max_age`.
    pub(super) fn fault_now(&self, now: Time, max_age: Duration) -> Option<FaultReason> {
        if self.flags.estop {
            return Some(FaultReason::EmergencyStop);
        }
        if !self.flags.motors_enabled {
            return Some(FaultReason::MotorsDisabled);
        }
        let fresh = |t: Option<Time>| t.is_some_and(|t| now.saturating_since(t) <= max_age);
        if !(fresh(self.odometry_time) && fresh(self.scan_time)) {
            return Some(FaultReason::StaleInputs);
        }
        None
    }
}
