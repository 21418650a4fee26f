//! `papillon-sim serve`: runs a simulated world in real time and serves an emulated P3-DX
//! microcontroller (ARCOS, on a pseudo-terminal and/or TCP) and an emulated SICK LMS1xx
//! (CoLa-A over TCP) or LMS200 (on a second pseudo-terminal), so that the onboard binary or
//! other P3-DX software can be tested exactly as it talks to the robot.
//!
//! One thread steps the physics at 100 Hz; each endpoint and each TCP client has its own
//! thread running a sans-IO emulator ([`crate::emulator`]) against its robot's body. With
//! `--robots N`, N robots share the world (each sees the others in its laser and collides
//! with them) and robot `i` is served on the given ports plus `i` (`LINK-i` for ptys).
//! Faults ([`crate::faults`]) are injected on the links, the laser and the bodies.

use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::os::fd::{FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use papillon::geometry::{Point2, Pose2};
use papillon::random::{self, ProjectRng};
use papillon::sensor::{LaserConfig, Scan};

use crate::emulator::arcos::ArcosEmulator;
use crate::emulator::lms1xx::Lms1xxEmulator;
use crate::emulator::lms200::Lms200Emulator;
use crate::faults::DelayLine;
use crate::laser::LaserSim;
use crate::physics::{BodyConfig, Disc, RobotBody, SlipConfig, advance_all};
use crate::world::World;

/// Cell size of the served world \[m\].
pub const MAP_RESOLUTION_M: f32 = 0.05;
/// Robot name answered in SYNC2 and CONFIG.
pub const ROBOT_NAME: &str = "papillon-sim";
/// How long an endpoint thread sleeps when it has nothing to read \[ms\].
const POLL_MS: u64 = 2;

/// Arguments of `papillon-sim serve`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// World: a built-in map (house, lab, empty, factory) or a map file (.csv, .png, .pgm).
    #[arg(long, default_value = "house")]
    pub map: String,
    /// Serve ARCOS on a pseudo-terminal and make this path a symlink to its device.
    #[arg(long)]
    pub pty: Option<PathBuf>,
    /// Serve ARCOS over TCP on this address (MobileSim's is 127.0.0.1:8101).
    #[arg(long)]
    pub tcp: Option<String>,
    /// Where the laser is served: a TCP address for the LMS1xx (default 127.0.0.1:2111), a
    /// pty symlink path for the LMS200 (default /tmp/papillon-sim-lms200).
    #[arg(long)]
    pub laser: Option<String>,
    /// The emulated laser: an LMS1xx on TCP (CoLa-A) or an LMS200 on a pty (RS-232 telegrams).
    #[arg(long, value_enum, default_value = "lms1xx")]
    pub laser_model: LaserModel,
    /// Seed of the simulation's random choices (wheel slip, faults).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Faults to inject, e.g. `corrupt=0.01,cut=10+3,laser-drop=20+2` (see the user guide:
    /// corrupt, drop, latency, jitter, cut, laser-drop, slip, estop, drain).
    #[arg(long, default_value = "")]
    pub faults: Faults,
    /// Robots sharing the world (1 to 16), served on consecutive endpoints.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=16))]
    pub robots: u8,
    /// Write each robot's true pose and velocity to this file every 20 ms, as JSON lines:
    /// `{"t_s","unix_s","robot","x_m","y_m","theta_rad","speed_mm_s","turn_deg_s",
    /// "motors_enabled"}` (`t_s` since start, `unix_s` since the Unix epoch). The file is
    /// created or truncated.
    #[arg(long)]
    pub truth_log: Option<PathBuf>,
    /// The emulated firmware's watchdog \[ms\] (FLASH `Watchdog`, reported in CONFIG): with no
    /// command for this long on an open session the robot halts at its deceleration.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u16).range(100..))]
    pub watchdog_ms: u16,
}

/// Period of the truth log \[s\].
pub const TRUTH_PERIOD_S: f64 = 0.02;

pub use crate::faults::{FaultSpecError, Faults};

/// Which laser `serve` emulates.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaserModel {
    /// SICK LMS1xx, CoLa-A over TCP.
    Lms1xx,
    /// SICK LMS200, telegrams over a serial line (a pty here).
    Lms200,
}

/// The world and the robots, shared by the endpoint threads.
struct Sim {
    world: World,
    watchdog_ms: u16,
    bodies: Mutex<Vec<RobotBody>>,
    start: Instant,
    seed: u64,
    faults: Faults,
    links: std::sync::atomic::AtomicU64,
}

impl Sim {
    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn bodies(&self) -> MutexGuard<'_, Vec<RobotBody>> {
        self.bodies.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A scan from robot `robot`'s true pose; the other robots appear as discs.
    fn scan(&self, robot: usize, config: LaserConfig) -> Scan {
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
        LaserSim::new(config, self.seed ^ robot as u64).scan(&self.world, pose, &others)
    }
}

/// Start poses of `n` robots: the world's start for the first, then the nearest clear spots
/// on a 0.75 m lattice around it, each at least a robot diameter from the others.
pub fn start_poses(world: &World, n: usize, radius_m: f32) -> Result<Vec<Pose2>, String> {
    let first = world.start();
    let mut poses = vec![first];
    let step = 0.75f32;
    let mut ring = 1i32;
    while poses.len() < n {
        if ring > 40 {
            return Err(format!(
                "no room for {n} robots around the start in map {:?}",
                world.name()
            ));
        }
        for dy in -ring..=ring {
            for dx in -ring..=ring {
                if dx.abs().max(dy.abs()) != ring || poses.len() == n {
                    continue;
                }
                let p = Point2::new(first.x + dx as f32 * step, first.y + dy as f32 * step);
                let clear = !world.disc_hits_blocked(p, radius_m + 0.05)
                    && poses
                        .iter()
                        .all(|q| q.position().distance(p) >= 2.0 * radius_m + 0.1);
                if clear {
                    poses.push(Pose2::new(p.x, p.y, first.theta));
                }
            }
        }
        ring += 1;
    }
    Ok(poses)
}

/// `addr` with its port moved up by `offset` (port 0, "any free port", stays 0).
fn offset_addr(addr: &str, offset: usize) -> Result<String, String> {
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

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_signal: libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

fn install_signal_handlers() {
    let handler = on_signal as extern "C" fn(libc::c_int);
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, handler as libc::sighandler_t);
        libc::signal(libc::SIGTERM, handler as libc::sighandler_t);
    }
}

/// Runs `serve` until SIGINT or SIGTERM.
pub fn run(args: Args) -> ExitCode {
    match serve(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("papillon-sim serve: {e}");
            ExitCode::FAILURE
        }
    }
}

fn serve(args: Args) -> Result<(), String> {
    let world = World::load(&args.map, MAP_RESOLUTION_M)
        .map_err(|e| format!("cannot load map {:?}: {e}", args.map))?;
    let n = usize::from(args.robots);
    // The thesis's slip (a slide of about 1.5 cm at the end of each move), as the mission
    // runner uses: the core has no scan matching, so the full default slip smears its map.
    let mut config = BodyConfig {
        slip: SlipConfig::thesis(),
        ..BodyConfig::default()
    };
    args.faults.apply_to_body(&mut config);
    let bodies = start_poses(&world, n, config.radius_m)?
        .into_iter()
        .enumerate()
        .map(|(i, pose)| RobotBody::new(config, pose, args.seed.wrapping_add(i as u64)))
        .collect();
    let sim = Arc::new(Sim {
        world,
        watchdog_ms: args.watchdog_ms,
        bodies: Mutex::new(bodies),
        start: Instant::now(),
        seed: args.seed,
        faults: args.faults.clone(),
        links: std::sync::atomic::AtomicU64::new(0),
    });
    install_signal_handlers();

    let truth = match &args.truth_log {
        Some(path) => Some(io::BufWriter::new(
            std::fs::File::create(path)
                .map_err(|e| format!("cannot create truth log {}: {e}", path.display()))?,
        )),
        None => None,
    };
    {
        let sim = Arc::clone(&sim);
        thread::spawn(move || physics_loop(&sim, truth));
    }

    let mut links_to_remove = Vec::new();
    for robot in 0..n {
        let label = if n > 1 {
            format!("robot {robot}: ")
        } else {
            String::new()
        };
        if let Some(link) = &args.pty {
            let link = robot_link(link, robot, n);
            println!(
                "{label}arcos {}",
                serve_on_pty(&sim, &link, robot, arcos_on_pty)?
            );
            links_to_remove.push(link);
        }
        if let Some(addr) = &args.tcp {
            let addr = offset_addr(addr, robot)?;
            let listener =
                TcpListener::bind(&addr).map_err(|e| format!("cannot bind {addr}: {e}"))?;
            let local = listener.local_addr().map_err(|e| e.to_string())?;
            println!("{label}arcos tcp {local}");
            let sim = Arc::clone(&sim);
            thread::spawn(move || accept_loop(listener, sim, robot, serve_arcos_tcp));
        }
        match args.laser_model {
            LaserModel::Lms1xx => {
                let addr = args.laser.as_deref().unwrap_or("127.0.0.1:2111");
                let addr = offset_addr(addr, robot)?;
                let listener =
                    TcpListener::bind(&addr).map_err(|e| format!("cannot bind {addr}: {e}"))?;
                let local = listener.local_addr().map_err(|e| e.to_string())?;
                println!("{label}laser lms1xx tcp {local}");
                let sim = Arc::clone(&sim);
                thread::spawn(move || accept_loop(listener, sim, robot, serve_laser));
            }
            LaserModel::Lms200 => {
                let link = args.laser.as_deref().unwrap_or("/tmp/papillon-sim-lms200");
                let link = robot_link(Path::new(link), robot, n);
                println!(
                    "{label}laser lms200 {}",
                    serve_on_pty(&sim, &link, robot, serve_lms200)?
                );
                links_to_remove.push(link);
            }
        }
    }
    println!("ready");
    let _ = io::stdout().flush();

    while !STOP.load(Ordering::SeqCst) {
        thread::sleep(Duration::from_millis(20));
    }
    for link in links_to_remove {
        let _ = std::fs::remove_file(&link);
    }
    let _ = writeln!(io::stdout(), "stopped");
    Ok(())
}

fn physics_loop(sim: &Sim, mut truth: Option<io::BufWriter<std::fs::File>>) {
    let mut next_truth_s = 0.0;
    while !STOP.load(Ordering::SeqCst) {
        thread::sleep(Duration::from_millis(10));
        let now = sim.now_s();
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
                    "{{\"t_s\":{now:.3},\"unix_s\":{unix_s:.3},\"robot\":{i},\"x_m\":{:.4},\"y_m\":{:.4},\"theta_rad\":{:.4},\"speed_mm_s\":{:.1},\"turn_deg_s\":{:.2},\"motors_enabled\":{}}}",
                    p.x,
                    p.y,
                    p.theta,
                    b.speed_mm_s(),
                    b.turn_deg_s(),
                    b.motors_enabled()
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

fn accept_loop(
    listener: TcpListener,
    sim: Arc<Sim>,
    robot: usize,
    serve: fn(&Sim, usize, TcpStream),
) {
    for stream in listener.incoming().flatten() {
        let sim = Arc::clone(&sim);
        thread::spawn(move || serve(&sim, robot, stream));
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
    let (master, slave_path, slave) = open_pty().map_err(|e| format!("openpty: {e}"))?;
    make_symlink(link, &slave_path)?;
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

/// Serves robot `robot`'s microcontroller on a pty master.
fn arcos_on_pty(sim: &Sim, robot: usize, master: &mut std::fs::File) {
    serve_arcos(sim, robot, master, false);
}

fn serve_arcos_tcp(sim: &Sim, robot: usize, mut stream: TcpStream) {
    if sim.faults.link_cut(sim.now_s()) {
        return; // the cable is out: the connection drops at once
    }
    let _ = stream.set_nodelay(true);
    if stream
        .set_read_timeout(Some(Duration::from_millis(POLL_MS)))
        .is_ok()
    {
        serve_arcos(sim, robot, &mut stream, true);
    }
}

/// Runs an ARCOS session for robot `robot` over `io` (reads time out or would block when
/// idle) until EOF; a dropped link stops the robot and disables its motors. A TCP link
/// (`drops_on_cut`) is closed when a `cut` fault begins; a serial line just goes silent.
fn serve_arcos(sim: &Sim, robot: usize, io: &mut (impl Read + Write), drops_on_cut: bool) {
    let mut emu = ArcosEmulator::new(ROBOT_NAME).with_watchdog_ms(sim.watchdog_ms);
    let link = sim.links.fetch_add(1, Ordering::SeqCst);
    let mut rng = random::seeded(sim.seed ^ (link + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    arcos_session(sim, robot, io, &mut emu, &mut rng, drops_on_cut);
    emu.disconnect(&mut sim.bodies()[robot]);
}

fn arcos_session(
    sim: &Sim,
    robot: usize,
    io: &mut (impl Read + Write),
    emu: &mut ArcosEmulator,
    rng: &mut ProjectRng,
    drops_on_cut: bool,
) {
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    let mut send = Vec::new();
    let mut line = DelayLine::default();
    while !STOP.load(Ordering::SeqCst) {
        let n = match io.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            Err(_) => {
                thread::sleep(Duration::from_millis(POLL_MS * 10));
                0
            }
        };
        let now = sim.now_s();
        let cut = sim.faults.link_cut(now);
        if cut && drops_on_cut {
            return;
        }
        {
            let mut bodies = sim.bodies();
            let body = &mut bodies[robot];
            if !cut {
                emu.receive(now, &buf[..n], body, &mut out);
            }
            emu.tick(now, &sim.world, body, &mut out);
        }
        if cut {
            // The firmware runs on (its watchdog halts the robot), but nothing gets through.
            out.clear();
            line.clear();
        } else {
            sim.faults.damage(rng, &mut out);
            line.push(&sim.faults, rng, now, std::mem::take(&mut out));
            line.due(now, &mut send);
        }
        if !send.is_empty() {
            if write_some(io, &send).is_err() {
                return;
            }
            send.clear();
        }
        if n == 0 {
            thread::sleep(Duration::from_millis(POLL_MS));
        }
    }
}

fn serve_laser(sim: &Sim, robot: usize, mut stream: TcpStream) {
    let _ = stream.set_nodelay(true);
    if stream
        .set_read_timeout(Some(Duration::from_millis(POLL_MS)))
        .is_err()
    {
        return;
    }
    let mut emu = Lms1xxEmulator::new();
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    while !STOP.load(Ordering::SeqCst) {
        let n = match stream.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            Err(_) => return,
        };
        let now = sim.now_s();
        emu.receive(now, &buf[..n], |c| sim.scan(robot, c), &mut out);
        let replies = out.len();
        emu.tick(now, |c| sim.scan(robot, c), &mut out);
        sim.faults.silence_laser(now, &mut out, replies);
        if !out.is_empty() {
            if stream.write_all(&out).is_err() {
                return;
            }
            out.clear();
        }
    }
}

/// Runs the LMS200 of robot `robot` on a pty master (non-blocking) until shutdown.
fn serve_lms200(sim: &Sim, robot: usize, io: &mut (impl Read + Write)) {
    let mut emu = Lms200Emulator::new();
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    while !STOP.load(Ordering::SeqCst) {
        let n = match io.read(&mut buf) {
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            // No client has the slave open: wait for one.
            Err(_) => 0,
        };
        let now = sim.now_s();
        emu.receive(now, &buf[..n], &mut out);
        let replies = out.len();
        emu.tick(now, |c| sim.scan(robot, c), &mut out);
        sim.faults.silence_laser(now, &mut out, replies);
        if !out.is_empty() {
            let _ = write_some(io, &out);
            out.clear();
        }
        if n == 0 {
            thread::sleep(Duration::from_millis(POLL_MS));
        }
    }
}

fn is_idle(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
    )
}

/// Writes `data`; on a full non-blocking pty (no reader) the rest is dropped, as bytes sent
/// down a serial line nobody listens to are lost.
fn write_some(io: &mut impl Write, mut data: &[u8]) -> io::Result<()> {
    while !data.is_empty() {
        match io.write(data) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(n) => data = &data[n..],
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Opens a pseudo-terminal pair in raw mode: the master (non-blocking), the slave's device
/// path and the slave itself.
fn open_pty() -> io::Result<(OwnedFd, PathBuf, OwnedFd)> {
    let mut master: libc::c_int = -1;
    let mut slave: libc::c_int = -1;
    // SAFETY: openpty writes two descriptors; the name, termios and winsize pointers may be
    // null.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if rc != 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: both descriptors were just opened by openpty and are owned by nobody else.
    let (master, slave) = unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    use std::os::fd::AsRawFd;
    // SAFETY: plain termios/fcntl calls on descriptors we own, with a zeroed termios that
    // tcgetattr fills.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(slave.as_raw_fd(), &mut t) == 0 {
            libc::cfmakeraw(&mut t);
            libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t);
        }
        let flags = libc::fcntl(master.as_raw_fd(), libc::F_GETFL);
        libc::fcntl(master.as_raw_fd(), libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let path = std::fs::read_link(format!("/proc/self/fd/{}", slave.as_raw_fd()))?;
    Ok((master, path, slave))
}

/// Makes `link` a symlink to `target`, replacing an older symlink (never a regular file).
fn make_symlink(link: &Path, target: &Path) -> Result<(), String> {
    if let Ok(meta) = std::fs::symlink_metadata(link) {
        if meta.file_type().is_symlink() {
            let _ = std::fs::remove_file(link);
        } else {
            return Err(format!(
                "{} exists and is not a symlink; not replacing it",
                link.display()
            ));
        }
    }
    std::os::unix::fs::symlink(target, link)
        .map_err(|e| format!("cannot create symlink {}: {e}", link.display()))
}
