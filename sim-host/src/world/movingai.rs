//! Moving AI `.map` grids as worlds.
//!
//! The file is parsed by [`crate::movingai::MovingAiMap`] (Sturtevant 2012): `@ O T W` are
//! blocked, `. G S` free. Each character is one cell of the `--resolution` given to
//! [`super::World::load`]; the first map line is the north edge (rows are flipped into the
//! map frame, row 0 south). The origin is (0, 0) and the start the default (1 m, 1 m).

use std::path::Path;

use papillon::geometry::Point2;
use papillon::grid::{Cell, GridGeometry};

use super::{World, WorldError};
use crate::movingai::MovingAiMap;

/// Reads a Moving AI `.map` file, one character per cell of `resolution_m`.
pub fn load(path: &Path, resolution_m: f32) -> Result<World, WorldError> {
    let resolution_m = super::check_resolution(resolution_m)?;
    let map = MovingAiMap::load(path).map_err(|e| WorldError::File {
        message: e.to_string(),
    })?;
    from_map(&map, &path.display().to_string(), resolution_m)
}

/// A world from a parsed Moving AI map.
pub fn from_map(map: &MovingAiMap, name: &str, resolution_m: f32) -> Result<World, WorldError> {
    let g = GridGeometry::new(map.width, map.height, resolution_m, Point2::default())?;
    super::check_size(name, &g, "the map's width and height")?;
    let mut blocked = vec![false; g.cell_count()];
    for row in 0..map.height {
        for col in 0..map.width {
            blocked[row * map.width + col] = map.is_cell_blocked(Cell::new(col as i32, row as i32));
        }
    }
    World::from_blocked(name, g, blocked)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn characters_become_cells_with_north_on_top() {
        let text = "type octile\nheight 2\nwidth 3\nmap\n@.T\n..G\n";
        let m = MovingAiMap::parse(text, Path::new("t.map")).unwrap();
        let w = from_map(&m, "t.map", 0.2).unwrap();
        let g = w.geometry();
        assert_eq!((g.width, g.height, g.resolution_m), (3, 2, 0.2));
        assert!(w.is_blocked(Cell::new(0, 1)));
        assert!(w.is_blocked(Cell::new(2, 1)));
        assert!(!w.is_blocked(Cell::new(1, 1)));
        assert_eq!(w.blocked_count(), 2);
    }

    #[test]
    fn errors_name_the_file_and_the_line() {
        let p = std::env::temp_dir().join(format!("papillon-mai-{}.map", std::process::id()));
        std::fs::write(&p, "type octile\nheight 2\nwidth 3\nmap\n@.T\n.x.\n").unwrap();
        let e = load(&p, 0.1).unwrap_err().to_string();
        assert!(e.contains(&format!("{}:6", p.display())), "{e}");
        std::fs::remove_file(&p).unwrap();
        let e = load(Path::new("/no/such.map"), 0.1)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/no/such.map: cannot read"), "{e}");
    }

    #[test]
    fn the_benchmark_arena_loads() {
        let Some(p) = crate::shared_data::locate_or_skip(
            "the_benchmark_arena_loads",
            "data/movingai/arena.map",
        ) else {
            return;
        };
        let w = load(&p, 0.1).unwrap();
        assert_eq!((w.geometry().width, w.geometry().height), (49, 49));
    }
}
