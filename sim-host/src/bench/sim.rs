//! One run of a sweep in the simulator: the mission set up exactly as `papillon-sim mission`
//! would for the same options ([`crate::cli::mission::Setup`]), run by the fast runner
//! ([`crate::runner::Runner`]).
//!
//! The convergence curve (best fitness per generation) is the run's first decision: the
//! runner does not keep each decision's history, so when robot 0 first decides the decision
//! is computed once more, off the run, from the same map, pose, battery and decision
//! generator state (robot 0's decision stream starts fresh at that point, the first decision
//! being its first use), with its own working memory. With one robot it is the very decision
//! the run made; with several, the other robots' marks of that control period may differ.

use papillon::explore::{DecisionRequest, ExploreObjective, Optimized, Outcome, TargetSelector};
use papillon::mission::SelectorKind;
use papillon::planner::{AStar, DistanceField};
use papillon::random;

use super::record::RunResult;
use super::sweep::RunSpec;
use crate::cli::mission::{Args, Setup};
use crate::dynamic::Dynamics;
use crate::runner::{self, MAP_CAPACITY, Progress, Runner};

/// The runner's stream number of the decision generator (see [`runner::derive_seed`]).
const STREAM_DECIDE: u64 = 3;

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

/// Best fitness per generation of the decision robot 0 would make now in `runner`.
fn replay_first_decision(runner: &Runner, setup: &Setup) -> Vec<f32> {
    let SelectorKind::Optimized(method) = setup.run.mission.selector else {
        return Vec::new();
    };
    let mission = runner.mission(0);
    let map = runner.map();
    let mut field = DistanceField::<MAP_CAPACITY>::new_boxed();
    let mut astar = AStar::<MAP_CAPACITY>::new_boxed();
    let mut stamps = vec![0u32; MAP_CAPACITY];
    let mut objective = ExploreObjective::new(&mut field, &mut astar, &mut stamps);
    let req = DecisionRequest {
        grid: &map.grid,
        trav: &map.trav,
        pose: mission.pose_map(),
        battery_steps: mission.battery_steps(),
        laser: &setup.run.mission.laser,
    };
    let mut rng = random::seeded(runner::derive_seed(setup.run.seed, 0, STREAM_DECIDE));
    match Optimized::new(method, setup.run.mission.explore, &mut objective).decide(&req, &mut rng) {
        Ok(Outcome::Go(d)) => d.history.to_vec(),
        _ => Vec::new(),
    }
}

/// Runs `spec` in the simulator.
pub fn run(spec: &RunSpec) -> Result<RunResult, String> {
    let setup = Setup::from_args(&mission_args(spec)?)?;
    let mut runner = Runner::new(setup.world.clone(), Dynamics::new(), setup.run.clone())
        .map_err(|e| e.to_string())?;
    let mut convergence: Option<Vec<f32>> = None;
    let report = runner
        .run_with(|r, p| {
            if p == (Progress::Decided { robot: 0 }) && convergence.is_none() {
                convergence = Some(replay_first_decision(r, &setup));
            }
        })
        .map_err(|e| e.to_string())?;
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
