//! The thesis's CSV map format (Bendahmane 2023, the House and Empty benchmark maps).
//!
//! One text line per row of metre cells, row 0 the north edge; comma-separated values `1`
//! (wall) or `0` (free), all rows the same length (the thesis's maps are 24 x 24). Blank lines
//! and spaces around values are ignored. Each value covers 1 m x 1 m; at a finer `resolution`
//! every simulator cell takes the value of the metre cell containing its centre (at 0.1 m, a
//! 10 x 10 block per value).
//!
//! The thesis's start "(1, 1)" is its metre cell (1, 1); the world's start is that cell's centre,
//! (1.5 m, 1.5 m), heading east, so a P3-DX disc (radius 0.25 m) starts clear of the 1 m outer
//! walls.

use std::path::Path;

use papillon::geometry::{Point2, Pose2};
use papillon::grid::GridGeometry;

use super::{World, WorldError};

/// Side of one CSV value \[m\].
pub const CSV_CELL_M: f32 = 1.0;

/// Start pose of worlds loaded from CSV: the centre of metre cell (1, 1).
pub const CSV_START: Pose2 = Pose2 {
    x: 1.5,
    y: 1.5,
    theta: 0.0,
};

/// Reads a CSV map file.
pub fn load(path: &Path, resolution_m: f32) -> Result<World, WorldError> {
    let text = papillon::files::read_limited_to_string(path, papillon::files::MAP_MAX_BYTES)
        .map_err(|e| WorldError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
    parse(&text, &path.display().to_string(), resolution_m)
}

/// Parses CSV map text; `name` is used in errors and as the world's name.
pub fn parse(text: &str, name: &str, resolution_m: f32) -> Result<World, WorldError> {
    let resolution_m = super::check_resolution(resolution_m)?;
    let err = |line: usize, message: String| WorldError::Csv {
        path: name.to_string(),
        line,
        message,
    };
    // Rows north to south, as in the file.
    let mut rows: Vec<Vec<bool>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let mut row = Vec::new();
        for (k, value) in line.split(',').enumerate() {
            match value.trim() {
                "0" => row.push(false),
                "1" => row.push(true),
                other => {
                    return Err(err(
                        line_no,
                        format!(
                            "value {} is '{other}', expected 0 (free) or 1 (wall)",
                            k + 1
                        ),
                    ));
                }
            }
        }
        if let Some(first) = rows.first()
            && first.len() != row.len()
        {
            return Err(err(
                line_no,
                format!(
                    "expected {} comma-separated values like the first row, found {}",
                    first.len(),
                    row.len()
                ),
            ));
        }
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(err(
            1,
            "no rows: expected lines of comma-separated 0/1 values".into(),
        ));
    }
    let (cols_m, rows_m) = (rows[0].len(), rows.len());
    let g = GridGeometry::from_extent(
        cols_m as f32 * CSV_CELL_M,
        rows_m as f32 * CSV_CELL_M,
        resolution_m,
        Point2::default(),
    )?;
    super::check_size(name, &g, super::RESOLUTION_FLAG)?;
    let mut blocked = vec![false; g.cell_count()];
    for (i, b) in blocked.iter_mut().enumerate() {
        let c = g.cell_center(g.cell(i));
        let mc = ((c.x / CSV_CELL_M) as usize).min(cols_m - 1);
        let mr = ((c.y / CSV_CELL_M) as usize).min(rows_m - 1);
        *b = rows[rows_m - 1 - mr][mc];
    }
    Ok(World::from_blocked(name, g, blocked)?.with_start(CSV_START))
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::Cell;

    #[test]
    fn values_become_blocks_with_row_zero_north() {
        let w = parse("1,0,0\n0,0,1\n", "t.csv", 0.5).unwrap();
        let g = *w.geometry();
        assert_eq!((g.width, g.height), (6, 4));
        // File row 0 (north) col 0 is a wall: cells rows 2..4, cols 0..2.
        for (col, row) in [(0, 2), (1, 3), (0, 3), (1, 2)] {
            assert!(w.is_blocked(Cell::new(col, row)));
        }
        // File row 1 (south) col 2: cells rows 0..2, cols 4..6.
        assert!(w.is_blocked(Cell::new(5, 0)));
        assert!(!w.is_blocked(Cell::new(0, 0)));
        assert_eq!(w.blocked_count(), 8);
        assert_eq!(w.start(), CSV_START);
    }

    #[test]
    fn errors_name_the_file_line_and_problem() {
        let e = parse("1,0\n1,0,1\n", "m.csv", 0.1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.csv line 2: expected 2 comma-separated values like the first row, found 3"
        );
        let e = parse("1,0\n\n1,x\n", "m.csv", 0.1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.csv line 3: value 2 is 'x', expected 0 (free) or 1 (wall)"
        );
        let e = parse("\n\n", "m.csv", 0.1).unwrap_err();
        assert!(e.to_string().starts_with("m.csv line 1: no rows"), "{e}");
    }

    #[test]
    fn thesis_house_map_loads_at_ten_centimetres() {
        let Some(path) = crate::shared_data::locate_or_skip(
            "thesis_house_map_loads_at_ten_centimetres",
            "data/thesis-maps/map-house.csv",
        ) else {
            return;
        };
        let w = World::load(&path.to_string_lossy(), 0.1).unwrap();
        assert_eq!((w.geometry().width, w.geometry().height), (240, 240));
        assert_eq!(w.blocked_count(), 155 * 100);
        let f = w.occupied_fraction();
        assert!((f - 0.269).abs() < 0.001, "{f}");
        let t = w.truth();
        assert_eq!(t.free_count(), (576 - 155) * 100);
    }
}
