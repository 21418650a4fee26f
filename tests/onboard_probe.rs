//! `papillon probe` against `papillon-sim serve`, over loopback TCP and a real pty.
#![cfg(feature = "onboard")]

mod e2e;

use std::time::Duration;

use e2e::{Sim, papillon, temp_dir, wait_bounded};

const LIMIT: Duration = Duration::from_secs(20);

fn stdout_of(out: &std::process::Output) -> String {
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert_eq!(
        out.status.code(),
        Some(0),
        "stdout:\n{text}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

fn assert_identity_and_status(text: &str) {
    assert!(
        text.contains(r#"robot: name "papillon-sim", class "Pioneer", subclass "p3dx-sh""#),
        "{text}"
    );
    assert!(text.contains("watchdog 2000 ms"), "{text}");
    assert!(text.contains("status: battery "), "{text}");
    assert!(
        text.contains(" V, pose x ") && text.contains(" deg (counters x "),
        "{text}"
    );
    assert!(
        text.contains("disconnected: motors disabled, session closed"),
        "{text}"
    );
}

#[test]
fn probe_over_tcp_prints_identity_config_battery_and_pose() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("probe-tcp");
    let out = wait_bounded(papillon(&["probe", "--tcp", &sim.arcos_tcp()], &dir), LIMIT);
    let text = stdout_of(&out);
    assert_identity_and_status(&text);
    assert!(text.contains("link: tcp 127.0.0.1:"), "{text}");
    // Nothing is written where the probe runs.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn probe_over_a_pty_prints_identity_config_battery_and_pose() {
    let dir = temp_dir("probe-pty");
    let link = dir.join("robot0");
    let sim = Sim::start("lab", Some(&link), &[]);
    let out = wait_bounded(
        papillon(&["probe", "--port", link.to_str().unwrap()], &dir),
        LIMIT,
    );
    let text = stdout_of(&out);
    assert_identity_and_status(&text);
    assert!(text.contains(" @ 9600 baud"), "{text}");
    drop(sim);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Parses `x <mm> mm, y <mm> mm, heading <deg> deg` after `prefix` on a line.
fn pose_after(line: &str, prefix: &str) -> (f32, f32, f32) {
    let rest = &line[line.find(prefix).unwrap() + prefix.len()..];
    let nums: Vec<f32> = rest
        .split(|c: char| !(c.is_ascii_digit() || c == '-' || c == '.'))
        .filter_map(|t| t.parse().ok())
        .collect();
    (nums[0], nums[1], nums[2])
}

#[test]
fn probe_drive_runs_a_square_and_reports_the_odometry() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("probe-drive");
    let out = wait_bounded(
        papillon(&["probe", "--tcp", &sim.arcos_tcp(), "--drive"], &dir),
        Duration::from_secs(60),
    );
    let text = stdout_of(&out);
    assert_identity_and_status(&text);
    let sides: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("square side"))
        .collect();
    assert_eq!(sides.len(), 4, "{text}");
    // 0.5 m sides, 90° turns (counter-clockwise): the corners of a square.
    let corners = [
        (500.0, 0.0, 90.0),
        (500.0, 500.0, 180.0),
        (0.0, 500.0, -90.0),
        (0.0, 0.0, 0.0),
    ];
    for (line, (cx, cy, ch)) in sides.iter().zip(corners) {
        let (x, y, h) = pose_after(line, "odometry ");
        assert!((x - cx).abs() < 80.0 && (y - cy).abs() < 80.0, "{line}");
        let dh = (h - ch + 540.0).rem_euclid(360.0) - 180.0;
        assert!(dh.abs() < 15.0, "{line}");
    }
    let summary = text
        .lines()
        .find(|l| l.starts_with("square: driven"))
        .unwrap();
    let driven: f32 = summary.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((driven - 2.0).abs() < 0.2, "{summary}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The corners (x mm, y mm, heading deg) and the distance driven \[m\] a `probe --drive`
/// printed.
fn square_of(text: &str) -> (Vec<(f32, f32, f32)>, f32) {
    let corners: Vec<_> = text
        .lines()
        .filter(|l| l.starts_with("square side"))
        .map(|l| pose_after(l, "odometry "))
        .collect();
    assert_eq!(corners.len(), 4, "{text}");
    let summary = text
        .lines()
        .find(|l| l.starts_with("square: driven"))
        .unwrap_or_else(|| panic!("no summary: {text}"));
    let driven: f32 = summary.split_whitespace().nth(2).unwrap().parse().unwrap();
    (corners, driven)
}

#[test]
fn probe_drive_reports_the_same_square_on_a_p3dx_and_a_p3dx_sh() {
    // A `p3dx` counts positions in 0.485 mm units, a `p3dx-sh` in mm: the same square must
    // come out of both.
    let sh = Sim::start("lab", None, &["--subclass", "p3dx-sh"]);
    let old = Sim::start("lab", None, &["--subclass", "p3dx"]);
    let dir_sh = temp_dir("probe-drive-sh");
    let dir_old = temp_dir("probe-drive-p3dx");
    let run_sh = papillon(&["probe", "--tcp", &sh.arcos_tcp(), "--drive"], &dir_sh);
    let run_old = papillon(&["probe", "--tcp", &old.arcos_tcp(), "--drive"], &dir_old);
    let text_sh = stdout_of(&wait_bounded(run_sh, Duration::from_secs(60)));
    let text_old = stdout_of(&wait_bounded(run_old, Duration::from_secs(60)));
    assert!(text_sh.contains(r#"subclass "p3dx-sh""#), "{text_sh}");
    assert!(text_old.contains(r#"subclass "p3dx""#), "{text_old}");
    let (corners_sh, driven_sh) = square_of(&text_sh);
    let (corners_old, driven_old) = square_of(&text_old);
    // 2 m driven on both (the unconverted p3dx read 4.1 m), within 5 % of each other.
    assert!((driven_sh - 2.0).abs() < 0.2, "{text_sh}");
    assert!(
        (driven_old - driven_sh).abs() <= 0.05 * driven_sh,
        "p3dx {driven_old} m, p3dx-sh {driven_sh} m\n{text_old}"
    );
    // Every corner within 5 % of the perimeter (100 mm) of the other run's.
    for (a, b) in corners_old.iter().zip(&corners_sh) {
        let apart_mm = (a.0 - b.0).hypot(a.1 - b.1);
        assert!(
            apart_mm <= 0.05 * 2000.0,
            "p3dx corner {a:?}, p3dx-sh corner {b:?}\n{text_old}\n{text_sh}"
        );
    }
    std::fs::remove_dir_all(&dir_sh).unwrap();
    std::fs::remove_dir_all(&dir_old).unwrap();
}

/// First contact at an unknown speed: the emulated microcontroller answers only at 38400 baud
/// (`serve --baud`, read from the pty's line settings as the client set them); `probe`,
/// starting at 9600, finds it, and checks the laser with one scan.
#[test]
fn probe_finds_a_robot_at_38400_baud_and_checks_the_laser() {
    let dir = temp_dir("probe-baud");
    let link = dir.join("robot0");
    let sim = Sim::start("lab", Some(&link), &["--baud", "38400"]);
    let out = wait_bounded(
        papillon(
            &[
                "probe",
                "--port",
                link.to_str().unwrap(),
                "--laser",
                &sim.laser(),
            ],
            &dir,
        ),
        Duration::from_secs(40),
    );
    let text = stdout_of(&out);
    assert_identity_and_status(&text);
    assert!(text.contains("baud: no answer at 9600 baud"), "{text}");
    assert!(text.contains("baud: no answer at 19200 baud"), "{text}");
    assert!(
        text.contains("baud: the robot answers at 38400 baud"),
        "{text}"
    );
    assert!(text.contains(" @ 38400 baud"), "{text}");
    assert!(!text.contains("57600"), "{text}");
    // One scan of the LMS1xx the board describes (541 beams), with returns from the lab's
    // walls.
    let laser = text
        .lines()
        .find(|l| l.starts_with("laser: lms1xx at "))
        .unwrap_or_else(|| panic!("no laser line in {text}"));
    assert!(
        laser.contains("one scan of 541 beams (as the board's 541)"),
        "{laser}"
    );
    assert!(
        laser.contains(" m to ") && !laser.contains(" 0 returns"),
        "{laser}"
    );

    // Forced to the wrong speed, the probe fails and names the flag to check.
    let out = wait_bounded(
        papillon(
            &["probe", "--port", link.to_str().unwrap(), "--baud", "9600"],
            &dir,
        ),
        Duration::from_secs(40),
    );
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--port"), "{stderr}");
    drop(sim);
    std::fs::remove_dir_all(&dir).unwrap();
}
