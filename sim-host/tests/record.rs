//! `papillon-sim mission --mcap`: the recording read back with the `mcap` crate's reader (not
//! Papillon's writer), channel by channel, schema by schema, counted against the mission's
//! own report.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("papillon-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Per topic: (schema name, schema encoding, message encoding, messages as JSON).
type Topics = BTreeMap<String, (String, String, String, Vec<serde_json::Value>)>;

fn read_back(path: &std::path::Path) -> Topics {
    let bytes = std::fs::read(path).unwrap();
    let mut topics = Topics::new();
    let mut last_time = 0;
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let m = message.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        let entry = topics.entry(m.channel.topic.clone()).or_insert_with(|| {
            (
                schema.name.clone(),
                schema.encoding.clone(),
                m.channel.message_encoding.clone(),
                Vec::new(),
            )
        });
        assert!(m.log_time >= last_time, "messages in time order");
        last_time = m.log_time;
        entry.3.push(serde_json::from_slice(&m.data).unwrap());
    }
    // The summary section lists the same channels.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    assert_eq!(summary.channels.len(), topics.len());
    topics
}

#[test]
fn a_mission_recorded_as_mcap_reads_back_with_every_channel() {
    let path = temp_path("lab.mcap");
    let out = Command::new(env!("CARGO_BIN_EXE_papillon-sim"))
        .args([
            "mission",
            "--map",
            "lab",
            "--battery",
            "25",
            "--json",
            "--mcap",
        ])
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let decisions = report["decisions"].as_u64().unwrap() as usize;
    assert!(decisions >= 2, "{report}");
    let sim_time_s = report["sim_time_s"].as_f64().unwrap();

    let topics = read_back(&path);
    let schema_of = |t: &str| {
        let (name, schema_enc, msg_enc, _) = &topics[t];
        assert_eq!(
            (schema_enc.as_str(), msg_enc.as_str()),
            ("jsonschema", "json"),
            "{t}"
        );
        name.as_str()
    };
    let expected = [
        ("/map", "foxglove.Grid"),
        ("/scan", "foxglove.LaserScan"),
        ("/pose/odometry", "foxglove.PoseInFrame"),
        ("/pose/estimated", "foxglove.PoseInFrame"),
        ("/pose/true", "foxglove.PoseInFrame"),
        ("/tf", "foxglove.FrameTransform"),
        ("/path", "foxglove.PosesInFrame"),
        ("/targets", "foxglove.SceneUpdate"),
        ("/decisions", "papillon.Decision"),
    ];
    assert_eq!(
        topics
            .keys()
            .map(String::as_str)
            .collect::<std::collections::BTreeSet<_>>(),
        expected.iter().map(|(t, _)| *t).collect(),
    );
    for (topic, schema) in expected {
        assert_eq!(schema_of(topic), schema, "{topic}");
    }
    let count = |t: &str| topics[t].3.len();
    // The map at the start, after each decision and at the end.
    assert_eq!(count("/map"), decisions + 2);
    assert_eq!(count("/decisions"), decisions);
    assert_eq!(count("/targets"), decisions);
    // Poses every control period (10 Hz) from time 0 to the end.
    let periods = (sim_time_s * 10.0).round() as usize + 1;
    for t in ["/pose/odometry", "/pose/estimated", "/pose/true", "/tf"] {
        assert!(
            count(t).abs_diff(periods) <= 1,
            "{t}: {} for {periods}",
            count(t)
        );
    }
    assert!(count("/scan") >= periods / 2, "{} scans", count("/scan"));
    assert!(count("/path") >= 1);

    // Contents: the final map has as many cells as the grid and knows some of them; a scan
    // has ranges; a decision names its targets as the targets channel draws them.
    let map = topics["/map"].3.last().unwrap();
    let columns = map["column_count"].as_u64().unwrap() as usize;
    let data = map["data"].as_str().unwrap();
    use base64::Engine as _;
    let cells = base64::engine::general_purpose::STANDARD
        .decode(data)
        .unwrap();
    assert_eq!(cells.len() % columns, 0);
    assert!(cells.contains(&0) && cells.contains(&100));
    let scan = &topics["/scan"].3[0];
    assert!(scan["ranges"].as_array().unwrap().len() > 100);
    let decision = &topics["/decisions"].3[0];
    let target = &decision["targets"][0];
    let sphere = &topics["/targets"].3[0]["entities"][0]["spheres"][0]["pose"]["position"];
    assert_eq!((&sphere["x"], &sphere["y"]), (&target[0], &target[1]));
    let _ = std::fs::remove_file(&path);
}

#[test]
fn an_unwritable_recording_is_one_line_naming_the_option() {
    let out = Command::new(env!("CARGO_BIN_EXE_papillon-sim"))
        .args([
            "mission",
            "--map",
            "lab",
            "--battery",
            "5",
            "--mcap",
            "/no/such/dir/x.mcap",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("papillon-sim mission: --mcap: /no/such/dir/x.mcap: cannot create"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}
