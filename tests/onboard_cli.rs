//! The `papillon` binary's `check` and `ports` subcommands: output and exit codes.
#![cfg(feature = "onboard")]

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_papillon");

fn board(name: &str) -> String {
    format!("{}/boards/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn temp_file(name: &str, text: &str) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!("papillon-cli-{}-{name}", std::process::id()));
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn shipped_boards_check_ok() {
    for name in ["p3dx-lms1xx.json", "p3dx-lms200.json", "sim.json"] {
        let out = Command::new(BIN)
            .args(["check", "--board", &board(name)])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{name}");
        let stdout = String::from_utf8(out.stdout).unwrap();
        assert_eq!(stdout.lines().count(), 1, "{stdout}");
        assert!(stdout.starts_with("OK: "), "{stdout}");
    }
}

#[test]
fn every_problem_is_printed_with_its_path_and_exit_is_1() {
    let text = std::fs::read_to_string(board("sim.json"))
        .unwrap()
        .replace("\"population\": 5", "\"population\": 200")
        .replace("\"baud\": 9600", "\"baud\": 1234");
    let p = temp_file("bad.json", &text);
    let out = Command::new(BIN)
        .args(["check", "--board", p.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "{stdout}");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("$.mission.population: "))
    );
    assert!(lines.iter().any(|l| l.starts_with("$.link.baud: ")));
    std::fs::remove_file(p).unwrap();
}

#[test]
fn syntax_error_names_line_and_column() {
    let p = temp_file("syntax.json", "{\n  \"robot\": {,\n}");
    let out = Command::new(BIN)
        .args(["check", "--board", p.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("line 2, column 13"), "{stderr}");
    std::fs::remove_file(p).unwrap();
}

#[test]
fn missing_file_exits_2_with_one_line() {
    let out = Command::new(BIN)
        .args(["check", "--board", "/nonexistent/board.json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("/nonexistent/board.json"));
}

#[test]
fn ports_lists_or_says_none() {
    let out = Command::new(BIN).arg("ports").output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        stdout.trim() == "no serial ports found"
            || stdout
                .lines()
                .all(|l| l.starts_with("/dev/") || l.starts_with("COM")),
        "{stdout}"
    );
}

/// Runs `papillon args` for at most `limit`; kills it and fails the test past that.
fn bounded(args: &[&str], limit: std::time::Duration) -> std::process::Output {
    use std::process::Stdio;
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + limit;
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("papillon {args:?} still running after {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Item 4 of issue 20: a board "file" that never ends is refused after a bounded read, on one
/// line naming it (before: `check --board /dev/zero` read 2.4 GB in 5 s and went on); so is a
/// board file larger than any board.
#[test]
fn a_board_file_that_never_ends_or_is_too_large_is_refused() {
    let out = bounded(
        &["check", "--board", "/dev/zero"],
        std::time::Duration::from_secs(10),
    );
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("/dev/zero") && stderr.contains("larger than"),
        "{stderr}"
    );
    let p = temp_file("huge.json", &" ".repeat(1 << 20));
    let out = bounded(
        &["check", "--board", p.to_str().unwrap()],
        std::time::Duration::from_secs(10),
    );
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("larger than"), "{stderr}");
    std::fs::remove_file(p).unwrap();
}
