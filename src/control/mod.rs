//! Odometry, PID, path following, robot commands and the safety monitor.
//!
//! Everything here is sans-IO: time comes in as a [`Time`] value, odometry as the raw integer
//! fields the P3-DX reports, scans as [`crate::sensor::Scan`]; the output is a
//! [`command::RobotCommand`] in ARCOS units, always clamped to the board's [`command::Limits`].
//!
//! One control period, as the mission layer runs it:
//!
//! ```text
//! SIP (x_raw, y_raw, th_raw) ──► odometry::ArcosOdometry ──► odom pose
//!                                 odometry::MapFromOdom  ──► map pose
//! map pose + path ──► follower::WaypointFollower (Controller) ──► MotionCommand
//! MotionCommand + flags + scan ──► safety::SafetyMonitor::filter ──► RobotCommand, SafetyEvent
//! ```
//!
//! Frames: `odom` is where the robot's own dead reckoning puts it (origin where its odometry
//! was last reset); `map` is the frame of the occupancy grid. Both are x east, y north,
//! heading counter-clockwise, metres and radians; [`odometry::MapFromOdom`] links them.

pub mod command;
pub mod follower;
pub mod odometry;
pub mod pid;
pub mod safety;
#[cfg(test)]
pub mod sim_double;
pub mod umbmark;

use core::time::Duration;

/// A point in time on the caller's monotonic clock, in whole microseconds since an arbitrary
/// origin (the onboard runtime uses its start; the simulator uses simulated time from 0).
///
/// This is the one time type of the core: the control and mission layers take `now: Time`
/// and never read a clock. Differences between two `Time`s are [`core::time::Duration`]s.
/// Microseconds give exact arithmetic over 584 000 years and resolve the 100 ms ARCOS cycle
/// and a 25 Hz laser without rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, bytemuck::Zeroable)]
pub struct Time {
    micros: u64,
}

impl Time {
    /// The clock's origin.
    pub const ZERO: Time = Time { micros: 0 };

    /// `micros` microseconds after the origin.
    pub const fn from_micros(micros: u64) -> Self {
        Self { micros }
    }

    /// `millis` milliseconds after the origin.
    pub const fn from_millis(millis: u64) -> Self {
        Self {
            micros: millis.saturating_mul(1000),
        }
    }

    /// `secs` seconds after the origin, rounded to the microsecond; negative or non-finite
    /// values give the origin.
    pub fn from_secs_f64(secs: f64) -> Self {
        if secs.is_finite() && secs > 0.0 {
            // `as` saturates at u64::MAX for huge values.
            Self {
                micros: (secs * 1e6 + 0.5) as u64,
            }
        } else {
            Self::ZERO
        }
    }

    /// Microseconds since the origin.
    pub const fn as_micros(self) -> u64 {
        self.micros
    }

    /// Seconds since the origin.
    pub fn as_secs_f64(self) -> f64 {
        self.micros as f64 * 1e-6
    }

    /// Time elapsed since `earlier`; zero if `earlier` is later than `self`.
    pub fn saturating_since(self, earlier: Time) -> Duration {
        Duration::from_micros(self.micros.saturating_sub(earlier.micros))
    }

    /// Seconds elapsed since `earlier` \[s\]; zero if `earlier` is later than `self`.
    pub fn secs_since(self, earlier: Time) -> f32 {
        self.micros.saturating_sub(earlier.micros) as f32 * 1e-6
    }

    /// This time plus `d`, saturating at the end of the clock.
    pub fn saturating_add(self, d: Duration) -> Time {
        let add = u64::try_from(d.as_micros()).unwrap_or(u64::MAX);
        Time {
            micros: self.micros.saturating_add(add),
        }
    }
}

impl core::ops::Add<Duration> for Time {
    type Output = Time;

    /// Saturating addition (see [`Time::saturating_add`]).
    fn add(self, d: Duration) -> Time {
        self.saturating_add(d)
    }
}

impl core::fmt::Display for Time {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{}.{:06} s",
            self.micros / 1_000_000,
            self.micros % 1_000_000
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_differences_are_exact_and_saturate() {
        let a = Time::from_millis(1_500);
        let b = a + Duration::from_millis(100);
        assert_eq!(b.as_micros(), 1_600_000);
        assert_eq!(b.saturating_since(a), Duration::from_millis(100));
        assert_eq!(a.saturating_since(b), Duration::ZERO);
        assert!((b.secs_since(a) - 0.1).abs() < 1e-6);
        assert_eq!(Time::from_secs_f64(-3.0), Time::ZERO);
        assert_eq!(Time::from_secs_f64(f64::NAN), Time::ZERO);
        assert_eq!(Time::from_secs_f64(0.25).as_micros(), 250_000);
        assert_eq!(
            Time::from_micros(u64::MAX) + Duration::from_secs(5),
            Time::from_micros(u64::MAX)
        );
    }
}

/// The whole control chain on the unicycle double: ARCOS odometry (crossing a 15-bit wrap),
/// the map-from-odom transform, the follower and the safety monitor.
#[cfg(test)]
mod chain_tests {
    use super::command::{Limits, RobotCommand};
    use super::follower::{Controller, FollowStatus, FollowerConfig, WaypointFollower};
    use super::odometry::{ArcosOdometry, MapFromOdom};
    use super::safety::{RobotFlags, SafetyConfig, SafetyEvent, SafetyInputs, SafetyMonitor};
    use super::sim_double::{Slip, Unicycle};
    use super::*;
    use crate::geometry::{Point2, Pose2};
    use crate::sensor::{Beam, LaserConfig, Scan};

    struct Chain {
        robot: Unicycle,
        odometry: ArcosOdometry,
        map_from_odom: MapFromOdom,
        follower: WaypointFollower,
        monitor: SafetyMonitor,
        laser: LaserConfig,
        scan: Scan,
        flags: RobotFlags,
        now: Time,
    }

    impl Chain {
        /// The robot at `map_start`; its odometry says `odom_start` (near the XPOS wrap).
        fn new(map_start: Pose2, odom_start: Pose2, path: &[Point2], seed: u64) -> Self {
            let robot = Unicycle::new(odom_start, Slip::thesis(), seed);
            let mut odometry = ArcosOdometry::new();
            let (x, y, th) = robot.arcos_raw();
            let first = odometry.update(x, y, th);
            let map_from_odom = MapFromOdom::from_start(map_start, first);
            let mut follower = WaypointFollower::new(FollowerConfig::default()).unwrap();
            follower.set_path(path).unwrap();
            let mut monitor = SafetyMonitor::new(SafetyConfig::default(), Limits::default());
            monitor.acknowledge_replan().unwrap();
            let laser = LaserConfig::thesis();
            let mut scan = Scan::new();
            for i in 0..laser.beam_count as usize {
                let beam = Beam {
                    angle_rad: laser.beam_angle(i),
                    range_m: None,
                };
                scan.push(beam).unwrap();
            }
            Self {
                robot,
                odometry,
                map_from_odom,
                follower,
                monitor,
                laser,
                scan,
                flags: RobotFlags::nominal(),
                now: Time::ZERO,
            }
        }

        fn map_pose(&self) -> Pose2 {
            self.map_from_odom.map_pose(self.odometry.pose_odom())
        }

        /// One 100 ms period: sense, decide, filter, act.
        fn period(&mut self) -> (RobotCommand, FollowStatus, Option<SafetyEvent>) {
            let (x, y, th) = self.robot.arcos_raw();
            let pose_odom = self.odometry.update(x, y, th);
            let pose_map = self.map_from_odom.map_pose(pose_odom);
            let (proposed, status) = self.follower.update(self.now, pose_map);
            let inputs = SafetyInputs {
                pose_odom,
                odometry_time: Some(self.now),
                scan: Some(&self.scan),
                scan_time: Some(self.now),
                laser: &self.laser,
                flags: self.flags,
                remembered: &[],
            };
            let (cmd, event) = self.monitor.filter(self.now, proposed, &inputs);
            if let Some(v) = cmd.velocity() {
                assert!(self.monitor.limits().allows(v));
            }
            self.robot.apply(cmd, 0.1);
            self.now = self.now + Duration::from_millis(100);
            (cmd, status, event)
        }
    }

    #[test]
    fn drives_a_path_through_the_whole_chain_across_an_odometry_wrap() {
        let map_start = Pose2::new(2.0, 3.0, 0.0);
        // 32.5 m east in odom: XPOS wraps 0.27 m into the drive.
        let odom_start = Pose2::new(32.5, -0.4, 0.0);
        let path = [
            Point2::new(4.0, 3.0),
            Point2::new(4.0, 4.5),
            Point2::new(2.5, 4.5),
        ];
        for seed in 0..5 {
            let mut chain = Chain::new(map_start, odom_start, &path, seed);
            let mut arrived = false;
            for _ in 0..1500 {
                let (_, status, event) = chain.period();
                assert_eq!(event, None, "seed {seed}");
                if status == FollowStatus::Arrived {
                    arrived = true;
                    break;
                }
            }
            assert!(arrived, "seed {seed}");
            // The unicycle's own frame is the true odom frame; the tracker read the first
            // XPOS as -268 mm (signed 15 bits), so compare through the true start.
            let truth = MapFromOdom::from_start(map_start, odom_start).map_pose(chain.robot.pose());
            let err = truth.position().distance(path[2]);
            assert!(err <= 0.05, "seed {seed}: {err} m from the goal");
            let seen = chain.map_pose();
            assert!(
                seen.position().distance(truth.position()) < 0.003,
                "{seen:?} vs {truth:?}"
            );
        }
    }

    #[test]
    fn a_bumper_hit_mid_drive_stops_the_robot_in_the_same_period() {
        let path = [Point2::new(3.0, 0.0)];
        let mut chain = Chain::new(Pose2::default(), Pose2::default(), &path, 1);
        for _ in 0..20 {
            chain.period();
        }
        assert!(chain.robot.velocity().0 > 0.2, "cruising");
        chain.flags.front_bumper = true;
        let (cmd, _, event) = chain.period();
        assert_eq!(cmd, RobotCommand::Stop);
        assert!(matches!(event, Some(SafetyEvent::Contact { .. })));
        chain.flags.front_bumper = false;
        // Backs off, then holds for a replan; the old path is never resumed.
        let mut replan = false;
        for _ in 0..60 {
            let (cmd, _, event) = chain.period();
            if let Some(v) = cmd.velocity() {
                assert!(v.speed_mm_s() <= 0, "{v:?}");
            }
            replan |= matches!(event, Some(SafetyEvent::RequiresReplan { .. }));
        }
        assert!(replan);
        assert!(chain.monitor.requires_replan());
        assert!(chain.robot.velocity().0.abs() < 1e-6);
    }

    #[test]
    fn an_obstacle_appearing_ahead_stops_the_robot_in_the_same_period() {
        let path = [Point2::new(3.0, 0.0)];
        let mut chain = Chain::new(Pose2::default(), Pose2::default(), &path, 2);
        for _ in 0..20 {
            chain.period();
        }
        // A person steps in 0.45 m ahead of the laser (0.24 m from the bumper; braking from
        // 300 mm/s needs 0.28 m).
        chain.scan.beams_mut()[90].range_m = Some(0.45);
        let (cmd, _, event) = chain.period();
        assert_eq!(cmd, RobotCommand::Stop);
        assert!(matches!(event, Some(SafetyEvent::ObstacleAhead { .. })));
    }
}
