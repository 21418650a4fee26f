//! UMBmark: the systematic odometry errors of a differential-drive robot from the return
//! errors of square paths driven clockwise and counter-clockwise (J. Borenstein and L. Feng,
//! "Measurement and correction of systematic odometry errors in mobile robots", IEEE
//! Transactions on Robotics and Automation 12(6), 1996).
//!
//! The robot drives an `L` x `L` square closed-loop on its odometry, in both directions,
//! several times; after each run the true end position is compared with the odometry's. Two
//! systematic errors explain the return errors:
//! - unequal wheel diameters, `Ed = D_R / D_L`: the robot curves by an angle `β` on each leg it
//!   believes straight (`β > 0`: to the left);
//! - a wrong wheelbase, `Eb = b_actual / b_nominal`: each 90° turn is truly `90° / Eb`, off by
//!   `a = (π/2)(1/Eb - 1)`.
//!
//! To first order (REP-103 frame of the run's start: x forward, y left), a counter-clockwise
//! run ends off by `ε = 2L(a + β)·(1, -1)` and a clockwise one by `ε = 2L(a - β)·(1, 1)`
//! (the paper's equations with this frame's signs), so with the centres of gravity of the
//! return errors of each direction:
//! `a = (x_cw + x_ccw) / 4L = (y_cw - y_ccw) / 4L` and
//! `β = (x_ccw - x_cw) / 4L = -(y_cw + y_ccw) / 4L`; both estimates are averaged. Then, as in
//! the paper, the leg is an arc of radius `R = (L/2) / sin(β/2)` and
//! `Ed = (R + b/2) / (R - b/2)` (with `b` the true wheelbase `Eb·b_nominal`), and
//! `Eb = (π/2) / (π/2 + a)`. The first-order `(a, β)` mistake a few degrees of leg curve
//! for a wheelbase error; they are refined against the exact geometry of the square (arcs and
//! turns): the errors predicted for the current `(a, β)` go through the same formulas, and the
//! difference from the measured ones corrects `(a, β)`, a few times. `Ed` then follows from
//! the wheel model exactly, `β = 2L (Ed - 1) / ((Ed + 1) Eb b)`, rather than from the paper's
//! chord approximation.

use crate::geometry::{Pose2, normalize_angle};
use crate::math;

/// What a UMBmark run measured: the true end position minus the odometry's end position, in
/// the frame of the run's start (x forward, y left) \[m\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReturnError {
    /// Along the start heading \[m\].
    pub x_m: f32,
    /// To the left of it \[m\].
    pub y_m: f32,
}

/// The systematic errors UMBmark finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryErrors {
    /// Right over left effective wheel diameter.
    pub ed: f32,
    /// Effective over nominal wheelbase.
    pub eb: f32,
    /// Heading error of each 90° turn, true minus nominal \[rad\].
    pub turn_error_rad: f32,
    /// Curvature error of each leg, the heading gained while driving "straight" \[rad\].
    pub leg_curve_rad: f32,
}

/// Why no estimate can be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum UmbmarkError {
    /// No run in one of the directions.
    MissingDirection,
    /// The side or the wheelbase is not a positive length, or a return error is not finite.
    BadInput,
    /// The errors are too large for the model (a leg curving by more than 90°).
    OutOfModel,
}

impl core::fmt::Display for UmbmarkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            UmbmarkError::MissingDirection => {
                "UMBmark needs at least one clockwise and one counter-clockwise run"
            }
            UmbmarkError::BadInput => {
                "the square's side and the wheelbase must be positive and every return error finite"
            }
            UmbmarkError::OutOfModel => {
                "the return errors are too large for UMBmark's model (check the measurements)"
            }
        })
    }
}

/// Estimates the systematic errors from the return errors of clockwise (`cw`) and
/// counter-clockwise (`ccw`) runs of an `side_m` square, on a robot whose nominal wheelbase is
/// `wheelbase_m`.
pub fn estimate(
    side_m: f32,
    wheelbase_m: f32,
    cw: &[ReturnError],
    ccw: &[ReturnError],
) -> Result<OdometryErrors, UmbmarkError> {
    if cw.is_empty() || ccw.is_empty() {
        return Err(UmbmarkError::MissingDirection);
    }
    let finite = |e: &ReturnError| e.x_m.is_finite() && e.y_m.is_finite();
    let lengths_ok =
        side_m.is_finite() && side_m > 0.0 && wheelbase_m.is_finite() && wheelbase_m > 0.0;
    if !(lengths_ok && cw.iter().chain(ccw).all(finite)) {
        return Err(UmbmarkError::BadInput);
    }
    let centre = |runs: &[ReturnError]| {
        let n = runs.len() as f32;
        let (sx, sy) = runs
            .iter()
            .fold((0.0, 0.0), |(sx, sy), e| (sx + e.x_m, sy + e.y_m));
        (sx / n, sy / n)
    };
    let measured = (centre(cw), centre(ccw));
    let (a0, b0) = first_order(side_m, measured);
    // The first-order estimate, refined: the errors predicted for (a, β) by the exact
    // geometry (arcs and turns) are put through the same first-order formulas, and the
    // difference from the measured ones corrects (a, β) (the first-order formulas alone
    // mistake a few degrees of leg curve for a wheelbase error).
    let (mut a, mut beta) = (a0, b0);
    let quarter = core::f32::consts::FRAC_PI_2;
    for _ in 0..REFINE_ITERATIONS {
        if !(a.abs() < quarter && beta.abs() < quarter) {
            return Err(UmbmarkError::OutOfModel);
        }
        let predicted = (
            square_end(side_m, a, beta, false),
            square_end(side_m, a, beta, true),
        );
        let (ap, bp) = first_order(side_m, predicted);
        a += a0 - ap;
        beta += b0 - bp;
    }
    if !(a.abs() < quarter && beta.abs() < quarter) {
        return Err(UmbmarkError::OutOfModel);
    }
    let eb = quarter / (quarter + a);
    // The wheel model: a leg of length L believed straight turns by
    // β = 2L (Ed - 1) / ((Ed + 1) Eb b).
    let k = beta * eb * wheelbase_m / (2.0 * side_m);
    let ed = (1.0 + k) / (1.0 - k);
    if !(ed.is_finite() && ed > 0.0) {
        return Err(UmbmarkError::OutOfModel);
    }
    Ok(OdometryErrors {
        ed,
        eb,
        turn_error_rad: a,
        leg_curve_rad: beta,
    })
}

/// The odometry corrected for the errors UMBmark found: each increment between two odometry
/// poses (a distance `d` along the heading and a turn `dθ`, as the firmware computed them
/// with equal wheels and the nominal wheelbase `b`) becomes the true one of the wheel model,
/// `dθ' = (dθ + 2d (Ed - 1) / ((Ed + 1) b)) / Eb` and `d' = d + (dθ b / 2)(Ed - 1)/(Ed + 1)`,
/// and the corrected pose is integrated from them. With `Ed = Eb = 1` the poses pass
/// unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryCorrection {
    ed: f32,
    eb: f32,
    wheelbase_m: f32,
    last_raw: Option<Pose2>,
    pose: Pose2,
}

impl OdometryCorrection {
    /// A correction for `ed`, `eb` on a nominal wheelbase `wheelbase_m` (the one UMBmark was
    /// computed with).
    pub fn new(ed: f32, eb: f32, wheelbase_m: f32) -> Self {
        Self {
            ed,
            eb,
            wheelbase_m,
            last_raw: None,
            pose: Pose2::default(),
        }
    }

    fn is_identity(&self) -> bool {
        self.ed == 1.0 && self.eb == 1.0
    }

    /// The corrected pose for the odometry pose `raw` (the first one is taken as is).
    pub fn apply(&mut self, raw: Pose2) -> Pose2 {
        let Some(last) = self.last_raw.replace(raw) else {
            self.pose = raw;
            return raw;
        };
        if self.is_identity() {
            self.pose = raw;
            return raw;
        }
        let (dx, dy) = (raw.x - last.x, raw.y - last.y);
        let d = dx * math::cos(last.theta) + dy * math::sin(last.theta);
        let dth = normalize_angle(raw.theta - last.theta);
        let k = (self.ed - 1.0) / (self.ed + 1.0);
        let b = self.wheelbase_m;
        let dth_true = (dth + 2.0 * d * k / b) / self.eb;
        let d_true = d + dth * b / 2.0 * k;
        let mid = self.pose.theta + dth_true / 2.0;
        self.pose = Pose2::new(
            self.pose.x + d_true * math::cos(mid),
            self.pose.y + d_true * math::sin(mid),
            normalize_angle(self.pose.theta + dth_true),
        );
        self.pose
    }

    /// The latest corrected pose.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }
}

/// Refinements of the first-order estimate.
const REFINE_ITERATIONS: usize = 20;

/// `(a, β)` from the centres of gravity `((x_cw, y_cw), (x_ccw, y_ccw))`, to first order.
fn first_order(
    side_m: f32,
    ((x_cw, y_cw), (x_ccw, y_ccw)): ((f32, f32), (f32, f32)),
) -> (f32, f32) {
    let four_l = 4.0 * side_m;
    let a = ((x_cw + x_ccw) + (y_cw - y_ccw)) / (2.0 * four_l);
    let beta = ((x_ccw - x_cw) - (y_cw + y_ccw)) / (2.0 * four_l);
    (a, beta)
}

/// Where a square driven on odometry truly ends, for a turn error `a` and a leg curve `β`.
fn square_end(side_m: f32, a: f32, beta: f32, ccw: bool) -> (f32, f32) {
    let (mut x, mut y, mut th) = (0.0f32, 0.0f32, 0.0f32);
    let turn = core::f32::consts::FRAC_PI_2 + a;
    for _ in 0..4 {
        let chord = if beta.abs() < 1e-6 {
            side_m
        } else {
            2.0 * (side_m / beta) * math::sin(beta / 2.0)
        };
        let dir = th + beta / 2.0;
        x += chord * math::cos(dir);
        y += chord * math::sin(dir);
        th += beta + if ccw { turn } else { -turn };
    }
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose2;

    /// Drives the square exactly on odometry, the true motion following Borenstein & Feng's
    /// wheel model (`Ed`, `Eb` on a wheelbase `b`), in small steps; returns the return error.
    fn drive(side: f32, b: f32, ed: f32, eb: f32, ccw: bool) -> ReturnError {
        let mut p = Pose2::new(0.0, 0.0, 0.0);
        let mut step = |d: f32, dth: f32| {
            let half = dth * b / 2.0;
            let left = (d - half) * 2.0 / (ed + 1.0);
            let right = (d + half) * 2.0 / (1.0 / ed + 1.0);
            let (dt, dr) = ((left + right) / 2.0, (right - left) / (eb * b));
            let mid = p.theta + dr / 2.0;
            p = Pose2::new(
                p.x + dt * math::cos(mid),
                p.y + dt * math::sin(mid),
                p.theta + dr,
            );
        };
        let n = 2000;
        for _ in 0..4 {
            for _ in 0..n {
                step(side / n as f32, 0.0);
            }
            let turn = if ccw { 1.0 } else { -1.0 } * core::f32::consts::FRAC_PI_2;
            for _ in 0..n {
                step(0.0, turn / n as f32);
            }
        }
        ReturnError { x_m: p.x, y_m: p.y }
    }

    #[test]
    fn recovers_known_wheel_errors_from_ideal_squares() {
        for (ed, eb) in [
            (1.0, 1.0),
            (1.01, 1.0),
            (1.0, 0.97),
            (1.02, 0.97),
            (0.99, 1.03),
            (1.003, 1.01),
        ] {
            let cw = [drive(4.0, 0.357, ed, eb, false)];
            let ccw = [drive(4.0, 0.357, ed, eb, true)];
            let e = estimate(4.0, 0.357, &cw, &ccw).unwrap();
            let close = |got: f32, want: f32| {
                if want == 1.0 {
                    (got - 1.0).abs() < 1e-4
                } else {
                    ((got - 1.0) - (want - 1.0)).abs() <= 0.05 * (want - 1.0).abs()
                }
            };
            assert!(close(e.ed, ed), "Ed {ed}, Eb {eb}: estimated {e:?}");
            assert!(close(e.eb, eb), "Ed {ed}, Eb {eb}: estimated {e:?}");
        }
    }

    /// The corrected odometry of a square driven on odometry ends where the robot truly is.
    #[test]
    fn the_correction_puts_the_odometry_where_the_robot_truly_is() {
        let (ed, eb, b) = (1.01, 0.97, 0.357);
        let truth = drive(4.0, b, ed, eb, true);
        let mut c = OdometryCorrection::new(ed, eb, b);
        let mut raw = Pose2::new(0.0, 0.0, 0.0);
        c.apply(raw);
        let n = 2000;
        for _ in 0..4 {
            for _ in 0..n {
                raw = Pose2::new(
                    raw.x + 4.0 / n as f32 * math::cos(raw.theta),
                    raw.y + 4.0 / n as f32 * math::sin(raw.theta),
                    raw.theta,
                );
                c.apply(raw);
            }
            for _ in 0..n {
                raw = Pose2::new(
                    raw.x,
                    raw.y,
                    raw.theta + core::f32::consts::FRAC_PI_2 / n as f32,
                );
                c.apply(raw);
            }
        }
        let p = c.pose();
        let off = libm::hypotf(p.x - truth.x_m, p.y - truth.y_m);
        let raw_off = libm::hypotf(raw.x - truth.x_m, raw.y - truth.y_m);
        assert!(raw_off > 0.5, "{raw_off}");
        assert!(off < 0.02, "corrected {off} m off, raw {raw_off} m");
        // Unity corrections pass the poses unchanged.
        let mut id = OdometryCorrection::new(1.0, 1.0, b);
        for q in [Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.3, -0.1, 0.2)] {
            assert_eq!(id.apply(q), q);
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let e = ReturnError { x_m: 0.1, y_m: 0.0 };
        assert_eq!(
            estimate(4.0, 0.3, &[], &[e]),
            Err(UmbmarkError::MissingDirection)
        );
        assert_eq!(estimate(0.0, 0.3, &[e], &[e]), Err(UmbmarkError::BadInput));
        let nan = ReturnError {
            x_m: f32::NAN,
            y_m: 0.0,
        };
        assert_eq!(
            estimate(4.0, 0.3, &[nan], &[e]),
            Err(UmbmarkError::BadInput)
        );
        let huge = ReturnError {
            x_m: 100.0,
            y_m: -100.0,
        };
        assert_eq!(
            estimate(4.0, 0.3, &[huge], &[huge]),
            Err(UmbmarkError::OutOfModel)
        );
    }
}
