//! Floating-point functions for the `no_std` core.
//!
//! `core` has no `sqrt`, `sin` or `atan2` for `f32` without `std`; these thin wrappers call
//! `libm` so every module uses the same implementation on the robot and on the host, and a
//! seeded simulation gives bit-identical results whichever feature set is built.

/// Square root.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Sine of `x` \[rad\].
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Cosine of `x` \[rad\].
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Sine and cosine of `x` \[rad\] at once: `(sin(x), cos(x))`, bit for bit [`sin`]'s and
/// [`cos`]'s (the same argument reduction and kernels, done once).
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    libm::sincosf(x)
}

/// Four-quadrant arctangent of `y / x` \[rad\], in (-pi, pi].
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f32) -> f32 {
    libm::expf(x)
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f32) -> f32 {
    libm::logf(x)
}

/// `x^y`.
#[inline]
pub fn powf(x: f32, y: f32) -> f32 {
    libm::powf(x, y)
}

/// Largest integer not greater than `x`.
///
/// Exact, so the same as every correct floor (libm's included): from 2^23 on every `f32` is an
/// integer (and NaN and infinities pass through); below, truncating through an `i32` is exact
/// and is one too high for negative non-integers. Integers, `-0.0` among them, come back
/// unchanged. Inline instead of a libm call: grid walks floor every point they convert to a
/// cell.
#[inline]
pub fn floor(x: f32) -> f32 {
    if x.is_nan() || abs(x) >= 8_388_608.0 {
        return x;
    }
    let t = x as i32 as f32;
    if t == x {
        x
    } else if t > x {
        t - 1.0
    } else {
        t
    }
}

/// Smallest integer not less than `x`.
#[inline]
pub fn ceil(x: f32) -> f32 {
    libm::ceilf(x)
}

/// Nearest integer, halfway cases away from zero.
#[inline]
pub fn round(x: f32) -> f32 {
    libm::roundf(x)
}

/// Euclidean length of `(x, y)`.
#[inline]
pub fn hypot(x: f32, y: f32) -> f32 {
    libm::hypotf(x, y)
}

/// Absolute value.
#[inline]
pub fn abs(x: f32) -> f32 {
    libm::fabsf(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{below, seeded};
    use rand_core::Rng;

    #[test]
    fn floor_is_libms_floor_bit_for_bit() {
        let same = |x: f32| {
            let (got, want) = (floor(x), libm::floorf(x));
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "floor({x:e}) = {got:e}, want {want:e}"
            );
        };
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            2.999_999_8,
            -2.999_999_8,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_609.0,
            1e30,
            -1e30,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            same(x);
        }
        // Random bit patterns cover every exponent; small values cover the usual grid range.
        let mut rng = seeded(3);
        for _ in 0..200_000 {
            same(f32::from_bits(rng.next_u32()));
            same((below(&mut rng, 2_000_001) as f32 - 1_000_000.0) / 64.0);
        }
    }

    #[test]
    fn sin_cos_is_sin_and_cos_bit_for_bit() {
        let same = |x: f32| {
            let (s, c) = sin_cos(x);
            let bits = |v: f32| if v.is_nan() { u32::MAX } else { v.to_bits() };
            assert_eq!(
                (bits(s), bits(c)),
                (bits(sin(x)), bits(cos(x))),
                "sin_cos({x:e})"
            );
        };
        for x in [0.0, -0.0, f32::INFINITY, f32::NAN, 1e-40, 1e30, -1e30] {
            same(x);
        }
        // Every f32 in [-8, 8] with a step of 2^-16 (the angles of beams and headings, and
        // every branch of the argument reduction up to 9π/4), and random bit patterns.
        let mut k = -8 * 65536;
        while k <= 8 * 65536 {
            same(k as f32 / 65536.0);
            k += 1;
        }
        let mut rng = seeded(4);
        for _ in 0..300_000 {
            same(f32::from_bits(rng.next_u32()));
            same((below(&mut rng, 1 << 24) as f32 - (1 << 23) as f32) * 1e-6);
        }
    }
}
