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
