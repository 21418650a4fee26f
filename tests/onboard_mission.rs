//! `papillon run` end to end: the onboard binary explores the simulator's `lab` world through
//! `papillon-sim serve` (ARCOS over loopback TCP, LMS1xx over loopback TCP), and survives
//! signals, `kill -9`, link cuts, laser dropouts and byte corruption. Coverage is scored with
//! the simulator's truth (the lab's observable cells) against the map the program saved.
#![cfg(feature = "onboard")]

mod e2e;

use std::path::{Path, PathBuf};
use std::process::{Child, Output};
use std::time::{Duration, Instant};

use e2e::{
    Relay, Sim, papillon, read_truth, run_on_board, run_on_sim_board, signal, sim_board,
    sim_board_laser_noise, temp_dir, unix_now_s, wait_bounded,
};
use papillon::onboard::persist::{MapImage, MissionState, PGM_UNKNOWN, StateStore};
use papillon_sim::serve::MAP_RESOLUTION_M;
use papillon_sim::world::World;

/// Longest a whole lab mission may take.
const MISSION_LIMIT: Duration = Duration::from_secs(360);

fn board() -> String {
    sim_board()
}

/// `papillon run` on `boards/sim-thesis.json` against these endpoints, logging into `log`.
fn run(arcos: &str, laser: &str, log: &Path, resume: bool) -> Child {
    run_on_sim_board(arcos, laser, log, if resume { &["--resume"] } else { &[] })
}

fn assert_exit_0(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "stderr:\n{stderr}");
    assert!(
        stderr.contains("robot stopped, motors disabled, session closed"),
        "{stderr}"
    );
    stderr
}

fn saved(log: &Path) -> (MissionState, MapImage) {
    let (state, map) = StateStore::open(log).unwrap().load().unwrap().unwrap();
    (state, map.expect("a saved map"))
}

/// Coverage of `map` (the robot's map frame: the odometry frame, which starts at the world's
/// start pose) over the world's observable cells.
fn coverage(world: &World, map: &MapImage) -> f32 {
    let truth = world.truth();
    let start = world.start();
    let (s, c) = start.theta.sin_cos();
    let g = *world.geometry();
    let known = truth.known_cells_by(|i| {
        let p = g.cell_center(g.cell(i));
        let (dx, dy) = (p.x - start.x, p.y - start.y);
        let (x, y) = (c * dx + s * dy, -s * dx + c * dy);
        let col = ((x - map.origin_x_m) / map.resolution_m).floor();
        let row = ((y - map.origin_y_m) / map.resolution_m).floor();
        if col < 0.0 || row < 0.0 || col >= map.width as f32 || row >= map.height as f32 {
            return false;
        }
        let image_row = map.height - 1 - row as usize;
        map.pixels[image_row * map.width + col as usize] != PGM_UNKNOWN
    });
    known as f32 / truth.len() as f32
}

fn lab() -> World {
    World::load("lab", MAP_RESOLUTION_M).unwrap()
}

/// Known cells of a saved map, by index.
fn known_cells(map: &MapImage) -> Vec<usize> {
    (0..map.pixels.len())
        .filter(|&i| map.pixels[i] != PGM_UNKNOWN)
        .collect()
}

/// Waits until the mission has saved a state with at least `cells` known cells.
fn wait_for_progress(log: &Path, cells: usize, limit: Duration) {
    let deadline = Instant::now() + limit;
    loop {
        if let Ok(Some((_, Some(map)))) = StateStore::open(log).unwrap().load()
            && known_cells(&map).len() >= cells
        {
            return;
        }
        assert!(Instant::now() < deadline, "no progress saved in {log:?}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// The last `done` record of a telemetry log.
fn done_record(telemetry: &str) -> serde_json::Value {
    telemetry
        .lines()
        .rev()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|r| r["kind"] == "done")
        .expect("a done record in the telemetry")
}

fn only_the_log_in(dir: &Path, log: &Path) {
    let entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(entries, [log.to_path_buf()], "stray files next to the log");
}

#[test]
fn a_lab_mission_finishes_with_95_percent_coverage() {
    let sim = Sim::start("lab", None, &["--laser-noise", &sim_board_laser_noise()]);
    let dir = temp_dir("mission-lab");
    let log = dir.join("log");
    let began = Instant::now();
    let out = wait_bounded(
        run(&sim.arcos_tcp(), &sim.laser(), &log, false),
        MISSION_LIMIT,
    );
    let stderr = assert_exit_0(&out);
    let (state, map) = saved(&log);
    assert!(state.finished, "{state:?}");
    let c = coverage(&lab(), &map);
    eprintln!(
        "lab mission: coverage {:.1} % in {:.0} s wall, {:.0} s mission time, {} decisions, {:.1} m",
        c * 100.0,
        began.elapsed().as_secs_f64(),
        state.mission_time_s,
        state.counters.decisions,
        state.counters.distance_m
    );
    assert!(c >= 0.95, "coverage {c}");
    assert!(log.join("map.png").exists());
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    assert!(telemetry.contains("\"kind\":\"decision\""));
    assert!(telemetry.contains("\"compute_ms\""));
    // The telemetry says why the mission ended, and counts re-plans per decision; stderr
    // shows the progress.
    let done = done_record(&telemetry);
    assert!(
        ["NothingReachable", "NothingObservable", "BatteryExhausted"]
            .contains(&done["reason"].as_str().unwrap_or("")),
        "{done}"
    );
    assert!(done["replans_per_decision"].is_number(), "{done}");
    assert!(stderr.contains(" progress "), "{stderr}");
    assert!(stderr.contains("mission done"), "{stderr}");
    only_the_log_in(&dir, &log);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 24: a board describing a 100 m x 100 m storey at 0.1 m (a million cells: the
/// program sizes its grid to the board at start-up) with an optimizer population of 50 runs
/// against `serve` on a generated storey: it maps and decides, and on SIGTERM stops cleanly with
/// the whole storey's map saved.
#[test]
fn a_hundred_metre_storey_board_with_population_50_maps_and_decides() {
    let world = World::load("gen-floor-1", MAP_RESOLUTION_M).unwrap();
    let start = world.start();
    assert_eq!(start.theta, 0.0, "a generated plan starts heading east");
    let mut b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(board()).unwrap()).unwrap();
    // The map frame is the odometry's, from the start pose: the storey from -start.
    b["grid"]["width_m"] = 101.0.into();
    b["grid"]["height_m"] = 101.0.into();
    b["grid"]["origin_x_m"] = (-f64::from(start.x) - 0.5).into();
    b["grid"]["origin_y_m"] = (-f64::from(start.y) - 0.5).into();
    b["mission"]["population"] = 50.into();
    // Few generations keep the test short (297 s with the board's 30 on a debug build); the
    // population is what is checked.
    b["mission"]["generations"] = 5.into();
    let boards = temp_dir("floor-board");
    let board_path = boards.join("floor.json");
    std::fs::write(&board_path, b.to_string()).unwrap();

    let sim = Sim::start(
        "gen-floor-1",
        None,
        &["--laser-noise", &sim_board_laser_noise()],
    );
    let dir = temp_dir("mission-floor");
    let log = dir.join("log");
    let child = run_on_board(
        board_path.to_str().unwrap(),
        &sim.arcos_tcp(),
        &sim.laser(),
        &log,
        &[],
    );
    wait_for_progress(&log, 1500, Duration::from_secs(120));
    // At least two decisions (population 50) before the stop.
    let deadline = Instant::now() + Duration::from_secs(300);
    while saved(&log).0.counters.decisions < 2 {
        assert!(Instant::now() < deadline, "no two decisions saved");
        std::thread::sleep(Duration::from_millis(500));
    }
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(30));
    assert_exit_0(&out);
    let (state, map) = saved(&log);
    assert!(!state.finished);
    assert_eq!((map.width, map.height), (1010, 1010));
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    assert!(telemetry.contains("\"kind\":\"decision\""));
    only_the_log_in(&dir, &log);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&boards).unwrap();
}

#[test]
fn sigterm_saves_the_mission_and_resume_finishes_it_without_losing_the_map() {
    let sim = Sim::start("lab", None, &["--laser-noise", &sim_board_laser_noise()]);
    let dir = temp_dir("mission-sigterm");
    let log = dir.join("log");
    let child = run(&sim.arcos_tcp(), &sim.laser(), &log, false);
    wait_for_progress(&log, 1500, Duration::from_secs(60));
    std::thread::sleep(Duration::from_secs(3));
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(20));
    assert_exit_0(&out);
    let (state, map) = saved(&log);
    assert!(!state.finished);
    let before = known_cells(&map);
    assert!(before.len() >= 1500);
    let time_before_s = state.mission_time_s;
    assert!(time_before_s > 3.0, "{state:?}");

    let out = wait_bounded(
        run(&sim.arcos_tcp(), &sim.laser(), &log, true),
        MISSION_LIMIT,
    );
    let stderr = assert_exit_0(&out);
    assert!(stderr.contains("resuming saved mission"), "{stderr}");
    let (state, map) = saved(&log);
    assert!(state.finished, "{state:?}");
    // Mission time carries over the resume (it restarted at 0 before).
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    let first_resumed_s = telemetry
        .lines()
        .skip_while(|l| !l.contains("\"stopped by signal\""))
        .skip(1)
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find_map(|r| {
            (r["kind"] == "mission")
                .then(|| r["t_s"].as_f64())
                .flatten()
        })
        .expect("mission telemetry after the resume");
    assert!(
        first_resumed_s >= time_before_s,
        "resumed at {first_resumed_s} s, saved at {time_before_s} s"
    );
    assert!(state.mission_time_s > time_before_s, "{state:?}");
    let lost = before
        .iter()
        .filter(|&&i| map.pixels[i] == PGM_UNKNOWN)
        .count();
    assert_eq!(
        lost, 0,
        "cells known before the signal are unknown after the resume"
    );
    let c = coverage(&lab(), &map);
    assert!(c >= 0.95, "coverage {c}");
    only_the_log_in(&dir, &log);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn after_kill_9_the_saved_map_is_intact_and_resume_continues_from_it() {
    let sim = Sim::start("lab", None, &["--laser-noise", &sim_board_laser_noise()]);
    let dir = temp_dir("mission-kill9");
    let log = dir.join("log");
    let mut child = run(&sim.arcos_tcp(), &sim.laser(), &log, false);
    wait_for_progress(&log, 1500, Duration::from_secs(60));
    std::thread::sleep(Duration::from_millis(4500));
    child.kill().unwrap();
    child.wait().unwrap();
    // Whatever the moment of the kill, the files parse: each was replaced atomically.
    let (state, map) = saved(&log);
    assert!(!state.finished);
    let before = known_cells(&map);
    assert!(before.len() >= 1500);
    let time_before_s = state.mission_time_s;
    assert!(time_before_s > 3.0, "{state:?}");
    let saved_at = state.mission_time_s;

    let child = run(&sim.arcos_tcp(), &sim.laser(), &log, true);
    // Wait for the resumed mission's first periodic save, then stop it.
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let (s, _) = saved(&log);
        if s.mission_time_s != saved_at {
            break;
        }
        assert!(Instant::now() < deadline, "the resumed mission never saved");
        std::thread::sleep(Duration::from_millis(200));
    }
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(20));
    assert_exit_0(&out);
    let (_, map) = saved(&log);
    let lost = before
        .iter()
        .filter(|&&i| map.pixels[i] == PGM_UNKNOWN)
        .count();
    assert_eq!(lost, 0, "cells saved before the kill were lost");
    only_the_log_in(&dir, &log);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// 0.1 % of the robot's bytes corrupted for the whole mission, the laser silent for 3 s, and
/// the robot link cut for 3 s: the robot stops each time and the mission still finishes. The
/// robot's true velocity (the simulator's truth log) is zero from 0.5 s into the cut to its
/// end.
#[test]
fn a_mission_survives_corruption_a_laser_dropout_and_a_link_cut() {
    let dir = temp_dir("mission-faults");
    let truth_log = dir.join("truth.jsonl");
    let noise = sim_board_laser_noise();
    let sim = Sim::start(
        "lab",
        None,
        &[
            "--laser-noise",
            &noise,
            "--faults",
            "corrupt=0.001",
            "--truth-log",
            truth_log.to_str().unwrap(),
        ],
    );
    let arcos = Relay::start(&sim.arcos_tcp(), true);
    let laser = Relay::start(&sim.laser(), false);
    let log = dir.join("log");
    let began = Instant::now();
    let child = run(&arcos.addr, &laser.addr, &log, false);
    wait_for_progress(&log, 1500, Duration::from_secs(60));

    // Laser dropout once the robot is moving.
    let moving = |since: Instant| {
        arcos
            .statuses()
            .iter()
            .any(|&(t, l, r, _)| t >= since && (l != 0 || r != 0))
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    while !moving(Instant::now() - Duration::from_millis(300)) {
        assert!(Instant::now() < deadline, "the robot never moved");
        std::thread::sleep(Duration::from_millis(50));
    }
    let dropout = Instant::now();
    laser.mute(true);
    std::thread::sleep(Duration::from_secs(3));
    laser.mute(false);
    // Stopped (commanded within the 0.5 s stale timeout, then the board's deceleration) for
    // the rest of the dropout.
    let during: Vec<_> = arcos
        .statuses()
        .into_iter()
        .filter(|&(t, ..)| {
            t >= dropout + Duration::from_millis(2000) && t <= dropout + Duration::from_secs(3)
        })
        .collect();
    assert!(!during.is_empty());
    assert!(
        during.iter().all(|&(_, l, r, _)| l == 0 && r == 0),
        "moving during the laser dropout: {during:?}"
    );
    let deadline = Instant::now() + Duration::from_secs(60);
    while !moving(dropout + Duration::from_secs(3)) {
        assert!(
            Instant::now() < deadline,
            "the robot never moved after the dropout"
        );
        std::thread::sleep(Duration::from_millis(50));
    }

    // Link cut for 3 s, while the robot truly moves.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !read_truth(&truth_log)
        .last()
        .is_some_and(|t| t.moving() && unix_now_s() - t.unix_s < 0.1)
    {
        assert!(Instant::now() < deadline, "the robot never moved again");
        std::thread::sleep(Duration::from_millis(20));
    }
    let cut_unix_s = unix_now_s();
    let cut = Instant::now();
    arcos.cut();
    std::thread::sleep(Duration::from_secs(3));
    let truth = read_truth(&truth_log);
    arcos.restore();
    let before: Vec<_> = truth
        .iter()
        .filter(|t| (cut_unix_s - 0.1..cut_unix_s).contains(&t.unix_s))
        .collect();
    assert!(
        before.iter().any(|t| t.moving()),
        "not moving at the cut: {before:?}"
    );
    let stopped: Vec<_> = truth
        .iter()
        .filter(|t| (cut_unix_s + 0.5..=cut_unix_s + 3.0).contains(&t.unix_s))
        .collect();
    assert!(stopped.len() >= 50, "truth log too sparse: {stopped:?}");
    assert!(
        stopped.iter().all(|t| !t.moving()),
        "the robot truly moved from 0.5 s into the cut: {:?}",
        stopped.iter().find(|t| t.moving())
    );
    // The simulator stops the robot when its link drops; the first status packet of the new
    // session shows it standing.
    let deadline = Instant::now() + Duration::from_secs(30);
    let first = loop {
        if let Some(&s) = arcos.statuses().iter().find(|&&(t, ..)| t > cut) {
            break s;
        }
        assert!(Instant::now() < deadline, "no status packet after the cut");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(
        (first.1, first.2),
        (0, 0),
        "the robot moved through the cut"
    );

    let out = wait_bounded(child, MISSION_LIMIT.saturating_sub(began.elapsed()));
    assert_exit_0(&out);
    let (state, map) = saved(&log);
    assert!(state.finished, "{state:?}");
    // The mission finishes; the map is still most of the lab (the stops and the restart add
    // turns, and so odometry drift, to the map).
    let c = coverage(&lab(), &map);
    eprintln!("faults mission: coverage {:.1} %", c * 100.0);
    assert!(c >= 0.85, "coverage {c}");
    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    assert!(telemetry.contains("no laser scan within the stale timeout"));
    assert!(telemetry.contains("\"kind\":\"reconnect\""));
    assert!(state.counters.reconnects >= 1, "{:?}", state.counters);
    let bad: u64 = telemetry
        .lines()
        .filter(|l| l.contains("\"kind\":\"link\""))
        .filter_map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).ok()?;
            v["bad_checksums"].as_u64()
        })
        .max()
        .unwrap_or(0);
    assert!(bad > 0, "corruption reached the decoder");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A P3-DX with an LMS200 on a second serial line (both ptys here): `papillon run` on a board
/// naming an `lms200` gets its scans through the telegram session, maps and drives; SIGTERM
/// then stops it cleanly.
#[test]
fn an_lms200_on_a_second_serial_line_feeds_the_mission() {
    let dir = temp_dir("mission-lms200");
    let robot_link = dir.join("robot0");
    let laser_link = dir.join("lms200");
    let sim = Sim::start_lms200("lab", &robot_link, &laser_link, &[]);
    let mut board: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(board()).unwrap()).unwrap();
    board["link"]["port"] = robot_link.to_str().unwrap().into();
    board["laser"] = serde_json::json!({
        "model": "lms200",
        "port": laser_link.to_str().unwrap(),
        "baud": 38400,
        "beam_count": 181,
        "first_angle_deg": -90.0,
        "step_deg": 1.0,
        "max_range_m": 4.0,
        "min_range_m": 0.3,
        "noise_fraction": 0.05,
        "rate_hz": 10.0,
        "mount": { "x_m": 0.021, "y_m": 0.0, "theta_deg": 0.0 }
    });
    let board_file = dir.join("board-lms200.json");
    std::fs::write(&board_file, board.to_string()).unwrap();
    let log = dir.join("log");
    let child = papillon(
        &[
            "run",
            "--board",
            board_file.to_str().unwrap(),
            "--log-dir",
            log.to_str().unwrap(),
        ],
        &dir,
    );
    // Scans mapped and the robot driven: at least 1500 cells known and 0.5 m on odometry.
    let deadline = Instant::now() + Duration::from_secs(90);
    let state = loop {
        if let Ok(Some((state, Some(map)))) = StateStore::open(&log).unwrap().load()
            && known_cells(&map).len() >= 1500
            && state.counters.distance_m >= 0.5
        {
            break state;
        }
        assert!(
            Instant::now() < deadline,
            "no mapping and driving saved in {log:?}"
        );
        std::thread::sleep(Duration::from_millis(200));
    };
    assert!(state.counters.scans >= 20, "{:?}", state.counters);
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(20));
    assert_exit_0(&out);
    drop(sim);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 26: at 0.1 % byte corruption on the robot link the lab mission finishes (before,
/// two of three seeds looped on `PathBlocked` re-plans towards targets outside the lab until
/// the time limit). Two seeds at once here; the five-seed check is
/// `scripts/house-check.sh --map lab --faults corrupt=0.001 1 2 3 4 5`.
#[test]
fn lab_missions_finish_at_a_tenth_of_a_percent_corruption() {
    let runs: Vec<_> = [4u64, 5]
        .into_iter()
        .map(|seed| {
            std::thread::spawn(move || {
                let seed_text = seed.to_string();
                let noise = sim_board_laser_noise();
                let sim = Sim::start(
                    "lab",
                    None,
                    &["--laser-noise", &noise, "--faults", "corrupt=0.001", "--seed", &seed_text],
                );
                let dir = temp_dir(&format!("mission-corrupt-{seed}"));
                let mut board: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(board()).unwrap()).unwrap();
                board["mission"]["seed"] = serde_json::json!(seed);
                let board_path = dir.join("board.json");
                std::fs::write(&board_path, board.to_string()).unwrap();
                let log = dir.join("log");
                let child = run_on_board(board_path.to_str().unwrap(), &sim.arcos_tcp(), &sim.laser(), &log, &[]);
                let out = wait_bounded(child, MISSION_LIMIT);
                assert_exit_0(&out);
                let (state, map) = saved(&log);
                let c = coverage(&lab(), &map);
                let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
                let done = done_record(&telemetry);
                eprintln!(
                    "lab at 0.1 % corruption, seed {seed}: coverage {:.1} %, {:.0} s, {} decisions, end {done}",
                    c * 100.0,
                    state.mission_time_s,
                    state.counters.decisions
                );
                assert!(state.finished, "seed {seed}: {state:?}");
                assert!(c >= 0.95, "seed {seed}: coverage {c}");
                std::fs::remove_dir_all(&dir).unwrap();
            })
        })
        .collect();
    for r in runs {
        r.join().unwrap();
    }
}

/// The manual check of the user guide: the same mission on the 24 m x 24 m `house`. Run with
/// `cargo test -p papillon --test onboard_mission -- --ignored --nocapture house`; it prints the
/// coverage and the durations.
#[test]
#[ignore = "manual check: a house mission takes many minutes"]
fn house_mission_manual_check() {
    let dir = temp_dir("mission-house");
    let truth_log = dir.join("truth.jsonl");
    let noise = sim_board_laser_noise();
    let sim = Sim::start(
        "house",
        None,
        &[
            "--laser-noise",
            &noise,
            "--truth-log",
            truth_log.to_str().unwrap(),
        ],
    );
    let log = dir.join("log");
    // Another board (e.g. a larger battery) with PAPILLON_HOUSE_BOARD.
    let house_board = std::env::var("PAPILLON_HOUSE_BOARD").ok();
    let began = Instant::now();
    let limit: u64 = std::env::var("PAPILLON_HOUSE_LIMIT_S")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1800);
    let mut child = match &house_board {
        Some(b) => run_on_board(b, &sim.arcos_tcp(), &sim.laser(), &log, &[]),
        None => run(&sim.arcos_tcp(), &sim.laser(), &log, false),
    };
    // Past the limit the mission is stopped with SIGTERM and its saved map scored.
    while child.try_wait().unwrap().is_none() && began.elapsed().as_secs() < limit {
        std::thread::sleep(Duration::from_millis(500));
    }
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(30));
    assert_exit_0(&out);
    let (state, map) = saved(&log);
    let house = World::load("house", MAP_RESOLUTION_M).unwrap();
    eprintln!(
        "house mission: coverage {:.1} % in {:.0} s wall, {:.0} s mission time, {} decisions, {:.1} m, finished {}",
        coverage(&house, &map) * 100.0,
        began.elapsed().as_secs_f64(),
        state.mission_time_s,
        state.counters.decisions,
        state.counters.distance_m,
        state.finished
    );
    // Odometry drift: the final pose estimate against the truth, in the map frame (the
    // odometry frame anchored at the world's start pose).
    if let Some(t) = read_truth(&truth_log).last() {
        let start = house.start();
        let (s, c) = (f64::from(start.theta)).sin_cos();
        let (dx, dy) = (t.x_m - f64::from(start.x), t.y_m - f64::from(start.y));
        let (x, y) = (c * dx + s * dy, -s * dx + c * dy);
        let theta = t.theta_rad - f64::from(start.theta);
        let p = &state.pose;
        let heading_err = (f64::from(p.theta_rad) - theta + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        eprintln!(
            "house mission: final pose error {:.2} m, {:.1} deg",
            (f64::from(p.x_m) - x).hypot(f64::from(p.y_m) - y),
            heading_err.to_degrees()
        );
    }
}
