//! `papillon-sim serve`: runs a simulated world in real time and serves an emulated P3-DX
//! microcontroller (ARCOS, on a pseudo-terminal and/or TCP) and an emulated SICK LMS1xx
//! (CoLa-A over TCP), so that the onboard binary or other P3-DX software can be tested
//! exactly as it talks to the robot.
//!
//! One thread steps the physics at 100 Hz; each endpoint and each TCP client has its own
//! thread running a sans-IO emulator ([`crate::emulator`]) against the shared robot body.

use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::os::fd::{FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use papillon::random::{self, ProjectRng};
use papillon::sensor::{LaserConfig, Scan};

use crate::emulator::arcos::ArcosEmulator;
use crate::emulator::lms1xx::Lms1xxEmulator;
use crate::laser::LaserSim;
use crate::physics::{BodyConfig, RobotBody};
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
    /// Serve the LMS1xx laser (CoLa-A) on this TCP address.
    #[arg(long, default_value = "127.0.0.1:2111")]
    pub laser: String,
    /// Seed of the simulation's random choices (wheel slip, faults).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Byte faults on the ARCOS link, server to client: `corrupt=P,drop=P` (probabilities per
    /// byte, e.g. `corrupt=0.01`).
    #[arg(long, default_value = "")]
    pub faults: Faults,
}

/// Byte faults injected on the ARCOS link (server to client), drawn from a seeded generator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Faults {
    /// Probability that a byte has one bit flipped.
    pub corrupt: f32,
    /// Probability that a byte is lost.
    pub drop: f32,
}

/// A `--faults` specification that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FaultSpecError {
    /// An item that is not `name=value`, or a name other than `corrupt` and `drop`.
    UnknownItem {
        /// The item seen.
        item: String,
    },
    /// A value that is not a probability in [0, 1].
    BadProbability {
        /// The item seen.
        item: String,
    },
}

impl std::fmt::Display for FaultSpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FaultSpecError::UnknownItem { item } => {
                write!(f, "unknown fault {item:?}: expected corrupt=P or drop=P")
            }
            FaultSpecError::BadProbability { item } => {
                write!(f, "in {item:?}: expected a probability between 0 and 1")
            }
        }
    }
}

impl std::error::Error for FaultSpecError {}

impl std::str::FromStr for Faults {
    type Err = FaultSpecError;

    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        let mut faults = Faults::default();
        for item in spec.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let unknown = || FaultSpecError::UnknownItem {
                item: item.to_string(),
            };
            let (name, value) = item.split_once('=').ok_or_else(unknown)?;
            let field = match name.trim() {
                "corrupt" => &mut faults.corrupt,
                "drop" => &mut faults.drop,
                _ => return Err(unknown()),
            };
            *field = value
                .trim()
                .parse()
                .ok()
                .filter(|p: &f32| (0.0..=1.0).contains(p))
                .ok_or_else(|| FaultSpecError::BadProbability {
                    item: item.to_string(),
                })?;
        }
        Ok(faults)
    }
}

impl Faults {
    /// Whether any fault is configured.
    pub fn any(&self) -> bool {
        self.corrupt > 0.0 || self.drop > 0.0
    }

    /// Drops and corrupts bytes of `data` in place.
    pub fn apply(&self, rng: &mut ProjectRng, data: &mut Vec<u8>) {
        if !self.any() {
            return;
        }
        data.retain(|_| !random::chance(rng, self.drop));
        for byte in data.iter_mut() {
            if random::chance(rng, self.corrupt) {
                *byte ^= 1 << random::below(rng, 8);
            }
        }
    }
}

/// The world and the robot, shared by the endpoint threads.
struct Sim {
    world: World,
    body: Mutex<RobotBody>,
    start: Instant,
    seed: u64,
    faults: Faults,
    links: std::sync::atomic::AtomicU64,
}

impl Sim {
    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn body(&self) -> MutexGuard<'_, RobotBody> {
        self.body.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn scan(&self, config: LaserConfig) -> Scan {
        let pose = self.body().true_pose();
        LaserSim::new(config, self.seed).scan(&self.world, pose, &[])
    }
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
    let body = RobotBody::new(BodyConfig::default(), world.start(), args.seed);
    let sim = Arc::new(Sim {
        world,
        body: Mutex::new(body),
        start: Instant::now(),
        seed: args.seed,
        faults: args.faults,
        links: std::sync::atomic::AtomicU64::new(0),
    });
    install_signal_handlers();

    {
        let sim = Arc::clone(&sim);
        thread::spawn(move || physics_loop(&sim));
    }

    let mut link_to_remove = None;
    if let Some(link) = &args.pty {
        let (master, slave_path, slave) = open_pty().map_err(|e| format!("openpty: {e}"))?;
        make_symlink(link, &slave_path)?;
        link_to_remove = Some(link.clone());
        println!("arcos pty {} -> {}", link.display(), slave_path.display());
        let sim = Arc::clone(&sim);
        thread::spawn(move || {
            // Holding the slave open keeps the master readable between client sessions.
            let _slave = slave;
            let mut master = std::fs::File::from(master);
            serve_arcos(&sim, &mut master);
        });
    }
    if let Some(addr) = &args.tcp {
        let listener = TcpListener::bind(addr).map_err(|e| format!("cannot bind {addr}: {e}"))?;
        let local = listener.local_addr().map_err(|e| e.to_string())?;
        println!("arcos tcp {local}");
        let sim = Arc::clone(&sim);
        thread::spawn(move || accept_loop(listener, sim, serve_arcos_tcp));
    }
    let listener =
        TcpListener::bind(&args.laser).map_err(|e| format!("cannot bind {}: {e}", args.laser))?;
    let local = listener.local_addr().map_err(|e| e.to_string())?;
    println!("laser lms1xx tcp {local}");
    {
        let sim = Arc::clone(&sim);
        thread::spawn(move || accept_loop(listener, sim, serve_laser));
    }
    let _ = io::stdout().flush();

    while !STOP.load(Ordering::SeqCst) {
        thread::sleep(Duration::from_millis(20));
    }
    if let Some(link) = link_to_remove {
        let _ = std::fs::remove_file(&link);
    }
    let _ = writeln!(io::stdout(), "stopped");
    Ok(())
}

fn physics_loop(sim: &Sim) {
    while !STOP.load(Ordering::SeqCst) {
        thread::sleep(Duration::from_millis(10));
        let now = sim.now_s();
        let mut body = sim.body();
        let dt = now - body.time_s();
        if dt > 0.0 {
            body.advance(dt as f32, &sim.world, &[]);
        }
    }
}

fn accept_loop(listener: TcpListener, sim: Arc<Sim>, serve: fn(&Sim, TcpStream)) {
    for stream in listener.incoming().flatten() {
        let sim = Arc::clone(&sim);
        thread::spawn(move || serve(&sim, stream));
    }
}

fn serve_arcos_tcp(sim: &Sim, mut stream: TcpStream) {
    let _ = stream.set_nodelay(true);
    if stream
        .set_read_timeout(Some(Duration::from_millis(POLL_MS)))
        .is_ok()
    {
        serve_arcos(sim, &mut stream);
    }
}

/// Runs an ARCOS session over `io` (reads time out or would block when idle) until EOF; a
/// dropped link stops the robot and disables its motors.
fn serve_arcos(sim: &Sim, io: &mut (impl Read + Write)) {
    let mut emu = ArcosEmulator::new(ROBOT_NAME);
    let link = sim.links.fetch_add(1, Ordering::SeqCst);
    let mut rng = random::seeded(sim.seed ^ (link + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    arcos_session(sim, io, &mut emu, &mut rng);
    emu.disconnect(&mut sim.body());
}

fn arcos_session(
    sim: &Sim,
    io: &mut (impl Read + Write),
    emu: &mut ArcosEmulator,
    rng: &mut ProjectRng,
) {
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
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
        {
            let now = sim.now_s();
            let mut body = sim.body();
            emu.receive(now, &buf[..n], &mut body, &mut out);
            emu.tick(now, &sim.world, &mut body, &mut out);
        }
        sim.faults.apply(rng, &mut out);
        if !out.is_empty() {
            if write_some(io, &out).is_err() {
                return;
            }
            out.clear();
        }
        if n == 0 {
            thread::sleep(Duration::from_millis(POLL_MS));
        }
    }
}

fn serve_laser(sim: &Sim, mut stream: TcpStream) {
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
        emu.receive(now, &buf[..n], |c| sim.scan(c), &mut out);
        emu.tick(now, |c| sim.scan(c), &mut out);
        if !out.is_empty() {
            if stream.write_all(&out).is_err() {
                return;
            }
            out.clear();
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
