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
    for name in [
        "p3dx-lms1xx.json",
        "p3dx-lms200.json",
        "sim.json",
        "sim-thesis.json",
    ] {
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
    let text = std::fs::read_to_string(board("sim-thesis.json"))
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

/// Issue 24: populations the optimizers hold pass `check` (50, and the limit itself); one
/// more is refused with the limit named, and so is a grid beyond the largest capacity.
#[test]
fn check_accepts_populations_up_to_the_limit_and_names_it_beyond() {
    let text = std::fs::read_to_string(board("sim-thesis.json")).unwrap();
    let limit = papillon::config::MAX_POPULATION;
    for (population, ok) in [(50, true), (limit, true), (limit + 1, false)] {
        let p = temp_file(
            &format!("pop{population}.json"),
            &text.replace(
                "\"population\": 5",
                &format!("\"population\": {population}"),
            ),
        );
        let out = Command::new(BIN)
            .args(["check", "--board", p.to_str().unwrap()])
            .output()
            .unwrap();
        let stdout = String::from_utf8(out.stdout).unwrap();
        if ok {
            assert_eq!(out.status.code(), Some(0), "{population}: {stdout}");
        } else {
            assert_eq!(out.status.code(), Some(1), "{population}: {stdout}");
            assert!(
                stdout.contains(&format!("$.mission.population: must be in 2..={limit}")),
                "{stdout}"
            );
        }
        std::fs::remove_file(p).unwrap();
    }
    let huge = text.replace("\"width_m\": 26.0", "\"width_m\": 2600.0");
    let p = temp_file("grid-huge.json", &huge);
    let out = Command::new(BIN)
        .args(["check", "--board", p.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains(&format!(
            "more than the {} the grid holds",
            papillon::capacity::MAX_CELLS
        )),
        "{stdout}"
    );
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

/// `check` on `boards/sim-thesis.json` with `from` replaced by `to`: exit 1, and the one problem line
/// on standard output names `path` (before: 10 of 44 bad boards of these kinds gave "a value
/// has the wrong type or is too long for its field (Invalid number.)" or a misleading
/// "Expected … ',' or '}'" without any path).
fn assert_board_error_names(kind: &str, from: &str, to: &str, path: &str, expected: &str) {
    let text = std::fs::read_to_string(board("sim-thesis.json")).unwrap();
    assert!(
        text.contains(from),
        "{kind}: {from:?} not in sim-thesis.json"
    );
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

/// A fresh directory of this test process.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("papillon-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Asserts a refusal (exit 1 or 2, no panic) whose last line on standard error holds every
/// one of `needles`; returns that line.
fn assert_last_line_names(out: &std::process::Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        matches!(out.status.code(), Some(1) | Some(2)),
        "exit {:?}: {stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let last = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("");
    for n in needles {
        assert!(last.contains(n), "{n:?} not in the last line of:\n{stderr}");
    }
    last.to_string()
}

/// Bad inputs table (docs/reliability.md): a named pipe no program writes to is refused after
/// a bounded wait, naming it (before: `check --board FIFO` blocked in open(2) for ever).
#[cfg(unix)]
#[test]
fn a_named_pipe_without_a_writer_is_refused_not_waited_for() {
    let dir = temp_dir("fifo");
    let fifo = dir.join("board.json");
    if !Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        eprintln!("skipped: no mkfifo");
        return;
    }
    let out = bounded(
        &["check", "--board", fifo.to_str().unwrap()],
        std::time::Duration::from_secs(15),
    );
    assert_eq!(out.status.code(), Some(2));
    assert_last_line_names(&out, &[fifo.to_str().unwrap(), "named pipe"]);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Bad inputs table: a bad command line is one line naming the flag (before: clap's error,
/// a blank line, the usage and a hint, five lines, the last naming nothing).
#[test]
fn a_bad_command_line_is_one_line_naming_the_flag() {
    let sim = board("sim-thesis.json");
    for (args, flag) in [
        (vec!["check", "--bored", "x.json"], "--bored"),
        (vec!["check"], "--board"),
        (
            vec!["run", "--board", &sim, "--resume", "--fresh"],
            "--fresh",
        ),
        (vec!["probe"], "--port"),
    ] {
        let out = Command::new(BIN).args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(flag), "{args:?}: {stderr}");
    }
}

/// Bad inputs table: a board value out of range is named with the file and its JSON path on
/// the last line of `check` and of `run`, and a value given on `run`'s command line by its
/// flag (before: "board.json: 1 problem(s)" and "the board has 1 problem(s); run `papillon
/// check`").
#[test]
fn a_board_problem_names_the_file_and_the_field_on_the_last_line() {
    let text = std::fs::read_to_string(board("sim-thesis.json")).unwrap();
    let p = temp_file(
        "radius0.json",
        &text.replacen("\"radius_m\": 0.25", "\"radius_m\": 0.0", 1),
    );
    let file = p.to_str().unwrap();
    let out = Command::new(BIN)
        .args(["check", "--board", file])
        .output()
        .unwrap();
    assert_last_line_names(&out, &[file, "$.robot.radius_m"]);
    let log = temp_dir("radius0-log");
    let out = bounded(
        &["run", "--board", file, "--log-dir", log.to_str().unwrap()],
        std::time::Duration::from_secs(10),
    );
    assert_last_line_names(&out, &[file, "$.robot.radius_m"]);
    let sim = board("sim-thesis.json");
    let out = bounded(
        &[
            "run",
            "--board",
            &sim,
            "--tcp",
            "nohost",
            "--log-dir",
            log.to_str().unwrap(),
        ],
        std::time::Duration::from_secs(10),
    );
    assert_last_line_names(&out, &["--tcp", "$.link.tcp"]);
    // Targets beyond the mission's 8 with the long strategy, a gain of 1e30: refused.
    let long = text
        .replacen("\"strategy\": \"short\"", "\"strategy\": \"long\"", 1)
        .replacen("\"targets\": 16", "\"targets\": 1000", 1);
    let gain = text.replacen("\"distance_kp\": 1.0", "\"distance_kp\": 1e30", 1);
    for (name, text, path) in [
        ("targets.json", long, "$.mission.targets"),
        ("gain.json", gain, "$.pid.distance_kp"),
    ] {
        let p = temp_file(name, &text);
        let out = Command::new(BIN)
            .args(["check", "--board", p.to_str().unwrap()])
            .output()
            .unwrap();
        assert_last_line_names(&out, &[p.to_str().unwrap(), path]);
        std::fs::remove_file(p).unwrap();
    }
    std::fs::remove_file(p).unwrap();
    std::fs::remove_dir_all(log).unwrap();
}

/// Bad inputs table: a log directory that cannot be one names `--log-dir` and the path
/// (before: "papillon: File exists (os error 17)").
#[test]
fn a_log_dir_that_is_a_file_names_the_flag() {
    let dir = temp_dir("logdir-file");
    let file = dir.join("afile");
    std::fs::write(&file, "not a directory\n").unwrap();
    let sim = board("sim-thesis.json");
    for log in [file.clone(), file.join("sub")] {
        let out = bounded(
            &["run", "--board", &sim, "--log-dir", log.to_str().unwrap()],
            std::time::Duration::from_secs(10),
        );
        assert_last_line_names(&out, &["--log-dir", log.to_str().unwrap()]);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Bad inputs table: a saved state that cannot be read names its file, and one with values no
/// mission has names the field, before any link is opened (before: "Is a directory (os error
/// 21)" without a path; a `mission_time_s` of 1e300 was loaded and panicked once connected,
/// "cannot convert float seconds to Duration").
#[test]
fn a_damaged_saved_state_names_its_file_and_field() {
    let sim = board("sim-thesis.json");
    let state = |time: &str, x: &str| {
        format!(
            r#"{{"version": 1, "mission_time_s": {time},
            "pose": {{"x_m": {x}, "y_m": 1.0, "theta_rad": 0.0}},
            "odom_pose": {{"x_m": 1.0, "y_m": 1.0, "theta_rad": 0.0}},
            "trajectory": [], "counters": {{"decisions": 1, "distance_m": 0.5,
            "energy_used_steps": 1.0, "faults": 0, "reconnects": 0, "scans": 10}},
            "coverage": 0.1, "finished": false}}"#
        )
    };
    for (name, contents, field) in [
        ("dir", None, ""),
        ("time", Some(state("1e300", "1.0")), "$.mission_time_s"),
        ("pose", Some(state("12.5", "1e30")), "$.pose"),
    ] {
        let log = temp_dir(&format!("state-{name}"));
        let path = log.join("state.json");
        match contents {
            Some(text) => std::fs::write(&path, text).unwrap(),
            None => std::fs::create_dir(&path).unwrap(),
        }
        let out = bounded(
            &[
                "run",
                "--board",
                &sim,
                "--resume",
                "--log-dir",
                log.to_str().unwrap(),
            ],
            std::time::Duration::from_secs(10),
        );
        assert_last_line_names(&out, &[path.to_str().unwrap(), field]);
        std::fs::remove_dir_all(log).unwrap();
    }
}

/// Bad inputs table: a `probe` that cannot connect names `--tcp` (before: "cannot connect to
/// nohost: invalid socket address").
#[test]
fn probe_names_the_flag_of_an_address_it_cannot_use() {
    let out = bounded(
        &["probe", "--tcp", "nohost"],
        std::time::Duration::from_secs(10),
    );
    assert_last_line_names(&out, &["--tcp", "nohost"]);
}

/// `run --live` on an address in use is refused at once, naming the flag, before the program
/// tries to reach the robot (port 1 on loopback would be retried for a long time); a bad
/// `RUST_LOG` is one line naming it; `--log-format json` writes JSON lines.
#[test]
fn live_address_rust_log_and_log_format_are_checked_first() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let log = std::env::temp_dir().join(format!("papillon-cli-{}-live", std::process::id()));
    let run = |extra: &[&str], env: Option<&str>| {
        let mut c = Command::new(BIN);
        c.args([
            "run",
            "--board",
            &board("sim-thesis.json"),
            "--tcp",
            "127.0.0.1:1",
        ])
        .args(extra)
        .arg("--log-dir")
        .arg(&log);
        if let Some(v) = env {
            c.env("RUST_LOG", v);
        }
        c
    };
    let started = std::time::Instant::now();
    let out = run(&["--live", &addr], None).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with(&format!("papillon: --live {addr}: cannot listen")),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(started.elapsed() < std::time::Duration::from_secs(10));

    let out = run(&[], Some("papillon=[")).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("papillon: RUST_LOG: "), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");

    // JSON lines: the first retry to reach the robot is logged as an object; stop there.
    let mut child = run(&["--log-format", "json"], Some("info"))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(child.stderr.take().unwrap()),
        &mut line,
    )
    .unwrap();
    let _ = child.kill();
    let _ = child.wait();
    let v: serde_json::Value =
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"));
    assert_eq!(v["level"], "WARN", "{line}");
    assert!(v["fields"]["message"].is_string(), "{line}");
    assert!(!line.contains('\u{1b}'), "no escape codes: {line}");
    let _ = std::fs::remove_dir_all(&log);
}

/// Issue 18: `run --localize` takes `on` or `off` (one line naming the flag otherwise), and
/// switching the matcher on for a grid too fine for its window is refused before anything
/// is connected, naming the flag and the board's field; `check` names the field.
#[test]
fn localize_is_checked_on_the_command_line_and_in_the_board() {
    let sim = board("sim-thesis.json");
    let out = Command::new(BIN)
        .args(["run", "--board", &sim, "--localize", "maybe"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--localize"), "{stderr}");

    let text = std::fs::read_to_string(&sim).unwrap();
    let fine = text.replacen("\"resolution_m\": 0.1", "\"resolution_m\": 0.05", 1);
    assert_ne!(fine, text);
    let p = temp_file("fine-grid.json", &fine);
    let file = p.to_str().unwrap();
    // Off (the board's default): a valid board.
    let out = Command::new(BIN)
        .args(["check", "--board", file])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let log = temp_dir("fine-grid-log");
    let out = bounded(
        &[
            "run",
            "--board",
            file,
            "--localize",
            "on",
            "--log-dir",
            log.to_str().unwrap(),
        ],
        std::time::Duration::from_secs(10),
    );
    assert_last_line_names(&out, &["--localize on", "$.localize.enabled"]);
    let on = temp_file(
        "fine-grid-on.json",
        &fine.replacen(
            "\"persistence\"",
            "\"localize\": {\"enabled\": true}, \"persistence\"",
            1,
        ),
    );
    let out = Command::new(BIN)
        .args(["check", "--board", on.to_str().unwrap()])
        .output()
        .unwrap();
    assert_last_line_names(&out, &[on.to_str().unwrap(), "$.localize.enabled"]);
    std::fs::remove_file(p).unwrap();
    std::fs::remove_file(on).unwrap();
    std::fs::remove_dir_all(log).unwrap();
}
