//! How uncertain the pose graph is about where the robot stands relative to an old keyframe:
//! the covariance of the steps between them compounded along the path (Smith & Cheeseman,
//! *On the representation and estimation of spatial uncertainty*, IJRR 5(4), 1986, §4, the
//! compounding operation `⊕` and its Jacobians).
//!
//! Each step `z_k` (the motion from keyframe `k` to `k + 1`, in the frame of `k`) carries
//! independent variances along `x`, `y` and the heading. Compounding `T_{k+1} = T_k ⊕ z_k`
//! in the old keyframe's frame gives
//!
//! ```text
//! Σ_{k+1} = J₁ Σ_k J₁ᵀ + J₂ Q_k J₂ᵀ
//! J₁ = [1 0 −(y_{k+1} − y_k); 0 1 (x_{k+1} − x_k); 0 0 1],   J₂ = R(θ_k) ⊕ 1
//! ```
//!
//! so a heading error early on the path grows into a position error with the lever arm of
//! everything driven after it, which a sum of the steps' position variances ignores: a
//! closure's consistency gate built on that sum refuses the matches a turned heading explains
//! (23 in 70 house missions, 3 with this covariance; docs/experiments.md, "Loop closures after
//! a drift"). Allocation-free.

use nalgebra::{Matrix3, Vector3};

use crate::geometry::{Pose2, normalize_angle};
use crate::math;

/// Covariance of the end of a path, in the frame of its start, accumulated step by step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathUncertainty {
    /// The end of the path so far, in the frame of its start.
    end: Pose2,
    /// Its covariance \[m², m², rad²; rows and columns x, y, θ\].
    covariance: Matrix3<f32>,
}

impl Default for PathUncertainty {
    fn default() -> Self {
        Self::new()
    }
}

impl PathUncertainty {
    /// A path that has not moved: certain.
    pub fn new() -> Self {
        Self {
            end: Pose2::new(0.0, 0.0, 0.0),
            covariance: Matrix3::zeros(),
        }
    }

    /// Appends a step `z` (in the frame of the path's current end) whose errors along its
    /// own `x`, `y` and heading have the variances `variances` \[m², m², rad²\].
    pub fn push(&mut self, z: Pose2, variances: [f32; 3]) {
        let next = self.end.compose(z);
        let (dx, dy) = (next.x - self.end.x, next.y - self.end.y);
        let j1 = Matrix3::new(1.0, 0.0, -dy, 0.0, 1.0, dx, 0.0, 0.0, 1.0);
        let (s, c) = (math::sin(self.end.theta), math::cos(self.end.theta));
        let j2 = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let q = Matrix3::from_diagonal(&Vector3::new(variances[0], variances[1], variances[2]));
        self.covariance = j1 * self.covariance * j1.transpose() + j2 * q * j2.transpose();
        self.end = next;
    }

    /// The end of the path in the frame of its start.
    pub fn end(&self) -> Pose2 {
        self.end
    }

    /// The covariance of the end \[m², m², rad²\].
    pub fn covariance(&self) -> &Matrix3<f32> {
        &self.covariance
    }

    /// Squared Mahalanobis distance between two poses of the end, `a` and `b` (both in the
    /// frame of the path's start), under the path's covariance plus `extra` (the variances
    /// of a measurement of it along the start frame's axes). `f32::INFINITY` when the sum
    /// cannot be inverted.
    pub fn mahalanobis2(&self, a: Pose2, b: Pose2, extra: [f32; 3]) -> f32 {
        let s =
            self.covariance + Matrix3::from_diagonal(&Vector3::new(extra[0], extra[1], extra[2]));
        let d = Vector3::new(a.x - b.x, a.y - b.y, normalize_angle(a.theta - b.theta));
        match s.try_inverse() {
            Some(inv) => (d.transpose() * inv * d)[(0, 0)],
            None => f32::INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32, tol: f32) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn a_straight_drive_sums_its_steps_and_its_heading_swings_the_far_end() {
        // Ten 1 m steps east, each with (1 cm)² along both axes and (0.01 rad)² of heading.
        let mut path = PathUncertainty::new();
        for _ in 0..10 {
            path.push(Pose2::new(1.0, 0.0, 0.0), [1e-4, 1e-4, 1e-4]);
        }
        let p = path.covariance();
        assert!(close(path.end().x, 10.0, 1e-4));
        // Along the path the position variances add up: 10 x 1e-4.
        assert!(close(p[(0, 0)], 1e-3, 1e-6), "{p}");
        // Across it the heading errors of every step swing everything after them:
        // 10 x 1e-4 + 1e-4 x (1² + 2² + ... + 9²) = 1e-3 + 2.85e-2.
        assert!(close(p[(1, 1)], 1e-3 + 2.85e-2, 1e-5), "{p}");
        assert!(close(p[(2, 2)], 1e-3, 1e-7), "{p}");
        // Across the path: 17 cm, where a sum of the steps' position variances says 3.2 cm.
        assert!(close(p[(1, 1)].sqrt(), 0.172, 1e-3), "{p}");
    }

    #[test]
    fn a_turned_step_puts_its_errors_along_the_turned_axes() {
        // A quarter turn in place, then a step along the robot's x (north in the start frame)
        // whose only error is along it: the error lies along the start frame's y.
        let mut path = PathUncertainty::new();
        path.push(Pose2::new(0.0, 0.0, core::f32::consts::FRAC_PI_2), [0.0; 3]);
        path.push(Pose2::new(1.0, 0.0, 0.0), [4e-4, 0.0, 0.0]);
        let p = path.covariance();
        assert!(close(path.end().y, 1.0, 1e-5));
        assert!(
            close(p[(0, 0)], 0.0, 1e-9) && close(p[(1, 1)], 4e-4, 1e-8),
            "{p}"
        );
    }

    #[test]
    fn the_distance_between_two_ends_is_measured_in_the_path_s_sigmas() {
        let mut path = PathUncertainty::new();
        path.push(Pose2::new(1.0, 0.0, 0.0), [1e-2, 1e-2, 1e-2]);
        let end = path.end();
        // 10 cm along x against σ² = 1e-2 along x: one σ, squared.
        let moved = Pose2::new(end.x + 0.1, end.y, end.theta);
        assert!(close(path.mahalanobis2(moved, end, [0.0; 3]), 1.0, 1e-3));
        // A measurement's own variance widens the gate.
        assert!(close(
            path.mahalanobis2(moved, end, [1e-2, 1e-2, 1e-2]),
            0.5,
            1e-3
        ));
        // Nothing known and nothing measured: not invertible, infinitely far.
        let certain = PathUncertainty::new();
        assert_eq!(certain.mahalanobis2(moved, end, [0.0; 3]), f32::INFINITY);
    }
}
