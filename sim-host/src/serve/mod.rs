//! The emulator server behind `papillon-sim serve`: a simulated world run in real time, with an
//! emulated P3-DX microcontroller (ARCOS, on a pseudo-terminal and/or TCP) and an emulated SICK
//! LMS1xx (CoLa-A over TCP) or LMS200 (on a second pseudo-terminal) per robot, so that the
//! onboard binary or other P3-DX software can be tested exactly as it talks to the robot.
//!
//! [`Server::start`] loads the world, places the robots ([`crate::placement::start_poses`], the
//! same rule as the fast runner's), opens every endpoint and starts the threads:
//!
//! - one physics thread steps every body to the wall clock about every 10 ms and writes the
//!   truth log;
//! - each endpoint (a pty master, or each client accepted on a TCP listener) has its own thread
//!   running a sans-IO emulator ([`crate::emulator`]) against its robot's body
//!   (`session.rs`).
//!
//! The bodies live in one `Mutex<Vec<RobotBody>>` shared by all threads (`Sim`); the clock is
//! the wall clock since the start. With several robots, all share the world (each sees the
//! others in its laser and collides with them) and robot `i` is served on the given ports plus
//! `i` (`LINK-i` for ptys). Faults ([`crate::faults`]) are injected on the links, the laser and
//! the bodies. [`Server::stop`] ends the threads' loops and removes the pty symlinks.

mod pty;
mod session;
pub mod signal;

use std::fmt;
use std::io::{self, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use papillon::geometry::Pose2;
use papillon::grid::CellClass;
use papillon::live::LiveServer;
use papillon::record::{PoseSource, RecordError, Recorder};
use papillon::sensor::{LaserConfig, Scan};

use crate::emulator::arcos::{Identity, Subclass};
use crate::faults::Faults;
use crate::laser::LaserSim;
use crate::physics::{BodyConfig, Disc, RobotBody, advance_all};
use crate::placement::start_poses;
use crate::world::World;

/// Cell size of the served world \[m\].
pub const MAP_RESOLUTION_M: f32 = 0.05;
/// Robot name answered in SYNC2 and CONFIG.
pub const ROBOT_NAME: &str = "papillon-sim";
/// Period of the truth log \[s\].
pub const TRUTH_PERIOD_S: f64 = 0.02;
/// Where the LMS1xx is served when no address is given.
pub const DEFAULT_LMS1XX_ADDR: &str = "127.0.0.1:2111";
/// Where the LMS200's pty symlink goes when no path is given.
pub const DEFAULT_LMS200_LINK: &str = "/tmp/papillon-sim-lms200";

/// Which laser the server emulates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaserModel {
    /// SICK LMS1xx, CoLa-A over TCP.
    Lms1xx,
    /// SICK LMS200, telegrams over a serial line (a pty here).
    Lms200,
}

/// What to serve.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// World: a built-in map name or a map file, loaded at [`MAP_RESOLUTION_M`].
    pub map: String,
    /// Serve ARCOS on a pseudo-terminal and make this path a symlink to its device.
    pub pty: Option<PathBuf>,
    /// Serve ARCOS over TCP on this address.
    pub tcp: Option<String>,
    /// Where the laser is served: a TCP address for the LMS1xx (default
    /// [`DEFAULT_LMS1XX_ADDR`]), a pty symlink path for the LMS200 (default
    /// [`DEFAULT_LMS200_LINK`]).
    pub laser: Option<String>,
    /// The emulated laser.
    pub laser_model: LaserModel,
    /// Seed of the simulation's random choices (wheel slip, faults).
    pub seed: u64,
    /// The robots' odometry slip ([`crate::scenario::Slip`], as `papillon-sim mission
    /// --slip`): the thesis's end-of-move slide by default; `realistic` adds per-robot
    /// wheel-diameter and wheelbase errors, random walks and fast-turn slip
    /// ([`crate::odometry_error`]), for a core that matches its scans.
    pub slip: crate::scenario::Slip,
    /// Faults to inject.
    pub faults: Faults,
    /// Robots sharing the world.
    pub robots: usize,
    /// Write each robot's true state to this file every [`TRUTH_PERIOD_S`] (JSON lines).
    pub truth_log: Option<PathBuf>,
    /// The emulated firmware's watchdog \[ms\].
    pub watchdog_ms: u16,
    /// What the microcontroller presents itself as (a robot, or MobileSim).
    pub identity: Identity,
    /// The P3-DX subclass emulated (its name and DistConvFactor).
    pub subclass: Subclass,
    /// Range noise of the emulated laser: each range gets Gaussian noise of standard deviation
    /// this fraction of the range ([`LaserSim`]'s model, the runner's), drawn afresh for every
    /// scan. 0: noise-free ranges. The runner simulates the laser of its mission
    /// configuration (`boards/sim-thesis.json`: 5 %, the thesis's; `boards/sim.json`: 0.3 %, an
    /// LMS1xx, with 12 mm more from `laser_range_sigma_m`); the binary predicts what the
    /// runner predicts only on the same laser (`scripts/house-check.sh` passes the board's).
    pub laser_noise_fraction: f32,
    /// Range noise of the emulated laser that does not grow with the range, standard
    /// deviation \[m\], added in quadrature to [`Self::laser_noise_fraction`]'s
    /// ([`LaserSim::with_range_sigma_m`]): a real laser's statistical error (a SICK LMS1xx:
    /// typically 12 mm). 0: none.
    pub laser_range_sigma_m: f32,
    /// The serial speed of the emulated microcontroller on a pty \[baud\]: it answers only a
    /// client whose line is set to this speed (a pty carries bytes at any speed; a real serial
    /// line at the wrong speed delivers garbage, modelled as lost bytes). `None`: any speed.
    /// Not used over TCP.
    pub baud: Option<u32>,
    /// The emulated robot's systematic odometry errors, `(Ed, Eb)` (Borenstein & Feng 1996,
    /// [`crate::odometry_error`]): right over left wheel diameter, effective over nominal
    /// wheelbase. `None`: perfect wheels.
    pub wheel_errors: Option<(f32, f32)>,
    /// Robot 0's start pose \[m, m, rad\] instead of the world's.
    pub start: Option<papillon::geometry::Pose2>,
    /// Record the run as MCAP into this file ([`papillon::record`]): the world's map at the
    /// start, each robot's true pose and odometry at 10 Hz, each scan served.
    pub mcap: Option<PathBuf>,
    /// Serve the same messages live to Foxglove on this address ([`papillon::live`]).
    pub live: Option<String>,
}

/// Period of the recorded poses \[s\] (as the mission's control period).
pub const RECORD_PERIOD_S: f64 = 0.1;

/// An endpoint the server opened, for the announcement line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Endpoint {
    /// The robot it serves.
    pub robot: usize,
    /// `arcos pty LINK -> DEVICE`, `arcos tcp ADDR`, `laser lms1xx tcp ADDR` or `laser lms200
    /// pty LINK -> DEVICE`.
    pub what: String,
}

/// The world and the robots, shared by the server's threads.
struct Sim {
    world: World,
    watchdog_ms: u16,
    identity: Identity,
    subclass: Subclass,
    /// See [`ServeConfig::laser_noise_fraction`].
    laser_noise_fraction: f32,
    /// See [`ServeConfig::laser_range_sigma_m`].
    laser_range_sigma_m: f32,
    /// See [`ServeConfig::baud`].
    baud: Option<u32>,
    /// Per robot: whether a client owns its microcontroller (one client at a time, as a
    /// serial port has one owner and AMRISim answers one client).
    owned: Vec<AtomicBool>,
    bodies: Mutex<Vec<RobotBody>>,
    start: Instant,
    seed: u64,
    faults: Faults,
    /// ARCOS sessions opened so far (each draws its fault RNG from its number).
    links: AtomicU64,
    /// Scans cast so far (each draws its noise from its number).
    scans: AtomicU64,
    stop: AtomicBool,
    /// The recording and/or live view (`--mcap`, `--live`); `None` once finished.
    recorder: Mutex<Option<Recorder<io::BufWriter<std::fs::File>>>>,
}

impl Sim {
    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn stopped(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// Claims robot `robot`'s microcontroller for one client; false if another has it.
    fn claim(&self, robot: usize) -> bool {
        self.owned[robot]
            .compare_exchange(false, true, Ordering::SeqCst, Ordering::SeqCst)
            .is_ok()
    }

    /// Gives robot `robot`'s microcontroller back.
    fn release(&self, robot: usize) {
        self.owned[robot].store(false, Ordering::SeqCst);
    }

    fn bodies(&self) -> MutexGuard<'_, Vec<RobotBody>> {
        self.bodies.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Runs `f` on the recording, if there is one; on an error the recording stops there
    /// (said once on stderr) and the server goes on.
    fn record(
        &self,
        f: impl FnOnce(&mut Recorder<io::BufWriter<std::fs::File>>) -> Result<(), RecordError>,
    ) {
        let mut guard = self.recorder.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(rec) = guard.as_mut()
            && let Err(e) = f(rec)
        {
            eprintln!("papillon-sim serve: --mcap: {e}; the recording stops here");
            *guard = None;
        }
    }

    /// A scan from robot `robot`'s true pose, with the server's range noise; the other robots
    /// appear as discs.
    fn scan(&self, robot: usize, mut config: LaserConfig) -> Scan {
        config.noise_fraction = self.laser_noise_fraction;
        let (pose, others) = {
            let bodies = self.bodies();
            let others: Vec<Disc> = bodies
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != robot)
                .map(|(_, b)| b.disc())
                .collect();
            (bodies[robot].true_pose(), others)
        };
        let mount = config.mount;
        // A fresh noise stream per scan: a laser made anew with one seed for every scan drew
        // the same noise for each beam every time (a fixed range bias per beam, which never
        // averaged out in the map and punched the same holes through walls scan after scan).
        let n = self.scans.fetch_add(1, Ordering::Relaxed);
        let seed = crate::runner::derive_seed(self.seed, robot, 16 + n);
        let scan = LaserSim::new(config, seed)
            .with_range_sigma_m(self.laser_range_sigma_m)
            .scan(&self.world, pose, &others);
        let t_s = self.now_s();
        self.record(|rec| rec.scan(t_s, robot, pose.compose(mount), &scan));
        scan
    }
}

/// A running server.
pub struct Server {
    sim: Arc<Sim>,
    endpoints: Vec<Endpoint>,
    links: Vec<PathBuf>,
}

impl fmt::Debug for Server {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Server")
            .field("world", &self.sim.world.name())
            .field("endpoints", &self.endpoints)
            .finish_non_exhaustive()
    }
}

impl Server {
    /// Loads the world, places the robots, opens every endpoint and starts the threads; the
    /// error is one line.
    pub fn start(config: &ServeConfig) -> Result<Self, String> {
        let mut world = World::load(&config.map, MAP_RESOLUTION_M)
            .map_err(|e| format!("cannot load map {:?}: {e}", config.map))?;
        if let Some(start) = config.start {
            world.set_start(start);
            if let Some(why) = world.start_outside() {
                return Err(format!("--start: {why}"));
            }
        }
        let n = config.robots;
        // The thesis's slip by default (a slide of about 1.5 cm at the end of each move), as
        // the mission runner's default: without scan matching (`papillon run`'s default) the
        // realistic slip smears the map. `--slip realistic` for a binary that matches.
        let mut body = BodyConfig {
            slip: config.slip.config(),
            ..BodyConfig::default()
        };
        config.faults.apply_to_body(&mut body);
        let bodies = start_poses(&world, world.start(), n, body.radius_m)
            .map_err(|e| format!("{e} in map {:?}", world.name()))?
            .into_iter()
            .enumerate()
            .map(|(i, pose)| {
                let mut b = RobotBody::new(body, pose, config.seed.wrapping_add(i as u64));
                // The motors are disabled at power-on until a client enables them.
                b.set_motors_enabled(false);
                if let Some((ed, eb)) = config.wheel_errors {
                    b.set_wheels(crate::odometry_error::DrawnWheels::exact(ed, eb));
                }
                b
            })
            .collect();
        let sim = Arc::new(Sim {
            world,
            watchdog_ms: config.watchdog_ms,
            identity: config.identity,
            subclass: config.subclass,
            laser_noise_fraction: config.laser_noise_fraction,
            laser_range_sigma_m: config.laser_range_sigma_m,
            baud: config.baud,
            owned: (0..n).map(|_| AtomicBool::new(false)).collect(),
            bodies: Mutex::new(bodies),
            start: Instant::now(),
            seed: config.seed,
            faults: config.faults.clone(),
            links: AtomicU64::new(0),
            scans: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            recorder: Mutex::new(open_recorder(config, n)?),
        });
        sim.record(|rec| {
            let world = &sim.world;
            rec.map_cells(
                0.0,
                world.geometry(),
                world.blocked().iter().map(|&b| {
                    if b {
                        CellClass::Occupied
                    } else {
                        CellClass::Free
                    }
                }),
            )
        });
        let truth = match &config.truth_log {
            Some(path) => Some(io::BufWriter::new(
                papillon::files::open_log(path, papillon::files::Existing::Truncate)
                    .map_err(|e| format!("--truth-log: {e}"))?,
            )),
            None => None,
        };
        {
            let sim = Arc::clone(&sim);
            thread::spawn(move || physics_loop(&sim, truth));
        }
        let mut server = Server {
            sim,
            endpoints: Vec::new(),
            links: Vec::new(),
        };
        if let Err(e) = server.open_endpoints(config) {
            let _ = server.stop();
            return Err(e);
        }
        Ok(server)
    }

    fn open_endpoints(&mut self, config: &ServeConfig) -> Result<(), String> {
        let n = config.robots;
        let sim = &self.sim;
        for robot in 0..n {
            let mut announce = |what: String| self.endpoints.push(Endpoint { robot, what });
            if let Some(link) = &config.pty {
                let link = robot_link(link, robot, n);
                let what = serve_on_pty(sim, &link, robot, session::arcos_on_pty)
                    .map_err(|e| format!("--pty: {e}"))?;
                self.links.push(link);
                announce(format!("arcos {what}"));
            }
            if let Some(addr) = &config.tcp {
                let listener = offset_addr(addr, robot)
                    .and_then(|a| bind(&a))
                    .map_err(|e| format!("--tcp: {e}"))?;
                announce(format!("arcos tcp {}", local_addr(&listener)?));
                let sim = Arc::clone(sim);
                thread::spawn(move || {
                    session::accept_loop(listener, sim, robot, session::serve_arcos_tcp)
                });
            }
            match config.laser_model {
                LaserModel::Lms1xx => {
                    let addr = config.laser.as_deref().unwrap_or(DEFAULT_LMS1XX_ADDR);
                    let listener = offset_addr(addr, robot)
                        .and_then(|a| bind(&a))
                        .map_err(|e| format!("--laser: {e}"))?;
                    announce(format!("laser lms1xx tcp {}", local_addr(&listener)?));
                    let sim = Arc::clone(sim);
                    thread::spawn(move || {
                        session::accept_loop(listener, sim, robot, session::serve_laser)
                    });
                }
                LaserModel::Lms200 => {
                    let link = config.laser.as_deref().unwrap_or(DEFAULT_LMS200_LINK);
                    let link = robot_link(Path::new(link), robot, n);
                    let what = serve_on_pty(sim, &link, robot, session::serve_lms200)
                        .map_err(|e| format!("--laser: {e}"))?;
                    self.links.push(link);
                    announce(format!("laser lms200 {what}"));
                }
            }
        }
        Ok(())
    }

    /// The endpoints opened, robot by robot, in the order they were opened.
    pub fn endpoints(&self) -> &[Endpoint] {
        &self.endpoints
    }

    /// Robots served.
    pub fn robot_count(&self) -> usize {
        self.sim.bodies().len()
    }

    /// The live view's address (`--live`), when there is one.
    pub fn live_addr(&self) -> Option<std::net::SocketAddr> {
        let guard = self.sim.recorder.lock().unwrap_or_else(|e| e.into_inner());
        guard.as_ref().and_then(Recorder::live_addr)
    }

    /// Ends the threads' loops (within a poll period), removes the pty symlinks and finishes
    /// the recording; the error is the recording's (one line naming the option).
    pub fn stop(&mut self) -> Result<(), String> {
        self.sim.stop.store(true, Ordering::SeqCst);
        for link in self.links.drain(..) {
            let _ = std::fs::remove_file(&link);
        }
        let recorder = self
            .sim
            .recorder
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        match recorder {
            Some(rec) => rec.finish().map_err(|e| format!("--mcap: {e}")),
            None => Ok(()),
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Err(e) = self.stop() {
            eprintln!("papillon-sim serve: {e}");
        }
    }
}

/// The recording and/or live view asked for by `config` (`None` for neither), for `robots`
/// robots, times from the wall clock now; the error names the option.
fn open_recorder(
    config: &ServeConfig,
    robots: usize,
) -> Result<Option<Recorder<io::BufWriter<std::fs::File>>>, String> {
    let live = match &config.live {
        Some(addr) => Some(LiveServer::bind(addr).map_err(|e| format!("--live {e}"))?),
        None => None,
    };
    let base_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    let recorder = match (&config.mcap, live) {
        (None, None) => return Ok(None),
        (Some(path), live) => {
            let rec =
                Recorder::create(path, robots, base_ns).map_err(|e| format!("--mcap: {e}"))?;
            match live {
                Some(l) => rec.with_live(l),
                None => rec,
            }
        }
        (None, Some(l)) => Recorder::live_only(l, robots, base_ns),
    };
    Ok(Some(recorder))
}

fn bind(addr: &str) -> Result<TcpListener, String> {
    TcpListener::bind(addr).map_err(|e| format!("cannot bind {addr}: {e}"))
}

fn local_addr(listener: &TcpListener) -> Result<std::net::SocketAddr, String> {
    listener.local_addr().map_err(|e| e.to_string())
}

/// `addr` with its port moved up by `offset` (port 0, "any free port", stays 0).
pub fn offset_addr(addr: &str, offset: usize) -> Result<String, String> {
    if offset == 0 {
        return Ok(addr.to_string());
    }
    let (host, port) = addr
        .rsplit_once(':')
        .ok_or_else(|| format!("{addr:?} is not HOST:PORT"))?;
    let port: u16 = port
        .parse()
        .map_err(|_| format!("{addr:?}: bad port number"))?;
    if port == 0 {
        return Ok(addr.to_string());
    }
    let port = usize::from(port) + offset;
    let port = u16::try_from(port).map_err(|_| format!("{addr:?}: port {port} is above 65535"))?;
    Ok(format!("{host}:{port}"))
}

/// Steps every body to the server's clock about every 10 ms (the physics itself runs in its
/// fixed steps, [`crate::physics::BodyConfig::step_s`]), presses and releases the e-stop
/// faults, and writes the truth log every [`TRUTH_PERIOD_S`]: per robot its true pose, speed,
/// turn rate, whether its motors are enabled and whether it touches something (`contact`: a
/// wheel stall or a bumper, the physics' wall contact).
fn physics_loop(sim: &Sim, mut truth: Option<io::BufWriter<std::fs::File>>) {
    let mut next_truth_s = 0.0;
    let mut next_record_s = 0.0;
    while !sim.stopped() {
        thread::sleep(Duration::from_millis(10));
        let now = sim.now_s();
        if now >= next_record_s {
            next_record_s = now + RECORD_PERIOD_S;
            let poses: Vec<(Pose2, Pose2)> = sim
                .bodies()
                .iter()
                .map(|b| (b.true_pose(), b.odometry_pose()))
                .collect();
            sim.record(|rec| {
                for (k, (truth, odometry)) in poses.into_iter().enumerate() {
                    rec.pose(now, k, PoseSource::True, truth)?;
                    rec.pose(now, k, PoseSource::Odometry, odometry)?;
                }
                Ok(())
            });
        }
        let mut bodies = sim.bodies();
        if !sim.faults.estops.is_empty() {
            let pressed = sim.faults.estop_pressed(now);
            for body in bodies.iter_mut() {
                body.set_e_stop(pressed);
            }
        }
        let dt = now - bodies[0].time_s();
        if dt > 0.0 {
            advance_all(&mut bodies, dt as f32, &sim.world, &[]);
        }
        if let Some(out) = truth.as_mut()
            && now >= next_truth_s
        {
            next_truth_s = now + TRUTH_PERIOD_S;
            let unix_s = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64());
            let mut lines = String::new();
            for (i, b) in bodies.iter().enumerate() {
                use std::fmt::Write as _;
                let p = b.true_pose();
                let _ = writeln!(
                    lines,
                    "{{\"t_s\":{now:.3},\"unix_s\":{unix_s:.3},\"robot\":{i},\"x_m\":{:.4},\"y_m\":{:.4},\"theta_rad\":{:.4},\"speed_mm_s\":{:.1},\"turn_deg_s\":{:.2},\"motors_enabled\":{},\"contact\":{}}}",
                    p.x,
                    p.y,
                    p.theta,
                    b.speed_mm_s(),
                    b.turn_deg_s(),
                    b.motors_enabled(),
                    b.stalled() || b.front_bumper() || b.rear_bumper()
                );
            }
            drop(bodies);
            let written = out.write_all(lines.as_bytes());
            if written.and_then(|()| out.flush()).is_err() {
                eprintln!("papillon-sim serve: cannot write the truth log; it stops here");
                truth = None;
            }
        }
    }
}

/// The link of robot `robot` of `n`: `link` itself for one robot, `link-ROBOT` for several.
fn robot_link(link: &Path, robot: usize, n: usize) -> PathBuf {
    if n > 1 {
        PathBuf::from(format!("{}-{robot}", link.display()))
    } else {
        link.to_path_buf()
    }
}

/// Opens a pty, links `link` to its slave and serves robot `robot`'s device on the master with
/// `serve` in a thread of its own. Returns the line announcing it (`pty LINK -> SLAVE`).
fn serve_on_pty(
    sim: &Arc<Sim>,
    link: &Path,
    robot: usize,
    serve: fn(&Sim, usize, &mut std::fs::File),
) -> Result<String, String> {
    let (master, slave_path, slave) = pty::open_pty().map_err(|e| format!("openpty: {e}"))?;
    pty::make_symlink(link, &slave_path)?;
    let sim = Arc::clone(sim);
    thread::spawn(move || {
        // Holding the slave open keeps the master readable between client sessions.
        let _slave = slave;
        let mut master = std::fs::File::from(master);
        serve(&sim, robot, &mut master);
    });
    Ok(format!(
        "pty {} -> {}",
        link.display(),
        slave_path.display()
    ))
}
