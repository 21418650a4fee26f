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

use core::time::Duration;

/// A point in time on the caller's monotonic clock, in whole microseconds since an arbitrary
/// origin (the onboard runtime uses its start; the simulator uses simulated time from 0).
///
/// This is the one time type of the core: the control and mission layers take `now: Time`
/// and never read a clock. Differences between two `Time`s are [`core::time::Duration`]s.
/// Microseconds give exact arithmetic over 584 000 years and resolve the 100 ms ARCOS cycle
/// and a 25 Hz laser without rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
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

    /// Seconds elapsed since `earlier` [s]; zero if `earlier` is later than `self`.
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
        write!(f, "{}.{:06} s", self.micros / 1_000_000, self.micros % 1_000_000)
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
        assert_eq!(Time::from_micros(u64::MAX) + Duration::from_secs(5), Time::from_micros(u64::MAX));
    }
}
