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
    // The recording and the directory of this run's own that holds it.
    if let Some(dir) = path.parent() {
        let _ = std::fs::remove_dir_all(dir);
    }
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

/// `papillon-sim mission --live 127.0.0.1:0`: a WebSocket client (tungstenite, not Papillon's
/// server code) connects with the `foxglove.websocket.v1` subprotocol, is advertised the
/// mission's channels, subscribes to the estimated pose and the map and receives them as
/// Foxglove message data while the mission runs.
#[test]
fn a_live_mission_is_served_to_a_foxglove_websocket_client() {
    use std::io::{BufRead, BufReader};
    use tungstenite::Message;
    use tungstenite::client::IntoClientRequest;

    let mut child = Command::new(env!("CARGO_BIN_EXE_papillon-sim"))
        .args([
            "mission",
            "--map",
            "lab",
            "--battery",
            "25",
            "--live",
            "127.0.0.1:0",
            "--live-speed",
            "5",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("ws://"))
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    let mut request = url.as_str().into_client_request().unwrap();
    request.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        tungstenite::http::HeaderValue::from_static("foxglove.websocket.v1"),
    );
    let (mut ws, response) = tungstenite::connect(request).unwrap();
    assert_eq!(
        response.headers()["Sec-WebSocket-Protocol"],
        "foxglove.websocket.v1"
    );
    if let tungstenite::stream::MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(std::time::Duration::from_secs(30)))
            .unwrap();
    }
    let mut channels: BTreeMap<String, (u64, String)> = BTreeMap::new();
    let mut subscribed: BTreeMap<u64, String> = BTreeMap::new();
    let mut received: BTreeMap<String, Vec<serde_json::Value>> = BTreeMap::new();
    let mut first = true;
    while received.get("/pose/estimated").is_none_or(|v| v.len() < 3)
        || !received.contains_key("/map")
    {
        match ws.read().unwrap() {
            Message::Text(text) => {
                let m: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
                if first {
                    assert_eq!(m["op"], "serverInfo", "{m}");
                    first = false;
                    continue;
                }
                assert_eq!(m["op"], "advertise", "{m}");
                for c in m["channels"].as_array().unwrap() {
                    let topic = c["topic"].as_str().unwrap().to_string();
                    let id = c["id"].as_u64().unwrap();
                    assert_eq!(c["encoding"], "json");
                    assert_eq!(c["schemaEncoding"], "jsonschema");
                    channels.insert(topic.clone(), (id, c["schemaName"].to_string()));
                    if topic == "/pose/estimated" || topic == "/map" {
                        let sub = 100 + id;
                        subscribed.insert(sub, topic);
                        ws.send(Message::text(
                            serde_json::json!({"op": "subscribe",
                                "subscriptions": [{"id": sub, "channelId": id}]})
                            .to_string(),
                        ))
                        .unwrap();
                    }
                }
            }
            Message::Binary(b) => {
                assert_eq!(b[0], 1, "message data");
                let sub = u32::from_le_bytes(b[1..5].try_into().unwrap()) as u64;
                let topic = subscribed.get(&sub).expect("a subscribed id").clone();
                let m: serde_json::Value = serde_json::from_slice(&b[13..]).unwrap();
                received.entry(topic).or_default().push(m);
            }
            _ => {}
        }
    }
    assert_eq!(channels["/map"].1, "\"foxglove.Grid\"");
    assert_eq!(channels["/pose/estimated"].1, "\"foxglove.PoseInFrame\"");
    let pose = &received["/pose/estimated"][0];
    assert_eq!(pose["frame_id"], "map");
    assert!(pose["pose"]["position"]["x"].is_number(), "{pose}");
    assert!(received["/map"][0]["column_count"].as_u64().unwrap() > 0);
    drop(ws);
    // The mission goes on without its viewer and ends by itself.
    let status = child.wait().unwrap();
    assert!(status.success());
}
