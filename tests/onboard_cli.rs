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
