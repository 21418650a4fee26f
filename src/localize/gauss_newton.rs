//! Local Gauss-Newton refinement of a scan's pose on the interpolated map, as in Hector SLAM
//! (Kohlbrecher, von Stryk, Meyer & Klingauf, *A flexible and scalable SLAM system with full
//! 3D motion estimation*, SSRR 2011, §IV.A).
//!
//! With `S_i(ξ)` the map position of return `i` under pose `ξ = (x, y, θ)` and `M` the
//! bilinearly interpolated map ([`super::likelihood::LikelihoodField::sample`]), the pose
//! minimises `Σ w_i (1 - M(S_i(ξ)))²`. One step solves `H Δξ = Σ w_i J_iᵀ (1 - M(S_i(ξ)))`
//! with `J_i = ∇M(S_i) · ∂S_i/∂ξ` and `H = Σ w_i J_iᵀ J_i`, where
//! `∂S_i/∂ξ = [[1, 0, -sinθ·p_x - cosθ·p_y], [0, 1, cosθ·p_x - sinθ·p_y]]`.
//!
//! The weights `w_i` (Hector weighs every return alike) discount far returns, whose range
//! noise is larger. Two guards Hector leaves to its multi-resolution maps: a step is taken only
//! along the directions the scan constrains (see [`refine`]), and a step that does not lower
//! the cost is halved, then refused. `H` at the final pose is returned: it is the information
//! the fit carries (`H⁻¹`, scaled by the residual, approximates the covariance), and
//! [`super::constraint`] reads from it which directions the scan pins down.

use nalgebra::{Matrix3, Vector3};

use crate::geometry::{Point2, Pose2};
use crate::math;

use super::constraint::Constraint;
use super::likelihood::LikelihoodField;

/// The refined pose and what the fit knows about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refined {
    /// The pose \[m, rad\].
    pub pose: Pose2,
    /// Weighted mean map value at the returns, 0..=1.
    pub mean_value: f32,
    /// `Σ w_i J_iᵀ J_i / Σ w_i` at the pose, in `(x [m], y [m], θ·L [m])` with `L` the length scale
    /// of the [`Limits`] given to [`refine`] \[1/m²\].
    pub information: Matrix3<f64>,
    /// Gauss-Newton steps taken.
    pub iterations: u32,
}

/// Largest translation of one step \[m\] and largest rotation \[rad\].
const MAX_STEP_M: f32 = 0.1;
const MAX_STEP_RAD: f32 = 0.05;

/// How the steps are limited to what the scan constrains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Length that turns a rotation into a distance \[m\].
    pub length_scale_m: f32,
    /// A direction is stepped along when its information per unit weight is at least this
    /// \[1/m²\] ...
    pub min_information: f32,
    /// ... and at least this fraction of the strongest direction's.
    pub min_information_ratio: f32,
}

/// Refines `start` for the `points` (robot frame \[m\], weighted by `weights`) on `field`, for
/// at most `iterations` steps.
///
/// Each step is the Gauss-Newton step restricted to the eigen-directions of `H` the scan
/// constrains ([`Limits`], [`Constraint`]): the truncated pseudo-inverse of Zhang, Kaess &
/// Singh (ICRA 2016). Along a direction the scan leaves flat (a wall seen alone, a corridor)
/// the cost still has small slopes from the map's texture, and a full step would slide the
/// pose along them; restricted, the pose keeps the prediction there.
pub fn refine<const T: usize>(
    field: &LikelihoodField<T>,
    points: &[Point2],
    weights: &[f32],
    start: Pose2,
    iterations: u32,
    limits: &Limits,
) -> Refined {
    let mut pose = start;
    let mut eval = evaluate(field, points, weights, pose);
    let mut taken = 0;
    let n = (weights.iter().sum::<f32>() as f64).max(1e-9);
    let l = limits.length_scale_m as f64;
    let scale = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0 / l));
    for _ in 0..iterations {
        // In (x, y, θ·L), per unit weight.
        let h = scale * eval.h * scale / n;
        let g = scale * eval.g / n;
        let c = Constraint::analyse(&h, limits.min_information, limits.min_information_ratio);
        let mut step_scaled = Vector3::zeros();
        for k in 0..3 {
            if c.constrained[k] {
                let v = Vector3::from(c.directions[k]).cast::<f64>();
                step_scaled += v * (v.dot(&g) / c.eigenvalues[k] as f64);
            }
        }
        if step_scaled == Vector3::zeros() {
            break;
        }
        let step = scale * step_scaled;
        let (mut dx, mut dy, mut dth) = (step[0] as f32, step[1] as f32, step[2] as f32);
        let t = math::hypot(dx, dy);
        if t > MAX_STEP_M {
            dx *= MAX_STEP_M / t;
            dy *= MAX_STEP_M / t;
        }
        dth = dth.clamp(-MAX_STEP_RAD, MAX_STEP_RAD);
        let mut accepted = false;
        for _ in 0..3 {
            let trial = Pose2::new(pose.x + dx, pose.y + dy, pose.theta + dth);
            let e = evaluate(field, points, weights, trial);
            if e.cost < eval.cost {
                pose = trial;
                eval = e;
                accepted = true;
                break;
            }
            dx *= 0.5;
            dy *= 0.5;
            dth *= 0.5;
        }
        if !accepted {
            break;
        }
        taken += 1;
        if math::hypot(dx, dy) < 1e-4 && math::abs(dth) < 1e-5 {
            break;
        }
    }
    Refined {
        pose,
        mean_value: (eval.sum_value / n) as f32,
        information: scale * eval.h * scale / n,
        iterations: taken,
    }
}

struct Evaluation {
    cost: f64,
    sum_value: f64,
    h: Matrix3<f64>,
    g: Vector3<f64>,
}

fn evaluate<const T: usize>(
    field: &LikelihoodField<T>,
    points: &[Point2],
    weights: &[f32],
    pose: Pose2,
) -> Evaluation {
    let (s, c) = (math::sin(pose.theta), math::cos(pose.theta));
    let mut e = Evaluation {
        cost: 0.0,
        sum_value: 0.0,
        h: Matrix3::zeros(),
        g: Vector3::zeros(),
    };
    let (mut h00, mut h01, mut h02, mut h11, mut h12, mut h22) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut g0, mut g1, mut g2) = (0.0, 0.0, 0.0);
    for (p, &w) in points.iter().zip(weights) {
        let q = Point2::new(pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y);
        let (m, gx, gy) = field.sample(q);
        let r = 1.0 - m;
        let w = w as f64;
        e.cost += w * (r * r) as f64;
        e.sum_value += w * m as f64;
        let j2 = gx * (-s * p.x - c * p.y) + gy * (c * p.x - s * p.y);
        let (j0, j1, j2) = (gx as f64, gy as f64, j2 as f64);
        h00 += w * j0 * j0;
        h01 += w * j0 * j1;
        h02 += w * j0 * j2;
        h11 += w * j1 * j1;
        h12 += w * j1 * j2;
        h22 += w * j2 * j2;
        let r = w * r as f64;
        g0 += j0 * r;
        g1 += j1 * r;
        g2 += j2 * r;
    }
    e.h = Matrix3::new(h00, h01, h02, h01, h11, h12, h02, h12, h22);
    e.g = Vector3::new(g0, g1, g2);
    e
}
