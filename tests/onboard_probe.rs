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
