//! Unwrapping the SIP's wrapping odometry counters.
//!
//! XPOS and YPOS are 15-bit counters (ARIA masks them with 0x7FFF): a delta between two
//! consecutive packets larger than half the range means the counter wrapped. THPOS is a heading
//! in 4096 units per turn. Both unwrap to continuous values by taking the shortest signed
//! delta modulo the counter range; this is right as long as the robot moves less than half a
//! range (16.4 m, half a turn) between two packets.

use crate::units::arcos_angle_to_rad;

/// Range of the XPOS/YPOS counters.
pub const POS_RANGE: i32 = 0x8000;
/// Heading units per turn.
pub const ANGLE_RANGE: i32 = 4096;

/// Shortest signed difference `new - old` of two counters modulo `range` (a power of two).
#[inline]
pub fn wrapped_delta(old: i32, new: i32, range: i32) -> i32 {
    let mask = range - 1;
    let d = new.wrapping_sub(old) & mask;
    if d >= range / 2 { d - range } else { d }
}

/// Turns a 15-bit position counter into a continuous position \[mm × DistConvFactor\].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PositionUnwrapper {
    last: Option<u16>,
    total: i64,
}

impl PositionUnwrapper {
    /// An unwrapper that takes its first reading as the starting value.
    pub const fn new() -> Self {
        Self {
            last: None,
            total: 0,
        }
    }

    /// Feeds one raw XPOS/YPOS value (bit 15 ignored); returns the continuous position.
    pub fn update(&mut self, raw: u16) -> i64 {
        let raw = raw & 0x7FFF;
        match self.last {
            None => self.total = raw as i64,
            Some(prev) => {
                self.total += wrapped_delta(prev as i32, raw as i32, POS_RANGE) as i64;
            }
        }
        self.last = Some(raw);
        self.total
    }

    /// The continuous position, if a value was fed.
    pub fn value(&self) -> Option<i64> {
        self.last.map(|_| self.total)
    }
}

/// Turns the 4096-unit THPOS into a continuous heading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HeadingUnwrapper {
    last: Option<i16>,
    total: i64,
}

impl HeadingUnwrapper {
    /// An unwrapper that takes its first reading as the starting value.
    pub const fn new() -> Self {
        Self {
            last: None,
            total: 0,
        }
    }

    /// Feeds one raw THPOS; returns the continuous heading \[2π/4096 rad\].
    pub fn update(&mut self, raw: i16) -> i64 {
        match self.last {
            None => self.total = raw as i64,
            Some(prev) => {
                self.total += wrapped_delta(prev as i32, raw as i32, ANGLE_RANGE) as i64;
            }
        }
        self.last = Some(raw);
        self.total
    }

    /// The continuous heading \[rad\], if a value was fed.
    pub fn heading_rad(&self) -> Option<f32> {
        self.last.map(|_| arcos_angle_to_rad(self.total as f32))
    }
}

/// A position \[mm\] as the 15-bit XPOS/YPOS counter (for emitting SIPs).
#[inline]
pub fn position_to_counter(pos_mm: i64) -> u16 {
    (pos_mm.rem_euclid(POS_RANGE as i64)) as u16
}

/// A heading \[2π/4096 rad\] as THPOS in (-2048, 2048].
#[inline]
pub fn heading_to_counter(units: i64) -> i16 {
    let r = units.rem_euclid(ANGLE_RANGE as i64) as i16;
    if r > 2048 { r - 4096 } else { r }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{range_f32, seeded};

    #[test]
    fn deltas_wrap_both_ways() {
        assert_eq!(wrapped_delta(0x7FF0, 0x0010, POS_RANGE), 0x20);
        assert_eq!(wrapped_delta(0x0010, 0x7FF0, POS_RANGE), -0x20);
        assert_eq!(wrapped_delta(2040, -2040, ANGLE_RANGE), 16);
        assert_eq!(heading_to_counter(2049), -2047);
        assert_eq!(heading_to_counter(2048), 2048);
        assert_eq!(position_to_counter(-1), 0x7FFF);
    }

    #[test]
    fn unwrapping_follows_a_long_random_walk() {
        let mut rng = seeded(3);
        let (mut x, mut th) = (-5_000i64, 100i64);
        let mut ux = PositionUnwrapper::new();
        let mut uth = HeadingUnwrapper::new();
        let x0 = ux.update(position_to_counter(x));
        let th0 = uth.update(heading_to_counter(th));
        for _ in 0..100_000 {
            x += range_f32(&mut rng, -300.0, 400.0) as i64;
            th += range_f32(&mut rng, -500.0, 400.0) as i64;
            let gx = ux.update(position_to_counter(x));
            let gth = uth.update(heading_to_counter(th));
            assert_eq!(gx - x0, x + 5_000);
            assert_eq!(gth - th0, th - 100);
        }
    }
}
