//! The occupancy grid: log-odds cells on a fixed-capacity array.
//!
//! Cells hold log-odds occupancy `l = ln(p / (1 - p))`, with the prior `p = 0.5` (`l = 0`).
//! Evidence is added by Bayes' rule in log-odds form (`l <- l + Δ`), saturating at configurable
//! bounds so a cell can still change its mind (Thrun, Burgard & Fox, *Probabilistic Robotics*,
//! 2005, ch. 9). Classification follows the thesis (Bendahmane 2023): Occupied if `l > 0`, Free
//! if `l < 0`, Unknown if exactly 0.
//!
//! Geometry: cell `(col, row)` covers `[origin.x + col·res, origin.x + (col+1)·res)` east and
//! `[origin.y + row·res, origin.y + (row+1)·res)` north; row 0 is the south edge. The flat index
//! is `row · width + col`.
//!
//! The capacity `N` \[cells\] is a compile-time constant; width and height are chosen at run time
//! and must fit it. Counters of free, occupied and known cells are kept up to date on every
//! change, so no query ever scans the grid.

use crate::geometry::Point2;
use crate::math;

/// Cells in the grid the onboard binary uses: a 30 m x 50 m map at 10 cm (300 x 500 cells)
/// fits, and so does a 24 m x 24 m map (240 x 240).
pub const DEFAULT_CELL_CAPACITY: usize = 150_000;

/// Default cell size \[m\].
pub const DEFAULT_RESOLUTION_M: f32 = 0.10;

/// A grid cell address: column (east) and row (north), row 0 at the south edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, bytemuck::Zeroable)]
pub struct Cell {
    /// Column \[cells\], growing east.
    pub col: i32,
    /// Row \[cells\], growing north.
    pub row: i32,
}

impl Cell {
    /// The cell at `(col, row)`.
    pub const fn new(col: i32, row: i32) -> Self {
        Self { col, row }
    }
}

/// What a cell is believed to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellClass {
    /// Log-odds below 0.
    Free,
    /// Log-odds exactly 0: never observed, or evidence cancelled out.
    Unknown,
    /// Log-odds above 0.
    Occupied,
}

impl CellClass {
    /// The thesis's rule: Occupied if `l > 0`, Free if `l < 0`, Unknown if `l == 0`.
    #[inline]
    pub fn of_log_odds(l: f32) -> Self {
        if l > 0.0 {
            CellClass::Occupied
        } else if l < 0.0 {
            CellClass::Free
        } else {
            CellClass::Unknown
        }
    }

    /// Free or Occupied.
    #[inline]
    pub fn is_known(self) -> bool {
        self != CellClass::Unknown
    }
}

/// Errors from building or addressing a grid.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum GridError {
    /// The requested size needs more cells than the grid's capacity.
    CapacityExceeded {
        /// Cells the geometry needs.
        needed: usize,
        /// Cells the grid type holds.
        capacity: usize,
    },
    /// Width or height is zero.
    EmptyGrid,
    /// The resolution is not a positive finite number \[m\].
    BadResolution(f32),
    /// The origin is not finite.
    BadOrigin,
    /// Log-odds bounds must satisfy `min < 0 < max`.
    BadBounds {
        /// Lower bound.
        min: f32,
        /// Upper bound.
        max: f32,
    },
    /// The Occupied threshold must satisfy `0 <= occupied_above < max`.
    BadOccupiedThreshold {
        /// The threshold given.
        occupied_above: f32,
        /// Upper bound.
        max: f32,
    },
}

impl core::fmt::Display for GridError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GridError::CapacityExceeded { needed, capacity } => write!(
                f,
                "grid needs {needed} cells but its capacity is {capacity} cells"
            ),
            GridError::EmptyGrid => write!(f, "grid width and height must be at least one cell"),
            GridError::BadResolution(r) => {
                write!(
                    f,
                    "grid resolution must be a positive number of metres, got {r}"
                )
            }
            GridError::BadOrigin => write!(f, "grid origin must be finite"),
            GridError::BadBounds { min, max } => write!(
                f,
                "log-odds bounds must satisfy min < 0 < max, got min {min}, max {max}"
            ),
            GridError::BadOccupiedThreshold {
                occupied_above,
                max,
            } => write!(
                f,
                "the Occupied threshold must be from 0 up to below the upper bound {max} \
                 (log-odds), got {occupied_above}"
            ),
        }
    }
}

impl core::error::Error for GridError {}

/// Errors from [`OccupancyGrid::coverage`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum CoverageError {
    /// The mask must hold one entry per grid cell.
    MaskLength {
        /// Cells in the grid.
        expected: usize,
        /// Entries in the mask.
        got: usize,
    },
    /// The mask selects no cell, so coverage is undefined.
    EmptyMask,
}

impl core::fmt::Display for CoverageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CoverageError::MaskLength { expected, got } => write!(
                f,
                "coverage mask has {got} entries but the grid has {expected} cells"
            ),
            CoverageError::EmptyMask => write!(f, "coverage mask selects no cell"),
        }
    }
}

impl core::error::Error for CoverageError {}

/// Size and placement of a grid in the map frame.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Zeroable)]
pub struct GridGeometry {
    /// Columns \[cells\].
    pub width: usize,
    /// Rows \[cells\].
    pub height: usize,
    /// Cell side \[m\].
    pub resolution_m: f32,
    /// Map-frame position of the south-west corner of cell (0, 0) \[m\].
    pub origin: Point2,
}

impl GridGeometry {
    /// A checked geometry.
    pub fn new(
        width: usize,
        height: usize,
        resolution_m: f32,
        origin: Point2,
    ) -> Result<Self, GridError> {
        if width == 0 || height == 0 {
            return Err(GridError::EmptyGrid);
        }
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(GridError::BadResolution(resolution_m));
        }
        if !(origin.x.is_finite() && origin.y.is_finite()) {
            return Err(GridError::BadOrigin);
        }
        Ok(Self {
            width,
            height,
            resolution_m,
            origin,
        })
    }

    /// A geometry covering `width_m` x `height_m` metres from `origin` (sizes rounded up to
    /// whole cells).
    pub fn from_extent(
        width_m: f32,
        height_m: f32,
        resolution_m: f32,
        origin: Point2,
    ) -> Result<Self, GridError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(GridError::BadResolution(resolution_m));
        }
        // Tolerate float noise such as 24.0 / 0.1 = 240.00001.
        let cols = math::ceil(width_m / resolution_m - 1e-3).max(0.0) as usize;
        let rows = math::ceil(height_m / resolution_m - 1e-3).max(0.0) as usize;
        Self::new(cols, rows, resolution_m, origin)
    }

    /// Number of cells.
    #[inline]
    pub fn cell_count(&self) -> usize {
        self.width * self.height
    }

    /// Width \[m\].
    pub fn width_m(&self) -> f32 {
        self.width as f32 * self.resolution_m
    }

    /// Height \[m\].
    pub fn height_m(&self) -> f32 {
        self.height as f32 * self.resolution_m
    }

    /// Whether the cell lies inside the grid.
    #[inline]
    pub fn contains(&self, cell: Cell) -> bool {
        cell.col >= 0
            && cell.row >= 0
            && (cell.col as usize) < self.width
            && (cell.row as usize) < self.height
    }

    /// Flat index of a cell inside the grid.
    #[inline]
    pub fn index(&self, cell: Cell) -> Option<usize> {
        if self.contains(cell) {
            Some(cell.row as usize * self.width + cell.col as usize)
        } else {
            None
        }
    }

    /// The cell at a flat index (the index must be below [`Self::cell_count`]).
    #[inline]
    pub fn cell(&self, index: usize) -> Cell {
        Cell {
            col: (index % self.width) as i32,
            row: (index / self.width) as i32,
        }
    }

    /// The cell containing a map-frame point, whether or not it is inside the grid.
    #[inline]
    pub fn cell_at_unchecked(&self, p: Point2) -> Cell {
        Cell {
            col: math::floor((p.x - self.origin.x) / self.resolution_m) as i32,
            row: math::floor((p.y - self.origin.y) / self.resolution_m) as i32,
        }
    }

    /// The cell containing a map-frame point, if it is inside the grid.
    #[inline]
    pub fn cell_at(&self, p: Point2) -> Option<Cell> {
        let c = self.cell_at_unchecked(p);
        self.contains(c).then_some(c)
    }

    /// Map-frame centre of a cell \[m\].
    #[inline]
    pub fn cell_center(&self, cell: Cell) -> Point2 {
        Point2 {
            x: self.origin.x + (cell.col as f32 + 0.5) * self.resolution_m,
            y: self.origin.y + (cell.row as f32 + 0.5) * self.resolution_m,
        }
    }

    /// Whether a map-frame point lies inside the grid's extent.
    pub fn contains_point(&self, p: Point2) -> bool {
        self.cell_at(p).is_some()
    }

    /// Flat indices of the grid's cells whose centres lie within `radius_m` of `centre`
    /// (inclusive), row by row from the south-west; `centre` itself may lie off the grid.
    pub fn indices_within(self, centre: Point2, radius_m: f32) -> impl Iterator<Item = usize> {
        let c = self.cell_at_unchecked(centre);
        let span = math::ceil(radius_m / self.resolution_m) as i32 + 1;
        (c.row - span..=c.row + span)
            .flat_map(move |row| (c.col - span..=c.col + span).map(move |col| Cell::new(col, row)))
            .filter_map(move |cell| {
                self.index(cell)
                    .filter(|_| self.cell_center(cell).distance(centre) <= radius_m)
            })
    }
}

/// Default probability above which a cell is Occupied: 0.5, the thesis's rule (any net
/// evidence of an obstacle). ROS `map_server`'s `occupied_thresh` is 0.65
/// ([`NOISY_LASER_OCCUPIED_THRESH`]).
pub const DEFAULT_OCCUPIED_THRESH: f32 = 0.5;

/// The Occupied threshold for a laser whose range noise is about a cell or more at the
/// ranges it maps from (the thesis's 5 % at 2-4 m): ROS `map_server`'s `occupied_thresh`.
/// Measured on the generated plans with the thesis's laser: 83 of 240 missions at 99 % against
/// 66 with the thesis's rule; with a SICK's 0.3 % and the scan matcher 2.5 points of mean
/// coverage lost (docs/experiments.md, issue 17, "Weak evidence of an obstacle").
pub const NOISY_LASER_OCCUPIED_THRESH: f32 = 0.65;

/// The log-odds of probability `p` (`ln(p / (1 - p))`).
pub fn log_odds_of(p: f32) -> f32 {
    math::ln(p / (1.0 - p))
}

/// The probability of log-odds `l`.
pub fn probability_of(l: f32) -> f32 {
    1.0 / (1.0 + math::exp(-l))
}

/// The Occupied thresholds a grid accepts, displayed for error messages ("a probability from
/// 0.5 ... up to below 0.97"; [`LogOddsBounds::occupied_thresh_range`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OccupiedThreshRange(f32);

impl core::fmt::Display for OccupiedThreshRange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "a probability from 0.5 (the thesis's rule) up to below {:.2}",
            self.0
        )
    }
}

/// Saturation bounds of the log-odds, and the evidence a cell needs to be Occupied.
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize, bytemuck::Zeroable,
)]
pub struct LogOddsBounds {
    /// Lowest value (most certainly free); negative.
    pub min: f32,
    /// Highest value (most certainly occupied); positive.
    pub max: f32,
    /// A cell is Occupied when its log-odds exceed this; a cell with evidence (log-odds not
    /// 0) up to it is Free ([`Self::class_of`]). 0 (the default) is the thesis's rule. At
    /// [`NOISY_LASER_OCCUPIED_THRESH`]'s log-odds (0.619) one return in a cell is an obstacle
    /// (0.847, [`crate::sensor::SensorModel`]), one return and one beam through it (0.44) are
    /// not.
    ///
    /// Why a threshold: with a laser whose range noise is a cell or more, a wall's face on a
    /// cell boundary leaves the free cell in front of it with returns about as often as with
    /// beams through it, and the thesis's rule draws any such cell whose hits outweigh its
    /// misses by a hair (log-odds 0.1-0.5) as an obstacle: a second row of wall that shuts a
    /// 0.5 m door (docs/experiments.md, issue 17, "Weak evidence of an obstacle").
    #[serde(default)]
    pub occupied_above: f32,
}

impl Default for LogOddsBounds {
    /// ±3.5, i.e. p in \[0.03, 0.97\]: certain enough to plan on, yet a few contrary readings
    /// (a door that opens) flip a cell; Occupied on any net evidence of an obstacle (the
    /// thesis's rule, [`DEFAULT_OCCUPIED_THRESH`]).
    fn default() -> Self {
        Self {
            min: -3.5,
            max: 3.5,
            occupied_above: 0.0,
        }
    }
}

impl LogOddsBounds {
    /// These bounds with cells Occupied above probability `p` (0.5, the thesis's rule, up to
    /// below the upper bound's probability); `None` for any other `p`.
    pub fn with_occupied_thresh(self, p: f32) -> Option<Self> {
        let l = log_odds_of(p);
        (p >= 0.5 && l.is_finite() && l < self.max).then_some(Self {
            occupied_above: l.max(0.0),
            ..self
        })
    }

    /// The probability above which a cell is Occupied.
    pub fn occupied_thresh(&self) -> f32 {
        probability_of(self.occupied_above)
    }

    /// The probability [`Self::with_occupied_thresh`] must stay below: the upper bound's.
    pub fn occupied_thresh_limit(&self) -> f32 {
        probability_of(self.max)
    }

    /// What [`Self::with_occupied_thresh`] accepts, for error messages.
    pub fn occupied_thresh_range(&self) -> OccupiedThreshRange {
        OccupiedThreshRange(self.occupied_thresh_limit())
    }

    fn check(self) -> Result<Self, GridError> {
        if !(self.min < 0.0 && self.max > 0.0 && self.min.is_finite() && self.max.is_finite()) {
            return Err(GridError::BadBounds {
                min: self.min,
                max: self.max,
            });
        }
        if !(self.occupied_above >= 0.0 && self.occupied_above < self.max) {
            return Err(GridError::BadOccupiedThreshold {
                occupied_above: self.occupied_above,
                max: self.max,
            });
        }
        Ok(self)
    }

    /// The class of a cell of log-odds `l`: Occupied above [`Self::occupied_above`], Unknown
    /// at 0 (no evidence, or evidence that cancelled out exactly) or not a number, Free
    /// otherwise. With `occupied_above` 0 this is the thesis's rule,
    /// [`CellClass::of_log_odds`].
    #[inline]
    pub fn class_of(&self, l: f32) -> CellClass {
        if l > self.occupied_above {
            CellClass::Occupied
        } else if l == 0.0 || l.is_nan() {
            CellClass::Unknown
        } else {
            CellClass::Free
        }
    }
}

/// Counters of cell classes, maintained incrementally.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct CellCounts {
    /// Free cells.
    pub free: usize,
    /// Occupied cells.
    pub occupied: usize,
}

impl CellCounts {
    /// Known (free or occupied) cells.
    #[inline]
    pub fn known(&self) -> usize {
        self.free + self.occupied
    }
}

/// Told about every cell whose class changes, so derived layers (the planner's inflation, a
/// frontier set, a change log) stay current without rescanning the grid.
pub trait CellObserver {
    /// Cell `index` went from `old` to `new` (`old != new`).
    fn class_changed(&mut self, index: usize, old: CellClass, new: CellClass);
}

/// Observes nothing.
impl CellObserver for () {
    #[inline]
    fn class_changed(&mut self, _index: usize, _old: CellClass, _new: CellClass) {}
}

impl<F: FnMut(usize, CellClass, CellClass)> CellObserver for F {
    #[inline]
    fn class_changed(&mut self, index: usize, old: CellClass, new: CellClass) {
        self(index, old, new)
    }
}

/// A rectangle of cells: columns `col_min..col_end` and rows `row_min..row_end` (end
/// exclusive).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct CellBox {
    /// First column.
    pub col_min: usize,
    /// One past the last column.
    pub col_end: usize,
    /// First row.
    pub row_min: usize,
    /// One past the last row.
    pub row_end: usize,
}

impl CellBox {
    /// No cell (all zero: what a zeroed grid holds).
    pub const EMPTY: CellBox = CellBox {
        col_min: 0,
        col_end: 0,
        row_min: 0,
        row_end: 0,
    };

    /// The whole grid of `geometry`.
    pub fn all(geometry: &GridGeometry) -> Self {
        Self {
            col_min: 0,
            col_end: geometry.width,
            row_min: 0,
            row_end: geometry.height,
        }
    }

    /// Whether the box holds no cell.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.col_end <= self.col_min || self.row_end <= self.row_min
    }

    /// Grows the box to hold cell (`col`, `row`).
    #[inline]
    pub fn include(&mut self, col: usize, row: usize) {
        if self.is_empty() {
            *self = Self {
                col_min: col,
                col_end: col + 1,
                row_min: row,
                row_end: row + 1,
            };
        } else {
            self.col_min = self.col_min.min(col);
            self.col_end = self.col_end.max(col + 1);
            self.row_min = self.row_min.min(row);
            self.row_end = self.row_end.max(row + 1);
        }
    }

    /// The box grown by `margin` cells on every side, clipped to `geometry` (empty stays
    /// empty).
    pub fn grown(&self, margin: usize, geometry: &GridGeometry) -> Self {
        if self.is_empty() {
            return Self::EMPTY;
        }
        Self {
            col_min: self.col_min.saturating_sub(margin),
            col_end: (self.col_end + margin).min(geometry.width),
            row_min: self.row_min.saturating_sub(margin),
            row_end: (self.row_end + margin).min(geometry.height),
        }
    }
}

/// An occupancy grid holding up to `N` cells.
#[derive(Clone, bytemuck::Zeroable)]
pub struct OccupancyGrid<const N: usize> {
    geometry: GridGeometry,
    bounds: LogOddsBounds,
    counts: CellCounts,
    /// Every cell known since the last reset lies in this box (it never shrinks).
    known_box: CellBox,
    log_odds: [f32; N],
}

impl<const N: usize> core::fmt::Debug for OccupancyGrid<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("OccupancyGrid")
            .field("geometry", &self.geometry)
            .field("bounds", &self.bounds)
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> OccupancyGrid<N> {
    /// Capacity \[cells\].
    pub const CAPACITY: usize = N;

    /// An all-Unknown grid, built on the stack. For large `N` on a host, prefer
    /// [`Self::new_boxed`].
    pub fn new(geometry: GridGeometry, bounds: LogOddsBounds) -> Result<Self, GridError> {
        Self::check_fits(&geometry)?;
        Ok(Self {
            geometry,
            bounds: bounds.check()?,
            counts: CellCounts::default(),
            known_box: CellBox::EMPTY,
            log_odds: [0.0; N],
        })
    }

    /// An all-Unknown grid built directly on the heap (never on the stack, whatever `N`).
    #[cfg(feature = "std")]
    pub fn new_boxed(
        geometry: GridGeometry,
        bounds: LogOddsBounds,
    ) -> Result<std::boxed::Box<Self>, GridError> {
        let mut grid = crate::heap::boxed_zeroed::<Self>();
        grid.set_up_zeroed(geometry, bounds)?;
        Ok(grid)
    }

    /// Gives an all-zero grid (as [`crate::heap::boxed_zeroed`] makes it) its geometry and
    /// bounds: zero log-odds is Unknown and the zero counters match it.
    pub(crate) fn set_up_zeroed(
        &mut self,
        geometry: GridGeometry,
        bounds: LogOddsBounds,
    ) -> Result<(), GridError> {
        Self::check_fits(&geometry)?;
        self.bounds = bounds.check()?;
        self.geometry = geometry;
        Ok(())
    }

    fn check_fits(geometry: &GridGeometry) -> Result<(), GridError> {
        if geometry.cell_count() > N {
            return Err(GridError::CapacityExceeded {
                needed: geometry.cell_count(),
                capacity: N,
            });
        }
        Ok(())
    }

    /// Forgets everything and takes a new geometry: all cells Unknown.
    pub fn reset(&mut self, geometry: GridGeometry) -> Result<(), GridError> {
        Self::check_fits(&geometry)?;
        self.geometry = geometry;
        self.log_odds[..geometry.cell_count()].fill(0.0);
        self.counts = CellCounts::default();
        self.known_box = CellBox::EMPTY;
        Ok(())
    }

    /// Size and placement.
    #[inline]
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Saturation bounds.
    #[inline]
    pub fn bounds(&self) -> LogOddsBounds {
        self.bounds
    }

    /// Incrementally maintained class counters.
    #[inline]
    pub fn counts(&self) -> CellCounts {
        self.counts
    }

    /// A box holding every cell that has been known (Free or Occupied) since the grid was
    /// built or reset, kept up to date on every change; it grows, never shrinks, so it may
    /// also hold cells that went back to Unknown. Outside it every cell is Unknown: work
    /// about known cells (and the Unknown cells next to them, one cell further) can stay in
    /// it, whatever the size of the map.
    #[inline]
    pub fn known_box(&self) -> CellBox {
        self.known_box
    }

    /// Number of cells in use.
    #[inline]
    pub fn cell_count(&self) -> usize {
        self.geometry.cell_count()
    }

    /// Log-odds of the cells in use, in flat-index order.
    #[inline]
    pub fn log_odds(&self) -> &[f32] {
        &self.log_odds[..self.geometry.cell_count()]
    }

    /// Log-odds at a flat index (panics on an index past [`Self::cell_count`], a caller bug).
    #[inline]
    pub fn log_odds_at(&self, index: usize) -> f32 {
        self.log_odds[index]
    }

    /// Class at a flat index.
    #[inline]
    pub fn class(&self, index: usize) -> CellClass {
        self.bounds.class_of(self.log_odds[index])
    }

    /// Class of a cell; `None` outside the grid.
    #[inline]
    pub fn class_of(&self, cell: Cell) -> Option<CellClass> {
        self.geometry.index(cell).map(|i| self.class(i))
    }

    /// Adds log-odds evidence `delta` to a cell (Bayes' rule in log-odds form), saturating at
    /// the bounds. Returns the cell's class before and after.
    #[inline]
    pub fn add_evidence(
        &mut self,
        index: usize,
        delta: f32,
        observer: &mut impl CellObserver,
    ) -> (CellClass, CellClass) {
        let value = (self.log_odds[index] + delta).clamp(self.bounds.min, self.bounds.max);
        self.set_log_odds(index, value, observer)
    }

    /// Sets a cell's log-odds (clamped to the bounds). Returns its class before and after.
    pub fn set_log_odds(
        &mut self,
        index: usize,
        value: f32,
        observer: &mut impl CellObserver,
    ) -> (CellClass, CellClass) {
        let value = if value.is_nan() {
            0.0
        } else {
            value.clamp(self.bounds.min, self.bounds.max)
        };
        let old = self.class(index);
        self.log_odds[index] = value;
        let new = self.bounds.class_of(value);
        if old != new {
            self.count(old, -1);
            self.count(new, 1);
            if old == CellClass::Unknown {
                let w = self.geometry.width;
                self.known_box.include(index % w, index / w);
            }
            observer.class_changed(index, old, new);
        }
        (old, new)
    }

    /// Copies the log-odds of the cells in `area` (row by row) into `out`; returns the class
    /// counters, for [`Self::restore_window`]. `None` (nothing copied) when the area leaves
    /// the grid or does not fit in `out`.
    pub(crate) fn save_window(&self, area: CellBox, out: &mut [f32]) -> Option<CellCounts> {
        let w = self.geometry.width;
        let cols = area.col_end.checked_sub(area.col_min)?;
        let rows = area.row_end.checked_sub(area.row_min)?;
        if area.col_end > w || area.row_end > self.geometry.height || cols * rows > out.len() {
            return None;
        }
        for (k, row) in (area.row_min..area.row_end).enumerate() {
            let from = row * w + area.col_min;
            out[k * cols..(k + 1) * cols].copy_from_slice(&self.log_odds[from..from + cols]);
        }
        Some(self.counts)
    }

    /// Puts back the log-odds and class counters saved by [`Self::save_window`] for `area`,
    /// as if every cell changed since had been set back one by one with
    /// [`Self::set_log_odds`]: the box of known cells keeps what it grew by meanwhile.
    /// The caller must not have changed any cell outside `area` since the save.
    pub(crate) fn restore_window(&mut self, area: CellBox, saved: &[f32], counts: CellCounts) {
        let w = self.geometry.width;
        let cols = area.col_end - area.col_min;
        for (k, row) in (area.row_min..area.row_end).enumerate() {
            let to = row * w + area.col_min;
            self.log_odds[to..to + cols].copy_from_slice(&saved[k * cols..(k + 1) * cols]);
        }
        self.counts = counts;
    }

    /// Sets a cell to a class with the bounds' certainty (Occupied: max, Free: min, Unknown: 0).
    pub fn set_class(
        &mut self,
        index: usize,
        class: CellClass,
        observer: &mut impl CellObserver,
    ) -> (CellClass, CellClass) {
        let value = match class {
            CellClass::Free => self.bounds.min,
            CellClass::Unknown => 0.0,
            CellClass::Occupied => self.bounds.max,
        };
        self.set_log_odds(index, value, observer)
    }

    #[inline]
    fn count(&mut self, class: CellClass, delta: isize) {
        let slot = match class {
            CellClass::Free => &mut self.counts.free,
            CellClass::Occupied => &mut self.counts.occupied,
            CellClass::Unknown => return,
        };
        *slot = slot.wrapping_add_signed(delta);
    }

    /// Coverage: the fraction of the cells selected by `truth_mask` (one entry per cell, in
    /// flat-index order; `true` = a cell that can be observed, as supplied by the simulator)
    /// that are known (Free or Occupied). In `[0, 1]`.
    pub fn coverage(&self, truth_mask: &[bool]) -> Result<f32, CoverageError> {
        if truth_mask.len() != self.cell_count() {
            return Err(CoverageError::MaskLength {
                expected: self.cell_count(),
                got: truth_mask.len(),
            });
        }
        let (mut selected, mut known) = (0usize, 0usize);
        for (&l, &m) in self.log_odds().iter().zip(truth_mask) {
            selected += m as usize;
            known += (m && l != 0.0) as usize;
        }
        if selected == 0 {
            return Err(CoverageError::EmptyMask);
        }
        Ok(known as f32 / selected as f32)
    }

    /// Recounts every cell (for tests and after bulk loads; normal updates keep the counters).
    pub fn recount(&mut self) -> CellCounts {
        let mut counts = CellCounts::default();
        let mut known_box = CellBox::EMPTY;
        let w = self.geometry.width;
        let bounds = self.bounds;
        for (i, &l) in self.log_odds().iter().enumerate() {
            match bounds.class_of(l) {
                CellClass::Free => counts.free += 1,
                CellClass::Occupied => counts.occupied += 1,
                CellClass::Unknown => continue,
            }
            known_box.include(i % w, i / w);
        }
        self.counts = counts;
        self.known_box = known_box;
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> OccupancyGrid<100> {
        let g = GridGeometry::new(10, 10, 0.1, Point2::new(0.0, 0.0)).unwrap();
        OccupancyGrid::new(g, LogOddsBounds::default()).unwrap()
    }

    #[test]
    fn classification_follows_the_sign_of_the_log_odds() {
        assert_eq!(CellClass::of_log_odds(0.0), CellClass::Unknown);
        assert_eq!(CellClass::of_log_odds(-0.0), CellClass::Unknown);
        assert_eq!(CellClass::of_log_odds(1e-6), CellClass::Occupied);
        assert_eq!(CellClass::of_log_odds(-1e-6), CellClass::Free);
    }

    #[test]
    fn a_cell_is_occupied_above_the_threshold_and_free_below_it() {
        // The default is the thesis's rule.
        let thesis_default = LogOddsBounds::default();
        assert_eq!(thesis_default.occupied_above, 0.0);
        assert_eq!(thesis_default.occupied_thresh(), DEFAULT_OCCUPIED_THRESH);
        let b = thesis_default
            .with_occupied_thresh(NOISY_LASER_OCCUPIED_THRESH)
            .unwrap();
        assert!((b.occupied_above - 0.619_039).abs() < 1e-5);
        assert!((b.occupied_thresh() - 0.65).abs() < 1e-6);
        // One return (0.847) is an obstacle; one return and one beam through (0.442) is not.
        assert_eq!(b.class_of(0.847), CellClass::Occupied);
        assert_eq!(b.class_of(0.847 - 0.405), CellClass::Free);
        assert_eq!(b.class_of(-0.405), CellClass::Free);
        assert_eq!(b.class_of(0.0), CellClass::Unknown);
        assert_eq!(b.class_of(f32::NAN), CellClass::Unknown);
        // 0.5 is the thesis's rule.
        let thesis = b.with_occupied_thresh(0.5).unwrap();
        assert_eq!(thesis.occupied_above, 0.0);
        for l in [-3.5, -1e-6, -0.0, 0.0, 1e-6, 0.3, 0.62, 3.5] {
            assert_eq!(thesis.class_of(l), CellClass::of_log_odds(l), "{l}");
        }
        // Below a half, or at the saturation's probability, or not a number: refused.
        for p in [0.49, 0.98, 1.0, f32::NAN] {
            assert_eq!(b.with_occupied_thresh(p), None, "{p}");
        }
        // A grid with the threshold keeps its cells' classes and counts by it.
        let g = GridGeometry::new(4, 1, 0.1, Point2::default()).unwrap();
        let mut grid = OccupancyGrid::<4>::new(g, b).unwrap();
        grid.add_evidence(0, 0.847, &mut ());
        grid.add_evidence(1, 0.847, &mut ());
        grid.add_evidence(1, -0.405, &mut ());
        assert_eq!(grid.class(0), CellClass::Occupied);
        assert_eq!(grid.class(1), CellClass::Free);
        let counts = grid.counts();
        assert_eq!((counts.occupied, counts.free), (1, 1));
        assert_eq!(grid.recount(), counts);
        let bad = LogOddsBounds {
            occupied_above: 3.5,
            ..b
        };
        assert!(matches!(
            OccupancyGrid::<4>::new(g, bad),
            Err(GridError::BadOccupiedThreshold { .. })
        ));
    }

    #[test]
    fn capacity_is_checked() {
        let g = GridGeometry::new(11, 10, 0.1, Point2::default()).unwrap();
        assert_eq!(
            OccupancyGrid::<100>::new(g, LogOddsBounds::default()).unwrap_err(),
            GridError::CapacityExceeded {
                needed: 110,
                capacity: 100
            }
        );
    }

    #[test]
    fn default_capacity_fits_the_thesis_and_factory_maps() {
        let house = GridGeometry::from_extent(24.0, 24.0, 0.1, Point2::default()).unwrap();
        let factory = GridGeometry::from_extent(30.0, 50.0, 0.1, Point2::default()).unwrap();
        assert_eq!((house.width, house.height), (240, 240));
        assert_eq!((factory.width, factory.height), (300, 500));
        assert!(house.cell_count() <= DEFAULT_CELL_CAPACITY);
        assert!(factory.cell_count() <= DEFAULT_CELL_CAPACITY);
    }

    #[test]
    fn evidence_saturates_and_counters_follow() {
        let mut g = small();
        let mut changes = 0;
        let mut obs = |_i: usize, _o: CellClass, _n: CellClass| changes += 1;
        for _ in 0..100 {
            g.add_evidence(5, 0.9, &mut obs);
        }
        assert_eq!(g.log_odds_at(5), g.bounds().max);
        assert_eq!(g.counts().occupied, 1);
        g.add_evidence(5, -10.0, &mut obs);
        assert_eq!(g.class(5), CellClass::Free);
        assert_eq!(
            g.counts(),
            CellCounts {
                free: 1,
                occupied: 0
            }
        );
        assert_eq!(changes, 2);
    }

    #[test]
    fn cell_addressing_puts_row_zero_south() {
        let geom = GridGeometry::new(4, 3, 0.5, Point2::new(-1.0, 2.0)).unwrap();
        assert_eq!(geom.cell_at(Point2::new(-0.9, 2.1)), Some(Cell::new(0, 0)));
        assert_eq!(geom.cell_at(Point2::new(0.9, 3.4)), Some(Cell::new(3, 2)));
        assert_eq!(geom.cell_at(Point2::new(1.1, 2.1)), None);
        assert_eq!(geom.index(Cell::new(3, 2)), Some(11));
        assert_eq!(geom.cell(11), Cell::new(3, 2));
        let c = geom.cell_center(Cell::new(1, 1));
        assert!((c.x - (-0.25)).abs() < 1e-6 && (c.y - 2.75).abs() < 1e-6);
    }

    #[test]
    fn counters_equal_a_full_recount_after_random_updates() {
        use crate::random::{below, range_f32, seeded};
        let mut rng = seeded(3);
        let mut g = small();
        let mut changes = 0usize;
        for step in 0..20_000 {
            let i = below(&mut rng, 100);
            let mut obs = |_i: usize, o: CellClass, n: CellClass| {
                assert_ne!(o, n);
                changes += 1;
            };
            match below(&mut rng, 4) {
                0 => {
                    g.add_evidence(i, range_f32(&mut rng, -2.0, 2.0), &mut obs);
                }
                1 => {
                    let class = [CellClass::Free, CellClass::Unknown, CellClass::Occupied]
                        [below(&mut rng, 3)];
                    g.set_class(i, class, &mut obs);
                }
                2 => {
                    g.set_log_odds(i, 0.0, &mut obs);
                }
                _ => {
                    // Evidence that exactly cancels brings a cell back to Unknown.
                    let l = g.log_odds_at(i);
                    g.add_evidence(i, -l, &mut obs);
                }
            }
            if step % 97 == 0 {
                let kept = g.counts();
                assert_eq!(kept, g.clone().recount(), "step {step}");
            }
        }
        let kept = g.counts();
        assert_eq!(kept, g.recount());
        assert!(changes > 1000);
    }

    #[test]
    fn the_known_box_holds_every_cell_ever_known_and_no_more() {
        use crate::random::{below, range_f32, seeded};
        let mut rng = seeded(8);
        for case in 0..200 {
            let mut g = small();
            assert!(g.known_box().is_empty());
            // Updates in a random sub-rectangle of the 10 x 10 grid.
            let (c0, r0) = (below(&mut rng, 10), below(&mut rng, 10));
            let (c1, r1) = (
                c0 + 1 + below(&mut rng, 10 - c0),
                r0 + 1 + below(&mut rng, 10 - r0),
            );
            let mut ever = CellBox::EMPTY;
            for _ in 0..below(&mut rng, 30) {
                let (c, r) = (c0 + below(&mut rng, c1 - c0), r0 + below(&mut rng, r1 - r0));
                let l = if below(&mut rng, 4) == 0 {
                    0.0
                } else {
                    range_f32(&mut rng, -2.0, 2.0)
                };
                g.set_log_odds(r * 10 + c, l, &mut ());
                if g.class(r * 10 + c).is_known() {
                    ever.include(c, r);
                }
            }
            assert_eq!(g.known_box(), ever, "case {case}");
            for i in 0..100 {
                if g.class(i).is_known() {
                    let (c, r) = (i % 10, i / 10);
                    assert!((ever.col_min..ever.col_end).contains(&c), "case {case}");
                    assert!((ever.row_min..ever.row_end).contains(&r), "case {case}");
                }
            }
            g.reset(*g.geometry()).unwrap();
            assert!(g.known_box().is_empty());
        }
    }

    #[test]
    fn coverage_counts_known_cells_in_the_mask() {
        let mut g = small();
        let mut mask = [false; 100];
        mask[..10].fill(true);
        assert_eq!(g.coverage(&mask), Ok(0.0));
        g.set_class(0, CellClass::Free, &mut ());
        g.set_class(1, CellClass::Occupied, &mut ());
        g.set_class(50, CellClass::Free, &mut ());
        assert_eq!(g.coverage(&mask), Ok(0.2));
        assert_eq!(
            g.coverage(&mask[..5]),
            Err(CoverageError::MaskLength {
                expected: 100,
                got: 5
            })
        );
        assert_eq!(g.coverage(&[false; 100]), Err(CoverageError::EmptyMask));
    }

    #[cfg(feature = "std")]
    #[test]
    fn boxed_grid_of_default_capacity_starts_unknown() {
        let geom = GridGeometry::from_extent(30.0, 50.0, 0.1, Point2::default()).unwrap();
        let g = OccupancyGrid::<DEFAULT_CELL_CAPACITY>::new_boxed(geom, LogOddsBounds::default())
            .unwrap();
        assert_eq!(g.counts().known(), 0);
        assert!(g.log_odds().iter().all(|&l| l == 0.0));
    }
}
