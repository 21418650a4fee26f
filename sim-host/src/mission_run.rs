//! A mission run the way `papillon-sim mission` does it: a checked [`Setup`] run by the fast
//! runner ([`crate::runner`]), with a picture per decision and a final one
//! ([`crate::render`]), an MCAP recording ([`crate::record`]), and its report as JSON or as a
//! human summary.

use std::path::{Path, PathBuf};

use crate::dynamic::Dynamics;
use crate::record::RunRecorder;
use crate::render::{self, Track};
use crate::runner::{self, RunReport, Runner};
use crate::scenario::Setup;
use crate::world::World;

/// Pixels per cell for pictures about 600 pixels across (1 to 4).
pub fn picture_scale(world: &World) -> u32 {
    papillon::picture::picture_scale(world.geometry())
}

/// A setting as the user wrote it (`0.08`, not the `f32`'s `0.07999999821186066`).
fn setting(value: f32) -> f64 {
    value.to_string().parse().unwrap_or(f64::from(value))
}

/// The JSON report (one object).
pub fn json_report(setup: &Setup, report: &RunReport) -> serde_json::Value {
    let per_robot: Vec<serde_json::Value> = report
        .robots
        .iter()
        .map(|r| {
            serde_json::json!({
                "steps": r.steps,
                "distance_m": r.distance_m,
                "rotation_rad": r.rotation_rad,
                "decisions": r.decisions,
                "fitness_evals": r.fitness_evals,
                "replans": r.replans,
                "yields": r.yields,
                "faults": r.faults,
                "collisions": r.collisions,
                "battery_steps": r.battery_steps,
                "done": r.done.map(|d| runner::EndReason::from(d).name()),
                "pose_error_m": r.pose_error_m,
                "localization": r.localization,
            })
        })
        .collect();
    let m = &setup.run.mission;
    serde_json::json!({
        "map": setup.world.name(),
        "method": setup.method(),
        "robots": setup.run.robots,
        "seed": setup.run.seed,
        "population": m.explore.population,
        "preset": m.explore.preset.name(),
        "generations": m.explore.max_generations,
        "strategy": setup.strategy.name(),
        "targets": m.explore.targets,
        "battery_steps": m.battery_steps,
        "slip": setup.slip.name(),
        "localize": m.localize.enabled,
        "pose_graph": m.localize.graph.enabled,
        "self_calibration": m.localize.enabled && m.localize.calibration.enabled,
        "resolution_m": setting(setup.world.geometry().resolution_m),
        "clearance_m": setting(setup.clearance_m),
        "occupied_thresh": setting(setup.occupied_thresh),
        "laser_noise": setting(m.laser.noise_fraction),
        "laser_noise_m": setting(setup.run.laser_range_sigma_m),
        "coverage": report.coverage,
        "map_accuracy": report.map_accuracy,
        "observable_cells": report.observable_cells,
        "known_cells": report.known_cells,
        "steps": report.steps(),
        "steps_per_robot": report.robots.iter().map(|r| r.steps).collect::<Vec<_>>(),
        "distance_m": report.distance_m(),
        "rotation_rad": report.rotation_rad(),
        "decisions": report.decisions(),
        "fitness_evals": report.fitness_evals(),
        "decision_ms_p50": report.decision_ms_quantile(0.5),
        "decision_ms_p99": report.decision_ms_quantile(0.99),
        "decision_ms_total": report.decision_ms_total(),
        "replans": report.replans(),
        "collisions": report.collisions(),
        "sim_time_s": report.sim_time_s,
        "wall_time_s": report.wall_time_s,
        "reason": report.reason.map(|r| r.name()),
        "coverage_curve": report.coverage_curve.iter().map(|&(s, c)| [s as f64, c as f64]).collect::<Vec<_>>(),
        "coverage_time_curve": report.coverage_time_curve.iter().map(|&(t, c)| [t, c as f64]).collect::<Vec<_>>(),
        "coverage_distance_curve": report.coverage_distance_curve.iter().map(|&(m, c)| [m as f64, c as f64]).collect::<Vec<_>>(),
        "per_robot": per_robot,
    })
}

/// The human summary.
pub fn summary(setup: &Setup, report: &RunReport) -> String {
    let g = setup.world.geometry();
    let m = &setup.run.mission;
    let mut s = String::new();
    let plural = if setup.run.robots == 1 { "" } else { "s" };
    s += &format!(
        "mission on {} ({:.1} m x {:.1} m, {} m cells): {}, {} robot{plural}, population {}, {} generations, {}-term (k = {}), battery {} steps, {} slip, seed {}\n",
        setup.world.name(),
        g.width_m(),
        g.height_m(),
        g.resolution_m,
        setup.method(),
        setup.run.robots,
        m.explore.population,
        m.explore.max_generations,
        setup.strategy,
        m.explore.targets,
        m.battery_steps,
        setup.slip,
        setup.run.seed
    );
    let speed = if report.wall_time_s > 0.0 {
        report.sim_time_s / report.wall_time_s
    } else {
        0.0
    };
    s += &format!(
        "ended: {} after {:.1} s simulated ({:.2} s wall, {:.0}x real time)\n",
        report.reason.map_or("running", |r| r.name()),
        report.sim_time_s,
        report.wall_time_s,
        speed
    );
    s += &format!(
        "coverage: {:.2} % ({} of {} observable cells known)\n",
        100.0 * report.coverage,
        report.known_cells,
        report.observable_cells
    );
    let per: Vec<String> = report
        .robots
        .iter()
        .enumerate()
        .map(|(k, r)| format!("robot {k}: {:.1}", r.steps))
        .collect();
    s += &format!(
        "steps: {:.1} ({}); {:.1} m travelled, {:.1} rad turned\n",
        report.steps(),
        per.join(", "),
        report.distance_m(),
        report.rotation_rad()
    );
    s += &format!(
        "decisions: {}, fitness evaluations {}, decision time p50 {:.2} ms, p99 {:.2} ms, total {:.1} ms\n",
        report.decisions(),
        report.fitness_evals(),
        report.decision_ms_quantile(0.5),
        report.decision_ms_quantile(0.99),
        report.decision_ms_total()
    );
    s += &format!(
        "replans: {}, yields: {}, contacts: {}",
        report.replans(),
        report.robots.iter().map(|r| r.yields).sum::<u32>(),
        report.collisions()
    );
    s
}

fn frame_path(dir: &Path, n: usize) -> PathBuf {
    dir.join(format!("frame-{n:04}.png"))
}

/// Why [`execute`] failed: a set-up the runner refuses (exit 2) or a file that could not be
/// written (exit 1); one line each.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The runner refused the set-up.
    Setup(String),
    /// A picture or the recording could not be written.
    Output(String),
}

/// Runs a checked set-up and returns the report, writing one picture per decision into
/// `frames` and the final picture to `png` when given.
pub fn execute(
    setup: &Setup,
    frames: Option<&Path>,
    png: Option<&Path>,
) -> Result<RunReport, Failure> {
    execute_recorded(setup, frames, png, None, None)
}

/// [`execute`], also recording the mission as MCAP into `mcap` when given and serving it live
/// when `live` is given ([`crate::record`]).
pub fn execute_recorded(
    setup: &Setup,
    frames: Option<&Path>,
    png: Option<&Path>,
    mcap: Option<&Path>,
    live: Option<&crate::record::LiveOptions>,
) -> Result<RunReport, Failure> {
    // The map's capacity follows the world (`papillon::capacity`).
    let cells = setup.world.geometry().cell_count();
    papillon::with_cell_capacity!(cells, N => {
        execute_sized::<N>(setup, frames, png, mcap, live)
    })
    .unwrap_or_else(|| {
        let e = runner::RunError::MapTooLarge {
            cells,
            capacity: runner::MAP_CAPACITY,
        };
        Err(Failure::Setup(format!("{}: {e}", setup.world.name())))
    })
}

/// [`execute_recorded`] on a map of `N` cells.
fn execute_sized<const N: usize>(
    setup: &Setup,
    frames: Option<&Path>,
    png: Option<&Path>,
    mcap: Option<&Path>,
    live: Option<&crate::record::LiveOptions>,
) -> Result<RunReport, Failure> {
    let scale = picture_scale(&setup.world);
    let mut runner = Runner::<N>::sized(setup.world.clone(), Dynamics::new(), setup.run.clone())
        .map_err(|e| Failure::Setup(e.to_string()))?;
    if let Some(dir) = frames {
        std::fs::create_dir_all(dir).map_err(|e| {
            Failure::Output(format!("--frames: {}: cannot create: {e}", dir.display()))
        })?;
    }
    let mut recorder = RunRecorder::open(mcap, live, setup.run.robots).map_err(Failure::Output)?;
    let mut frame = 0usize;
    let mut frame_error: Option<String> = None;
    let report = runner
        .run_with(|r, progress| {
            if let Some(rec) = &mut recorder {
                rec.observe(r, progress);
            }
            let Some(dir) = frames else { return };
            if frame_error.is_some() || !matches!(progress, runner::Progress::Decided { .. }) {
                return;
            }
            frame += 1;
            let img = render::render_grid_picture(&r.map().grid, &r.tracks(), scale);
            if let Err(e) = render::save_png(&img, &frame_path(dir, frame)) {
                frame_error = Some(format!("--frames: {e}"));
            }
        })
        .map_err(|e| Failure::Setup(e.to_string()))?;
    if let Some(e) = frame_error {
        return Err(Failure::Output(e));
    }
    if let Some(rec) = recorder {
        rec.finish()
            .map_err(|e| Failure::Output(format!("--mcap: {e}")))?;
    }
    if let Some(path) = png {
        let tracks: Vec<Track> = runner.tracks();
        let img = render::render_grid_picture(&runner.map().grid, &tracks, scale);
        render::save_png(&img, path).map_err(|e| Failure::Output(format!("--png: {e}")))?;
    }
    Ok(report)
}
