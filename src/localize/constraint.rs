//! Which directions of the pose a scan pins down, and the correction kept along them.
//!
//! The Gauss-Newton information `H = Σ JᵀJ` ([`super::gauss_newton`]) is the inverse of the
//! fit's covariance up to the residual's scale: along an eigenvector with a small eigenvalue
//! the cost is flat, so the fitted pose there is noise (a corridor seen without its ends
//! constrains nothing along its axis; Censi, *An accurate closed-form estimate of ICP's
//! covariance*, ICRA 2007, shows the same degeneracy for ICP). The correction is therefore
//! split along the eigenvectors of `H` (rotation scaled to a length), and only its components
//! along well-constrained directions are applied; along the others the odometry prediction is
//! kept. This is the "solution remapping" of Zhang, Kaess & Singh (*On degeneracy of
//! optimization-based state estimation problems*, ICRA 2016), applied to a single match.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// The eigen-analysis of a fit's information.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// Eigenvalues of the per-return information, ascending \[1/m²\].
    pub eigenvalues: [f32; 3],
    /// Unit eigenvectors in `(x, y, θ·L)`, same order.
    pub directions: [[f32; 3]; 3],
    /// Whether each direction is constrained, same order.
    pub constrained: [bool; 3],
}

impl Constraint {
    /// Analyses `information` (per return, symmetric): a direction is constrained when its
    /// eigenvalue is at least `min_eigenvalue` and at least `min_ratio` times the largest.
    pub fn analyse(information: &Matrix3<f64>, min_eigenvalue: f32, min_ratio: f32) -> Self {
        let eig = SymmetricEigen::new(*information);
        let mut order = [0usize, 1, 2];
        order.sort_unstable_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let largest = eig.eigenvalues[order[2]].max(0.0) as f32;
        let mut out = Constraint {
            eigenvalues: [0.0; 3],
            directions: [[0.0; 3]; 3],
            constrained: [false; 3],
        };
        for (k, &i) in order.iter().enumerate() {
            let value = eig.eigenvalues[i] as f32;
            let v = eig.eigenvectors.column(i);
            out.eigenvalues[k] = value;
            out.directions[k] = [v[0] as f32, v[1] as f32, v[2] as f32];
            out.constrained[k] =
                value.is_finite() && value >= min_eigenvalue && value >= min_ratio * largest;
        }
        out
    }

    /// Directions constrained (0..=3).
    pub fn constrained_count(&self) -> u8 {
        self.constrained.iter().filter(|&&c| c).count() as u8
    }

    /// The part of `delta` (in `(x, y, θ·L)`) along the constrained directions.
    pub fn project(&self, delta: [f32; 3]) -> [f32; 3] {
        let d = Vector3::new(delta[0], delta[1], delta[2]);
        let mut out = Vector3::zeros();
        for k in 0..3 {
            if self.constrained[k] {
                let v = Vector3::from(self.directions[k]);
                out += v * v.dot(&d);
            }
        }
        [out[0], out[1], out[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_axis_is_unconstrained_and_projected_out() {
        // Strong across (y) and in rotation, nothing along x: a corridor along x.
        let h = Matrix3::new(1e-4, 0.0, 0.0, 0.0, 40.0, 0.0, 0.0, 0.0, 20.0);
        let c = Constraint::analyse(&h, 1.0, 0.02);
        assert_eq!(c.constrained, [false, true, true]);
        assert_eq!(c.constrained_count(), 2);
        let p = c.project([0.3, -0.05, 0.01]);
        assert!(p[0].abs() < 1e-6);
        assert!((p[1] + 0.05).abs() < 1e-6 && (p[2] - 0.01).abs() < 1e-6);
    }
}
