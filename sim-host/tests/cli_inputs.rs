//! Bad inputs to `papillon-sim`'s commands (issue 20): each is refused with one line naming
//! the flag or the file and the field, never a panic, an abort or a hang. Each test here
//! failed before its fix.

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `papillon-sim args` for at most `limit`; kills it and fails the test past that.
fn sim(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_papillon-sim"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start papillon-sim");
    let deadline = Instant::now() + limit;
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "papillon-sim {args:?} still running after {limit:?}; stderr:\n{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Asserts a refusal: exit status 1 or 2 (not a panic's 101 nor a signal), and one line on
/// standard error containing every one of `needles`.
fn assert_refused(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let code = out.status.code();
    assert!(
        matches!(code, Some(1) | Some(2)),
        "exit {:?} (a panic is 101, an abort a signal); stderr:\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{n:?} not in: {stderr}");
    }
    stderr
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("papillon-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Item 3: a cell size that would need billions of cells is refused naming `--resolution`
/// (before: "attempt to multiply with overflow" in debug, an abort on a failed allocation of
/// 8.6e18 bytes in release).
#[test]
fn an_absurd_resolution_is_refused_naming_the_flag() {
    let limit = Duration::from_secs(20);
    for res in ["1e-9", "0.0001"] {
        let out = sim(&["mission", "--map", "lab", "--resolution", res], limit);
        assert_refused(&out, &["--resolution", "lab"]);
        let out = sim(
            &[
                "score",
                "--map",
                "lab",
                "--resolution",
                res,
                "--robot-map",
                "nowhere.yaml",
            ],
            limit,
        );
        assert_refused(&out, &["--resolution", "lab"]);
    }
}
