//! `papillon run` and `papillon probe`: start-up, the mission pump, safety checks, persistence
//! and a safe shutdown.
//!
//! [`run_with`] opens the robot link and the ARCOS session ([`connect_robot`]), builds the
//! mission ([`mission_driver`]: the core mission behind a [`MissionDriver`]), connects the
//! laser ([`connect_laser`]), then runs [`pump`] until the mission is done or a signal comes:
//! status and scan timestamps, stale-data and e-stop checks that stop the robot at once and
//! latch the fault until the mission re-plans, periodic atomic saves, telemetry, and a stop on
//! SIGINT/SIGTERM. A lost link is reconnected with back-off and the pump resumes.
//! `docs/architecture.md` ("Onboard pump") follows a scan and a velocity through it.

use std::io;
use std::path::PathBuf;
use std::time::Duration;

use tokio::time::Instant;

use super::driver::{MissionCommand, MissionDriver};
use super::laser::{LaserCodec, Lms1xxClient};
use super::link::{
    Backoff, TcpLink, connect_with_backoff, open_robot_link, permanent_always, permanent_at_start,
};
use super::lms200::Lms200Client;
use super::persist::{MapImage, MissionState, PersistError, STATE_VERSION, StateStore, Telemetry};
use super::robot::{ArcosClient, Fault, MotionLimits, SessionError, SessionOptions};
use crate::config::{BoardConfig, LaserModel};
use crate::control::command::{Limits, MotionCommand};
use crate::control::odometry::ArcosOdometry;
use crate::geometry::Point2;
use crate::sensor::Scan;
use crate::wire::arcos::StatusPacket;

/// The CoLa-A codec of `crate::wire::lms1xx`, for an LMS1xx session.
pub fn laser_codec() -> Box<dyn LaserCodec> {
    Box::new(super::codec::WireLms1xx::default())
}

/// The core mission for a board ([`super::mission::CoreMission`]), resumed from `resume` if
/// given. An error names the board field (or the saved state) that prevents it.
pub fn mission_driver(
    board: &BoardConfig,
    resume: Option<&(MissionState, Option<MapImage>)>,
) -> Result<Box<dyn MissionDriver>, String> {
    let mission = super::mission::CoreMission::new(board, resume)?;
    Ok(Box::new(mission))
}

/// A saved mission and its map, as `--resume` loads them.
pub type Saved = (MissionState, Option<MapImage>);

/// [`mission_driver`], the mission recorded into `log_dir` ([`super::record`]: `mission.mcap`,
/// or the next free `mission-N.mcap` when resuming): what the binary passes to [`run_with`].
/// A recording that cannot be created refuses the run, naming the file.
/// With `live` (`papillon run --live`, bound before anything is connected), the same messages
/// are also served live to Foxglove ([`crate::live`]).
pub fn recording_mission_driver(
    log_dir: PathBuf,
    live: Option<crate::live::LiveServer>,
) -> impl FnOnce(&BoardConfig, Option<&Saved>) -> Result<Box<dyn MissionDriver>, String> {
    move |board, resume| {
        let path = super::record::recording_path(&log_dir, resume.is_some());
        let mission_time_s = resume.map_or(0.0, |(s, _)| s.mission_time_s);
        let recording = super::record::MissionRecording::create(&path, mission_time_s, live)?;
        let mission = super::mission::CoreMission::recorded(board, resume, Some(recording))?;
        Ok(Box::new(mission))
    }
}

/// Errors of `papillon run` / `probe`.
#[derive(Debug)]
#[non_exhaustive]
pub enum RuntimeError {
    /// The link could not be opened.
    Link(io::Error),
    /// The ARCOS session failed.
    Session(SessionError),
    /// The laser session failed.
    Laser(super::laser::LaserError),
    /// Saving or loading the mission state failed.
    Persist(PersistError),
    /// `--resume` found no saved mission.
    NothingToResume(PathBuf),
    /// A new mission would overwrite an unfinished (or unreadable) saved one: neither
    /// `--resume` nor `--fresh` was given.
    UnfinishedMission {
        /// The log directory.
        dir: PathBuf,
        /// What is saved there (coverage and mission time, or why it does not load).
        saved: String,
    },
    /// The mission could not be set up (names the board field or the saved state).
    Mission(String),
    /// The log directory (`--log-dir`) cannot hold the mission's files.
    LogDir(PathBuf, io::Error),
    /// The robot or the laser could not be reached at start-up; `check` names the flag and
    /// the board field that gave its address.
    Endpoint {
        /// What failed.
        error: Box<RuntimeError>,
        /// The address and where it came from, e.g. `--tcp (or the board's $.link.tcp)
        /// 127.0.0.1:8101`.
        check: String,
    },
}

impl std::fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RuntimeError::Link(e) => write!(f, "{e}"),
            RuntimeError::Session(e) => write!(f, "{e}"),
            RuntimeError::Laser(e) => write!(f, "{e}"),
            RuntimeError::Persist(e) => write!(f, "{e}"),
            RuntimeError::Mission(e) => write!(f, "{e}"),
            RuntimeError::LogDir(dir, e) => write!(f, "--log-dir {}: {e}", dir.display()),
            RuntimeError::Endpoint { error, check } => write!(f, "{error}; check {check}"),
            RuntimeError::NothingToResume(dir) => {
                write!(f, "--resume: no saved mission in {}", dir.display())
            }
            RuntimeError::UnfinishedMission { dir, saved } => write!(
                f,
                "{} holds an unfinished mission ({saved}); pass --resume to continue it, or \
                 --fresh to start anew (its files are moved to {}/previous-N/)",
                dir.display(),
                dir.display()
            ),
        }
    }
}

impl std::error::Error for RuntimeError {}

impl From<SessionError> for RuntimeError {
    fn from(e: SessionError) -> Self {
        RuntimeError::Session(e)
    }
}

impl From<PersistError> for RuntimeError {
    fn from(e: PersistError) -> Self {
        RuntimeError::Persist(e)
    }
}

impl From<io::Error> for RuntimeError {
    fn from(e: io::Error) -> Self {
        RuntimeError::Link(e)
    }
}

/// Options of `papillon run` (command-line flags already applied over the board).
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The board (with `--port`, `--tcp`, `--laser` applied).
    pub board: BoardConfig,
    /// Log directory.
    pub log_dir: PathBuf,
    /// What to do with a mission saved in `log_dir`.
    pub start: Start,
}

/// What `run` does with a mission saved in the log directory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Start {
    /// A new mission; refused when an unfinished (or unreadable) one is saved there.
    #[default]
    New,
    /// Continue the saved mission (`--resume`); refused when there is none.
    Resume,
    /// A new mission; the saved one's files are first moved to `previous-N/` (`--fresh`).
    Fresh,
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum RunOutcome {
    /// The mission completed.
    Finished,
    /// Stopped by SIGINT/SIGTERM; state saved.
    Interrupted,
}

/// Resolves on SIGINT or SIGTERM.
pub async fn shutdown_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(_) => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}

/// Whether a link is opened for the first time or reopened after a loss: a missing serial
/// device is an error at once at start-up, and waited for (with back-off) after a loss.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Opening {
    /// At start-up.
    First,
    /// After the link was lost.
    Again,
}

impl Opening {
    fn permanent(self) -> fn(&io::Error) -> bool {
        match self {
            Opening::First => permanent_at_start,
            Opening::Again => permanent_always,
        }
    }
}

/// Opens the robot link with back-off and runs the ARCOS start-up (handshake, CONFIG check,
/// HOSTBAUD, ENABLE, limits).
pub async fn connect_robot(
    board: &BoardConfig,
    opening: Opening,
) -> Result<ArcosClient, RuntimeError> {
    let tcp = board.link.tcp.as_ref().map(|a| a.as_str().to_string());
    let port = board.link.port.as_str().to_string();
    let baud = board.link.baud;
    let link = connect_with_backoff(
        Backoff::default(),
        || open_robot_link(tcp.as_deref(), &port, baud),
        opening.permanent(),
        |attempt, e| tracing::warn!(attempt, error = %e, "robot link not available, retrying"),
    )
    .await?;
    tracing::info!(link = %link.describe(), "robot link open");
    let mut client = ArcosClient::connect(link, SessionOptions::from_board(board)).await?;
    let id = client.identity().clone();
    tracing::info!(name = %id.name, class = %id.class, subclass = %id.subclass, baud = ?client.baud_switch(), "connected");
    if let (Opening::First, Some(watchdog_ms)) = (opening, long_serial_watchdog_ms(&client)) {
        tracing::warn!(
            watchdog_ms,
            "if this serial line is cut, only the firmware watchdog stops the robot, after {} s; \
             ARCOScf's Watchdog can shorten it (papillon feeds it every quarter period)",
            f64::from(watchdog_ms) / 1000.0
        );
    }
    client.start(&MotionLimits::from_board(board)).await?;
    Ok(client)
}

/// Longest firmware watchdog \[ms\] `run` accepts without a warning on a serial link. A cut
/// serial line is silence to the robot: nothing the program sends gets through, and only the
/// firmware's watchdog (FLASH `Watchdog`, 2000 ms as shipped) stops it (docs/reliability.md,
/// section "Soaks": 2.0-2.3 s at 2000 ms, 0.5-0.8 s at 500 ms).
pub const LONG_SERIAL_WATCHDOG_MS: u16 = 1000;

/// The robot's watchdog \[ms\] when the session runs on a serial link and the watchdog is
/// longer than [`LONG_SERIAL_WATCHDOG_MS`].
fn long_serial_watchdog_ms(client: &ArcosClient) -> Option<u16> {
    let watchdog_ms = client.config()?.watchdog_ms;
    (client.link_kind() == super::link::LinkKind::Serial && watchdog_ms > LONG_SERIAL_WATCHDOG_MS)
        .then_some(watchdog_ms)
}

/// A laser session: an LMS1xx over TCP or an LMS200 over a serial port.
pub enum LaserClient {
    /// SICK LMS1xx, CoLa-A over TCP.
    Lms1xx(Lms1xxClient),
    /// SICK LMS200 over RS-232.
    Lms200(Lms200Client),
}

impl LaserClient {
    /// The next scan and its arrival time, or `None` at `deadline`.
    pub async fn next_scan(
        &mut self,
        deadline: Instant,
    ) -> Result<Option<(Instant, Scan)>, super::laser::LaserError> {
        match self {
            LaserClient::Lms1xx(c) => c.next_scan(deadline).await,
            LaserClient::Lms200(c) => c.next_scan(deadline).await,
        }
    }

    /// Stops the scans and closes the link.
    pub async fn close(self) -> Result<(), super::laser::LaserError> {
        match self {
            LaserClient::Lms1xx(c) => c.close().await,
            LaserClient::Lms200(c) => c.close().await,
        }
    }
}

/// Connects the laser the board names.
pub async fn connect_laser(
    board: &BoardConfig,
    codec: Box<dyn LaserCodec>,
    opening: Opening,
) -> Result<LaserClient, RuntimeError> {
    match board.laser_model() {
        Some(LaserModel::Lms1xx) => {
            let addr = board
                .laser
                .address
                .as_ref()
                .map(|a| a.as_str().to_string())
                .unwrap_or_default();
            let link = connect_with_backoff(
                Backoff::default(),
                || TcpLink::connect(&addr),
                opening.permanent(),
                |attempt, e| tracing::warn!(attempt, error = %e, "laser not available, retrying"),
            )
            .await?;
            Lms1xxClient::connect(Box::new(link), codec, board.laser_config())
                .await
                .map(LaserClient::Lms1xx)
                .map_err(RuntimeError::Laser)
        }
        _ => {
            let port = board
                .laser
                .port
                .as_ref()
                .map(|p| p.as_str().to_string())
                .ok_or_else(|| {
                    RuntimeError::Laser(super::laser::LaserError::Lms200(
                        "$.laser.port: the serial device of the LMS200 is missing".into(),
                    ))
                })?;
            let baud = board.laser.baud.unwrap_or(super::lms200::POWER_UP_BAUD);
            let link = connect_with_backoff(
                Backoff::default(),
                || open_robot_link(None, &port, super::lms200::POWER_UP_BAUD),
                opening.permanent(),
                |attempt, e| tracing::warn!(attempt, error = %e, "laser not available, retrying"),
            )
            .await?;
            Lms200Client::connect(link, board.laser_config(), baud)
                .await
                .map(LaserClient::Lms200)
                .map_err(RuntimeError::Laser)
        }
    }
}

/// The robot's address and where it came from, for an error at start-up.
fn robot_source(board: &BoardConfig) -> String {
    match &board.link.tcp {
        Some(tcp) => format!("--tcp (or the board's $.link.tcp) {}", tcp.as_str()),
        None => format!(
            "--port (or the board's $.link.port) {}",
            board.link.port.as_str()
        ),
    }
}

/// The laser's address and where it came from, for an error at start-up.
fn laser_source(board: &BoardConfig) -> String {
    let shown = |a: Option<&crate::config::Address>| a.map_or("(none)", |a| a.as_str()).to_string();
    match board.laser_model() {
        Some(LaserModel::Lms1xx) => format!(
            "--laser (or the board's $.laser.address) {}",
            shown(board.laser.address.as_ref())
        ),
        _ => format!(
            "--laser (or the board's $.laser.port) {}",
            shown(board.laser.port.as_ref())
        ),
    }
}

impl RuntimeError {
    /// This error of the robot or laser link at start-up, naming where its address came from
    /// (unless it already names a flag, as a serial port's errors do).
    fn at(self, check: String) -> Self {
        if self.to_string().contains("check --") {
            return self;
        }
        RuntimeError::Endpoint {
            error: Box::new(self),
            check,
        }
    }
}

/// Whether a failed (re)connection may succeed if tried again: the link or the session
/// broke, as opposed to a robot or a board that does not fit.
fn worth_retrying(e: &RuntimeError) -> bool {
    match e {
        RuntimeError::Link(e) => !permanent_always(e),
        RuntimeError::Laser(_) => true,
        RuntimeError::Session(s) => matches!(
            s,
            SessionError::Io(_)
                | SessionError::Closed
                | SessionError::HandshakeFailed { .. }
                | SessionError::NoConfig
                | SessionError::MicrocontrollerReset { .. }
        ),
        _ => false,
    }
}

/// Runs `connect` (link and session start-up) until it succeeds, with the default back-off
/// between attempts: a link that comes back may still drop the first sessions (a robot
/// rebooting, a bridge reconnecting).
async fn retry_session<T, F, Fut>(what: &str, mut connect: F) -> Result<T, RuntimeError>
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Result<T, RuntimeError>>,
{
    let policy = Backoff::default();
    let mut attempt = 1;
    loop {
        match connect().await {
            Ok(c) => return Ok(c),
            Err(e) if worth_retrying(&e) && attempt < policy.max_attempts => {
                tracing::warn!(attempt, error = %e, "{what} session not re-established, retrying");
                tokio::time::sleep(policy.delay(attempt)).await;
                attempt += 1;
            }
            Err(e) => return Err(e),
        }
    }
}

/// Link losses `run` recovers from (reconnecting with back-off each time) before giving up.
pub const MAX_RECONNECTS: u32 = 20;

/// `papillon run`, with the LMS1xx codec factory and the mission given (the binary passes
/// [`laser_codec`] and [`mission_driver`]; tests pass doubles). A lost robot or laser link is
/// reconnected with back-off (the robot was stopped at once, and its firmware watchdog stops
/// it too), then the mission resumes after a fresh re-plan.
pub async fn run_with(
    options: RunOptions,
    laser: impl Fn() -> Box<dyn LaserCodec>,
    make_mission: impl FnOnce(
        &BoardConfig,
        Option<&(MissionState, Option<MapImage>)>,
    ) -> Result<Box<dyn MissionDriver>, String>,
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<RunOutcome, RuntimeError> {
    let board = &options.board;
    let log_dir = |e: io::Error| RuntimeError::LogDir(options.log_dir.clone(), e);
    let store = StateStore::open(&options.log_dir).map_err(log_dir)?;
    match options.start {
        Start::New => {
            let saved = match store.load() {
                Ok(Some((state, _))) if !state.finished => Some(format!(
                    "coverage {:.0} % after {:.0} s",
                    state.coverage * 100.0,
                    state.mission_time_s
                )),
                Ok(_) => None,
                Err(e) => Some(e.to_string()),
            };
            if let Some(saved) = saved {
                return Err(RuntimeError::UnfinishedMission {
                    dir: options.log_dir.clone(),
                    saved,
                });
            }
        }
        Start::Fresh => {
            if let Some(aside) = store.set_aside().map_err(log_dir)? {
                tracing::info!(to = %aside.display(), "the saved mission's files were moved aside");
            }
        }
        Start::Resume => {}
    }
    let mut telemetry = Telemetry::open(&options.log_dir).map_err(log_dir)?;
    let resumed = if options.start == Start::Resume {
        match store.load()? {
            Some(saved) => {
                tracing::info!(
                    coverage = saved.0.coverage,
                    time_s = saved.0.mission_time_s,
                    "resuming saved mission"
                );
                Some(saved)
            }
            None => return Err(RuntimeError::NothingToResume(options.log_dir.clone())),
        }
    } else {
        None
    };
    let mut shutdown = std::pin::pin!(shutdown);
    let mut client = connect_robot(board, Opening::First)
        .await
        .map_err(|e| e.at(robot_source(board)))?;
    let mut mission = match make_mission(board, resumed.as_ref()) {
        Ok(m) => m,
        Err(e) => {
            let _ = client.stop_and_close().await;
            return Err(RuntimeError::Mission(e));
        }
    };
    let outcome = {
        let mut laser_client = connect_laser(board, laser(), Opening::First)
            .await
            .map_err(|e| e.at(laser_source(board)))?;
        // Mission time runs on across reconnections, and across a `--resume` from where the
        // saved mission stopped.
        let resumed_s = resumed
            .as_ref()
            .map_or(0.0, |(s, _)| s.mission_time_s.max(0.0));
        let epoch = Instant::now()
            .checked_sub(Duration::from_secs_f64(resumed_s))
            .unwrap_or_else(Instant::now);
        let mut reconnects = 0u32;
        let outcome = loop {
            let r = pump(
                board,
                &mut client,
                &mut laser_client,
                mission.as_mut(),
                Records {
                    store: &store,
                    telemetry: &mut telemetry,
                },
                epoch,
                &mut shutdown,
            )
            .await;
            let robot_lost = matches!(
                r,
                Err(RuntimeError::Session(
                    SessionError::Closed
                        | SessionError::Io(_)
                        | SessionError::MicrocontrollerReset { .. }
                ))
            );
            let laser_lost = matches!(r, Err(RuntimeError::Laser(_)));
            if !(robot_lost || laser_lost) || reconnects >= MAX_RECONNECTS {
                break r;
            }
            reconnects += 1;
            mission.on_reconnect();
            let (state, map) = mission.snapshot();
            tracing::warn!(
                robot = robot_lost,
                laser = laser_lost,
                "link lost; reconnecting"
            );
            telemetry.fault(state.mission_time_s, &Fault::Link.to_string())?;
            mission.on_fault(state.mission_time_s, Fault::Link);
            store.save(&state, map.as_ref())?;
            telemetry.record(
                state.mission_time_s,
                "reconnect",
                serde_json::json!({"robot": robot_lost, "laser": laser_lost, "count": reconnects}),
            )?;
            let reconnect = async {
                if robot_lost {
                    client =
                        retry_session("robot", || connect_robot(board, Opening::Again)).await?;
                    // Motion stays refused until the mission has re-planned.
                    client.halt(Fault::Link).await?;
                } else {
                    let _ = client.halt(Fault::Link).await;
                    laser_client =
                        retry_session("laser", || connect_laser(board, laser(), Opening::Again))
                            .await?;
                }
                Ok::<(), RuntimeError>(())
            };
            tokio::select! {
                r = reconnect => r?,
                _ = &mut shutdown => break Ok(RunOutcome::Interrupted),
            }
        };
        let _ = laser_client.close().await;
        let (state, map) = mission.snapshot();
        store.save(&state, map.as_ref())?;
        if let Some(map) = map {
            let track = crate::picture::Track {
                trajectory: state
                    .trajectory
                    .iter()
                    .map(|p| Point2::new(p.x_m, p.y_m))
                    .collect(),
                targets: telemetry.targets().to_vec(),
            };
            map.write_png(&options.log_dir.join("map.png"), &track)?;
        }
        // The session's last figures are recorded at the mission time it ended.
        (outcome, now_s(epoch))
    };
    let (outcome, end_s) = outcome;
    let stats = client.stop_and_close().await;
    if let Ok(stats) = &stats {
        telemetry.link_stats(end_s, stats)?;
        tracing::info!(%stats.codec, "robot stopped, motors disabled, session closed");
    }
    telemetry.flush()?;
    let outcome = outcome?;
    stats?;
    Ok(outcome)
}

/// Where the pump saves the mission state and writes telemetry.
pub struct Records<'a> {
    /// The state files.
    pub store: &'a StateStore,
    /// The telemetry log.
    pub telemetry: &'a mut Telemetry,
}

/// The mission pump (mission time counts from `epoch`): feeds the mission with status packets and scans, applies its commands,
/// enforces the safety rules and saves the state every `save_every_s`.
pub async fn pump(
    board: &BoardConfig,
    client: &mut ArcosClient,
    laser: &mut LaserClient,
    mission: &mut dyn MissionDriver,
    records: Records<'_>,
    epoch: Instant,
    shutdown: &mut (impl std::future::Future<Output = ()> + Unpin),
) -> Result<RunOutcome, RuntimeError> {
    let Records { store, telemetry } = records;
    let start = Instant::now();
    let t = |i: Instant| i.saturating_duration_since(epoch).as_secs_f64();
    let stale = Duration::from_secs_f32(board.safety.stale_timeout_s);
    let save_every = Duration::from_secs_f32(board.persistence.save_every_s);
    // Short, so that a scan waiting on its socket is read (and timed) within a few
    // milliseconds of its arrival: its time places it on the odometry.
    let tick = Duration::from_millis(5);
    let mut progress = Progress::new(now_s(epoch));
    let mut last_status = start;
    let mut last_scan = start;
    let mut next_save = start + save_every;
    let mut in_contact = false;
    // Status packets are placed on the robot's own clock, its SIP cycle (the firmware stamps
    // none), as scans are on the laser's (`sensor_clock`): a packet read late is still the
    // odometry of the moment it was sent.
    let sip_cycle_ms = client.config().map_or(100, |c| c.sip_cycle_ms).max(10);
    let mut sip_clock = super::sensor_clock::PeriodicClock::new(f64::from(sip_cycle_ms) * 1e-3);
    loop {
        let now = Instant::now();
        // The signal is checked between events (at least every `tick`), never by cancelling
        // a session call half-way through writing a command.
        let signalled = tokio::select! {
            biased;
            _ = &mut *shutdown => true,
            _ = std::future::ready(()) => false,
        };
        if signalled {
            client.halt(Fault::Operator).await?;
            telemetry.fault(t(Instant::now()), "stopped by signal")?;
            return Ok(RunOutcome::Interrupted);
        }
        let event = client.next_event(now + tick).await?;
        if let Some(super::robot::RobotEvent::Status { at, status }) = event {
            last_status = at;
            mission.on_status(sip_clock.place(t(at)), &status);
            // A wheel stall or a bumper is the mission's to handle: its safety monitor stops
            // and backs off before re-planning (a stop here would cut that back-off short).
            let contact = status.stalled() || status.bumpers_a() != 0 || status.bumpers_b() != 0;
            if contact && !in_contact {
                telemetry.record(
                    t(at),
                    "contact",
                    serde_json::json!({"stall_bumpers": status.stall_bumpers}),
                )?;
            }
            in_contact = contact;
            if status.estop() {
                stop_for(client, mission, telemetry, t(at), Fault::EStop).await?;
            }
        }
        match laser
            .next_scan(Instant::now() + Duration::from_millis(1))
            .await
        {
            Ok(Some((at, scan))) => {
                last_scan = at;
                mission.on_scan(t(at), &scan);
            }
            Ok(None) => {}
            Err(e) => {
                tracing::warn!(error = %e, "laser link lost");
                stop_for(
                    client,
                    mission,
                    telemetry,
                    t(Instant::now()),
                    Fault::StaleScan,
                )
                .await?;
                return Err(RuntimeError::Laser(e));
            }
        }
        let now = Instant::now();
        if now - last_status > stale {
            stop_for(client, mission, telemetry, t(now), Fault::StaleStatus).await?;
        } else if now - last_scan > stale {
            stop_for(client, mission, telemetry, t(now), Fault::StaleScan).await?;
        } else if client.fault().is_some() && mission.replanned() {
            client.clear_fault();
        }
        for r in mission.take_telemetry() {
            progress.note(&r);
            telemetry.record(r.t_s, r.kind, r.fields)?;
        }
        progress.print_if_due(t(now));
        match mission.step(t(now)) {
            MissionCommand::Done => {
                // The mission thread may have published its end (and its `done` record)
                // after the telemetry above was taken: record what is left.
                for r in mission.take_telemetry() {
                    progress.note(&r);
                    telemetry.record(r.t_s, r.kind, r.fields)?;
                }
                return Ok(RunOutcome::Finished);
            }
            MissionCommand::Hold => {}
            MissionCommand::Drive(velocity) => match client.drive(velocity).await {
                Ok(()) | Err(SessionError::Faulted(_)) => {}
                Err(e) => return Err(e.into()),
            },
        }
        if now >= next_save {
            next_save = now + save_every;
            let (mut state, map) = mission.snapshot();
            state.version = STATE_VERSION;
            store.save(&state, map.as_ref())?;
            telemetry.pose(t(now), state.pose)?;
            telemetry.coverage(t(now), state.coverage)?;
            telemetry.link_stats(t(now), &client.stats())?;
            telemetry.flush()?;
        }
    }
}

/// How often `papillon run` prints a progress line \[s\].
pub const PROGRESS_EVERY_S: f64 = 5.0;

fn now_s(epoch: Instant) -> f64 {
    Instant::now()
        .saturating_duration_since(epoch)
        .as_secs_f64()
}

/// The progress line on standard error: the mission's latest `mission` telemetry record,
/// every [`PROGRESS_EVERY_S`], and the `done` record with its reason.
struct Progress {
    last: Option<serde_json::Value>,
    next_s: f64,
}

impl Progress {
    fn new(now_s: f64) -> Self {
        Self {
            last: None,
            next_s: now_s + PROGRESS_EVERY_S,
        }
    }

    fn note(&mut self, record: &super::driver::TelemetryRecord) {
        match record.kind {
            "mission" => self.last = Some(record.fields.clone()),
            "done" => tracing::info!(
                t_s = format_args!("{:.0}", record.t_s),
                reason = %record.fields["reason"].as_str().unwrap_or("?"),
                "mission done"
            ),
            "returning" => tracing::info!(
                t_s = format_args!("{:.0}", record.t_s),
                reason = %record.fields["reason"].as_str().unwrap_or("?"),
                start_distance_m = format_args!(
                    "{:.1}",
                    record.fields["start_distance_m"].as_f64().unwrap_or(0.0)
                ),
                "mission ended: returning to the start"
            ),
            _ => {}
        }
    }

    fn print_if_due(&mut self, t_s: f64) {
        if t_s < self.next_s {
            return;
        }
        self.next_s = t_s + PROGRESS_EVERY_S;
        let Some(m) = &self.last else {
            return;
        };
        let num = |k: &str| m[k].as_f64().unwrap_or(0.0);
        tracing::info!(
            t_s = format_args!("{t_s:.0}"),
            known_m2 = format_args!("{:.1}", num("known_m2")),
            battery_steps = format_args!("{:.1}", num("battery_steps")),
            state = %m["state"].as_str().unwrap_or("?"),
            decisions = num("decisions"),
            replans = num("replans"),
            replans_per_decision = format_args!("{:.2}", num("replans_per_decision")),
            "progress"
        );
    }
}

async fn stop_for(
    client: &mut ArcosClient,
    mission: &mut dyn MissionDriver,
    telemetry: &mut Telemetry,
    t_s: f64,
    fault: Fault,
) -> Result<(), RuntimeError> {
    if client.fault().is_none() {
        tracing::warn!(%fault, "stopping the robot");
        telemetry.fault(t_s, &fault.to_string())?;
        mission.on_fault(t_s, fault);
    }
    client.halt(fault).await?;
    Ok(())
}

/// Options of `papillon probe`.
#[derive(Clone, Debug)]
pub struct ProbeOptions {
    /// Serial device (ignored when `tcp` is set).
    pub port: String,
    /// TCP address instead of a serial port.
    pub tcp: Option<String>,
    /// Drive a small square at low speed and report the odometry.
    pub drive: bool,
    /// The serial speed to use \[baud\]; `None` tries [`PROBE_BAUD_RATES`] in turn.
    pub baud: Option<u32>,
    /// The laser to check with one scan: `board.laser` as the board (with `--laser`) says;
    /// `None` checks no laser.
    pub laser: Option<BoardConfig>,
}

/// The serial speeds `probe` tries, in order, when none is forced: the P3-DX's power-up 9600
/// first, then the speeds HOSTBAUD can select (a robot whose FLASH `HostBaud` was changed
/// answers at that speed).
pub const PROBE_BAUD_RATES: [u32; 5] = crate::config::ARCOS_BAUD_RATES;

/// How long `probe` waits for each SYNC reply while it looks for the robot's speed.
pub const PROBE_SYNC_TIMEOUT: Duration = Duration::from_millis(400);

/// Opens the link and runs the ARCOS handshake: at `options.baud`, or at each of
/// [`PROBE_BAUD_RATES`] in turn until the robot answers (over TCP, once). Writes one line per
/// speed tried.
pub(super) async fn probe_connect(
    options: &ProbeOptions,
    out: &mut impl io::Write,
) -> Result<ArcosClient, RuntimeError> {
    let session = SessionOptions {
        expected_subclass: None,
        ..SessionOptions::default()
    };
    let rates: Vec<u32> = match (&options.tcp, options.baud) {
        (Some(_), _) => vec![9600],
        (None, Some(b)) => vec![b],
        (None, None) => PROBE_BAUD_RATES.to_vec(),
    };
    let searching = rates.len() > 1;
    let mut last = None;
    for &baud in &rates {
        let link = open_robot_link(options.tcp.as_deref(), &options.port, baud).await?;
        writeln!(out, "link: {}", link.describe())?;
        // While searching, a short handshake per speed; the speed found then gets a whole one.
        let trial = if searching {
            SessionOptions {
                sync_timeout: PROBE_SYNC_TIMEOUT,
                sync_attempts: 2,
                ..session.clone()
            }
        } else {
            session.clone()
        };
        match ArcosClient::connect(link, trial).await {
            Ok(client) => {
                if searching {
                    writeln!(out, "baud: the robot answers at {baud} baud")?;
                }
                return Ok(client);
            }
            Err(e @ (SessionError::HandshakeFailed { .. } | SessionError::Io(_))) if searching => {
                writeln!(out, "baud: no answer at {baud} baud ({e})")?;
                last = Some(e);
            }
            Err(e) => return Err(e.into()),
        }
    }
    Err(match last {
        Some(e) => RuntimeError::Session(e),
        None => RuntimeError::Link(io::Error::other("no serial speed to try")),
    })
}

/// `papillon probe`: connects, prints the robot's identity, CONFIG highlights, battery and
/// pose, optionally drives a 0.5 m square at 100 mm/s, then disconnects cleanly. Lines are
/// written to `out`.
pub async fn probe_with(
    options: &ProbeOptions,
    out: &mut impl io::Write,
) -> Result<(), RuntimeError> {
    let mut client = probe_connect(options, out).await?;
    let id = client.identity().clone();
    writeln!(
        out,
        "robot: name {:?}, class {:?}, subclass {:?}",
        id.name, id.class, id.subclass
    )?;
    if let Some(c) = client.config() {
        writeln!(
            out,
            "config: firmware {:?}, serial {:?}, top speeds {} mm/s / {} deg/s, current max {} mm/s / {} deg/s, watchdog {} ms, SIP cycle {} ms, host baud code {}, autobaud {}",
            c.extras
                .firmware_version
                .as_ref()
                .map(|v| v.as_str())
                .unwrap_or_default(),
            c.serial,
            c.trans_vel_top,
            c.rot_vel_top,
            c.trans_vel_max,
            c.rot_vel_max,
            c.watchdog_ms,
            c.sip_cycle_ms,
            c.host_baud,
            c.auto_baud
        )?;
    }
    writeln!(out, "baud: {:?}", client.baud_switch())?;
    let mut odometry = ArcosOdometry::new();
    let status = next_status(&mut client, Duration::from_secs(2)).await?;
    match status {
        Some(s) => writeln!(
            out,
            "status: battery {:.1} V, pose {} (counters x {}, y {}, th {}), motors {}, e-stop {}",
            f32::from(s.battery_dv) * 0.1,
            pose_text(odometry.update(s.x_pos, s.y_pos, s.th_pos)),
            s.x_pos,
            s.y_pos,
            s.th_pos,
            if s.motors_enabled() {
                "enabled"
            } else {
                "disabled"
            },
            if s.estop() { "PRESSED" } else { "released" }
        )?,
        None => writeln!(out, "status: no status packet within 2 s")?,
    }
    if options.drive {
        let limits = MotionLimits {
            max_speed_mm_s: 150,
            max_turn_rate_deg_s: 30,
            accel_mm_s2: 200,
            decel_mm_s2: 200,
            rot_accel_deg_s2: 60,
        };
        client.start(&limits).await?;
        // The square's velocities go through the same limits the firmware was just given.
        let clamp = Limits::new(150, 30, 200, 200, 60, 60);
        let ahead = clamp.clamp(MotionCommand {
            speed_mm_s: 100,
            turn_rate_deg_s: 0,
        });
        let turn = clamp.clamp(MotionCommand {
            speed_mm_s: 0,
            turn_rate_deg_s: 30,
        });
        let start = odometry.pose_odom();
        for side in 0..4 {
            drive_for(&mut client, &mut odometry, ahead, Duration::from_secs(5)).await?;
            drive_for(&mut client, &mut odometry, turn, Duration::from_secs(3)).await?;
            if let Some(s) = next_status(&mut client, Duration::from_secs(1)).await? {
                let pose = odometry.update(s.x_pos, s.y_pos, s.th_pos);
                writeln!(
                    out,
                    "square side {}: odometry {}",
                    side + 1,
                    pose_text(pose)
                )?;
            }
        }
        let end = odometry.pose_odom();
        writeln!(
            out,
            "square: driven {:.2} m, closure error {:.0} mm",
            odometry.distance_travelled_m(),
            libm::hypotf(end.x - start.x, end.y - start.y) * 1000.0
        )?;
    }
    let stats = client.stop_and_close().await?;
    writeln!(out, "link: {}", stats.codec)?;
    writeln!(out, "disconnected: motors disabled, session closed")?;
    if let Some(board) = &options.laser {
        probe_laser(board, out).await?;
    }
    Ok(())
}

/// How long `probe` waits for the laser's first scan.
pub const PROBE_SCAN_WAIT: Duration = Duration::from_secs(5);

/// Connects the board's laser, takes one scan and prints its beam count (against the board's)
/// and its ranges.
async fn probe_laser(board: &BoardConfig, out: &mut impl io::Write) -> Result<(), RuntimeError> {
    let model = board.laser.model.as_str();
    let at = board
        .laser
        .address
        .as_ref()
        .or(board.laser.port.as_ref())
        .map_or("?", |a| a.as_str());
    let mut laser = connect_laser(board, laser_codec(), Opening::First)
        .await
        .map_err(|e| e.at(laser_source(board)))?;
    let scan = laser.next_scan(Instant::now() + PROBE_SCAN_WAIT).await;
    let _ = laser.close().await;
    let Some((_, scan)) = scan.map_err(RuntimeError::Laser)? else {
        writeln!(
            out,
            "laser: {model} at {at}: no scan within {} s",
            PROBE_SCAN_WAIT.as_secs()
        )?;
        return Err(RuntimeError::Laser(super::laser::LaserError::Io(
            io::Error::new(
                io::ErrorKind::TimedOut,
                format!("no scan within {} s", PROBE_SCAN_WAIT.as_secs()),
            ),
        )));
    };
    let ranges: Vec<f32> = scan.beams().iter().filter_map(|b| b.range_m).collect();
    let (lo, hi) = ranges.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &r| {
        (lo.min(r), hi.max(r))
    });
    let expected = board.laser.beam_count;
    writeln!(
        out,
        "laser: {model} at {at}: one scan of {} beams ({}), {} returns{}",
        scan.len(),
        if scan.len() == usize::from(expected) {
            format!("as the board's {expected}")
        } else {
            format!("the board says {expected}: check $.laser.beam_count")
        },
        ranges.len(),
        if ranges.is_empty() {
            ", nothing within range".to_string()
        } else {
            format!(", ranges {lo:.2} m to {hi:.2} m")
        }
    )?;
    Ok(())
}

/// An odometry pose as the probe prints it.
fn pose_text(p: crate::geometry::Pose2) -> String {
    format!(
        "x {:.0} mm, y {:.0} mm, heading {:.1} deg",
        p.x * 1000.0,
        p.y * 1000.0,
        p.theta.to_degrees()
    )
}

pub(super) async fn next_status(
    client: &mut ArcosClient,
    wait: Duration,
) -> Result<Option<StatusPacket>, RuntimeError> {
    let deadline = Instant::now() + wait;
    while let Some(ev) = client.next_event(deadline).await? {
        if let super::robot::RobotEvent::Status { status, .. } = ev {
            return Ok(Some(*status));
        }
    }
    Ok(None)
}

/// Drives at a constant command for `duration`, re-sending it every 200 ms (fresh, not stale:
/// the loop is alive), then stops.
async fn drive_for(
    client: &mut ArcosClient,
    odometry: &mut ArcosOdometry,
    velocity: crate::control::command::Velocity,
    duration: Duration,
) -> Result<(), RuntimeError> {
    let end = Instant::now() + duration;
    while Instant::now() < end {
        client.drive(velocity).await?;
        let resend = (Instant::now() + Duration::from_millis(200)).min(end);
        while let Some(ev) = client.next_event(resend).await? {
            if let super::robot::RobotEvent::Status { status: s, .. } = ev {
                odometry.update(s.x_pos, s.y_pos, s.th_pos);
            }
        }
    }
    client
        .drive(crate::control::command::Velocity::ZERO)
        .await?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::onboard::laser::tests::ByteCodec;
    use crate::onboard::testkit::{CommandLog, FakeRobotScript, run_fake_robot};

    /// The fake robot behind [`tcp_robot`] has ended: it ends when the runtime's CLOSE reaches
    /// it (or the link to it ends). It reads the link on its own task, so the last commands
    /// reach its log a little after the run returns; this waits for that event, not for a time.
    struct RobotDone(tokio::sync::oneshot::Receiver<()>);

    impl RobotDone {
        /// Waits for the event; the 120 s bound only turns a hang (no CLOSE ever reaching the
        /// robot) into a failure.
        async fn wait(self) {
            let ended = tokio::time::timeout(Duration::from_secs(120), self.0).await;
            assert!(
                ended.is_ok(),
                "the fake robot never ended: no CLOSE reached it"
            );
        }
    }

    /// A mission that is done at its first step, never moving the robot.
    struct DoneAtOnce;

    impl MissionDriver for DoneAtOnce {
        fn on_status(&mut self, _: f64, _: &StatusPacket) {}
        fn on_scan(&mut self, _: f64, _: &Scan) {}
        fn on_fault(&mut self, _: f64, _: Fault) {}
        fn on_reconnect(&mut self) {}
        fn replanned(&self) -> bool {
            true
        }
        fn step(&mut self, _: f64) -> MissionCommand {
            MissionCommand::Done
        }
        fn snapshot(&self) -> (MissionState, Option<MapImage>) {
            let state = MissionState {
                version: STATE_VERSION,
                ..MissionState::default()
            };
            (state, None)
        }
    }

    fn byte_codec() -> Box<dyn LaserCodec> {
        Box::new(ByteCodec::default())
    }

    /// A fake robot behind a loopback TCP listener.
    ///
    /// The bridge copies each direction on its own: the runtime closes its socket right after
    /// CLOSE with status packets unread, so the kernel answers with a reset, and the robot's next
    /// status packet then fails to reach the socket. With `copy_bidirectional` that error ended
    /// the bridge before it had passed on the CLOSE still waiting in the socket (under load,
    /// now and then), and the log lacked the CLOSE. Here what the runtime wrote is always passed
    /// on to the end, and what the robot sends after the runtime hung up is dropped.
    async fn tcp_robot(script: FakeRobotScript) -> (String, CommandLog, RobotDone) {
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let log = CommandLog::default();
        let log2 = log.clone();
        let (done_tx, done_rx) = tokio::sync::oneshot::channel();
        tokio::spawn(async move {
            let (sock, _) = listener.accept().await.unwrap();
            let (a, b) = tokio::io::duplex(4096);
            tokio::spawn(async move {
                run_fake_robot(a, script, log2).await;
                let _ = done_tx.send(());
            });
            let (mut sock_rx, mut sock_tx) = sock.into_split();
            let (mut robot_rx, mut robot_tx) = tokio::io::split(b);
            let to_robot = async move {
                let _ = tokio::io::copy(&mut sock_rx, &mut robot_tx).await;
                let _ = robot_tx.shutdown().await;
            };
            let from_robot = async move {
                let mut buf = [0u8; 512];
                let mut open = true;
                while let Ok(n @ 1..) = robot_rx.read(&mut buf).await {
                    open = open && sock_tx.write_all(&buf[..n]).await.is_ok();
                }
            };
            tokio::join!(to_robot, from_robot);
        });
        (addr, log, RobotDone(done_rx))
    }

    fn temp_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("papillon-runtime-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[tokio::test]
    async fn run_of_a_mission_done_at_once_starts_up_then_stops_safely() {
        let (addr, log, robot_done) = tcp_robot(FakeRobotScript::default()).await;
        let laser = super::reconnect_tests::laser_server().await;
        let mut board = BoardConfig::default();
        board.robot.subclass = crate::config::Name::new("p3dx-sh").unwrap();
        board.link.tcp = crate::config::Address::new(&addr);
        board.laser.address = crate::config::Address::new(&laser);
        board.laser.beam_count = 3;
        let dir = temp_dir("doneatonce");
        let outcome = run_with(
            RunOptions {
                board,
                log_dir: dir.clone(),
                start: Start::New,
            },
            byte_codec,
            |_, _| Ok(Box::new(DoneAtOnce) as Box<dyn MissionDriver>),
            std::future::pending(),
        )
        .await
        .unwrap();
        assert_eq!(outcome, RunOutcome::Finished);
        robot_done.wait().await;
        let sent: Vec<(u8, Option<i16>)> = log
            .lock()
            .unwrap()
            .iter()
            .map(|&(_, n, a)| (n, a))
            .collect();
        assert!(
            sent.contains(&(4, Some(1))),
            "motors were enabled at start-up"
        );
        let n = sent.len();
        assert_eq!(
            &sent[n - 2..],
            [(4, Some(0)), (2, Some(1))],
            "ENABLE 0 then CLOSE last: {sent:?}"
        );
        assert!(
            !sent
                .iter()
                .any(|&(c, a)| (c == 11 || c == 21) && a != Some(0))
        );
        let saved = StateStore::open(&dir).unwrap().load().unwrap();
        assert!(saved.is_some(), "the mission's state is saved at the end");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[tokio::test]
    async fn resume_without_saved_state_is_refused_before_connecting() {
        let dir = temp_dir("noresume");
        let err = run_with(
            RunOptions {
                board: BoardConfig::default(),
                log_dir: dir.clone(),
                start: Start::Resume,
            },
            byte_codec,
            |_, _| Ok(Box::new(DoneAtOnce) as Box<dyn MissionDriver>),
            std::future::pending(),
        )
        .await
        .unwrap_err();
        assert!(matches!(err, RuntimeError::NothingToResume(_)));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[tokio::test]
    async fn probe_prints_identity_config_and_status() {
        let (addr, log, robot_done) = tcp_robot(FakeRobotScript::default()).await;
        let mut out = Vec::new();
        probe_with(
            &ProbeOptions {
                port: String::new(),
                tcp: Some(addr),
                drive: false,
                baud: None,
                laser: None,
            },
            &mut out,
        )
        .await
        .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("subclass \"p3dx-sh\""), "{text}");
        assert!(text.contains("watchdog 2000 ms"), "{text}");
        assert!(text.contains("battery 13.0 V"), "{text}");
        assert!(text.contains("disconnected"), "{text}");
        robot_done.wait().await;
        let last = log.lock().unwrap().last().map(|&(_, n, a)| (n, a));
        assert_eq!(last, Some((2, Some(1))));
    }
}

#[cfg(test)]
mod pump_tests {
    use super::*;
    use crate::onboard::laser::tests::{ByteCodec, streaming_laser};
    use crate::onboard::link::DuplexLink;
    use crate::onboard::testkit::{CommandLog, FakeRobotScript, run_fake_robot};
    use std::sync::{Arc, Mutex};

    /// Faults a mission saw, with their mission times \[s\].
    type FaultLog = Arc<Mutex<Vec<(f64, Fault)>>>;

    /// Drives straight; re-plans 0.3 s after a fault; done at `done_at_s`.
    struct ScriptedMission {
        faults: FaultLog,
        fault_at: Option<f64>,
        replanned: bool,
        scans: u64,
        statuses: u64,
        now_s: f64,
        done_at_s: f64,
    }

    impl MissionDriver for ScriptedMission {
        fn on_status(&mut self, _t_s: f64, _status: &StatusPacket) {
            self.statuses += 1;
        }
        fn on_scan(&mut self, _t_s: f64, scan: &Scan) {
            assert_eq!(scan.len(), 3);
            self.scans += 1;
        }
        fn on_fault(&mut self, t_s: f64, fault: Fault) {
            self.faults.lock().unwrap().push((t_s, fault));
            self.fault_at = Some(t_s);
            self.replanned = false;
        }
        fn on_reconnect(&mut self) {}
        fn replanned(&self) -> bool {
            self.replanned
        }
        fn step(&mut self, t_s: f64) -> MissionCommand {
            self.now_s = t_s;
            if let Some(f) = self.fault_at
                && t_s - f > 0.3
            {
                self.replanned = true;
            }
            if t_s >= self.done_at_s {
                MissionCommand::Done
            } else {
                MissionCommand::Drive(Limits::default().clamp(MotionCommand {
                    speed_mm_s: 100,
                    turn_rate_deg_s: 0,
                }))
            }
        }
        fn snapshot(&self) -> (MissionState, Option<MapImage>) {
            (
                MissionState {
                    version: STATE_VERSION,
                    mission_time_s: self.now_s,
                    counters: crate::onboard::persist::Counters {
                        scans: self.scans,
                        ..Default::default()
                    },
                    ..MissionState::default()
                },
                None,
            )
        }
    }

    struct Rig {
        client: ArcosClient,
        laser: LaserClient,
        log: CommandLog,
        board: BoardConfig,
        store: StateStore,
        telemetry: Telemetry,
        dir: PathBuf,
        t0: Instant,
    }

    async fn rig(name: &str, dropout: (Duration, Duration)) -> Rig {
        let (link, peer) = DuplexLink::pair(8192, None);
        let log = CommandLog::default();
        tokio::spawn(run_fake_robot(
            peer,
            FakeRobotScript::default(),
            log.clone(),
        ));
        let mut board = BoardConfig::default();
        board.safety.stale_timeout_s = 0.5;
        board.persistence.save_every_s = 1.0;
        let client = ArcosClient::connect(Box::new(link), SessionOptions::default())
            .await
            .unwrap();
        let (llink, lpeer) = DuplexLink::pair(8192, None);
        tokio::spawn(streaming_laser(lpeer, Duration::from_millis(100), dropout));
        let mut laser_config = board.laser_config();
        laser_config.beam_count = 3;
        let laser = LaserClient::Lms1xx(
            Lms1xxClient::connect(
                Box::new(llink),
                Box::new(ByteCodec::default()),
                laser_config,
            )
            .await
            .unwrap(),
        );
        let dir = std::env::temp_dir().join(format!("papillon-pump-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Rig {
            client,
            laser,
            log,
            board,
            store: StateStore::open(&dir).unwrap(),
            telemetry: Telemetry::open(&dir).unwrap(),
            dir,
            t0: Instant::now(),
        }
    }

    fn mission(done_at_s: f64) -> (ScriptedMission, FaultLog) {
        let faults = Arc::new(Mutex::new(Vec::new()));
        (
            ScriptedMission {
                faults: faults.clone(),
                fault_at: None,
                replanned: true,
                scans: 0,
                statuses: 0,
                now_s: 0.0,
                done_at_s,
            },
            faults,
        )
    }

    #[tokio::test(start_paused = true)]
    async fn laser_dropout_stops_the_robot_until_scans_return_and_a_replan() {
        let mut r = rig(
            "dropout",
            (Duration::from_millis(1000), Duration::from_millis(1800)),
        )
        .await;
        let (mut m, faults) = mission(3.0);
        let mut never = std::pin::pin!(std::future::pending::<()>());
        let outcome = pump(
            &r.board,
            &mut r.client,
            &mut r.laser,
            &mut m,
            Records {
                store: &r.store,
                telemetry: &mut r.telemetry,
            },
            Instant::now(),
            &mut never,
        )
        .await
        .unwrap();
        assert_eq!(outcome, RunOutcome::Finished);
        let faults = faults.lock().unwrap().clone();
        assert_eq!(faults.len(), 1, "{faults:?}");
        assert_eq!(faults[0].1, Fault::StaleScan);
        // The stop comes within the stale timeout (+ one 100 ms scan period) of the last scan.
        assert!(
            (1.4..1.65).contains(&faults[0].0),
            "fault at {} s",
            faults[0].0
        );
        let log = r.log.lock().unwrap().clone();
        let halt = log
            .iter()
            .position(|&(t, n, a)| {
                n == 11 && a == Some(0) && t > r.t0 + Duration::from_millis(1300)
            })
            .expect("a VEL 0 at the dropout");
        let resumed = log[halt..]
            .iter()
            .find(|&&(_, n, a)| n == 11 && a != Some(0))
            .expect("driving resumed after the dropout");
        assert!(
            resumed.0 >= r.t0 + Duration::from_millis(1800),
            "no motion before scans return"
        );
        assert!(m.scans >= 15 && m.statuses >= 20);
        let saved = r.store.load().unwrap().unwrap().0;
        assert!(
            saved.mission_time_s >= 1.0,
            "state saved during the mission"
        );
        std::fs::remove_dir_all(&r.dir).unwrap();
    }

    #[tokio::test(start_paused = true)]
    async fn shutdown_signal_stops_the_robot_mid_mission() {
        let mut r = rig("signal", (Duration::MAX, Duration::MAX)).await;
        let (mut m, faults) = mission(100.0);
        let mut signal = std::pin::pin!(tokio::time::sleep(Duration::from_millis(1200)));
        let outcome = pump(
            &r.board,
            &mut r.client,
            &mut r.laser,
            &mut m,
            Records {
                store: &r.store,
                telemetry: &mut r.telemetry,
            },
            Instant::now(),
            &mut signal,
        )
        .await
        .unwrap();
        assert_eq!(outcome, RunOutcome::Interrupted);
        assert!(faults.lock().unwrap().is_empty());
        assert_eq!(r.client.fault(), Some(Fault::Operator));
        r.client.stop_and_close().await.unwrap();
        tokio::time::sleep(Duration::from_millis(20)).await;
        let sent: Vec<(u8, Option<i16>)> = r
            .log
            .lock()
            .unwrap()
            .iter()
            .map(|&(_, n, a)| (n, a))
            .collect();
        let n = sent.len();
        assert_eq!(&sent[n - 2..], [(4, Some(0)), (2, Some(1))]);
        let last_nonzero = sent
            .iter()
            .rposition(|&(c, a)| c == 11 && a == Some(100))
            .unwrap();
        let first_stop_after = sent[last_nonzero..]
            .iter()
            .position(|&c| c == (11, Some(0)));
        assert!(first_stop_after.is_some());
        std::fs::remove_dir_all(&r.dir).unwrap();
    }
}

#[cfg(test)]
mod reconnect_tests {
    use super::*;
    use crate::onboard::laser::tests::{ByteCodec, streaming_laser};
    use crate::onboard::testkit::{CommandLog, FakeRobotScript, run_fake_robot};

    /// A robot behind a TCP listener; the first connection is cut after `cut_after`.
    async fn flaky_robot(cut_after: Duration) -> (String, CommandLog) {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let log = CommandLog::default();
        let log2 = log.clone();
        tokio::spawn(async move {
            let mut first = true;
            while let Ok((mut sock, _)) = listener.accept().await {
                let (a, mut b) = tokio::io::duplex(8192);
                tokio::spawn(run_fake_robot(a, FakeRobotScript::default(), log2.clone()));
                let bridge = tokio::spawn(async move {
                    let _ = tokio::io::copy_bidirectional(&mut sock, &mut b).await;
                });
                if first {
                    first = false;
                    tokio::time::sleep(cut_after).await;
                    bridge.abort();
                }
            }
        });
        (addr, log)
    }

    /// An LMS1xx double (the test byte codec's format) streaming 3-beam scans every 50 ms
    /// behind a loopback TCP listener.
    pub(super) async fn laser_server() -> String {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        tokio::spawn(async move {
            while let Ok((mut sock, _)) = listener.accept().await {
                let (a, mut b) = tokio::io::duplex(8192);
                tokio::spawn(streaming_laser(
                    a,
                    Duration::from_millis(50),
                    (Duration::MAX, Duration::MAX),
                ));
                tokio::spawn(async move {
                    let _ = tokio::io::copy_bidirectional(&mut sock, &mut b).await;
                });
            }
        });
        addr
    }

    /// Drives until `done_at_s`; re-plans 0.2 s after a fault.
    struct Mission {
        faults: Vec<(f64, Fault)>,
        fault_at: Option<f64>,
        now_s: f64,
        reconnects: u64,
    }

    impl MissionDriver for Mission {
        fn on_status(&mut self, _: f64, _: &StatusPacket) {}
        fn on_scan(&mut self, _: f64, _: &Scan) {}
        fn on_fault(&mut self, t_s: f64, fault: Fault) {
            self.faults.push((t_s, fault));
            self.fault_at = Some(t_s);
        }
        fn on_reconnect(&mut self) {
            self.reconnects += 1;
        }
        fn replanned(&self) -> bool {
            self.fault_at.is_none_or(|f| self.now_s - f > 0.2)
        }
        fn step(&mut self, t_s: f64) -> MissionCommand {
            self.now_s = t_s;
            let after_fault = self.fault_at.is_some_and(|f| t_s - f > 0.5);
            if after_fault || t_s > 10.0 {
                MissionCommand::Done
            } else {
                MissionCommand::Drive(Limits::default().clamp(MotionCommand {
                    speed_mm_s: 120,
                    turn_rate_deg_s: 0,
                }))
            }
        }
        fn snapshot(&self) -> (MissionState, Option<MapImage>) {
            let state = MissionState {
                version: STATE_VERSION,
                mission_time_s: self.now_s,
                counters: crate::onboard::persist::Counters {
                    faults: self.faults.len() as u64,
                    reconnects: self.reconnects,
                    ..Default::default()
                },
                ..MissionState::default()
            };
            (state, None)
        }
    }

    #[tokio::test]
    async fn a_cut_robot_link_is_reconnected_and_the_mission_finishes() {
        let (robot, log) = flaky_robot(Duration::from_millis(600)).await;
        let laser = laser_server().await;
        let mut board = BoardConfig::default();
        board.robot.subclass = crate::config::Name::new("p3dx-sh").unwrap();
        board.link.tcp = crate::config::Address::new(&robot);
        board.laser.address = crate::config::Address::new(&laser);
        board.laser.beam_count = 3;
        let dir = std::env::temp_dir().join(format!("papillon-reconnect-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let outcome = run_with(
            RunOptions {
                board,
                log_dir: dir.clone(),
                start: Start::New,
            },
            || Box::new(ByteCodec::default()) as Box<dyn LaserCodec>,
            |_, _| {
                Ok(Box::new(Mission {
                    faults: Vec::new(),
                    fault_at: None,
                    now_s: 0.0,
                    reconnects: 0,
                }) as Box<dyn MissionDriver>)
            },
            std::future::pending(),
        )
        .await
        .unwrap();
        assert_eq!(outcome, RunOutcome::Finished);
        let (state, _) = StateStore::open(&dir).unwrap().load().unwrap().unwrap();
        assert_eq!(state.counters.faults, 1, "one link fault");
        assert_eq!(state.counters.reconnects, 1, "one reconnection");
        assert!(
            state.mission_time_s > 1.0,
            "mission time runs on across the reconnection: {} s",
            state.mission_time_s
        );
        let telemetry = std::fs::read_to_string(dir.join("telemetry.jsonl")).unwrap();
        assert!(telemetry.contains("\"kind\":\"reconnect\""), "{telemetry}");
        // Two handshakes: SYNC2 (bare command 2) appears twice.
        let syncs = log
            .lock()
            .unwrap()
            .iter()
            .filter(|&&(_, n, a)| n == 2 && a.is_none())
            .count();
        assert_eq!(syncs, 2);
        // After the second handshake, the first velocity command is a stop.
        let entries = log.lock().unwrap().clone();
        let second = entries
            .iter()
            .rposition(|&(_, n, a)| n == 2 && a.is_none())
            .unwrap();
        let first_vel = entries[second..]
            .iter()
            .find(|&&(_, n, _)| n == 11)
            .unwrap();
        assert_eq!(first_vel.2, Some(0));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
