//! `papillon run` records its mission: `mission.mcap` in the log directory, read back with the
//! `mcap` crate's reader (not Papillon's writer), after a short mission on the simulator's
//! `lab` world through `papillon-sim serve` (loopback TCP, ports chosen by the system).
#![cfg(feature = "onboard")]

mod e2e;

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use e2e::{Sim, papillon, temp_dir, wait_bounded};

#[test]
fn papillon_run_records_the_mission_as_mcap_in_its_log_directory() {
    let sim = Sim::start("lab", None, &[]);
    let dir = temp_dir("record");
    let log = dir.join("log");
    // boards/sim-thesis.json with a small battery: a short mission with a few decisions.
    let text = std::fs::read_to_string(format!(
        "{}/boards/sim-thesis.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut board: serde_json::Value = serde_json::from_str(&text).unwrap();
    board["mission"]["battery_steps"] = serde_json::json!(8.0);
    let board_path = dir.join("board.json");
    std::fs::write(&board_path, board.to_string()).unwrap();
    let (arcos, laser) = (sim.arcos_tcp(), sim.laser());
    let args = [
        "run",
        "--board",
        board_path.to_str().unwrap(),
        "--tcp",
        &arcos,
        "--laser",
        &laser,
        "--log-dir",
        log.to_str().unwrap(),
    ];
    let out = wait_bounded(papillon(&args, &dir), Duration::from_secs(240));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");

    let telemetry = std::fs::read_to_string(log.join("telemetry.jsonl")).unwrap();
    let decisions = telemetry
        .lines()
        .filter(|l| l.contains("\"kind\":\"decision\""))
        .count();
    assert!(decisions >= 1, "{telemetry}");

    let bytes = std::fs::read(log.join("mission.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a finished recording has a summary");
    let mut topics: BTreeMap<String, (String, Vec<serde_json::Value>)> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!(
            (
                schema.encoding.as_str(),
                m.channel.message_encoding.as_str()
            ),
            ("jsonschema", "json")
        );
        topics
            .entry(m.channel.topic.clone())
            .or_insert_with(|| (schema.name.clone(), Vec::new()))
            .1
            .push(serde_json::from_slice(&m.data).unwrap());
    }
    assert_eq!(summary.channels.len(), topics.len());
    let expected = [
        ("/map", "foxglove.Grid"),
        ("/scan", "foxglove.LaserScan"),
        ("/pose/odometry", "foxglove.PoseInFrame"),
        ("/pose/estimated", "foxglove.PoseInFrame"),
        ("/tf", "foxglove.FrameTransform"),
        ("/path", "foxglove.PosesInFrame"),
        ("/targets", "foxglove.SceneUpdate"),
        ("/decisions", "papillon.Decision"),
    ];
    assert_eq!(
        topics.keys().map(String::as_str).collect::<BTreeSet<_>>(),
        expected.iter().map(|(t, _)| *t).collect::<BTreeSet<_>>(),
        "the robot has no true pose: /pose/true is the simulator's"
    );
    for (topic, schema) in expected {
        assert_eq!(topics[topic].0, schema, "{topic}");
    }
    let count = |t: &str| topics[t].1.len();
    // The map at the start, after each decision and at the end.
    assert_eq!(count("/map"), decisions + 2);
    assert_eq!(count("/decisions"), decisions);
    assert_eq!(count("/targets"), decisions);
    assert_eq!(count("/pose/odometry"), count("/pose/estimated"));
    assert!(count("/pose/odometry") >= 10 && count("/scan") >= 10);
    // Times are the wall clock: the recording was made in the last hour.
    let first = &topics["/map"].1[0]["timestamp"]["sec"];
    let now_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs();
    assert!(first.as_u64().unwrap().abs_diff(now_s) < 3600, "{first}");
    std::fs::remove_dir_all(&dir).unwrap();
}
