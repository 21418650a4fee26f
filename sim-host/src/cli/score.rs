//! `papillon-sim score`: scores a saved robot map (ROS map_server YAML + PGM) against a world's
//! ground truth ([`crate::score`]).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use papillon::geometry::Pose2;
use papillon::mapfile;

use crate::score::{Score, parse_pose, score};
use crate::world::World;

/// Arguments of `papillon-sim score`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// World: a built-in map (house, empty, factory, lab) or a map file (.csv, .png, .pgm,
    /// .map, .yaml).
    #[arg(long, default_value = "house")]
    pub map: String,
    /// The robot's map to score: a ROS map_server YAML (with its PGM beside it).
    #[arg(long)]
    pub robot_map: PathBuf,
    /// Cell size for worlds whose file does not give one (built-in, .csv, images, .map), in metres.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub resolution: f32,
    /// The robot's start in the world's map frame: X Y, optionally THETA (m, m, rad; default: the
    /// world's start, 1 m east and 1 m north of its south-west corner).
    #[arg(long, num_args = 2..=3, allow_negative_numbers = true, value_names = ["X", "Y", "THETA"])]
    pub start: Option<Vec<f32>>,
    /// The robot's start in the robot map's frame: X Y, optionally THETA (m, m, rad; default 0 0 0, the
    /// onboard binary's convention; give the world's start for a map drawn in the world's frame).
    #[arg(long, num_args = 2..=3, allow_negative_numbers = true, value_names = ["X", "Y", "THETA"])]
    pub robot_start: Option<Vec<f32>>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

fn execute(args: &Args) -> Result<Score, String> {
    let mut world = World::load(&args.map, args.resolution).map_err(|e| e.to_string())?;
    if let Some(v) = &args.start {
        world.set_start(parse_pose("--start", v)?);
        if let Some(why) = world.start_outside() {
            return Err(format!("--start: {why}"));
        }
    }
    let robot_start = match &args.robot_start {
        Some(v) => parse_pose("--robot-start", v)?,
        None => Pose2::default(),
    };
    // As a map file's origin: a start farther than 100 km from the map's is a mistake (the
    // world's `--start` is checked against the world itself).
    if robot_start.x.abs() > 100_000.0 || robot_start.y.abs() > 100_000.0 {
        return Err(format!(
            "--robot-start: ({}, {}) is more than 100 km from the robot map's origin",
            robot_start.x, robot_start.y
        ));
    }
    let map = mapfile::read_map(&args.robot_map).map_err(|e| e.to_string())?;
    Ok(score(&world, &map, robot_start))
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    match execute(&args) {
        Ok(s) => {
            let text = if args.json {
                serde_json::to_string(&s).unwrap_or_default()
            } else {
                format!(
                    "coverage {:.2} % ({} of {} observable cells known), map accuracy {:.2} % (free {:.2} %, occupied {:.2} %), wall error {:.3} m over {} occupied cells",
                    100.0 * s.coverage,
                    s.known_cells,
                    s.observable_cells,
                    100.0 * s.accuracy,
                    100.0 * s.free_agreement,
                    100.0 * s.occupied_agreement,
                    s.wall_error_m,
                    s.occupied_cells
                )
            };
            // A closed standard output (`| head`) is not an error.
            let _ = writeln!(std::io::stdout(), "{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("papillon-sim score: {e}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::builtin;
    use papillon::mapfile;

    #[test]
    fn the_command_reads_a_saved_map() {
        let w = builtin::lab(0.1).unwrap();
        let dir = std::env::temp_dir().join(format!("papillon-score-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let yaml = dir.join("robot.yaml");
        mapfile::write_map_image(&w.perfect_map(), &yaml).unwrap();
        let args = Args {
            map: "lab".into(),
            robot_map: yaml.clone(),
            resolution: 0.1,
            start: None,
            robot_start: Some(vec![w.start().x, w.start().y]),
            json: true,
        };
        assert_eq!(execute(&args).unwrap().coverage, 1.0);
        assert_eq!(execute(&args).unwrap().accuracy, 1.0);
        // The default robot start, the origin, is 1 m off: the map no longer lines up.
        let shifted = Args {
            robot_start: None,
            ..args.clone()
        };
        assert!(execute(&shifted).unwrap().coverage < 0.95);
        let bad = Args {
            robot_map: dir.join("missing.yaml"),
            ..args.clone()
        };
        let e = execute(&bad).unwrap_err();
        assert!(e.contains("missing.yaml") && !e.contains('\n'), "{e}");
        let bad = Args {
            start: Some(vec![1.0, f32::NAN]),
            ..args
        };
        assert!(execute(&bad).unwrap_err().starts_with("--start:"));
        std::fs::remove_dir_all(dir).unwrap();
    }
}
