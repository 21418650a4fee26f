//! Worlds: the true occupancy of the simulated environment.
//!
//! A [`World`] is a bitmap of blocked and free cells laid on a
//! [`GridGeometry`] (map frame: x east, y north, cell (0, 0) at the
//! south-west corner, row 0 south), with a name and the robot's start pose. Worlds come from the
//! built-in designs ([`builtin`]) or from files ([`World::load`]): the thesis's CSV format
//! ([`csv`]), plain PGM/PNG images ([`image`]), Moving AI `.map` grids ([`movingai`]) and ROS
//! map_server YAML + PGM maps ([`rosmap`]). Ground truth for scoring lives in [`truth`].

pub mod builtin;
pub mod clearance;
pub mod csv;
pub mod generated;
pub mod image;
pub mod movingai;
pub mod rosmap;
pub mod truth;

use std::fmt;
use std::path::Path;
use std::sync::OnceLock;

use papillon::geometry::{Point2, Pose2};
use papillon::grid::{Cell, CellClass, GridError, GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::mapfile::MapImage;
use papillon::math;

use self::clearance::Clearance;

pub use truth::Truth;

/// Default start: 1 m east and 1 m north of the map's south-west corner, heading east.
pub const DEFAULT_START: Pose2 = Pose2 {
    x: 1.0,
    y: 1.0,
    theta: 0.0,
};

/// Errors building or loading a world. File errors name the file and what is wrong.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum WorldError {
    /// The spec is neither a built-in world name nor a file name with a known extension.
    UnknownWorld {
        /// What was asked for.
        spec: String,
    },
    /// The file's extension names no format the simulator reads.
    UnsupportedFormat {
        /// The file.
        path: String,
        /// Its extension (without the dot).
        extension: String,
    },
    /// A Moving AI or ROS map file is malformed; the message names the file (and line or
    /// byte where known) and what is wrong.
    File {
        /// The reader's message.
        message: String,
    },
    /// The file could not be read.
    Io {
        /// The file.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// A CSV map file is malformed.
    Csv {
        /// The file.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong on that line.
        message: String,
    },
    /// An image file could not be decoded or has no pixels.
    Image {
        /// The file.
        path: String,
        /// What was wrong.
        message: String,
    },
    /// The cell size is not a positive finite number of metres up to [`MAX_RESOLUTION_M`].
    BadResolution(f32),
    /// The blocked-cell bitmap does not match the geometry.
    SizeMismatch {
        /// Cells the geometry has.
        expected: usize,
        /// Cells the bitmap has.
        found: usize,
    },
    /// The grid geometry is invalid.
    Grid(GridError),
    /// The world would have more than [`MAX_CELLS`] cells.
    TooLarge {
        /// The world (a built-in name or the file).
        name: String,
        /// Columns it would have (saturated).
        width: usize,
        /// Rows it would have (saturated).
        height: usize,
        /// The cell size \[m\].
        resolution_m: f32,
        /// Where the cell size came from: `--resolution` or the file's field.
        resolution_from: &'static str,
    },
}

/// Coarsest cell size of a world \[m\] (the robot is 0.5 m wide).
pub const MAX_RESOLUTION_M: f32 = 1.0;

/// Most cells a world may have (4096 x 4096): a mission at a finer cell size would need more
/// memory and time than a simulation is worth.
pub const MAX_CELLS: usize = 1 << 24;

/// Where the cell size of a world comes from when it is not the file's own.
pub const RESOLUTION_FLAG: &str = "--resolution";

/// Checks that a world of this geometry has at most [`MAX_CELLS`] cells, before any of them
/// is allocated.
pub fn check_size(
    name: &str,
    g: &GridGeometry,
    resolution_from: &'static str,
) -> Result<(), WorldError> {
    match g.width.checked_mul(g.height) {
        Some(n) if n <= MAX_CELLS => Ok(()),
        _ => Err(WorldError::TooLarge {
            name: name.to_string(),
            width: g.width,
            height: g.height,
            resolution_m: g.resolution_m,
            resolution_from,
        }),
    }
}

impl fmt::Display for WorldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WorldError::UnknownWorld { spec } => write!(
                f,
                "unknown world '{spec}': expected one of {}, gen-00..gen-23, gen-KIND-SEED, gen-floor-SEED, gen-floor-SIDEm-SEED (SIDE {}..={} m) or a .csv, .png, .pgm, .map or .yaml file",
                builtin::NAMES.join(", "),
                generated::FLOOR_SIDES_M.start(),
                generated::FLOOR_SIDES_M.end()
            ),
            WorldError::UnsupportedFormat { path, extension } => write!(
                f,
                "{path}: unsupported map format '.{extension}' (expected .csv, .png, .pgm, .map or .yaml)"
            ),
            WorldError::File { message } => f.write_str(message),
            WorldError::Io { path, message } => write!(f, "{path}: cannot read: {message}"),
            WorldError::Csv {
                path,
                line,
                message,
            } => write!(f, "{path} line {line}: {message}"),
            WorldError::Image { path, message } => write!(f, "{path}: {message}"),
            WorldError::BadResolution(r) => write!(
                f,
                "--resolution: expected a cell size of more than 0 and at most {MAX_RESOLUTION_M} m (coarser cells than the robot make no map), got {r}"
            ),
            WorldError::SizeMismatch { expected, found } => write!(
                f,
                "world bitmap has {found} cells but its geometry has {expected}"
            ),
            WorldError::Grid(e) => write!(f, "bad world geometry: {e}"),
            WorldError::TooLarge {
                name,
                width,
                height,
                resolution_m,
                resolution_from,
            } => write!(
                f,
                "{name}: {width} x {height} cells of {resolution_m} m ({resolution_from}) is more than the {MAX_CELLS} cells a world may have; choose a larger cell size"
            ),
        }
    }
}

impl std::error::Error for WorldError {}

impl From<GridError> for WorldError {
    fn from(e: GridError) -> Self {
        WorldError::Grid(e)
    }
}

/// Checks a cell size \[m\].
pub(crate) fn check_resolution(resolution_m: f32) -> Result<f32, WorldError> {
    if resolution_m.is_finite() && resolution_m > 0.0 && resolution_m <= MAX_RESOLUTION_M {
        Ok(resolution_m)
    } else {
        Err(WorldError::BadResolution(resolution_m))
    }
}

/// The true environment: blocked or free per cell, a name and a start pose.
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    name: String,
    geometry: GridGeometry,
    blocked: Vec<bool>,
    start: Pose2,
    /// The blocked cells' [`Clearance`], computed at its first use after a change.
    clearance: ClearanceCache,
}

/// A world's clearance, worked out when first asked for and dropped when a cell changes. It
/// is a function of the bitmap, so it takes no part in comparisons.
#[derive(Clone, Debug, Default)]
struct ClearanceCache(OnceLock<Clearance>);

impl PartialEq for ClearanceCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl World {
    /// An all-free world of the given geometry, starting at [`DEFAULT_START`].
    pub fn new(name: impl Into<String>, geometry: GridGeometry) -> Self {
        Self {
            name: name.into(),
            blocked: vec![false; geometry.cell_count()],
            geometry,
            start: DEFAULT_START,
            clearance: ClearanceCache::default(),
        }
    }

    /// A world from a bitmap in flat-index order (`row · width + col`, row 0 south).
    pub fn from_blocked(
        name: impl Into<String>,
        geometry: GridGeometry,
        blocked: Vec<bool>,
    ) -> Result<Self, WorldError> {
        if blocked.len() != geometry.cell_count() {
            return Err(WorldError::SizeMismatch {
                expected: geometry.cell_count(),
                found: blocked.len(),
            });
        }
        Ok(Self {
            name: name.into(),
            geometry,
            blocked,
            start: DEFAULT_START,
            clearance: ClearanceCache::default(),
        })
    }

    /// A built-in world or a map file, chosen by `spec`:
    /// - `empty`, `house`, `factory`, `lab`: the built-in designs ([`builtin`]);
    /// - `gen-NN`, `gen-KIND-SEED`, `gen-floor-SIDEm-SEED`: generated floor plans
    ///   ([`generated`]);
    /// - `*.csv`: the thesis's CSV format ([`csv`]), upsampled to `resolution_m`;
    /// - `*.png`, `*.pgm`: a plain image, one pixel per cell of `resolution_m` ([`image`]);
    /// - `*.map`: a Moving AI grid, one character per cell of `resolution_m` ([`movingai`]);
    /// - `*.yaml`, `*.yml`: a ROS map_server map, at its own resolution and origin
    ///   ([`rosmap`]; `resolution_m` is not used).
    pub fn load(spec: &str, resolution_m: f32) -> Result<Self, WorldError> {
        let resolution_m = check_resolution(resolution_m)?;
        if let Some(world) = builtin::by_name(spec, resolution_m) {
            return world;
        }
        if let Some(world) = generated::by_name(spec, resolution_m) {
            return world;
        }
        let path = Path::new(spec);
        let Some(extension) = path.extension().and_then(|e| e.to_str()) else {
            return Err(WorldError::UnknownWorld {
                spec: spec.to_string(),
            });
        };
        match extension.to_ascii_lowercase().as_str() {
            "csv" => csv::load(path, resolution_m),
            "png" | "pgm" => image::load(path, resolution_m),
            "map" => movingai::load(path, resolution_m),
            "yaml" | "yml" => rosmap::load(path),
            other => Err(WorldError::UnsupportedFormat {
                path: spec.to_string(),
                extension: other.to_string(),
            }),
        }
    }

    /// The world's name (a built-in name or the file it came from).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Size and placement of the cells.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Where the robot starts \[m, rad\].
    pub fn start(&self) -> Pose2 {
        self.start
    }

    /// Moves the start pose.
    pub fn set_start(&mut self, start: Pose2) {
        self.start = start;
    }

    /// `None` when the start lies inside the world's grid; else why not, as
    /// `(x, y) is outside NAME, which spans X0..X1 m east and Y0..Y1 m north`.
    pub fn start_outside(&self) -> Option<String> {
        let g = self.geometry;
        let (x0, y0) = (g.origin.x, g.origin.y);
        let (x1, y1) = (x0 + g.width_m(), y0 + g.height_m());
        let p = self.start;
        let inside = p.x >= x0 && p.x < x1 && p.y >= y0 && p.y < y1;
        (!inside).then(|| {
            format!(
                "({}, {}) is outside {}, which spans {x0}..{x1} m east and {y0}..{y1} m north",
                p.x, p.y, self.name
            )
        })
    }

    /// The start pose with the start moved.
    pub fn with_start(mut self, start: Pose2) -> Self {
        self.start = start;
        self
    }

    /// The cell under the start position, if inside the grid.
    pub fn start_cell(&self) -> Option<Cell> {
        self.geometry.cell_at(self.start.position())
    }

    /// Blocked flags in flat-index order.
    pub fn blocked(&self) -> &[bool] {
        &self.blocked
    }

    /// Whether a cell is blocked; cells outside the grid count as blocked.
    #[inline]
    pub fn is_blocked(&self, cell: Cell) -> bool {
        match self.geometry.index(cell) {
            Some(i) => self.blocked[i],
            None => true,
        }
    }

    /// Whether the cell at a flat index is blocked (panics past the cell count, a caller bug).
    #[inline]
    pub fn is_blocked_index(&self, index: usize) -> bool {
        self.blocked[index]
    }

    /// Whether the map-frame point lies in a blocked cell or outside the grid.
    pub fn is_blocked_at(&self, p: Point2) -> bool {
        self.is_blocked(self.geometry.cell_at_unchecked(p))
    }

    /// Blocks or frees one cell; cells outside the grid are ignored.
    pub fn set_blocked(&mut self, cell: Cell, blocked: bool) {
        if let Some(i) = self.geometry.index(cell)
            && self.blocked[i] != blocked
        {
            self.blocked[i] = blocked;
            self.clearance.0.take();
        }
    }

    /// Per cell, the chessboard distance \[cells\] to the nearest blocked cell or the grid's
    /// edge ([`Clearance`]), worked out at the first call after a change.
    pub fn clearance(&self) -> &Clearance {
        self.clearance
            .0
            .get_or_init(|| Clearance::new(self.geometry.width, &self.blocked))
    }

    /// Blocks or frees every cell whose centre lies in `[x0, x1) x [y0, y1)` \[m\].
    pub fn fill_rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, blocked: bool) {
        for cell in self.cells_in_rect(x0, y0, x1, y1) {
            self.set_blocked(cell, blocked);
        }
    }

    /// The cells whose centres lie in `[x0, x1) x [y0, y1)` \[m\], clipped to the grid.
    pub fn cells_in_rect(&self, x0: f32, y0: f32, x1: f32, y1: f32) -> Vec<Cell> {
        let g = &self.geometry;
        let r = g.resolution_m;
        // Cell c's centre is origin + (c + 0.5) r; it lies in [a, b) when c >= (a - o)/r - 0.5
        // and c < (b - o)/r - 0.5.
        let lo = |a: f32, o: f32| ((a - o) / r - 0.5 - 1e-4).ceil().max(0.0) as i64;
        let hi = |b: f32, o: f32, n: usize| {
            (((b - o) / r - 0.5 - 1e-4).ceil().max(0.0) as i64).min(n as i64)
        };
        let (c0, c1) = (lo(x0, g.origin.x), hi(x1, g.origin.x, g.width));
        let (r0, r1) = (lo(y0, g.origin.y), hi(y1, g.origin.y, g.height));
        let mut cells = Vec::new();
        for row in r0..r1 {
            for col in c0..c1 {
                cells.push(Cell::new(col as i32, row as i32));
            }
        }
        cells
    }

    /// The world as a perfect robot map would hold it: blocked cells Occupied, the rest Free.
    pub fn perfect_map(&self) -> MapImage {
        let cells = self
            .blocked
            .iter()
            .map(|&b| {
                if b {
                    CellClass::Occupied
                } else {
                    CellClass::Free
                }
            })
            .collect();
        MapImage {
            geometry: self.geometry,
            cells,
        }
    }

    /// Number of blocked cells.
    pub fn blocked_count(&self) -> usize {
        self.blocked.iter().filter(|&&b| b).count()
    }

    /// Fraction of the area that is blocked (0..1).
    pub fn occupied_fraction(&self) -> f32 {
        self.blocked_count() as f32 / self.blocked.len() as f32
    }

    /// The ground truth for scoring: the observable set from the start cell ([`truth`]).
    pub fn truth(&self) -> Truth {
        Truth::new(self)
    }

    /// Observable-set membership per cell, flat-index order ([`truth`]).
    pub fn truth_mask(&self) -> Vec<bool> {
        self.truth().mask().to_vec()
    }

    /// The world as a fully known occupancy grid (blocked cells Occupied, free cells Free, at
    /// the default bounds' certainty), built on the heap: for rendering, planning tests and
    /// scoring. Errs if the world has more cells than `N`.
    pub fn to_occupancy_grid<const N: usize>(&self) -> Result<Box<OccupancyGrid<N>>, GridError> {
        let mut grid = OccupancyGrid::<N>::new_boxed(self.geometry, LogOddsBounds::default())?;
        for (i, &b) in self.blocked.iter().enumerate() {
            let class = if b {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            grid.set_class(i, class, &mut ());
        }
        Ok(grid)
    }

    /// Whether a robot disc of `radius_m` \[m\] at the start position touches nothing blocked.
    pub fn start_is_clear(&self, radius_m: f32) -> bool {
        !self.disc_hits_blocked(self.start.position(), radius_m)
    }

    /// Whether a disc of `radius_m` centred at `p` overlaps a blocked cell (or leaves the grid).
    pub fn disc_hits_blocked(&self, p: Point2, radius_m: f32) -> bool {
        self.wall_penetration(p, radius_m) > 0.0
    }

    /// How deep a disc at `p` of `radius_m` reaches into the blocked cells \[m\] (0 when
    /// clear): the largest `radius_m - d` over the blocked cells, `d` being the distance from
    /// `p` to the cell's square. Cells outside the grid count as blocked.
    pub fn wall_penetration(&self, p: Point2, radius_m: f32) -> f32 {
        let g = self.geometry();
        let r = g.resolution_m;
        let c0 = math::floor((p.x - radius_m - g.origin.x) / r) as i32;
        let c1 = math::floor((p.x + radius_m - g.origin.x) / r) as i32;
        let r0 = math::floor((p.y - radius_m - g.origin.y) / r) as i32;
        let r1 = math::floor((p.y + radius_m - g.origin.y) / r) as i32;
        // Open space: when the cell holding `p` is farther from every blocked cell (and the
        // grid's edge) than from any cell of the box, no cell of the box is blocked and the
        // loop below would find nothing.
        if p.x.is_finite() && p.y.is_finite() && radius_m >= 0.0 {
            let (col, row) = (
                math::floor((p.x - g.origin.x) / r) as i32,
                math::floor((p.y - g.origin.y) / r) as i32,
            );
            if let Some(i) = g.index(Cell::new(col, row)) {
                let (col, row) = (i64::from(col), i64::from(row));
                let reach = (col - i64::from(c0))
                    .max(i64::from(c1) - col)
                    .max(row - i64::from(r0))
                    .max(i64::from(r1) - row);
                if i64::from(self.clearance().at_index(i)) > reach {
                    return 0.0;
                }
            }
        }
        let mut depth = 0.0f32;
        for row in r0..=r1 {
            let y0 = g.origin.y + row as f32 * r;
            let dy = (y0 - p.y).max(p.y - (y0 + r)).max(0.0);
            for col in c0..=c1 {
                if !self.is_blocked(Cell::new(col, row)) {
                    continue;
                }
                let x0 = g.origin.x + col as f32 * r;
                let dx = (x0 - p.x).max(p.x - (x0 + r)).max(0.0);
                let d = (dx * dx + dy * dy).sqrt();
                depth = depth.max(radius_m - d);
            }
        }
        depth
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`World::wall_penetration`] without its open-space shortcut: every cell of the box.
    fn wall_penetration_by_cells(w: &World, p: Point2, radius_m: f32) -> f32 {
        let g = w.geometry();
        let r = g.resolution_m;
        let c0 = ((p.x - radius_m - g.origin.x) / r).floor() as i32;
        let c1 = ((p.x + radius_m - g.origin.x) / r).floor() as i32;
        let r0 = ((p.y - radius_m - g.origin.y) / r).floor() as i32;
        let r1 = ((p.y + radius_m - g.origin.y) / r).floor() as i32;
        let mut depth = 0.0f32;
        for row in r0..=r1 {
            let y0 = g.origin.y + row as f32 * r;
            let dy = (y0 - p.y).max(p.y - (y0 + r)).max(0.0);
            for col in c0..=c1 {
                if w.is_blocked(Cell::new(col, row)) {
                    let x0 = g.origin.x + col as f32 * r;
                    let dx = (x0 - p.x).max(p.x - (x0 + r)).max(0.0);
                    depth = depth.max(radius_m - (dx * dx + dy * dy).sqrt());
                }
            }
        }
        depth
    }

    #[test]
    fn wall_penetration_is_the_cell_by_cell_answer_in_open_space_too() {
        let mut rng = papillon::random::seeded(3);
        let g = GridGeometry::from_extent(10.0, 8.0, 0.1, Point2::default()).unwrap();
        let mut w = World::new("blocks", g);
        let mut touching = 0;
        for round in 0..3 {
            // More blocks each round: the clearance must follow the changes.
            for _ in 0..4 {
                let x = papillon::random::range_f32(&mut rng, 0.0, 10.0);
                let y = papillon::random::range_f32(&mut rng, 0.0, 8.0);
                w.fill_rect(x, y, x + 0.4, y + 0.2, true);
            }
            for _ in 0..5_000 {
                let p = Point2::new(
                    papillon::random::range_f32(&mut rng, -0.5, 10.5),
                    papillon::random::range_f32(&mut rng, -0.5, 8.5),
                );
                let radius_m = papillon::random::range_f32(&mut rng, 0.0, 0.6);
                let want = wall_penetration_by_cells(&w, p, radius_m);
                assert_eq!(
                    w.wall_penetration(p, radius_m).to_bits(),
                    want.to_bits(),
                    "round {round}: {p:?}, radius {radius_m}"
                );
                touching += (want > 0.0) as usize;
            }
        }
        assert!(touching > 500 && touching < 14_000, "{touching} touching");
    }

    #[test]
    fn rectangles_fill_cells_by_centre() {
        let g = GridGeometry::from_extent(2.0, 1.0, 0.1, Point2::default()).unwrap();
        let mut w = World::new("t", g);
        w.fill_rect(0.0, 0.0, 1.0, 0.5, true);
        assert_eq!(w.blocked_count(), 50);
        assert!(w.is_blocked(Cell::new(9, 4)));
        assert!(!w.is_blocked(Cell::new(10, 4)));
        assert!(!w.is_blocked(Cell::new(9, 5)));
        assert!(w.is_blocked(Cell::new(-1, 0)), "outside counts as blocked");
    }

    #[test]
    fn load_names_the_problem() {
        let e = World::load("nowhere", 0.1).unwrap_err();
        assert!(e.to_string().contains("unknown world 'nowhere'"), "{e}");
        let e = World::load("gen-floor-300m-1", 0.1).unwrap_err();
        assert!(
            e.to_string().contains("unknown world 'gen-floor-300m-1'")
                && e.to_string()
                    .contains("gen-floor-SIDEm-SEED (SIDE 20..=200 m)"),
            "{e}"
        );
        let e = World::load("maps/x.map", 0.1).unwrap_err();
        assert!(e.to_string().starts_with("maps/x.map: cannot read"), "{e}");
        let e = World::load("a.yaml", 0.1).unwrap_err();
        assert!(e.to_string().starts_with("a.yaml: "), "{e}");
        let e = World::load("a.bmp", 0.1).unwrap_err();
        assert!(e.to_string().contains("'.bmp'"), "{e}");
        let e = World::load("house", 0.0).unwrap_err();
        assert_eq!(e, WorldError::BadResolution(0.0));
        let e = World::load("/no/such/file.csv", 0.1).unwrap_err();
        assert!(
            e.to_string().starts_with("/no/such/file.csv: cannot read"),
            "{e}"
        );
    }

    #[test]
    fn the_true_grid_matches_the_bitmap() {
        let w = builtin::lab(0.1).unwrap();
        let g = w.to_occupancy_grid::<6400>().unwrap();
        assert_eq!(g.counts().occupied, w.blocked_count());
        assert_eq!(g.counts().known(), 6400);
        let inside = w.geometry().index(Cell::new(40, 20)).unwrap();
        assert!(w.is_blocked_index(inside));
        assert_eq!(g.class(inside), CellClass::Occupied);
        assert!(matches!(
            w.to_occupancy_grid::<100>().unwrap_err(),
            GridError::CapacityExceeded { needed: 6400, .. }
        ));
        assert_eq!(w.truth().coverage(&g), 1.0);
    }

    #[test]
    fn bitmap_must_match_geometry() {
        let g = GridGeometry::new(3, 3, 0.1, Point2::default()).unwrap();
        let e = World::from_blocked("x", g, vec![false; 8]).unwrap_err();
        assert_eq!(
            e,
            WorldError::SizeMismatch {
                expected: 9,
                found: 8
            }
        );
    }
}
