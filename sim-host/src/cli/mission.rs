//! `papillon-sim mission`: a whole exploration mission in simulated time
//! ([`crate::runner`]), with a human summary, `--json`, `--png` and `--frames`.
//!
//! Bad arguments, bad map files and a start inside an obstacle exit with status 2 and one line
//! on standard error.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use papillon::geometry::Pose2;
use papillon::mission::{MissionConfig, SelectorKind};
use papillon::optim::Method;

use crate::dynamic::Dynamics;
use crate::physics::SlipConfig;
use crate::render::{self, Track};
use crate::runner::{self, RunConfig, RunReport, Runner};
use crate::world::World;

/// Arguments of `papillon-sim mission` (kept as text and checked by [`Setup::from_args`], so
/// every problem is reported on one line naming the option).
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// World: house, empty, factory, lab, or a map file (.csv, .png, .pgm, .map, .yaml).
    #[arg(long, default_value = "house")]
    pub map: String,
    /// Number of robots sharing the map (1 to 8).
    #[arg(long, default_value = "1")]
    pub robots: String,
    /// Target selector: xboa boa mboa aboa saboa ga pso gwo abc cmaes nearest-frontier
    /// frontier-utility.
    #[arg(long, default_value = "xboa")]
    pub method: String,
    /// Population of the optimizer.
    #[arg(long, default_value = "5")]
    pub pop: String,
    /// Generations of the optimizer.
    #[arg(long, default_value = "30")]
    pub gens: String,
    /// Strategy: short (one target per decision) or long (several, see --targets).
    #[arg(long, default_value = "short")]
    pub strategy: String,
    /// Targets per decision, k (short: 1; long: default 3, at most 8).
    #[arg(long)]
    pub targets: Option<String>,
    /// Seed of every random choice (slip, laser noise, decisions).
    #[arg(long, default_value = "25")]
    pub seed: String,
    /// Energy at the start [steps: 1 m of travel or 45° of rotation] (default: the core
    /// mission's, 500).
    #[arg(long)]
    pub battery: Option<String>,
    /// Start pose in the map frame: X Y, optionally THETA (m, m, rad; default 1 m east and 1 m north of
    /// the map's south-west corner, heading east).
    #[arg(long, num_args = 2..=3, allow_negative_numbers = true, value_names = ["X", "Y", "THETA"])]
    pub start: Option<Vec<String>>,
    /// Odometry slip of the simulated robots: thesis (a 1.5 cm slide at the end of each move,
    /// what the thesis saw), full (also heading and distance random walks, see
    /// docs/simulator.md), realistic (also per-robot wheel-diameter and wheelbase errors and
    /// fast-turn slip, see sim-host/src/odometry_error.rs) or none.
    #[arg(long, default_value = "thesis")]
    pub slip: String,
    /// Scan-to-map matching before each scan is integrated: on or off.
    #[arg(long, default_value = "off")]
    pub localize: String,
    /// Cell size in metres (the map file's own for .yaml).
    #[arg(long, default_value = "0.1")]
    pub resolution: String,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Write the final map with trajectories and targets as a PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Write one PNG per decision into this directory (created if needed).
    #[arg(long)]
    pub frames: Option<PathBuf>,
}

/// A checked mission set-up.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The world.
    pub world: World,
    /// The run.
    pub run: RunConfig,
    /// The selector's name as given.
    pub method: String,
    /// `short` or `long`.
    pub strategy: String,
    /// `thesis`, `full` or `none`.
    pub slip: String,
}

fn number<T: std::str::FromStr>(option: &str, text: &str, what: &str) -> Result<T, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("{option}: expected {what}, got '{text}'"))
}

impl Setup {
    /// Checks the arguments and loads the world; the error is one line naming the option or
    /// the file.
    pub fn from_args(args: &Args) -> Result<Self, String> {
        let robots: usize = number("--robots", &args.robots, "a whole number of robots")?;
        if !(1..=runner::MAX_ROBOTS).contains(&robots) {
            return Err(format!(
                "--robots: expected 1 to {}, got {robots}",
                runner::MAX_ROBOTS
            ));
        }
        let selector = match args.method.as_str() {
            "nearest-frontier" => SelectorKind::NearestFrontier,
            "frontier-utility" => SelectorKind::FrontierUtility,
            m => SelectorKind::Optimized(m.parse::<Method>().map_err(|_| {
                format!(
                    "--method: unknown method '{m}', expected one of: xboa boa mboa aboa saboa ga pso gwo abc cmaes nearest-frontier frontier-utility"
                )
            })?),
        };
        let pop: usize = number("--pop", &args.pop, "a whole number")?;
        if !(2..=64).contains(&pop) {
            return Err(format!("--pop: expected 2 to 64, got {pop}"));
        }
        let gens: u32 = number("--gens", &args.gens, "a whole number")?;
        if gens == 0 {
            return Err("--gens: expected at least 1".into());
        }
        let max_k = papillon::explore::MAX_TARGETS;
        let targets = match args.strategy.as_str() {
            "short" => match &args.targets {
                None => 1,
                Some(t) => {
                    let k: usize = number("--targets", t, "a whole number")?;
                    if k != 1 {
                        return Err(format!(
                            "--targets: the short-term strategy has one target per decision, got {k} (use --strategy long)"
                        ));
                    }
                    k
                }
            },
            "long" => {
                let k: usize = match &args.targets {
                    None => 3,
                    Some(t) => number("--targets", t, "a whole number")?,
                };
                if !(1..=max_k).contains(&k) {
                    return Err(format!("--targets: expected 1 to {max_k}, got {k}"));
                }
                k
            }
            other => {
                return Err(format!("--strategy: expected short or long, got '{other}'"));
            }
        };
        let seed: u64 = number("--seed", &args.seed, "a whole number")?;
        let mut mission = MissionConfig {
            selector,
            ..MissionConfig::default()
        };
        mission.explore.population = pop;
        mission.explore.max_generations = gens;
        mission.explore.targets = targets;
        if let Some(b) = &args.battery {
            let b: f32 = number("--battery", b, "a number of steps")?;
            if !(b.is_finite() && b > 0.0) {
                return Err(format!(
                    "--battery: expected a positive number of steps, got {b}"
                ));
            }
            mission.battery_steps = b;
        }
        let resolution: f32 = number("--resolution", &args.resolution, "a cell size in metres")?;
        let mut world = World::load(&args.map, resolution).map_err(|e| e.to_string())?;
        if let Some(v) = &args.start {
            let nums = v
                .iter()
                .map(|t| number::<f32>("--start", t, "X Y [THETA] as numbers"))
                .collect::<Result<Vec<f32>, String>>()?;
            if nums.iter().any(|x| !x.is_finite()) {
                return Err("--start: expected finite numbers".into());
            }
            let pose = Pose2::new(nums[0], nums[1], nums.get(2).copied().unwrap_or(0.0));
            world.set_start(pose);
        }
        let mut run = RunConfig::new(mission, robots, seed);
        run.body.slip = match args.slip.as_str() {
            "thesis" => SlipConfig::thesis(),
            "full" => SlipConfig::default(),
            "none" => SlipConfig::none(),
            "realistic" => SlipConfig::realistic(),
            other => {
                return Err(format!(
                    "--slip: expected thesis, full, realistic or none, got '{other}'"
                ));
            }
        };
        run.mission.localize.enabled = match args.localize.as_str() {
            "on" => true,
            "off" => false,
            other => return Err(format!("--localize: expected on or off, got '{other}'")),
        };
        if !world.start_is_clear(run.body.radius_m) {
            let s = world.start();
            return Err(format!(
                "--start: ({:.2} m, {:.2} m) on {} is inside an obstacle or too close to one for a robot of radius {} m",
                s.x,
                s.y,
                world.name(),
                run.body.radius_m
            ));
        }
        Ok(Self {
            world,
            run,
            method: args.method.clone(),
            strategy: args.strategy.clone(),
            slip: args.slip.clone(),
        })
    }
}

/// Pixels per cell for pictures about 600 pixels across (1 to 4).
pub fn picture_scale(world: &World) -> u32 {
    let g = world.geometry();
    (600 / g.width.max(g.height).max(1) as u32).clamp(1, 4)
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
        "method": setup.method,
        "robots": setup.run.robots,
        "seed": setup.run.seed,
        "population": m.explore.population,
        "generations": m.explore.max_generations,
        "strategy": setup.strategy,
        "targets": m.explore.targets,
        "battery_steps": m.battery_steps,
        "slip": setup.slip,
        "localize": m.localize.enabled,
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
        setup.method,
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
    /// A picture could not be written.
    Output(String),
}

/// Runs a checked set-up and returns the report, writing one picture per decision into
/// `frames` and the final picture to `png` when given.
pub fn execute(
    setup: &Setup,
    frames: Option<&Path>,
    png: Option<&Path>,
) -> Result<RunReport, Failure> {
    let scale = picture_scale(&setup.world);
    let mut runner = Runner::new(setup.world.clone(), Dynamics::new(), setup.run.clone())
        .map_err(|e| Failure::Setup(e.to_string()))?;
    if let Some(dir) = frames {
        std::fs::create_dir_all(dir).map_err(|e| {
            Failure::Output(format!("--frames: {}: cannot create: {e}", dir.display()))
        })?;
    }
    let mut frame = 0usize;
    let mut frame_error: Option<String> = None;
    let report = runner
        .run_with(|r, progress| {
            let Some(dir) = frames else { return };
            if frame_error.is_some() || !matches!(progress, runner::Progress::Decided { .. }) {
                return;
            }
            frame += 1;
            let img = render::render_grid(&r.map().grid, &r.tracks(), scale);
            if let Err(e) = render::save_png(&img, &frame_path(dir, frame)) {
                frame_error = Some(format!("--frames: {e}"));
            }
        })
        .map_err(|e| Failure::Setup(e.to_string()))?;
    if let Some(e) = frame_error {
        return Err(Failure::Output(e));
    }
    if let Some(path) = png {
        let tracks: Vec<Track> = runner.tracks();
        let img = render::render_grid(&runner.map().grid, &tracks, scale);
        render::save_png(&img, path).map_err(|e| Failure::Output(format!("--png: {e}")))?;
    }
    Ok(report)
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    let setup = match Setup::from_args(&args) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("papillon-sim mission: {e}");
            return ExitCode::from(2);
        }
    };
    match execute(&setup, args.frames.as_deref(), args.png.as_deref()) {
        Ok(report) => {
            let text = if args.json {
                json_report(&setup, &report).to_string()
            } else {
                summary(&setup, &report)
            };
            // A closed standard output (`| head`) is not an error of the mission.
            let _ = writeln!(std::io::stdout(), "{text}");
            ExitCode::SUCCESS
        }
        Err(Failure::Setup(e)) => {
            eprintln!("papillon-sim mission: {e}");
            ExitCode::from(2)
        }
        Err(Failure::Output(e)) => {
            eprintln!("papillon-sim mission: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args() -> Args {
        Args {
            map: "lab".into(),
            robots: "1".into(),
            method: "xboa".into(),
            pop: "5".into(),
            gens: "30".into(),
            strategy: "short".into(),
            targets: None,
            seed: "25".into(),
            battery: None,
            start: None,
            resolution: "0.1".into(),
            slip: "thesis".into(),
            localize: "off".into(),
            json: false,
            png: None,
            frames: None,
        }
    }

    #[test]
    fn defaults_are_the_thesis_setup() {
        let s = Setup::from_args(&Args {
            map: "house".into(),
            ..args()
        })
        .unwrap();
        let m = &s.run.mission;
        assert_eq!(m.selector, SelectorKind::Optimized(Method::Xboa));
        assert_eq!(
            (
                m.explore.population,
                m.explore.max_generations,
                m.explore.targets
            ),
            (5, 30, 1)
        );
        assert_eq!((s.run.robots, s.run.seed), (1, 25));
        assert_eq!(s.world.start(), Pose2::new(1.0, 1.0, 0.0));
        assert_eq!(m.battery_steps, MissionConfig::default().battery_steps);
        assert_eq!(s.run.body.slip, SlipConfig::thesis());
    }

    #[test]
    fn bad_arguments_name_the_option_on_one_line() {
        let cases: Vec<(Args, &str)> = vec![
            (
                Args {
                    robots: "0".into(),
                    ..args()
                },
                "--robots:",
            ),
            (
                Args {
                    robots: "two".into(),
                    ..args()
                },
                "--robots:",
            ),
            (
                Args {
                    method: "xbox".into(),
                    ..args()
                },
                "--method:",
            ),
            (
                Args {
                    pop: "1".into(),
                    ..args()
                },
                "--pop:",
            ),
            (
                Args {
                    gens: "0".into(),
                    ..args()
                },
                "--gens:",
            ),
            (
                Args {
                    strategy: "medium".into(),
                    ..args()
                },
                "--strategy:",
            ),
            (
                Args {
                    targets: Some("3".into()),
                    ..args()
                },
                "--targets:",
            ),
            (
                Args {
                    strategy: "long".into(),
                    targets: Some("9".into()),
                    ..args()
                },
                "--targets:",
            ),
            (
                Args {
                    seed: "-1".into(),
                    ..args()
                },
                "--seed:",
            ),
            (
                Args {
                    slip: "lots".into(),
                    ..args()
                },
                "--slip:",
            ),
            (
                Args {
                    battery: Some("0".into()),
                    ..args()
                },
                "--battery:",
            ),
            (
                Args {
                    start: Some(vec!["0.1".into(), "0.1".into()]),
                    ..args()
                },
                "--start:",
            ),
            (
                Args {
                    start: Some(vec!["a".into(), "1".into()]),
                    ..args()
                },
                "--start:",
            ),
            (
                Args {
                    map: "nowhere".into(),
                    ..args()
                },
                "unknown world 'nowhere'",
            ),
            (
                Args {
                    map: "/no/such.map".into(),
                    ..args()
                },
                "/no/such.map: cannot read",
            ),
        ];
        for (a, want) in cases {
            let e = Setup::from_args(&a).unwrap_err();
            assert!(e.starts_with(want) && !e.contains('\n'), "{want}: {e}");
        }
        let long = Setup::from_args(&Args {
            strategy: "long".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(long.run.mission.explore.targets, 3);
        let nf = Setup::from_args(&Args {
            method: "nearest-frontier".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(nf.run.mission.selector, SelectorKind::NearestFrontier);
    }
}
