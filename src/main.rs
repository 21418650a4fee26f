//! `papillon`: the onboard program of a Pioneer P3-DX.
//!
//! Subcommands: `check` (validate a board file), `ports` (list serial ports), `probe` (talk to
//! a robot and print what it reports), `run` (an autonomous mission), `calibrate` (UMBmark
//! odometry calibration). See docs/user-guide.md.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use papillon::config::{Address, BoardConfig, ConfigError};
use papillon::onboard::runtime::{self, ProbeOptions, RunOptions, Start};

#[derive(Parser)]
#[command(
    name = "papillon",
    version,
    about = "Autonomous exploration on a Pioneer P3-DX"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// How log lines on standard error are written: `text` (one line each; colours only on a
    /// terminal) or `json` (one JSON object per line). Which lines: `RUST_LOG` (e.g.
    /// `RUST_LOG=debug`, `RUST_LOG=papillon::onboard::mission=debug`; default `info`).
    #[arg(long, global = true, value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum LogFormat {
    Text,
    Json,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a board file and print every problem with its JSON path.
    Check {
        /// The board file (JSON).
        #[arg(long)]
        board: PathBuf,
    },
    /// List the serial ports of this machine.
    Ports,
    /// Connect to a robot, print its identity, CONFIG, battery and pose, then disconnect.
    Probe(ProbeArgs),
    /// Run an autonomous mission.
    Run(RunArgs),
    /// Run the UMBmark square (Borenstein & Feng 1996) clockwise and counter-clockwise and
    /// propose the board's odometry corrections. The robot drives blind: clear a 5 m square.
    Calibrate(CalibrateArgs),
}

#[derive(Args)]
struct CalibrateArgs {
    #[command(flatten)]
    target: Target,
    /// Serial speed [baud]; by default the usual speeds are tried in turn.
    #[arg(long, value_parser = ["9600", "19200", "38400", "57600", "115200"])]
    baud: Option<String>,
    /// Side of the square [m] (4 in the paper).
    #[arg(long, default_value_t = 4.0)]
    side_m: f32,
    /// Runs in each direction (5 in the paper).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=20))]
    runs: u32,
    /// Cruise speed on the legs [mm/s].
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(i16).range(50..=400))]
    speed_mm_s: i16,
    /// The robot's nominal wheelbase (wheel track) [mm], as its odometry assumes it.
    #[arg(long, default_value_t = 330.0)]
    wheelbase_mm: f32,
    /// Read the true end positions from `papillon-sim serve --truth-log FILE` instead of
    /// asking for them.
    #[arg(long)]
    truth_log: Option<PathBuf>,
}

#[derive(Args)]
#[group(required = true, multiple = false)]
struct Target {
    /// Serial device of the robot's microcontroller.
    #[arg(long)]
    port: Option<String>,
    /// TCP address (host:port) of the robot (MobileSim, papillon-sim serve).
    #[arg(long)]
    tcp: Option<String>,
}

#[derive(Args)]
struct ProbeArgs {
    #[command(flatten)]
    target: Target,
    /// Drive a 0.5 m square at 100 mm/s and report the odometry (keep clear of the robot).
    #[arg(long)]
    drive: bool,
    /// Serial speed [baud]; by default 9600, 19200, 38400, 57600 and 115200 are tried in turn
    /// until the robot answers.
    #[arg(long, value_parser = ["9600", "19200", "38400", "57600", "115200"])]
    baud: Option<String>,
    /// Also check the laser with one scan (beam count and ranges): host:port of an LMS1xx, or
    /// the serial device of an LMS200 (with --board naming an LMS200).
    #[arg(long)]
    laser: Option<String>,
    /// Board file describing the laser for --laser (default: a P3-DX's LMS1xx, 541 beams).
    #[arg(long, requires = "laser")]
    board: Option<PathBuf>,
}

#[derive(Args)]
struct RunArgs {
    /// The board file (JSON).
    #[arg(long)]
    board: PathBuf,
    /// Serial device of the robot (overrides the board).
    #[arg(long, conflicts_with = "tcp")]
    port: Option<String>,
    /// TCP address of the robot (overrides the board).
    #[arg(long)]
    tcp: Option<String>,
    /// Laser endpoint (overrides the board): host:port of an LMS1xx, or the serial device of
    /// an LMS200.
    #[arg(long)]
    laser: Option<String>,
    /// Directory for the mission state, telemetry and maps.
    #[arg(long, default_value = "papillon-log")]
    log_dir: PathBuf,
    /// Continue the mission saved in the log directory.
    #[arg(long)]
    resume: bool,
    /// Start a new mission even if an unfinished one is saved in the log directory: its
    /// files are first moved to `<log-dir>/previous-N/`.
    #[arg(long, conflicts_with = "resume")]
    fresh: bool,
    /// Serve the mission live to Foxglove on this address (host:port, e.g. 127.0.0.1:8765;
    /// 0.0.0.0:8765 to watch from another machine): Foxglove → Open connection → Foxglove
    /// WebSocket → ws://HOST:PORT. Off by default: without it nothing listens.
    #[arg(long, value_name = "HOST:PORT")]
    live: Option<String>,
    /// When the mission ends (explored, energy budget or battery voltage low), drive back to
    /// the start position first (the board's $.mission.return_to_start).
    #[arg(long)]
    return_to_start: bool,
    /// Scan matching (overrides the board's $.localize.enabled): on or off.
    #[arg(long, value_parser = ["on", "off"])]
    localize: Option<String>,
}

/// Exit code for a missing or unreadable file.
const EXIT_FILE: u8 = 2;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            eprintln!("papillon: {}", clap_error_line(&e));
            return ExitCode::from(EXIT_FILE);
        }
        Err(e) => {
            // --help and --version.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
    };
    match cli.command {
        Command::Check { board } => check(&board),
        Command::Ports => ports(),
        Command::Probe(args) => {
            if let Err(code) = init_logging(cli.log_format) {
                return code;
            }
            probe(args)
        }
        Command::Run(args) => {
            if let Err(code) = init_logging(cli.log_format) {
                return code;
            }
            run(args)
        }
        Command::Calibrate(args) => {
            if let Err(code) = init_logging(cli.log_format) {
                return code;
            }
            calibrate(args)
        }
    }
}

/// One line for a bad command line: clap's first paragraph (the error and, for a missing
/// argument, the flags it names), without its `error: ` prefix.
fn clap_error_line(e: &clap::Error) -> String {
    if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        return "a subcommand is missing: check, ports, probe, run or calibrate (see papillon --help)".into();
    }
    papillon::command_line::error_line(&e.to_string())
}

/// Log lines on standard error: filtered by `RUST_LOG` (default `info`), as text (colours only
/// on a terminal: a log file of the progress lines stays plain text) or JSON. A `RUST_LOG` that
/// does not parse is one line naming it.
fn init_logging(format: LogFormat) -> Result<(), ExitCode> {
    use tracing_subscriber::EnvFilter;
    use tracing_subscriber::filter::LevelFilter;
    let filter = EnvFilter::builder()
        .with_default_directive(LevelFilter::INFO.into())
        .from_env()
        .map_err(|e| {
            eprintln!(
                "papillon: RUST_LOG: {e} (for example RUST_LOG=debug or RUST_LOG=papillon=debug)"
            );
            ExitCode::from(EXIT_FILE)
        })?;
    let builder = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(filter)
        .with_target(false);
    let _ = match format {
        LogFormat::Text => builder
            .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
            .try_init(),
        LogFormat::Json => builder.json().with_ansi(false).try_init(),
    };
    Ok(())
}

/// Reads and parses a board file; prints one line and returns the exit code on failure.
fn load_board(path: &Path) -> Result<BoardConfig, ExitCode> {
    let bytes = match papillon::files::read_limited(path, papillon::files::BOARD_MAX_BYTES) {
        Ok(b) => b,
        Err(_) if path.as_os_str().is_empty() => {
            eprintln!("papillon: --board: an empty path names no board file");
            return Err(ExitCode::from(EXIT_FILE));
        }
        Err(e) => {
            eprintln!("papillon: cannot read board file {}: {e}", path.display());
            return Err(ExitCode::from(EXIT_FILE));
        }
    };
    BoardConfig::from_json(&bytes).map_err(|e| {
        match &e {
            ConfigError::MissingKey { path: key } => {
                println!("{key}: missing")
            }
            ConfigError::UnknownKey { path: key, .. } => println!("{key}: unknown key ({e})"),
            ConfigError::DuplicateKey { path: key, .. } => println!("{key}: duplicate key ({e})"),
            ConfigError::Value {
                path: key,
                expected,
                found,
                ..
            } if !key.is_empty() => println!("{key}: expected {expected}, found {found}"),
            _ => {}
        }
        eprintln!("{}: {e}", path.display());
        ExitCode::from(1)
    })
}

fn check(path: &Path) -> ExitCode {
    let board = match load_board(path) {
        Ok(b) => b,
        Err(code) => return code,
    };
    let mut first = None;
    let problems = board.validate(|json_path, problem| {
        println!("{json_path}: {problem}");
        first.get_or_insert_with(|| format!("{json_path}: {problem}"));
    });
    if let Some(first) = first {
        eprintln!("{}: {first}{}", path.display(), more(problems));
        return ExitCode::from(1);
    }
    let link = match &board.link.tcp {
        Some(tcp) => format!("tcp {tcp}"),
        None => format!("{} @ {} baud", board.link.port, board.link.baud),
    };
    let (cols, rows) = board.grid.size_cells();
    let body = board.footprint();
    let opening = papillon::mission::footprint::narrowest_opening_m(
        &board.planning_layer(),
        board.grid.resolution_m,
    )
    .map_or(String::new(), |m| {
        format!(", passes openings from {m:.2} m (aligned with the cells)")
    });
    println!(
        "OK: {} ({}), link {link}, laser {} {} beams, grid {cols}x{rows} cells at {} m, mission {} pop {} gen {}, body {} m wide with {} m clearance{opening}",
        board.robot.name,
        board.robot.subclass,
        board.laser.model,
        board.laser.beam_count,
        board.grid.resolution_m,
        board.mission.method,
        board.mission.population,
        board.mission.generations,
        body.width_m,
        board.clearance_m(),
    );
    ExitCode::SUCCESS
}

fn ports() -> ExitCode {
    let mut names: Vec<String> = match serialport::available_ports() {
        Ok(list) => list.into_iter().map(|p| p.port_name).collect(),
        Err(e) => {
            eprintln!("papillon: listing serial ports failed: {e}");
            Vec::new()
        }
    };
    // Without libudev the enumeration may miss ports; look for the usual device names too.
    if let Ok(dir) = std::fs::read_dir("/dev") {
        for entry in dir.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if ["ttyS", "ttyUSB", "ttyACM"]
                .iter()
                .any(|p| name.starts_with(p))
            {
                let full = format!("/dev/{name}");
                if !names.contains(&full) {
                    names.push(full);
                }
            }
        }
    }
    names.sort();
    if names.is_empty() {
        println!("no serial ports found");
    }
    for n in names {
        println!("{n}");
    }
    ExitCode::SUCCESS
}

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("a tokio runtime")
}

fn probe(args: ProbeArgs) -> ExitCode {
    let flag = match (&args.target.tcp, &args.target.port) {
        (Some(tcp), _) => format!("--tcp {tcp}"),
        (None, Some(port)) => format!("--port {port}"),
        (None, None) => "--port or --tcp".to_string(),
    };
    let laser = match &args.laser {
        None => None,
        Some(address) => {
            let mut board = match &args.board {
                Some(path) => match load_board(path) {
                    Ok(b) => b,
                    Err(code) => return code,
                },
                None => BoardConfig::default(),
            };
            let Some(a) = Address::new(address) else {
                return too_long("--laser");
            };
            if board.laser_model() == Some(papillon::config::LaserModel::Lms200) {
                board.laser.port = Some(a);
            } else {
                board.laser.address = Some(a);
            }
            Some(board)
        }
    };
    let options = ProbeOptions {
        port: args.target.port.unwrap_or_default(),
        tcp: args.target.tcp,
        drive: args.drive,
        baud: args.baud.and_then(|b| b.parse().ok()),
        laser,
    };
    let result = runtime().block_on(async {
        let mut out = std::io::stdout();
        tokio::select! {
            r = runtime::probe_with(&options, &mut out) => r,
            _ = runtime::shutdown_signal() => {
                // The session is dropped; the firmware watchdog stops the robot within 2 s.
                eprintln!("papillon: probe interrupted");
                Ok(())
            }
        }
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let e = e.to_string();
            if e.contains("check --") {
                eprintln!("papillon: {e}");
            } else {
                eprintln!("papillon: {e}; check {flag}");
            }
            ExitCode::from(1)
        }
    }
}

fn run(args: RunArgs) -> ExitCode {
    let mut board = match load_board(&args.board) {
        Ok(b) => b,
        Err(code) => return code,
    };
    if let Some(port) = &args.port {
        board.link.tcp = None;
        match Address::new(port) {
            Some(p) => board.link.port = p,
            None => return too_long("--port"),
        }
    }
    if let Some(tcp) = &args.tcp {
        match Address::new(tcp) {
            Some(t) => board.link.tcp = Some(t),
            None => return too_long("--tcp"),
        }
    }
    if args.return_to_start {
        board.mission.return_to_start = Some(true);
    }
    if let Some(on) = &args.localize {
        board.localize.enabled = Some(on == "on");
    }
    if let Some(laser) = &args.laser {
        match Address::new(laser) {
            Some(a) if board.laser_model() == Some(papillon::config::LaserModel::Lms200) => {
                board.laser.port = Some(a);
            }
            Some(a) => board.laser.address = Some(a),
            None => return too_long("--laser"),
        }
    }
    // A problem in a value given on the command line names its flag, any other the board file
    // and the JSON path.
    let flag_for = |path: &str| match path {
        "$.link.port" => args.port.as_ref().map(|v| format!("--port '{v}'")),
        "$.link.tcp" => args.tcp.as_ref().map(|v| format!("--tcp '{v}'")),
        "$.laser.address" | "$.laser.port" => args.laser.as_ref().map(|v| format!("--laser '{v}'")),
        "$.localize.enabled" => args.localize.as_ref().map(|v| format!("--localize {v}")),
        _ => None,
    };
    let mut first = None;
    let problems = board.validate(|path, problem| {
        first.get_or_insert_with(|| match flag_for(path) {
            Some(flag) => format!("{flag} (the board's {path}): {problem}"),
            None => format!("{}: {path}: {problem}", args.board.display()),
        });
    });
    if let Some(first) = first {
        eprintln!("papillon: {first}{}", more(problems));
        return ExitCode::from(1);
    }
    let options = RunOptions {
        board,
        log_dir: args.log_dir,
        start: match (args.resume, args.fresh) {
            (true, _) => Start::Resume,
            (_, true) => Start::Fresh,
            _ => Start::New,
        },
    };
    // The live view listens before anything is connected: an address it cannot use refuses
    // the run at once.
    let live = match args.live.as_deref().map(papillon::live::LiveServer::bind) {
        None => None,
        Some(Ok(server)) => {
            tracing::info!(
                url = %format_args!("ws://{}", server.local_addr()),
                "live view: open this in Foxglove (Open connection, Foxglove WebSocket)"
            );
            Some(server)
        }
        Some(Err(e)) => {
            eprintln!("papillon: --live {e}");
            return ExitCode::from(1);
        }
    };
    let mission = runtime::recording_mission_driver(options.log_dir.clone(), live);
    let result = runtime().block_on(runtime::run_with(
        options,
        runtime::laser_codec,
        mission,
        runtime::shutdown_signal(),
    ));
    match result {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("papillon: {e}");
            ExitCode::from(1)
        }
    }
}

fn calibrate(args: CalibrateArgs) -> ExitCode {
    if !(args.side_m.is_finite() && (1.0..=10.0).contains(&args.side_m)) {
        eprintln!("papillon: --side-m must be from 1 to 10 m");
        return ExitCode::from(EXIT_FILE);
    }
    if !(args.wheelbase_mm.is_finite() && (100.0..=1000.0).contains(&args.wheelbase_mm)) {
        eprintln!("papillon: --wheelbase-mm must be from 100 to 1000 mm");
        return ExitCode::from(EXIT_FILE);
    }
    let options = papillon::onboard::calibrate::CalibrateOptions {
        link: ProbeOptions {
            port: args.target.port.unwrap_or_default(),
            tcp: args.target.tcp,
            drive: false,
            baud: args.baud.and_then(|b| b.parse().ok()),
            laser: None,
        },
        side_m: args.side_m,
        runs: args.runs,
        speed_mm_s: args.speed_mm_s,
        wheelbase_m: args.wheelbase_mm / 1000.0,
        truth: match args.truth_log {
            Some(p) => papillon::onboard::calibrate::Truth::TruthLog(p),
            None => papillon::onboard::calibrate::Truth::Ask,
        },
    };
    let result = runtime().block_on(async {
        let mut out = std::io::stdout();
        let mut input = std::io::stdin().lock();
        tokio::select! {
            r = papillon::onboard::calibrate::calibrate_with(&options, &mut input, &mut out) => r.map(|_| ()),
            _ = runtime::shutdown_signal() => {
                eprintln!("papillon: calibrate interrupted");
                Ok(())
            }
        }
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("papillon: {e}");
            ExitCode::from(1)
        }
    }
}

/// ` (and N more problems)` after the first of `problems`.
fn more(problems: usize) -> String {
    match problems {
        0 | 1 => String::new(),
        2 => " (and 1 more problem)".into(),
        n => format!(" (and {} more problems)", n - 1),
    }
}

fn too_long(flag: &str) -> ExitCode {
    eprintln!("papillon: {flag} is longer than 64 bytes");
    ExitCode::from(EXIT_FILE)
}
