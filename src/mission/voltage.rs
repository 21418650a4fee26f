//! The battery-voltage watch: when the voltage the robot reports stays low, the mission ends
//! (or returns to its start, [`super::MissionConfig::return_to_start`]).
//!
//! A lead-acid battery's voltage sags under load (a P3-DX accelerating draws several amperes)
//! and recovers at rest, so one low reading says little. The watch is a comparator with
//! hysteresis (a Schmitt trigger: O. H. Schmitt, "A thermionic trigger", Journal of
//! Scientific Instruments 15, 1938) followed by a hold time: a reading below
//! [`VoltageConfig::low_v`] starts a timer; only a reading at or above `low_v +
//! hysteresis_v` stops it; once the timer has run [`VoltageConfig::hold_s`] the watch trips,
//! for good (a battery that recovers at rest is still nearly empty).

use crate::control::Time;

/// Settings of the voltage watch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoltageConfig {
    /// Below this voltage the battery counts as low \[V\]; 0 turns the watch off.
    pub low_v: f32,
    /// A low spell ends only once the voltage is back at `low_v + hysteresis_v` \[V\].
    pub hysteresis_v: f32,
    /// How long a low spell must last before the mission ends \[s\].
    pub hold_s: f32,
}

impl Default for VoltageConfig {
    /// 11.5 V (a P3-DX's 12 V lead-acid batteries at about a fifth of their charge; the
    /// robot's own low-battery alarm, FLASH `LowBattery`, is 11.0 V as shipped), 0.3 V of
    /// hysteresis, 5 s.
    fn default() -> Self {
        Self {
            low_v: 11.5,
            hysteresis_v: 0.3,
            hold_s: 5.0,
        }
    }
}

/// The watch's state: fed every voltage reading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoltageWatch {
    /// When the current low spell began.
    low_since: Option<Time>,
    /// The watch tripped.
    tripped: bool,
    /// The latest reading \[V\].
    last_v: Option<f32>,
}

impl VoltageWatch {
    /// A watch that has seen nothing.
    pub const fn new() -> Self {
        Self {
            low_since: None,
            tripped: false,
            last_v: None,
        }
    }

    /// A reading of `volts` at `now`; returns `true` at the reading that trips the watch. A
    /// reading that is not finite or not positive (no voltage reported) is ignored.
    pub fn update(&mut self, config: &VoltageConfig, now: Time, volts: f32) -> bool {
        if !(volts.is_finite() && volts > 0.0) {
            return false;
        }
        self.last_v = Some(volts);
        if self.tripped || config.low_v <= 0.0 {
            return false;
        }
        if volts < config.low_v {
            let since = *self.low_since.get_or_insert(now);
            if now.secs_since(since) >= config.hold_s {
                self.tripped = true;
                return true;
            }
        } else if volts >= config.low_v + config.hysteresis_v {
            self.low_since = None;
        }
        false
    }

    /// Whether the voltage has stayed low for the hold time.
    pub fn tripped(&self) -> bool {
        self.tripped
    }

    /// The latest reading \[V\].
    pub fn last_v(&self) -> Option<f32> {
        self.last_v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(s: f32) -> Time {
        Time::from_secs_f64(f64::from(s))
    }

    #[test]
    fn a_sag_under_load_does_not_trip_a_steady_low_voltage_does() {
        let c = VoltageConfig::default();
        let mut w = VoltageWatch::new();
        // 12.4 V at rest, sagging to 11.2 V for 2 s while accelerating, ten times.
        let mut s = 0.0;
        for _ in 0..10 {
            for _ in 0..20 {
                assert!(!w.update(&c, t(s), 11.2));
                s += 0.1;
            }
            for _ in 0..30 {
                assert!(!w.update(&c, t(s), 12.4));
                s += 0.1;
            }
        }
        assert!(!w.tripped());
        // Now the voltage stays low: tripped after the hold time, once.
        let low_from = s;
        let mut tripped_at = None;
        while s < low_from + 10.0 {
            if w.update(&c, t(s), 11.3) {
                assert!(tripped_at.is_none());
                tripped_at = Some(s);
            }
            s += 0.1;
        }
        let at = tripped_at.expect("tripped");
        assert!(
            at >= low_from + c.hold_s && at < low_from + c.hold_s + 0.2,
            "{at}"
        );
        // It stays tripped, even if the voltage recovers at rest.
        assert!(!w.update(&c, t(s), 12.6));
        assert!(w.tripped());
        assert_eq!(w.last_v(), Some(12.6));
    }

    #[test]
    fn only_a_recovery_past_the_hysteresis_restarts_the_hold() {
        let c = VoltageConfig::default();
        let mut w = VoltageWatch::new();
        // Hovering just around the threshold (below, then 0.1 V above): the spell goes on.
        let mut tripped = false;
        for i in 0..60u32 {
            let v = if i.is_multiple_of(2) { 11.45 } else { 11.6 };
            tripped |= w.update(&c, t(i as f32 * 0.1), v);
        }
        assert!(tripped);
        // Back above low + hysteresis between short dips: never.
        let mut w = VoltageWatch::new();
        let mut s = 0.0;
        while s < 60.0 {
            let v = if (s as u32) % 4 < 3 { 11.4 } else { 11.9 };
            assert!(!w.update(&c, t(s), v), "at {s}");
            s += 0.1;
        }
    }

    #[test]
    fn off_at_zero_and_blind_to_missing_readings() {
        let off = VoltageConfig {
            low_v: 0.0,
            ..VoltageConfig::default()
        };
        let mut w = VoltageWatch::new();
        for i in 0..200 {
            assert!(!w.update(&off, t(i as f32 * 0.1), 9.0));
        }
        let c = VoltageConfig::default();
        let mut w = VoltageWatch::new();
        for i in 0..200 {
            let s = i as f32 * 0.1;
            assert!(!w.update(&c, t(s), 0.0));
            assert!(!w.update(&c, t(s), f32::NAN));
        }
        assert_eq!(w.last_v(), None);
    }
}
