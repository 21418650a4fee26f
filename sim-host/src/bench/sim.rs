//! One run of a sweep in the simulator (to be wired to the fast mission runner).

use super::record::RunResult;
use super::sweep::RunSpec;

/// Runs `spec` in the simulator.
pub fn run(spec: &RunSpec) -> Result<RunResult, String> {
    Err(format!("run {}: the mission runner is not available yet", spec.index))
}
