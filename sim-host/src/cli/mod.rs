//! Subcommands of `papillon-sim`, one module each.

pub mod bench;
pub mod mission;
pub mod optimize;
pub mod plan;
pub mod score;
pub mod serve;
pub mod tune;

use std::path::{Path, PathBuf};

use crate::bench::sweep::Shard;

/// `--jobs` of `bench` and `tune`: 0 (one per core) to [`bench::MAX_JOBS`].
pub(crate) fn check_jobs(jobs: usize) -> Result<(), String> {
    if jobs > bench::MAX_JOBS {
        return Err(format!(
            "--jobs: expected 0 (one per core) to {}, got {jobs}",
            bench::MAX_JOBS
        ));
    }
    Ok(())
}

/// Where a `bench` or `tune` run goes: the part `--shard` names (every run when absent) and
/// the output directory, `--out` or else `default_dir/name`.
pub(crate) fn shard_and_out(
    shard: Option<&str>,
    out: Option<&Path>,
    default_dir: &str,
    name: &str,
) -> Result<(Shard, PathBuf), String> {
    let shard = match shard {
        Some(t) => Shard::parse(t)?,
        None => Shard::ALL,
    };
    let out = out.map_or_else(|| Path::new(default_dir).join(name), Path::to_path_buf);
    Ok((shard, out))
}

/// A `--laser-noise` value (`mission`, `serve`): a fraction of the range in [0, 1).
pub(crate) fn noise_fraction(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..1.0).contains(&v) => Ok(v),
        _ => Err(format!("{s:?} is not a fraction of the range in [0, 1)")),
    }
}

/// Largest `--laser-noise-m` \[m\]: a laser whose ranges scatter by more is no rangefinder.
pub(crate) const MAX_RANGE_SIGMA_M: f32 = 0.5;

/// A `--laser-noise-m` value (`mission`, `serve`): a standard deviation in metres in
/// [0, [`MAX_RANGE_SIGMA_M`]].
pub(crate) fn range_sigma_m(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..=MAX_RANGE_SIGMA_M).contains(&v) => Ok(v),
        _ => Err(format!(
            "{s:?} is not a standard deviation in metres in [0, {MAX_RANGE_SIGMA_M}]"
        )),
    }
}
