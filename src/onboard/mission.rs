//! The core mission ([`crate::mission::Mission`]) behind the runtime's [`MissionDriver`].
//!
//! The mission runs on its own thread (a "mission thread"): a decision by a population
//! optimizer can take seconds, and while it runs the runtime must keep reading status packets
//! and scans, keep the link alive and watch the stale-data timeouts. The runtime side
//! ([`CoreMission`]) only posts inputs and picks up results, never waits for the thread:
//! - status packets become odometry ([`ArcosOdometry`] over the SIP's XPOS/YPOS/THPOS) and
//!   [`RobotFlags`] (STALL AND BUMPERS, FLAGS);
//! - scans are integrated into the shared map, every one of them, each at the odometry pose
//!   interpolated to its time ([`PoseHistory`], the odometry readings of the last seconds with
//!   their times): a scan waits for the status packet after it, and the mission then sees
//!   the pose at the scan's time, the scan, and the packet's pose, in time order (the
//!   interpolated pose lies on the way between the two readings, so the distance and energy
//!   counted on odometry are unchanged). A scan while the robot turns faster than
//!   [`MAX_MAPPING_TURN_RAD`] per status period (20 deg/s) only feeds the safety monitor: its
//!   time is its arrival in the pump, a few milliseconds after the laser took it, and at the
//!   60 deg/s of a turn in place that is enough to fan the walls out across the map (seen
//!   end to end under load before the interpolation: phantom walls inside the lab, every
//!   path then cut, the robot turning in place until the battery ran out); nor does a scan
//!   in a gap of the odometry longer than [`MAX_ODOMETRY_GAP_S`] (after a stall);
//! - the mission steps right after each status packet (at most every [`MIN_STEP_S`], at least
//!   every [`STEP_FALLBACK_S`]), so a command is computed from the freshest pose; each new
//!   command is handed to the runtime once; between periods the runtime is told to
//!   hold (nothing re-sent, so a slow serial link is not flooded). If the thread has produced
//!   no command for [`BUSY_STOP_S`] while the last one moved the robot, the runtime is told to
//!   stop: a stale velocity is never kept;
//! - a fault the runtime detected (stale data, link loss, e-stop, contact) is passed to the
//!   core as one period with the motors reported disabled: the core drops its path, and when
//!   the real flags come back it re-plans from where the robot is. [`MissionDriver::replanned`]
//!   is true once the core reported that re-plan (`FaultCleared`, `Replanned` or `Decided`)
//!   for a period after the fault;
//! - the state to save (map image, poses, trajectory, counters) is published by the thread
//!   every [`PUBLISH_EVERY_S`] of mission time and at the end;
//! - with a recording ([`CoreMission::recorded`], what `papillon run` uses), the thread also
//!   writes the poses, scans, path, decisions and map to an MCAP file
//!   ([`super::record`]), finished when the mission ends or the runtime drops the mission.
//!
//! Resuming (`--resume`): the saved map is loaded into the grid; the first odometry reading
//! after the restart is placed with the saved odometry-to-map transform when the robot's
//! counters continued (a restarted program, the robot untouched: within
//! [`CONTINUED_ODOMETRY_M`] of the saved odometry), else at the saved map pose (the counters were
//! reset with the robot).

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant as WallInstant;

use super::driver::{MissionCommand, MissionDriver, TelemetryRecord};
use super::persist::{Counters, MapImage, MissionState as SavedState, PoseRecord, STATE_VERSION};
use super::pose_history::{PoseAt, PoseHistory};
use super::record::MissionRecording;
use super::robot::Fault;
use crate::config::{BoardConfig, Strategy};
use crate::control::Time;
use crate::control::command::{Limits, Velocity};
use crate::control::odometry::{ArcosOdometry, MapFromOdom};
use crate::control::safety::RobotFlags;
use crate::geometry::normalize_angle;
use crate::geometry::{Point2, Pose2};
use crate::grid::{CellClass, GridGeometry};
use crate::mission::{
    DoneReason, Mission, MissionConfig, MissionEvent, SelectorKind, SharedMap, Workspace,
};
use crate::optim::Method;
use crate::sensor::Scan;
use crate::wire::arcos::StatusPacket;

/// The nominal wheelbase the odometry corrections are computed with when the board names
/// none (`papillon calibrate --wheelbase-mm`'s default) \[m\].
pub const DEFAULT_WHEELBASE_M: f32 = 0.33;

/// Most cells the onboard grid can hold: the largest capacity of [`crate::capacity`] (2048 x
/// 2048, a 200 m square at 10 cm; with the feature `fixed-capacity`, 512 x 512). The mission
/// is built for the smallest capacity that holds the board's `$.grid`, so memory follows the
/// board's area.
pub const GRID_CELLS: usize = crate::capacity::MAX_CELLS;
/// The mission steps after each status packet (the P3-DX sends one every 100 ms), at most
/// this often \[s\]...
pub const MIN_STEP_S: f64 = 0.05;
/// ...and at least this often, status packets or not \[s\].
pub const STEP_FALLBACK_S: f64 = 0.15;
/// With no new command for this long after a moving one, the runtime is told to stop \[s\].
pub const BUSY_STOP_S: f64 = 0.3;
/// Scans kept while they wait for the status packet after them (more are dropped, oldest
/// first): 0.32 s of scans at the LMS1xx board's 25 Hz, 0.16 s at `boards/sim.json`'s 50 Hz.
pub const PENDING_SCANS: usize = 8;
/// A turn between two status packets (100 ms apart) above which a scan between them is not
/// mapped \[rad\] (2°).
pub const MAX_MAPPING_TURN_RAD: f32 = 0.035;
/// A gap between two odometry readings above which a scan in it is not mapped \[s\] (2.5
/// status periods: one packet lost to a bad checksum still maps). After a stall of the pump or
/// of the link the queued packets arrive, and are placed, together at its end: a scan taken in
/// the gap, placed by the laser's own clock, would be interpolated between the reading before
/// the gap and the first queued one, up to 60° off in a turn in place, at a turn rate that
/// looks slow (seen on the house with the matcher on at load 16: a 0.8 s stall in a turn, the
/// pose 54° off for the rest of the mission).
pub const MAX_ODOMETRY_GAP_S: f64 = 0.25;
/// The mission ends as explored when this many decisions in a row...
pub const STALL_DECISIONS: usize = 5;
/// ...added fewer known cells than this between them...
pub const STALL_NEW_CELLS: usize = 100;
/// ...while the robot spent at least this much energy on them \[steps\]: what is left
/// Unknown next to Free cells cannot be seen (the inside of an obstacle behind a cell of its
/// wall that noise marked Free), and the core would otherwise chase it until the battery is
/// spent (see `Stall`). 15 steps (15 m of driving): the efficient objective's decisions are
/// short (about 2.5 steps each on the lab), and with 5 steps it ended a lab mission with small
/// unknown pockets still to clear (94.7 %, seed 5 at 0.1 % corruption).
pub const STALL_STEPS: f32 = 15.0;
/// The mission also ends as explored when this many decisions in a row added fewer than
/// [`STALL_NEW_CELLS`] known cells, however little the robot drove for them: a decision whose
/// target is where the robot stands (its predicted scan looking at Unknown space that the
/// laser, facing elsewhere, never sees) is decided again and again without moving. Measured
/// on the house with a noise-free laser: 3959 such decisions in 400 s, the robot standing,
/// until the check's time limit.
pub const STALL_IDLE_DECISIONS: usize = 50;
/// The state to save is published at least this often \[s of mission time\].
pub const PUBLISH_EVERY_S: f64 = 1.0;
/// After `--resume`, odometry within this distance of the saved odometry counts as continued
/// \[m\].
pub const CONTINUED_ODOMETRY_M: f32 = 3.0;
/// Trajectory points kept in the saved state (older ones are thinned out).
pub const MAX_TRAJECTORY: usize = 4000;

/// The grid geometry a board asks for, checked against [`GRID_CELLS`].
pub fn grid_geometry(board: &BoardConfig) -> Result<GridGeometry, String> {
    let g = &board.grid;
    let geometry = GridGeometry::from_extent(
        g.width_m,
        g.height_m,
        g.resolution_m,
        Point2::new(g.origin_x_m, g.origin_y_m),
    )
    .map_err(|e| format!("$.grid: {e}"))?;
    if geometry.cell_count() > GRID_CELLS {
        return Err(format!(
            "$.grid: {} x {} cells, this build holds at most {GRID_CELLS}; use a coarser $.grid.resolution_m or a smaller area",
            geometry.width, geometry.height
        ));
    }
    Ok(geometry)
}

/// The core mission configuration of a board: [`MissionConfig::default`] (the runner's set-up)
/// with what the board says (selector, battery, laser, optimizer budget, limits, PID gains,
/// safety distances, the body and its clearance with the planning layer they make at the
/// grid's cell size, scan matching); `boards/sim-thesis.json` says what the runner's defaults say
/// (the thesis's laser, no matcher), so that `papillon-sim mission` predicts `papillon run` on
/// the simulator; `boards/sim.json` is the same robot with its LMS1xx described as it is and
/// the matcher on (`onboard_compare` gives the runner a board's set-up).
pub fn mission_config(board: &BoardConfig) -> Result<MissionConfig, String> {
    let m = &board.mission;
    let selector = match m.method.as_str() {
        "nearest-frontier" => SelectorKind::NearestFrontier,
        "frontier-utility" => SelectorKind::FrontierUtility,
        name => SelectorKind::Optimized(
            Method::ALL
                .into_iter()
                .find(|method| method.name() == name)
                .ok_or_else(|| format!("$.mission.method: unknown method {name:?}"))?,
        ),
    };
    let mut config = MissionConfig {
        selector,
        battery_steps: m.battery_steps,
        coverage_target: m.coverage_target,
        laser: board.laser_config(),
        ..MissionConfig::default()
    };
    config.explore.targets = match board.strategy() {
        Some(Strategy::Long) => usize::from(m.targets).clamp(1, crate::explore::MAX_TARGETS),
        _ => 1,
    };
    config.explore.reserve_steps = m.reserve_steps;
    config.explore.objective = board.objective().unwrap_or_default();
    config.explore.preset = board.preset().unwrap_or(crate::explore::DEFAULT_PRESET);
    config.explore.population = usize::from(m.population);
    config.explore.max_generations = u32::from(m.generations);
    let r = &board.robot;
    let whole = |v: f32| v.round().clamp(0.0, u16::MAX as f32) as u16;
    config.limits = Limits::new(
        whole(r.max_speed_mm_s),
        whole(r.max_turn_rate_deg_s),
        whole(r.accel_mm_s2),
        whole(r.decel_mm_s2),
        whole(r.rot_accel_deg_s2),
        whole(r.rot_accel_deg_s2),
    );
    let f = &mut config.follower;
    f.cruise_speed_mm_s = f.cruise_speed_mm_s.min(r.max_speed_mm_s);
    f.max_turn_rate_deg_s = f.max_turn_rate_deg_s.min(r.max_turn_rate_deg_s);
    f.heading_kp = board.pid.heading_kp;
    f.heading_ki = board.pid.heading_ki;
    f.heading_kd = board.pid.heading_kd;
    f.distance_kd = board.pid.distance_kd;
    let s = &mut config.safety;
    s.max_input_age = core::time::Duration::from_secs_f32(board.safety.stale_timeout_s);
    s.min_clearance_m = board.safety.obstacle_stop_m;
    s.backoff_distance_m = board.safety.back_off_m;
    s.footprint = board.footprint();
    // The planning layer is derived as the runner derives it (`footprint::planning_layer`,
    // through `BoardConfig::planning_layer`) from the board's body, clearance and cell size:
    // with the defaults it is the runner's,
    // which predicts the binary only if both plan alike. (A planning radius of the robot's
    // radius plus the stop distance, as before, made every doorway of the house narrower
    // than in the runner.)
    config.traversability = board.planning_layer();
    let v = &mut config.voltage;
    v.low_v = m.low_voltage_v.unwrap_or(v.low_v);
    v.hold_s = m.low_voltage_hold_s.unwrap_or(v.hold_s);
    config.return_to_start = m.return_to_start.unwrap_or(false);
    config.localize = board.localize_config();
    config.motion_filter = board.motion_filter_config();
    config.grid_bounds = board.grid_bounds().ok_or_else(|| {
        format!(
            "$.mapping.occupied_thresh: must be {}",
            config.grid_bounds.occupied_thresh_range()
        )
    })?;
    config.validate().map_err(|e| format!("$.mission: {e}"))?;
    Ok(config)
}

/// An input for the mission thread.
enum Input {
    Status(f64, Box<StatusPacket>),
    Scan(f64, Box<Scan>),
    Fault,
    Reconnected,
    Step(f64),
    /// The runtime is done with the mission: finish the recording and end the thread.
    Close,
}

/// What the mission thread publishes.
#[derive(Default)]
struct Published {
    /// Commands produced so far, and the last one.
    commands: u64,
    command: Option<MissionCommand>,
    /// Mission time of the last re-plan the core reported \[s\].
    last_plan_s: Option<f64>,
    /// The core's end, or the onboard one ([`END_NOTHING_OBSERVABLE`]).
    done: Option<&'static str>,
    state: SavedState,
    map: Option<MapImage>,
    telemetry: Vec<TelemetryRecord>,
    error: Option<String>,
}

/// The core mission on its own thread, as the runtime's [`MissionDriver`].
pub struct CoreMission {
    tx: Sender<Input>,
    out: Arc<Mutex<Published>>,
    /// When the last step was asked for \[s\].
    step_sent_s: f64,
    /// A status packet arrived since then.
    status_pending: bool,
    /// The latest status packet's time (on the robot's clock, `sensor_clock`) \[s\].
    status_t_s: f64,
    /// The time of the last step asked for, on the mission's clock \[s\]: the status
    /// packet's time for a step after one (the core sees the robot's SIP cycle, not how late
    /// the program read the packet), strictly increasing.
    core_step_s: f64,
    commands_seen: u64,
    last_command_s: f64,
    last_moving: bool,
    fault_at_s: Option<f64>,
    done: bool,
    /// The mission thread (joined, for a bounded time, when the mission is dropped).
    worker: Option<std::thread::JoinHandle<()>>,
}

/// How long dropping a [`CoreMission`] waits for its thread to finish the recording \[s\].
pub const CLOSE_WAIT_S: f64 = 5.0;

impl Drop for CoreMission {
    fn drop(&mut self) {
        let _ = self.tx.send(Input::Close);
        let Some(worker) = self.worker.take() else {
            return;
        };
        // A decision in progress is finished first; never wait for ever.
        let began = WallInstant::now();
        while !worker.is_finished() && began.elapsed().as_secs_f64() < CLOSE_WAIT_S {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        if worker.is_finished() {
            let _ = worker.join();
        }
    }
}

fn lock(m: &Mutex<Published>) -> MutexGuard<'_, Published> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl CoreMission {
    /// A mission for `board`, resumed from `resume` if given. Errors name the board field.
    pub fn new(
        board: &BoardConfig,
        resume: Option<&(SavedState, Option<MapImage>)>,
    ) -> Result<Self, String> {
        Self::recorded(board, resume, None)
    }

    /// [`Self::new`], the mission thread writing `recording` ([`super::record`]).
    pub fn recorded(
        board: &BoardConfig,
        resume: Option<&(SavedState, Option<MapImage>)>,
        recording: Option<MissionRecording>,
    ) -> Result<Self, String> {
        let mut config = mission_config(board)?;
        if let Some((state, _)) = resume {
            // The energy used before the restart is gone for good.
            config.battery_steps =
                (config.battery_steps - state.counters.energy_used_steps).max(0.0);
        }
        let geometry = grid_geometry(board)?;
        // The capacity follows the board's grid (checked against GRID_CELLS just above).
        let (tx, out, worker) = crate::with_cell_capacity!(geometry.cell_count(), N => {
            start_worker::<N>(board, config, geometry, resume, recording)
        })
        .ok_or_else(|| format!("$.grid: more than {GRID_CELLS} cells"))??;
        Ok(Self {
            tx,
            out,
            step_sent_s: f64::NEG_INFINITY,
            status_pending: false,
            status_t_s: 0.0,
            core_step_s: f64::NEG_INFINITY,
            commands_seen: 0,
            last_command_s: 0.0,
            last_moving: false,
            fault_at_s: None,
            done: false,
            worker: Some(worker),
        })
    }
}

/// What [`start_worker`] hands back: the thread's input, what it publishes, the thread.
type Started = (
    Sender<Input>,
    Arc<Mutex<Published>>,
    std::thread::JoinHandle<()>,
);

/// Builds the map of `N` cells and starts the mission thread on it.
fn start_worker<const N: usize>(
    board: &BoardConfig,
    config: MissionConfig,
    geometry: GridGeometry,
    resume: Option<&(SavedState, Option<MapImage>)>,
    recording: Option<MissionRecording>,
) -> Result<Started, String> {
    let (worker, out) = new_worker::<N>(board, config, geometry, resume, recording)?;
    let (tx, rx) = mpsc::channel();
    let worker = std::thread::Builder::new()
        .name("mission".into())
        .spawn(move || worker.run(rx))
        .map_err(|e| format!("cannot start the mission thread: {e}"))?;
    Ok((tx, out, worker))
}

/// The mission thread's state on a map of `N` cells, and what it publishes.
fn new_worker<const N: usize>(
    board: &BoardConfig,
    config: MissionConfig,
    geometry: GridGeometry,
    resume: Option<&(SavedState, Option<MapImage>)>,
    recording: Option<MissionRecording>,
) -> Result<(Worker<N>, Arc<Mutex<Published>>), String> {
    {
        let mut map =
            SharedMap::<N>::new_boxed(geometry, &config).map_err(|e| format!("$.grid: {e}"))?;
        let mut saved = SavedState {
            version: STATE_VERSION,
            ..SavedState::default()
        };
        if let Some((state, image)) = resume {
            if let Some(image) = image {
                image
                    .apply_to_grid(&mut map.grid)
                    .map_err(|e| format!("--resume: {e}"))?;
                map.rebuild_traversability()
                    .map_err(|e| format!("--resume: {e}"))?;
            }
            saved = state.clone();
            saved.finished = false;
        }
        let published = Published {
            state: saved.clone(),
            map: Some(MapImage::from_grid(&map.grid)),
            ..Published::default()
        };
        let out = Arc::new(Mutex::new(published));
        let worker = Worker {
            config,
            map,
            ws: Workspace::new_boxed(),
            rng: crate::random::seeded(board.mission.seed),
            mission: None,
            odometry: ArcosOdometry::new(),
            correction: crate::control::umbmark::OdometryCorrection::new(
                board.robot.wheel_diameter_ratio.unwrap_or(1.0),
                board.robot.wheelbase_ratio.unwrap_or(1.0),
                board.robot.wheelbase_m.unwrap_or(DEFAULT_WHEELBASE_M),
            ),
            resume: resume.is_some().then_some(saved.clone()),
            base: saved,
            out: Arc::clone(&out),
            last_publish_s: f64::NEG_INFINITY,
            force_fault: false,
            last_flags: RobotFlags::nominal(),
            last_status_s: 0.0,
            stall: Stall::default(),
            history: PoseHistory::new(),
            pending: std::collections::VecDeque::with_capacity(PENDING_SCANS),
            trajectory_step_m: 0.1,
            scans_integrated: 0,
            scans_unmapped: 0,
            scans_dropped: 0,
            scans_late: 0,
            last_odometry_s: f64::NEG_INFINITY,
            reconnects: 0,
            recording,
        };
        Ok((worker, out))
    }
}

impl MissionDriver for CoreMission {
    fn on_status(&mut self, t_s: f64, status: &StatusPacket) {
        self.status_pending = true;
        self.status_t_s = t_s;
        let _ = self.tx.send(Input::Status(t_s, Box::new(status.clone())));
    }

    fn on_scan(&mut self, t_s: f64, scan: &Scan) {
        let _ = self.tx.send(Input::Scan(t_s, Box::new(scan.clone())));
    }

    fn on_fault(&mut self, _t_s: f64, _fault: Fault) {
        // Only a plan made at a step asked for after the fault counts (steps are in the
        // mission's clock, strictly increasing).
        self.fault_at_s = Some(self.core_step_s);
        let _ = self.tx.send(Input::Fault);
    }

    fn on_reconnect(&mut self) {
        let _ = self.tx.send(Input::Reconnected);
    }

    fn replanned(&self) -> bool {
        match self.fault_at_s {
            None => true,
            Some(f) => lock(&self.out).last_plan_s.is_some_and(|p| p > f),
        }
    }

    fn step(&mut self, t_s: f64) -> MissionCommand {
        if self.done {
            return MissionCommand::Done;
        }
        // Step right after each status packet (the freshest pose, the least delay between
        // measuring and commanding), or every STEP_FALLBACK_S without one (so the mission
        // notices stale inputs).
        let since = t_s - self.step_sent_s;
        if (self.status_pending && since >= MIN_STEP_S) || since >= STEP_FALLBACK_S {
            let at_s = if self.status_pending {
                self.status_t_s
            } else {
                t_s
            };
            self.core_step_s = at_s.max(self.core_step_s + 1e-6);
            self.status_pending = false;
            self.step_sent_s = t_s;
            let _ = self.tx.send(Input::Step(self.core_step_s));
        }
        let (command, commands) = {
            let out = lock(&self.out);
            if let Some(e) = &out.error {
                tracing::error!(error = %e, "the mission stopped");
                self.done = true;
                return MissionCommand::Done;
            }
            if out.done.is_some() {
                self.done = true;
                return MissionCommand::Done;
            }
            (out.command, out.commands)
        };
        if commands > self.commands_seen
            && let Some(c) = command
        {
            self.commands_seen = commands;
            self.last_command_s = t_s;
            self.last_moving = !matches!(c, MissionCommand::Drive(Velocity::ZERO));
            return c;
        }
        if self.last_moving && t_s - self.last_command_s > BUSY_STOP_S {
            // The thread is busy (deciding): never keep driving on an old command.
            self.last_moving = false;
            return MissionCommand::Drive(Velocity::ZERO);
        }
        MissionCommand::Hold
    }

    fn snapshot(&self) -> (SavedState, Option<MapImage>) {
        let out = lock(&self.out);
        (out.state.clone(), out.map.clone())
    }

    fn take_telemetry(&mut self) -> Vec<TelemetryRecord> {
        std::mem::take(&mut lock(&self.out).telemetry)
    }
}

/// The mission thread's state.
struct Worker<const N: usize> {
    config: MissionConfig,
    map: Box<SharedMap<N>>,
    ws: Box<Workspace<N>>,
    rng: crate::random::ProjectRng,
    /// Built at the first status packet (the start pose depends on it when resuming).
    mission: Option<Mission<N>>,
    odometry: ArcosOdometry,
    /// The board's odometry corrections (`papillon calibrate`), applied to every reading.
    correction: crate::control::umbmark::OdometryCorrection,
    /// The saved state when resuming.
    resume: Option<SavedState>,
    /// Counters and trajectory carried over from a resumed mission.
    base: SavedState,
    out: Arc<Mutex<Published>>,
    last_publish_s: f64,
    /// Report the motors disabled for one period (a fault the runtime saw).
    force_fault: bool,
    last_flags: RobotFlags,
    last_status_s: f64,
    /// Known cells at the latest decisions.
    stall: Stall,
    /// Odometry readings with their times.
    history: PoseHistory,
    /// Scans waiting for the status packet after them.
    pending: std::collections::VecDeque<(f64, Box<Scan>)>,
    trajectory_step_m: f32,
    /// Scans integrated into the map in this run.
    scans_integrated: u64,
    /// Scans given to the safety monitor only (the robot turning, or the scan in a gap of the
    /// odometry, [`MAX_ODOMETRY_GAP_S`]), and scans dropped (older
    /// than the odometry history, or more than [`PENDING_SCANS`] waiting), in this run.
    scans_unmapped: u64,
    scans_dropped: u64,
    /// Scans read after a later odometry reading than their time (mapped at their own pose
    /// by [`Mission::on_late_scan`]), in this run.
    scans_late: u64,
    /// The time of the latest odometry pose handed to the mission \[s\]: a scan older than it
    /// is late.
    last_odometry_s: f64,
    /// Link reconnections in this run.
    reconnects: u64,
    /// The MCAP recording, if any.
    recording: Option<MissionRecording>,
}

impl<const N: usize> Drop for Worker<N> {
    fn drop(&mut self) {
        if let Some(rec) = &mut self.recording {
            rec.finish(self.last_status_s, &self.map.grid);
        }
    }
}

impl<const N: usize> Worker<N> {
    fn run(mut self, rx: Receiver<Input>) {
        while let Ok(first) = rx.recv() {
            let mut batch = vec![first];
            batch.extend(rx.try_iter());
            for input in batch {
                if matches!(input, Input::Close) {
                    return;
                }
                if let Err(e) = self.handle(input) {
                    lock(&self.out).error = Some(e);
                    return;
                }
            }
            if lock(&self.out).done.is_some() {
                return;
            }
        }
    }

    fn handle(&mut self, input: Input) -> Result<(), String> {
        match input {
            Input::Status(t_s, status) => {
                let raw = self
                    .odometry
                    .update(status.x_pos, status.y_pos, status.th_pos);
                let pose_odom = self.correction.apply(raw);
                self.last_flags = RobotFlags::from_sip(status.stall_bumpers, status.flags);
                self.last_status_s = t_s;
                self.history.push(t_s, pose_odom);
                let start = self.start_pose(pose_odom);
                if self.mission.is_none() {
                    let m = Mission::new(0, self.config.clone(), start)
                        .map_err(|e| format!("mission: {e}"))?;
                    self.mission = Some(m);
                }
                let mut flags = self.last_flags;
                if self.force_fault {
                    flags.motors_enabled = false;
                }
                self.integrate_pending(flags)?;
                if let Some(m) = &mut self.mission {
                    let volts = battery_v(&status);
                    if m.on_battery_voltage(time(t_s), volts) {
                        let v = m.config().voltage;
                        tracing::warn!(
                            battery_v = volts,
                            low_v = v.low_v,
                            hold_s = v.hold_s,
                            return_to_start = m.config().return_to_start,
                            "battery voltage low: the mission ends"
                        );
                        lock(&self.out).telemetry.push(TelemetryRecord {
                            t_s,
                            kind: "battery_low",
                            fields: serde_json::json!({
                                "battery_v": volts,
                                "low_v": v.low_v,
                                "hold_s": v.hold_s,
                                "return_to_start": m.config().return_to_start,
                            }),
                        });
                    }
                    m.on_odometry(time(t_s), pose_odom, flags);
                    self.last_odometry_s = self.last_odometry_s.max(t_s);
                    if let Some(rec) = &mut self.recording {
                        rec.status(t_s, pose_odom, m.pose_map(), m.path(), &self.map.grid);
                    }
                }
            }
            Input::Scan(t_s, scan) => {
                if self.pending.len() == PENDING_SCANS {
                    self.pending.pop_front();
                    self.scans_dropped += 1;
                }
                self.pending.push_back((t_s, scan));
            }
            Input::Fault => {
                self.force_fault = true;
                if let Some(m) = &mut self.mission {
                    let mut flags = self.last_flags;
                    flags.motors_enabled = false;
                    m.on_odometry(time(self.last_status_s), self.correction.pose(), flags);
                }
            }
            Input::Reconnected => {
                // A reset robot's odometry jumps: never interpolate across a reconnection.
                self.reconnects += 1;
                self.history.clear();
                self.pending.clear();
                self.last_odometry_s = f64::NEG_INFINITY;
            }
            Input::Step(t_s) => self.step(t_s),
            Input::Close => {}
        }
        Ok(())
    }

    /// Integrates the scans waiting for a status packet, each at the odometry pose of its time
    /// (between the previous reading and the one just pushed), before the mission sees the new
    /// reading. A scan older than the history is dropped.
    fn integrate_pending(&mut self, flags: RobotFlags) -> Result<(), String> {
        let Some(mission) = &mut self.mission else {
            self.pending.clear();
            return Ok(());
        };
        let max_turn_rate = MAX_MAPPING_TURN_RAD / 0.1;
        while let Some((t_scan, _)) = self.pending.front() {
            let t_scan = *t_scan;
            let pose = match self.history.at(t_scan) {
                PoseAt::Later => break,
                PoseAt::TooOld => {
                    tracing::debug!(t_scan, "scan older than the odometry history: dropped");
                    self.pending.pop_front();
                    self.scans_dropped += 1;
                    continue;
                }
                PoseAt::Pose(p) => p,
            };
            let Some((_, scan)) = self.pending.pop_front() else {
                break;
            };
            let turning = self
                .history
                .turn_rate_at(t_scan)
                .is_some_and(|r| r > max_turn_rate);
            let blind = self
                .history
                .span_at(t_scan)
                .is_some_and(|s| s > MAX_ODOMETRY_GAP_S);
            if turning || blind {
                tracing::debug!(
                    t_scan,
                    turning,
                    blind,
                    "robot turning or odometry gap: scan not mapped (safety only)"
                );
                mission.on_scan_unmapped(time(t_scan), &scan);
                self.scans_unmapped += 1;
            } else if t_scan < self.last_odometry_s {
                // Read after a later status packet was handed in: mapped at its own pose,
                // the robot left where the packet put it (never moved back and forth, which
                // charged the way twice: under load the odometry distance exceeded what the
                // robot could drive at cruise speed).
                mission
                    .on_late_scan(time(t_scan), &scan, pose, &mut self.map)
                    .map_err(|e| format!("scan integration: {e}"))?;
                self.scans_integrated += 1;
                self.scans_late += 1;
            } else {
                mission.on_odometry(time(t_scan), pose, flags);
                self.last_odometry_s = t_scan;
                mission
                    .on_scan(time(t_scan), &scan, &mut self.map)
                    .map_err(|e| format!("scan integration: {e}"))?;
                self.scans_integrated += 1;
                if let Some(rec) = &mut self.recording {
                    let laser = mission.pose_map().compose(self.config.laser.mount);
                    rec.scan(t_scan, laser, &scan);
                }
            }
        }
        Ok(())
    }

    /// Where the mission starts, in the map frame, given the first odometry reading.
    fn start_pose(&self, pose_odom: Pose2) -> Pose2 {
        let Some(saved) = &self.resume else {
            return pose_odom;
        };
        let saved_map = pose(saved.pose);
        let saved_odom = pose(saved.odom_pose);
        // The 15-bit counters wrap every 32.768 m: compare modulo that.
        let wrap = |d: f32| d - 32.768 * (d / 32.768).round();
        let dx = wrap(pose_odom.x - saved_odom.x);
        let dy = wrap(pose_odom.y - saved_odom.y);
        if libm::hypotf(dx, dy) <= CONTINUED_ODOMETRY_M {
            let odom_now = Pose2::new(saved_odom.x + dx, saved_odom.y + dy, pose_odom.theta);
            let transform = MapFromOdom::from_start(saved_map, saved_odom);
            transform.map_pose(odom_now)
        } else {
            saved_map
        }
    }

    fn step(&mut self, t_s: f64) {
        let Some(mission) = &mut self.mission else {
            return;
        };
        let began = WallInstant::now();
        let output = mission.step(time(t_s), &mut self.map, &mut self.ws, &mut self.rng);
        let compute_ms = began.elapsed().as_secs_f64() * 1000.0;
        if self.force_fault {
            // The core has seen the fault for one period; give it the real flags back.
            self.force_fault = false;
            let pose_odom = self.correction.pose();
            mission.on_odometry(time(self.last_status_s), pose_odom, self.last_flags);
        }
        let stats = mission.stats();
        let mut out = lock(&self.out);
        for event in &output.events {
            match event {
                MissionEvent::Decided {
                    targets,
                    path_length_m,
                    predicted_gain_cells,
                    evaluations,
                    ..
                } => {
                    out.last_plan_s = Some(t_s);
                    let first = targets.first().copied().unwrap_or(Point2::new(0.0, 0.0));
                    tracing::debug!(
                        t_s,
                        targets = targets.len(),
                        target_x_m = first.x,
                        target_y_m = first.y,
                        path_length_m,
                        predicted_gain_cells,
                        evaluations,
                        compute_ms,
                        "decision"
                    );
                    out.telemetry.push(TelemetryRecord {
                        t_s,
                        kind: "decision",
                        fields: serde_json::json!({
                            "target_x_m": first.x,
                            "target_y_m": first.y,
                            "targets": targets.len(),
                            "path_length_m": path_length_m,
                            "predicted_gain_cells": predicted_gain_cells,
                            "evaluations": evaluations,
                            "compute_ms": compute_ms,
                        }),
                    });
                    if let Some(rec) = &mut self.recording {
                        let fields = serde_json::json!({
                            "path_length_m": path_length_m,
                            "predicted_gain_cells": predicted_gain_cells,
                            "evaluations": evaluations,
                            "compute_ms": compute_ms,
                            "battery_steps": mission.battery_steps(),
                        });
                        rec.decision(t_s, targets, fields, mission.path(), &self.map.grid);
                    }
                }
                MissionEvent::Replanned { cause } => {
                    tracing::debug!(t_s, ?cause, "replanned");
                    out.last_plan_s = Some(t_s);
                    out.telemetry.push(TelemetryRecord {
                        t_s,
                        kind: "replan",
                        fields: serde_json::json!({ "cause": format!("{cause:?}") }),
                    });
                }
                MissionEvent::FaultCleared => {
                    out.last_plan_s = Some(t_s);
                }
                MissionEvent::Fault(reason) => {
                    tracing::debug!(t_s, ?reason, "mission fault");
                    out.telemetry.push(TelemetryRecord {
                        t_s,
                        kind: "mission_fault",
                        fields: serde_json::json!({ "reason": format!("{reason:?}") }),
                    })
                }
                MissionEvent::Returning(reason) => {
                    out.last_plan_s = Some(t_s);
                    out.telemetry.push(TelemetryRecord {
                        t_s,
                        kind: "returning",
                        fields: serde_json::json!({
                            "reason": done_name(*reason),
                            "start_distance_m": start_distance_m(mission),
                            "battery_v": mission.voltage().last_v(),
                            "battery_steps": mission.battery_steps(),
                        }),
                    });
                }
                MissionEvent::Done(reason) => {
                    out.done = Some(done_name(*reason));
                    out.telemetry.push(TelemetryRecord {
                        t_s,
                        kind: "done",
                        fields: serde_json::json!({
                            "reason": done_name(*reason),
                            "start_distance_m": start_distance_m(mission),
                            "battery_v": mission.voltage().last_v(),
                            "battery_steps": mission.battery_steps(),
                            "decisions": stats.decisions,
                            "replans": stats.replans,
                            "replans_per_decision":
                                f64::from(stats.replans) / f64::from(stats.decisions.max(1)),
                        }),
                    });
                }
                _ => {}
            }
        }
        let decided = output
            .events
            .iter()
            .any(|e| matches!(e, MissionEvent::Decided { .. }));
        let stalled = decided
            && out.done.is_none()
            && mission.returning().is_none()
            && self.stall.on_decision(known_cells(&self.map), stats.steps);
        if stalled && self.config.return_to_start {
            // The end of an explored building, by the way back to the start: the core turns
            // back at its next step (reported `NothingObservable` when it is there).
            mission.end(DoneReason::Requested);
        } else if stalled {
            out.done = Some(END_NOTHING_OBSERVABLE);
            out.telemetry.push(TelemetryRecord {
                t_s,
                kind: "done",
                fields: serde_json::json!({
                    "reason": END_NOTHING_OBSERVABLE,
                    "battery_steps": mission.battery_steps(),
                    "decisions": stats.decisions,
                    "replans": stats.replans,
                    "replans_per_decision":
                        f64::from(stats.replans) / f64::from(stats.decisions.max(1)),
                }),
            });
            // Stop here: the decision's path is not driven.
            out.command = Some(MissionCommand::Drive(Velocity::ZERO));
            out.commands += 1;
            drop(out);
            self.last_publish_s = t_s;
            self.publish(t_s, true);
            return;
        }
        // The monitor's command as the velocity it sets (zero for a stop, and for a command
        // that sets none): a clamped `Velocity`, unchanged down to the VEL/RVEL bytes.
        let velocity = output.command.velocity().unwrap_or_default();
        out.command = Some(MissionCommand::Drive(velocity));
        out.commands += 1;
        drop(out);
        let done = matches!(mission.state(), crate::mission::MissionState::Done(_));
        if done || t_s - self.last_publish_s >= PUBLISH_EVERY_S {
            self.last_publish_s = t_s;
            self.publish(t_s, done);
        }
    }

    /// Publishes the state to save.
    fn publish(&mut self, t_s: f64, finished: bool) {
        let Some(mission) = &self.mission else {
            return;
        };
        let p = mission.pose_map();
        let record = PoseRecord {
            x_m: p.x,
            y_m: p.y,
            theta_rad: p.theta,
        };
        let last = self.base.trajectory.last().copied();
        if last.is_none_or(|l| libm::hypotf(l.x_m - p.x, l.y_m - p.y) >= self.trajectory_step_m) {
            self.base.trajectory.push(record);
            if self.base.trajectory.len() > MAX_TRAJECTORY {
                // Keep every other point: the trajectory stays bounded and spans the mission.
                let thinned = self.base.trajectory.iter().copied().step_by(2).collect();
                self.base.trajectory = thinned;
                self.trajectory_step_m *= 2.0;
            }
        }
        let stats = mission.stats();
        let known = known_cells(&self.map);
        let base = self.base.counters;
        let o = self.correction.pose();
        let state = SavedState {
            version: STATE_VERSION,
            mission_time_s: t_s,
            pose: record,
            odom_pose: PoseRecord {
                x_m: o.x,
                y_m: o.y,
                theta_rad: o.theta,
            },
            trajectory: self.base.trajectory.clone(),
            counters: Counters {
                decisions: base.decisions + u64::from(stats.decisions),
                distance_m: base.distance_m + stats.distance_m,
                energy_used_steps: base.energy_used_steps + stats.steps,
                faults: base.faults + u64::from(stats.faults),
                reconnects: base.reconnects + self.reconnects,
                scans: base.scans + self.scans_integrated,
            },
            coverage: known as f32 / self.map.grid.geometry().cell_count().max(1) as f32,
            finished,
        };
        let image = MapImage::from_grid(&self.map.grid);
        let mission_record = TelemetryRecord {
            t_s,
            kind: "mission",
            fields: serde_json::json!({
                "state": format!("{:?}", mission.state()),
                "returning": mission.returning().is_some(),
                "battery_v": mission.voltage().last_v(),
                "battery_steps": mission.battery_steps(),
                "decisions": stats.decisions,
                "failed_decisions": stats.failed_decisions,
                "replans": stats.replans,
                "replans_per_decision": f64::from(stats.replans) / f64::from(stats.decisions.max(1)),
                "known_cells": known,
                "scans_mapped": self.scans_integrated,
                "scans_unmapped": self.scans_unmapped,
                "scans_dropped": self.scans_dropped,
                "scans_late": self.scans_late,
                "known_m2": known as f64 * f64::from(self.map.grid.geometry().resolution_m).powi(2),
                "escapes": stats.escapes,
                "faults": stats.faults,
                "stopped_s": stats.stopped_s,
                "safety": format!("{:?}", mission.monitor().state()),
                "path_waypoints": mission.path().len(),
                // The pose the mission uses (corrected by scan matching when it is on) and the
                // odometry's (odometry frame: the map frame of a mission that was not
                // resumed), so that drift and correction are visible; the true pose is in
                // `papillon-sim serve --truth-log`.
                "pose_x_m": p.x,
                "pose_y_m": p.y,
                "pose_theta_rad": p.theta,
                "odom_x_m": o.x,
                "odom_y_m": o.y,
                "odom_theta_rad": o.theta,
                "localize": mission.config().localize.enabled,
                "matches": mission.localizer().matches(),
                "matches_trusted": mission.localizer().trusted(),
            }),
        };
        let mut out = lock(&self.out);
        out.telemetry.push(mission_record);
        out.state = state;
        out.map = Some(image);
    }
}

/// Known (Free or Occupied) cells of the grid: without the world's truth the onboard program
/// cannot tell how much of the building this is, so it is reported, never a target.
fn known_cells<const N: usize>(map: &SharedMap<N>) -> usize {
    let g = map.grid.geometry();
    (0..g.cell_count())
        .filter(|&i| map.grid.class(i) != CellClass::Unknown)
        .count()
}

/// The `done` reason of an onboard end: decisions stopped adding to the map.
pub const END_NOTHING_OBSERVABLE: &str = "NothingObservable";

/// The battery voltage a status packet reports \[V\] (the 16-bit BATTERYX10 when the firmware
/// sends it, else the 8-bit BATTERY; both in 0.1 V).
fn battery_v(status: &StatusPacket) -> f32 {
    f32::from(
        status
            .extras
            .battery_dv_x10
            .unwrap_or(u16::from(status.battery_dv)),
    ) * 0.1
}

/// How far the mission's pose estimate is from its start \[m\].
fn start_distance_m<const N: usize>(mission: &Mission<N>) -> f32 {
    let start = mission.start_pose_map().position();
    mission.pose_map().position().distance(start)
}

fn done_name(reason: DoneReason) -> &'static str {
    match reason {
        DoneReason::CoverageReached => "CoverageReached",
        DoneReason::BatteryExhausted => "BatteryExhausted",
        DoneReason::NothingReachable => "NothingReachable",
        DoneReason::Stuck => "Stuck",
        DoneReason::VoltageLow => "VoltageLow",
        // The onboard program ends a mission itself only when decisions stop adding to the
        // map ([`Stall`]).
        DoneReason::Requested => END_NOTHING_OBSERVABLE,
    }
}

/// The onboard end of an explored building: [`STALL_DECISIONS`] decisions in a row that
/// together added fewer than [`STALL_NEW_CELLS`] known cells while the robot spent at least
/// [`STALL_STEPS`] on them, or [`STALL_IDLE_DECISIONS`] in a row that added fewer than
/// [`STALL_NEW_CELLS`] however far the robot drove. The core ends with `NothingReachable` only when no frontier cell
/// can be reached; a frontier cell that can be reached but never seen (measured on the lab:
/// the inside of a box behind a cell of its wall that range noise marked Free) keeps it
/// deciding, driving there and back until the battery is spent.
#[derive(Clone, Debug, Default)]
struct Stall {
    /// (known cells, energy used) at each of the latest decisions.
    at: std::collections::VecDeque<(usize, f32)>,
}

impl Stall {
    /// Records a decision; true when the mission should end.
    fn on_decision(&mut self, known_cells: usize, steps: f32) -> bool {
        if self.at.len() > STALL_IDLE_DECISIONS {
            self.at.pop_front();
        }
        self.at.push_back((known_cells, steps));
        let n = self.at.len();
        let Some(&(k1, s1)) = self.at.back() else {
            return false;
        };
        let driven = n > STALL_DECISIONS && {
            let (k0, s0) = self.at[n - 1 - STALL_DECISIONS];
            k1.saturating_sub(k0) < STALL_NEW_CELLS && s1 - s0 >= STALL_STEPS
        };
        let idle = n > STALL_IDLE_DECISIONS && {
            let (k0, _) = self.at[0];
            k1.saturating_sub(k0) < STALL_NEW_CELLS
        };
        driven || idle
    }
}

fn pose(p: PoseRecord) -> Pose2 {
    Pose2::new(p.x_m, p.y_m, normalize_angle(p.theta_rad))
}

fn time(t_s: f64) -> Time {
    Time::from_secs_f64(t_s.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_boards_make_valid_missions() {
        for name in [
            "sim.json",
            "sim-thesis.json",
            "p3dx-lms1xx.json",
            "p3dx-lms200.json",
        ] {
            let path = format!("{}/boards/{name}", env!("CARGO_MANIFEST_DIR"));
            let board = BoardConfig::from_json(&std::fs::read(path).unwrap()).unwrap();
            let config = mission_config(&board).unwrap();
            assert_eq!(
                config.explore.population,
                usize::from(board.mission.population)
            );
            assert_eq!(config.limits.max_speed_mm_s(), 400);
            grid_geometry(&board).unwrap();
        }
    }

    #[test]
    fn decisions_that_add_nothing_end_the_mission_only_after_enough_of_them_and_of_driving() {
        let mut stall = Stall::default();
        // Growing map: never.
        for i in 0..20 {
            assert!(!stall.on_decision(1000 + 100 * i, i as f32));
        }
        // Nothing new, but no driving either (decisions dropped at once): not yet.
        let mut stall = Stall::default();
        for _ in 0..10 {
            assert!(!stall.on_decision(5000, 3.0));
        }
        // ...unless it goes on for STALL_IDLE_DECISIONS decisions (the robot deciding where
        // it stands, again and again).
        let mut stall = Stall::default();
        let ends: Vec<bool> = (0..=STALL_IDLE_DECISIONS)
            .map(|i| stall.on_decision(5000 + i, 3.0))
            .collect();
        assert_eq!(ends.iter().filter(|&&e| e).count(), 1);
        assert!(ends[STALL_IDLE_DECISIONS]);
        // A map that grows by a little at each of them never ends it.
        let mut stall = Stall::default();
        for i in 0..200 {
            assert!(!stall.on_decision(5000 + 3 * i, 3.0));
        }
        // Nothing new over STALL_DECISIONS decisions and STALL_STEPS of driving: the end.
        let mut stall = Stall::default();
        let ends: Vec<bool> = (0..=STALL_DECISIONS)
            .map(|i| stall.on_decision(5000 + i, 10.0 + 4.0 * i as f32))
            .collect();
        assert_eq!(ends.iter().filter(|&&e| e).count(), 1);
        assert!(ends[STALL_DECISIONS]);
    }

    /// The planning layer follows the board's body, clearance and cell size, derived as the
    /// runner derives it; the safety monitor gets the same body.
    #[test]
    fn the_planning_layer_follows_the_boards_body_clearance_and_cells() {
        use crate::control::safety::RobotFootprint;
        use crate::mission::footprint::planning_layer;
        let mut board = BoardConfig::default();
        board.grid.resolution_m = 0.05;
        board.robot.footprint.width_m = Some(0.425);
        board.robot.footprint.rear_m = Some(0.301);
        board.robot.footprint.swing_radius_m = Some(0.25);
        board.planning.clearance_m = Some(0.08);
        let config = mission_config(&board).unwrap();
        assert_eq!(config.safety.footprint, RobotFootprint::p3dx_with_bumpers());
        let layer = config.traversability;
        assert!((layer.robot_radius_m - (0.2125 + 0.08 + 0.025)).abs() < 1e-6);
        assert_eq!(
            layer,
            planning_layer(&config.safety, 0.08, 0.05, layer.unknown_policy)
        );
        // The map's Occupied threshold is the board's.
        let mut noisy = BoardConfig::default();
        noisy.mapping.occupied_thresh = Some(0.65);
        let b = mission_config(&noisy).unwrap().grid_bounds;
        assert!((b.occupied_thresh() - 0.65).abs() < 1e-6);
        // The defaults at the default cell size: the runner's layer.
        let config = mission_config(&BoardConfig::default()).unwrap();
        assert_eq!(
            config.traversability,
            MissionConfig::default().traversability
        );
    }

    #[test]
    fn the_thesis_simulator_board_is_the_runners_default_mission_with_its_laser() {
        let path = format!("{}/boards/sim-thesis.json", env!("CARGO_MANIFEST_DIR"));
        let board = BoardConfig::from_json(&std::fs::read(path).unwrap()).unwrap();
        let mut config = mission_config(&board).unwrap();
        // The LMS1xx at 0.5° scans at 50 Hz (`papillon-sim serve`'s emulator too).
        let lms1xx = crate::sensor::LaserConfig {
            rate_hz: 50.0,
            ..crate::sensor::LaserConfig::lms1xx()
        };
        assert_eq!(config.laser, lms1xx);
        config.laser = MissionConfig::default().laser;
        assert_eq!(config, MissionConfig::default());
    }

    #[test]
    fn an_unknown_method_and_an_oversized_grid_name_their_field() {
        let mut board = BoardConfig::default();
        board.mission.method = crate::config::Name::new("simplex").unwrap();
        assert!(
            mission_config(&board)
                .unwrap_err()
                .starts_with("$.mission.method")
        );
        // A 100 m x 100 m storey fits (issue 24); 300 m x 300 m at 0.1 m (9 000 000 cells)
        // is beyond the largest capacity, and the error names it.
        let mut board = BoardConfig::default();
        board.grid.width_m = 100.0;
        board.grid.height_m = 100.0;
        #[cfg(not(feature = "fixed-capacity"))]
        assert!(grid_geometry(&board).is_ok());
        board.grid.width_m = 300.0;
        board.grid.height_m = 300.0;
        let e = grid_geometry(&board).unwrap_err();
        assert!(e.starts_with("$.grid"), "{e}");
        assert!(e.contains(&GRID_CELLS.to_string()), "{e}");
    }

    /// A status packet at `x_mm` east (the robot 50 mm north of the map's x axis, heading
    /// east, motors on).
    fn packet_at(x_mm: u16) -> Box<StatusPacket> {
        Box::new(StatusPacket {
            x_pos: x_mm,
            y_pos: 50,
            flags: 1,
            battery_dv: 130,
            ..StatusPacket::default()
        })
    }

    /// One beam straight ahead, returning at `range_m`.
    fn beam_ahead(range_m: f32) -> Box<Scan> {
        let mut scan = Scan::new();
        scan.push(crate::sensor::Beam {
            angle_rad: 0.0,
            range_m: Some(range_m),
        })
        .unwrap();
        Box::new(scan)
    }

    /// A box room, x from -1 to 3.2 m and y from -1.2 to 1.3 m (the robot drives east along y =
    /// 0.05 m from x = 0), as the board's laser sees it from the robot pose `at` (map frame)
    /// with the board's range noise ([`matching_board`]: 1 %, about a real LMS1xx's 12 mm at
    /// a metre or two): every direction is constrained (the end walls by x, the long walls by
    /// y).
    fn room_scan(board: &BoardConfig, at: Pose2) -> Box<Scan> {
        let laser = board.laser_config();
        let mut rng = crate::random::seeded((at.x * 1000.0) as u64);
        let origin = at.compose(laser.mount);
        let (x0, x1, y0, y1) = (-1.0f32, 3.2f32, -1.2f32, 1.3f32);
        let mut scan = Scan::new();
        for i in 0..usize::from(laser.beam_count) {
            let a = laser.beam_angle(i);
            let (dy, dx) = (origin.theta + a).sin_cos();
            let along = |d: f32, p: f32, lo: f32, hi: f32| {
                if d > 1e-6 {
                    (hi - p) / d
                } else if d < -1e-6 {
                    (lo - p) / d
                } else {
                    f32::INFINITY
                }
            };
            let t = along(dx, origin.x, x0, x1).min(along(dy, origin.y, y0, y1));
            let noisy = t * (1.0 + laser.noise_fraction * crate::random::gaussian(&mut rng));
            let range_m = (t >= laser.min_range_m && t < laser.max_range_m).then_some(noisy);
            scan.push(crate::sensor::Beam {
                angle_rad: a,
                range_m,
            })
            .unwrap();
        }
        Box::new(scan)
    }

    /// `boards/sim-thesis.json` with scan matching on at every scan (no minimum travel, no pose
    /// graph) and a laser of 1 % range noise. (The board's 5 %, the thesis's laser, gives the point-to-line
    /// matcher a few centimetres of error a match in this small room, and the pose checks
    /// below are within 2 cm; with the matcher fed the latest packet's pose instead of the
    /// interpolated one, all three tests of this room fail at 1 %, checked.)
    fn matching_board() -> BoardConfig {
        let path = format!("{}/boards/sim-thesis.json", env!("CARGO_MANIFEST_DIR"));
        let mut board = BoardConfig::from_json(&std::fs::read(path).unwrap()).unwrap();
        board.localize.enabled = Some(true);
        board.localize.min_travel_m = Some(0.0);
        board.localize.min_turn_deg = Some(0.0);
        board.laser.noise_fraction = 0.01;
        board
    }

    /// Drives a matching worker through the room: standing at x = 0 for ten status packets
    /// (100 ms apart), then east at 1 m/s with exact odometry, a scan taken 20 ms after each
    /// packet (the packet after it 8 cm further). The scan is read before the next packet, or
    /// with `late` after it (then mapped as a late scan when the one after that arrives).
    /// Returns the worker and the corrections (match minus prediction, before the blend) of
    /// the trusted matches while driving; checks that the robot's pose is the latest packet's
    /// after each.
    fn drive_through_the_room(
        late: bool,
    ) -> (Worker<{ crate::capacity::FIXED_CELLS }>, Vec<[f32; 3]>) {
        let board = matching_board();
        let config = mission_config(&board).unwrap();
        assert!(config.localize.enabled);
        let geometry = grid_geometry(&board).unwrap();
        let (mut worker, _out) =
            new_worker::<{ crate::capacity::FIXED_CELLS }>(&board, config, geometry, None, None)
                .unwrap();
        let x_mm = |k: u16| if k < 10 { 0 } else { 100 * (k - 9) };
        let t = |k: u16| 1.0 + 0.1 * f64::from(k);
        worker
            .handle(Input::Status(t(0), packet_at(x_mm(0))))
            .unwrap();
        if late {
            worker
                .handle(Input::Status(t(1), packet_at(x_mm(1))))
                .unwrap();
        }
        let mut corrections = Vec::new();
        for k in 0..24u16 {
            let before = worker.mission.as_ref().unwrap().localizer().matches();
            let (x0, x1) = (f32::from(x_mm(k)) / 1000.0, f32::from(x_mm(k + 1)) / 1000.0);
            let scan = room_scan(&board, Pose2::new(x0 + 0.2 * (x1 - x0), 0.05, 0.0));
            worker.handle(Input::Scan(t(k) + 0.02, scan)).unwrap();
            let next = if late { k + 2 } else { k + 1 };
            worker
                .handle(Input::Status(t(next), packet_at(x_mm(next))))
                .unwrap();
            let m = worker.mission.as_ref().unwrap();
            assert!(m.localizer().matches() > before, "scan {k} not matched");
            if x1 > x0
                && let Some(q) = m.localizer().last()
                && q.trusted()
            {
                corrections.push(q.correction);
            }
            let expected_x = f32::from(x_mm(next)) / 1000.0;
            assert!(
                (m.pose_map().x - expected_x).abs() < 0.02,
                "pose {:?} after packet {next}",
                m.pose_map()
            );
        }
        (worker, corrections)
    }

    /// Issue 18: the matcher is given each scan at the odometry pose interpolated to the
    /// scan's time, not the latest status packet's. The map drawn while the robot stood is
    /// true; driving, the prediction the matcher starts from is where the scan was taken,
    /// and its correction stays near zero. Matched at the latest packet's pose it would find
    /// about -8 cm along x (checked by feeding it that pose: this test then fails).
    #[test]
    fn the_matcher_gets_each_scan_at_the_pose_interpolated_to_its_time() {
        let (worker, corrections) = drive_through_the_room(false);
        assert_eq!(worker.scans_late, 0);
        assert_unbiased(&corrections);
    }

    /// A late scan (read after a later packet than its time) is matched too, at its own
    /// time's pose (not the latest packet's, 18 cm further): its correction stays near zero,
    /// and the robot's pose stays the latest packet's (not moved back to the scan's).
    #[test]
    fn a_late_scan_is_matched_at_its_own_pose() {
        let (worker, corrections) = drive_through_the_room(true);
        assert_eq!(worker.scans_late, 24);
        assert_unbiased(&corrections);
    }

    /// One match is off by up to a few centimetres, so the test is on their mean: within 2 cm of zero along the
    /// way driven, where a prediction 8 cm ahead would pull it to about -8 cm.
    fn assert_unbiased(corrections: &[[f32; 3]]) {
        assert!(corrections.len() >= 10, "{corrections:?}");
        let n = corrections.len() as f32;
        let mean = |i: usize| corrections.iter().map(|c| c[i]).sum::<f32>() / n;
        assert!(mean(0).abs() < 0.02, "mean {} m: {corrections:?}", mean(0));
        assert!(mean(1).abs() < 0.02, "mean {} m: {corrections:?}", mean(1));
        assert!(
            mean(2).abs() < 0.02,
            "mean {} rad: {corrections:?}",
            mean(2)
        );
    }

    /// A worker on `boards/sim-thesis.json` after two status packets 100 ms apart, standing at
    /// the origin.
    fn worker_after_two_packets() -> Worker<{ crate::capacity::FIXED_CELLS }> {
        let path = format!("{}/boards/sim-thesis.json", env!("CARGO_MANIFEST_DIR"));
        let board = BoardConfig::from_json(&std::fs::read(path).unwrap()).unwrap();
        let config = mission_config(&board).unwrap();
        let geometry = grid_geometry(&board).unwrap();
        let (mut worker, _out) =
            new_worker::<{ crate::capacity::FIXED_CELLS }>(&board, config, geometry, None, None)
                .unwrap();
        worker.handle(Input::Status(1.0, packet_at(0))).unwrap();
        worker.handle(Input::Status(1.1, packet_at(100))).unwrap();
        worker
    }

    /// A scan taken in a gap of the odometry (the pump stalled 1 s, the queued status packets
    /// then all placed at its end) is not mapped: its pose would be interpolated between the
    /// reading before the gap and the first queued one, anywhere along what the robot did
    /// meanwhile. (Mapped, its return 1.04 m ahead of the interpolated x = 0.46 m would mark
    /// x = 1.55 m: checked by raising the gap limit.)
    #[test]
    fn a_scan_in_a_gap_of_the_odometry_is_not_mapped() {
        let mut worker = worker_after_two_packets();
        worker.handle(Input::Scan(1.5, beam_ahead(1.04))).unwrap();
        worker.handle(Input::Status(2.1, packet_at(200))).unwrap();
        worker.handle(Input::Status(2.1, packet_at(1100))).unwrap();
        let grid = &worker.map.grid;
        let class = |x: f32| {
            let cell = grid.geometry().cell_at(Point2::new(x, 0.05)).unwrap();
            grid.class_of(cell).unwrap()
        };
        assert_eq!(class(1.55), CellClass::Unknown);
        assert_eq!((worker.scans_integrated, worker.scans_unmapped), (0, 1));
        // A scan between readings one period apart is mapped as before.
        worker.handle(Input::Scan(2.15, beam_ahead(1.04))).unwrap();
        worker.handle(Input::Status(2.2, packet_at(1200))).unwrap();
        assert_eq!(worker.scans_integrated, 1);
    }

    /// A scan the mission thread reads after a later status packet than its time (the pump
    /// read it late) is mapped at the odometry of its own time, and the robot is not moved
    /// back to it and forward again: the distance counted is the 0.2 m the robot drove
    /// (handed in as odometry, the scan's pose made it 0.3 m).
    #[test]
    fn a_late_scan_is_mapped_at_its_pose_without_charging_the_way_twice() {
        let mut worker = worker_after_two_packets();
        // Taken at 1.05 s (x = 0.05 m), read after the packet of 1.1 s.
        worker.handle(Input::Scan(1.05, beam_ahead(1.04))).unwrap();
        worker.handle(Input::Status(1.2, packet_at(200))).unwrap();
        let mission = worker.mission.as_ref().unwrap();
        let distance_m = mission.stats().distance_m;
        assert!((distance_m - 0.2).abs() < 1e-3, "{distance_m}");
        assert!((mission.pose_map().x - 0.2).abs() < 1e-3);
        // The return: 0.05 + 0.055 (mount) + 1.04 = 1.145 m, not 1.295 m from the packet's
        // pose.
        let grid = &worker.map.grid;
        let class = |x: f32| {
            let cell = grid.geometry().cell_at(Point2::new(x, 0.05)).unwrap();
            grid.class_of(cell).unwrap()
        };
        assert_ne!(class(1.15), CellClass::Unknown);
        assert_ne!(class(1.15), CellClass::Free);
        assert_eq!(class(1.25), CellClass::Unknown);
        assert_eq!(class(0.6), CellClass::Free);
        assert_eq!((worker.scans_integrated, worker.scans_late), (1, 1));
    }
}
