//! Online self-calibration of a differential drive's systematic odometry errors, estimated
//! from the scan matches as two extra states of the tracker's extended Kalman filter.
//!
//! Borenstein & Feng (*Measurement and correction of systematic odometry errors in mobile
//! robots*, IEEE Transactions on Robotics and Automation 12(6), 1996) name the two dominant
//! systematic errors of a differential drive: the ratio `Ed` of the wheels' effective
//! diameters and the ratio `Eb` of the effective wheelbase to the nominal one. For a step whose
//! encoders report a signed forward travel `s` and a turn `Δθ` (computed with the nominal
//! wheelbase `b`), the true turn is exactly linear in both:
//!
//! `Δθ_true = g · Δθ + k · s`, with the turn gain `g = 1 / Eb` and the curvature per metre
//! `k = 2 (Ed − 1) / ((Ed + 1) · Eb · b)` \[rad/m\]
//!
//! (the travel itself changes only by `Δθ · b/2 · (Ed − 1)/(Ed + 1)`, below a tenth of a
//! millimetre a radian at the ranges below; not modelled). `g` and `k` are fixed for a robot
//! and a floor, so they are estimated, as Roy & Thrun (*Online self-calibration for mobile
//! robots*, ICRA 1999) do from the difference between the corrected and the odometry motion,
//! and Martinelli, Tomatis & Siegwart (*Simultaneous localization and odometry self
//! calibration for mobile robot*, Autonomous Robots 22, 2007) do in an augmented Kalman
//! filter: the pose `(x, y, θ)` and `(g, k)` share one covariance. Each odometry increment is
//! corrected with the estimate before the prediction ([`OdometryCalibration::predict`]), the
//! parameters' own uncertainty enters the prediction's covariance through the increment's
//! Jacobian (a turn of `Δθ` adds `Δθ² σ_g²` to the heading's variance, correlated from step to
//! step, as a systematic error is), and a match's correction reaches the parameters through
//! the cross-covariance ([`OdometryCalibration::update`]). Once their variance is small the
//! prediction's noise is only the random part the tracker's odometry model leaves
//! ([`CalibrationConfig::random_scale`]).
//!
//! `no_std`, no allocation: fixed-size matrices.

use crate::geometry::{Pose2, normalize_angle};
use crate::math;
use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

/// Whether and how the tracker estimates the odometry's systematic errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationConfig {
    /// Estimate them (off: the tracker's prediction is the odometry as reported, as before).
    pub enabled: bool,
    /// Prior standard deviation of the turn gain `1 / Eb` around 1.
    pub turn_gain_sigma: f32,
    /// Prior standard deviation of the curvature per metre driven around 0 \[rad/m\].
    pub curvature_sigma_rad_per_m: f32,
    /// While calibrating, the tracker's odometry variances
    /// ([`super::LocalizeConfig::odometry_var_m2_per_m`] and the two heading terms) are
    /// multiplied by this: the share of that model that is random, not systematic.
    pub random_scale: f32,
}

impl Default for CalibrationConfig {
    /// On; priors σ 0.01 for the turn gain and 0.01 rad/m (0.57°/m) for the curvature: an
    /// uncalibrated P3-DX's wheelbase uncertain by about a percent and its wheel diameters
    /// unequal by a few tenths of a percent (Borenstein & Feng 1996; `papillon-sim`'s
    /// realistic model draws within ±1 % and ±0.3 %, i.e. up to 0.0084 rad/m); the odometry
    /// model's variances kept in full (`random_scale` 1).
    fn default() -> Self {
        Self {
            enabled: true,
            turn_gain_sigma: 0.01,
            curvature_sigma_rad_per_m: 0.01,
            random_scale: 1.0,
        }
    }
}

/// The estimate of the turn gain and the curvature, and their covariance with the pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryCalibration {
    /// Turn gain `g` and curvature `k` \[rad/m\].
    params: Vector2<f64>,
    /// Covariance of `(g, k)`.
    cov_pp: Matrix2<f64>,
    /// Cross-covariance of the pose `(x, y, θ)` with `(g, k)`.
    cov_xp: Matrix3x2<f64>,
    /// The prior has been set.
    started: bool,
}

impl Default for OdometryCalibration {
    fn default() -> Self {
        Self::new()
    }
}

impl OdometryCalibration {
    /// Not started: the first [`Self::predict`] or [`Self::start`] sets the prior.
    pub const fn new() -> Self {
        Self {
            params: Vector2::new(1.0, 0.0),
            cov_pp: Matrix2::new(0.0, 0.0, 0.0, 0.0),
            cov_xp: Matrix3x2::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            started: false,
        }
    }

    /// Sets the prior of `config` (turn gain 1, curvature 0) and forgets any estimate.
    pub fn start(&mut self, config: &CalibrationConfig) {
        let sg = config.turn_gain_sigma.max(0.0) as f64;
        let sk = config.curvature_sigma_rad_per_m.max(0.0) as f64;
        *self = Self {
            params: Vector2::new(1.0, 0.0),
            cov_pp: Matrix2::new(sg * sg, 0.0, 0.0, sk * sk),
            cov_xp: Matrix3x2::zeros(),
            started: true,
        };
    }

    /// The turn gain `1 / Eb`: true turn over the odometry's.
    pub fn turn_gain(&self) -> f32 {
        self.params[0] as f32
    }

    /// The curvature \[rad/m\]: heading change per metre the odometry reports as straight.
    pub fn curvature_rad_per_m(&self) -> f32 {
        self.params[1] as f32
    }

    /// Standard deviations of the turn gain and of the curvature \[rad/m\].
    pub fn sigmas(&self) -> (f32, f32) {
        (
            math::sqrt(self.cov_pp[(0, 0)].max(0.0) as f32),
            math::sqrt(self.cov_pp[(1, 1)].max(0.0) as f32),
        )
    }

    /// The wheel errors the estimate implies on a drive of nominal wheelbase `track_m`:
    /// `(Ed, Eb)`, right over left wheel diameter and effective over nominal wheelbase.
    pub fn wheel_errors(&self, track_m: f32) -> (f32, f32) {
        wheel_errors_of(self.turn_gain(), self.curvature_rad_per_m(), track_m)
    }

    /// Predicts the map pose after an odometry increment `inc` (the new odometry pose in the
    /// frame of the previous one) from the map pose `from`, with the increment corrected by
    /// the estimate, and propagates the pose covariance `cov` (the tracker's) together with
    /// the parameters' own: `q` is the random part of the odometry's noise (map frame).
    pub fn predict(
        &mut self,
        config: &CalibrationConfig,
        from: Pose2,
        inc: Pose2,
        cov: &mut Matrix3<f64>,
        q: &Matrix3<f64>,
    ) -> Pose2 {
        if !self.started {
            self.start(config);
        }
        let (g, k) = (self.params[0], self.params[1]);
        let s = inc.x as f64;
        let dth = inc.theta as f64;
        let turn = g * dth + k * s;
        // The corrected heading change turns the step's translation about its midpoint.
        let heading = from.theta as f64 + 0.5 * (turn - dth);
        let (c, sn) = (
            math::cos(heading as f32) as f64,
            math::sin(heading as f32) as f64,
        );
        let (lx, ly) = (inc.x as f64, inc.y as f64);
        let (tx, ty) = (c * lx - sn * ly, sn * lx + c * ly);
        let f = Matrix3::new(1.0, 0.0, -ty, 0.0, 1.0, tx, 0.0, 0.0, 1.0);
        let jac = Matrix3x2::new(
            -ty * 0.5 * dth,
            -ty * 0.5 * s,
            tx * 0.5 * dth,
            tx * 0.5 * s,
            dth,
            s,
        );
        let fp = f * self.cov_xp;
        let p = f * *cov * f.transpose()
            + fp * jac.transpose()
            + jac * fp.transpose()
            + jac * self.cov_pp * jac.transpose()
            + q;
        *cov = 0.5 * (p + p.transpose());
        self.cov_xp = fp + jac * self.cov_pp;
        Pose2::new(
            from.x + tx as f32,
            from.y + ty as f32,
            normalize_angle(from.theta + turn as f32),
        )
    }

    /// Fuses a match of information `h` (map frame, `x, y, θ`) whose correction of the
    /// predicted pose is `delta` into the pose covariance `cov` and the parameters: returns
    /// the pose's step (map frame), or `None` (nothing changed) when the numbers are not
    /// finite. The Kalman form `K = P Eᵀ H (I + P_xx H)⁻¹`, so that a match that constrains
    /// only some directions (`h` singular) is fused as it is.
    pub fn update(
        &mut self,
        cov: &mut Matrix3<f64>,
        h: &Matrix3<f64>,
        delta: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        let s_inv = (Matrix3::identity() + *cov * h).try_inverse()?;
        let gain_x = *cov * h * s_inv;
        let gain_p = self.cov_xp.transpose() * h * s_inv;
        let step_x = gain_x * delta;
        let step_p = gain_p * delta;
        let new_cov = *cov - gain_x * *cov;
        let new_xp = self.cov_xp - gain_x * self.cov_xp;
        let new_pp = self.cov_pp - gain_p * self.cov_xp;
        let finite = step_x.iter().chain(step_p.iter()).all(|v| v.is_finite())
            && new_cov.iter().chain(new_pp.iter()).all(|v| v.is_finite());
        if !finite {
            return None;
        }
        *cov = 0.5 * (new_cov + new_cov.transpose());
        self.cov_xp = new_xp;
        self.cov_pp = 0.5 * (new_pp + new_pp.transpose());
        self.params += step_p;
        Some(step_x)
    }
}

/// `(Ed, Eb)` of a turn gain and a curvature \[rad/m\] on a drive of nominal wheelbase
/// `track_m` (the inverse of [`gain_and_curvature_of`]).
pub fn wheel_errors_of(turn_gain: f32, curvature_rad_per_m: f32, track_m: f32) -> (f32, f32) {
    let eb = 1.0 / turn_gain;
    // (Ed − 1)/(Ed + 1) = k · Eb · b / 2.
    let r = curvature_rad_per_m * eb * track_m / 2.0;
    ((1.0 + r) / (1.0 - r), eb)
}

/// The turn gain and the curvature \[rad/m\] of wheels with diameter ratio `ed` and wheelbase
/// ratio `eb` on a drive of nominal wheelbase `track_m`.
pub fn gain_and_curvature_of(ed: f32, eb: f32, track_m: f32) -> (f32, f32) {
    (1.0 / eb, 2.0 * (ed - 1.0) / ((ed + 1.0) * eb * track_m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{gaussian, seeded};

    const TRACK_M: f32 = 0.357;

    /// The true motion of a step the encoders report as `(s, dth)` on wheels `(ed, eb)`
    /// (Borenstein & Feng's model, as `papillon-sim`'s odometry error model draws it).
    fn true_step(s: f32, dth: f32, ed: f32, eb: f32) -> (f32, f32) {
        let half = dth * TRACK_M / 2.0;
        let left = (s - half) * 2.0 / (ed + 1.0);
        let right = (s + half) * 2.0 / (1.0 / ed + 1.0);
        ((left + right) / 2.0, (right - left) / (eb * TRACK_M))
    }

    /// Drives an exploration-like path (straight runs of 0.5-3 m, turns in place of up to
    /// ±π, forward and backward) in steps of 3 cm or 4°, with wheels `(ed, eb)` and random
    /// heading noise of `noise_rad` per step; every step a match reports the true pose with
    /// noise (1 cm, 0.05°). Returns the calibration after `steps` steps and the tracker's pose
    /// covariance.
    fn drive(ed: f32, eb: f32, noise_rad: f32, steps: usize, seed: u64) -> OdometryCalibration {
        let config = CalibrationConfig {
            enabled: true,
            ..CalibrationConfig::default()
        };
        let mut rng = seeded(seed);
        let mut cal = OdometryCalibration::new();
        let mut cov = Matrix3::from_diagonal_element(1e-6);
        let mut truth = Pose2::new(0.0, 0.0, 0.0);
        let mut est = truth;
        let (sm, sr) = (0.01f64, 0.05f64.to_radians());
        let h = Matrix3::from_diagonal(&Vector3::new(
            1.0 / (sm * sm),
            1.0 / (sm * sm),
            1.0 / (sr * sr),
        ));
        let mut left = 0usize;
        let mut step = (0.0f32, 0.0f32);
        for _ in 0..steps {
            if left == 0 {
                // A new move: straight (either way) or a turn in place.
                if crate::random::chance(&mut rng, 0.5) {
                    let metres = crate::random::range_f32(&mut rng, 0.5, 3.0);
                    let back = crate::random::chance(&mut rng, 0.2);
                    left = (metres / 0.03) as usize;
                    step = (if back { -0.03 } else { 0.03 }, 0.0);
                } else {
                    let angle = crate::random::range_f32(&mut rng, -3.1, 3.1);
                    let per = 4f32.to_radians().copysign(angle);
                    left = (angle / per) as usize + 1;
                    step = (0.0, per);
                }
            }
            left -= 1;
            let (s, dth) = step;
            let (ts, tth) = true_step(s, dth, ed, eb);
            let tth = tth + noise_rad * gaussian(&mut rng);
            truth = truth.compose(Pose2::new(ts, 0.0, tth));
            let var = (noise_rad as f64).powi(2).max(1e-12);
            let q = Matrix3::from_diagonal(&Vector3::new(1e-8, 1e-8, var));
            est = cal.predict(&config, est, Pose2::new(s, 0.0, dth), &mut cov, &q);
            let seen = Pose2::new(
                truth.x + 0.01 * gaussian(&mut rng),
                truth.y + 0.01 * gaussian(&mut rng),
                truth.theta + 0.05f32.to_radians() * gaussian(&mut rng),
            );
            let delta = Vector3::new(
                (seen.x - est.x) as f64,
                (seen.y - est.y) as f64,
                normalize_angle(seen.theta - est.theta) as f64,
            );
            let d = cal.update(&mut cov, &h, &delta).unwrap();
            est = Pose2::new(
                est.x + d[0] as f32,
                est.y + d[1] as f32,
                normalize_angle(est.theta + d[2] as f32),
            );
        }
        cal
    }

    #[test]
    fn the_estimate_converges_to_the_drawn_wheels() {
        for (seed, ed, eb) in [(1, 1.003, 0.99), (2, 0.997, 1.01), (3, 1.0015, 1.004)] {
            let (g, k) = gain_and_curvature_of(ed, eb, TRACK_M);
            // Random heading noise per step as papillon-sim's realistic model: (0.57°)² per
            // metre, (0.81°)² per radian; here 0.1° per 3 cm or 4° step.
            let cal = drive(ed, eb, 0.1f32.to_radians(), 20_000, seed);
            let (sg, sk) = cal.sigmas();
            let (eg, ek) = (cal.turn_gain() - g, cal.curvature_rad_per_m() - k);
            assert!(
                eg.abs() < 1.5e-3 && eg.abs() < 4.0 * sg,
                "gain {eg} off, σ {sg}"
            );
            assert!(
                ek.abs() < 1e-3 && ek.abs() < 4.0 * sk,
                "curvature {ek} off, σ {sk}"
            );
            // Converged: far inside the prior.
            assert!(sg < 0.002 && sk < 0.002, "σ {sg} {sk}");
            let (ed_est, eb_est) = cal.wheel_errors(TRACK_M);
            assert!((ed_est - ed).abs() < 3e-4 && (eb_est - eb).abs() < 2e-3);
        }
    }

    #[test]
    fn exact_odometry_keeps_the_estimate_at_one() {
        for seed in 4..7 {
            let cal = drive(1.0, 1.0, 0.0, 20_000, seed);
            let (sg, sk) = cal.sigmas();
            assert!((cal.turn_gain() - 1.0).abs() < 1e-3, "{}", cal.turn_gain());
            assert!(
                cal.curvature_rad_per_m().abs() < 5e-4,
                "{}",
                cal.curvature_rad_per_m()
            );
            assert!(sg < 0.002 && sk < 0.002, "σ {sg} {sk}");
        }
    }

    #[test]
    fn a_converged_estimate_shrinks_the_prediction_to_the_random_part() {
        // The heading variance a 1 rad turn adds, before and after calibrating.
        let config = CalibrationConfig {
            enabled: true,
            ..CalibrationConfig::default()
        };
        let turn_var = |cal: &mut OdometryCalibration| {
            let mut cov = Matrix3::zeros();
            let mut c = *cal;
            c.cov_xp = Matrix3x2::zeros();
            let _ = c.predict(
                &config,
                Pose2::new(0.0, 0.0, 0.0),
                Pose2::new(0.0, 0.0, 1.0),
                &mut cov,
                &Matrix3::zeros(),
            );
            cov[(2, 2)]
        };
        let mut fresh = OdometryCalibration::new();
        fresh.start(&config);
        let mut done = drive(1.002, 1.008, 0.1f32.to_radians(), 20_000, 8);
        let before = turn_var(&mut fresh);
        let after = turn_var(&mut done);
        assert!((before - 1e-4).abs() < 1e-9, "{before}");
        assert!(after < before / 25.0, "{after} vs {before}");
    }

    #[test]
    fn wheel_errors_and_parameters_are_inverse() {
        for (ed, eb) in [(1.003, 0.99), (0.997, 1.01), (1.0, 1.0)] {
            let (g, k) = gain_and_curvature_of(ed, eb, TRACK_M);
            let (ed2, eb2) = wheel_errors_of(g, k, TRACK_M);
            assert!((ed2 - ed).abs() < 1e-6 && (eb2 - eb).abs() < 1e-6);
            // The model is the simulator's: a straight metre turns by k, a radian by g.
            let (_, straight) = true_step(1.0, 0.0, ed, eb);
            let (_, turn) = true_step(0.0, 1.0, ed, eb);
            assert!((straight - k).abs() < 1e-6 && (turn - g).abs() < 1e-6);
        }
    }
}
