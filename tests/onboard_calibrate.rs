//! `papillon calibrate` end to end: the UMBmark square driven by the onboard binary on an
//! emulated robot whose wheels have known systematic errors (`papillon-sim serve
//! --wheel-errors ED,EB`, Borenstein & Feng's model in `sim-host/src/odometry_error.rs`),
//! with the true end positions read from serve's `--truth-log`.
#![cfg(feature = "onboard")]

mod e2e;

use std::time::Duration;

use e2e::{Sim, papillon, temp_dir, wait_bounded};

/// The number after `key` on the line starting with `prefix`.
fn value_after(text: &str, key: &str) -> f32 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("no {key:?} in {text}"))
        + key.len();
    text[at..]
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
        .find(|t| !t.is_empty())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no number after {key:?} in {text}"))
}

#[test]
fn calibrate_recovers_the_wheel_diameter_ratio_and_the_wheelbase_error_within_20_percent() {
    let (ed, eb) = (1.01f32, 0.97f32);
    let dir = temp_dir("calibrate");
    let truth = dir.join("truth.jsonl");
    let errors = format!("{ed},{eb}");
    let sim = Sim::start(
        "empty",
        None,
        &[
            "--wheel-errors",
            &errors,
            "--truth-log",
            truth.to_str().unwrap(),
            // In the middle of the 24 m empty world: room for both squares.
            "--start",
            "12,12,0",
        ],
    );
    // A 2 m square at 400 mm/s keeps the test short; the emulated wheelbase is 357 mm.
    let out = wait_bounded(
        papillon(
            &[
                "calibrate",
                "--tcp",
                &sim.arcos_tcp(),
                "--side-m",
                "2",
                "--runs",
                "1",
                "--speed-mm-s",
                "400",
                "--wheelbase-mm",
                "357",
                "--truth-log",
                truth.to_str().unwrap(),
            ],
            &dir,
        ),
        Duration::from_secs(300),
    );
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "stdout:\n{text}\nstderr:\n{stderr}"
    );
    eprintln!("{text}");
    assert!(text.contains("run 1 (counter-clockwise)"), "{text}");
    assert!(text.contains("run 2 (clockwise)"), "{text}");
    let got_ed = value_after(&text, "\"wheel_diameter_ratio\": ");
    let got_eb = value_after(&text, "\"wheelbase_ratio\": ");
    let within =
        |got: f32, want: f32| ((got - 1.0) - (want - 1.0)).abs() <= 0.2 * (want - 1.0).abs();
    assert!(within(got_ed, ed), "Ed {got_ed}, truly {ed}\n{text}");
    assert!(within(got_eb, eb), "Eb {got_eb}, truly {eb}\n{text}");
    drop(sim);
    std::fs::remove_dir_all(&dir).unwrap();
}
