//! A realistic odometry error model for the simulated P3-DX: systematic wheel errors drawn per
//! robot, random errors growing with distance and rotation, extra slip in fast turns, and the
//! slide at the end of each move.
//!
//! Systematic errors follow Borenstein & Feng (*Measurement and correction of systematic
//! odometry errors in mobile robots*, IEEE Transactions on Robotics and Automation 12(6),
//! 1996, the UMBmark paper), who identify two dominant systematic errors of a differential
//! drive:
//! - `Ed = D_R / D_L`, the ratio of the right and left wheels' effective diameters (tyre wear,
//!   load, manufacturing): a robot told to drive straight drives a gentle arc;
//! - `Eb = b_actual / b_nominal`, the effective wheelbase over the nominal one (the tyres'
//!   contact patches are wide, so the wheelbase is uncertain): every turn is over- or
//!   under-reported by the same factor.
//!
//! With the average diameter kept nominal, the true wheel travels are
//! `s_L = 2/(Ed + 1) · s_L,measured` and `s_R = 2/(1/Ed + 1) · s_R,measured`
//! (Borenstein & Feng's correction factors, read the other way), and the true heading change
//! is `(s_R - s_L) / (Eb · b)`. Each robot draws `Ed - 1` and `Eb - 1` uniformly from its own
//! seeded stream, within ±0.3 % and ±1 % ([`WheelErrors::realistic`]): the order of the
//! uncalibrated errors UMBmark was designed to expose (a fraction of a percent in diameter
//! ratio, around a percent in wheelbase); the exact ranges are this simulator's assumption.
//! At ±0.3 % a robot driving straight turns up to 0.5° per metre; at ±1 % a full turn is off
//! by up to 3.6°.
//!
//! Random (non-systematic) errors are [`crate::physics::SlipConfig`]'s Gaussian random walks in distance and
//! heading; turns faster than [`WheelErrors::fast_turn_deg_s`] add heading variance in
//! proportion to the excess rate (the wheels skid sideways more when the robot spins fast),
//! and the end-of-move slide stays as the thesis measured it.

use papillon::random::{ProjectRng, range_f32};

/// Systematic-error ranges and fast-turn slip of a robot model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelErrors {
    /// Half-width of the uniform range of `Ed - 1` (wheel-diameter ratio).
    pub diameter_ratio: f32,
    /// Half-width of the uniform range of `Eb - 1` (effective wheelbase ratio).
    pub wheelbase_ratio: f32,
    /// Turn rate above which turning adds slip \[deg/s\].
    pub fast_turn_deg_s: f32,
    /// Extra heading variance per radian turned, per deg/s above
    /// [`Self::fast_turn_deg_s`] \[rad²/rad per deg/s\].
    pub fast_turn_var_rad2_per_rad: f32,
}

impl WheelErrors {
    /// Perfect wheels (no draw is made, so other random streams do not shift).
    pub const fn none() -> Self {
        Self {
            diameter_ratio: 0.0,
            wheelbase_ratio: 0.0,
            fast_turn_deg_s: 0.0,
            fast_turn_var_rad2_per_rad: 0.0,
        }
    }

    /// `Ed - 1` within ±0.3 %, `Eb - 1` within ±1 %; above 40 deg/s, 2·10⁻⁵ rad²/rad more
    /// heading variance per deg/s (at the exploration limit of 60 deg/s, 3 times the default
    /// rotation variance).
    pub const fn realistic() -> Self {
        Self {
            diameter_ratio: 0.003,
            wheelbase_ratio: 0.01,
            fast_turn_deg_s: 40.0,
            fast_turn_var_rad2_per_rad: 2e-5,
        }
    }

    /// One robot's wheels, drawn from its stream.
    pub fn draw(&self, rng: &mut ProjectRng) -> DrawnWheels {
        let mut ratio = |half: f32| {
            if half > 0.0 {
                1.0 + range_f32(rng, -half, half)
            } else {
                1.0
            }
        };
        let ed = ratio(self.diameter_ratio);
        let eb = ratio(self.wheelbase_ratio);
        DrawnWheels {
            ed,
            eb,
            fast_turn_deg_s: self.fast_turn_deg_s,
            fast_turn_var_rad2_per_rad: self.fast_turn_var_rad2_per_rad,
        }
    }
}

/// One robot's drawn systematic errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawnWheels {
    /// Right over left effective wheel diameter.
    pub ed: f32,
    /// Effective over nominal wheelbase.
    pub eb: f32,
    fast_turn_deg_s: f32,
    fast_turn_var_rad2_per_rad: f32,
}

impl DrawnWheels {
    /// Wheels with exactly these systematic errors (`ed`: right over left diameter; `eb`:
    /// effective over nominal wheelbase) and no fast-turn slip.
    pub const fn exact(ed: f32, eb: f32) -> Self {
        Self {
            ed,
            eb,
            fast_turn_deg_s: 0.0,
            fast_turn_var_rad2_per_rad: 0.0,
        }
    }

    /// Perfect wheels.
    pub const PERFECT: Self = Self {
        ed: 1.0,
        eb: 1.0,
        fast_turn_deg_s: 0.0,
        fast_turn_var_rad2_per_rad: 0.0,
    };

    /// The true translation \[m\] and rotation \[rad\] of a step whose encoders measured `d`
    /// and `dth` on a robot of nominal wheelbase `track_m`, before random slip.
    pub fn true_motion(&self, d: f32, dth: f32, track_m: f32) -> (f32, f32) {
        if self.ed == 1.0 && self.eb == 1.0 {
            return (d, dth);
        }
        let half = dth * track_m / 2.0;
        let left = (d - half) * 2.0 / (self.ed + 1.0);
        let right = (d + half) * 2.0 / (1.0 / self.ed + 1.0);
        ((left + right) / 2.0, (right - left) / (self.eb * track_m))
    }

    /// Extra heading variance of a step that turned `dth` \[rad\] at `turn_deg_s`.
    pub fn fast_turn_var(&self, dth: f32, turn_deg_s: f32) -> f32 {
        let excess = turn_deg_s.abs() - self.fast_turn_deg_s;
        if self.fast_turn_var_rad2_per_rad > 0.0 && excess > 0.0 {
            self.fast_turn_var_rad2_per_rad * excess * dth.abs()
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::random::seeded;

    #[test]
    fn unequal_wheels_curve_a_straight_drive_and_a_wide_base_under_turns() {
        let track = 0.357;
        let w = DrawnWheels {
            ed: 1.003,
            ..DrawnWheels::PERFECT
        };
        // 1 m "straight": the right wheel is larger, so the robot turns left.
        let (d, dth) = w.true_motion(1.0, 0.0, track);
        assert!((d - 1.0).abs() < 1e-6);
        assert!(dth > 0.0 && (dth - 0.003 / track).abs() < 1e-4, "{dth}");
        let w = DrawnWheels {
            eb: 1.01,
            ..DrawnWheels::PERFECT
        };
        let (d, dth) = w.true_motion(0.0, 1.0, track);
        assert!(d.abs() < 1e-6);
        assert!((dth - 1.0 / 1.01).abs() < 1e-6);
        assert_eq!(
            DrawnWheels::PERFECT.true_motion(0.3, 0.2, track),
            (0.3, 0.2)
        );
    }

    #[test]
    fn each_robot_draws_its_own_errors_within_the_ranges() {
        let model = WheelErrors::realistic();
        let mut seen = Vec::new();
        for seed in 0..50 {
            let w = model.draw(&mut seeded(seed));
            assert!((w.ed - 1.0).abs() <= 0.003 && (w.eb - 1.0).abs() <= 0.01);
            seen.push((w.ed, w.eb));
        }
        seen.sort_by(|a, b| a.0.total_cmp(&b.0));
        seen.dedup();
        assert_eq!(seen.len(), 50);
        // Perfect wheels consume nothing from the stream.
        let mut a = seeded(3);
        let _ = WheelErrors::none().draw(&mut a);
        assert_eq!(
            papillon::random::unit_f32(&mut a),
            papillon::random::unit_f32(&mut seeded(3))
        );
    }

    #[test]
    fn only_fast_turns_add_slip() {
        let w = WheelErrors::realistic().draw(&mut seeded(1));
        assert_eq!(w.fast_turn_var(0.1, 30.0), 0.0);
        assert!((w.fast_turn_var(0.1, -60.0) - 2e-5 * 20.0 * 0.1).abs() < 1e-9);
    }
}
