//! `papillon-sim mission`: a whole exploration mission in simulated time
//! ([`crate::mission_run`]), with a human summary, `--json`, `--png` and `--frames`.
//!
//! The options become a [`ScenarioSpec`] ([`crate::scenario`]); bad arguments, bad map files
//! and a start inside an obstacle exit with status 2 and one line on standard error.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use papillon::geometry::Pose2;

use crate::mission_run::{Failure, execute_recorded, json_report, summary};
use crate::scenario::{
    ScenarioSpec, Setup, Slip, Strategy, objective_from_name, preset_from_name, selector_from_name,
};

/// Arguments of `papillon-sim mission`: the options with a fixed set of values are checked by
/// clap (their values listed in `--help`, a near miss answered with clap's suggestion); the
/// others are kept as text and checked by [`setup_from_args`], so every problem is reported on
/// one line naming the option.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// World: house, empty, factory, lab, or a map file (.csv, .png, .pgm, .map, .yaml).
    #[arg(long, default_value = "house")]
    pub map: String,
    /// Number of robots sharing the map (1 to 100).
    #[arg(long, default_value = "1", allow_negative_numbers = true)]
    pub robots: String,
    /// Target selector: an optimizer on the objective, or a frontier rule.
    #[arg(long, default_value = "xboa", value_parser = [
        "xboa", "boa", "mboa", "aboa", "saboa", "ga", "pso", "gwo", "abc", "cmaes",
        "nearest-frontier", "frontier-utility",
    ])]
    pub method: String,
    /// What the optimizers maximise: efficient (reachable frontier viewpoints, gain
    /// discounted by energy; the default) or thesis (the thesis's objective, for reproduction).
    #[arg(long, default_value = "efficient", value_parser = ["efficient", "thesis"])]
    pub objective: String,
    /// The optimizer's parameter set: standard (the literature's defaults: Deb's GA, Clerc and
    /// Kennedy's PSO, GWO's paper schedule, GABC; Papillon's default) or thesis (the thesis's
    /// Table 4.1 for GA and PSO, GWO's earlier schedule, Karaboga's ABC, for reproduction).
    /// The other methods are the same in both; see docs/optimizers.md.
    #[arg(long, default_value = papillon::explore::DEFAULT_PRESET.name(), value_parser = ["thesis", "standard"])]
    pub preset: String,
    /// Population of the optimizer.
    #[arg(long, default_value = "5", allow_negative_numbers = true)]
    pub pop: String,
    /// Generations of the optimizer.
    #[arg(long, default_value = "30", allow_negative_numbers = true)]
    pub gens: String,
    /// Strategy: short (one target per decision) or long (several, see --targets).
    #[arg(long, default_value = "short", value_parser = ["short", "long"])]
    pub strategy: String,
    /// Targets per decision, k (short: 1; long: default 3, at most 8).
    #[arg(long, allow_negative_numbers = true)]
    pub targets: Option<String>,
    /// Seed of every random choice (slip, laser noise, decisions).
    #[arg(long, default_value = "25", allow_negative_numbers = true)]
    pub seed: String,
    /// Energy at the start [steps: 1 m of travel or 45° of rotation] (default: the core
    /// mission's, 500).
    #[arg(long, allow_negative_numbers = true)]
    pub battery: Option<String>,
    /// Start pose in the map frame: X Y, optionally THETA (m, m, rad; default 1 m east and 1 m north of
    /// the map's south-west corner, heading east).
    #[arg(long, num_args = 1.., allow_negative_numbers = true, value_names = ["X", "Y", "THETA"])]
    pub start: Option<Vec<String>>,
    /// Odometry slip of the simulated robots: thesis (a 1.5 cm slide at the end of each move,
    /// what the thesis saw), full (also heading and distance random walks, see
    /// docs/simulator.md), realistic (also per-robot wheel-diameter and wheelbase errors and
    /// fast-turn slip, see sim-host/src/odometry_error.rs) or none.
    #[arg(long, default_value = "thesis", value_parser = ["thesis", "full", "realistic", "none"])]
    pub slip: String,
    /// Scan-to-map matching before each scan is integrated: on or off.
    #[arg(long, default_value = "off", value_parser = ["on", "off"])]
    pub localize: String,
    /// Keyframes in a pose graph with loop closures behind the scan matcher
    /// (`src/localize/graph.rs`): on or off; on needs --localize on. Boards:
    /// $.localize.pose_graph.
    #[arg(long, default_value = "off", value_parser = ["on", "off"])]
    pub pose_graph: String,
    /// The scan matcher's online estimate of the odometry's systematic errors (turn gain,
    /// curvature; `src/localize/odometry_calibration.rs`): on or off; only with --localize
    /// on. Boards: $.localize.self_calibration.
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub self_calibration: String,
    /// Range noise of the simulated laser, as a fraction of the range (standard deviation of
    /// Gaussian noise): default the thesis's 0.05; a SICK LMS1xx is nearer 0.003 (about 12 mm
    /// at 4 m), 0 for noise-free ranges.
    #[arg(long, allow_negative_numbers = true)]
    pub laser_noise: Option<String>,
    /// Range noise of the simulated laser that does not grow with the range, standard
    /// deviation in metres, added in quadrature to --laser-noise's (the simulator only: the
    /// mission's sensor model still knows only the fraction): 0.012 for a SICK LMS1xx's
    /// typical statistical error (SICK: 12 mm, 1 σ); default 0.
    #[arg(long, allow_negative_numbers = true)]
    pub laser_noise_m: Option<String>,
    /// Room the planner keeps between the robot's side and a wall on a planned path, each side,
    /// in metres (0 to 0.3): cells nearer a wall than half the body's width plus this (plus
    /// half a cell) are blocked. A board's `$.planning.clearance_m`.
    #[arg(long, default_value = "0.05", allow_negative_numbers = true)]
    pub clearance: String,
    /// Probability above which a map cell counts as an obstacle, from 0.5 up to below 0.97;
    /// cells with less evidence of an obstacle are Free. 0.5 (the default) is the thesis's
    /// rule, any net evidence; 0.65 (ROS `map_server`'s `occupied_thresh`) suits a laser as
    /// noisy as the thesis's 5 %. A board's `$.mapping.occupied_thresh`.
    #[arg(long, default_value = "0.5", allow_negative_numbers = true)]
    pub occupied_thresh: String,
    /// Cell size in metres (the map file's own for .yaml).
    #[arg(long, default_value = "0.1", allow_negative_numbers = true)]
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
    /// Record the mission as MCAP with Foxglove's schemas (map, scans, poses, path, targets,
    /// decisions; see docs/simulator.md).
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// Serve the mission live to Foxglove on this address (host:port, e.g. 127.0.0.1:8765):
    /// Foxglove → Open connection → Foxglove WebSocket → ws://HOST:PORT. The run is then paced
    /// to --live-speed. Off by default.
    #[arg(long, value_name = "HOST:PORT")]
    pub live: Option<String>,
    /// With --live: simulated seconds per wall-clock second (more than 0, at most 1000).
    #[arg(long, default_value = "1", requires = "live", value_parser = live_speed)]
    pub live_speed: f64,
    /// When a robot's mission ends, drive it back to its start position first (the core's
    /// return to start, as `papillon run --return-to-start`).
    #[arg(long)]
    pub return_to_start: bool,
    /// Which scans go into the map: off (every scan, the thesis; the default), on (the motion
    /// filter with its standard thresholds: a scan is mapped once the robot moved 0.2 m or
    /// turned 10° since the last mapped scan, or after 2 s), or TRAVEL_M,TURN_DEG,INTERVAL_S.
    /// Boards: $.mapping.
    #[arg(long, value_name = "off|on|TRAVEL_M,TURN_DEG,INTERVAL_S", value_parser = motion_filter)]
    pub motion_filter: Option<papillon::mission::MotionFilterConfig>,
    /// End the run after this many simulated seconds (reason `time-limit`), e.g. to sample
    /// a mission on a big map; default 600 s plus 10 s per step of battery.
    #[arg(long, value_name = "SECONDS", value_parser = max_time)]
    pub max_time: Option<f64>,
}

/// `--motion-filter`: off, on, or three thresholds.
fn motion_filter(text: &str) -> Result<papillon::mission::MotionFilterConfig, String> {
    use papillon::mission::MotionFilterConfig;
    match text.trim() {
        "off" => return Ok(MotionFilterConfig::off()),
        "on" => return Ok(MotionFilterConfig::standard()),
        _ => {}
    }
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected off, on or TRAVEL_M,TURN_DEG,INTERVAL_S, got '{text}'"))?;
    let [travel_m, turn_deg, interval_s] = parts[..] else {
        return Err(format!(
            "expected off, on or three numbers TRAVEL_M,TURN_DEG,INTERVAL_S, got '{text}'"
        ));
    };
    let config =
        MotionFilterConfig::on(travel_m, papillon::units::deg_to_rad(turn_deg), interval_s);
    match config.invalid_field() {
        Some((field, value)) => Err(format!(
            "{field} must be finite and not negative, got {value}"
        )),
        None => Ok(config),
    }
}

/// `--max-time`: a positive number of simulated seconds.
fn max_time(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!(
            "expected a positive number of simulated seconds, got '{text}'"
        )),
    }
}

/// `--live-speed`: a number above 0 and at most 1000.
fn live_speed(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x <= 1000.0 => Ok(x),
        _ => Err(format!(
            "expected simulated seconds per second, above 0 and at most 1000, got '{text}'"
        )),
    }
}

fn number<T: std::str::FromStr>(option: &str, text: &str, what: &str) -> Result<T, String> {
    text.trim()
        .parse()
        .map_err(|_| format!("{option}: expected {what}, got '{text}'"))
}

/// A switch's value: `on` or `off` (clap has checked it; a caller building `Args` by hand
/// gets the error naming `flag`).
fn on_off(flag: &str, value: &str) -> Result<bool, String> {
    match value {
        "on" => Ok(true),
        "off" => Ok(false),
        other => Err(format!("{flag}: expected on or off, got '{other}'")),
    }
}

/// The scenario the options describe; the error is one line naming the option.
pub fn spec_from_args(args: &Args) -> Result<ScenarioSpec, String> {
    let robots = number("--robots", &args.robots, "a whole number of robots")?;
    let selector = selector_from_name(&args.method)?;
    let objective = objective_from_name(&args.objective)?;
    let preset = preset_from_name(&args.preset)?;
    let population = number("--pop", &args.pop, "a whole number")?;
    let generations = number("--gens", &args.gens, "a whole number")?;
    let strategy = Strategy::from_name(&args.strategy)?;
    let targets = match &args.targets {
        Some(t) => Some(number("--targets", t, "a whole number")?),
        None => None,
    };
    let seed = number("--seed", &args.seed, "a whole number")?;
    let battery_steps = match &args.battery {
        Some(b) => Some(number("--battery", b, "a number of steps")?),
        None => None,
    };
    let resolution_m = number("--resolution", &args.resolution, "a cell size in metres")?;
    let clearance_m = number("--clearance", &args.clearance, "a distance in metres")?;
    let occupied_thresh = number("--occupied-thresh", &args.occupied_thresh, "a probability")?;
    let start = match &args.start {
        Some(v) => {
            if !(2..=3).contains(&v.len()) {
                return Err(format!(
                    "--start: expected X Y [THETA], got {} values",
                    v.len()
                ));
            }
            let nums = v
                .iter()
                .map(|t| number::<f32>("--start", t, "X Y [THETA] as numbers"))
                .collect::<Result<Vec<f32>, String>>()?;
            Some(Pose2::new(
                nums[0],
                nums[1],
                nums.get(2).copied().unwrap_or(0.0),
            ))
        }
        None => None,
    };
    let slip = Slip::from_name(&args.slip)?;
    let laser_noise = match &args.laser_noise {
        Some(t) => Some(super::noise_fraction(t).map_err(|e| format!("--laser-noise: {e}"))?),
        None => None,
    };
    let laser_noise_m = match &args.laser_noise_m {
        Some(t) => Some(super::range_sigma_m(t).map_err(|e| format!("--laser-noise-m: {e}"))?),
        None => None,
    };
    let localize = on_off("--localize", &args.localize)?;
    // `--pose-graph on` without `--localize on` is refused by `Setup::new`.
    let pose_graph = on_off("--pose-graph", &args.pose_graph)?;
    let self_calibration = on_off("--self-calibration", &args.self_calibration)?;
    Ok(ScenarioSpec {
        map: args.map.clone(),
        resolution_m,
        robots,
        selector,
        objective,
        population,
        generations,
        strategy,
        targets,
        seed,
        battery_steps,
        start,
        slip,
        localize,
        pose_graph,
        self_calibration,
        laser_noise,
        laser_noise_m,
        preset,
        tuning: None,
        clearance_m,
        occupied_thresh,
    })
}

/// The checked set-up the options describe ([`Setup::new`]).
pub fn setup_from_args(args: &Args) -> Result<Setup, String> {
    Setup::new(&spec_from_args(args)?)
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    let setup = match setup_from_args(&args) {
        Ok(mut s) => {
            s.run.mission.return_to_start = args.return_to_start;
            if let Some(filter) = args.motion_filter {
                s.run.mission.motion_filter = filter;
            }
            if let Some(limit_s) = args.max_time {
                s.run.max_sim_time_s = limit_s;
            }
            s
        }
        Err(e) => {
            eprintln!("papillon-sim mission: {e}");
            return ExitCode::from(2);
        }
    };
    match execute_recorded(
        &setup,
        args.frames.as_deref(),
        args.png.as_deref(),
        args.mcap.as_deref(),
        args.live
            .as_ref()
            .map(|addr| crate::record::LiveOptions {
                addr: addr.clone(),
                speed: args.live_speed,
            })
            .as_ref(),
    ) {
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
    use crate::physics::SlipConfig;
    use papillon::mission::{MissionConfig, SelectorKind};
    use papillon::optim::Method;

    fn args() -> Args {
        Args {
            map: "lab".into(),
            robots: "1".into(),
            method: "xboa".into(),
            objective: "efficient".into(),
            preset: papillon::explore::DEFAULT_PRESET.name().into(),
            pop: "5".into(),
            gens: "30".into(),
            strategy: "short".into(),
            targets: None,
            seed: "25".into(),
            battery: None,
            start: None,
            resolution: "0.1".into(),
            clearance: "0.05".into(),
            occupied_thresh: "0.5".into(),
            slip: "thesis".into(),
            localize: "off".into(),
            pose_graph: "off".into(),
            self_calibration: "on".into(),
            laser_noise: None,
            laser_noise_m: None,
            json: false,
            png: None,
            frames: None,
            mcap: None,
            live: None,
            live_speed: 1.0,
            return_to_start: false,
            motion_filter: None,
            max_time: None,
        }
    }

    #[test]
    fn defaults_are_the_thesis_setup() {
        let s = setup_from_args(&Args {
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
        assert_eq!(m.laser.noise_fraction, 0.05);
        assert!(!m.localize.enabled && !m.localize.graph.enabled);
        let graph = setup_from_args(&Args {
            localize: "on".into(),
            pose_graph: "on".into(),
            ..args()
        })
        .unwrap();
        assert!(graph.run.mission.localize.enabled && graph.run.mission.localize.graph.enabled);
        let matcher = setup_from_args(&Args {
            localize: "on".into(),
            ..args()
        })
        .unwrap();
        assert!(!matcher.run.mission.localize.graph.enabled);
        assert!(matcher.run.mission.localize.calibration.enabled);
        let uncalibrated = setup_from_args(&Args {
            localize: "on".into(),
            self_calibration: "off".into(),
            ..args()
        })
        .unwrap();
        assert!(!uncalibrated.run.mission.localize.calibration.enabled);
        let sick = setup_from_args(&Args {
            laser_noise: Some("0.003".into()),
            ..args()
        })
        .unwrap();
        assert_eq!(sick.run.mission.laser.noise_fraction, 0.003);
        assert_eq!(m.laser.noise_fraction, 0.05);
        assert_eq!(s.run.laser_range_sigma_m, 0.0);
        let sick_m = setup_from_args(&Args {
            laser_noise_m: Some("0.012".into()),
            ..args()
        })
        .unwrap();
        // The simulator's laser only: the mission's sensor model keeps its fraction.
        assert_eq!(sick_m.run.laser_range_sigma_m, 0.012);
        assert_eq!(sick_m.run.mission.laser.noise_fraction, 0.05);
        assert_eq!(
            m.explore.objective,
            papillon::explore::ObjectiveKind::Efficient
        );
        let thesis = setup_from_args(&Args {
            objective: "thesis".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(
            thesis.run.mission.explore.objective,
            papillon::explore::ObjectiveKind::Thesis
        );
        assert_eq!(m.explore.preset, papillon::explore::DEFAULT_PRESET);
        // The planning layer: the body with 5 cm a side by default, `--clearance` else.
        let layer = |clearance_m: f32| {
            papillon::mission::footprint::planning_layer(
                &m.safety,
                clearance_m,
                0.1,
                m.traversability.unknown_policy,
            )
        };
        assert_eq!(m.traversability, layer(0.05));
        let roomy = setup_from_args(&Args {
            clearance: "0.12".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(roomy.run.mission.traversability, layer(0.12));
        // The thesis's rule by default (any net evidence of an obstacle); 0.65 on request.
        assert_eq!(m.grid_bounds.occupied_above, 0.0);
        let noisy = setup_from_args(&Args {
            occupied_thresh: "0.65".into(),
            ..args()
        })
        .unwrap();
        let b = noisy.run.mission.grid_bounds;
        assert!((b.occupied_thresh() - 0.65).abs() < 1e-6);
        for preset in papillon::optim::Preset::ALL {
            let s = setup_from_args(&Args {
                preset: preset.name().into(),
                ..args()
            })
            .unwrap();
            assert_eq!(s.run.mission.explore.preset, preset);
        }
    }

    #[test]
    fn the_json_report_records_the_settings_as_given() {
        let s = setup_from_args(&Args {
            clearance: "0.08".into(),
            laser_noise: Some("0.003".into()),
            laser_noise_m: Some("0.012".into()),
            resolution: "0.05".into(),
            ..args()
        })
        .unwrap();
        let json = json_report(&s, &crate::runner::RunReport::default());
        assert_eq!(json["clearance_m"], 0.08);
        assert_eq!(json["occupied_thresh"], 0.5);
        assert_eq!(json["laser_noise"], 0.003);
        assert_eq!(json["laser_noise_m"], 0.012);
        assert_eq!(json["resolution_m"], 0.05);
        let defaults = json_report(&setup_from_args(&args()).unwrap(), &Default::default());
        assert_eq!(defaults["clearance_m"], 0.05);
        assert_eq!(defaults["laser_noise"], 0.05);
        assert_eq!(defaults["laser_noise_m"], 0.0);
        assert_eq!(defaults["resolution_m"], 0.1);
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
                    objective: "thesys".into(),
                    ..args()
                },
                "--objective:",
            ),
            (
                Args {
                    preset: "pygmo".into(),
                    ..args()
                },
                "--preset:",
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
                    clearance: "-0.05".into(),
                    ..args()
                },
                "--clearance:",
            ),
            (
                Args {
                    clearance: "wide".into(),
                    ..args()
                },
                "--clearance:",
            ),
            (
                Args {
                    occupied_thresh: "0.4".into(),
                    ..args()
                },
                "--occupied-thresh:",
            ),
            (
                Args {
                    occupied_thresh: "0.99".into(),
                    ..args()
                },
                "--occupied-thresh:",
            ),
            (
                Args {
                    occupied_thresh: "most".into(),
                    ..args()
                },
                "--occupied-thresh:",
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
                    laser_noise: Some("1.5".into()),
                    ..args()
                },
                "--laser-noise:",
            ),
            (
                Args {
                    laser_noise: Some("NaN".into()),
                    ..args()
                },
                "--laser-noise:",
            ),
            (
                Args {
                    laser_noise_m: Some("-0.01".into()),
                    ..args()
                },
                "--laser-noise-m:",
            ),
            (
                Args {
                    laser_noise_m: Some("0.6".into()),
                    ..args()
                },
                "--laser-noise-m:",
            ),
            (
                Args {
                    laser_noise_m: Some("inf".into()),
                    ..args()
                },
                "--laser-noise-m:",
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
                    pose_graph: "on".into(),
                    ..args()
                },
                "--pose-graph:",
            ),
            (
                Args {
                    self_calibration: "maybe".into(),
                    ..args()
                },
                "--self-calibration: expected on or off, got 'maybe'",
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
            let e = setup_from_args(&a).unwrap_err();
            assert!(e.starts_with(want) && !e.contains('\n'), "{want}: {e}");
        }
        let long = setup_from_args(&Args {
            strategy: "long".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(long.run.mission.explore.targets, 3);
        let nf = setup_from_args(&Args {
            method: "nearest-frontier".into(),
            ..args()
        })
        .unwrap();
        assert_eq!(nf.run.mission.selector, SelectorKind::NearestFrontier);
    }
}
