//! The mapping motion filter: a scan is integrated into the map only when the robot moved or
//! turned enough since the last integrated scan, or when enough time passed.
//!
//! Sources: GMapping's `linearUpdate` / `angularUpdate` / `temporalUpdate` (G. Grisetti,
//! C. Stachniss and W. Burgard, "Improved Techniques for Grid Mapping with Rao-Blackwellized
//! Particle Filters", IEEE Transactions on Robotics 23(1), 2007; the thresholds of its ROS
//! wrapper) and Cartographer's motion filter (W. Hess, D. Kohler, H. Rapp and D. Andor,
//! "Real-Time Loop Closure in 2D LIDAR SLAM", ICRA 2016; `max_distance_meters`,
//! `max_angle_radians`, `max_time_seconds`). A scan from (nearly) the pose of the previous
//! integrated one adds little the map does not have; skipping it saves the integration's grid
//! walks. Off by default ([`MotionFilterConfig::off`]): the thesis maps every scan.

use crate::control::Time;
use crate::geometry::{Pose2, normalize_angle};
use crate::math;

/// When a scan is integrated into the map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionFilterConfig {
    /// Filter scans at all; `false`: every scan is integrated.
    pub enabled: bool,
    /// A scan is integrated once the robot moved at least this far since the last integrated
    /// scan \[m\].
    pub min_travel_m: f32,
    /// ... or turned at least this much \[rad\].
    pub min_turn_rad: f32,
    /// ... or this long has passed \[s\] (a standing robot still maps what moves around it).
    pub max_interval_s: f32,
}

impl MotionFilterConfig {
    /// Every scan is integrated (the thesis's behaviour; the default).
    pub const fn off() -> Self {
        Self {
            enabled: false,
            min_travel_m: 0.0,
            min_turn_rad: 0.0,
            max_interval_s: 0.0,
        }
    }

    /// The filter on with the thresholds proposed for the P3-DX's 10 Hz scans: 0.2 m
    /// (Cartographer's `max_distance_meters`), 10°, 2 s (see docs/benchmarks.md, issue 24).
    pub const fn standard() -> Self {
        Self::on(0.2, 10.0 * core::f32::consts::PI / 180.0, 2.0)
    }

    /// The filter on with the given thresholds.
    pub const fn on(min_travel_m: f32, min_turn_rad: f32, max_interval_s: f32) -> Self {
        Self {
            enabled: true,
            min_travel_m,
            min_turn_rad,
            max_interval_s,
        }
    }

    /// The first bad threshold, named, with its value: each must be finite and not negative.
    pub fn invalid_field(&self) -> Option<(&'static str, f32)> {
        [
            ("motion_filter.min_travel_m", self.min_travel_m),
            ("motion_filter.min_turn_rad", self.min_turn_rad),
            ("motion_filter.max_interval_s", self.max_interval_s),
        ]
        .into_iter()
        .find(|&(_, v)| !(v.is_finite() && v >= 0.0))
    }
}

impl Default for MotionFilterConfig {
    fn default() -> Self {
        Self::off()
    }
}

/// The filter's memory: where and when the last integrated scan was taken.
#[derive(Clone, Copy, Debug, Default)]
pub struct MotionFilter {
    last: Option<(Time, Pose2)>,
}

impl MotionFilter {
    /// A filter that integrates the next scan.
    pub const fn new() -> Self {
        Self { last: None }
    }

    /// Whether a scan taken at `now` from `pose` is to be integrated; if so it becomes the
    /// reference for the next ones. The first scan is always integrated.
    pub fn admit(&mut self, config: &MotionFilterConfig, now: Time, pose: Pose2) -> bool {
        let due = match self.last {
            _ if !config.enabled => true,
            None => true,
            Some((t, p)) => {
                let moved = p.position().distance(pose.position());
                let turned = math::abs(normalize_angle(pose.theta - p.theta));
                let waited = now.saturating_since(t).as_secs_f32();
                moved >= config.min_travel_m
                    || turned >= config.min_turn_rad
                    || waited >= config.max_interval_s
            }
        };
        if due {
            self.last = Some((now, pose));
        }
        due
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(s: f64) -> Time {
        Time::from_micros((s * 1e6) as u64)
    }

    #[test]
    fn off_admits_every_scan() {
        let mut f = MotionFilter::new();
        let c = MotionFilterConfig::off();
        let p = Pose2::new(1.0, 2.0, 0.3);
        assert!((0..5).all(|k| f.admit(&c, t(k as f64 * 0.1), p)));
    }

    #[test]
    fn admits_after_travel_turn_or_time_measured_from_the_last_admitted_scan() {
        let c = MotionFilterConfig::on(0.2, 0.1, 1.0);
        let mut f = MotionFilter::new();
        assert!(f.admit(&c, t(0.0), Pose2::new(0.0, 0.0, 0.0)), "first scan");
        // Small moves do not add up scan to scan: they count from the last admitted pose.
        assert!(!f.admit(&c, t(0.1), Pose2::new(0.1, 0.0, 0.0)));
        assert!(!f.admit(&c, t(0.2), Pose2::new(0.15, 0.0, 0.05)));
        assert!(f.admit(&c, t(0.3), Pose2::new(0.2, 0.0, 0.05)), "travel");
        assert!(!f.admit(&c, t(0.4), Pose2::new(0.2, 0.0, 0.1)));
        assert!(f.admit(&c, t(0.5), Pose2::new(0.2, 0.0, 0.16)), "turn");
        // Across ±π the turn is the short way round.
        let mut g = MotionFilter::new();
        assert!(g.admit(&c, t(0.0), Pose2::new(0.0, 0.0, 3.1)));
        assert!(!g.admit(&c, t(0.1), Pose2::new(0.0, 0.0, -3.1)));
        assert!(!f.admit(&c, t(1.4), Pose2::new(0.2, 0.0, 0.16)));
        assert!(f.admit(&c, t(1.5), Pose2::new(0.2, 0.0, 0.16)), "time");
    }

    #[test]
    fn bad_thresholds_are_named() {
        assert_eq!(MotionFilterConfig::on(0.2, 0.1, 1.0).invalid_field(), None);
        let bad = MotionFilterConfig::on(0.2, f32::NAN, 1.0).invalid_field();
        assert_eq!(bad.map(|b| b.0), Some("motion_filter.min_turn_rad"));
        let bad = MotionFilterConfig::on(0.2, 0.1, -1.0).invalid_field();
        assert_eq!(bad, Some(("motion_filter.max_interval_s", -1.0)));
    }
}
