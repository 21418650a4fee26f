//! Draws from a seeded random number generator.
//!
//! The core never owns a global RNG: every function that needs randomness takes
//! `&mut impl Rng` (rand_core 0.10), normally a seeded [`rand_xoshiro::Xoshiro256PlusPlus`]
//! created by the caller with [`seeded`]. Same seed, same run.

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::math;

/// The generator used across the project.
pub type ProjectRng = Xoshiro256PlusPlus;

/// A generator seeded from a 64-bit seed.
pub fn seeded(seed: u64) -> ProjectRng {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// Uniform in `[0, 1)` with 24 bits of precision.
#[inline]
pub fn unit_f32(rng: &mut impl Rng) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Uniform in `[lo, hi)`.
#[inline]
pub fn range_f32(rng: &mut impl Rng, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * unit_f32(rng)
}

/// Uniform integer in `0..n`; `n` must be non-zero. Uses Lemire's multiply-shift, whose bias
/// is below 2^-32 for the small `n` used here.
#[inline]
pub fn below(rng: &mut impl Rng, n: usize) -> usize {
    debug_assert!(n > 0);
    ((rng.next_u32() as u64 * n as u64) >> 32) as usize
}

/// `true` with probability `p`.
#[inline]
pub fn chance(rng: &mut impl Rng, p: f32) -> bool {
    unit_f32(rng) < p
}

/// Standard normal draw (Box–Muller, one of the pair).
pub fn gaussian(rng: &mut impl Rng) -> f32 {
    // 1 - u lies in (0, 1], so the logarithm is finite.
    let u1 = 1.0 - unit_f32(rng);
    let u2 = unit_f32(rng);
    math::sqrt(-2.0 * math::ln(u1)) * math::cos(core::f32::consts::TAU * u2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_draws() {
        let mut a = seeded(25);
        let mut b = seeded(25);
        for _ in 0..100 {
            assert_eq!(unit_f32(&mut a).to_bits(), unit_f32(&mut b).to_bits());
        }
    }

    #[test]
    fn draws_stay_in_range() {
        let mut rng = seeded(1);
        for _ in 0..10_000 {
            let u = unit_f32(&mut rng);
            assert!((0.0..1.0).contains(&u));
            assert!(below(&mut rng, 7) < 7);
            let r = range_f32(&mut rng, -2.0, 3.0);
            assert!((-2.0..3.0).contains(&r));
        }
    }

    #[test]
    fn gaussian_has_unit_spread() {
        let mut rng = seeded(7);
        let n = 20_000;
        let (mut sum, mut sq) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let g = gaussian(&mut rng) as f64;
            sum += g;
            sq += g * g;
        }
        let mean = sum / n as f64;
        let var = sq / n as f64 - mean * mean;
        assert!(mean.abs() < 0.05, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
    }
}
