//! A PID controller for the heading and distance loops of the path follower.
//!
//! Textbook parallel form `u = Kp·e + Ki·∫e dt − Kd·dy/dt` with the practical refinements of
//! Åström & Murray, *Feedback Systems*, 2nd ed., 2021, §11.3 ("Implementation"):
//! - derivative on the measurement `y`, not on the error, so a jump of the setpoint (a new
//!   waypoint) gives no derivative kick;
//! - anti-windup by conditional integration (the integral does not grow while the output is
//!   saturated in the direction the error pushes) and by clamping the integral term itself;
//! - the output clamped to `[output_min, output_max]`;
//! - the time step passed in by the caller.
//!
//! Angles: [`Pid::update_angle`] wraps the error and the measurement change into (−π, π], so
//! a heading loop behaves across the ±π seam.
//!
//! Bad numbers never escape: a non-finite input or time step leaves the state unchanged and
//! yields the output nearest to zero within the limits.

use crate::geometry::normalize_angle;

/// Gains and limits of one PID loop (units are those of the loop: e.g. rad in, rad/s out).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidConfig {
    /// Proportional gain [output per unit error].
    pub kp: f32,
    /// Integral gain [output per unit error·s].
    pub ki: f32,
    /// Derivative gain [output per unit measurement/s].
    pub kd: f32,
    /// Lowest output.
    pub output_min: f32,
    /// Highest output.
    pub output_max: f32,
    /// Bound on the magnitude of the integral term `Ki·∫e dt` [output units].
    pub integral_limit: f32,
}

/// Errors configuring a PID loop.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum PidError {
    /// A gain or limit is NaN or infinite.
    NotFinite,
    /// `output_min > output_max`.
    EmptyOutputRange {
        /// The lower limit given.
        output_min: f32,
        /// The upper limit given.
        output_max: f32,
    },
    /// A gain or the integral limit is negative.
    Negative,
}

impl core::fmt::Display for PidError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PidError::NotFinite => write!(f, "PID gains and limits must be finite"),
            PidError::EmptyOutputRange {
                output_min,
                output_max,
            } => write!(
                f,
                "PID output range is empty: min {output_min} > max {output_max}"
            ),
            PidError::Negative => write!(f, "PID gains and integral limit must be >= 0"),
        }
    }
}

impl core::error::Error for PidError {}

/// A PID controller with its integral and last measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pid {
    config: PidConfig,
    integral: f32,
    last_measurement: Option<f32>,
}

impl Pid {
    /// A controller with a checked configuration.
    pub fn new(config: PidConfig) -> Result<Self, PidError> {
        let c = &config;
        let all = [
            c.kp,
            c.ki,
            c.kd,
            c.output_min,
            c.output_max,
            c.integral_limit,
        ];
        if all.iter().any(|v| !v.is_finite()) {
            return Err(PidError::NotFinite);
        }
        if c.output_min > c.output_max {
            return Err(PidError::EmptyOutputRange {
                output_min: c.output_min,
                output_max: c.output_max,
            });
        }
        if c.kp < 0.0 || c.ki < 0.0 || c.kd < 0.0 || c.integral_limit < 0.0 {
            return Err(PidError::Negative);
        }
        Ok(Self {
            config,
            integral: 0.0,
            last_measurement: None,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PidConfig {
        &self.config
    }

    /// The current integral term [output units].
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Forgets the integral and the last measurement.
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.last_measurement = None;
    }

    /// One step toward `setpoint` given `measurement`, `dt_s` seconds after the previous
    /// step. The first step after a reset (or any step with `dt_s <= 0`) has no derivative or
    /// integral contribution.
    pub fn update(&mut self, setpoint: f32, measurement: f32, dt_s: f32) -> f32 {
        let change = self.last_measurement.map(|m| measurement - m);
        self.step(setpoint - measurement, measurement, change, dt_s)
    }

    /// As [`Pid::update`] for angles \[rad\]: the error and the measurement change are wrapped
    /// into (−π, π].
    pub fn update_angle(&mut self, setpoint_rad: f32, measurement_rad: f32, dt_s: f32) -> f32 {
        let change = self
            .last_measurement
            .map(|m| normalize_angle(measurement_rad - m));
        let error = normalize_angle(setpoint_rad - measurement_rad);
        self.step(error, measurement_rad, change, dt_s)
    }

    fn neutral(&self) -> f32 {
        0.0f32.clamp(self.config.output_min, self.config.output_max)
    }

    fn step(&mut self, error: f32, measurement: f32, change: Option<f32>, dt_s: f32) -> f32 {
        if !(error.is_finite() && measurement.is_finite()) || dt_s.is_nan() {
            return self.neutral();
        }
        let c = self.config;
        let timed = dt_s > 0.0 && dt_s.is_finite();
        let derivative = match change {
            Some(dy) if timed && dy.is_finite() => -c.kd * dy / dt_s,
            _ => 0.0,
        };
        let p = c.kp * error;
        let unclamped = p + self.integral + derivative;
        if timed {
            // Conditional integration: hold the integral while the output is saturated and
            // the error would push it further out.
            let pushing_out = (unclamped >= c.output_max && error > 0.0)
                || (unclamped <= c.output_min && error < 0.0);
            if !pushing_out {
                let grown = self.integral + c.ki * error * dt_s;
                if grown.is_finite() {
                    self.integral = grown.clamp(-c.integral_limit, c.integral_limit);
                }
            }
        }
        self.last_measurement = Some(measurement);
        let out = p + self.integral + derivative;
        if out.is_finite() {
            out.clamp(c.output_min, c.output_max)
        } else if out.is_nan() {
            self.neutral()
        } else if out > 0.0 {
            c.output_max
        } else {
            c.output_min
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{chance, range_f32, seeded};

    fn config() -> PidConfig {
        PidConfig {
            kp: 2.0,
            ki: 0.5,
            kd: 0.2,
            output_min: -1.0,
            output_max: 1.0,
            integral_limit: 0.3,
        }
    }

    #[test]
    fn proportional_only_on_the_first_step() {
        let mut pid = Pid::new(config()).unwrap();
        assert!((pid.update(0.3, 0.0, 0.1) - (0.6 + 0.5 * 0.3 * 0.1)).abs() < 1e-6);
        pid.reset();
        assert_eq!(pid.integral(), 0.0);
        assert!((pid.update(0.1, 0.0, 0.0) - 0.2).abs() < 1e-6);
    }

    #[test]
    fn setpoint_jumps_give_no_derivative_kick() {
        let cfg = PidConfig {
            ki: 0.0,
            kp: 1.0,
            kd: 5.0,
            output_min: -100.0,
            output_max: 100.0,
            ..config()
        };
        let mut pid = Pid::new(cfg).unwrap();
        pid.update(0.0, 0.0, 0.1);
        // Setpoint jumps from 0 to 10, measurement unchanged: pure proportional response.
        assert!((pid.update(10.0, 0.0, 0.1) - 10.0).abs() < 1e-5);
        // Measurement moves by 0.1 in 0.1 s toward the setpoint: derivative brakes by Kd·1.
        let u = pid.update(10.0, 0.1, 0.1);
        assert!((u - (9.9 - 5.0)).abs() < 1e-4, "{u}");
    }

    #[test]
    fn integral_stops_growing_while_saturated() {
        let mut pid = Pid::new(PidConfig {
            integral_limit: 10.0,
            ..config()
        })
        .unwrap();
        // A huge persistent error saturates the output; the integral must not wind up.
        for _ in 0..1000 {
            assert_eq!(pid.update(100.0, 0.0, 0.1), 1.0);
        }
        assert!(pid.integral() < 0.1, "wound up to {}", pid.integral());
        // When the error reverses the output leaves saturation at once.
        let u = pid.update(-0.2, 0.0, 0.1);
        assert!(u < 0.0, "{u}");
    }

    #[test]
    fn integral_is_bounded_by_its_limit() {
        let mut pid = Pid::new(PidConfig {
            kp: 0.0,
            kd: 0.0,
            ..config()
        })
        .unwrap();
        for _ in 0..1000 {
            pid.update(0.5, 0.0, 0.1);
        }
        assert!((pid.integral() - 0.3).abs() < 1e-6);
    }

    #[test]
    fn angle_loop_takes_the_short_way_across_pi() {
        let mut pid = Pid::new(config()).unwrap();
        // Setpoint just past +pi, measurement just below: small positive error.
        let u = pid.update_angle(-3.1, 3.1, 0.1);
        assert!(u > 0.0 && u < 0.3, "{u}");
        // The measurement crossing the seam is a small change, not 2π.
        let u2 = pid.update_angle(-3.1, -3.13, 0.1);
        assert!(u2.abs() < 1.0, "{u2}");
    }

    #[test]
    fn bad_configs_are_rejected() {
        let bad = PidConfig {
            output_min: 1.0,
            output_max: -1.0,
            ..config()
        };
        assert!(matches!(
            Pid::new(bad),
            Err(PidError::EmptyOutputRange { .. })
        ));
        let bad = PidConfig {
            kp: f32::NAN,
            ..config()
        };
        assert_eq!(Pid::new(bad), Err(PidError::NotFinite));
        let bad = PidConfig {
            ki: -1.0,
            ..config()
        };
        assert_eq!(Pid::new(bad), Err(PidError::Negative));
    }

    /// Property: whatever the gains, limits, inputs and time steps (NaN and infinities
    /// included), every output is within the limits.
    #[test]
    fn output_always_within_limits_for_random_inputs() {
        let mut rng = seeded(0x50_49_44);
        let specials = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1e30,
            -1e30,
        ];
        for _ in 0..2_000 {
            let lo = range_f32(&mut rng, -500.0, 10.0);
            let hi = lo + range_f32(&mut rng, 0.0, 500.0);
            let cfg = PidConfig {
                kp: range_f32(&mut rng, 0.0, 100.0),
                ki: range_f32(&mut rng, 0.0, 50.0),
                kd: range_f32(&mut rng, 0.0, 20.0),
                output_min: lo,
                output_max: hi,
                integral_limit: range_f32(&mut rng, 0.0, 1000.0),
            };
            let mut pid = Pid::new(cfg).unwrap();
            let draw = |rng: &mut crate::random::ProjectRng, scale: f32| {
                if chance(rng, 0.05) {
                    specials[crate::random::below(rng, specials.len())]
                } else {
                    range_f32(rng, -scale, scale)
                }
            };
            for _ in 0..50 {
                let sp = draw(&mut rng, 1e4);
                let y = draw(&mut rng, 1e4);
                let dt = draw(&mut rng, 1.0);
                let u = if chance(&mut rng, 0.5) {
                    pid.update(sp, y, dt)
                } else {
                    pid.update_angle(sp, y, dt)
                };
                assert!(u >= lo && u <= hi, "{u} outside [{lo}, {hi}] for {cfg:?}");
                assert!(pid.integral().abs() <= cfg.integral_limit);
            }
        }
    }
}
