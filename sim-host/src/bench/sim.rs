//! One run of a sweep in the simulator: the mission set up by the same scenario builder as
//! `papillon-sim mission` for the same options ([`crate::scenario::Setup`]), run by the fast
//! runner ([`crate::runner::Runner`]).
//!
//! The convergence curve (best fitness per generation) is that of robot 0's first decision,
//! as the runner recorded it.

use super::record::RunResult;
use super::sweep::RunSpec;
use crate::dynamic::Dynamics;
use crate::runner;
use crate::scenario::{
    ScenarioSpec, Setup, Slip, Strategy, objective_from_name, preset_from_name, selector_from_name,
};

/// The scenario of a run: `papillon-sim mission`'s defaults (thesis slip, the world's start)
/// with the run's world, robots, selector, budget, strategy, seed, battery and cell size. The
/// run's `targets` counts for the long-term strategy only, as `--targets` does.
pub fn scenario(spec: &RunSpec) -> Result<ScenarioSpec, String> {
    let strategy = Strategy::from_name(&spec.strategy)?;
    Ok(ScenarioSpec {
        map: spec.map.clone(),
        resolution_m: spec.resolution_m,
        robots: spec.robots,
        selector: selector_from_name(&spec.method)?,
        objective: objective_from_name(&spec.objective)?,
        population: spec.population,
        generations: spec.generations,
        strategy,
        targets: (strategy == Strategy::Long).then_some(spec.targets),
        seed: spec.seed,
        battery_steps: spec.battery_steps,
        start: None,
        slip: Slip::Thesis,
        localize: false,
        pose_graph: false,
        self_calibration: true,
        laser_noise: None,
        laser_noise_m: None,
        preset: preset_from_name(&spec.preset)?,
        tuning: match &spec.params {
            Some(values) => Some(super::params::tuning(
                &spec.method,
                spec.population,
                preset_from_name(&spec.preset)?,
                values,
            )?),
            None => None,
        },
        clearance_m: papillon::mission::footprint::DEFAULT_CLEARANCE_M,
        occupied_thresh: papillon::grid::DEFAULT_OCCUPIED_THRESH,
    })
}

/// Runs `spec` in the simulator (sized to its world, as [`runner::run_sized`]), cut at its
/// `max_time_s` if it has one; measures the CPU time of the run loop (the span of the
/// report's `wall_time_s`, not the world's generation nor the runner's set-up) and the
/// process's peak memory over the whole run ([`super::cost`]).
pub fn run(spec: &RunSpec) -> Result<RunResult, String> {
    let reset = super::cost::reset_peak_rss();
    let Setup { world, mut run, .. } = Setup::new(&scenario(spec)?)?;
    if let Some(t) = spec.max_time_s {
        run.max_sim_time_s = t;
    }
    let cells = world.geometry().cell_count();
    let (report, cpu_time_s) = papillon::with_cell_capacity!(cells, N => {
        let mut r = runner::Runner::<N>::sized(world, Dynamics::new(), run)
            .map_err(|e| e.to_string())?;
        let cpu0 = super::cost::thread_cpu_s();
        let report = r.run().map_err(|e| e.to_string())?;
        let cpu = cpu0.zip(super::cost::thread_cpu_s()).map(|(a, b)| b - a);
        (report, cpu)
    })
    .ok_or_else(|| {
        runner::RunError::MapTooLarge {
            cells,
            capacity: runner::MAP_CAPACITY,
        }
        .to_string()
    })?;
    let cells = cells as u64;
    let peak_rss_mb = super::cost::peak_rss_mb().filter(|_| reset);
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
        cells: Some(cells),
        cpu_time_s,
        peak_rss_mb,
    })
}
