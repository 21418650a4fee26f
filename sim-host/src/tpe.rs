//! The Tree-structured Parzen Estimator (TPE), for hyper-parameter search.
//!
//! Source: J. Bergstra, R. Bardenet, Y. Bengio and B. Kégl, "Algorithms for Hyper-Parameter
//! Optimization", NeurIPS 2011, section 4; the details below follow Hyperopt's `tpe.suggest`
//! (the library the thesis tuned with), read as a description, not copied.
//!
//! TPE models `p(x | y)` instead of `p(y | x)`. The trials so far are split at the quantile
//! `γ` of their loss: the `n_below = ceil(γ √n)` best form `l(x)`, the rest `g(x)`. Each is a
//! Parzen estimator over one parameter's range `[low, high]`: a truncated Gaussian at every
//! observation, its width the larger distance to its sorted neighbours, clipped to
//! `[(high − low) / min(100, n + 1), high − low]`, plus a prior Gaussian at the middle of the
//! range with width `high − low`, all weighted equally. `n_candidates` points are drawn from
//! `l` and the one with the largest `l(x) / g(x)` (the expected-improvement criterion of the
//! paper, eq. 6) is proposed. Parameters are modelled independently (Hyperopt's univariate
//! TPE). Before `n_startup` trials, a proposal is uniform in the ranges.
//!
//! Every draw comes from the generator the caller passes, so a proposal is a function of the
//! history and the seed.

use papillon::random;
use rand_core::Rng;

/// Hyperopt's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TpeConfig {
    /// Trials drawn uniformly before the model is used.
    pub n_startup: usize,
    /// Quantile `γ` of the split.
    pub gamma: f64,
    /// Candidates drawn from `l(x)` per proposal.
    pub n_candidates: usize,
}

impl Default for TpeConfig {
    fn default() -> Self {
        Self {
            n_startup: 10,
            gamma: 0.25,
            n_candidates: 24,
        }
    }
}

/// One parameter's range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower bound.
    pub low: f64,
    /// Upper bound (more than `low`).
    pub high: f64,
}

/// A truncated Gaussian mixture on `[low, high]` with equal weights.
struct Parzen {
    mus: Vec<f64>,
    sigmas: Vec<f64>,
    bounds: Bounds,
}

/// The standard normal distribution function (Abramowitz & Stegun 7.1.26, error below
/// 1.5e-7).
fn phi(x: f64) -> f64 {
    let z = x.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-z * z).exp();
    if x >= 0.0 {
        0.5 * (1.0 + erf)
    } else {
        0.5 * (1.0 - erf)
    }
}

impl Parzen {
    fn new(observations: &[f64], b: Bounds) -> Self {
        let width = b.high - b.low;
        // (centre, whether it is the prior), sorted by centre.
        let mut points: Vec<(f64, bool)> = observations.iter().map(|&x| (x, false)).collect();
        points.push((0.5 * (b.low + b.high), true));
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let n = points.len();
        let min_sigma = width / (100.0f64).min(observations.len() as f64 + 1.0);
        let sigmas = (0..n)
            .map(|i| {
                if points[i].1 {
                    return width;
                }
                let left = if i > 0 {
                    points[i].0 - points[i - 1].0
                } else {
                    0.0
                };
                let right = if i + 1 < n {
                    points[i + 1].0 - points[i].0
                } else {
                    0.0
                };
                left.max(right).clamp(min_sigma, width)
            })
            .collect();
        Self {
            mus: points.iter().map(|p| p.0).collect(),
            sigmas,
            bounds: b,
        }
    }

    fn density(&self, x: f64) -> f64 {
        let Bounds { low, high } = self.bounds;
        let mut sum = 0.0;
        for (&m, &s) in self.mus.iter().zip(&self.sigmas) {
            let mass = (phi((high - m) / s) - phi((low - m) / s)).max(1e-12);
            let z = (x - m) / s;
            sum += (-0.5 * z * z).exp() / (s * (2.0 * std::f64::consts::PI).sqrt() * mass);
        }
        sum / self.mus.len() as f64
    }

    fn sample<R: Rng>(&self, rng: &mut R) -> f64 {
        let Bounds { low, high } = self.bounds;
        let k = random::below(rng, self.mus.len());
        for _ in 0..100 {
            let x = self.mus[k] + self.sigmas[k] * f64::from(random::gaussian(rng));
            if (low..=high).contains(&x) {
                return x;
            }
        }
        self.mus[k].clamp(low, high)
    }
}

/// Proposes the next point: `history` holds each past trial's point (one value per
/// parameter, in the order of `bounds`) and loss (lower is better).
pub fn suggest<R: Rng>(
    config: &TpeConfig,
    bounds: &[Bounds],
    history: &[(Vec<f64>, f64)],
    rng: &mut R,
) -> Vec<f64> {
    if history.len() < config.n_startup.max(2) {
        return bounds
            .iter()
            .map(|b| b.low + (b.high - b.low) * f64::from(random::unit_f32(rng)))
            .collect();
    }
    let mut order: Vec<usize> = (0..history.len()).collect();
    order.sort_by(|&a, &b| history[a].1.total_cmp(&history[b].1).then(a.cmp(&b)));
    let n_below = ((config.gamma * (history.len() as f64).sqrt()).ceil() as usize)
        .clamp(1, history.len() - 1);
    let (below, above) = order.split_at(n_below);
    bounds
        .iter()
        .enumerate()
        .map(|(d, &b)| {
            let l = Parzen::new(
                &below.iter().map(|&i| history[i].0[d]).collect::<Vec<_>>(),
                b,
            );
            let g = Parzen::new(
                &above.iter().map(|&i| history[i].0[d]).collect::<Vec<_>>(),
                b,
            );
            let mut best = (f64::NEG_INFINITY, b.low);
            for _ in 0..config.n_candidates.max(1) {
                let x = l.sample(rng);
                let score = l.density(x).ln() - g.density(x).max(1e-300).ln();
                if score > best.0 {
                    best = (score, x);
                }
            }
            best.1
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_distribution_function_matches_known_values() {
        assert!((phi(0.0) - 0.5).abs() < 1e-7);
        assert!((phi(1.0) - 0.841_344_746).abs() < 2e-7);
        assert!((phi(-1.96) - 0.024_997_895).abs() < 2e-7);
    }

    #[test]
    fn a_truncated_mixture_integrates_to_one_on_its_range() {
        let b = Bounds {
            low: 0.0,
            high: 1.0,
        };
        let p = Parzen::new(&[0.1, 0.15, 0.9], b);
        let n = 10_000;
        let integral: f64 = (0..n)
            .map(|i| p.density((i as f64 + 0.5) / n as f64) / n as f64)
            .sum();
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
    }

    /// With the same 60 trials, TPE gets nearer the minimum of a 2-D bowl than random search
    /// (summed over 10 seeds; Hyperopt's broad Parzen windows make the margin moderate: about
    /// 0.63 of random search's distance here), and stays in the bounds.
    #[test]
    fn tpe_beats_random_search_on_a_bowl() {
        let bounds = [
            Bounds {
                low: -5.0,
                high: 5.0,
            },
            Bounds {
                low: 0.0,
                high: 10.0,
            },
        ];
        let f = |x: &[f64]| (x[0] - 1.3).powi(2) + (x[1] - 7.2).powi(2);
        let best_of = |config: TpeConfig, seed: u64| {
            let mut rng = random::seeded(seed);
            let mut history: Vec<(Vec<f64>, f64)> = Vec::new();
            for _ in 0..60 {
                let x = suggest(&config, &bounds, &history, &mut rng);
                assert!(
                    x.iter()
                        .zip(&bounds)
                        .all(|(v, b)| (b.low..=b.high).contains(v))
                );
                let y = f(&x);
                history.push((x, y));
            }
            history.iter().map(|h| h.1).fold(f64::INFINITY, f64::min)
        };
        let random_only = TpeConfig {
            n_startup: usize::MAX,
            ..TpeConfig::default()
        };
        let (mut tpe, mut rs) = (0.0, 0.0);
        for seed in 0..10 {
            tpe += best_of(TpeConfig::default(), seed);
            rs += best_of(random_only, seed);
        }
        assert!(
            tpe < 0.8 * rs,
            "TPE {tpe} vs random {rs} (sums over 10 seeds)"
        );
    }
}
