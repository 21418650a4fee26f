//! Bad inputs to `papillon-sim`'s commands (issue 20): each is refused with one line naming
//! the flag or the file and the field, never a panic, an abort or a hang. Each test here
//! failed before its fix.

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `papillon-sim args` for at most `limit`; kills it and fails the test past that.
fn sim(args: &[&str], limit: Duration) -> Output {
    wait(
        Command::new(env!("CARGO_BIN_EXE_papillon-sim")).args(args),
        args,
        limit,
    )
}

/// [`sim`] with at most 256 MiB of address space (`ulimit -v`): an allocation past that
/// fails, and the process aborts.
fn sim_in_256_mib(args: &[&str], limit: Duration) -> Output {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg("ulimit -v 262144 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_papillon-sim"))
        .args(args);
    wait(&mut cmd, args, limit)
}

fn wait(cmd: &mut Command, args: &[&str], limit: Duration) -> Output {
    let mut child = cmd
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

/// A PNG of `width` x `height` white pixels, compressed to a few hundred kilobytes at most.
fn big_png(width: u32, height: u32) -> Vec<u8> {
    use image::ImageEncoder;
    let row = vec![255u8; width as usize];
    let mut pixels = Vec::with_capacity((width * height) as usize);
    for _ in 0..height {
        pixels.extend_from_slice(&row);
    }
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(&pixels, width, height, image::ExtendedColorType::L8)
        .unwrap();
    out
}

/// Item 4: an image whose header promises 20000 x 20000 pixels (a 439 kB PNG) is refused from
/// its header, before it is decoded: within 256 MiB of memory (before: still decoding after
/// 30 s at 4.8 GB; with the size checked only after decoding, an abort on the 400 MB pixel
/// buffer).
#[test]
fn an_image_map_larger_than_a_world_may_be_is_refused_before_decoding() {
    let dir = temp_dir("bigpng");
    let png = dir.join("huge.png");
    std::fs::write(&png, big_png(20_000, 20_000)).unwrap();
    let out = sim_in_256_mib(
        &[
            "score",
            "--map",
            png.to_str().unwrap(),
            "--robot-map",
            "nowhere.yaml",
        ],
        Duration::from_secs(10),
    );
    assert_refused(&out, &[png.to_str().unwrap(), "20000 x 20000"]);
    let out = sim_in_256_mib(
        &["mission", "--map", png.to_str().unwrap()],
        Duration::from_secs(10),
    );
    assert_refused(&out, &[png.to_str().unwrap(), "20000 x 20000"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 4: a map file that never ends (`/dev/zero` under a map's name) is refused after a
/// bounded read, naming the file.
#[test]
fn a_map_file_that_never_ends_is_refused_after_a_bounded_read() {
    let dir = temp_dir("endless");
    for name in ["zero.png", "zero.csv", "zero.map", "zero.yaml"] {
        let path = dir.join(name);
        std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
        let out = sim(
            &["mission", "--map", path.to_str().unwrap()],
            Duration::from_secs(20),
        );
        assert_refused(&out, &[path.to_str().unwrap(), "larger than"]);
    }
    // The robot map given to `score`, and a ROS map whose image never ends.
    let yaml = dir.join("robot.yaml");
    std::fs::write(
        &yaml,
        "image: zero.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.pgm")).unwrap();
    let out = sim(
        &[
            "score",
            "--map",
            "lab",
            "--robot-map",
            yaml.to_str().unwrap(),
        ],
        Duration::from_secs(20),
    );
    assert_refused(&out, &["zero.pgm", "larger than"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 6: a ROS map whose YAML says `resolution: 1e30` is refused naming the file and the
/// field (before: a mission ran on it and exited 0 with "0 of 0 observable cells").
#[test]
fn a_map_yaml_with_a_nonsense_resolution_is_refused() {
    let dir = temp_dir("yaml-res");
    std::fs::write(
        dir.join("m.pgm"),
        b"P2\n3 2\n255\n254 254 254\n254 254 254\n",
    )
    .unwrap();
    for resolution in ["1e30", "0", "-0.1", "1e-9"] {
        let yaml = dir.join("m.yaml");
        std::fs::write(
            &yaml,
            format!(
                "image: m.pgm\nresolution: {resolution}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
            ),
        )
        .unwrap();
        let out = sim(
            &["mission", "--map", yaml.to_str().unwrap()],
            Duration::from_secs(20),
        );
        assert_refused(&out, &[yaml.to_str().unwrap(), "resolution"]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 6: a start pose outside the map is refused naming `--start` (before: `mission --start
/// 1e9 1e9` ran and exited 0 with "0 of 0 observable cells"); so is a cell size coarser than
/// the robot.
#[test]
fn a_start_outside_the_map_and_a_cell_coarser_than_the_robot_are_refused() {
    let limit = Duration::from_secs(20);
    for start in [["1e9", "1e9"], ["-3", "2"], ["2", "8.5"]] {
        let out = sim(
            &["mission", "--map", "lab", "--start", start[0], start[1]],
            limit,
        );
        assert_refused(&out, &["--start", "outside", "lab"]);
        let out = sim(
            &[
                "score",
                "--map",
                "lab",
                "--start",
                start[0],
                start[1],
                "--robot-map",
                "nowhere.yaml",
            ],
            limit,
        );
        assert_refused(&out, &["--start", "outside", "lab"]);
    }
    for res in ["5", "100", "1e30"] {
        let out = sim(&["mission", "--map", "lab", "--resolution", res], limit);
        assert_refused(&out, &["--resolution"]);
    }
}

/// Item 6: `serve --faults latency=1e12` (31 years) is refused naming the item (before: the
/// server started).
#[test]
fn serve_refuses_a_latency_or_jitter_of_years() {
    for spec in ["latency=1e12", "jitter=1e9", "latency=100000"] {
        let out = sim(
            &[
                "serve",
                "--map",
                "lab",
                "--tcp",
                "127.0.0.1:0",
                "--laser",
                "127.0.0.1:0",
                "--faults",
                spec,
            ],
            Duration::from_secs(10),
        );
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(2), "{spec}: {stderr}");
        assert!(
            stderr.contains("--faults") && stderr.contains(spec),
            "{spec}: {stderr}"
        );
    }
}

/// Item 8: `serve --truth-log` refuses a symbolic link in the log's place (before: it
/// truncated what the link pointed to).
#[test]
fn serve_refuses_a_truth_log_that_is_a_symlink() {
    let dir = temp_dir("truth-link");
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    let log = dir.join("truth.jsonl");
    std::os::unix::fs::symlink(&victim, &log).unwrap();
    let out = sim(
        &[
            "serve",
            "--map",
            "lab",
            "--tcp",
            "127.0.0.1:0",
            "--laser",
            "127.0.0.1:0",
            "--truth-log",
            log.to_str().unwrap(),
        ],
        Duration::from_secs(10),
    );
    assert_refused(&out, &[log.to_str().unwrap(), "symbolic link"]);
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

const SERVE: [&str; 7] = [
    "serve",
    "--map",
    "lab",
    "--tcp",
    "127.0.0.1:0",
    "--laser",
    "127.0.0.1:0",
];

/// Bad inputs table (docs/reliability.md): fault windows beyond a day, a slip of a billion
/// times the thesis's, a drain of 1e30 V/min, empty items and a fault given twice are refused
/// naming `--faults` (before: the server started with them).
#[test]
fn serve_refuses_fault_values_no_run_can_have() {
    for spec in [
        "cut=1e30+1",
        "estop=1+1e9",
        "slip=1e9",
        "drain=1e30",
        ",,,",
        "corrupt=0.1,corrupt=0.2",
    ] {
        let mut args = SERVE.to_vec();
        args.extend(["--faults", spec]);
        let out = sim(&args, Duration::from_secs(10));
        assert_refused(&out, &["--faults"]);
    }
}

/// Bad inputs table: an address `serve` cannot listen on names its flag (before: "cannot
/// bind nohost: invalid socket address").
#[test]
fn serve_names_the_flag_of_an_address_it_cannot_use() {
    for (flag, value) in [("--tcp", "nohost"), ("--laser", "127.0.0.1:99999")] {
        let mut args = SERVE.to_vec();
        let at = args.iter().position(|a| *a == flag).unwrap();
        args[at + 1] = value;
        let out = sim(&args, Duration::from_secs(10));
        assert_refused(&out, &[flag, value]);
    }
}

/// Bad inputs table: a negative number for a flag is refused naming the flag (before: clap
/// took `-1` for an unknown flag, "unexpected argument '-1' found"); a missing argument names
/// the flag (before: "the following required arguments were not provided:", and no flag).
#[test]
fn a_negative_number_or_a_missing_argument_names_the_flag() {
    for (args, flag) in [
        (vec!["optimize", "--dim", "-1"], "--dim"),
        (vec!["optimize", "--seed", "-1"], "--seed"),
        (
            vec!["bench", "--experiment", "horizon", "--runs", "-1"],
            "--runs",
        ),
        (
            vec!["bench", "--experiment", "horizon", "--jobs", "-1"],
            "--jobs",
        ),
        (
            vec!["score", "--robot-map", "x.yaml", "--resolution", "-1"],
            "--resolution",
        ),
        (vec!["plan", "--map", "x.map"], "--scen"),
        (
            vec!["mission", "--map", "lab", "--start", "1", "2", "3", "4"],
            "--start",
        ),
    ] {
        let out = sim(&args, Duration::from_secs(20));
        assert_refused(&out, &[flag]);
    }
    let mut args = SERVE.to_vec();
    args.extend(["--seed", "-1"]);
    assert_refused(&sim(&args, Duration::from_secs(10)), &["--seed"]);
}

/// Bad inputs table: a map YAML whose thresholds are not fractions, whose `free_thresh` is
/// above `occupied_thresh`, or which gives a key twice is refused naming the file and the key
/// (before: all three were loaded, the second value of a key silently winning).
#[test]
fn a_map_yaml_with_bad_thresholds_or_a_key_given_twice_is_refused() {
    let dir = temp_dir("thresholds");
    let pgm = dir.join("m.pgm");
    let mut bytes = b"P5\n40 40\n255\n".to_vec();
    bytes.extend(std::iter::repeat_n(254u8, 1600));
    std::fs::write(&pgm, bytes).unwrap();
    let good = "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    for (name, from, to, key) in [
        (
            "occ",
            "occupied_thresh: 0.65",
            "occupied_thresh: 2",
            "occupied_thresh",
        ),
        (
            "order",
            "free_thresh: 0.196",
            "free_thresh: 0.9",
            "free_thresh",
        ),
        ("twice", "negate: 0", "negate: 0\nnegate: 1", "negate"),
    ] {
        let yaml = dir.join(format!("{name}.yaml"));
        std::fs::write(&yaml, good.replacen(from, to, 1)).unwrap();
        let out = sim(
            &["mission", "--map", yaml.to_str().unwrap()],
            Duration::from_secs(20),
        );
        assert_refused(&out, &[yaml.to_str().unwrap(), key]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad inputs table: a sweep's unknown method or world, a population or robot count out of
/// range and a run count too large to hold are refused naming the file and the field, before
/// any run (before: "1 runs failed (see the status column ...)", and 10^12 runs aborted on
/// a failed allocation).
#[test]
fn a_sweep_with_values_no_run_can_have_is_refused_naming_the_field() {
    let dir = temp_dir("sweeps");
    let out_dir = dir.join("out");
    for (name, field, value) in [
        ("method", "methods", r#"["nope"]"#),
        ("map", "maps", r#"["nowhere"]"#),
        ("pop", "populations", "[0]"),
        ("robots", "robots", "[101]"),
        ("runs", "runs", "1000000000000"),
    ] {
        let mut sweep = serde_json::json!({
            "maps": ["lab"],
            "methods": ["nearest-frontier"],
            "runs": 1,
            "generations": 2,
        });
        sweep[field] = serde_json::from_str(value).unwrap();
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, sweep.to_string()).unwrap();
        let out = sim(
            &[
                "bench",
                "--config",
                file.to_str().unwrap(),
                "--out",
                out_dir.to_str().unwrap(),
            ],
            Duration::from_secs(20),
        );
        assert_refused(&out, &[file.to_str().unwrap(), field]);
        assert!(
            !out_dir.join("results.csv").exists(),
            "{name}: runs were made"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad inputs table: `bench --jobs 100000` is refused naming the flag (before: it started
/// 100000 worker threads; with 2 GiB of address space a thread's stack could not be allocated
/// and it panicked).
#[test]
fn a_hundred_thousand_bench_jobs_are_refused() {
    let dir = temp_dir("jobs");
    let sweep = dir.join("sweep.json");
    std::fs::write(
        &sweep,
        r#"{"maps": ["lab"], "methods": ["nearest-frontier"], "runs": 1, "generations": 2}"#,
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = sim(
        &[
            "bench",
            "--config",
            sweep.to_str().unwrap(),
            "--jobs",
            "100000",
            "--out",
            out_dir.to_str().unwrap(),
        ],
        Duration::from_secs(20),
    );
    assert_refused(&out, &["--jobs"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad inputs table: `mission --gens 4000000000`, `--battery 1e30` and a start heading of
/// 1e30 rad are refused naming the flag (before: all three ran), and so is `score
/// --robot-start 1e30 1e30` (before: "coverage 0.00 %").
#[test]
fn absurd_generations_battery_and_headings_are_refused() {
    for (args, flag) in [
        (vec!["--gens", "4000000000"], "--gens"),
        (vec!["--battery", "1e30"], "--battery"),
        (vec!["--start", "1", "1", "1e30"], "--start"),
    ] {
        let mut all = vec!["mission", "--map", "lab"];
        all.extend(args);
        let out = sim(&all, Duration::from_secs(20));
        assert_refused(&out, &[flag]);
    }
    let dir = temp_dir("robot-start");
    let yaml = dir.join("robot.yaml");
    std::fs::write(
        &yaml,
        "image: robot.pgm\nresolution: 0.1\norigin: [0, 0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
    )
    .unwrap();
    let mut pgm = b"P5\n4 4\n255\n".to_vec();
    pgm.extend([254u8; 16]);
    std::fs::write(dir.join("robot.pgm"), pgm).unwrap();
    let out = sim(
        &[
            "score",
            "--map",
            "lab",
            "--robot-map",
            yaml.to_str().unwrap(),
            "--robot-start",
            "1e30",
            "1e30",
        ],
        Duration::from_secs(20),
    );
    assert_refused(&out, &["--robot-start"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Bad inputs table: a map that is a named pipe no program writes to is refused after a
/// bounded wait (before: `mission --map FIFO.csv` blocked in open(2) for ever).
#[test]
fn a_map_that_is_a_named_pipe_without_a_writer_is_refused() {
    let dir = temp_dir("fifo-map");
    let fifo = dir.join("map.csv");
    if !Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        eprintln!("skipped: no mkfifo");
        return;
    }
    let out = sim(
        &["mission", "--map", fifo.to_str().unwrap()],
        Duration::from_secs(15),
    );
    assert_refused(&out, &[fifo.to_str().unwrap(), "named pipe"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 22: options with a fixed set of values are typed by clap: `--help` lists them, and a
/// near miss is one line naming the flag, the values and clap's suggestion.
#[test]
fn fixed_choices_are_listed_and_a_near_miss_gets_a_suggestion() {
    let out = sim(&["mission", "--method", "xbao"], Duration::from_secs(20));
    let err = assert_refused(&out, &["--method", "possible values", "xboa"]);
    assert!(err.contains("tip: a similar value exists: 'xboa'"), "{err}");
    let out = sim(&["mission", "--slip", "ice"], Duration::from_secs(20));
    assert_refused(&out, &["--slip", "thesis", "realistic"]);
    let out = sim(&["mission", "--help"], Duration::from_secs(20));
    let help = String::from_utf8_lossy(&out.stdout);
    for values in [
        "[possible values: xboa, boa, mboa, aboa, saboa, ga, pso, gwo, abc, cmaes, nearest-frontier, frontier-utility]",
        "[possible values: efficient, thesis]",
        "[possible values: short, long]",
        "[possible values: thesis, full, realistic, none]",
        "[possible values: on, off]",
    ] {
        assert!(help.contains(values), "{values} not in:\n{help}");
    }
}

/// `--laser-noise-m` (`serve`, `mission`) takes a standard deviation in metres from 0 to 0.5;
/// anything else is refused naming the flag, before a server starts or a mission runs.
#[test]
fn laser_noise_m_refuses_what_no_laser_has() {
    for value in ["-0.01", "0.6", "NaN", "inf", "12mm"] {
        let mut args = SERVE.to_vec();
        args.extend(["--laser-noise-m", value]);
        let out = sim(&args, Duration::from_secs(10));
        assert_refused(&out, &["--laser-noise-m"]);
        let out = sim(
            &["mission", "--map", "lab", "--laser-noise-m", value],
            Duration::from_secs(10),
        );
        assert_refused(&out, &["--laser-noise-m"]);
    }
}
