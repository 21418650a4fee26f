//! Subcommands of `papillon-sim`, one module each.

pub mod bench;
pub mod mission;
pub mod optimize;
pub mod plan;
pub mod score;
pub mod serve;
pub mod tune;

/// A `--laser-noise` value (`mission`, `serve`): a fraction of the range in [0, 1).
pub(crate) fn noise_fraction(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..1.0).contains(&v) => Ok(v),
        _ => Err(format!("{s:?} is not a fraction of the range in [0, 1)")),
    }
}
