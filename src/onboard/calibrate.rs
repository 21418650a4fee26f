//! `papillon calibrate`: the UMBmark benchmark (Borenstein & Feng 1996,
//! [`crate::control::umbmark`]) on the robot, and the odometry corrections it proposes for
//! the board (`$.robot.wheel_diameter_ratio`, `$.robot.wheelbase_ratio`).
//!
//! The robot drives an `L` x `L` square (4 m in the paper) closed-loop on its own odometry:
//! each leg until the odometry has gone `L` along the leg's heading (holding that heading),
//! each corner until the odometry heading is within [`TURN_TOLERANCE_DEG`] of the next one;
//! `runs` times counter-clockwise, then `runs` times clockwise. After each run the true end
//! position is asked for (measured by the user from a mark at the start, x forward and y to
//! the left of the start heading), or read from `papillon-sim serve --truth-log`. The robot
//! drives blind (no laser): keep a 5 m square clear; a bumper or a stalled wheel stops it.

use std::io::{self, BufRead};
use std::path::PathBuf;
use std::time::Duration;

use tokio::time::Instant;

use super::robot::{ArcosClient, MotionLimits, RobotEvent};
use super::runtime::{ProbeOptions, RuntimeError, next_status, probe_connect};
use crate::control::command::{Limits, MotionCommand};
use crate::control::odometry::ArcosOdometry;
use crate::control::umbmark::{self, OdometryErrors, ReturnError};
use crate::geometry::{Pose2, normalize_angle};

/// A corner ends once the odometry heading is this close to the next leg's \[deg\].
pub const TURN_TOLERANCE_DEG: f32 = 0.15;
/// A leg ends once this little is left of it on odometry \[m\].
pub const LEG_TOLERANCE_M: f32 = 0.003;
/// Longest a leg or a corner may take before the run is abandoned \[s\].
pub const MOVE_TIMEOUT_S: f64 = 120.0;

/// Where the true end positions come from.
#[derive(Clone, Debug)]
pub enum Truth {
    /// The user measures them and types them in.
    Ask,
    /// `papillon-sim serve --truth-log FILE`: robot 0's true pose, read after each run.
    TruthLog(PathBuf),
}

/// Options of `papillon calibrate`.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// The robot link (`drive` and `laser` are not used).
    pub link: ProbeOptions,
    /// Side of the square \[m\].
    pub side_m: f32,
    /// Runs in each direction.
    pub runs: u32,
    /// Cruise speed on the legs \[mm/s\].
    pub speed_mm_s: i16,
    /// The nominal wheelbase the firmware's odometry assumes \[m\].
    pub wheelbase_m: f32,
    /// Where the true end positions come from.
    pub truth: Truth,
}

/// Runs UMBmark and prints the runs, the errors found and the board settings proposed.
pub async fn calibrate_with(
    options: &CalibrateOptions,
    input: &mut impl BufRead,
    out: &mut impl io::Write,
) -> Result<OdometryErrors, RuntimeError> {
    let mut client = probe_connect(&options.link, out).await?;
    let cruise = options.speed_mm_s.clamp(50, 400);
    let limits = MotionLimits {
        max_speed_mm_s: cruise,
        max_turn_rate_deg_s: 30,
        accel_mm_s2: 300,
        decel_mm_s2: 300,
        rot_accel_deg_s2: 60,
    };
    client.start(&limits).await?;
    let result = runs(options, &mut client, input, out).await;
    let _ = client.stop_and_close().await;
    let (cw, ccw) = result?;
    let errors = umbmark::estimate(options.side_m, options.wheelbase_m, &cw, &ccw)
        .map_err(|e| RuntimeError::Mission(format!("calibrate: {e}")))?;
    writeln!(
        out,
        "umbmark: each 90° turn is truly {:+.2}° off, each leg curves {:+.2}° (left positive)",
        errors.turn_error_rad.to_degrees(),
        errors.leg_curve_rad.to_degrees()
    )?;
    writeln!(
        out,
        "umbmark: wheel-diameter ratio Ed = D_R/D_L = {:.4}, wheelbase ratio Eb = {:.4}",
        errors.ed, errors.eb
    )?;
    writeln!(
        out,
        "proposed board settings ($.robot): \"wheel_diameter_ratio\": {:.4}, \"wheelbase_ratio\": {:.4}, \"wheelbase_m\": {:.3}",
        errors.ed, errors.eb, options.wheelbase_m
    )?;
    Ok(errors)
}

type Runs = (Vec<ReturnError>, Vec<ReturnError>);

async fn runs(
    options: &CalibrateOptions,
    client: &mut ArcosClient,
    input: &mut impl BufRead,
    out: &mut impl io::Write,
) -> Result<Runs, RuntimeError> {
    let mut cw = Vec::new();
    let mut ccw = Vec::new();
    let mut odometry = ArcosOdometry::new();
    for (n, left) in (0..options.runs)
        .map(|_| true)
        .chain((0..options.runs).map(|_| false))
        .enumerate()
    {
        let name = if left {
            "counter-clockwise"
        } else {
            "clockwise"
        };
        if let Truth::Ask = options.truth {
            writeln!(
                out,
                "run {}: place the robot on the start mark, facing the first leg ({name}); press Enter",
                n + 1
            )?;
            out.flush()?;
            let mut line = String::new();
            input.read_line(&mut line)?;
        }
        let true_start = true_pose(&options.truth)?;
        let odo_start = settle(client, &mut odometry).await?;
        let turn = if left { 90.0f32 } else { -90.0 }.to_radians();
        for leg in 0..4 {
            let heading = odo_start.theta + turn * leg as f32;
            drive_leg(client, &mut odometry, options, heading).await?;
            turn_to(client, &mut odometry, heading + turn).await?;
        }
        let odo_end = settle(client, &mut odometry).await?;
        let odo = relative(odo_start, odo_end);
        let truth = match &options.truth {
            Truth::Ask => ask_end(input, out)?,
            t => relative(
                true_start.unwrap_or_default(),
                true_pose(t)?.unwrap_or_default(),
            ),
        };
        let e = ReturnError {
            x_m: truth.x - odo.x,
            y_m: truth.y - odo.y,
        };
        writeln!(
            out,
            "run {} ({name}): odometry ends at x {:+.3} m, y {:+.3} m; truly at x {:+.3} m, y {:+.3} m: return error x {:+.3} m, y {:+.3} m",
            n + 1,
            odo.x,
            odo.y,
            truth.x,
            truth.y,
            e.x_m,
            e.y_m
        )?;
        if left { &mut ccw } else { &mut cw }.push(e);
    }
    Ok((cw, ccw))
}

/// `to` in the frame of `from`.
fn relative(from: Pose2, to: Pose2) -> Pose2 {
    let (s, c) = from.theta.sin_cos();
    let (dx, dy) = (to.x - from.x, to.y - from.y);
    Pose2::new(
        c * dx + s * dy,
        -s * dx + c * dy,
        normalize_angle(to.theta - from.theta),
    )
}

/// Stops, waits for the robot to stand still, and returns the odometry pose.
async fn settle(
    client: &mut ArcosClient,
    odometry: &mut ArcosOdometry,
) -> Result<Pose2, RuntimeError> {
    client
        .drive(crate::control::command::Velocity::ZERO)
        .await?;
    let until = Instant::now() + Duration::from_millis(1000);
    while Instant::now() < until {
        if let Some(s) = next_status(client, Duration::from_millis(300)).await? {
            odometry.update(s.x_pos, s.y_pos, s.th_pos);
        }
    }
    Ok(odometry.pose_odom())
}

/// One status period: sends `command` (through the calibration's limits) and waits for the
/// next status packet; a bumper or a stalled wheel stops the run.
async fn period(
    client: &mut ArcosClient,
    odometry: &mut ArcosOdometry,
    command: MotionCommand,
) -> Result<Pose2, RuntimeError> {
    let clamp = Limits::new(400, 30, 300, 300, 60, 60);
    client.drive(clamp.clamp(command)).await?;
    let deadline = Instant::now() + Duration::from_millis(500);
    while let Some(ev) = client.next_event(deadline).await? {
        if let RobotEvent::Status { status: s, .. } = ev {
            if s.stalled() || s.bumpers_a() != 0 || s.bumpers_b() != 0 {
                client
                    .drive(crate::control::command::Velocity::ZERO)
                    .await?;
                return Err(RuntimeError::Mission(
                    "calibrate: a bumper or a stalled wheel stopped the run; clear a 5 m square"
                        .into(),
                ));
            }
            return Ok(odometry.update(s.x_pos, s.y_pos, s.th_pos));
        }
    }
    Err(RuntimeError::Mission(
        "calibrate: no status packet for 0.5 s".into(),
    ))
}

/// Drives one leg of `options.side_m` along `heading` (odometry), holding the heading.
async fn drive_leg(
    client: &mut ArcosClient,
    odometry: &mut ArcosOdometry,
    options: &CalibrateOptions,
    heading: f32,
) -> Result<(), RuntimeError> {
    let start = odometry.pose_odom();
    let began = Instant::now();
    let mut pose = start;
    loop {
        let along = (pose.x - start.x) * heading.cos() + (pose.y - start.y) * heading.sin();
        let left = options.side_m - along;
        if left <= LEG_TOLERANCE_M {
            return Ok(());
        }
        if began.elapsed().as_secs_f64() > MOVE_TIMEOUT_S {
            return Err(RuntimeError::Mission(
                "calibrate: a leg took too long".into(),
            ));
        }
        // Slow down over the last 0.3 m (the firmware decelerates at 300 mm/s²).
        let speed = (left * 1000.0).min(f32::from(options.speed_mm_s)).max(15.0);
        let err = normalize_angle(heading - pose.theta).to_degrees();
        let turn = (2.0 * err).clamp(-5.0, 5.0);
        pose = period(
            client,
            odometry,
            MotionCommand {
                speed_mm_s: speed.round() as i16,
                turn_rate_deg_s: turn.round() as i16,
            },
        )
        .await?;
    }
}

/// Turns in place until the odometry heading is within [`TURN_TOLERANCE_DEG`] of `heading`.
async fn turn_to(
    client: &mut ArcosClient,
    odometry: &mut ArcosOdometry,
    heading: f32,
) -> Result<(), RuntimeError> {
    let began = Instant::now();
    let mut pose = odometry.pose_odom();
    loop {
        let err = normalize_angle(heading - pose.theta).to_degrees();
        if err.abs() <= TURN_TOLERANCE_DEG {
            client
                .drive(crate::control::command::Velocity::ZERO)
                .await?;
            return Ok(());
        }
        if began.elapsed().as_secs_f64() > MOVE_TIMEOUT_S {
            return Err(RuntimeError::Mission(
                "calibrate: a turn took too long".into(),
            ));
        }
        let rate = (err * 1.5).clamp(-30.0, 30.0);
        let rate = if rate.abs() < 1.0 {
            rate.signum()
        } else {
            rate
        };
        pose = period(
            client,
            odometry,
            MotionCommand {
                speed_mm_s: 0,
                turn_rate_deg_s: rate.round() as i16,
            },
        )
        .await?;
    }
}

/// The robot's true pose, from the truth log (`None` when the user measures).
fn true_pose(truth: &Truth) -> Result<Option<Pose2>, RuntimeError> {
    let Truth::TruthLog(path) = truth else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| RuntimeError::Mission(format!("--truth-log {}: {e}", path.display())))?;
    text.lines()
        .rev()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|v| v["robot"].as_u64() == Some(0))
        .and_then(|v| {
            Some(Pose2::new(
                v["x_m"].as_f64()? as f32,
                v["y_m"].as_f64()? as f32,
                v["theta_rad"].as_f64()? as f32,
            ))
        })
        .map(Some)
        .ok_or_else(|| {
            RuntimeError::Mission(format!(
                "--truth-log {}: no pose of robot 0 in it",
                path.display()
            ))
        })
}

/// Asks the user for the true end position (mm forward and left of the start mark).
fn ask_end(input: &mut impl BufRead, out: &mut impl io::Write) -> Result<Pose2, RuntimeError> {
    loop {
        writeln!(
            out,
            "measure the robot's centre from the start mark: millimetres forward (along the start heading) and to the left, e.g. \"35 -120\":"
        )?;
        out.flush()?;
        let mut line = String::new();
        if input.read_line(&mut line)? == 0 {
            return Err(RuntimeError::Mission(
                "calibrate: no measurement given (end of input)".into(),
            ));
        }
        let nums: Vec<f32> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .filter_map(|t| t.parse().ok())
            .filter(|v: &f32| v.is_finite())
            .collect();
        if let [x, y] = nums[..] {
            return Ok(Pose2::new(x / 1000.0, y / 1000.0, 0.0));
        }
        writeln!(
            out,
            "expected two numbers in millimetres, found {:?}",
            line.trim()
        )?;
    }
}
