//! Which directions of the pose a scan pins down, and the correction kept along them.
//!
//! The Gauss-Newton information `H = Σ JᵀJ` ([`super::ndt`]) is the inverse of the
//! fit's covariance up to the residual's scale: along an eigenvector with a small eigenvalue
//! the cost is flat, so the fitted pose there is noise (a corridor seen without its ends
//! constrains nothing along its axis; Censi, *An accurate closed-form estimate of ICP's
//! covariance*, ICRA 2007, shows the same degeneracy for ICP). The correction is therefore
//! split along the eigenvectors of `H` (rotation scaled to a length), and only its components
//! along well-constrained directions are applied; along the others the odometry prediction is
//! kept. This is the "solution remapping" of Zhang, Kaess & Singh (*On degeneracy of
//! optimization-based state estimation problems*, ICRA 2016), applied to a single match.

use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector3};

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
    /// Analyses `information` (symmetric): a direction is constrained when its eigenvalue is
    /// at least `min_eigenvalue` and at least `min_ratio` times the largest.
    ///
    /// The position block is judged first, on its own, on `position_test` (the information
    /// net of what the map's uncertain normals could fake, [`super::ndt`]): a position direction whose
    /// information (the block's smaller eigenvalue) fails the test is left out before the
    /// rest is analysed, so no constrained direction has a part along it. Analysed together,
    /// a position axis the scan does not pin (a corridor's) mixes with the heading through
    /// their coupling, and the heading's eigenvector then carries part of the corridor axis:
    /// with the thesis's noisy laser the corridor test slid 24 m along it
    /// (docs/experiments.md, sixth measurement).
    pub fn analyse(
        information: &Matrix3<f64>,
        position_test: &Matrix3<f64>,
        min_eigenvalue: f32,
        min_ratio: f32,
    ) -> Self {
        let mut out = Constraint {
            eigenvalues: [0.0; 3],
            directions: [[0.0; 3]; 3],
            constrained: [false; 3],
        };
        let full = SymmetricEigen::new(*information);
        let largest = full
            .eigenvalues
            .iter()
            .fold(0.0f64, |m, &v| if v > m { v } else { m });
        let passes = |value: f64| {
            value.is_finite()
                && value >= min_eigenvalue as f64
                && value >= min_ratio as f64 * largest
        };
        // The position block's weak direction `d` (a unit vector in x, y).
        let block = Matrix2::new(
            position_test[(0, 0)],
            position_test[(0, 1)],
            position_test[(1, 0)],
            position_test[(1, 1)],
        );
        let pos = SymmetricEigen::new(block);
        let (weak, strong) = if pos.eigenvalues[0] <= pos.eigenvalues[1] {
            (0, 1)
        } else {
            (1, 0)
        };
        let mut found = 0;
        let mut push = |out: &mut Constraint, value: f64, v: Vector3<f64>, ok: bool| {
            if found < 3 {
                out.eigenvalues[found] = value as f32;
                out.directions[found] = [v[0] as f32, v[1] as f32, v[2] as f32];
                out.constrained[found] = ok;
                found += 1;
            }
        };
        // Basis of the part analysed together: all of it, or all but `d` (or but the whole
        // position when neither position direction passes).
        let mut basis: [Vector3<f64>; 3] = [Vector3::zeros(); 3];
        let mut dims = 0;
        let weak_value = pos.eigenvalues[weak];
        if passes(weak_value) {
            basis = [Vector3::x(), Vector3::y(), Vector3::z()];
            dims = 3;
        } else {
            let d = pos.eigenvectors.column(weak);
            push(&mut out, weak_value, Vector3::new(d[0], d[1], 0.0), false);
            let strong_value = pos.eigenvalues[strong];
            let e = pos.eigenvectors.column(strong);
            if passes(strong_value) {
                basis[dims] = Vector3::new(e[0], e[1], 0.0);
                dims += 1;
            } else {
                push(&mut out, strong_value, Vector3::new(e[0], e[1], 0.0), false);
            }
            basis[dims] = Vector3::z();
            dims += 1;
        }
        // Eigen-analysis of the information restricted to the basis.
        let mut reduced = Matrix3::<f64>::zeros();
        for a in 0..dims {
            for b in 0..dims {
                reduced[(a, b)] = basis[a].dot(&(information * basis[b]));
            }
        }
        // (values, vectors in the basis' coordinates), statically sized: no allocation.
        let mut values = [0.0f64; 3];
        let mut vectors = [[0.0f64; 3]; 3];
        match dims {
            3 => {
                let eig = SymmetricEigen::new(reduced);
                for (i, (value, vector)) in values.iter_mut().zip(vectors.iter_mut()).enumerate() {
                    *value = eig.eigenvalues[i];
                    for (a, x) in vector.iter_mut().enumerate() {
                        *x = eig.eigenvectors[(a, i)];
                    }
                }
            }
            2 => {
                let eig = SymmetricEigen::new(reduced.fixed_view::<2, 2>(0, 0).into_owned());
                for (i, (value, vector)) in values
                    .iter_mut()
                    .zip(vectors.iter_mut())
                    .enumerate()
                    .take(2)
                {
                    *value = eig.eigenvalues[i];
                    for (a, x) in vector.iter_mut().enumerate().take(2) {
                        *x = eig.eigenvectors[(a, i)];
                    }
                }
            }
            _ => {
                values[0] = reduced[(0, 0)];
                vectors[0][0] = 1.0;
            }
        }
        for i in 0..dims {
            let mut v = Vector3::zeros();
            for (a, b) in basis.iter().enumerate().take(dims) {
                v += b * vectors[i][a];
            }
            push(&mut out, values[i], v, passes(values[i]));
        }
        // Ascending by eigenvalue, the unconstrained position directions included.
        let mut idx = [0usize, 1, 2];
        idx.sort_unstable_by(|&a, &b| out.eigenvalues[a].total_cmp(&out.eigenvalues[b]));
        Constraint {
            eigenvalues: idx.map(|i| out.eigenvalues[i]),
            directions: idx.map(|i| out.directions[i]),
            constrained: idx.map(|i| out.constrained[i]),
        }
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
        let c = Constraint::analyse(&h, &h, 1.0, 0.02);
        assert_eq!(c.constrained, [false, true, true]);
        assert_eq!(c.constrained_count(), 2);
        let p = c.project([0.3, -0.05, 0.01]);
        assert!(p[0].abs() < 1e-6);
        assert!((p[1] + 0.05).abs() < 1e-6 && (p[2] - 0.01).abs() < 1e-6);
    }

    #[test]
    fn a_direction_pinned_to_millimetres_beside_a_far_held_heading_is_constrained() {
        // Seed 34's stretch (docs/experiments.md, "seed 34's turned map"): y pinned to 5 mm
        // (4·10⁴ m⁻²) beside a heading held by walls 3–4 m away (2.5·10⁶ in θ·1 m), 1.6 % of
        // it; nothing along x (a corridor). With the matcher's settings y is kept, x is not.
        let h = Matrix3::new(1e-4, 0.0, 0.0, 0.0, 4.0e4, 0.0, 0.0, 0.0, 2.5e6);
        let fine = crate::localize::ndt::NdtConfig::default();
        let min_eigenvalue = 1.0 / (fine.max_sigma_m * fine.max_sigma_m);
        let c = Constraint::analyse(&h, &h, min_eigenvalue, fine.min_information_ratio);
        assert_eq!(c.constrained, [false, true, true]);
        assert!(c.directions[1][1].abs() > 0.99, "{:?}", c.directions);
    }
}
