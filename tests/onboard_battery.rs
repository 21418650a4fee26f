//! `papillon run` end to end on a draining battery: `papillon-sim serve --faults drain=V`
//! makes the emulated battery fall; the mission ends when the voltage the robot reports stays
//! under the board's threshold (`$.mission.low_voltage_v`, 11.5 V by default, held 5 s), and
//! with `--return-to-start` the robot first drives back to where it started. The robot's
//! true pose comes from serve's `--truth-log`.
#![cfg(feature = "onboard")]

mod e2e;

use std::time::Duration;

use e2e::{Sim, read_truth, run_on_sim_board, temp_dir, wait_bounded};

/// The battery falls from 13.0 V at this rate \[V/min\]: under 11.5 V after about 30 s.
const DRAIN_V_PER_MIN: f64 = 3.0;
/// The board's threshold and hold (the defaults: `boards/sim-thesis.json` names neither).
const LOW_V: f64 = 11.5;
const HOLD_S: f64 = 5.0;

fn records(telemetry: &str, kind: &str) -> Vec<serde_json::Value> {
    telemetry
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|r| r["kind"] == kind)
        .collect()
}

#[test]
fn a_draining_battery_ends_the_mission_at_the_threshold_and_the_robot_returns_to_its_start() {
    let dir = temp_dir("battery-return");
    let truth_log = dir.join("truth.jsonl");
    let drain = format!("drain={DRAIN_V_PER_MIN}");
    let sim = Sim::start(
        "lab",
        None,
        &[
            "--faults",
            &drain,
            "--truth-log",
            truth_log.to_str().unwrap(),
        ],
    );
    let log = dir.join("log");
    let out = wait_bounded(
        run_on_sim_board(&sim.arcos_tcp(), &sim.laser(), &log, &["--return-to-start"]),
        Duration::from_secs(300),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "stderr:\n{stderr}");
    drop(sim);

    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    // The voltage stopped the mission: at the threshold (within the hold time and the SIP's
    // 0.1 V resolution), not before.
    let low = records(&telemetry, "battery_low");
    assert_eq!(low.len(), 1, "{telemetry}");
    let v = low[0]["battery_v"].as_f64().unwrap();
    let lowest = LOW_V - DRAIN_V_PER_MIN * HOLD_S / 60.0 - 0.15;
    assert!(v < LOW_V && v >= lowest, "battery_low at {v} V: {}", low[0]);
    let t_low = low[0]["t_s"].as_f64().unwrap();
    let t_expected = (13.0 - LOW_V) / DRAIN_V_PER_MIN * 60.0 + HOLD_S;
    assert!(
        (t_low - t_expected).abs() < 10.0,
        "battery_low at {t_low} s, expected about {t_expected} s"
    );
    let returning = records(&telemetry, "returning");
    assert_eq!(returning.len(), 1, "{telemetry}");
    assert_eq!(returning[0]["reason"], "VoltageLow");
    let done = records(&telemetry, "done");
    assert_eq!(done.len(), 1, "{telemetry}");
    assert_eq!(done[0]["reason"], "VoltageLow");
    // The mission telemetry carries the voltage.
    let mission = records(&telemetry, "mission");
    assert!(
        mission.iter().all(|m| m["battery_v"].as_f64().is_some()),
        "{telemetry}"
    );
    assert!(stderr.contains("battery voltage low"), "{stderr}");
    assert!(stderr.contains("returning to the start"), "{stderr}");

    // The robot had left its start, and ends within 0.5 m of it (its true pose).
    let truth = read_truth(&truth_log);
    assert!(truth.len() > 100, "{} truth lines", truth.len());
    let start = &truth[0];
    let dist = |t: &e2e::Truth| (t.x_m - start.x_m).hypot(t.y_m - start.y_m);
    let farthest = truth.iter().map(dist).fold(0.0, f64::max);
    let end = truth.last().unwrap();
    eprintln!(
        "battery: low at {t_low:.0} s ({v:.1} V), returning at {:.0} s from {:.2} m, done at {:.0} s; farthest {farthest:.2} m from the start, ends {:.2} m from it",
        returning[0]["t_s"].as_f64().unwrap_or(0.0),
        returning[0]["start_distance_m"].as_f64().unwrap_or(0.0),
        done[0]["t_s"].as_f64().unwrap_or(0.0),
        dist(end)
    );
    assert!(
        farthest > 1.5,
        "the robot never left its start ({farthest} m)"
    );
    assert!(
        dist(end) <= 0.5,
        "the robot ends {} m from its start",
        dist(end)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
