//! Unit conversions, all in one place.
//!
//! Internally the core works in metres, radians and seconds. The wire protocols speak
//! millimetres, degrees, ARCOS angle units (4096 per turn) and tenths of a degree; every
//! conversion between them is here.

use core::f32::consts::{PI, TAU};

/// ARCOS heading units per full turn (THPOS, CONTROL).
pub const ARCOS_ANGLE_UNITS_PER_TURN: f32 = 4096.0;

/// Millimetres to metres.
#[inline]
pub fn mm_to_m(mm: f32) -> f32 {
    mm * 0.001
}

/// Metres to millimetres.
#[inline]
pub fn m_to_mm(m: f32) -> f32 {
    m * 1000.0
}

/// Degrees to radians.
#[inline]
pub fn deg_to_rad(deg: f32) -> f32 {
    deg * (PI / 180.0)
}

/// Radians to degrees.
#[inline]
pub fn rad_to_deg(rad: f32) -> f32 {
    rad * (180.0 / PI)
}

/// ARCOS angle units (2π/4096 rad each) to radians.
#[inline]
pub fn arcos_angle_to_rad(units: f32) -> f32 {
    units * (TAU / ARCOS_ANGLE_UNITS_PER_TURN)
}

/// Radians to ARCOS angle units (not rounded).
#[inline]
pub fn rad_to_arcos_angle(rad: f32) -> f32 {
    rad * (ARCOS_ANGLE_UNITS_PER_TURN / TAU)
}

/// Exploration energy: one step is 1 m of travel or 45 degrees of rotation, pro rata (the
/// thesis's unit of battery).
pub const METRES_PER_STEP: f32 = 1.0;
/// Radians of rotation per energy step (45 degrees).
pub const RADIANS_PER_STEP: f32 = PI / 4.0;

/// Energy steps for a move of `distance_m` metres and `rotation_rad` radians (absolute values
/// are taken).
#[inline]
pub fn steps(distance_m: f32, rotation_rad: f32) -> f32 {
    distance_m.abs() / METRES_PER_STEP + rotation_rad.abs() / RADIANS_PER_STEP
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip() {
        assert!((arcos_angle_to_rad(1024.0) - PI / 2.0).abs() < 1e-6);
        assert!((rad_to_arcos_angle(PI) - 2048.0).abs() < 1e-3);
        assert!((deg_to_rad(180.0) - PI).abs() < 1e-6);
        assert!((m_to_mm(mm_to_m(1234.0)) - 1234.0).abs() < 1e-3);
    }

    #[test]
    fn a_step_is_a_metre_or_an_eighth_turn() {
        assert!((steps(1.0, 0.0) - 1.0).abs() < 1e-6);
        assert!((steps(0.0, PI / 4.0) - 1.0).abs() < 1e-6);
        assert!((steps(-2.0, -PI) - 6.0).abs() < 1e-5);
    }
}
