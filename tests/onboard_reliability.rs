//! Reliability of `papillon` end to end (issue 20): start-up over a corrupting link, saved
//! missions that are never overwritten by accident, bounded reads, permanent port errors and
//! files that refuse planted symlinks. Each test failed before its fix.
#![cfg(feature = "onboard")]

mod e2e;

use std::path::Path;
use std::process::{Child, Output};
use std::time::{Duration, Instant};

use e2e::{Sim, papillon, run_on_sim_board, signal, sim_board, temp_dir, wait_bounded};
use papillon::onboard::persist::StateStore;

fn board() -> String {
    sim_board()
}

/// `papillon run` on `boards/sim.json` against these endpoints, logging into `log`, plus
/// `extra` flags.
fn run(arcos: &str, laser: &str, log: &Path, extra: &[&str]) -> Child {
    run_on_sim_board(arcos, laser, log, extra)
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Waits until the mission in `log` has saved a state (its first periodic save).
fn wait_for_a_save(log: &Path, limit: Duration) {
    let deadline = Instant::now() + limit;
    loop {
        if let Ok(Some(_)) = StateStore::open(log).unwrap().load() {
            return;
        }
        assert!(Instant::now() < deadline, "nothing saved in {log:?}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Item 1: at 1 % of the robot's bytes corrupted, a CONFIG packet (about 130 bytes) arrives
/// whole only about one time in three, and a SYNC reply may be lost: `probe` connects on every
/// seed all the same (it failed on 5 of 5 before the CONFIG request and the handshake were
/// retried).
#[test]
fn probe_connects_at_1_percent_corruption_on_5_seeds() {
    for seed in 1..=5 {
        let sim = Sim::start(
            "lab",
            None,
            &["--faults", "corrupt=0.01", "--seed", &seed.to_string()],
        );
        let dir = temp_dir(&format!("probe-corrupt-{seed}"));
        let out = wait_bounded(
            papillon(&["probe", "--tcp", &sim.arcos_tcp()], &dir),
            Duration::from_secs(60),
        );
        let (stdout, stderr) = text(&out);
        assert_eq!(
            out.status.code(),
            Some(0),
            "seed {seed}\nstdout:\n{stdout}\nstderr:\n{stderr}"
        );
        assert!(stdout.contains("config: firmware"), "seed {seed}: {stdout}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// Item 1: `run` connects at 0.2 % corruption (seed 2 lost its CONFIG packet and exited 1
/// after 1 s before the fix) and at 1 %, starts the mission, and stops on SIGTERM.
#[test]
fn run_connects_at_0_2_and_1_percent_corruption() {
    for (rate, seed) in [("0.002", "2"), ("0.01", "1")] {
        let spec = format!("corrupt={rate}");
        let sim = Sim::start("lab", None, &["--faults", &spec, "--seed", seed]);
        let dir = temp_dir(&format!("run-corrupt-{rate}"));
        let log = dir.join("log");
        let mut child = run(&sim.arcos_tcp(), &sim.laser(), &log, &[]);
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            if let Ok(Some(status)) = child.try_wait() {
                let out = wait_bounded(child, Duration::from_secs(1));
                panic!(
                    "corrupt={rate}: run exited early ({status}): {}",
                    text(&out).1
                );
            }
            if let Ok(Some(_)) = StateStore::open(&log).unwrap().load() {
                break;
            }
            assert!(Instant::now() < deadline, "corrupt={rate}: nothing saved");
            std::thread::sleep(Duration::from_millis(200));
        }
        signal(&child, libc::SIGTERM);
        let out = wait_bounded(child, Duration::from_secs(20));
        let (_, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(0), "corrupt={rate}: {stderr}");
        assert!(stderr.contains("connected"), "{stderr}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// A saved, unfinished mission in `log`, as `kill -9` leaves it: a state and a map.
fn plant_unfinished_mission(log: &Path) -> (Vec<u8>, Vec<u8>) {
    use papillon::onboard::persist::{MapImage, MissionState, STATE_VERSION};
    let store = StateStore::open(log).unwrap();
    let state = MissionState {
        version: STATE_VERSION,
        mission_time_s: 42.0,
        coverage: 0.4,
        finished: false,
        ..MissionState::default()
    };
    let map = MapImage {
        width: 4,
        height: 2,
        resolution_m: 0.1,
        origin_x_m: 0.0,
        origin_y_m: 0.0,
        pixels: vec![0, 254, 254, 205, 205, 254, 0, 0],
    };
    store.save(&state, Some(&map)).unwrap();
    std::fs::write(
        log.join("telemetry.jsonl"),
        "{\"t_s\":1.0,\"kind\":\"pose\"}\n",
    )
    .unwrap();
    (
        std::fs::read(log.join("state.json")).unwrap(),
        std::fs::read(log.join("map.pgm")).unwrap(),
    )
}

/// Item 2: `run` without `--resume` on a log directory holding an unfinished mission is
/// refused at once and the saved files are left as they were (before the fix it started a
/// new mission and overwrote them); `--resume` and `--fresh` together are refused; `--fresh`
/// moves the old files aside into `previous-1/` and starts anew.
#[test]
fn an_unfinished_saved_mission_is_never_overwritten_without_fresh() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("unfinished");
    let log = dir.join("log");
    let (state, map) = plant_unfinished_mission(&log);

    let out = wait_bounded(
        run(&sim.arcos_tcp(), &sim.laser(), &log, &[]),
        Duration::from_secs(20),
    );
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("unfinished mission")
            && stderr.contains("--resume")
            && stderr.contains("--fresh")
            && stderr.contains(log.to_str().unwrap()),
        "{stderr}"
    );
    assert_eq!(std::fs::read(log.join("state.json")).unwrap(), state);
    assert_eq!(std::fs::read(log.join("map.pgm")).unwrap(), map);

    let out = wait_bounded(
        run(
            &sim.arcos_tcp(),
            &sim.laser(),
            &log,
            &["--resume", "--fresh"],
        ),
        Duration::from_secs(20),
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out).1);
    assert!(text(&out).1.contains("--fresh"), "{}", text(&out).1);

    let child = run(&sim.arcos_tcp(), &sim.laser(), &log, &["--fresh"]);
    // The planted state is moved aside first, then the new mission saves its own.
    let deadline = Instant::now() + Duration::from_secs(60);
    while !log.join("previous-1").join("state.json").exists() {
        assert!(Instant::now() < deadline, "nothing moved aside");
        std::thread::sleep(Duration::from_millis(100));
    }
    wait_for_a_save(&log, Duration::from_secs(60));
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(20));
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("previous-1"), "{stderr}");
    let aside = log.join("previous-1");
    assert_eq!(std::fs::read(aside.join("state.json")).unwrap(), state);
    assert_eq!(std::fs::read(aside.join("map.pgm")).unwrap(), map);
    assert!(aside.join("map.yaml").exists());
    assert!(aside.join("telemetry.jsonl").exists());
    assert_ne!(std::fs::read(log.join("state.json")).unwrap(), state);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 7: a serial port that does not exist (ENOENT) or is not a serial port (`/dev/null`,
/// ENOTTY; a plain file) fails at once with one line naming the port and the flag (before:
/// retried like a lost link for 31 s).
#[test]
fn a_port_that_does_not_exist_or_is_no_serial_port_fails_at_once() {
    let dir = temp_dir("badport");
    let log = dir.join("log");
    let plain = dir.join("plain-file");
    std::fs::write(&plain, b"").unwrap();
    let board = board();
    for (port, what) in [
        ("/dev/nonexistent", "no such device"),
        ("/dev/null", "not a serial port"),
        (plain.to_str().unwrap(), "not a serial port"),
    ] {
        let began = Instant::now();
        let args = [
            "run",
            "--board",
            &board,
            "--port",
            port,
            "--log-dir",
            log.to_str().unwrap(),
        ];
        let out = wait_bounded(papillon(&args, &dir), Duration::from_secs(10));
        let (_, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(1), "{port}: {stderr}");
        assert!(
            began.elapsed() < Duration::from_secs(3),
            "{port}: {:?}",
            began.elapsed()
        );
        let last = stderr.lines().last().unwrap_or("");
        assert!(
            last.contains(port) && last.contains(what) && last.contains("--port"),
            "{port}: {stderr}"
        );
        assert!(!stderr.contains("retrying"), "{port}: {stderr}");
        let out = wait_bounded(
            papillon(&["probe", "--port", port], &dir),
            Duration::from_secs(10),
        );
        let (_, stderr) = text(&out);
        assert_eq!(out.status.code(), Some(1), "{port}: {stderr}");
        assert!(stderr.contains(port) && stderr.contains(what), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 8: a symbolic link planted as `telemetry.jsonl` is refused before anything is written
/// through it (before: the telemetry was appended to whatever it pointed to).
#[test]
fn a_symlink_planted_as_the_telemetry_log_is_refused() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("telemetry-link");
    let log = dir.join("log");
    std::fs::create_dir_all(&log).unwrap();
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    std::os::unix::fs::symlink(&victim, log.join("telemetry.jsonl")).unwrap();
    let out = wait_bounded(
        run(&sim.arcos_tcp(), &sim.laser(), &log, &[]),
        Duration::from_secs(20),
    );
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("telemetry.jsonl") && stderr.contains("symbolic link"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 8: a symbolic link planted where the running program writes its temporary state
/// file (`.state.json.tmp.<pid>`) is not followed: the saves go on, and what it points to is
/// left alone (before: the save truncated and overwrote it).
#[test]
fn a_symlink_planted_as_the_temporary_state_file_is_not_followed() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("state-link");
    let log = dir.join("log");
    std::fs::create_dir_all(&log).unwrap();
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    let child = run(&sim.arcos_tcp(), &sim.laser(), &log, &[]);
    // Planted as soon as the pid is known, well before the first save (after connecting).
    for name in ["state.json", "map.pgm", "map.yaml"] {
        let tmp = log.join(format!(".{name}.tmp.{}", child.id()));
        std::os::unix::fs::symlink(&victim, &tmp).unwrap();
    }
    wait_for_a_save(&log, Duration::from_secs(60));
    std::thread::sleep(Duration::from_secs(2));
    signal(&child, libc::SIGTERM);
    let out = wait_bounded(child, Duration::from_secs(20));
    let (_, stderr) = text(&out);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    assert!(StateStore::open(&log).unwrap().load().unwrap().is_some());
    std::fs::remove_dir_all(&dir).unwrap();
}
