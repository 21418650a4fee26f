//! Sensor readings placed on the computer's clock by the sensor's own clock, not by when the
//! program happened to read them: passive synchronisation after E. Olson, "A passive solution
//! to the sensor synchronization problem", IEEE/RSJ IROS 2010.
//!
//! A reading taken at device time `d` arrives at host time `a = d + offset + delay`, where the
//! delay (transmission, buffering, the program not being scheduled) is never negative and is
//! close to its minimum for some readings. So `offset + min delay` is estimated as the
//! minimum of `a - d` over the readings, allowed to grow slowly (a device clock a little
//! slower than the host's), and each reading is placed at `d + estimate`: on the host's clock,
//! never later than its arrival, and no longer moved by how late the program read it. Under
//! load the pump reads a status packet or a scan tens of milliseconds late; placed by arrival,
//! a scan then lands on the odometry of another moment (a wall a cell off, an inflated cell
//! across the path, a re-plan the same seed did not make on another run).
//!
//! Two devices here:
//! - an LMS1xx stamps each scan with its time since start-up (µs, 32 bits, wrapping every
//!   71.6 minutes);
//! - the P3-DX's ARCOS firmware sends a status packet every SIP cycle (100 ms) but stamps none:
//!   its device time is the cycle count ([`PeriodicClock`]), a packet lost to a bad checksum
//!   showing as an arrival gap of about two cycles.

/// How much faster the device's clock may run behind the host's before the estimate follows
/// (the offset may grow by this fraction of the device time elapsed): 1 %, far above a real
/// clock's drift (tens of ppm), so that the estimate also recovers within seconds from a
/// cycle the [`PeriodicClock`] failed to count.
pub const CREEP: f64 = 0.01;

/// A reading that arrives this much later than its placement, or whose device time went
/// backwards, starts the estimate afresh (the device restarted, the link was reconnected) \[s\].
pub const RESYNC_S: f64 = 1.0;

/// The offset of one device's clock from the host's (Olson's minimum-delay estimate).
#[derive(Clone, Debug, Default)]
pub struct PassiveClock {
    /// `offset + min delay` \[s\], and the device time it was last updated at.
    estimate: Option<(f64, f64)>,
}

impl PassiveClock {
    /// A clock with no reading yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the estimate (a reconnected device's clock starts over).
    pub fn reset(&mut self) {
        self.estimate = None;
    }

    /// Places a reading taken at `device_s` (the device's clock) that arrived at `arrival_s`
    /// (the host's) on the host's clock: never later than `arrival_s`.
    pub fn place(&mut self, arrival_s: f64, device_s: f64) -> f64 {
        let seen = arrival_s - device_s;
        let offset = match self.estimate {
            Some((offset, at_s)) if device_s >= at_s => {
                let grown = offset + CREEP * (device_s - at_s);
                if seen - grown > RESYNC_S {
                    seen
                } else {
                    grown.min(seen)
                }
            }
            _ => seen,
        };
        self.estimate = Some((offset, device_s));
        device_s + offset
    }
}

/// The device time of a stream that sends one reading per `period_s` and stamps none (the
/// ARCOS status packets): the count of periods, a gap in arrivals of about `n` periods counting
/// `n` (readings lost), placed on the host's clock by a [`PassiveClock`].
#[derive(Clone, Debug)]
pub struct PeriodicClock {
    period_s: f64,
    last_arrival_s: Option<f64>,
    device_s: f64,
    clock: PassiveClock,
}

impl PeriodicClock {
    /// A stream of one reading every `period_s` seconds.
    pub fn new(period_s: f64) -> Self {
        Self {
            period_s,
            last_arrival_s: None,
            device_s: 0.0,
            clock: PassiveClock::new(),
        }
    }

    /// Starts over (a reconnected robot).
    pub fn reset(&mut self) {
        *self = Self::new(self.period_s);
    }

    /// Places the reading that arrived at `arrival_s` on the host's clock.
    pub fn place(&mut self, arrival_s: f64) -> f64 {
        if let Some(last) = self.last_arrival_s {
            // Readings queued behind a late one arrive together (a gap under half a period:
            // one period each); a gap of n periods is n - 1 readings lost. A late reading is
            // counted as a loss too, and the estimate then steps down to the truth at the
            // next reading on time.
            let periods = ((arrival_s - last) / self.period_s).round().max(1.0);
            self.device_s += periods * self.period_s;
        }
        self.last_arrival_s = Some(arrival_s);
        self.clock.place(arrival_s, self.device_s)
    }
}

/// The device time of an LMS1xx scan \[s\]: its 32-bit microseconds since start-up, unwrapped.
#[derive(Clone, Debug, Default)]
pub struct WrappingMicros {
    last: Option<u32>,
    wraps: u64,
}

impl WrappingMicros {
    /// The time of `us` \[s\], counting the wraps seen so far.
    pub fn seconds(&mut self, us: u32) -> f64 {
        if let Some(last) = self.last
            // A wrap (not a restart: a restarted laser counts from near zero, far from the
            // top of the range).
            && us < last
            && last - us > u32::MAX / 2
        {
            self.wraps += 1;
        }
        self.last = Some(us);
        (self.wraps as f64 * (f64::from(u32::MAX) + 1.0) + f64::from(us)) * 1e-6
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_readings_are_placed_at_their_device_time_plus_the_least_delay() {
        let mut c = PassiveClock::new();
        // Device clock 100 s behind the host's, delays 2 ms at least, up to 60 ms.
        let delays = [0.010, 0.002, 0.060, 0.004, 0.030, 0.002, 0.045];
        let mut placed = Vec::new();
        for (k, d) in delays.iter().enumerate() {
            let device = k as f64 * 0.02;
            placed.push(c.place(device + 100.0 + d, device));
        }
        // From the first 2 ms reading on, each is placed 2 ms after it was taken, however late
        // it arrived (within the creep).
        for (k, p) in placed.iter().enumerate().skip(1) {
            let taken = k as f64 * 0.02 + 100.0;
            assert!((p - taken - 0.002).abs() < 1e-3, "{k}: {p} vs {taken}");
            assert!(*p <= taken + delays[k] + 1e-12);
        }
    }

    #[test]
    fn a_restarted_device_or_a_long_gap_starts_the_estimate_afresh() {
        let mut c = PassiveClock::new();
        assert!((c.place(10.0, 1.0) - 10.0).abs() < 1e-9);
        // The device restarted: its clock went back.
        assert!((c.place(11.0, 0.5) - 11.0).abs() < 1e-9);
        // A reading 5 s later than the estimate says: a new offset.
        assert!((c.place(17.0, 1.5) - 17.0).abs() < 1e-9);
    }

    #[test]
    fn periodic_readings_are_counted_through_bursts_and_losses() {
        let mut c = PeriodicClock::new(0.1);
        // On time (1 ms after each period), then one reading 80 ms late with the next queued
        // behind it, then one lost, then on time again for 3 s.
        let mut readings = vec![(0.001, 0.0), (0.101, 0.1), (0.201, 0.2)];
        readings.extend([(0.381, 0.3), (0.382, 0.4)]);
        readings.extend((5..40).filter(|&k| k != 7).map(|k| {
            let t = f64::from(k) * 0.1;
            (t + 0.001, t)
        }));
        let placed: Vec<f64> = readings.iter().map(|&(a, _)| c.place(a)).collect();
        for (k, (&p, &(a, t))) in placed.iter().zip(&readings).enumerate() {
            // Never after the arrival; once on time again, within 20 ms of the reading's
            // time (the late reading was counted as a loss: the estimate stepped down and
            // creeps back), and within 2 ms after two seconds.
            assert!(p <= a + 1e-12, "{k}");
            if !(0.25..=0.45).contains(&a) {
                assert!((p - t - 0.001).abs() < 0.02, "{k}: {p} vs {t}");
            }
            if !(0.25..=2.5).contains(&a) {
                assert!((p - t - 0.001).abs() < 0.002, "{k}: {p} vs {t}");
            }
        }
    }

    #[test]
    fn laser_microseconds_unwrap() {
        let mut w = WrappingMicros::default();
        assert!((w.seconds(u32::MAX - 999) - (f64::from(u32::MAX) - 999.0) * 1e-6).abs() < 1e-9);
        let after = w.seconds(1000);
        assert!((after - (f64::from(u32::MAX) + 1001.0) * 1e-6).abs() < 1e-9);
        // A restart (back to near zero from the middle of the range) is no wrap.
        let mut w = WrappingMicros::default();
        w.seconds(2_000_000_000);
        assert!((w.seconds(5) - 5e-6).abs() < 1e-12);
    }
}
