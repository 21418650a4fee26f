//! One run of a sweep in the simulator: the mission set up exactly as `papillon-sim mission`
//! would for the same options ([`crate::cli::mission::Setup`]), run by the fast runner
//! ([`crate::runner::Runner`]).
//!
//! The convergence curve (best fitness per generation) is that of robot 0's first decision,
//! as the runner recorded it.

use super::record::RunResult;
use super::sweep::RunSpec;
use crate::cli::mission::{Args, Setup};
use crate::dynamic::Dynamics;
use crate::runner::Runner;

/// `papillon-sim mission`'s options, parsed the way its command line is.
#[derive(clap::Parser)]
struct MissionLine {
    #[command(flatten)]
    args: Args,
}

/// The `papillon-sim mission` command line of a run (options not given keep their defaults).
pub fn mission_line(spec: &RunSpec) -> Vec<String> {
    let mut v: Vec<String> = [
        "--map",
        &spec.map,
        "--robots",
        &spec.robots.to_string(),
        "--method",
        &spec.method,
        "--pop",
        &spec.population.to_string(),
        "--gens",
        &spec.generations.to_string(),
        "--strategy",
        &spec.strategy,
        "--seed",
        &spec.seed.to_string(),
        "--resolution",
        &spec.resolution_m.to_string(),
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if spec.strategy == "long" {
        v.extend(["--targets".to_string(), spec.targets.to_string()]);
    }
    if let Some(b) = spec.battery_steps {
        v.extend(["--battery".to_string(), b.to_string()]);
    }
    v
}

/// The `papillon-sim mission` options of a run.
pub fn mission_args(spec: &RunSpec) -> Result<Args, String> {
    use clap::Parser;
    let line = std::iter::once("mission".to_string()).chain(mission_line(spec));
    MissionLine::try_parse_from(line)
        .map(|m| m.args)
        .map_err(|e| {
            let text = e.to_string();
            text.lines()
                .next()
                .unwrap_or("bad mission options")
                .to_string()
        })
}

/// Runs `spec` in the simulator.
pub fn run(spec: &RunSpec) -> Result<RunResult, String> {
    let setup = Setup::from_args(&mission_args(spec)?)?;
    let mut runner = Runner::new(setup.world.clone(), Dynamics::new(), setup.run.clone())
        .map_err(|e| e.to_string())?;
    let report = runner.run().map_err(|e| e.to_string())?;
    let convergence = report
        .robots
        .first()
        .and_then(|r| r.decision_histories.first())
        .cloned();
    Ok(RunResult {
        coverage: report.coverage,
        steps: report.steps(),
        steps_per_robot: report.robots.iter().map(|r| r.steps).collect(),
        distance_m: report.distance_m(),
        rotation_rad: report.rotation_rad(),
        decisions: report.decisions(),
        fitness_evals: report.fitness_evals(),
        decision_ms: report
            .robots
            .iter()
            .flat_map(|r| r.decision_ms.iter().copied())
            .collect(),
        sim_time_s: report.sim_time_s,
        wall_time_s: report.wall_time_s,
        reason: report.reason.map_or("running", |r| r.name()).to_string(),
        coverage_curve: report.coverage_curve.clone(),
        convergence: convergence.unwrap_or_default(),
    })
}
