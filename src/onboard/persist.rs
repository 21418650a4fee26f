//! Saving and loading the mission state, and the telemetry log.
//!
//! Every file is written atomically: a temporary file in the same directory (created
//! exclusively: a symbolic link planted in its place is removed, never followed), write, fsync
//! the file, rename over the old one, fsync the directory. The telemetry log refuses a
//! symbolic link in its place. A power cut or `kill -9` therefore
//! leaves either the previous or the new version of each file, never a mix, and a leftover
//! temporary file is ignored by [`StateStore::load`].
//!
//! Layout of a log directory:
//! - `map.pgm` + `map.yaml`: the occupancy map (ROS map_server conventions: 0 occupied,
//!   254 free, 205 unknown, first row = north edge);
//! - `state.json`: pose, trajectory and counters ([`MissionState`]); written last, so a
//!   complete `state.json` always has a map at least as new as itself;
//! - `telemetry.jsonl`: one JSON object per line ([`Telemetry`]);
//! - `map.png`: the final map, written at exit.
//!
//! The map files are read and written by [`crate::mapfile`] (the one map reader and writer);
//! [`MapImage`] is the mission's copy of the map between saves.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::files::{Existing, MAP_MAX_BYTES, create_temporary, open_log, read_limited};
use crate::geometry::Point2;
use crate::grid::{CellClass, GridGeometry, OccupancyGrid};
use crate::mapfile;

/// Writes `bytes` to `path` atomically (temporary file, fsync, rename, fsync of the directory).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "path has no file name"))?;
    let tmp = dir.join(format!(
        ".{}.tmp.{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut f = create_temporary(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)?;
        // Make the rename itself durable.
        File::open(dir)?.sync_all()
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// A pose record \[m, m, rad\] in the map frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoseRecord {
    /// East \[m\].
    pub x_m: f32,
    /// North \[m\].
    pub y_m: f32,
    /// Heading \[rad\].
    pub theta_rad: f32,
}

/// Mission counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Counters {
    /// Target decisions made.
    pub decisions: u64,
    /// Distance driven \[m\].
    pub distance_m: f32,
    /// Energy used \[steps\].
    pub energy_used_steps: f32,
    /// Faults seen (stops).
    pub faults: u64,
    /// Link reconnections.
    pub reconnects: u64,
    /// Scans integrated into the map.
    pub scans: u64,
}

/// Everything needed to continue a mission, apart from the map.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionState {
    /// Format version (1).
    pub version: u32,
    /// Mission time when saved \[s\].
    pub mission_time_s: f64,
    /// Current pose (map frame).
    pub pose: PoseRecord,
    /// Odometry pose at the time of the save (odom frame), to re-anchor after a restart.
    pub odom_pose: PoseRecord,
    /// Poses visited, oldest first.
    pub trajectory: Vec<PoseRecord>,
    /// Counters.
    pub counters: Counters,
    /// Known-area fraction when saved (0..=1).
    pub coverage: f32,
    /// Whether the mission had finished.
    pub finished: bool,
}

/// Largest mission time a saved state may hold \[s\]: a year.
pub const MAX_MISSION_TIME_S: f64 = 365.0 * 86_400.0;
/// Largest distance of a saved pose from the map's origin \[m\] (as a map file's origin).
pub const MAX_POSE_M: f32 = 100_000.0;

impl MissionState {
    /// Why the state cannot be a mission's (a field out of range, with its JSON path), if so:
    /// a damaged or hand-edited `state.json` is refused rather than resumed.
    pub fn implausible(&self) -> Option<String> {
        if !(self.mission_time_s.is_finite()
            && (0.0..=MAX_MISSION_TIME_S).contains(&self.mission_time_s))
        {
            return Some(format!(
                "$.mission_time_s is {}, expected 0 to {MAX_MISSION_TIME_S} s",
                self.mission_time_s
            ));
        }
        if !(self.coverage.is_finite() && (0.0..=1.0).contains(&self.coverage)) {
            return Some(format!(
                "$.coverage is {}, expected a fraction from 0 to 1",
                self.coverage
            ));
        }
        let poses = [("$.pose", &self.pose), ("$.odom_pose", &self.odom_pose)];
        let trajectory = self.trajectory.iter().map(|p| ("$.trajectory[]", p));
        for (path, p) in poses.into_iter().chain(trajectory) {
            let fine = |v: f32| v.is_finite() && v.abs() <= MAX_POSE_M;
            if !(fine(p.x_m) && fine(p.y_m) && p.theta_rad.is_finite()) {
                return Some(format!(
                    "{path} is ({}, {}, {}), expected metres within ±{MAX_POSE_M} and a finite heading",
                    p.x_m, p.y_m, p.theta_rad
                ));
            }
        }
        None
    }
}

/// Current [`MissionState::version`].
pub const STATE_VERSION: u32 = 1;

/// PGM value of an occupied cell.
pub const PGM_OCCUPIED: u8 = 0;
/// PGM value of a free cell.
pub const PGM_FREE: u8 = 254;
/// PGM value of an unknown cell.
pub const PGM_UNKNOWN: u8 = 205;

/// The class of a pixel of a [`MapImage`] (the values [`MapImage::from_grid`] writes; others
/// as the nearest of them).
fn pixel_class(p: u8) -> CellClass {
    match p {
        PGM_OCCUPIED..=50 => CellClass::Occupied,
        200..=210 => CellClass::Unknown,
        _ => CellClass::Free,
    }
}

/// The PGM value [`MapImage`] writes for a class.
fn pgm_value(class: CellClass) -> u8 {
    match class {
        CellClass::Occupied => PGM_OCCUPIED,
        CellClass::Free => PGM_FREE,
        CellClass::Unknown => PGM_UNKNOWN,
    }
}

/// A map as an image: one byte per cell, rows from north to south.
#[derive(Clone, Debug, PartialEq)]
pub struct MapImage {
    /// Columns \[cells\].
    pub width: usize,
    /// Rows \[cells\].
    pub height: usize,
    /// Cell side \[m\].
    pub resolution_m: f32,
    /// Map-frame position of the south-west corner \[m\].
    pub origin_x_m: f32,
    /// Map-frame position of the south-west corner \[m\].
    pub origin_y_m: f32,
    /// `width × height` PGM values, first row = north edge.
    pub pixels: Vec<u8>,
}

impl MapImage {
    /// The image of a grid: each cell's class as a PGM value.
    pub fn from_grid<const N: usize>(grid: &OccupancyGrid<N>) -> Self {
        Self::from_classes(*grid.geometry(), |cell| grid.class(cell))
    }

    /// The image of a map of `g`'s geometry whose cell `row * width + col` (row 0 south) has
    /// the class `class(cell)`: rows from north to south, each class as its PGM value.
    pub fn from_classes(g: GridGeometry, class: impl Fn(usize) -> CellClass) -> Self {
        let mut pixels = Vec::with_capacity(g.width * g.height);
        for row in (0..g.height).rev() {
            for col in 0..g.width {
                pixels.push(pgm_value(class(row * g.width + col)));
            }
        }
        Self {
            width: g.width,
            height: g.height,
            resolution_m: g.resolution_m,
            origin_x_m: g.origin.x,
            origin_y_m: g.origin.y,
            pixels,
        }
    }

    /// Each pixel's grid cell (`row * width + col`, row 0 south) and class.
    fn cell_classes(&self) -> impl Iterator<Item = (usize, CellClass)> + '_ {
        self.pixels.iter().enumerate().map(|(i, &p)| {
            let (image_row, col) = (i / self.width, i % self.width);
            let row = self.height - 1 - image_row;
            (row * self.width + col, pixel_class(p))
        })
    }

    /// Restores a saved map into `grid` (for `--resume`): every cell gets the class its pixel
    /// shows (occupied, free or unknown, at the grid's log-odds bounds). The grid must have the
    /// image's size, resolution and origin.
    pub fn apply_to_grid<const N: usize>(
        &self,
        grid: &mut OccupancyGrid<N>,
    ) -> Result<(), PersistError> {
        let g = *grid.geometry();
        if g.width != self.width
            || g.height != self.height
            || (g.resolution_m - self.resolution_m).abs() > 1e-6
            || (g.origin.x - self.origin_x_m).abs() > 1e-4
            || (g.origin.y - self.origin_y_m).abs() > 1e-4
        {
            return Err(PersistError::Corrupt(format!(
                "saved map is {}x{} cells at {} m from ({}, {}), the board's grid is {}x{} at {} m from ({}, {})",
                self.width,
                self.height,
                self.resolution_m,
                self.origin_x_m,
                self.origin_y_m,
                g.width,
                g.height,
                g.resolution_m,
                g.origin.x,
                g.origin.y
            )));
        }
        for (cell, class) in self.cell_classes() {
            grid.set_class(cell, class, &mut ());
        }
        Ok(())
    }

    /// This map in the map files' terms ([`crate::mapfile`]); an error when its pixels do
    /// not make its grid.
    pub fn to_map_file(&self) -> Result<mapfile::MapImage, PersistError> {
        let geometry = GridGeometry::new(
            self.width,
            self.height,
            self.resolution_m,
            Point2::new(self.origin_x_m, self.origin_y_m),
        )
        .map_err(|e| PersistError::Corrupt(format!("map: {e}")))?;
        if self.pixels.len() != geometry.cell_count() {
            return Err(PersistError::Corrupt(
                "map size does not match its pixels".into(),
            ));
        }
        let mut cells = vec![CellClass::Unknown; geometry.cell_count()];
        for (cell, class) in self.cell_classes() {
            cells[cell] = class;
        }
        Ok(mapfile::MapImage { geometry, cells })
    }

    /// A map read from map files ([`crate::mapfile`]).
    pub fn from_map_file(map: &mapfile::MapImage) -> Self {
        Self::from_classes(map.geometry, |cell| map.cells[cell])
    }

    /// Binary PGM (P5) bytes, as [`mapfile::encode_pgm`] writes them.
    pub fn to_pgm(&self) -> Vec<u8> {
        let mut out = format!("P5\n{} {}\n255\n", self.width, self.height).into_bytes();
        out.extend(self.pixels.iter().map(|&p| pgm_value(pixel_class(p))));
        out
    }

    /// The map_server YAML beside `image` (a file name in the same directory), as
    /// [`mapfile::yaml_text`] writes it.
    pub fn to_yaml(&self, image: &str) -> String {
        let g = GridGeometry {
            width: self.width,
            height: self.height,
            resolution_m: self.resolution_m,
            origin: Point2::new(self.origin_x_m, self.origin_y_m),
        };
        mapfile::yaml_text(&g, image)
    }

    /// Parses an image (PGM or PNG) and its YAML with the map files' reader
    /// ([`mapfile::parse_map`]: comments, thresholds, negate, flow or block style); errors name
    /// `map.yaml` or `map.pgm`.
    pub fn from_pgm_yaml(pgm: &[u8], yaml: &str) -> Result<Self, PersistError> {
        let map = mapfile::parse_map(Path::new("map.yaml"), yaml, |_| Ok(pgm.to_vec()))
            .map_err(|e| PersistError::Corrupt(e.to_string()))?;
        Ok(Self::from_map_file(&map))
    }

    /// Writes the map as a picture a person can read (`map.png`): the map (free white,
    /// unknown grey, occupied black; [`crate::picture::picture_scale`] pixels a cell) with the
    /// trajectory, the chosen targets, the start and robot marks, a scale bar and a legend
    /// ([`crate::picture::render_picture`], the drawing of `papillon-sim mission --png`).
    pub fn write_png(
        &self,
        path: &Path,
        track: &crate::picture::Track,
    ) -> Result<(), PersistError> {
        if self.pixels.len() != self.width * self.height {
            return Err(PersistError::Corrupt(
                "map size does not match its pixels".into(),
            ));
        }
        let g = GridGeometry {
            width: self.width,
            height: self.height,
            resolution_m: self.resolution_m,
            origin: Point2::new(self.origin_x_m, self.origin_y_m),
        };
        // Flat index: row 0 south; the pixels' first row is the north edge.
        let class = |i: usize| {
            let (row, col) = (i / self.width, i % self.width);
            pixel_class(self.pixels[(self.height - 1 - row) * self.width + col])
        };
        let img = crate::picture::render_picture(
            &g,
            class,
            core::slice::from_ref(track),
            crate::picture::picture_scale(&g),
        );
        let mut bytes = Vec::new();
        img.write_to(&mut io::Cursor::new(&mut bytes), image::ImageFormat::Png)
            .map_err(|e| PersistError::Io(io::Error::other(e)))?;
        write_atomic(path, &bytes)?;
        Ok(())
    }
}

/// Errors saving or loading the mission state.
#[derive(Debug)]
#[non_exhaustive]
pub enum PersistError {
    /// A file could not be read or written.
    Io(io::Error),
    /// A file exists but does not parse; names the file and the problem.
    Corrupt(String),
}

impl std::fmt::Display for PersistError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PersistError::Io(e) => write!(f, "{e}"),
            PersistError::Corrupt(what) => write!(f, "saved mission state is damaged: {what}"),
        }
    }
}

impl std::error::Error for PersistError {}

impl From<io::Error> for PersistError {
    fn from(e: io::Error) -> Self {
        PersistError::Io(e)
    }
}

/// The files of one mission in its log directory.
pub const MISSION_FILES: [&str; 5] = [
    "state.json",
    "map.pgm",
    "map.yaml",
    "map.png",
    "telemetry.jsonl",
];

/// The mission state files of a log directory.
#[derive(Clone, Debug)]
pub struct StateStore {
    dir: PathBuf,
}

impl StateStore {
    /// The store in `dir`, created if needed.
    pub fn open(dir: &Path) -> io::Result<Self> {
        fs::create_dir_all(dir)?;
        Ok(Self {
            dir: dir.to_path_buf(),
        })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn write_map(&self, map: &MapImage) -> io::Result<()> {
        write_atomic(&self.dir.join("map.pgm"), &map.to_pgm())?;
        write_atomic(
            &self.dir.join("map.yaml"),
            map.to_yaml("map.pgm").as_bytes(),
        )
    }

    /// Saves the map (if given) then the state, each atomically.
    pub fn save(&self, state: &MissionState, map: Option<&MapImage>) -> Result<(), PersistError> {
        if let Some(map) = map {
            self.write_map(map)?;
        }
        let json =
            serde_json::to_vec_pretty(state).map_err(|e| PersistError::Io(io::Error::other(e)))?;
        write_atomic(&self.dir.join("state.json"), &json)?;
        Ok(())
    }

    /// Moves the files of the mission saved here (state, map, telemetry) into the first free
    /// `previous-N/` subdirectory and returns it; `Ok(None)` when there was nothing to move.
    pub fn set_aside(&self) -> io::Result<Option<PathBuf>> {
        let present: Vec<&str> = MISSION_FILES
            .iter()
            .copied()
            .filter(|f| fs::symlink_metadata(self.dir.join(f)).is_ok())
            .collect();
        if present.is_empty() {
            return Ok(None);
        }
        let aside = (1u32..)
            .map(|n| self.dir.join(format!("previous-{n}")))
            .find(|d| fs::symlink_metadata(d).is_err())
            .ok_or_else(|| io::Error::other("no free previous-N directory"))?;
        fs::create_dir(&aside)?;
        for f in present {
            fs::rename(self.dir.join(f), aside.join(f))?;
        }
        File::open(&self.dir)?.sync_all()?;
        Ok(Some(aside))
    }

    /// Loads the last saved state and map; `Ok(None)` when nothing was saved yet.
    pub fn load(&self) -> Result<Option<(MissionState, Option<MapImage>)>, PersistError> {
        let state_path = self.dir.join("state.json");
        let text = match read_limited(&state_path, MAP_MAX_BYTES) {
            Ok(t) => t,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
            Err(e) => {
                return Err(PersistError::Io(io::Error::new(
                    e.kind(),
                    format!("{}: {e}", state_path.display()),
                )));
            }
        };
        let state: MissionState = serde_json::from_slice(&text)
            .map_err(|e| PersistError::Corrupt(format!("{}: {e}", state_path.display())))?;
        if state.version != STATE_VERSION {
            return Err(PersistError::Corrupt(format!(
                "{}: version {} (this program reads version {STATE_VERSION})",
                state_path.display(),
                state.version
            )));
        }
        if let Some(why) = state.implausible() {
            return Err(PersistError::Corrupt(format!(
                "{}: {why}",
                state_path.display()
            )));
        }
        // The map through the map files' reader: `map.yaml` and the image it names (a map
        // edited by hand, or saved as PNG, reads back too); errors name the file.
        let yaml_path = self.dir.join("map.yaml");
        let map = if yaml_path.exists() {
            let map =
                mapfile::read_map(&yaml_path).map_err(|e| PersistError::Corrupt(e.to_string()))?;
            Some(MapImage::from_map_file(&map))
        } else {
            None
        };
        Ok(Some((state, map)))
    }
}

/// The telemetry log: one JSON object per line, each with `t_s` (mission time \[s\]) and `kind`.
pub struct Telemetry {
    out: BufWriter<File>,
    /// Each `decision` record's (first) target, in order, for `map.png`.
    targets: Vec<Point2>,
}

impl Telemetry {
    /// Opens (appends to) `telemetry.jsonl` in `dir`.
    pub fn open(dir: &Path) -> io::Result<Self> {
        fs::create_dir_all(dir)?;
        let f = open_log(&dir.join("telemetry.jsonl"), Existing::Append)?;
        Ok(Self {
            out: BufWriter::new(f),
            targets: Vec::new(),
        })
    }

    /// The target of each `decision` record written so far (its `target_x_m`, `target_y_m`:
    /// the decision's first target), oldest first.
    pub fn targets(&self) -> &[Point2] {
        &self.targets
    }

    /// Writes one record: `{"t_s": t_s, "kind": kind, ...fields}`.
    pub fn record(&mut self, t_s: f64, kind: &str, fields: serde_json::Value) -> io::Result<()> {
        let mut obj = serde_json::Map::new();
        obj.insert("t_s".into(), serde_json::json!(t_s));
        obj.insert("kind".into(), serde_json::json!(kind));
        if kind == "decision"
            && let (Some(x), Some(y)) =
                (fields["target_x_m"].as_f64(), fields["target_y_m"].as_f64())
        {
            self.targets.push(Point2::new(x as f32, y as f32));
        }
        if let serde_json::Value::Object(m) = fields {
            obj.extend(m);
        }
        serde_json::to_writer(&mut self.out, &serde_json::Value::Object(obj))?;
        self.out.write_all(b"\n")
    }

    /// A pose record.
    pub fn pose(&mut self, t_s: f64, pose: PoseRecord) -> io::Result<()> {
        self.record(
            t_s,
            "pose",
            serde_json::json!({"x_m": pose.x_m, "y_m": pose.y_m, "theta_rad": pose.theta_rad}),
        )
    }

    /// A target decision with its compute time \[ms\].
    pub fn decision(
        &mut self,
        t_s: f64,
        target_x_m: f32,
        target_y_m: f32,
        compute_ms: f64,
    ) -> io::Result<()> {
        self.record(
            t_s,
            "decision",
            serde_json::json!({"target_x_m": target_x_m, "target_y_m": target_y_m, "compute_ms": compute_ms}),
        )
    }

    /// A coverage record (known-area fraction).
    pub fn coverage(&mut self, t_s: f64, coverage: f32) -> io::Result<()> {
        self.record(t_s, "coverage", serde_json::json!({"coverage": coverage}))
    }

    /// A fault (why the robot stopped).
    pub fn fault(&mut self, t_s: f64, what: &str) -> io::Result<()> {
        self.record(t_s, "fault", serde_json::json!({"fault": what}))
    }

    /// Link statistics.
    pub fn link_stats(&mut self, t_s: f64, stats: &super::robot::SessionStats) -> io::Result<()> {
        self.record(
            t_s,
            "link",
            serde_json::json!({
                "commands_sent": stats.commands_sent,
                "pulses_sent": stats.pulses_sent,
                "status_packets": stats.status_packets,
                "packets": stats.codec.packets,
                "bad_checksums": stats.codec.bad_checksums,
                "junk_bytes": stats.codec.junk_bytes,
                "bad_payloads": stats.codec.bad_payloads,
            }),
        )
    }

    /// Flushes buffered lines to the file.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()?;
        self.out.get_ref().sync_data()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("papillon-persist-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn sample_map() -> MapImage {
        MapImage {
            width: 3,
            height: 2,
            resolution_m: 0.1,
            origin_x_m: -1.5,
            origin_y_m: -2.0,
            pixels: vec![0, 254, 205, 205, 254, 0],
        }
    }

    fn sample_state(n: usize) -> MissionState {
        MissionState {
            version: STATE_VERSION,
            mission_time_s: 12.5,
            pose: PoseRecord {
                x_m: 1.0,
                y_m: 2.0,
                theta_rad: 0.5,
            },
            odom_pose: PoseRecord::default(),
            trajectory: (0..n)
                .map(|i| PoseRecord {
                    x_m: i as f32 * 0.1,
                    y_m: 0.0,
                    theta_rad: 0.0,
                })
                .collect(),
            counters: Counters {
                decisions: 3,
                distance_m: 4.5,
                ..Counters::default()
            },
            coverage: 0.42,
            finished: false,
        }
    }

    #[test]
    fn save_then_load_round_trips() {
        let dir = temp_dir("roundtrip");
        let store = StateStore::open(&dir).unwrap();
        assert!(store.load().unwrap().is_none());
        store.save(&sample_state(10), Some(&sample_map())).unwrap();
        let (state, map) = store.load().unwrap().unwrap();
        assert_eq!(state, sample_state(10));
        assert_eq!(map.unwrap(), sample_map());
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
            .collect();
        assert!(leftovers.is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn set_aside_moves_the_mission_into_the_next_free_previous_dir() {
        let dir = temp_dir("aside");
        let store = StateStore::open(&dir).unwrap();
        assert_eq!(store.set_aside().unwrap(), None);
        store.save(&sample_state(3), Some(&sample_map())).unwrap();
        fs::create_dir(dir.join("previous-1")).unwrap();
        let aside = store.set_aside().unwrap().unwrap();
        assert_eq!(aside, dir.join("previous-2"));
        assert!(store.load().unwrap().is_none());
        let moved = StateStore::open(&aside).unwrap().load().unwrap().unwrap();
        assert_eq!(moved.0, sample_state(3));
        assert_eq!(moved.1.unwrap(), sample_map());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_partial_temp_file_does_not_corrupt_the_last_good_state() {
        let dir = temp_dir("partial");
        let store = StateStore::open(&dir).unwrap();
        store.save(&sample_state(5), Some(&sample_map())).unwrap();
        // A save interrupted by a power cut: half-written temporary files beside the good ones.
        fs::write(
            dir.join(".state.json.tmp.99999"),
            b"{\"version\": 1, \"missi",
        )
        .unwrap();
        fs::write(dir.join(".map.pgm.tmp.99999"), b"P5\n3 2\n255\n\x00").unwrap();
        let (state, map) = store.load().unwrap().unwrap();
        assert_eq!(state, sample_state(5));
        assert_eq!(map.unwrap(), sample_map());
        // The next save replaces the state whole.
        store.save(&sample_state(7), None).unwrap();
        assert_eq!(store.load().unwrap().unwrap().0.trajectory.len(), 7);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn damaged_files_are_reported_not_trusted() {
        let dir = temp_dir("damaged");
        let store = StateStore::open(&dir).unwrap();
        fs::write(dir.join("state.json"), b"{\"version\": 1, \"missi").unwrap();
        let err = store.load().unwrap_err();
        assert!(
            matches!(err, PersistError::Corrupt(ref m) if m.contains("state.json")),
            "{err}"
        );
        store.save(&sample_state(1), Some(&sample_map())).unwrap();
        fs::write(dir.join("map.pgm"), b"P5\n3 2\n255\n\x00\x00").unwrap();
        assert!(matches!(store.load(), Err(PersistError::Corrupt(m)) if m.contains("map.pgm")));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn write_atomic_replaces_whole_files() {
        let dir = temp_dir("atomic");
        let p = dir.join("f.txt");
        write_atomic(&p, b"first version, longer").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn map_from_grid_puts_north_first() {
        use crate::geometry::Point2;
        use crate::grid::{Cell, GridGeometry, LogOddsBounds};
        let g = GridGeometry::new(2, 2, 0.5, Point2::new(0.0, 0.0)).unwrap();
        let mut grid = OccupancyGrid::<4>::new(g, LogOddsBounds::default()).unwrap();
        let i = g.index(Cell::new(0, 0)).unwrap();
        grid.set_class(i, CellClass::Occupied, &mut ());
        let j = g.index(Cell::new(1, 1)).unwrap();
        grid.set_class(j, CellClass::Free, &mut ());
        let m = MapImage::from_grid(&grid);
        // Row 0 of the image is the north row (grid row 1).
        assert_eq!(m.pixels, [PGM_UNKNOWN, PGM_FREE, PGM_OCCUPIED, PGM_UNKNOWN]);
        let back = MapImage::from_pgm_yaml(&m.to_pgm(), &m.to_yaml("map.pgm")).unwrap();
        assert_eq!(back, m);
        // Restoring into a fresh grid gives the same classes.
        let mut restored = OccupancyGrid::<4>::new(g, LogOddsBounds::default()).unwrap();
        back.apply_to_grid(&mut restored).unwrap();
        for idx in 0..4 {
            assert_eq!(restored.class(idx), grid.class(idx), "cell {idx}");
        }
        assert_eq!(restored.counts(), grid.counts());
        // A grid of another size is refused.
        let other = GridGeometry::new(1, 2, 0.5, Point2::new(0.0, 0.0)).unwrap();
        let mut small = OccupancyGrid::<4>::new(other, LogOddsBounds::default()).unwrap();
        assert!(back.apply_to_grid(&mut small).is_err());
    }

    #[test]
    fn telemetry_lines_are_json_objects() {
        let dir = temp_dir("telemetry");
        let mut t = Telemetry::open(&dir).unwrap();
        t.pose(
            0.5,
            PoseRecord {
                x_m: 1.0,
                y_m: 0.0,
                theta_rad: 0.0,
            },
        )
        .unwrap();
        t.fault(1.0, "no laser scan").unwrap();
        t.flush().unwrap();
        let text = fs::read_to_string(dir.join("telemetry.jsonl")).unwrap();
        let lines: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(lines.len(), 2);
        assert_eq!(lines[0]["kind"], "pose");
        assert_eq!(lines[1]["fault"], "no laser scan");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_is_written() {
        let dir = temp_dir("png");
        let track = crate::picture::Track {
            trajectory: vec![Point2::new(0.2, 0.2), Point2::new(0.4, 0.3)],
            targets: vec![Point2::new(0.5, 0.5)],
        };
        sample_map()
            .write_png(&dir.join("map.png"), &track)
            .unwrap();
        let bytes = fs::read(dir.join("map.png")).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        fs::remove_dir_all(&dir).unwrap();
    }
}
