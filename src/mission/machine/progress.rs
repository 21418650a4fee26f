//! The mission's progress watch: a robot that stays within
//! [`MissionConfig::progress_distance_m`](crate::mission::MissionConfig::progress_distance_m)
//! of one place for
//! [`MissionConfig::progress_timeout_s`](crate::mission::MissionConfig::progress_timeout_s)
//! while it should be exploring gets nowhere, whatever it is doing (deciding, replanning,
//! escaping, turning), and the mission ends [`DoneReason::Stuck`](crate::mission::DoneReason)
//! instead of trying for ever.
//!
//! The last line of defence behind the rules that stop a known loop (errands dropped in a row,
//! decisions that gain nothing, failed decisions): it needs no knowledge of the loop. It is
//! ROS move_base's `oscillation_timeout` / `oscillation_distance` (the robot must move that far
//! within that time, or the navigation gives up after its recovery behaviours), measured on
//! odometry, which drifts slowly and is what the robot's wheels did.

use core::time::Duration;

use crate::control::Time;
use crate::geometry::Point2;

/// Where the robot last made progress, and when.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ProgressWatch {
    anchor: Option<(Point2, Time)>,
}

impl ProgressWatch {
    /// Forgets the place: the robot is not expected to move now (starting, faulted, waiting
    /// for another robot), so the time does not count.
    pub(super) fn reset(&mut self) {
        self.anchor = None;
    }

    /// Whether the robot, at `here` (odometry) at `now`, has stayed within `distance_m` of
    /// the place it last made progress from for longer than `timeout`. Moving farther makes
    /// `here` the new place.
    pub(super) fn stalled(
        &mut self,
        now: Time,
        here: Point2,
        distance_m: f32,
        timeout: Duration,
    ) -> bool {
        match self.anchor {
            Some((place, since)) if here.distance(place) <= distance_m => {
                now.saturating_since(since) > timeout
            }
            _ => {
                self.anchor = Some((here, now));
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(s: u64) -> Time {
        Time::ZERO + Duration::from_secs(s)
    }

    #[test]
    fn staying_in_place_past_the_timeout_is_stalled_and_moving_restarts_the_clock() {
        let mut w = ProgressWatch::default();
        let t = Duration::from_secs(120);
        let home = Point2::new(1.0, 1.0);
        assert!(!w.stalled(at(0), home, 0.5, t));
        assert!(!w.stalled(at(100), Point2::new(1.4, 1.0), 0.5, t));
        assert!(!w.stalled(at(120), home, 0.5, t));
        assert!(w.stalled(at(121), Point2::new(0.6, 1.2), 0.5, t));
        // 0.6 m away: progress, the clock starts again there.
        assert!(!w.stalled(at(122), Point2::new(1.6, 1.0), 0.5, t));
        assert!(!w.stalled(at(242), Point2::new(1.6, 1.0), 0.5, t));
        assert!(w.stalled(at(243), Point2::new(1.6, 1.0), 0.5, t));
        // A reset (a fault, a wait) forgets the time spent.
        w.reset();
        assert!(!w.stalled(at(400), Point2::new(1.6, 1.0), 0.5, t));
        assert!(!w.stalled(at(520), Point2::new(1.6, 1.0), 0.5, t));
    }
}
