//! The odometry poses of the last seconds with their times, so that a scan is placed at the
//! pose the robot had when the scan was taken rather than at the latest status packet's.
//!
//! The P3-DX reports odometry every 100 ms and an LMS1xx scans every 40 ms: a scan falls
//! between two status packets, and while the robot turns at 60 deg/s the pose of the packet
//! before it is up to 6° off. [`PoseHistory::at`] interpolates linearly between the two
//! readings around a time (the heading along the shorter arc), as odometry-based scan
//! de-skewing does (e.g. the motion interpolation of Hess et al. 2016, Cartographer's pose
//! extrapolator); a time after the newest reading is not extrapolated: the caller waits for
//! the next one.

use std::collections::VecDeque;

use crate::geometry::{Pose2, normalize_angle};

/// Readings kept: 4 s of 10 Hz status packets.
pub const POSE_HISTORY_LEN: usize = 40;

/// A bounded, time-ordered history of odometry poses.
#[derive(Clone, Debug, Default)]
pub struct PoseHistory {
    readings: VecDeque<(f64, Pose2)>,
}

/// Where a time falls in the history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PoseAt {
    /// Between two readings (or on one): the interpolated pose.
    Pose(Pose2),
    /// After the newest reading: wait for the next one.
    Later,
    /// Before the oldest reading kept (or the history is empty).
    TooOld,
}

impl PoseHistory {
    /// An empty history.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the reading of time `t_s`; a reading older than the newest one replaces the whole
    /// history (time went back: a restarted session), and the oldest readings are dropped
    /// beyond [`POSE_HISTORY_LEN`].
    pub fn push(&mut self, t_s: f64, pose: Pose2) {
        if self.readings.back().is_some_and(|&(t, _)| t_s < t) {
            self.readings.clear();
        }
        if self.readings.len() == POSE_HISTORY_LEN {
            self.readings.pop_front();
        }
        self.readings.push_back((t_s, pose));
    }

    /// Forgets every reading (after a jump in the odometry: a reset robot).
    pub fn clear(&mut self) {
        self.readings.clear();
    }

    /// The newest reading.
    pub fn latest(&self) -> Option<(f64, Pose2)> {
        self.readings.back().copied()
    }

    /// The pose at time `t_s`.
    pub fn at(&self, t_s: f64) -> PoseAt {
        let (Some(&(first_t, first)), Some(&(last_t, last))) =
            (self.readings.front(), self.readings.back())
        else {
            return PoseAt::TooOld;
        };
        if t_s > last_t {
            return PoseAt::Later;
        }
        if t_s < first_t {
            return PoseAt::TooOld;
        }
        if t_s == last_t {
            return PoseAt::Pose(last);
        }
        if t_s == first_t {
            return PoseAt::Pose(first);
        }
        // The first reading later than t_s (readings are in time order).
        let after = self.readings.partition_point(|&(t, _)| t <= t_s);
        let (t0, p0) = self.readings[after - 1];
        let (t1, p1) = self.readings[after];
        let span = t1 - t0;
        let f = if span > 0.0 {
            ((t_s - t0) / span) as f32
        } else {
            1.0
        };
        let turn = normalize_angle(p1.theta - p0.theta);
        PoseAt::Pose(Pose2::new(
            p0.x + f * (p1.x - p0.x),
            p0.y + f * (p1.y - p0.y),
            normalize_angle(p0.theta + f * turn),
        ))
    }

    /// The time between the two readings around `t_s` \[s\] (`None` outside the history):
    /// what the interpolation at `t_s` spans. One status period (100 ms) normally; after
    /// the pump or the link stalled, the gap the robot's motion in it is unknown across
    /// (status packets queued in the socket all arrive, and are placed, at the gap's end).
    pub fn span_at(&self, t_s: f64) -> Option<f64> {
        let ((t0, _), (t1, _)) = self.readings_around(t_s)?;
        Some(t1 - t0)
    }

    /// How far the robot turned between the readings around `t_s`, per second \[rad/s\]
    /// (`None` outside the history).
    pub fn turn_rate_at(&self, t_s: f64) -> Option<f32> {
        let ((t0, p0), (t1, p1)) = self.readings_around(t_s)?;
        let span = (t1 - t0) as f32;
        (span > 0.0).then(|| normalize_angle(p1.theta - p0.theta).abs() / span)
    }

    /// The two readings around `t_s` (`None` outside the history or with fewer than two).
    fn readings_around(&self, t_s: f64) -> Option<((f64, Pose2), (f64, Pose2))> {
        let last_t = self.readings.back()?.0;
        if t_s > last_t || t_s < self.readings.front()?.0 || self.readings.len() < 2 {
            return None;
        }
        let after = self
            .readings
            .partition_point(|&(t, _)| t < t_s)
            .clamp(1, self.readings.len() - 1);
        Some((self.readings[after - 1], self.readings[after]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    fn close(a: Pose2, b: Pose2) -> bool {
        (a.x - b.x).abs() < 1e-5
            && (a.y - b.y).abs() < 1e-5
            && normalize_angle(a.theta - b.theta).abs() < 1e-5
    }

    #[test]
    fn the_span_at_a_time_is_the_gap_between_the_readings_around_it() {
        let mut h = PoseHistory::new();
        assert_eq!(h.span_at(1.0), None);
        h.push(1.0, Pose2::new(0.0, 0.0, 0.0));
        h.push(1.1, Pose2::new(0.1, 0.0, 0.0));
        h.push(2.1, Pose2::new(1.1, 0.0, 0.0));
        h.push(2.1, Pose2::new(1.2, 0.0, 0.0));
        assert!((h.span_at(1.05).unwrap() - 0.1).abs() < 1e-9);
        assert!((h.span_at(1.5).unwrap() - 1.0).abs() < 1e-9);
        assert_eq!(h.span_at(0.9), None);
        assert_eq!(h.span_at(2.2), None);
    }

    #[test]
    fn a_time_between_two_readings_gets_the_interpolated_pose() {
        let mut h = PoseHistory::new();
        h.push(1.0, Pose2::new(0.0, 0.0, 0.0));
        h.push(1.1, Pose2::new(0.04, 0.0, 0.1));
        h.push(1.2, Pose2::new(0.08, 0.02, 0.2));
        let PoseAt::Pose(p) = h.at(1.125) else {
            panic!("{:?}", h.at(1.125))
        };
        assert!(close(p, Pose2::new(0.05, 0.005, 0.125)), "{p:?}");
        assert_eq!(h.at(1.2), PoseAt::Pose(Pose2::new(0.08, 0.02, 0.2)));
        assert_eq!(h.at(1.0), PoseAt::Pose(Pose2::new(0.0, 0.0, 0.0)));
        assert_eq!(h.at(1.21), PoseAt::Later);
        assert_eq!(h.at(0.9), PoseAt::TooOld);
        let rate = h.turn_rate_at(1.15).unwrap();
        assert!((rate - 1.0).abs() < 1e-4, "{rate}");
    }

    #[test]
    fn the_heading_is_interpolated_along_the_shorter_arc() {
        let mut h = PoseHistory::new();
        h.push(0.0, Pose2::new(0.0, 0.0, PI - 0.1));
        h.push(0.1, Pose2::new(0.0, 0.0, -PI + 0.1));
        let PoseAt::Pose(p) = h.at(0.05) else {
            panic!()
        };
        assert!(close(p, Pose2::new(0.0, 0.0, PI)), "{p:?}");
    }

    #[test]
    fn the_history_is_bounded_and_restarts_when_time_goes_back() {
        let mut h = PoseHistory::new();
        for i in 0..100 {
            h.push(f64::from(i) * 0.1, Pose2::new(i as f32, 0.0, 0.0));
        }
        assert_eq!(h.at(0.0), PoseAt::TooOld);
        assert!(matches!(h.at(9.0), PoseAt::Pose(_)));
        h.push(1.0, Pose2::new(5.0, 5.0, 0.0));
        assert_eq!(h.latest(), Some((1.0, Pose2::new(5.0, 5.0, 0.0))));
        assert_eq!(h.at(0.5), PoseAt::TooOld);
        assert_eq!(h.turn_rate_at(1.0), None);
    }
}
