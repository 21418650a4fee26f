//! Real-time correlative scan matching: an exhaustive search of a small pose window around the
//! odometry prediction (Olson, *Real-time correlative scan matching*, ICRA 2009, §III-§IV).
//!
//! For each candidate heading the returns are rotated once and rounded to window cells; every
//! candidate translation is then a whole-cell offset, so scoring it is one table look-up per
//! return. The score of a pose is the weighted mean likelihood of the returns
//! ([`super::likelihood::LikelihoodField`]), minus a weak motion prior that grows with the
//! distance from the prediction (Olson's `p(x_i | x_{i-1}, u)`): where several poses fit
//! equally well (a corridor seen without its ends), the one nearest the odometry wins. The
//! search is global within its window, so it cannot be trapped in a local optimum the way a
//! gradient method can; its result is a whole-cell translation, refined by
//! [`super::ndt`].

use crate::geometry::{Point2, Pose2};
use crate::math;

use super::likelihood::LikelihoodField;

/// The pose window searched around the prediction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchWindow {
    /// Translations searched in each axis: `-cells..=cells` window cells.
    pub cells: i32,
    /// Headings searched: `-steps..=steps` times `step_rad`.
    pub steps: i32,
    /// Heading step \[rad\].
    pub step_rad: f32,
    /// Score taken off at the window's edge in translation and again in heading (the motion
    /// prior; 0 for none), in units of mean likelihood.
    pub prior_at_edge: f32,
}

/// The best pose found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Best {
    /// The pose \[m, rad\].
    pub pose: Pose2,
    /// Its mean likelihood, prior included.
    pub score: f32,
    /// The mean likelihood of the prediction itself, scored the same way.
    pub score_at_prediction: f32,
}

/// Searches `window` around `predicted` for the pose under which the `points` (robot frame
/// \[m\], each with its weight in `weights`) best fit `field`. `scratch` holds one window
/// index and weight per point (at least as many entries as points). Points that fall off the
/// window score nothing. Allocation-free.
pub fn search<const T: usize>(
    field: &LikelihoodField<T>,
    points: &[Point2],
    weights: &[f32],
    predicted: Pose2,
    window: &SearchWindow,
    scratch: &mut [(u32, f32)],
) -> Best {
    let mut best = Best {
        pose: predicted,
        score: f32::NEG_INFINITY,
        score_at_prediction: f32::NEG_INFINITY,
    };
    let (w, h) = (field.width() as i32, field.height() as i32);
    let m = window.cells;
    if points.is_empty() || w <= 2 * m || h <= 2 * m {
        return best;
    }
    let values = field.values();
    let total: f32 = weights.iter().sum();
    if total <= 0.0 {
        return best;
    }
    let inv_n = 1.0 / total;
    let res = field.resolution_m();
    let edge_xy = (m.max(1) * m.max(1)) as f32;
    let edge_th = (window.steps.max(1) * window.steps.max(1)) as f32;
    for k in -window.steps..=window.steps {
        let theta = predicted.theta + k as f32 * window.step_rad;
        let (s, c) = (math::sin(theta), math::cos(theta));
        let mut n_in = 0usize;
        for (p, &wt) in points.iter().zip(weights) {
            let q = Point2::new(
                predicted.x + c * p.x - s * p.y,
                predicted.y + s * p.x + c * p.y,
            );
            let (u, v) = field.to_window(q);
            // Nearest cell centre (`floor(x + 0.5)`: no libm call in the inner loop).
            let (iu, iv) = (math::floor(u + 0.5) as i32, math::floor(v + 0.5) as i32);
            if iu >= m && iv >= m && iu < w - m && iv < h - m {
                scratch[n_in] = ((iv * w + iu) as u32, wt);
                n_in += 1;
            }
        }
        let cells = &scratch[..n_in];
        let prior_th = window.prior_at_edge * (k * k) as f32 / edge_th;
        for dy in -m..=m {
            for dx in -m..=m {
                let offset = (dy * w + dx) as isize;
                let mut sum = 0.0f32;
                for &(i, wt) in cells {
                    sum += values[(i as isize + offset) as usize] * wt;
                }
                let prior = prior_th + window.prior_at_edge * (dx * dx + dy * dy) as f32 / edge_xy;
                let score = sum * inv_n - prior;
                if k == 0 && dx == 0 && dy == 0 {
                    best.score_at_prediction = score;
                }
                if score > best.score {
                    best.pose = Pose2::new(
                        predicted.x + dx as f32 * res,
                        predicted.y + dy as f32 * res,
                        theta,
                    );
                    best.score = score;
                }
            }
        }
    }
    best
}
