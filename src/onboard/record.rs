//! `papillon run`'s mission recording: `mission.mcap` in the log directory, written by the
//! mission thread ([`super::mission`]) with [`crate::record::Recorder`] (the channels and
//! schemas are listed there), so that a lab can open the run in Foxglove afterwards.
//!
//! What is written, at mission time plus the wall clock at the start (so Foxglove shows the
//! real date and time):
//! - each status packet: the odometry pose (`/pose/odometry`, frame `odom`) and the mission's
//!   estimate (`/pose/estimated`, and `map` → `base_link` on `/tf`), and the path when it
//!   changed (`/path`);
//! - each scan integrated into the map (`/scan`), at the laser's pose in the map;
//! - each decision: the targets (`/targets`), its figures (`/decisions`) and the map (`/map`):
//!   the map only once per decision (and at the start and the end), which keeps the file small;
//! - at the end (the mission done, or the runtime closing it), the final map; then the file's
//!   summary and footer. A recording cut short (`kill -9`, a power cut) keeps every complete
//!   chunk: MCAP readers read it up to there.
//!
//! With `papillon run --live ADDR` the same messages are served live ([`crate::live`]).
//!
//! A write error stops the recording (logged once), never the mission (and with it the live
//! view).

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use crate::geometry::{Point2, Pose2};
use crate::grid::OccupancyGrid;
use crate::record::{PoseSource, RecordError, Recorder};
use crate::sensor::Scan;

/// The recording's file name in the log directory.
pub const FILE_NAME: &str = "mission.mcap";

/// Where a run logging into `log_dir` records: `mission.mcap`, or after `--resume`
/// (`resumed`) the first free `mission-2.mcap`, `mission-3.mcap`, ... so that the recording of
/// the first part is kept.
pub fn recording_path(log_dir: &Path, resumed: bool) -> PathBuf {
    let first = log_dir.join(FILE_NAME);
    if !resumed || !first.exists() {
        return first;
    }
    (2u32..)
        .map(|n| log_dir.join(format!("mission-{n}.mcap")))
        .find(|p| !p.exists())
        .unwrap_or(first)
}

/// The mission thread's recording (single robot, topics without a robot prefix).
pub struct MissionRecording {
    recorder: Option<Recorder<std::io::BufWriter<std::fs::File>>>,
    path: PathBuf,
    started: bool,
}

impl std::fmt::Debug for MissionRecording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MissionRecording")
            .field("path", &self.path)
            .field("open", &self.recorder.is_some())
            .finish()
    }
}

impl MissionRecording {
    /// Creates `path`; mission time `mission_time_s` is now (so the file's times are the wall
    /// clock). With `live`, every message is also served to the live view. The error names the
    /// file.
    pub fn create(
        path: &Path,
        mission_time_s: f64,
        live: Option<crate::live::LiveServer>,
    ) -> Result<Self, String> {
        let now_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let base_ns = now_ns.saturating_sub((mission_time_s.max(0.0) * 1e9) as u64);
        let mut recorder = Recorder::create(path, 1, base_ns)?;
        if let Some(live) = live {
            recorder = recorder.with_live(live);
        }
        Ok(Self {
            recorder: Some(recorder),
            path: path.to_path_buf(),
            started: false,
        })
    }

    fn with(
        &mut self,
        f: impl FnOnce(&mut Recorder<std::io::BufWriter<std::fs::File>>) -> Result<(), RecordError>,
    ) {
        let Some(rec) = &mut self.recorder else {
            return;
        };
        if let Err(e) = f(rec) {
            tracing::warn!(file = %self.path.display(), error = %e, "recording stopped");
            self.recorder = None;
        }
    }

    /// A status packet was applied: the odometry and estimated poses, and the path.
    pub fn status<const N: usize>(
        &mut self,
        t_s: f64,
        odometry: Pose2,
        estimated: Pose2,
        path: &[Point2],
        grid: &OccupancyGrid<N>,
    ) {
        let first = !self.started;
        self.started = true;
        self.with(|rec| {
            if first {
                rec.map(t_s, grid)?;
            }
            rec.pose(t_s, 0, PoseSource::Odometry, odometry)?;
            rec.pose(t_s, 0, PoseSource::Estimated, estimated)?;
            rec.path(t_s, 0, path)
        });
    }

    /// A scan was integrated from the laser pose `laser_map`.
    pub fn scan(&mut self, t_s: f64, laser_map: Pose2, scan: &Scan) {
        self.with(|rec| rec.scan(t_s, 0, laser_map, scan));
    }

    /// A decision: its targets and figures, the path and the map.
    pub fn decision<const N: usize>(
        &mut self,
        t_s: f64,
        targets: &[Point2],
        fields: serde_json::Value,
        path: &[Point2],
        grid: &OccupancyGrid<N>,
    ) {
        self.with(|rec| {
            rec.targets(t_s, 0, targets)?;
            rec.decision(t_s, 0, targets, fields)?;
            rec.path(t_s, 0, path)?;
            rec.map(t_s, grid)
        });
    }

    /// The final map, then the file's summary and footer.
    pub fn finish<const N: usize>(&mut self, t_s: f64, grid: &OccupancyGrid<N>) {
        self.with(|rec| rec.map(t_s, grid));
        if let Some(rec) = self.recorder.take()
            && let Err(e) = rec.finish()
        {
            tracing::warn!(file = %self.path.display(), error = %e, "recording not finished");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resumed_run_records_next_to_the_first_recording() {
        let dir = std::env::temp_dir().join(format!("papillon-rec-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(recording_path(&dir, true), dir.join("mission.mcap"));
        std::fs::write(dir.join("mission.mcap"), b"x").unwrap();
        assert_eq!(recording_path(&dir, false), dir.join("mission.mcap"));
        assert_eq!(recording_path(&dir, true), dir.join("mission-2.mcap"));
        std::fs::write(dir.join("mission-2.mcap"), b"x").unwrap();
        assert_eq!(recording_path(&dir, true), dir.join("mission-3.mcap"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
