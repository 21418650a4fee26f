//! ROS `map_server` maps (a YAML description plus a PGM image) as worlds.
//!
//! The files are read by the core's reader, [`papillon::mapfile::read_map`], which honours the
//! YAML's `resolution`, `origin`, `negate`, `occupied_thresh` and `free_thresh` (ROS wiki,
//! `map_server`): a pixel of value `v` out of `maxval` has occupancy `p = (maxval - v) / maxval`
//! (`v / maxval` when negated); Occupied above `occupied_thresh`, Free below `free_thresh`,
//! Unknown between. For a world, Occupied **and Unknown** cells are blocked: a map's unknown
//! area is where nothing is known to be free, so the robot may not drive or see through it.
//!
//! The world's geometry takes the map's resolution and origin (the `--resolution` given to
//! [`super::World::load`] is not used); the start is 1 m east and 1 m north of the map's
//! south-west corner, i.e. `origin + (1 m, 1 m)`, heading east.

use std::path::Path;

use papillon::geometry::Pose2;
use papillon::grid::CellClass;
use papillon::mapfile;

use super::{World, WorldError};

/// Reads a ROS map (YAML and the PGM it names).
pub fn load(path: &Path) -> Result<World, WorldError> {
    let map = mapfile::read_map(path).map_err(|e| WorldError::File {
        message: e.to_string(),
    })?;
    let g = map.geometry;
    super::check_size(
        &path.display().to_string(),
        &g,
        "the image's width and height",
    )?;
    let blocked = map.cells.iter().map(|&c| c != CellClass::Free).collect();
    let world = World::from_blocked(path.display().to_string(), g, blocked)?;
    Ok(world.with_start(Pose2::new(g.origin.x + 1.0, g.origin.y + 1.0, 0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::Cell;

    fn write(dir: &Path, yaml: &str, pgm: &[u8]) -> std::path::PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("m.pgm"), pgm).unwrap();
        let y = dir.join("m.yaml");
        std::fs::write(&y, yaml).unwrap();
        y
    }

    fn tmp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("papillon-rosmap-{}-{name}", std::process::id()))
    }

    const YAML: &str = "image: m.pgm\nresolution: 0.5\norigin: [-2.0, 3.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

    #[test]
    fn thresholds_origin_and_rows() {
        // 3 x 2, top row (north): 0 (occupied) 254 (free) 205 (unknown); bottom: 254 100 220.
        // p(100) = 0.61: between the thresholds, unknown; p(220) = 0.137: free.
        let dir = tmp("a");
        let y = write(&dir, YAML, b"P2\n3 2\n255\n0 254 205\n254 100 220\n");
        let w = load(&y).unwrap();
        let g = w.geometry();
        assert_eq!((g.width, g.height, g.resolution_m), (3, 2, 0.5));
        assert_eq!((g.origin.x, g.origin.y), (-2.0, 3.0));
        assert!(w.is_blocked(Cell::new(0, 1)));
        assert!(!w.is_blocked(Cell::new(1, 1)));
        assert!(w.is_blocked(Cell::new(2, 1)), "unknown is blocked");
        assert!(!w.is_blocked(Cell::new(0, 0)));
        assert!(w.is_blocked(Cell::new(1, 0)));
        assert!(!w.is_blocked(Cell::new(2, 0)));
        assert_eq!(
            w.start().position(),
            papillon::geometry::Point2::new(-1.0, 4.0)
        );
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn negate_inverts_the_pixels() {
        let dir = tmp("b");
        let yaml = YAML.replace("negate: 0", "negate: 1");
        let y = write(&dir, &yaml, b"P2\n2 1\n255\n0 255\n");
        let w = load(&y).unwrap();
        assert!(!w.is_blocked(Cell::new(0, 0)));
        assert!(w.is_blocked(Cell::new(1, 0)));
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn errors_name_the_file_and_the_problem() {
        let dir = tmp("c");
        let y = write(
            &dir,
            "image: m.pgm\nresolution: fast\n",
            b"P2\n1 1\n255\n0\n",
        );
        let e = load(&y).unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("resolution"), "{e}");
        let y = write(&dir, YAML, b"P7\n");
        let e = load(&y).unwrap_err().to_string();
        assert!(e.contains("m.pgm") && e.contains("not a PGM"), "{e}");
        let y = write(&dir, YAML, b"P2\n3 3\n255\n0 0 0\n");
        let e = load(&y).unwrap_err().to_string();
        assert!(e.contains("m.pgm") && e.contains("truncated"), "{e}");
        let e = load(&dir.join("none.yaml")).unwrap_err().to_string();
        assert!(e.contains("none.yaml"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
