//! `papillon-sim score`: scores a saved robot map (ROS map_server YAML + PGM, as the onboard
//! binary and `papillon-sim mission` write) against a world's ground truth, with the same
//! coverage measure as a simulated mission ([`crate::world::truth`]).
//!
//! Alignment: the robot map's frame and the world's map frame are tied by the start pose. The
//! robot started at `--robot-start` in its map's frame (default (0, 0, 0): the onboard binary's
//! map frame has the robot's start pose at its origin) and at the world's start (`--start`,
//! default the world's own, 1 m east and 1 m north of its south-west corner) in the world. Each observable world cell's centre
//! `p` is looked up in the robot map at `robot_start ⊕ world_start⁻¹ ⊕ p`; cells outside the
//! robot map count as unknown.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use papillon::geometry::{Point2, Pose2};
use papillon::grid::CellClass;
use papillon::mapfile::{self, MapImage};

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
    #[arg(long, default_value_t = 0.1)]
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

/// The score of a robot map.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Score {
    /// Known observable cells / observable cells (0..1).
    pub coverage: f32,
    /// Size of the observable set \[cells\].
    pub observable_cells: usize,
    /// Observable cells the robot map knows \[cells\].
    pub known_cells: usize,
}

/// The pose `(x, y, theta)` from 2 or 3 numbers (theta 0 when absent).
pub fn pose_from(values: &[f32]) -> Pose2 {
    Pose2::new(
        values.first().copied().unwrap_or(0.0),
        values.get(1).copied().unwrap_or(0.0),
        values.get(2).copied().unwrap_or(0.0),
    )
}

/// Checks a `--start`-style option's numbers (finite); `name` is the option.
pub fn parse_pose(name: &str, values: &[f32]) -> Result<Pose2, String> {
    if !(2..=3).contains(&values.len()) || values.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "{name}: expected X Y [THETA] as finite numbers, got {values:?}"
        ));
    }
    Ok(pose_from(values))
}

/// The inverse of a rigid transform.
fn inverse(p: Pose2) -> Pose2 {
    let (s, c) = p.theta.sin_cos();
    Pose2::new(-(c * p.x + s * p.y), -(-s * p.x + c * p.y), -p.theta)
}

/// Scores `map` against `world`'s truth, the robot having started at `robot_start` in the
/// map's frame and at `world.start()` in the world.
pub fn score(world: &World, map: &MapImage, robot_start: Pose2) -> Score {
    let truth = world.truth();
    let g = *world.geometry();
    let robot_from_world = robot_start.compose(inverse(world.start()));
    let identity = robot_from_world.x.abs() < 1e-6
        && robot_from_world.y.abs() < 1e-6
        && robot_from_world.theta.abs() < 1e-6;
    let known_cells = if identity && map.geometry == g {
        truth.known_cells_by(|i| map.cells[i].is_known())
    } else {
        truth.known_cells_by(|i| {
            let p = robot_from_world.transform_point(g.cell_center(g.cell(i)));
            class_at(map, p).is_known()
        })
    };
    let observable_cells = truth.len();
    Score {
        coverage: if observable_cells == 0 {
            0.0
        } else {
            known_cells as f32 / observable_cells as f32
        },
        observable_cells,
        known_cells,
    }
}

fn class_at(map: &MapImage, p: Point2) -> CellClass {
    map.geometry
        .cell_at(p)
        .and_then(|c| map.geometry.index(c))
        .and_then(|i| map.cells.get(i).copied())
        .unwrap_or(CellClass::Unknown)
}

fn execute(args: &Args) -> Result<Score, String> {
    let mut world = World::load(&args.map, args.resolution).map_err(|e| e.to_string())?;
    if let Some(v) = &args.start {
        world.set_start(parse_pose("--start", v)?);
    }
    let robot_start = match &args.robot_start {
        Some(v) => parse_pose("--robot-start", v)?,
        None => Pose2::default(),
    };
    let map = mapfile::read_map(&args.robot_map).map_err(|e| e.to_string())?;
    Ok(score(&world, &map, robot_start))
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    match execute(&args) {
        Ok(s) => {
            let text = if args.json {
                serde_json::json!({
                    "coverage": s.coverage,
                    "observable_cells": s.observable_cells,
                    "known_cells": s.known_cells,
                })
                .to_string()
            } else {
                format!(
                    "coverage {:.2} % ({} of {} observable cells known)",
                    100.0 * s.coverage,
                    s.known_cells,
                    s.observable_cells
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

    #[test]
    fn a_perfect_map_scores_one_and_an_empty_map_zero() {
        let w = builtin::lab(0.1).unwrap();
        let s = score(&w, &w.perfect_map(), w.start());
        assert_eq!(s.coverage, 1.0);
        assert_eq!(s.known_cells, s.observable_cells);
        assert_eq!(s.observable_cells, w.truth().len());
        let empty = MapImage {
            geometry: *w.geometry(),
            cells: vec![CellClass::Unknown; w.geometry().cell_count()],
        };
        let s = score(&w, &empty, w.start());
        assert_eq!((s.coverage, s.known_cells), (0.0, 0));
    }

    #[test]
    fn maps_are_aligned_by_the_start_pose() {
        // A robot whose map frame has its start at the origin, facing north (+90°): world
        // point q maps to robot-frame R(+90°)·(q - start).
        let w = builtin::lab(0.1).unwrap();
        let robot_start = Pose2::new(0.0, 0.0, core::f32::consts::FRAC_PI_2);
        let g = *w.geometry();
        // Robot map: 8 m x 8 m rotated, so x in [-8, 0] (well, -7..1) and y in [-1, 7].
        let rg = papillon::grid::GridGeometry::new(100, 100, 0.1, Point2::new(-8.0, -2.0)).unwrap();
        let robot_from_world = robot_start.compose(inverse(w.start()));
        let mut cells = vec![CellClass::Unknown; rg.cell_count()];
        for (i, c) in cells.iter_mut().enumerate() {
            let p = rg.cell_center(rg.cell(i));
            // Back to the world.
            let q = inverse(robot_from_world).transform_point(p);
            if let Some(wc) = g.cell_at(q) {
                *c = if w.is_blocked(wc) {
                    CellClass::Occupied
                } else {
                    CellClass::Free
                };
            }
        }
        let map = MapImage {
            geometry: rg,
            cells,
        };
        let s = score(&w, &map, robot_start);
        assert!(s.coverage > 0.99, "{s:?}");
        // Without alignment (start taken as the world's), the rotated map mostly misses.
        let s = score(&w, &map, w.start());
        assert!(s.coverage < 0.5, "{s:?}");
    }

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
