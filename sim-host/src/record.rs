//! `papillon-sim mission --mcap FILE`: a simulated mission recorded as MCAP with Foxglove's
//! schemas ([`papillon::record`], where the channels are listed), fed from the runner's
//! observer ([`crate::runner::Progress`]).
//!
//! What is written, in simulated time (the recording starts at time 0):
//! - each scan of each robot (`/scan`), at the laser's pose on the mission's estimate (where
//!   the mission mapped it);
//! - each control period (10 Hz), each robot's odometry, estimated and true pose
//!   (`/pose/odometry`, `/pose/estimated`, `/pose/true`) and its path when it changed (`/path`);
//! - each decision: the targets (`/targets`), the decision's figures (`/decisions`) and the
//!   map (`/map`): the map only once per decision (and at the start and the end), which keeps
//!   the file small;
//! - at the end, the final map.
//!
//! With `--live ADDR` the same messages are served live to Foxglove ([`papillon::live`]) and
//! the run is paced to `--live-speed` simulated seconds per second, so that a viewer sees it.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::time::{Duration, Instant};

use papillon::mission::MissionEvent;
use papillon::record::{PoseSource, Recorder};
use serde_json::json;

use crate::runner::{Progress, Runner};

/// A mission recording fed by [`Runner::run_with`]'s observer.
#[derive(Debug)]
pub struct RunRecorder {
    recorder: Recorder<BufWriter<File>>,
    /// The first error (the recording stops there; the run goes on).
    error: Option<String>,
    /// Whether the map was recorded at the start.
    started: bool,
    /// With a live view: the wall clock at the start and the simulated seconds per wall-clock
    /// second, to pace the run so that a viewer sees it happen.
    pace: Option<(Instant, f64)>,
}

/// `papillon-sim mission --live ADDR --live-speed X`: the live view's address and the
/// simulated seconds per wall-clock second.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveOptions {
    /// `host:port` to listen on.
    pub addr: String,
    /// Simulated seconds per wall-clock second (> 0).
    pub speed: f64,
}

impl RunRecorder {
    /// Creates `path` for a run of `robots` robots; the error names the file.
    pub fn create(path: &Path, robots: usize) -> Result<Self, String> {
        Ok(Self {
            recorder: Recorder::create(path, robots, 0)?,
            error: None,
            started: false,
            pace: None,
        })
    }

    /// A recording into `mcap` (when given) and/or served live (when `live` is given: the run
    /// is then paced at `live.speed` simulated seconds per second). The error names the file
    /// or the address (prefixed with its option).
    pub fn open(
        mcap: Option<&Path>,
        live: Option<&LiveOptions>,
        robots: usize,
    ) -> Result<Option<Self>, String> {
        let server = match live {
            Some(l) => {
                Some(papillon::live::LiveServer::bind(&l.addr).map_err(|e| format!("--live {e}"))?)
            }
            None => None,
        };
        let recorder = match (mcap, server) {
            (None, None) => return Ok(None),
            (Some(path), None) => Recorder::create(path, robots, 0),
            (Some(path), Some(server)) => {
                Recorder::create(path, robots, 0).map(|r| r.with_live(server))
            }
            (None, Some(server)) => Ok(Recorder::live_only(server, robots, 0)),
        }
        .map_err(|e| format!("--mcap: {e}"))?;
        if let Some(addr) = recorder.live_addr() {
            eprintln!("live view: ws://{addr} (Foxglove: Open connection → Foxglove WebSocket)");
        }
        Ok(Some(Self {
            recorder,
            error: None,
            started: false,
            pace: live.map(|l| (Instant::now(), l.speed)),
        }))
    }

    /// Records what `progress` says happened in `runner`.
    pub fn observe<const N: usize>(&mut self, runner: &Runner<N>, progress: Progress) {
        if let Some((start, speed)) = self.pace
            && matches!(progress, Progress::Controlled)
        {
            let due = Duration::from_secs_f64(runner.sim_time_s() / speed);
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        if self.error.is_some() {
            return;
        }
        if let Err(e) = self.record(runner, progress) {
            self.error = Some(e.to_string());
        }
    }

    fn record<const N: usize>(
        &mut self,
        runner: &Runner<N>,
        progress: Progress,
    ) -> Result<(), papillon::record::RecordError> {
        let t = runner.sim_time_s();
        let rec = &mut self.recorder;
        if !self.started {
            self.started = true;
            rec.map(t, &runner.map().grid)?;
        }
        match progress {
            Progress::Scanned { robot } => {
                let mission = runner.mission(robot);
                let laser = mission.pose_map().compose(mission.config().laser.mount);
                rec.scan(t, robot, laser, runner.last_scan(robot))?;
            }
            Progress::Controlled => {
                for k in 0..runner.robot_count() {
                    let body = runner.body(k);
                    let mission = runner.mission(k);
                    rec.pose(t, k, PoseSource::Odometry, body.odometry_pose())?;
                    rec.pose(t, k, PoseSource::Estimated, mission.pose_map())?;
                    rec.pose(t, k, PoseSource::True, body.true_pose())?;
                    rec.path(t, k, mission.path())?;
                }
            }
            Progress::Decided { robot } => {
                let decided = runner.events().iter().rev().find_map(|e| match &e.event {
                    MissionEvent::Decided {
                        targets,
                        path_length_m,
                        predicted_gain_cells,
                        energy_steps,
                        evaluations,
                    } if e.robot == robot => Some((
                        targets.clone(),
                        json!({
                            "path_length_m": path_length_m,
                            "predicted_gain_cells": predicted_gain_cells,
                            "energy_steps": energy_steps,
                            "evaluations": evaluations,
                            "coverage": runner.coverage(),
                            "battery_steps": runner.mission(robot).battery_steps(),
                        }),
                    )),
                    _ => None,
                });
                if let Some((targets, fields)) = decided {
                    rec.targets(t, robot, &targets)?;
                    rec.decision(t, robot, &targets, fields)?;
                }
                rec.path(t, robot, runner.mission(robot).path())?;
                rec.map(t, &runner.map().grid)?;
            }
            Progress::Finished => rec.map(t, &runner.map().grid)?,
        }
        Ok(())
    }

    /// Finishes the file (summary, footer); the error is the first one of the recording.
    pub fn finish(self) -> Result<(), String> {
        if let Some(e) = self.error {
            return Err(e);
        }
        self.recorder.finish().map_err(|e| e.to_string())
    }
}
