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
#[inline]
pub fn floor(x: f32) -> f32 {
    libm::floorf(x)
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
