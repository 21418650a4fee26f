//! Moving AI grid benchmark files: `.map` grids and `.scen` problem lists; [`solve`] runs
//! Papillon's A* on them.
//!
//! Format: Sturtevant, "Benchmarks for Grid-Based Pathfinding", IEEE Trans. Computational
//! Intelligence and AI in Games 4(2), 2012 (<https://movingai.com/benchmarks/formats.html>).
//!
//! - `.map`: four header lines `type octile`, `height H`, `width W`, `map`, then H rows of W
//!   characters. Passable: `.` `G` `S`; blocked: `@` `O` `T` `W`. Text after the rows (some
//!   files carry a citation footer) is ignored.
//! - `.scen`: `version 1` (or `version 1.0`), then one problem per line, tab-separated: bucket,
//!   map file, map width, map height, start x, start y, goal x, goal y, optimal length. A blank
//!   line ends the problems; what follows (a citation footer) is ignored.
//!
//! Moving AI coordinates are `(x, y)` = (column, row) with `(0, 0)` the **top-left** (north-west)
//! corner and y growing south. Papillon's grid has row 0 at the south edge; use
//! [`MovingAiMap::to_cell`] to convert. Flipping rows changes no path length and no
//! corner-cutting rule, so optimal lengths carry over unchanged.

pub mod solve;

use std::fmt;
use std::path::{Path, PathBuf};

use papillon::grid::Cell;

/// What went wrong reading a Moving AI file.
#[derive(Debug)]
#[non_exhaustive]
pub enum MovingAiError {
    /// The file could not be read.
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A line does not follow the format.
    Malformed {
        /// File.
        path: PathBuf,
        /// Line number, from 1.
        line: usize,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
}

impl fmt::Display for MovingAiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MovingAiError::Io { path, source } => {
                write!(f, "{}: cannot read: {source}", path.display())
            }
            MovingAiError::Malformed {
                path,
                line,
                expected,
                found,
            } => write!(
                f,
                "{}:{line}: expected {expected}, found {found:?}",
                path.display()
            ),
        }
    }
}

impl std::error::Error for MovingAiError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            MovingAiError::Io { source, .. } => Some(source),
            MovingAiError::Malformed { .. } => None,
        }
    }
}

fn malformed(path: &Path, line: usize, expected: impl Into<String>, found: &str) -> MovingAiError {
    let mut found = found.to_string();
    if found.len() > 60 {
        let mut cut = 60;
        while !found.is_char_boundary(cut) {
            cut -= 1;
        }
        found.truncate(cut);
        found.push('…');
    }
    MovingAiError::Malformed {
        path: path.to_path_buf(),
        line,
        expected: expected.into(),
        found,
    }
}

fn read(path: &Path) -> Result<String, MovingAiError> {
    papillon::files::read_limited_to_string(path, papillon::files::MAP_MAX_BYTES).map_err(
        |source| MovingAiError::Io {
            path: path.to_path_buf(),
            source,
        },
    )
}

/// A Moving AI grid: which cells are blocked, in the file's order (row 0 = north, the first
/// map line; index `y * width + x`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MovingAiMap {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Blocked flags, row 0 = north (file order), index `y * width + x`.
    pub blocked: Vec<bool>,
}

impl MovingAiMap {
    /// Reads a `.map` file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, MovingAiError> {
        let path = path.as_ref();
        Self::parse(&read(path)?, path)
    }

    /// Parses `.map` text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, MovingAiError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
        let mut next = |expected: &str| {
            lines
                .next()
                .ok_or_else(|| malformed(path, text.lines().count() + 1, expected, "end of file"))
        };
        let (n, l) = next("`type octile`")?;
        if l.trim() != "type octile" {
            return Err(malformed(path, n, "`type octile`", l));
        }
        let mut dims = [0usize; 2];
        for (k, key) in ["height", "width"].into_iter().enumerate() {
            let expected = format!("`{key} N` with N a positive integer");
            let (n, l) = next(&expected)?;
            let mut parts = l.split_whitespace();
            let value = match (parts.next(), parts.next(), parts.next()) {
                (Some(k2), Some(v), None) if k2 == key => v.parse::<usize>().ok(),
                _ => None,
            };
            match value {
                Some(v) if v > 0 => dims[k] = v,
                _ => return Err(malformed(path, n, expected, l)),
            }
        }
        let [height, width] = dims;
        let (n, l) = next("`map`")?;
        if l.trim() != "map" {
            return Err(malformed(path, n, "`map`", l));
        }
        // The header may promise more cells than the text holds: the rows are counted below.
        let mut blocked = Vec::with_capacity(width.saturating_mul(height).min(text.len()));
        for y in 0..height {
            let expected = format!("map row {y} of {width} characters from `.GS@OTW`");
            let (n, l) = next(&expected)?;
            if l.chars().count() != width {
                return Err(malformed(path, n, expected, l));
            }
            for ch in l.chars() {
                blocked.push(match ch {
                    '.' | 'G' | 'S' => false,
                    '@' | 'O' | 'T' | 'W' => true,
                    _ => return Err(malformed(path, n, expected, l)),
                });
            }
        }
        // Anything after the rows (the Moving AI files carry a citation footer) is ignored.
        Ok(Self {
            width,
            height,
            blocked,
        })
    }

    /// Whether Moving AI cell `(x, y)` (y from the top) is blocked; outside counts as blocked.
    pub fn is_blocked(&self, x: usize, y: usize) -> bool {
        x >= self.width || y >= self.height || self.blocked[y * self.width + x]
    }

    /// Papillon's cell (row 0 south) for Moving AI `(x, y)` (row 0 north).
    pub fn to_cell(&self, x: usize, y: usize) -> Cell {
        Cell::new(x as i32, self.height as i32 - 1 - y as i32)
    }

    /// Whether Papillon's cell (row 0 south) is blocked; outside counts as blocked.
    pub fn is_cell_blocked(&self, cell: Cell) -> bool {
        if cell.col < 0 || cell.row < 0 || cell.row as usize >= self.height {
            return true;
        }
        self.is_blocked(cell.col as usize, self.height - 1 - cell.row as usize)
    }
}

/// One benchmark problem, in Moving AI coordinates (y from the top).
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Line in the `.scen` file, from 1.
    pub line: usize,
    /// Difficulty bucket.
    pub bucket: u32,
    /// Map file named by the problem.
    pub map: String,
    /// Start column.
    pub start_x: usize,
    /// Start row (from the top).
    pub start_y: usize,
    /// Goal column.
    pub goal_x: usize,
    /// Goal row (from the top).
    pub goal_y: usize,
    /// Published optimal length \[cells\].
    pub optimal: f64,
}

/// A `.scen` file's problems.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Problems in file order.
    pub problems: Vec<Problem>,
}

impl Scenario {
    /// Reads a `.scen` file and checks every problem against `map` (size, coordinates inside,
    /// start and goal passable).
    pub fn load(path: impl AsRef<Path>, map: &MovingAiMap) -> Result<Self, MovingAiError> {
        let path = path.as_ref();
        Self::parse(&read(path)?, path, map)
    }

    /// Parses `.scen` text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path, map: &MovingAiMap) -> Result<Self, MovingAiError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
        match lines.next() {
            Some((_, l)) if matches!(l.trim(), "version 1" | "version 1.0") => {}
            Some((n, l)) => return Err(malformed(path, n, "`version 1`", l)),
            None => return Err(malformed(path, 1, "`version 1`", "end of file")),
        }
        let mut problems = Vec::new();
        for (n, l) in lines {
            if l.trim().is_empty() {
                // A blank line ends the problems (the Moving AI files carry a citation footer).
                break;
            }
            let fields: Vec<&str> = l.split('\t').collect();
            let expected = "9 tab-separated fields: bucket, map, width, height, start x, start y, \
                            goal x, goal y, optimal length";
            if fields.len() != 9 {
                return Err(malformed(path, n, expected, l));
            }
            let int = |k: usize, what: &str| {
                fields[k].trim().parse::<usize>().map_err(|_| {
                    malformed(
                        path,
                        n,
                        format!("{what} as a non-negative integer"),
                        fields[k],
                    )
                })
            };
            let bucket = int(0, "bucket")? as u32;
            let (w, h) = (int(2, "map width")?, int(3, "map height")?);
            if (w, h) != (map.width, map.height) {
                return Err(malformed(
                    path,
                    n,
                    format!("map size {} x {}", map.width, map.height),
                    &format!("{w} x {h}"),
                ));
            }
            let (sx, sy) = (int(4, "start x")?, int(5, "start y")?);
            let (gx, gy) = (int(6, "goal x")?, int(7, "goal y")?);
            for (what, x, y) in [("start", sx, sy), ("goal", gx, gy)] {
                if x >= w || y >= h {
                    return Err(malformed(
                        path,
                        n,
                        format!("{what} inside the {w} x {h} map"),
                        &format!("({x}, {y})"),
                    ));
                }
                if map.is_blocked(x, y) {
                    return Err(malformed(
                        path,
                        n,
                        format!("{what} on a passable cell"),
                        &format!("blocked cell ({x}, {y})"),
                    ));
                }
            }
            let optimal = fields[8]
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0);
            let Some(optimal) = optimal else {
                return Err(malformed(
                    path,
                    n,
                    "optimal length as a non-negative number",
                    fields[8],
                ));
            };
            problems.push(Problem {
                line: n,
                bucket,
                map: fields[1].to_string(),
                start_x: sx,
                start_y: sy,
                goal_x: gx,
                goal_y: gy,
                optimal,
            });
        }
        Ok(Self { problems })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> MovingAiMap {
        MovingAiMap::parse(
            "type octile\nheight 2\nwidth 3\nmap\n.@T\nGS.\n",
            Path::new("t.map"),
        )
        .unwrap()
    }

    #[test]
    fn rows_are_flipped_to_south_up() {
        let m = map();
        assert_eq!((m.width, m.height), (3, 2));
        assert!(m.is_blocked(1, 0) && m.is_blocked(2, 0) && !m.is_blocked(0, 1));
        assert_eq!(m.to_cell(1, 0), Cell::new(1, 1));
        assert!(m.is_cell_blocked(Cell::new(1, 1)));
        assert!(!m.is_cell_blocked(Cell::new(1, 0)));
    }

    #[test]
    fn malformed_maps_name_file_and_line() {
        let e = MovingAiMap::parse(
            "type octile\nheight 2\nwidth 3\nmap\n.@T\nGX.\n",
            Path::new("a.map"),
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("a.map:6: expected map row 1"),
            "{e}"
        );
        let e = MovingAiMap::parse("type octile\nheight two\n", Path::new("a.map")).unwrap_err();
        assert!(
            e.to_string().starts_with("a.map:2: expected `height N`"),
            "{e}"
        );
        let e = MovingAiMap::parse(
            "type octile\nheight 2\nwidth 3\nmap\n.@T\n",
            Path::new("a.map"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("found \"end of file\""), "{e}");
    }

    #[test]
    fn scenarios_are_checked_against_the_map() {
        let m = map();
        let ok = Scenario::parse(
            "version 1\n0\tt.map\t3\t2\t0\t1\t2\t1\t2.0\n",
            Path::new("s"),
            &m,
        )
        .unwrap();
        assert_eq!(ok.problems[0].goal_x, 2);
        assert_eq!(ok.problems[0].line, 2);
        let e = Scenario::parse(
            "version 1\n0\tt.map\t3\t2\t1\t0\t2\t1\t2.0\n",
            Path::new("s"),
            &m,
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("s:2: expected start on a passable cell"),
            "{e}"
        );
        let e = Scenario::parse(
            "version 1\n0\tt.map\t4\t2\t0\t1\t2\t1\t2.0\n",
            Path::new("s"),
            &m,
        )
        .unwrap_err();
        assert!(e.to_string().contains("map size 3 x 2"), "{e}");
        let e = Scenario::parse("version 2\n", Path::new("s"), &m).unwrap_err();
        assert!(
            e.to_string().starts_with("s:1: expected `version 1`"),
            "{e}"
        );
    }
}
