//! `papillon-sim serve`: the emulator server ([`crate::serve`]) until SIGINT or SIGTERM.
//!
//! Prints one line per endpoint (prefixed with `robot i: ` when there are several robots),
//! then `live ws://ADDR` with `--live`, then `ready`; on a signal it stops the server (and
//! finishes the `--mcap` recording) and prints `stopped`.

use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use crate::emulator::arcos;
use crate::faults::Faults;
use crate::serve::{self, ServeConfig, Server};

/// Arguments of `papillon-sim serve`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// World: a built-in map (house, lab, empty, factory) or a map file (.csv, .png, .pgm).
    #[arg(long, default_value = "house")]
    pub map: String,
    /// Serve ARCOS on a pseudo-terminal and make this path a symlink to its device.
    #[arg(long)]
    pub pty: Option<PathBuf>,
    /// Serve ARCOS over TCP on this address (MobileSim's is 127.0.0.1:8101).
    #[arg(long)]
    pub tcp: Option<String>,
    /// Where the laser is served: a TCP address for the LMS1xx (default 127.0.0.1:2111), a
    /// pty symlink path for the LMS200 (default /tmp/papillon-sim-lms200).
    #[arg(long)]
    pub laser: Option<String>,
    /// The emulated laser: an LMS1xx on TCP (CoLa-A) or an LMS200 on a pty (RS-232 telegrams).
    #[arg(long, value_enum, default_value = "lms1xx")]
    pub laser_model: LaserModel,
    /// Seed of the simulation's random choices (wheel slip, faults).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Odometry slip of the simulated robots, as `papillon-sim mission --slip`: thesis (a
    /// 1.5 cm slide at the end of each move, what the thesis saw), full (also heading and
    /// distance random walks), realistic (also per-robot wheel-diameter and wheelbase errors
    /// drawn from the seed, and fast-turn slip; sim-host/src/odometry_error.rs) or none.
    /// `--wheel-errors` then sets the systematic errors instead of the drawn ones.
    #[arg(long, default_value = "thesis", value_parser = ["thesis", "full", "realistic", "none"])]
    pub slip: String,
    /// Faults to inject, e.g. `corrupt=0.01,cut=10+3,laser-drop=20+2` (see the user guide:
    /// corrupt, drop, latency, jitter, cut, laser-drop, slip, estop, drain).
    #[arg(long, default_value = "")]
    pub faults: Faults,
    /// Robots sharing the world (1 to 16), served on consecutive endpoints.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=16), allow_negative_numbers = true)]
    pub robots: u8,
    /// Write each robot's true pose and velocity to this file every 20 ms, as JSON lines:
    /// `{"t_s","unix_s","robot","x_m","y_m","theta_rad","speed_mm_s","turn_deg_s",
    /// "motors_enabled","contact"}` (`t_s` since start, `unix_s` since the Unix epoch;
    /// `contact`: a wheel stall or a bumper). The file is
    /// created or truncated; a symbolic link in its place is refused.
    #[arg(long)]
    pub truth_log: Option<PathBuf>,
    /// The emulated firmware's watchdog \[ms\] (FLASH `Watchdog`, reported in CONFIG): with no
    /// command for this long on an open session the robot halts at its deceleration.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u16).range(100..), allow_negative_numbers = true)]
    pub watchdog_ms: u16,
    /// What the microcontroller presents itself as: `robot` (a robot's serial number; ARIA
    /// then connects the laser on its own port) or `mobilesim` (serial number `SIM`, as
    /// MobileSim: ARIA then asks for the laser over the robot link and gets it there).
    #[arg(long, value_enum, default_value = "robot")]
    pub identity: Identity,
    /// The P3-DX subclass emulated: `p3dx-sh` (ARCOS, DistConvFactor 1.0) or `p3dx` (old
    /// AROS firmware, positions in units of 0.485 mm).
    #[arg(long, value_enum, default_value = "p3dx-sh")]
    pub subclass: Subclass,
    /// Range noise of the emulated laser, as a fraction of the range (standard deviation of
    /// Gaussian noise, drawn afresh for every scan; the runner's model): 0 for noise-free
    /// ranges, 0.05 for the thesis's laser that `papillon-sim mission` simulates by default
    /// (`boards/sim-thesis.json`), 0.003 for `boards/sim.json`'s LMS1xx (with --laser-noise-m
    /// 0.012).
    #[arg(long, default_value_t = 0.0, value_parser = super::noise_fraction)]
    pub laser_noise: f32,
    /// Range noise of the emulated laser that does not grow with the range, standard deviation
    /// in metres, added in quadrature to --laser-noise's: 0.012 for a SICK LMS1xx's typical
    /// statistical error (SICK: 12 mm, 1 σ, over its whole range). Default 0.
    #[arg(long, default_value_t = 0.0, value_parser = super::range_sigma_m, allow_negative_numbers = true)]
    pub laser_noise_m: f32,
    /// The serial speed of the emulated microcontroller on `--pty`, in baud: it answers only a
    /// client that set its line to this speed, as a real serial line would (a pty itself
    /// carries bytes at any speed). Default: any speed.
    #[arg(long, value_parser = ["9600", "19200", "38400", "57600", "115200"])]
    pub baud: Option<String>,
    /// Systematic odometry errors of the emulated robot, `ED,EB` (Borenstein & Feng's UMBmark
    /// errors): ED the right over left wheel diameter, EB the effective over nominal
    /// wheelbase, e.g. `1.02,0.97`; each from 0.8 to 1.2. Default: perfect wheels.
    #[arg(long, value_parser = wheel_errors)]
    pub wheel_errors: Option<(f32, f32)>,
    /// Robot 0's start pose `X,Y,THETA` [m, m, rad] instead of the world's (1 m from its
    /// south-west corner, heading east), e.g. `12,12,0`.
    #[arg(long, value_parser = start_pose, allow_negative_numbers = true)]
    pub start: Option<papillon::geometry::Pose2>,
    /// Record the run as MCAP with Foxglove's schemas: the world's map at the start, each
    /// robot's true pose and odometry at 10 Hz (`/pose/true`, `/pose/odometry`) and each scan
    /// served (`/scan`, at the laser's true pose). Written when the server stops.
    #[arg(long)]
    pub mcap: Option<PathBuf>,
    /// Serve the same messages live to Foxglove on this address (host:port, e.g.
    /// 127.0.0.1:8765): Foxglove → Open connection → Foxglove WebSocket → ws://HOST:PORT.
    /// Announced as `live ws://ADDR`. Off by default.
    #[arg(long, value_name = "HOST:PORT")]
    pub live: Option<String>,
}

/// `X,Y,THETA`, finite numbers.
fn start_pose(s: &str) -> Result<papillon::geometry::Pose2, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<f32>>>()
        .ok_or_else(|| format!("expected X,Y,THETA as numbers (e.g. 12,12,0), found {s:?}"))?;
    match v[..] {
        [x, y, theta] => Ok(papillon::geometry::Pose2::new(x, y, theta)),
        _ => Err(format!("expected X,Y,THETA (three numbers), found {s:?}")),
    }
}

/// `ED,EB`, each a ratio from 0.8 to 1.2.
fn wheel_errors(s: &str) -> Result<(f32, f32), String> {
    let bad = || {
        format!("expected ED,EB with each a ratio from 0.8 to 1.2 (e.g. 1.02,0.97), found {s:?}")
    };
    let (ed, eb) = s.split_once(',').ok_or_else(bad)?;
    let ratio = |v: &str| {
        v.trim()
            .parse::<f32>()
            .ok()
            .filter(|r| (0.8..=1.2).contains(r))
            .ok_or_else(bad)
    };
    Ok((ratio(ed)?, ratio(eb)?))
}

/// What `serve` presents itself as.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identity {
    /// A robot: a robot's serial number, the laser on its own link.
    Robot,
    /// MobileSim: serial number `SIM`, the laser also over the robot link.
    #[value(name = "mobilesim")]
    MobileSim,
}

/// The P3-DX subclass `serve` emulates.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subclass {
    /// `p3dx`: DistConvFactor 0.485.
    #[value(name = "p3dx")]
    P3dx,
    /// `p3dx-sh`: DistConvFactor 1.0.
    #[value(name = "p3dx-sh")]
    P3dxSh,
}

/// Which laser `serve` emulates.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaserModel {
    /// SICK LMS1xx, CoLa-A over TCP.
    Lms1xx,
    /// SICK LMS200, telegrams over a serial line (a pty here).
    Lms200,
}

impl From<LaserModel> for serve::LaserModel {
    fn from(m: LaserModel) -> Self {
        match m {
            LaserModel::Lms1xx => serve::LaserModel::Lms1xx,
            LaserModel::Lms200 => serve::LaserModel::Lms200,
        }
    }
}

impl From<Args> for ServeConfig {
    fn from(a: Args) -> Self {
        ServeConfig {
            // Checked by clap's value parser (the names of `Slip::from_name`).
            slip: crate::scenario::Slip::from_name(&a.slip)
                .unwrap_or(crate::scenario::Slip::Thesis),
            map: a.map,
            pty: a.pty,
            tcp: a.tcp,
            laser: a.laser,
            laser_model: a.laser_model.into(),
            seed: a.seed,
            faults: a.faults,
            robots: usize::from(a.robots),
            truth_log: a.truth_log,
            watchdog_ms: a.watchdog_ms,
            identity: match a.identity {
                Identity::Robot => arcos::Identity::Robot,
                Identity::MobileSim => arcos::Identity::MobileSim,
            },
            subclass: match a.subclass {
                Subclass::P3dx => arcos::Subclass::P3dx,
                Subclass::P3dxSh => arcos::Subclass::P3dxSh,
            },
            laser_noise_fraction: a.laser_noise,
            laser_range_sigma_m: a.laser_noise_m,
            baud: a.baud.and_then(|b| b.parse().ok()),
            wheel_errors: a.wheel_errors,
            start: a.start,
            mcap: a.mcap,
            live: a.live,
        }
    }
}

/// Runs `serve` until SIGINT or SIGTERM.
pub fn run(args: Args) -> ExitCode {
    serve::signal::install_handlers();
    let mut server = match Server::start(&ServeConfig::from(args)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("papillon-sim serve: {e}");
            return ExitCode::FAILURE;
        }
    };
    let several = server.robot_count() > 1;
    for e in server.endpoints() {
        if several {
            println!("robot {}: {}", e.robot, e.what);
        } else {
            println!("{}", e.what);
        }
    }
    if let Some(addr) = server.live_addr() {
        println!("live ws://{addr}");
    }
    println!("ready");
    let _ = io::stdout().flush();
    serve::signal::wait();
    let finished = server.stop();
    let _ = writeln!(io::stdout(), "stopped");
    match finished {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("papillon-sim serve: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Slip;
    use clap::Parser;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(extra: &[&str]) -> Result<ServeConfig, clap::Error> {
        let argv = ["serve"].iter().chain(extra);
        Cli::try_parse_from(argv).map(|c| ServeConfig::from(c.args))
    }

    #[test]
    fn the_slip_is_named_as_for_mission_and_defaults_to_the_thesis() {
        assert_eq!(parse(&[]).unwrap().slip, Slip::Thesis);
        for slip in [Slip::Thesis, Slip::Full, Slip::Realistic, Slip::None] {
            assert_eq!(parse(&["--slip", slip.name()]).unwrap().slip, slip);
        }
        let both = parse(&["--slip", "realistic", "--wheel-errors", "1.02,0.97"]).unwrap();
        assert_eq!(
            (both.slip, both.wheel_errors),
            (Slip::Realistic, Some((1.02, 0.97)))
        );
        let e = parse(&["--slip", "lots"]).unwrap_err().to_string();
        assert!(e.contains("--slip") && e.contains("realistic"), "{e}");
    }
}
