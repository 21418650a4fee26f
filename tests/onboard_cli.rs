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

/// `check` on `boards/sim.json` with `from` replaced by `to`: exit 1, and the one problem line
/// on standard output names `path` (before: 10 of 44 bad boards of these kinds gave "a value
/// has the wrong type or is too long for its field (Invalid number.)" or a misleading
/// "Expected … ',' or '}'" without any path).
fn assert_board_error_names(kind: &str, from: &str, to: &str, path: &str, expected: &str) {
    let text = std::fs::read_to_string(board("sim.json")).unwrap();
    assert!(text.contains(from), "{kind}: {from:?} not in sim.json");
    let p = temp_file(
        &format!("kind-{}.json", kind.replace(' ', "-")),
        &text.replacen(from, to, 1),
    );
    let out = Command::new(BIN)
        .args(["check", "--board", p.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{kind}: {stdout}{stderr}");
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with(&format!("{path}: ")) && l.contains(expected)),
        "{kind}: no line '{path}: …{expected}…' in stdout:\n{stdout}stderr:\n{stderr}"
    );
    assert!(stderr.contains(path), "{kind}: {stderr}");
    std::fs::remove_file(p).unwrap();
}

#[test]
fn a_negative_value_in_an_unsigned_field_names_its_path() {
    assert_board_error_names(
        "negative",
        "\"population\": 5",
        "\"population\": -5",
        "$.mission.population",
        "a whole number from 0 to 65535, found -5",
    );
}

#[test]
fn a_float_for_an_integer_names_its_path() {
    assert_board_error_names(
        "float",
        "\"beam_count\": 541",
        "\"beam_count\": 541.5",
        "$.laser.beam_count",
        "a whole number from 0 to 65535, found 541.5",
    );
}

#[test]
fn a_string_for_a_number_names_its_path() {
    assert_board_error_names(
        "string",
        "\"baud\": 9600",
        "\"baud\": \"9600\"",
        "$.link.baud",
        "found \"9600\"",
    );
}

#[test]
fn a_duplicate_key_names_its_path() {
    assert_board_error_names(
        "duplicate",
        "\"seed\": 1",
        "\"seed\": 1, \"seed\": 2",
        "$.mission.seed",
        "duplicate key",
    );
}

#[test]
fn an_over_long_string_names_its_path() {
    let long = format!("\"name\": \"{}\"", "n".repeat(40));
    assert_board_error_names(
        "long",
        "\"name\": \"sim-p3dx\"",
        &long,
        "$.robot.name",
        "at most 32 bytes, found 40",
    );
}

#[test]
fn a_number_too_large_for_its_field_names_its_path() {
    assert_board_error_names(
        "too large",
        "\"population\": 5",
        "\"population\": 70000",
        "$.mission.population",
        "found 70000",
    );
}
