//! Mission recordings: an MCAP file (<https://mcap.dev>) of what a mission saw and decided,
//! in Foxglove's well-known schemas, so that Foxglove (or any MCAP reader) replays the map
//! growing, the scans, the poses, the planned path and the chosen targets.
//!
//! Host only (feature `record`); the core never imports it. The onboard runtime
//! (`crate::onboard::record`) and the simulator (`papillon-sim mission --mcap`) feed one
//! [`Recorder`] with the core's own types. Messages are JSON (message encoding `json`, schema
//! encoding `jsonschema`); chunks are zstd-compressed by the `mcap` crate's writer.
//!
//! Channels (topics for a one-robot recording; with several robots, each robot's topics are
//! under `/robot<k>`, e.g. `/robot1/scan`, and the map stays `/map`):
//!
//! | topic | schema | what |
//! |---|---|---|
//! | `/map` | `foxglove.Grid` | the occupancy grid, one `int8` field `occupancy` (ROS values: -1 unknown, 0 free, 100 occupied), frame `map` |
//! | `/scan` | `foxglove.LaserScan` | each scan, placed at the laser's pose in the map (estimated pose and mount); no return is `null` |
//! | `/pose/odometry`, `/pose/estimated`, `/pose/true` | `foxglove.PoseInFrame` | the robot's odometry, the mission's map-frame estimate, the simulator's truth |
//! | `/tf` | `foxglove.FrameTransform` | `map` → `base_link` from the estimated pose |
//! | `/path` | `foxglove.PosesInFrame` | the planned path, when it changes |
//! | `/targets` | `foxglove.SceneUpdate` | the chosen targets as spheres, at each decision |
//! | `/decisions` | `papillon.Decision` | each decision's figures as plain JSON |
//!
//! Times are nanoseconds: the mission time plus a base given at creation (the wall clock at
//! the start for `papillon run`, zero for the simulator's simulated time).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, Write};
use std::path::Path;

use base64::Engine as _;
use mcap::records::MessageHeader;
use serde_json::{Value, json};

use crate::geometry::{Point2, Pose2};
use crate::grid::{CellClass, GridGeometry, OccupancyGrid};
use crate::sensor::Scan;

/// The frame every message is placed in.
pub const MAP_FRAME: &str = "map";

/// Which pose a `/pose/...` message carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseSource {
    /// The robot's odometry (its own frame, started where the robot was switched on).
    Odometry,
    /// The mission's estimate in the map frame.
    Estimated,
    /// The simulator's true pose.
    True,
}

impl PoseSource {
    fn name(self) -> &'static str {
        match self {
            PoseSource::Odometry => "odometry",
            PoseSource::Estimated => "estimated",
            PoseSource::True => "true",
        }
    }
}

/// An error of a recording: the file, or the MCAP writer.
#[derive(Debug)]
pub enum RecordError {
    /// The file could not be created or written.
    Io(io::Error),
    /// The MCAP writer refused a record.
    Mcap(mcap::McapError),
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RecordError::Io(e) => write!(f, "{e}"),
            RecordError::Mcap(e) => write!(f, "MCAP: {e}"),
        }
    }
}

impl std::error::Error for RecordError {}

impl From<io::Error> for RecordError {
    fn from(e: io::Error) -> Self {
        RecordError::Io(e)
    }
}

impl From<mcap::McapError> for RecordError {
    fn from(e: mcap::McapError) -> Self {
        RecordError::Mcap(e)
    }
}

/// The schemas, by name: (name, JSON schema).
fn schema(name: &str) -> Value {
    let time = json!({"type": "object", "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}});
    let vector3 = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}});
    let quaternion = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"},
        "w": {"type": "number"}}});
    let pose = json!({"title": "foxglove.Pose", "type": "object", "properties": {
        "position": vector3, "orientation": quaternion}});
    let color = json!({"type": "object", "properties": {
        "r": {"type": "number"}, "g": {"type": "number"}, "b": {"type": "number"},
        "a": {"type": "number"}}});
    let properties = match name {
        "foxglove.Grid" => json!({
            "timestamp": time, "frame_id": {"type": "string"}, "pose": pose,
            "column_count": {"type": "integer", "minimum": 0},
            "cell_size": {"type": "object", "properties": {
                "x": {"type": "number"}, "y": {"type": "number"}}},
            "row_stride": {"type": "integer", "minimum": 0},
            "cell_stride": {"type": "integer", "minimum": 0},
            "fields": {"type": "array", "items": {"type": "object", "properties": {
                "name": {"type": "string"},
                "offset": {"type": "integer", "minimum": 0},
                "type": {"type": "integer"}}}},
            "data": {"type": "string", "contentEncoding": "base64"}}),
        "foxglove.LaserScan" => json!({
            "timestamp": time, "frame_id": {"type": "string"}, "pose": pose,
            "start_angle": {"type": "number"}, "end_angle": {"type": "number"},
            "ranges": {"type": "array", "items": {"type": ["number", "null"]}},
            "intensities": {"type": "array", "items": {"type": "number"}}}),
        "foxglove.PoseInFrame" => json!({
            "timestamp": time, "frame_id": {"type": "string"}, "pose": pose}),
        "foxglove.PosesInFrame" => json!({
            "timestamp": time, "frame_id": {"type": "string"},
            "poses": {"type": "array", "items": pose}}),
        "foxglove.FrameTransform" => json!({
            "timestamp": time, "parent_frame_id": {"type": "string"},
            "child_frame_id": {"type": "string"}, "translation": vector3,
            "rotation": quaternion}),
        "foxglove.SceneUpdate" => json!({
            "deletions": {"type": "array", "items": {"type": "object"}},
            "entities": {"type": "array", "items": {"type": "object", "properties": {
                "timestamp": time, "frame_id": {"type": "string"}, "id": {"type": "string"},
                "lifetime": time, "frame_locked": {"type": "boolean"},
                "spheres": {"type": "array", "items": {"type": "object", "properties": {
                    "pose": pose, "size": vector3, "color": color}}}}}}}),
        _ => json!({
            "robot": {"type": "integer"}, "t_s": {"type": "number"},
            "targets": {"type": "array"}, "path_length_m": {"type": "number"},
            "predicted_gain_cells": {"type": "integer"}, "energy_steps": {"type": "number"},
            "evaluations": {"type": "integer"}}),
    };
    json!({"title": name, "type": "object", "properties": properties})
}

/// A Foxglove `time` from nanoseconds.
fn stamp(t_ns: u64) -> Value {
    json!({"sec": t_ns / 1_000_000_000, "nsec": t_ns % 1_000_000_000})
}

/// A `foxglove.Pose` in the plane (z = 0, a yaw).
fn pose_json(p: Pose2) -> Value {
    let (s, c) = (0.5 * p.theta).sin_cos();
    json!({"position": {"x": p.x, "y": p.y, "z": 0.0},
           "orientation": {"x": 0.0, "y": 0.0, "z": s, "w": c}})
}

/// The ROS occupancy value of a cell class (-1 unknown, 0 free, 100 occupied).
fn occupancy(class: CellClass) -> i8 {
    match class {
        CellClass::Unknown => -1,
        CellClass::Free => 0,
        CellClass::Occupied => 100,
    }
}

/// An MCAP recording of a mission (see the module documentation for the channels), and/or
/// its live view ([`Self::with_live`]).
pub struct Recorder<W: Write + Seek> {
    /// The MCAP file; `None` for a live view alone ([`Recorder::live_only`]).
    writer: Option<mcap::Writer<W>>,
    /// The live view and its channel ids by topic.
    #[cfg(feature = "live")]
    live: Option<(crate::live::LiveServer, BTreeMap<String, u32>)>,
    robots: usize,
    base_ns: u64,
    schemas: BTreeMap<&'static str, u16>,
    channels: BTreeMap<String, u16>,
    sequence: u32,
    /// The last path recorded per robot (a path is recorded when it changes).
    last_path: Vec<Vec<Point2>>,
}

impl<W: Write + Seek> std::fmt::Debug for Recorder<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("robots", &self.robots)
            .field("channels", &self.channels.len())
            .field("messages", &self.sequence)
            .finish_non_exhaustive()
    }
}

impl Recorder<BufWriter<File>> {
    /// Creates (or truncates) `path` for a recording of `robots` robots, times offset by
    /// `base_ns`. The error names the file.
    pub fn create(path: &Path, robots: usize, base_ns: u64) -> Result<Self, String> {
        let file =
            File::create(path).map_err(|e| format!("{}: cannot create: {e}", path.display()))?;
        Self::new(BufWriter::new(file), robots, base_ns)
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// A live view of `robots` robots alone, no file (see [`Self::with_live`]).
    #[cfg(feature = "live")]
    pub fn live_only(live: crate::live::LiveServer, robots: usize, base_ns: u64) -> Self {
        let mut recorder = Self::starting(None, robots, base_ns);
        recorder.live = Some((live, BTreeMap::new()));
        recorder
    }
}

impl<W: Write + Seek> Recorder<W> {
    /// A recording of `robots` robots into `w`, times offset by `base_ns`.
    pub fn new(w: W, robots: usize, base_ns: u64) -> Result<Self, RecordError> {
        let writer = mcap::WriteOptions::new()
            .profile("")
            .library(concat!("papillon ", env!("CARGO_PKG_VERSION")))
            .create(w)?;
        Ok(Self::starting(Some(writer), robots, base_ns))
    }

    /// A recorder that has written nothing yet: no live view, no schema or channel registered.
    fn starting(writer: Option<mcap::Writer<W>>, robots: usize, base_ns: u64) -> Self {
        Self {
            writer,
            #[cfg(feature = "live")]
            live: None,
            robots: robots.max(1),
            base_ns,
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            sequence: 0,
            last_path: vec![Vec::new(); robots.max(1)],
        }
    }

    /// Also publishes every message to the live view `live` ([`crate::live`]).
    #[cfg(feature = "live")]
    pub fn with_live(mut self, live: crate::live::LiveServer) -> Self {
        self.live = Some((live, BTreeMap::new()));
        self
    }

    /// The live view's address, when there is one.
    #[cfg(feature = "live")]
    pub fn live_addr(&self) -> Option<std::net::SocketAddr> {
        self.live.as_ref().map(|(l, _)| l.local_addr())
    }

    /// The topic of robot `robot`'s channel `name`.
    pub fn topic(&self, robot: usize, name: &str) -> String {
        if self.robots == 1 {
            format!("/{name}")
        } else {
            format!("/robot{robot}/{name}")
        }
    }

    fn time_ns(&self, t_s: f64) -> u64 {
        self.base_ns
            .saturating_add((t_s.max(0.0) * 1e9).round() as u64)
    }

    fn write(
        &mut self,
        topic: &str,
        schema_name: &'static str,
        t_ns: u64,
        message: &Value,
    ) -> Result<(), RecordError> {
        let data = serde_json::to_vec(message).map_err(io::Error::other)?;
        self.sequence = self.sequence.wrapping_add(1);
        #[cfg(feature = "live")]
        if let Some((live, ids)) = &mut self.live {
            let id = match ids.get(topic) {
                Some(&id) => id,
                None => {
                    let schema = schema(schema_name).to_string();
                    let id = live.add_channel(topic, schema_name, &schema);
                    ids.insert(topic.to_string(), id);
                    id
                }
            };
            live.publish(id, t_ns, &data);
        }
        let Some(writer) = &mut self.writer else {
            return Ok(());
        };
        let channel_id = match self.channels.get(topic) {
            Some(&id) => id,
            None => {
                let schema_id = match self.schemas.get(schema_name) {
                    Some(&id) => id,
                    None => {
                        let data =
                            serde_json::to_vec(&schema(schema_name)).map_err(io::Error::other)?;
                        let id = writer.add_schema(schema_name, "jsonschema", &data)?;
                        self.schemas.insert(schema_name, id);
                        id
                    }
                };
                let id = writer.add_channel(schema_id, topic, "json", &BTreeMap::new())?;
                self.channels.insert(topic.to_string(), id);
                id
            }
        };
        writer.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: t_ns,
                publish_time: t_ns,
            },
            &data,
        )?;
        Ok(())
    }

    /// The map at mission time `t_s` \[s\] (`/map`, `foxglove.Grid`).
    pub fn map<const N: usize>(
        &mut self,
        t_s: f64,
        grid: &OccupancyGrid<N>,
    ) -> Result<(), RecordError> {
        self.map_cells(
            t_s,
            grid.geometry(),
            (0..grid.cell_count()).map(|i| grid.class(i)),
        )
    }

    /// A map of geometry `g` given cell by cell (flat-index order, row 0 south) at mission
    /// time `t_s` \[s\] (`/map`, `foxglove.Grid`): for maps that are no [`OccupancyGrid`],
    /// such as a simulated world.
    pub fn map_cells(
        &mut self,
        t_s: f64,
        g: &GridGeometry,
        classes: impl IntoIterator<Item = CellClass>,
    ) -> Result<(), RecordError> {
        let cells: Vec<u8> = classes.into_iter().map(|c| occupancy(c) as u8).collect();
        let t_ns = self.time_ns(t_s);
        let message = json!({
            "timestamp": stamp(t_ns),
            "frame_id": MAP_FRAME,
            "pose": pose_json(Pose2::new(g.origin.x, g.origin.y, 0.0)),
            "column_count": g.width,
            "cell_size": {"x": g.resolution_m, "y": g.resolution_m},
            "row_stride": g.width,
            "cell_stride": 1,
            // foxglove.NumericType INT8 = 2.
            "fields": [{"name": "occupancy", "offset": 0, "type": 2}],
            "data": base64::engine::general_purpose::STANDARD.encode(&cells),
        });
        self.write("/map", "foxglove.Grid", t_ns, &message)
    }

    /// A scan of robot `robot` taken from the laser pose `laser_map` (map frame) at `t_s`
    /// (`/scan`, `foxglove.LaserScan`). The beams are taken as evenly spaced from the first
    /// beam's angle to the last one's, as the schema requires.
    pub fn scan(
        &mut self,
        t_s: f64,
        robot: usize,
        laser_map: Pose2,
        scan: &Scan,
    ) -> Result<(), RecordError> {
        let beams = scan.beams();
        let (start, end) = match (beams.first(), beams.last()) {
            (Some(a), Some(b)) => (a.angle_rad, b.angle_rad),
            _ => (0.0, 0.0),
        };
        let ranges: Vec<Value> = beams
            .iter()
            .map(|b| b.range_m.map_or(Value::Null, |r| json!(r)))
            .collect();
        let t_ns = self.time_ns(t_s);
        let message = json!({
            "timestamp": stamp(t_ns),
            "frame_id": MAP_FRAME,
            "pose": pose_json(laser_map),
            "start_angle": start,
            "end_angle": end,
            "ranges": ranges,
            "intensities": [],
        });
        let topic = self.topic(robot, "scan");
        self.write(&topic, "foxglove.LaserScan", t_ns, &message)
    }

    /// Robot `robot`'s pose from `source` at `t_s` (`/pose/<source>`, `foxglove.PoseInFrame`);
    /// the estimated pose also moves the `base_link` frame (`/tf`, `foxglove.FrameTransform`).
    pub fn pose(
        &mut self,
        t_s: f64,
        robot: usize,
        source: PoseSource,
        pose: Pose2,
    ) -> Result<(), RecordError> {
        let t_ns = self.time_ns(t_s);
        let frame = match source {
            PoseSource::Odometry => "odom",
            _ => MAP_FRAME,
        };
        let message = json!({"timestamp": stamp(t_ns), "frame_id": frame, "pose": pose_json(pose)});
        let topic = self.topic(robot, &format!("pose/{}", source.name()));
        self.write(&topic, "foxglove.PoseInFrame", t_ns, &message)?;
        if source == PoseSource::Estimated {
            let child = if self.robots == 1 {
                "base_link".to_string()
            } else {
                format!("robot{robot}/base_link")
            };
            let p = pose_json(pose);
            let tf = json!({
                "timestamp": stamp(t_ns),
                "parent_frame_id": MAP_FRAME,
                "child_frame_id": child,
                "translation": p["position"],
                "rotation": p["orientation"],
            });
            self.write("/tf", "foxglove.FrameTransform", t_ns, &tf)?;
        }
        Ok(())
    }

    /// Robot `robot`'s planned path at `t_s`, recorded only when it differs from the last one
    /// recorded (`/path`, `foxglove.PosesInFrame`; each waypoint heads to the next).
    pub fn path(&mut self, t_s: f64, robot: usize, path: &[Point2]) -> Result<(), RecordError> {
        let k = robot.min(self.last_path.len() - 1);
        if self.last_path[k] == path {
            return Ok(());
        }
        self.last_path[k] = path.to_vec();
        let poses: Vec<Value> = path
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let heading = path.get(i + 1).map_or(0.0, |q| p.bearing_to(*q));
                pose_json(Pose2::new(p.x, p.y, heading))
            })
            .collect();
        let t_ns = self.time_ns(t_s);
        let message = json!({"timestamp": stamp(t_ns), "frame_id": MAP_FRAME, "poses": poses});
        let topic = self.topic(robot, "path");
        self.write(&topic, "foxglove.PosesInFrame", t_ns, &message)
    }

    /// Robot `robot`'s chosen targets at `t_s`, as spheres replacing the previous ones
    /// (`/targets`, `foxglove.SceneUpdate`).
    pub fn targets(
        &mut self,
        t_s: f64,
        robot: usize,
        targets: &[Point2],
    ) -> Result<(), RecordError> {
        let t_ns = self.time_ns(t_s);
        let spheres: Vec<Value> = targets
            .iter()
            .map(|p| {
                json!({
                    "pose": pose_json(Pose2::new(p.x, p.y, 0.0)),
                    "size": {"x": 0.3, "y": 0.3, "z": 0.3},
                    "color": {"r": 1.0, "g": 0.4, "b": 0.0, "a": 0.9},
                })
            })
            .collect();
        let message = json!({
            "deletions": [],
            "entities": [{
                "timestamp": stamp(t_ns),
                "frame_id": MAP_FRAME,
                "id": format!("targets{robot}"),
                "lifetime": {"sec": 0, "nsec": 0},
                "frame_locked": false,
                "spheres": spheres,
            }],
        });
        let topic = self.topic(robot, "targets");
        self.write(&topic, "foxglove.SceneUpdate", t_ns, &message)
    }

    /// One decision of robot `robot` at `t_s` as plain JSON (`/decisions`,
    /// `papillon.Decision`): `fields` (an object) with `robot`, `t_s` and `targets` added.
    pub fn decision(
        &mut self,
        t_s: f64,
        robot: usize,
        targets: &[Point2],
        mut fields: Value,
    ) -> Result<(), RecordError> {
        if let Value::Object(map) = &mut fields {
            map.insert("robot".into(), json!(robot));
            map.insert("t_s".into(), json!(t_s));
            map.insert(
                "targets".into(),
                json!(targets.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>()),
            );
        }
        let t_ns = self.time_ns(t_s);
        let topic = self.topic(robot, "decisions");
        self.write(&topic, "papillon.Decision", t_ns, &fields)
    }

    /// Messages written so far.
    pub fn messages(&self) -> u32 {
        self.sequence
    }

    /// Writes the summary and the footer and flushes the file.
    pub fn finish(self) -> Result<(), RecordError> {
        if let Some(mut writer) = self.writer {
            writer.finish()?;
            writer.into_inner().flush()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridGeometry, LogOddsBounds};
    use crate::sensor::Beam;
    use std::io::Cursor;

    #[test]
    fn a_recording_reads_back_with_its_channels_and_schemas() {
        let g = GridGeometry::new(4, 3, 0.5, Point2::new(-1.0, 2.0)).unwrap();
        let mut grid = OccupancyGrid::<16>::new(g, LogOddsBounds::default()).unwrap();
        grid.set_class(5, CellClass::Occupied, &mut ());
        let mut scan = Scan::new();
        for (i, r) in [Some(1.0), None, Some(2.5)].into_iter().enumerate() {
            scan.push(Beam {
                angle_rad: -0.5 + 0.5 * i as f32,
                range_m: r,
            })
            .unwrap();
        }
        let mut rec = Recorder::new(Cursor::new(Vec::new()), 1, 7).unwrap();
        rec.map(0.5, &grid).unwrap();
        rec.scan(0.5, 0, Pose2::new(1.0, 2.0, 0.3), &scan).unwrap();
        rec.pose(0.6, 0, PoseSource::Estimated, Pose2::new(1.0, 2.0, 0.3))
            .unwrap();
        let path = [Point2::new(1.0, 2.0), Point2::new(2.0, 2.0)];
        rec.path(0.7, 0, &path).unwrap();
        rec.path(0.8, 0, &path).unwrap(); // unchanged: not recorded
        rec.targets(0.7, 0, &path[1..]).unwrap();
        rec.decision(0.7, 0, &path[1..], json!({"evaluations": 150}))
            .unwrap();
        assert_eq!(rec.messages(), 7);
        let bytes = {
            let mut w = rec.writer.unwrap();
            w.finish().unwrap();
            w.into_inner().into_inner()
        };
        let mut by_topic: BTreeMap<String, (String, Vec<Value>)> = BTreeMap::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "jsonschema");
            let entry = by_topic
                .entry(m.channel.topic.clone())
                .or_insert_with(|| (schema.name.clone(), Vec::new()));
            entry.1.push(serde_json::from_slice(&m.data).unwrap());
        }
        let names: Vec<(&str, &str, usize)> = by_topic
            .iter()
            .map(|(t, (s, v))| (t.as_str(), s.as_str(), v.len()))
            .collect();
        assert_eq!(
            names,
            [
                ("/decisions", "papillon.Decision", 1),
                ("/map", "foxglove.Grid", 1),
                ("/path", "foxglove.PosesInFrame", 1),
                ("/pose/estimated", "foxglove.PoseInFrame", 1),
                ("/scan", "foxglove.LaserScan", 1),
                ("/targets", "foxglove.SceneUpdate", 1),
                ("/tf", "foxglove.FrameTransform", 1),
            ]
        );
        let map = &by_topic["/map"].1[0];
        let data = base64::engine::general_purpose::STANDARD
            .decode(map["data"].as_str().unwrap())
            .unwrap();
        assert_eq!(data.len(), 12);
        assert_eq!(data[5] as i8, 100);
        assert_eq!(data[0] as i8, -1);
        assert_eq!(map["column_count"], 4);
        assert_eq!(map["pose"]["position"]["x"], -1.0);
        assert_eq!(map["timestamp"]["nsec"], 500_000_007);
        let scan = &by_topic["/scan"].1[0];
        assert_eq!(scan["ranges"], json!([1.0, null, 2.5]));
        assert_eq!(scan["start_angle"], -0.5);
        let d = &by_topic["/decisions"].1[0];
        assert_eq!(
            (d["evaluations"].as_i64(), d["robot"].as_i64()),
            (Some(150), Some(0))
        );
        assert_eq!(d["targets"], json!([[2.0, 2.0]]));
    }

    #[test]
    fn several_robots_have_their_own_topics() {
        let rec = Recorder::new(Cursor::new(Vec::new()), 3, 0).unwrap();
        assert_eq!(rec.topic(2, "scan"), "/robot2/scan");
        let one = Recorder::new(Cursor::new(Vec::new()), 1, 0).unwrap();
        assert_eq!(one.topic(0, "scan"), "/scan");
    }
}
