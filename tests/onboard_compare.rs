//! The runner's prediction against the binary: on the same world, seed and board, the fast
//! runner (`papillon_sim::runner`, in simulated time, with the board's mission configuration
//! and `papillon run`'s pump: no coverage from the truth, decisions that take the time the
//! binary's took) and `papillon run` against `papillon-sim serve` in real time. Both maps are
//! scored against the world's truth (`papillon_sim::score`, what `papillon-sim score` prints).
//!
//! A manual check (it takes as long as the missions, 15-20 minutes on the house; the seeds'
//! binary missions run at the same time, each against its own `serve`):
//!
//! ```text
//! PAPILLON_COMPARE_MAP=lab PAPILLON_COMPARE_SEEDS="1 2 3" \
//!   cargo test --release -p papillon --test onboard_compare -- --ignored --nocapture
//! ```
//!
//! The runner's prediction is the median over `PAPILLON_COMPARE_DRAWS` (default 9) draws of
//! its laser noise and wheel slip, each printed: one draw is one sample of what a mission
//! meets, and on one seed the draws spread as much as the binary's own runs do.
//!
//! `PAPILLON_COMPARE_DECISIONS=1` prints each runner draw's decisions;
//! `PAPILLON_COMPARE_STATES=1` prints the energy and time each side spent in each mission state;
//! `PAPILLON_COMPARE_KEEP=1` keeps (and names) each binary mission's log directory;
//! `PAPILLON_COMPARE_NEAR_POCKETS=1` turns `ExploreConfig::near_pockets_first` on in the runner
//! (with `PAPILLON_COMPARE_RUNNER_ONLY`: the binary keeps the board's setting, off);
//! `PAPILLON_COMPARE_LOOK_AROUND=1` turns `MissionConfig::look_around` on in the runner.
//!
//! The world both sides meet: `PAPILLON_COMPARE_BOARD=FILE` (default `boards/sim.json`; its
//! mission, its laser's `noise_fraction` and its `$.localize`, the matcher and the pose graph,
//! on both sides), `PAPILLON_COMPARE_SLIP=NAME` (`serve --slip`, the runner's body slip;
//! default `thesis`, the default of both) and `PAPILLON_COMPARE_LASER_NOISE_M=M` (`serve
//! --laser-noise-m`, the runner's `laser_range_sigma_m`; default 0). Issue 26's house check
//! with `boards/sim.json`'s LMS1xx (`laser.noise_fraction` 0.003 and serve's 12 mm), the
//! realistic odometry and the matcher with its graph, the runner alone:
//!
//! ```text
//! PAPILLON_COMPARE_SLIP=realistic \
//!   PAPILLON_COMPARE_LASER_NOISE_M=0.012 PAPILLON_COMPARE_MAP=house \
//!   PAPILLON_COMPARE_RUNNER_ONLY=0.006 PAPILLON_COMPARE_SEEDS="1 2 3 4 5" \
//!   cargo test --release -p papillon --test onboard_compare -- --ignored --nocapture
//! ```
//!
//! `PAPILLON_COMPARE_WORLD_GRID=1` gives the runner its own map (the world's extent) instead of
//! the board's grid. It prints one line per seed and pump, then checks the targets of issue 26: coverage within
//! 2 points and energy steps within 15 %.
#![cfg(feature = "onboard")]

mod e2e;

use std::path::Path;
use std::time::{Duration, Instant};

use e2e::{Sim, run_on_board, signal, temp_dir, wait_bounded};
use papillon::config::BoardConfig;
use papillon::geometry::Pose2;
use papillon::onboard::mission::mission_config;
use papillon::onboard::persist::StateStore;
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{PumpModel, RunConfig, Runner};
use papillon_sim::world::World;

/// Cell size of the runner's world and of the truth both maps are scored against (the
/// runner's and `papillon-sim score`'s default; the board's grid has the same).
const RESOLUTION_M: f32 = 0.1;

/// Draws of the world's noise the runner's prediction is the median of, unless
/// `PAPILLON_COMPARE_DRAWS` says otherwise.
const DEFAULT_DRAWS: u64 = 9;

/// One mission's result.
#[derive(Debug)]
struct Outcome {
    coverage: f32,
    time_s: f64,
    steps: f32,
    /// Distance driven by odometry \[m\]; the rest of the steps is turning.
    distance_m: f64,
    decisions: u64,
    replans_per_decision: f64,
    end: String,
    /// Mean decision time \[s\] (the binary's telemetry).
    decision_s: f64,
}

/// The board both sides run with (`PAPILLON_COMPARE_BOARD`, default `boards/sim.json`), its
/// mission seed set to `seed`: its mission, laser and `$.localize` (the matcher, the pose
/// graph) go to the binary as a board file and to the runner as its mission configuration.
fn board(seed: u64) -> (BoardConfig, String) {
    let path = std::env::var("PAPILLON_COMPARE_BOARD")
        .unwrap_or_else(|_| format!("{}/boards/sim.json", env!("CARGO_MANIFEST_DIR")));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("PAPILLON_COMPARE_BOARD: cannot read {path}: {e}"));
    let mut json: serde_json::Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("PAPILLON_COMPARE_BOARD: {path} is not JSON: {e}"));
    json["mission"]["seed"] = serde_json::json!(seed);
    let text = json.to_string();
    let board = BoardConfig::from_json(text.as_bytes())
        .unwrap_or_else(|e| panic!("PAPILLON_COMPARE_BOARD: {path}: {e}"));
    (board, text)
}

/// The simulated odometry error (`PAPILLON_COMPARE_SLIP`: `thesis`, the default of `serve`
/// and of the runner, `realistic`, `full` or `none`): `serve --slip` on the binary's side,
/// the runner's body slip on the other.
fn slip() -> String {
    let name = std::env::var("PAPILLON_COMPARE_SLIP").unwrap_or_else(|_| "thesis".into());
    assert!(
        SlipConfig::named(&name).is_some(),
        "PAPILLON_COMPARE_SLIP: {name} is not thesis, realistic, full or none"
    );
    name
}

/// The laser's range noise that does not grow with the range, 1 sigma \[m\]
/// (`PAPILLON_COMPARE_LASER_NOISE_M`, default 0; 0.012 for an LMS1xx): `serve
/// --laser-noise-m` on the binary's side, `RunConfig::laser_range_sigma_m` on the runner's.
/// The part growing with the range is the board's `laser.noise_fraction` on both.
fn laser_noise_m() -> f32 {
    match std::env::var("PAPILLON_COMPARE_LASER_NOISE_M") {
        Ok(v) => match v.parse::<f32>() {
            Ok(m) if m.is_finite() && (0.0..=0.5).contains(&m) => m,
            _ => panic!("PAPILLON_COMPARE_LASER_NOISE_M: {v} is not metres in 0..=0.5"),
        },
        Err(_) => 0.0,
    }
}

fn binary(map: &str, seed: u64, limit: Duration) -> Outcome {
    let dir = temp_dir(&format!("compare-{map}-{seed}"));
    let (_, text) = board(seed);
    let board_path = dir.join("board.json");
    std::fs::write(&board_path, text).unwrap();
    let seed_text = seed.to_string();
    // The laser the board describes (its range noise), as the runner simulates it.
    let noise = board(seed).0.laser.noise_fraction.to_string();
    let noise_m = laser_noise_m().to_string();
    let slip = slip();
    let sim = Sim::start(
        map,
        None,
        &[
            "--seed",
            &seed_text,
            "--laser-noise",
            &noise,
            "--laser-noise-m",
            &noise_m,
            "--slip",
            &slip,
        ],
    );
    let log = dir.join("log");
    let began = Instant::now();
    let mut child = run_on_board(
        board_path.to_str().unwrap(),
        &sim.arcos_tcp(),
        &sim.laser(),
        &log,
        &[],
    );
    let mut end = None;
    while child.try_wait().unwrap().is_none() {
        if began.elapsed() > limit {
            signal(&child, libc::SIGTERM);
            end = Some("limit".to_string());
            break;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    let out = wait_bounded(child, Duration::from_secs(30));
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    drop(sim);
    let (state, _) = StateStore::open(&log).unwrap().load().unwrap().unwrap();
    let map_file = papillon::mapfile::read_map(&log.join("map.yaml")).unwrap();
    let world = World::load(map, RESOLUTION_M).unwrap();
    let score = papillon_sim::score::score(&world, &map_file, Pose2::default());
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    let records: Vec<serde_json::Value> = telemetry
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    let compute: Vec<f64> = records
        .iter()
        .filter(|r| r["kind"] == "decision")
        .filter_map(|r| r["compute_ms"].as_f64())
        .collect();
    if std::env::var("PAPILLON_COMPARE_STATES").is_ok() {
        let battery = f64::from(board(seed).0.mission.battery_steps);
        let samples: Vec<(f64, String, f32)> = records
            .iter()
            .filter(|r| r["kind"] == "mission")
            .filter_map(|r| {
                let used = battery - r["battery_steps"].as_f64()?;
                Some((
                    r["t_s"].as_f64()?,
                    r["state"].as_str()?.to_string(),
                    used as f32,
                ))
            })
            .collect();
        eprintln!("    {map} seed {seed} binary {}", state_summary(&samples));
    }
    let done = records.iter().rev().find(|r| r["kind"] == "done");
    let last_mission = records.iter().rev().find(|r| r["kind"] == "mission");
    let replans_per_decision = done
        .or(last_mission)
        .and_then(|r| r["replans_per_decision"].as_f64())
        .unwrap_or(f64::NAN);
    let end = end.unwrap_or_else(|| {
        done.and_then(|r| r["reason"].as_str())
            .unwrap_or("?")
            .to_string()
    });
    // PAPILLON_COMPARE_KEEP=1: keep the binary's logs (board, telemetry, map) to trace it.
    if std::env::var("PAPILLON_COMPARE_KEEP").is_ok() {
        eprintln!("    {map} seed {seed} binary's logs in {}", dir.display());
    } else {
        let _ = std::fs::remove_dir_all(&dir);
    }
    Outcome {
        coverage: score.coverage,
        time_s: state.mission_time_s,
        steps: state.counters.energy_used_steps,
        distance_m: f64::from(state.counters.distance_m),
        decisions: state.counters.decisions,
        replans_per_decision,
        end,
        decision_s: compute.iter().sum::<f64>() / compute.len().max(1) as f64 / 1000.0,
    }
}

/// `world` on the board's grid: the binary maps a grid of the board's extent around its start
/// (the lab's 8 m inside `boards/sim.json`'s 26 m), and the selector draws its candidate
/// targets anywhere in it; the runner's map is its world's extent. So the runner gets the
/// world padded with solid cells out to the board's grid (placed at the world's start, the
/// binary's map frame): the padding is never observable (the outer walls hide it), the
/// robot's map holds the same Unknown beyond the walls as the binary's.
fn on_board_grid(world: &World, board: &BoardConfig) -> World {
    let start = world.start();
    let g = &board.grid;
    let geometry = papillon::grid::GridGeometry::from_extent(
        g.width_m,
        g.height_m,
        g.resolution_m,
        papillon::geometry::Point2::new(start.x + g.origin_x_m, start.y + g.origin_y_m),
    )
    .unwrap();
    assert!(
        start.theta.abs() < 1e-6,
        "a world whose start is not heading east"
    );
    let inner = world.geometry();
    let blocked = (0..geometry.cell_count())
        .map(|i| {
            let p = geometry.cell_center(geometry.cell(i));
            match inner.cell_at(p) {
                Some(c) if inner.index(c).is_some() => world.is_blocked(c),
                _ => true,
            }
        })
        .collect();
    World::from_blocked(world.name(), geometry, blocked)
        .unwrap()
        .with_start(start)
}

fn runner(map: &str, seed: u64, decision_s: f64, draw: u64) -> Outcome {
    let (board, _) = board(seed);
    let world = World::load(map, RESOLUTION_M).unwrap();
    let world = if std::env::var("PAPILLON_COMPARE_WORLD_GRID").is_ok() {
        world
    } else {
        on_board_grid(&world, &board)
    };
    let mut config = RunConfig::new(mission_config(&board).unwrap(), 1, seed);
    config.pump = PumpModel::onboard(decision_s);
    config.pump.noise_draw = draw;
    config.body.slip = SlipConfig::named(&slip()).unwrap();
    config.laser_range_sigma_m = laser_noise_m();
    // PAPILLON_COMPARE_NEAR_POCKETS=1: the runner with `ExploreConfig::near_pockets_first` on
    // (the binary keeps the board's, off): what the rule would change, runner only.
    if std::env::var("PAPILLON_COMPARE_NEAR_POCKETS").is_ok() {
        config.mission.explore.near_pockets_first = true;
    }
    // PAPILLON_COMPARE_LOOK_AROUND=1: the runner with `MissionConfig::look_around` on (the
    // binary keeps the default's).
    if std::env::var("PAPILLON_COMPARE_LOOK_AROUND").is_ok() {
        config.mission.look_around = true;
    }
    // PAPILLON_COMPARE_STATES=1: the energy and time spent in each mission state (sampled
    // every second, as the binary's `mission` telemetry records them), to see where one
    // pump spends what the other does not.
    let states = std::env::var("PAPILLON_COMPARE_STATES").is_ok();
    let mut samples: Vec<(f64, String, f32)> = Vec::new();
    let report = Runner::new(world, Dynamics::new(), config)
        .unwrap_or_else(|e| panic!("runner on {map}: {e}"))
        .run_with(|runner, progress| {
            if states && matches!(progress, papillon_sim::runner::Progress::Controlled) {
                let t = runner.sim_time_s();
                if samples.last().is_none_or(|s| t - s.0 >= 1.0) {
                    let m = runner.mission(0);
                    samples.push((t, format!("{:?}", m.state()), m.stats().steps));
                }
            }
        })
        .unwrap_or_else(|e| panic!("runner on {map}: {e}"));
    if states {
        eprintln!("    {}", state_summary(&samples));
    }
    let r = &report.robots[0];
    // PAPILLON_COMPARE_DECISIONS=1: each decision of each draw (time, targets, planned length,
    // predicted gain, energy), to see which trip one draw makes and another does not.
    if std::env::var("PAPILLON_COMPARE_DECISIONS").is_ok() {
        for e in &report.events {
            if let papillon::mission::MissionEvent::Decided {
                targets,
                path_length_m,
                predicted_gain_cells,
                energy_steps,
                ..
            } = &e.event
            {
                let t: Vec<String> = targets
                    .iter()
                    .map(|p| format!("({:.1}, {:.1})", p.x, p.y))
                    .collect();
                eprintln!(
                    "    {:6.1} s to {} planned {:.1} m, gain {} cells, {:.1} steps",
                    e.time_s,
                    t.join(" "),
                    path_length_m,
                    predicted_gain_cells,
                    energy_steps
                );
            }
        }
    }
    Outcome {
        coverage: report.coverage,
        time_s: report.sim_time_s,
        steps: r.steps,
        distance_m: r.distance_m,
        decisions: u64::from(r.decisions),
        replans_per_decision: f64::from(r.replans) / f64::from(r.decisions.max(1)),
        end: format!("{:?}", report.reason),
        decision_s,
    }
}

/// Energy and time by mission state from (time, state, energy used) samples: each interval
/// counts for the state at its start.
fn state_summary(samples: &[(f64, String, f32)]) -> String {
    let mut by: Vec<(String, f32, f64)> = Vec::new();
    for w in samples.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let name = a.1.split('(').next().unwrap_or("").to_string();
        let i = match by.iter().position(|e| e.0 == name) {
            Some(i) => i,
            None => {
                by.push((name, 0.0, 0.0));
                by.len() - 1
            }
        };
        by[i].1 += b.2 - a.2;
        by[i].2 += b.0 - a.0;
    }
    by.iter()
        .map(|(n, e, t)| format!("{n} {e:.1} steps in {t:.0} s"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Draws of the world's noise the prediction is the median of (`PAPILLON_COMPARE_DRAWS`).
fn draws() -> u64 {
    std::env::var("PAPILLON_COMPARE_DRAWS")
        .ok()
        .map(|v| v.parse().expect("PAPILLON_COMPARE_DRAWS: a number"))
        .unwrap_or(DEFAULT_DRAWS)
        .max(1)
}

/// The runner's prediction: the median, coverage and steps each, over `draws` draws of the
/// laser noise and wheel slip (`PumpModel::noise_draw`), each draw printed. One draw is one
/// sample of what a mission meets: the binary, on its simulator's draw, spreads from run to
/// run as much as the draws do (docs/user-guide.md, section 7).
fn prediction(map: &str, seed: u64, decision_s: f64, draws: u64) -> Outcome {
    let mut runs: Vec<Outcome> = (0..draws)
        .map(|draw| {
            let o = runner(map, seed, decision_s, draw);
            if draws > 1 {
                print(map, seed, &format!("draw {draw}"), &o);
            }
            o
        })
        .collect();
    if runs.len() == 1 {
        return runs.remove(0);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        }
    };
    let coverage = median(runs.iter().map(|o| f64::from(o.coverage)).collect()) as f32;
    let steps = median(runs.iter().map(|o| f64::from(o.steps)).collect()) as f32;
    let time_s = median(runs.iter().map(|o| o.time_s).collect());
    let distance_m = median(runs.iter().map(|o| o.distance_m).collect());
    let decisions = median(runs.iter().map(|o| o.decisions as f64).collect()).round() as u64;
    let replans_per_decision = median(runs.iter().map(|o| o.replans_per_decision).collect());
    let mut ends: Vec<&str> = runs.iter().map(|o| o.end.as_str()).collect();
    ends.sort_unstable();
    ends.dedup();
    Outcome {
        coverage,
        time_s,
        steps,
        distance_m,
        decisions,
        replans_per_decision,
        end: ends.join("/"),
        decision_s,
    }
}

fn print(map: &str, seed: u64, pump: &str, o: &Outcome) {
    eprintln!(
        "{map:6} seed {seed:3} {pump:8} coverage {:6.2} % time {:6.0} s steps {:6.1} ({:5.1} m) decisions {:4} replans/decision {:4.2} decision {:5.3} s end {}",
        o.coverage * 100.0,
        o.time_s,
        o.steps,
        o.distance_m,
        o.decisions,
        o.replans_per_decision,
        o.decision_s,
        o.end
    );
}

/// The runner's onboard pump ends a mission on the binary's `NothingObservable` values.
#[test]
fn the_runner_ends_as_the_binary_does() {
    use papillon::onboard::mission as onboard;
    use papillon_sim::runner;
    assert_eq!(runner::STALL_DECISIONS, onboard::STALL_DECISIONS);
    assert_eq!(runner::STALL_IDLE_DECISIONS, onboard::STALL_IDLE_DECISIONS);
    assert_eq!(runner::STALL_NEW_CELLS, onboard::STALL_NEW_CELLS);
    assert_eq!(runner::STALL_STEPS, onboard::STALL_STEPS);
}

#[test]
#[ignore = "manual check: real-time missions (see the module documentation)"]
fn runner_predicts_the_binary() {
    let map = std::env::var("PAPILLON_COMPARE_MAP").unwrap_or_else(|_| "lab".into());
    let seeds: Vec<u64> = std::env::var("PAPILLON_COMPARE_SEEDS")
        .unwrap_or_else(|_| "1 2 3".into())
        .split_whitespace()
        .map(|s| s.parse().expect("PAPILLON_COMPARE_SEEDS: numbers"))
        .collect();
    let limit = Duration::from_secs(
        std::env::var("PAPILLON_COMPARE_LIMIT_S")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1800),
    );
    assert!(Path::new(e2e::PAPILLON).exists());
    let mut misses = Vec::new();
    // PAPILLON_COMPARE_RUNNER_ONLY=SECONDS: only the runner's prediction, decisions taking
    // that long (the binary's mean `compute_ms`).
    if let Ok(d) = std::env::var("PAPILLON_COMPARE_RUNNER_ONLY") {
        let decision_s: f64 = d.parse().expect("PAPILLON_COMPARE_RUNNER_ONLY: seconds");
        for &seed in &seeds {
            print(
                &map,
                seed,
                "runner",
                &prediction(&map, seed, decision_s, draws()),
            );
        }
        return;
    }
    // The binary's missions run at once, one `serve` each (they mostly wait on real time).
    let binaries: Vec<Outcome> = std::thread::scope(|scope| {
        let runs: Vec<_> = seeds
            .iter()
            .map(|&seed| {
                let map = &map;
                scope.spawn(move || binary(map, seed, limit))
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    for (&seed, b) in seeds.iter().zip(binaries) {
        print(&map, seed, "binary", &b);
        let r = prediction(&map, seed, b.decision_s, draws());
        print(&map, seed, "runner", &r);
        let dc = (b.coverage - r.coverage).abs() * 100.0;
        let ds = (b.steps - r.steps).abs() / r.steps.max(1.0);
        if dc > 2.0 || ds > 0.15 {
            misses.push(format!(
                "seed {seed}: coverage differs by {dc:.2} points, steps by {:.1} %",
                ds * 100.0
            ));
        }
    }
    assert!(misses.is_empty(), "{misses:#?}");
}
