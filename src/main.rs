//! `papillon`: the onboard program of a Pioneer P3-DX.
//!
//! Subcommands: `check` (validate a board file), `ports` (list serial ports), `probe` (talk to
//! a robot and print what it reports), `run` (an autonomous mission). See docs/user-guide.md.

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
}

/// Exit code for a missing or unreadable file.
const EXIT_FILE: u8 = 2;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { board } => check(&board),
        Command::Ports => ports(),
        Command::Probe(args) => {
            init_logging();
            probe(args)
        }
        Command::Run(args) => {
            init_logging();
            run(args)
        }
    }
}

fn init_logging() {
    // Colours only on a terminal: a log file of the progress lines stays plain text.
    let _ = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_target(false)
        .try_init();
}

/// Reads and parses a board file; prints one line and returns the exit code on failure.
fn load_board(path: &Path) -> Result<BoardConfig, ExitCode> {
    let bytes = match papillon::files::read_limited(path, papillon::files::BOARD_MAX_BYTES) {
        Ok(b) => b,
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
    let problems = board.validate(|json_path, problem| println!("{json_path}: {problem}"));
    if problems > 0 {
        eprintln!("{}: {problems} problem(s)", path.display());
        return ExitCode::from(1);
    }
    let link = match &board.link.tcp {
        Some(tcp) => format!("tcp {tcp}"),
        None => format!("{} @ {} baud", board.link.port, board.link.baud),
    };
    let (cols, rows) = board.grid.size_cells();
    println!(
        "OK: {} ({}), link {link}, laser {} {} beams, grid {cols}x{rows} cells at {} m, mission {} pop {} gen {}",
        board.robot.name,
        board.robot.subclass,
        board.laser.model,
        board.laser.beam_count,
        board.grid.resolution_m,
        board.mission.method,
        board.mission.population,
        board.mission.generations
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
    let options = ProbeOptions {
        port: args.target.port.unwrap_or_default(),
        tcp: args.target.tcp,
        drive: args.drive,
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
            eprintln!("papillon: {e}");
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
    if let Some(laser) = &args.laser {
        match Address::new(laser) {
            Some(a) if board.laser_model() == Some(papillon::config::LaserModel::Lms200) => {
                board.laser.port = Some(a);
            }
            Some(a) => board.laser.address = Some(a),
            None => return too_long("--laser"),
        }
    }
    let problems = board.validate(|path, problem| eprintln!("{path}: {problem}"));
    if problems > 0 {
        eprintln!("papillon: the board has {problems} problem(s); run `papillon check`");
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
    let mission = runtime::recording_mission_driver(options.log_dir.clone());
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

fn too_long(flag: &str) -> ExitCode {
    eprintln!("papillon: {flag} is longer than 64 bytes");
    ExitCode::from(EXIT_FILE)
}
