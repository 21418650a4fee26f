//! Issue 18's hardware-in-the-loop check: `papillon run` with scan matching on (`--localize
//! on`) against `papillon-sim serve --map lab --slip realistic` (per-robot wheel-diameter and
//! wheelbase errors, random walks, fast-turn slip and the end-of-move slide,
//! `sim-host/src/odometry_error.rs`) and the lab robot's laser, an LMS1xx: the board copy
//! describes it as `boards/p3dx-lms1xx.json` does (`noise_fraction` 0.003) and `serve`
//! simulates that plus the datasheet's 12 mm statistical error (`--laser-noise-m 0.012`). The
//! saved map is scored against the lab's truth with `papillon-sim score`'s measures (the
//! map's frame is the odometry frame anchored at the world's start pose) and the final pose
//! against `serve`'s truth log: map accuracy ≥ 97 %, coverage ≥ 95 %, final position error
//! ≤ 10 cm.
//!
//! Measured 2026-11-27 (branch `hil18`, release build, docs/experiments.md): seeds 1, 2, 3
//! pass (map accuracy 98.28 / 98.28 / 98.25 %, final position error 0.035 / 0.018 / 0.030 m,
//! coverage 100 %). With the thesis's simulated laser of `boards/sim-thesis.json`
//! (`PAPILLON_LOCALIZE_LASER_NOISE=0.05 PAPILLON_LOCALIZE_LASER_NOISE_M=0`) it fails (seed 1:
//! 87.77 %, 0.257 m). Ignored in `cargo test`'s default run: a lab mission takes two to three
//! minutes of real time, and the binary must match every scan in real time, which a debug
//! build on a busy machine does not. Run it in release (`PAPILLON_LOCALIZE_SEED=S` for another
//! seed of `serve` and the board, default 1):
//!
//! ```text
//! cargo test --release -p papillon --test onboard_localize -- --ignored --nocapture
//! ```
#![cfg(feature = "onboard")]

mod e2e;

use std::time::{Duration, Instant};

use e2e::{Sim, read_truth, run_on_board, sim_board, temp_dir, wait_bounded};
use papillon::geometry::Pose2;
use papillon::onboard::persist::StateStore;
use papillon_sim::world::World;

/// Longest the lab mission may take.
const MISSION_LIMIT: Duration = Duration::from_secs(420);

/// The cell size the map is scored at (`papillon-sim score`'s default) \[m\].
const SCORE_RESOLUTION_M: f32 = 0.1;

/// `(position error [m], heading error [rad])` of `pose` (robot map frame) against the
/// truth log's last sample, the log's first sample being the start pose (the map frame's
/// origin).
fn pose_error(first: &e2e::Truth, last: &e2e::Truth, pose: Pose2) -> (f64, f64) {
    let (s, c) = first.theta_rad.sin_cos();
    let (dx, dy) = (last.x_m - first.x_m, last.y_m - first.y_m);
    let (x, y) = (c * dx + s * dy, -s * dx + c * dy);
    let theta = last.theta_rad - first.theta_rad;
    let heading = (f64::from(pose.theta) - theta + std::f64::consts::PI)
        .rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    (
        (f64::from(pose.x) - x).hypot(f64::from(pose.y) - y),
        heading,
    )
}

/// A SICK LMS1xx's typical statistical range error, 1 σ \[m\] (SICK support, "Measurement
/// Errors LMSxxx": 12 mm typical, 20 mm maximum, whatever the range; a systematic error of
/// ±30 mm typical comes on top and is not simulated).
const LMS1XX_RANGE_SIGMA_M: f64 = 0.012;

/// A fraction or a length from the environment variable `name`, within `range`, else
/// `default`.
fn env_number(name: &str, range: std::ops::Range<f64>, default: f64) -> f64 {
    match std::env::var(name) {
        Ok(v) => {
            let n: f64 = v.trim().parse().unwrap_or(f64::NAN);
            assert!(
                range.contains(&n),
                "{name}={v:?}: expected a number in {range:?}"
            );
            n
        }
        Err(_) => default,
    }
}

/// The lab robot's laser: `(noise_fraction, range_sigma_m)`. The board's description of its
/// range noise, a fraction of the range, which `serve` also simulates; and the part of
/// `serve`'s noise that does not grow with the range (`serve --laser-noise-m`). By default
/// the real robot's, an LMS1xx: `boards/p3dx-lms1xx.json`'s `noise_fraction` and the
/// datasheet's 12 mm. `PAPILLON_LOCALIZE_LASER_NOISE=F` and `PAPILLON_LOCALIZE_LASER_NOISE_M=S`
/// set them (`=0.05` and `=0`: the thesis's simulated laser of `boards/sim-thesis.json`).
fn hil_laser() -> (f64, f64) {
    let lms1xx: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(format!(
            "{}/boards/p3dx-lms1xx.json",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap(),
    )
    .unwrap();
    let board_fraction = lms1xx["laser"]["noise_fraction"].as_f64().unwrap();
    (
        env_number("PAPILLON_LOCALIZE_LASER_NOISE", 0.0..1.0, board_fraction),
        env_number(
            "PAPILLON_LOCALIZE_LASER_NOISE_M",
            0.0..0.5,
            LMS1XX_RANGE_SIGMA_M,
        ),
    )
}

#[test]
#[ignore = "issue 18's acceptance: a lab mission in real time, in a release build"]
fn a_lab_mission_with_realistic_odometry_and_scan_matching_keeps_its_map_true() {
    let seed: u64 = std::env::var("PAPILLON_LOCALIZE_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let dir = temp_dir("localize-lab");
    let truth_log = dir.join("truth.jsonl");
    let mut board: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sim_board()).unwrap()).unwrap();
    board["mission"]["seed"] = serde_json::json!(seed);
    // The laser's range noise, the same on both sides: the board's description and what
    // `serve` simulates.
    let (noise_fraction, range_sigma_m) = hil_laser();
    board["laser"]["noise_fraction"] = serde_json::json!(noise_fraction);
    let board_path = dir.join("board.json");
    std::fs::write(&board_path, board.to_string()).unwrap();
    let seed_text = seed.to_string();
    let sim = Sim::start(
        "lab",
        None,
        &[
            "--laser-noise",
            &noise_fraction.to_string(),
            "--laser-noise-m",
            &range_sigma_m.to_string(),
            "--slip",
            "realistic",
            "--truth-log",
            truth_log.to_str().unwrap(),
            "--seed",
            &seed_text,
        ],
    );
    let log = dir.join("log");
    let began = Instant::now();
    let out = wait_bounded(
        run_on_board(
            board_path.to_str().unwrap(),
            &sim.arcos_tcp(),
            &sim.laser(),
            &log,
            &["--localize", "on"],
        ),
        MISSION_LIMIT,
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "stderr:\n{stderr}");
    drop(sim);
    let (state, _) = StateStore::open(&log).unwrap().load().unwrap().unwrap();
    assert!(state.finished, "{state:?}");

    let world = World::load("lab", SCORE_RESOLUTION_M).unwrap();
    let map = papillon::mapfile::read_map(&log.join("map.yaml")).unwrap();
    let score = papillon_sim::score::score(&world, &map, Pose2::default());

    let truth = read_truth(&truth_log);
    let (first, last) = (truth.first().unwrap(), truth.last().unwrap());
    let p = |r: papillon::onboard::persist::PoseRecord| Pose2::new(r.x_m, r.y_m, r.theta_rad);
    let (pos_m, head_rad) = pose_error(first, last, p(state.pose));
    // The odometry alone, for the record (its frame is the map frame of a fresh mission).
    let (odom_pos_m, odom_head_rad) = pose_error(first, last, p(state.odom_pose));
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    let last_mission = telemetry
        .lines()
        .rev()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|r| r["kind"] == "mission")
        .expect("a mission record");
    eprintln!(
        "lab, realistic slip, matcher on, laser noise {noise_fraction} of the range and {range_sigma_m} m, seed {seed}: coverage {:.2} %, map accuracy {:.2} % (wall error {:.3} m), \
         final pose error {:.3} m / {:.2} deg (odometry alone {:.3} m / {:.2} deg), {} of {} matches trusted, \
         {:.0} s wall, {:.0} s mission, {} decisions",
        100.0 * score.coverage,
        100.0 * score.accuracy,
        score.wall_error_m,
        pos_m,
        head_rad.to_degrees(),
        odom_pos_m,
        odom_head_rad.to_degrees(),
        last_mission["matches_trusted"],
        last_mission["matches"],
        began.elapsed().as_secs_f64(),
        state.mission_time_s,
        state.counters.decisions,
    );
    // The matcher ran, and its counts are in the telemetry.
    assert_eq!(last_mission["localize"], true, "{last_mission}");
    assert!(
        last_mission["matches_trusted"].as_u64().unwrap_or(0) > 0,
        "{last_mission}"
    );
    assert!(score.coverage >= 0.95, "coverage {score:?}");
    assert!(score.accuracy >= 0.97, "map accuracy {score:?}");
    assert!(pos_m <= 0.10, "final position error {pos_m} m");
    std::fs::remove_dir_all(&dir).unwrap();
}
