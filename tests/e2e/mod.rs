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
        let mut cmd = Command::new(sim_binary());
        cmd.args(["serve", "--map", map, "--laser", "127.0.0.1:0"]);
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
