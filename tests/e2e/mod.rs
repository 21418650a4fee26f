//! Shared harness of the end-to-end tests: `papillon-sim serve` and the `papillon` binary as
//! real processes over loopback TCP and a real pty, every wait bounded.

#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The onboard binary under test.
pub const PAPILLON: &str = env!("CARGO_BIN_EXE_papillon");

/// The simulator binary, built into the same target directory and profile as `papillon`
/// (once per test process; a no-op when it is up to date).
pub fn sim_binary() -> &'static Path {
    static SIM: OnceLock<PathBuf> = OnceLock::new();
    SIM.get_or_init(|| {
        let dir = Path::new(PAPILLON).parent().expect("binary directory");
        let target = dir.parent().expect("target directory");
        let profile = match dir.file_name().and_then(|n| n.to_str()) {
            Some("debug") | None => "dev".to_string(),
            Some(p) => p.to_string(),
        };
        let status = Command::new(env!("CARGO"))
            .args([
                "build",
                "--quiet",
                "-p",
                "papillon-sim",
                "--bin",
                "papillon-sim",
            ])
            .args(["--profile", &profile])
            .env("CARGO_TARGET_DIR", target)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .status()
            .expect("run cargo to build papillon-sim");
        assert!(status.success(), "building papillon-sim failed");
        dir.join("papillon-sim")
    })
}

/// A fresh temporary directory for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("papillon-e2e-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Sends `signal` to a child process.
pub fn signal(child: &Child, signal: libc::c_int) {
    // SAFETY: sends a signal to our own child process, which has not been reaped yet.
    unsafe { libc::kill(child.id() as libc::pid_t, signal) };
}

/// A `papillon-sim serve` process with its endpoints; stopped (SIGTERM, then SIGKILL) on drop.
pub struct Sim {
    child: Child,
    lines: Vec<String>,
    _stdout: BufReader<std::process::ChildStdout>,
}

impl Sim {
    /// Starts `serve` on `map` with the ARCOS link on loopback TCP (or on a pty symlink at
    /// `pty`) and the laser on a free loopback port, plus `extra` arguments.
    pub fn start(map: &str, pty: Option<&Path>, extra: &[&str]) -> Self {
        Self::spawn(map, pty, "127.0.0.1:0", extra)
    }

    /// Starts `serve` on `map` with the ARCOS link on a pty symlink at `pty` and an LMS200 on
    /// a second pty symlink at `laser`, plus `extra` arguments.
    pub fn start_lms200(map: &str, pty: &Path, laser: &Path, extra: &[&str]) -> Self {
        let mut args = vec!["--laser-model", "lms200"];
        args.extend_from_slice(extra);
        Self::spawn(map, Some(pty), laser.to_str().unwrap(), &args)
    }

    fn spawn(map: &str, pty: Option<&Path>, laser: &str, extra: &[&str]) -> Self {
        let mut cmd = Command::new(sim_binary());
        cmd.args(["serve", "--map", map, "--laser", laser]);
        match pty {
            Some(p) => cmd.arg("--pty").arg(p),
            None => cmd.args(["--tcp", "127.0.0.1:0"]),
        };
        let mut child = cmd
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start papillon-sim serve");
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut lines = Vec::new();
        loop {
            let mut line = String::new();
            assert!(
                stdout.read_line(&mut line).unwrap() > 0,
                "papillon-sim serve exited: {lines:?}"
            );
            let done = line.starts_with("laser ");
            lines.push(line.trim().to_string());
            if done {
                break;
            }
        }
        Self {
            child,
            lines,
            _stdout: stdout,
        }
    }

    fn endpoint(&self, prefix: &str) -> String {
        let line = self
            .lines
            .iter()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} line in {:?}", self.lines));
        line[prefix.len()..]
            .split_whitespace()
            .next()
            .unwrap()
            .to_string()
    }

    /// The ARCOS TCP address.
    pub fn arcos_tcp(&self) -> String {
        self.endpoint("arcos tcp")
    }

    /// The LMS1xx TCP address.
    pub fn laser(&self) -> String {
        self.endpoint("laser lms1xx tcp")
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        signal(&self.child, libc::SIGTERM);
        let deadline = Instant::now() + Duration::from_secs(3);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Waits for `child` at most `limit`; kills it and fails the test if it runs longer.
pub fn wait_bounded(mut child: Child, limit: Duration) -> Output {
    let deadline = Instant::now() + limit;
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let out = collect(child);
            panic!(
                "process still running after {limit:?}\nstdout:\n{}\nstderr:\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    collect(child)
}

fn collect(mut child: Child) -> Output {
    let status = child.wait().unwrap();
    let mut stdout = Vec::new();
    let mut stderr = Vec::new();
    if let Some(mut s) = child.stdout.take() {
        let _ = s.read_to_end(&mut stdout);
    }
    if let Some(mut s) = child.stderr.take() {
        let _ = s.read_to_end(&mut stderr);
    }
    Output {
        status,
        stdout,
        stderr,
    }
}

/// Starts `papillon` with `args`, output captured, in `cwd`.
pub fn papillon(args: &[&str], cwd: &Path) -> Child {
    Command::new(PAPILLON)
        .args(args)
        .current_dir(cwd)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start papillon")
}

/// The board of the pump's end-to-end tests, `boards/sim-thesis.json`: the simulated P3-DX with
/// the thesis's laser and the matcher off, the runner's defaults. (`boards/sim.json`, the
/// project's board for the simulator, runs the scan matcher and its pose graph, which a debug
/// build cannot keep up with in real time; the release house check runs it.)
pub fn sim_board() -> String {
    format!("{}/boards/sim-thesis.json", env!("CARGO_MANIFEST_DIR"))
}

/// The range noise of [`sim_board`]'s laser (`laser.noise_fraction`), for `serve
/// --laser-noise`: a mission test's simulator serves the laser its board describes (the
/// house check's and `onboard_compare`'s do). On a noise-free laser under a board that
/// says 5 % the core maps walls one cell thick with holes, its predicted scans see through
/// them, and the robot chases gain it can never observe: back and forth or deciding where it
/// stands until `NothingObservable` (docs/architecture.md, "The binary against the runner").
pub fn sim_board_laser_noise() -> String {
    let board: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sim_board()).unwrap()).unwrap();
    board["laser"]["noise_fraction"]
        .as_f64()
        .unwrap_or(0.0)
        .to_string()
}

/// `papillon run` on [`sim_board`] against these endpoints, logging into `log`, plus
/// `extra` flags. The working directory is the log's parent: nothing may be written there but
/// the log.
pub fn run_on_sim_board(arcos: &str, laser: &str, log: &Path, extra: &[&str]) -> Child {
    run_on_board(&sim_board(), arcos, laser, log, extra)
}

/// `papillon run --board BOARD` against these endpoints, logging into `log`, plus `extra`
/// flags; the working directory is the log's parent, as in [`run_on_sim_board`].
pub fn run_on_board(board: &str, arcos: &str, laser: &str, log: &Path, extra: &[&str]) -> Child {
    let mut args = vec![
        "run",
        "--board",
        board,
        "--tcp",
        arcos,
        "--laser",
        laser,
        "--log-dir",
        log.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    papillon(&args, log.parent().unwrap())
}

/// A loopback TCP relay between `papillon` and an endpoint of the simulator, to cut a link or
/// pause one direction, and to watch the robot's status packets on their way.
pub struct Relay {
    /// The address `papillon` connects to.
    pub addr: String,
    state: std::sync::Arc<RelayState>,
}

#[derive(Default)]
struct RelayState {
    /// While set, connections are closed and new ones refused.
    cut: std::sync::atomic::AtomicBool,
    /// While set, bytes from the simulator are dropped (the link stays up).
    mute: std::sync::atomic::AtomicBool,
    /// Bumped at each cut, so that open connections notice it.
    generation: std::sync::atomic::AtomicU64,
    /// (time, left wheel, right wheel, motors enabled) of each status packet relayed.
    statuses: std::sync::Mutex<Vec<(Instant, i16, i16, bool)>>,
}

impl Relay {
    /// Relays connections on a free loopback port to `target`; with `watch_arcos`, status
    /// packets from the simulator are decoded and logged.
    pub fn start(target: &str, watch_arcos: bool) -> Self {
        use std::sync::atomic::Ordering;
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let state = std::sync::Arc::new(RelayState::default());
        let target = target.to_string();
        let st = std::sync::Arc::clone(&state);
        std::thread::spawn(move || {
            for client in listener.incoming().flatten() {
                if st.cut.load(Ordering::SeqCst) {
                    drop(client);
                    continue;
                }
                let Ok(server) = std::net::TcpStream::connect(&target) else {
                    continue;
                };
                let generation = st.generation.load(Ordering::SeqCst);
                for (from, to, downstream) in [
                    (
                        client.try_clone().unwrap(),
                        server.try_clone().unwrap(),
                        false,
                    ),
                    (server, client, true),
                ] {
                    let st = std::sync::Arc::clone(&st);
                    let watch = downstream && watch_arcos;
                    std::thread::spawn(move || pump(from, to, downstream, watch, generation, &st));
                }
            }
        });
        Self { addr, state }
    }

    /// Cuts the link (both directions closed, reconnections refused) until [`Relay::restore`].
    pub fn cut(&self) {
        use std::sync::atomic::Ordering;
        self.state.cut.store(true, Ordering::SeqCst);
        self.state.generation.fetch_add(1, Ordering::SeqCst);
    }

    /// Accepts connections again.
    pub fn restore(&self) {
        self.state
            .cut
            .store(false, std::sync::atomic::Ordering::SeqCst);
    }

    /// Drops (`true`) or relays (`false`) what the simulator sends.
    pub fn mute(&self, on: bool) {
        self.state
            .mute
            .store(on, std::sync::atomic::Ordering::SeqCst);
    }

    /// The status packets relayed so far: (time, left and right wheel velocities \[mm/s\],
    /// motors enabled).
    pub fn statuses(&self) -> Vec<(Instant, i16, i16, bool)> {
        self.state.statuses.lock().unwrap().clone()
    }
}

fn pump(
    mut from: std::net::TcpStream,
    mut to: std::net::TcpStream,
    downstream: bool,
    watch: bool,
    generation: u64,
    st: &RelayState,
) {
    use papillon::wire::arcos::{FrameDecoder, ServerPacket};
    use std::io::Write;
    use std::sync::atomic::Ordering;
    let _ = from.set_read_timeout(Some(Duration::from_millis(20)));
    let mut decoder = FrameDecoder::new();
    let mut buf = [0u8; 4096];
    loop {
        if st.generation.load(Ordering::SeqCst) != generation {
            let _ = from.shutdown(std::net::Shutdown::Both);
            let _ = to.shutdown(std::net::Shutdown::Both);
            return;
        }
        let n = match from.read(&mut buf) {
            Ok(0) => {
                let _ = to.shutdown(std::net::Shutdown::Both);
                return;
            }
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(_) => {
                let _ = to.shutdown(std::net::Shutdown::Both);
                return;
            }
        };
        if watch {
            let mut input = &buf[..n];
            while let Some(frame) = decoder.decode(&mut input) {
                if let Ok(ServerPacket::Status(s)) = ServerPacket::parse(&frame) {
                    st.statuses.lock().unwrap().push((
                        Instant::now(),
                        s.left_vel_mm_s,
                        s.right_vel_mm_s,
                        s.motors_enabled(),
                    ));
                }
            }
        }
        if downstream && st.mute.load(Ordering::SeqCst) {
            continue;
        }
        if to.write_all(&buf[..n]).is_err() {
            return;
        }
    }
}

/// One line of `papillon-sim serve --truth-log`: a robot's true state.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    /// Time of the sample since `serve` started \[s\] (the clock of its `--faults` windows).
    pub t_s: f64,
    /// Wall-clock time of the sample \[s since the Unix epoch\].
    pub unix_s: f64,
    /// True pose in the world \[m, m, rad\].
    pub x_m: f64,
    pub y_m: f64,
    pub theta_rad: f64,
    /// True translational speed \[mm/s\].
    pub speed_mm_s: f64,
    /// True turn rate \[deg/s\].
    pub turn_deg_s: f64,
    /// Whether the robot touches something (a wheel stall or a bumper).
    pub contact: bool,
}

impl Truth {
    /// Whether the robot is moving at all.
    pub fn moving(&self) -> bool {
        self.speed_mm_s != 0.0 || self.turn_deg_s != 0.0
    }
}

/// The samples of robot 0 in a truth log written so far (a partial last line is skipped).
pub fn read_truth(path: &Path) -> Vec<Truth> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["robot"].as_u64() == Some(0))
        .filter_map(|v| {
            Some(Truth {
                t_s: v["t_s"].as_f64()?,
                unix_s: v["unix_s"].as_f64()?,
                x_m: v["x_m"].as_f64()?,
                y_m: v["y_m"].as_f64()?,
                theta_rad: v["theta_rad"].as_f64()?,
                speed_mm_s: v["speed_mm_s"].as_f64()?,
                turn_deg_s: v["turn_deg_s"].as_f64()?,
                contact: v["contact"].as_bool()?,
            })
        })
        .collect()
}

/// Now, in seconds since the Unix epoch (the truth log's clock).
pub fn unix_now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}
