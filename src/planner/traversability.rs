//! Traversability: which cells the robot may enter, and at what cost.
//!
//! Occupied cells are blocked. Obstacles are inflated by the robot radius (configuration
//! space for a disc robot, Lozano-Pérez, "Spatial planning: a configuration space approach",
//! IEEE Trans. Computers C-32(2), 1983): a cell whose centre is closer than `robot_radius_m`
//! to the centre of an Occupied cell is blocked too. Unknown cells are either traversable at a
//! cost factor (exploration plans through unknown space optimistically) or blocked (strict).
//!
//! Inflation is kept up to date incrementally: for every cell the layer counts the Occupied
//! cells within the radius (a precomputed disc stencil of offsets). When a cell becomes or
//! stops being Occupied, the counts under its stencil are incremented or decremented; a cell is
//! inflated while its count is non-zero. The layer is a [`CellObserver`], so passing it to the
//! grid's updates keeps it current; no query rescans the grid.
//!
//! Around the blocked band the layer keeps two cost bands, the idea of a costmap's inflation
//! layer (Lu, Hershberger & Smart, "Layered costmaps for context-sensitive navigation", IROS
//! 2014): cells closer than [`WallBands::no_turn_radius_m`] to an Occupied cell are where the
//! robot's swing circle does not fit, so it may cross them but not turn in place there (a
//! door it fits through straight), and cells closer than [`WallBands::near_radius_m`] cost a
//! little more, so that paths keep away from walls where there is room. Each band is one more
//! count per cell under a wider stencil, kept current the same way.
//!
//! For the searches, the layer also keeps a move mask per cell: one bit per legal step out of
//! the cell (in bounds, into a passable cell, and for a diagonal both orthogonal neighbours
//! passable: no corner cutting). A search then expands a cell from one byte instead of testing
//! bounds and up to eight neighbours' codes. The mask of a cell depends only on the codes of
//! its 3 x 3 neighbourhood, so a change of a cell between blocked and passable refreshes the nine
//! masks around it.

use crate::grid::{Cell, CellBox, CellClass, CellObserver, GridGeometry, OccupancyGrid};

/// Default robot radius \[m\]: the Pioneer P3-DX body (about 0.45 m wide, 0.38 m from the wheel
/// axle to the front bumper) fits in a 0.25 m disc around its centre of rotation.
pub const P3DX_RADIUS_M: f32 = 0.25;

/// Default cost factor of Unknown cells: 1, i.e. fully optimistic.
pub const DEFAULT_UNKNOWN_COST_FACTOR: f32 = 1.0;

/// Most offsets an inflation disc may hold (a radius of up to 17 cells).
pub const MAX_STENCIL: usize = 1024;

/// Rows of the widest stencil's row spans (a reach of up to 23 cells; the stencil's
/// capacity allows about 18).
const MAX_SPAN_ROWS: usize = 47;

/// Per-cell step code: blocked.
pub(crate) const CODE_BLOCKED: u8 = 0;
/// Per-cell step code: Free (or Occupied-free benchmark cell), cost factor 1.
pub(crate) const CODE_FREE: u8 = 1;
/// Per-cell step code: Unknown, traversable at the configured factor.
pub(crate) const CODE_UNKNOWN: u8 = 2;
/// Step codes of passable cells: `CODE_FREE` or `CODE_UNKNOWN` plus twice the wall band (0:
/// clear of walls, [`BAND_NEAR`], [`BAND_NO_TURN`]).
pub(crate) const CODE_COUNT: usize = 7;
/// Wall band: within [`WallBands::near_radius_m`] of an Occupied cell.
pub(crate) const BAND_NEAR: u8 = 1;
/// Wall band: within [`WallBands::no_turn_radius_m`] of an Occupied cell.
pub(crate) const BAND_NO_TURN: u8 = 2;

/// The wall band of a passable step code (0 for blocked codes too).
#[inline]
pub(crate) const fn band_of_code(code: u8) -> u8 {
    if code == CODE_BLOCKED {
        0
    } else {
        (code - 1) / 2
    }
}

/// The eight steps out of a cell as (column, row) offsets, in the order of the move-mask bits
/// (bit `k` of a mask is step `MOVES[k]`): west, east, south, south-west, south-east, north,
/// north-west, north-east.
pub(crate) const MOVES: [(i8, i8); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (-1, -1),
    (1, -1),
    (0, 1),
    (-1, 1),
    (1, 1),
];

const CLASS_UNKNOWN: u8 = 0;
const CLASS_FREE: u8 = 1;
const CLASS_OCCUPIED: u8 = 2;

/// What to do with Unknown cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UnknownPolicy {
    /// Unknown cells may be crossed; entering one costs `cost_factor` times a Free step
    /// (`cost_factor >= 1`, which keeps the octile heuristic admissible).
    Traversable {
        /// Multiplier of the step cost into an Unknown cell; at least 1.
        cost_factor: f32,
    },
    /// Unknown cells are blocked (strict mode).
    Blocked,
}

/// The cost bands beside the blocked band (see the module documentation). A radius no larger
/// than the robot radius leaves its band empty; [`WallBands::NONE`] has none.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Zeroable)]
pub struct WallBands {
    /// Cells whose centre lies closer than this to an Occupied cell's centre are where the
    /// robot cannot turn in place (its swing radius plus a margin) \[m\].
    pub no_turn_radius_m: f32,
    /// Cost factor of entering a no-turn cell (at least 1; multiplies the Unknown factor).
    pub no_turn_cost_factor: f32,
    /// Cells closer than this to an Occupied cell (and outside the no-turn band) cost
    /// [`Self::near_cost_factor`] \[m\].
    pub near_radius_m: f32,
    /// Cost factor of entering a near-wall cell (at least 1).
    pub near_cost_factor: f32,
}

impl WallBands {
    /// No bands: every passable cell costs its Free or Unknown factor.
    pub const NONE: Self = Self {
        no_turn_radius_m: 0.0,
        no_turn_cost_factor: 1.0,
        near_radius_m: 0.0,
        near_cost_factor: 1.0,
    };
}

/// Configuration of a [`Traversability`] layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraversabilityConfig {
    /// Robot radius \[m\]; cells whose centre lies closer than this to an Occupied cell's centre
    /// are blocked. Zero: only Occupied cells are blocked.
    pub robot_radius_m: f32,
    /// Treatment of Unknown cells.
    pub unknown_policy: UnknownPolicy,
    /// Cost bands near walls.
    pub bands: WallBands,
}

impl Default for TraversabilityConfig {
    /// P3-DX radius, Unknown traversable at factor 1, no wall bands.
    fn default() -> Self {
        Self {
            robot_radius_m: P3DX_RADIUS_M,
            unknown_policy: UnknownPolicy::Traversable {
                cost_factor: DEFAULT_UNKNOWN_COST_FACTOR,
            },
            bands: WallBands::NONE,
        }
    }
}

/// Errors from building a traversability layer.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum TraversabilityError {
    /// The grid has more cells than the layer's capacity.
    CapacityExceeded {
        /// Cells needed.
        needed: usize,
        /// Cells the layer holds.
        capacity: usize,
    },
    /// The grid is empty (zero width or height).
    EmptyGrid,
    /// The robot radius is negative or not finite \[m\].
    BadRadius(f32),
    /// The inflation disc has more offsets than [`MAX_STENCIL`].
    InflationTooLarge {
        /// Offsets the disc needs.
        needed: usize,
        /// [`MAX_STENCIL`].
        capacity: usize,
    },
    /// The Unknown cost factor, or a wall band's, is below 1 or not finite.
    BadCostFactor(f32),
    /// The cell size is not a positive number of metres.
    BadResolution(f32),
}

impl core::fmt::Display for TraversabilityError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TraversabilityError::CapacityExceeded { needed, capacity } => write!(
                f,
                "traversability needs {needed} cells but its capacity is {capacity} cells"
            ),
            TraversabilityError::EmptyGrid => {
                write!(
                    f,
                    "traversability grid must be at least one cell wide and high"
                )
            }
            TraversabilityError::BadRadius(r) => {
                write!(
                    f,
                    "robot radius must be a finite non-negative number of metres, got {r}"
                )
            }
            TraversabilityError::InflationTooLarge { needed, capacity } => write!(
                f,
                "inflation disc needs {needed} cell offsets but at most {capacity} are allowed"
            ),
            TraversabilityError::BadCostFactor(c) => {
                write!(
                    f,
                    "a cost factor (Unknown cells, wall bands) must be finite and at least 1, got {c}"
                )
            }
            TraversabilityError::BadResolution(r) => {
                write!(f, "cell size must be a positive number of metres, got {r}")
            }
        }
    }
}

impl core::error::Error for TraversabilityError {}

/// The discs of cell offsets a configuration stamps around an Occupied cell at a resolution
/// (see [`Traversability`]), with the configuration's checked values.
struct Stencil {
    /// Offsets of the widest band's disc, those within the robot radius first, then those of
    /// the no-turn band, then the near band's.
    offsets: [[i16; 2]; MAX_STENCIL],
    /// Offsets within the robot radius, the no-turn radius and the near radius.
    lens: [usize; 3],
    /// No offset is farther than this in a row or a column \[cells\].
    reach: usize,
    /// Each row's largest `|dc|` per band (see [`Traversability`]'s `row_spans`).
    row_spans: [[i16; 3]; MAX_SPAN_ROWS],
    unknown_blocked: bool,
    unknown_cost_factor: f32,
}

impl Stencil {
    fn of(resolution_m: f32, config: &TraversabilityConfig) -> Result<Self, TraversabilityError> {
        let r = config.robot_radius_m;
        if !(r.is_finite() && r >= 0.0) {
            return Err(TraversabilityError::BadRadius(r));
        }
        let (unknown_blocked, factor) = match config.unknown_policy {
            UnknownPolicy::Blocked => (true, 1.0),
            UnknownPolicy::Traversable { cost_factor } => {
                if !(cost_factor.is_finite() && cost_factor >= 1.0) {
                    return Err(TraversabilityError::BadCostFactor(cost_factor));
                }
                (false, cost_factor)
            }
        };
        let bands = config.bands;
        for f in [bands.no_turn_cost_factor, bands.near_cost_factor] {
            if !(f.is_finite() && f >= 1.0) {
                return Err(TraversabilityError::BadCostFactor(f));
            }
        }
        for b in [bands.no_turn_radius_m, bands.near_radius_m] {
            if !(b.is_finite() && b >= 0.0) {
                return Err(TraversabilityError::BadRadius(b));
            }
        }
        // Discs of offsets whose centre distance is below each radius ((0, 0) always within
        // the robot radius), the inner ones first.
        let res = resolution_m;
        let r_turn = bands.no_turn_radius_m.max(r);
        let r_near = bands.near_radius_m.max(r_turn);
        let radii2 = [r, r_turn, r_near].map(|m| {
            let c = m / res;
            c * c
        });
        // A disc wider than the row spans hold is refused before it is walked (on cells
        // fine enough, a metre is a million of them).
        let reach_cells = crate::math::ceil(r_near / res);
        if !(reach_cells.is_finite() && 2.0 * reach_cells < MAX_SPAN_ROWS as f32) {
            let side = 2.0 * reach_cells + 1.0;
            return Err(TraversabilityError::InflationTooLarge {
                needed: (side * side).min(usize::MAX as f32) as usize,
                capacity: MAX_STENCIL,
            });
        }
        let reach = reach_cells as i32;
        let mut stencil = [[0i16; 2]; MAX_STENCIL];
        let mut lens = [0usize; 3];
        let mut len = 0usize;
        for (band, &limit2) in radii2.iter().enumerate() {
            let inner2 = if band == 0 { -1.0 } else { radii2[band - 1] };
            for dr in -reach..=reach {
                for dc in -reach..=reach {
                    let d2 = (dc * dc + dr * dr) as f32;
                    let centre = dc == 0 && dr == 0;
                    let inside = centre || d2 < limit2;
                    let inner = if band == 0 {
                        false
                    } else {
                        centre || d2 < inner2
                    };
                    if inside && !inner {
                        if len == MAX_STENCIL {
                            let side = (2 * reach + 1) as usize;
                            return Err(TraversabilityError::InflationTooLarge {
                                needed: side * side,
                                capacity: MAX_STENCIL,
                            });
                        }
                        stencil[len] = [dc as i16, dr as i16];
                        len += 1;
                    }
                }
            }
            lens[band] = len;
        }
        let mut row_spans = [[-1i16; 3]; MAX_SPAN_ROWS];
        for (k, &[dc, dr]) in stencil[..len].iter().enumerate() {
            let row = &mut row_spans[(dr as i32 + reach) as usize];
            // Offset k lies in its own band's disc and every wider one.
            let first_band = lens.iter().position(|&l| k < l).unwrap_or(2);
            for span in &mut row[first_band..] {
                *span = (*span).max(dc.abs());
            }
        }
        Ok(Self {
            offsets: stencil,
            lens,
            reach: reach as usize,
            row_spans,
            unknown_blocked,
            unknown_cost_factor: factor,
        })
    }
}

impl TraversabilityConfig {
    /// Whether a layer of cells of `resolution_m` can be built with this configuration: the
    /// radii and cost factors are valid and the discs fit the layer's stencil
    /// ([`MAX_STENCIL`]). A board is checked with it before a mission is built.
    pub fn check(&self, resolution_m: f32) -> Result<(), TraversabilityError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(TraversabilityError::BadResolution(resolution_m));
        }
        Stencil::of(resolution_m, self).map(|_| ())
    }
}

/// Traversability of up to `N` cells: blocked flags (obstacles and their inflation) and step
/// cost factors, maintained incrementally from the occupancy grid.
///
/// Build it with [`Self::new`] / [`Self::new_boxed`] and load a grid with
/// [`Self::rebuild_from`]; then pass it as the observer of every grid update
/// (`grid.add_evidence(i, delta, &mut trav)`) so it stays current. For benchmarks on plain
/// blocked/passable maps, [`Self::from_blocked`] builds it without a grid or inflation.
#[derive(Clone, bytemuck::Zeroable)]
pub struct Traversability<const N: usize> {
    geometry: GridGeometry,
    robot_radius_m: f32,
    unknown_blocked: bool,
    unknown_cost_factor: f32,
    bands: WallBands,
    /// Every cell whose step code has differed from the Unknown cells' since the last
    /// reset lies in this box (it never shrinks).
    marked: CellBox,
    /// Offsets of the widest band's disc, those within the robot radius first, then those of
    /// the no-turn band, then the near band's.
    stencil: [[i16; 2]; MAX_STENCIL],
    /// Offsets within the robot radius.
    stencil_len: usize,
    /// Offsets within the no-turn radius (or the robot radius, if larger).
    stencil_turn_len: usize,
    /// Offsets within the near radius (or either smaller one, if larger).
    stencil_near_len: usize,
    /// No offset of the stencil is farther than this in a row or a column \[cells\].
    stencil_reach: usize,
    /// The stencil by rows, for bumping counts a row span at a time: for the row of offset
    /// `dr`, entry `dr + stencil_reach` holds the largest `|dc|` within the robot radius, the
    /// no-turn radius and the near radius (each band's whole disc), -1 where the row has none.
    /// A disc's row is one run of columns, so the offsets `(dc, dr)` of a band are exactly
    /// those with `|dc|` up to its entry.
    row_spans: [[i16; 3]; MAX_SPAN_ROWS],
    /// Cell classes (CLASS_*).
    class: [u8; N],
    /// Occupied cells within the inflation radius (the cell itself included).
    near: [u16; N],
    /// Occupied cells within the no-turn stencil.
    near_turn: [u16; N],
    /// Occupied cells within the near-band stencil.
    near_band: [u16; N],
    /// Step code (CODE_*), derived from `class` and `near`.
    code: [u8; N],
    /// Legal steps out of each cell (bit `k`: step [`MOVES`]`[k]`), derived from `code`; zero
    /// for blocked cells.
    moves: [u8; N],
}

impl<const N: usize> core::fmt::Debug for Traversability<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Traversability")
            .field("geometry", &self.geometry)
            .field("config", &self.config())
            .field("stencil_len", &self.stencil_len)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> Traversability<N> {
    /// Capacity \[cells\].
    pub const CAPACITY: usize = N;

    /// An all-Unknown layer of the given geometry, built on the stack. For large `N` on a host
    /// prefer [`Self::new_boxed`].
    pub fn new(
        geometry: GridGeometry,
        config: TraversabilityConfig,
    ) -> Result<Self, TraversabilityError> {
        let mut t = Self {
            geometry,
            robot_radius_m: 0.0,
            unknown_blocked: false,
            unknown_cost_factor: 1.0,
            bands: WallBands::NONE,
            marked: CellBox::EMPTY,
            stencil: [[0; 2]; MAX_STENCIL],
            stencil_len: 0,
            stencil_turn_len: 0,
            stencil_near_len: 0,
            stencil_reach: 0,
            row_spans: [[-1; 3]; MAX_SPAN_ROWS],
            class: [CLASS_UNKNOWN; N],
            near: [0; N],
            near_turn: [0; N],
            near_band: [0; N],
            code: [CODE_BLOCKED; N],
            moves: [0; N],
        };
        t.configure(geometry, config)?;
        t.reset_cells();
        Ok(t)
    }

    /// An all-Unknown layer built directly on the heap (never on the stack, whatever `N`).
    #[cfg(feature = "std")]
    pub fn new_boxed(
        geometry: GridGeometry,
        config: TraversabilityConfig,
    ) -> Result<std::boxed::Box<Self>, TraversabilityError> {
        let mut t = crate::heap::boxed_zeroed::<Self>();
        t.set_up_zeroed(geometry, config)?;
        Ok(t)
    }

    /// Gives an all-zero layer (as [`crate::heap::boxed_zeroed`] makes it) its geometry and
    /// configuration: `configure` and `reset_cells` set every field.
    #[cfg(feature = "std")]
    pub(crate) fn set_up_zeroed(
        &mut self,
        geometry: GridGeometry,
        config: TraversabilityConfig,
    ) -> Result<(), TraversabilityError> {
        self.configure(geometry, config)?;
        self.reset_cells();
        Ok(())
    }

    /// A layer over a plain blocked/passable map of `width` x `height` cells (resolution 1 m,
    /// origin 0, no inflation, no Unknown cells): `blocked(cell)` says which cells are walls.
    /// Lengths are then in cells. Used for benchmark maps.
    pub fn from_blocked(
        width: usize,
        height: usize,
        blocked: impl FnMut(Cell) -> bool,
    ) -> Result<Self, TraversabilityError> {
        let geometry = Self::unit_geometry(width, height)?;
        let mut t = Self::new(geometry, Self::no_inflation())?;
        t.load_blocked(width, height, blocked)?;
        Ok(t)
    }

    /// [`Self::from_blocked`], built on the heap.
    #[cfg(feature = "std")]
    pub fn from_blocked_boxed(
        width: usize,
        height: usize,
        blocked: impl FnMut(Cell) -> bool,
    ) -> Result<std::boxed::Box<Self>, TraversabilityError> {
        let geometry = Self::unit_geometry(width, height)?;
        let mut t = Self::new_boxed(geometry, Self::no_inflation())?;
        t.load_blocked(width, height, blocked)?;
        Ok(t)
    }

    /// Replaces the content with a plain blocked/passable map (see [`Self::from_blocked`]),
    /// reusing this layer's memory.
    pub fn load_blocked(
        &mut self,
        width: usize,
        height: usize,
        mut blocked: impl FnMut(Cell) -> bool,
    ) -> Result<(), TraversabilityError> {
        let geometry = Self::unit_geometry(width, height)?;
        self.configure(geometry, Self::no_inflation())?;
        let n = geometry.cell_count();
        for i in 0..n {
            let b = blocked(geometry.cell(i));
            self.class[i] = if b { CLASS_OCCUPIED } else { CLASS_FREE };
            self.near[i] = b as u16;
            self.near_turn[i] = b as u16;
            self.near_band[i] = b as u16;
            self.code[i] = if b { CODE_BLOCKED } else { CODE_FREE };
        }
        self.recompute_marked();
        self.refresh_all_moves();
        Ok(())
    }

    fn unit_geometry(width: usize, height: usize) -> Result<GridGeometry, TraversabilityError> {
        GridGeometry::new(width, height, 1.0, crate::geometry::Point2::new(0.0, 0.0))
            .map_err(|_| TraversabilityError::EmptyGrid)
    }

    fn no_inflation() -> TraversabilityConfig {
        TraversabilityConfig {
            robot_radius_m: 0.0,
            unknown_policy: UnknownPolicy::Blocked,
            bands: WallBands::NONE,
        }
    }

    /// Recomputes everything from a grid (initial load, or after the grid was reset or its
    /// geometry changed). Takes the grid's geometry.
    pub fn rebuild_from<const M: usize>(
        &mut self,
        grid: &OccupancyGrid<M>,
    ) -> Result<(), TraversabilityError> {
        self.configure(*grid.geometry(), self.config())?;
        let n = self.geometry.cell_count();
        for i in 0..n {
            self.class[i] = class_code(grid.class(i));
        }
        self.recompute_from_classes();
        Ok(())
    }

    /// Changes the configuration (radius, Unknown policy) and recomputes every cell.
    pub fn set_config(&mut self, config: TraversabilityConfig) -> Result<(), TraversabilityError> {
        self.configure(self.geometry, config)?;
        self.recompute_from_classes();
        Ok(())
    }

    fn recompute_from_classes(&mut self) {
        let n = self.geometry.cell_count();
        self.near[..n].fill(0);
        self.near_turn[..n].fill(0);
        self.near_band[..n].fill(0);
        for i in 0..n {
            if self.class[i] == CLASS_OCCUPIED {
                self.stamp_disc(i, 1);
            }
        }
        for i in 0..n {
            self.code[i] = self.code_of(i);
        }
        self.recompute_marked();
        self.refresh_all_moves();
    }

    /// The box of the cells whose step code is not the Unknown cells', from scratch.
    fn recompute_marked(&mut self) {
        let (w, n) = (self.geometry.width, self.geometry.cell_count());
        let plain = self.unknown_code();
        self.marked = CellBox::EMPTY;
        for i in 0..n {
            if self.code[i] != plain {
                self.marked.include(i % w, i / w);
            }
        }
    }

    /// A box outside which every cell has the step code of an Unknown cell away from walls
    /// (passable at the Unknown cost factor, or blocked if Unknown cells are blocked): the
    /// cells that are known, inflated or in a wall band lie in it. It grows, never shrinks,
    /// until the layer is rebuilt. Work that only needs those cells can stay in it, whatever
    /// the size of the map.
    pub fn marked_box(&self) -> CellBox {
        self.marked
    }

    /// Whether Unknown cells are blocked ([`UnknownPolicy::Blocked`]).
    pub fn unknown_is_blocked(&self) -> bool {
        self.unknown_blocked
    }

    /// Checks and stores geometry and configuration, recomputes the stencil. Cell arrays are
    /// left as they are.
    fn configure(
        &mut self,
        geometry: GridGeometry,
        config: TraversabilityConfig,
    ) -> Result<(), TraversabilityError> {
        let n = geometry.cell_count();
        if n == 0 {
            return Err(TraversabilityError::EmptyGrid);
        }
        if n > N {
            return Err(TraversabilityError::CapacityExceeded {
                needed: n,
                capacity: N,
            });
        }
        let stencil = Stencil::of(geometry.resolution_m, &config)?;
        self.geometry = geometry;
        self.robot_radius_m = config.robot_radius_m;
        self.unknown_blocked = stencil.unknown_blocked;
        self.unknown_cost_factor = stencil.unknown_cost_factor;
        self.bands = config.bands;
        self.stencil = stencil.offsets;
        [
            self.stencil_len,
            self.stencil_turn_len,
            self.stencil_near_len,
        ] = stencil.lens;
        self.stencil_reach = stencil.reach;
        self.row_spans = stencil.row_spans;
        Ok(())
    }

    fn reset_cells(&mut self) {
        let n = self.geometry.cell_count();
        self.class[..n].fill(CLASS_UNKNOWN);
        self.near[..n].fill(0);
        self.near_turn[..n].fill(0);
        self.near_band[..n].fill(0);
        let c = self.unknown_code();
        self.code[..n].fill(c);
        self.marked = CellBox::EMPTY;
        self.refresh_all_moves();
    }

    #[inline]
    fn unknown_code(&self) -> u8 {
        if self.unknown_blocked {
            CODE_BLOCKED
        } else {
            CODE_UNKNOWN
        }
    }

    #[inline]
    fn code_of(&self, i: usize) -> u8 {
        if self.near[i] > 0 {
            return CODE_BLOCKED;
        }
        let base = match self.class[i] {
            CLASS_FREE => CODE_FREE,
            CLASS_UNKNOWN => self.unknown_code(),
            _ => CODE_BLOCKED,
        };
        if base == CODE_BLOCKED {
            return CODE_BLOCKED;
        }
        let band = if self.near_turn[i] > 0 {
            BAND_NO_TURN
        } else if self.near_band[i] > 0 {
            BAND_NEAR
        } else {
            0
        };
        base + 2 * band
    }

    /// Adds `delta` (+1 or -1) to the counts under the discs centred on cell `i`, refreshing
    /// the step code of every cell whose counts change between zero and non-zero.
    fn stamp_disc(&mut self, i: usize, delta: i32) {
        let w = self.geometry.width as i32;
        let h = self.geometry.height as i32;
        let col = (i % self.geometry.width) as i32;
        let row = (i / self.geometry.width) as i32;
        let bump = |count: &mut u16| {
            let before = *count;
            *count = if delta > 0 {
                before.saturating_add(1)
            } else {
                before.saturating_sub(1)
            };
            (before == 0) != (*count == 0)
        };
        for k in 0..self.stencil_near_len {
            let [dc, dr] = self.stencil[k];
            let c = col + dc as i32;
            let r = row + dr as i32;
            if c < 0 || r < 0 || c >= w || r >= h {
                continue;
            }
            let j = (r * w + c) as usize;
            // Offsets are ordered inner band first: an offset counts in its own band and
            // every wider one.
            let mut changed = bump(&mut self.near_band[j]);
            if k < self.stencil_turn_len {
                changed |= bump(&mut self.near_turn[j]);
            }
            if k < self.stencil_len {
                changed |= bump(&mut self.near[j]);
            }
            if changed {
                self.set_code(j, self.code_of(j));
            }
        }
    }

    /// Adds `delta` (+1 or -1) to the counts under the discs centred on cell `i`, leaving the
    /// step codes to [`Deferred::finish`].
    fn bump_disc_deferred(&mut self, i: usize, delta: i32) {
        let (width, reach) = (self.geometry.width, self.stencil_reach);
        let (col, row) = (i % width, i / width);
        if col >= reach && row >= reach && col + reach < width && row + reach < self.geometry.height
        {
            // The whole disc on the grid: no bounds to test, one run of columns a row and band
            // (a loop the compiler turns into vector saturating adds).
            let bump = |counts: &mut [u16]| {
                if delta > 0 {
                    counts.iter_mut().for_each(|c| *c = c.saturating_add(1));
                } else {
                    counts.iter_mut().for_each(|c| *c = c.saturating_sub(1));
                }
            };
            let rows = 2 * reach + 1;
            for (k, spans) in self.row_spans[..rows].iter().enumerate() {
                let mid = (row + k - reach) * width + col;
                let [a0, a1, a2] = spans.map(|a| a as isize);
                let run = |a: isize| (mid as isize - a) as usize..(mid as isize + a + 1) as usize;
                if a2 >= 0 {
                    bump(&mut self.near_band[run(a2)]);
                }
                if a1 >= 0 {
                    bump(&mut self.near_turn[run(a1)]);
                }
                if a0 >= 0 {
                    bump(&mut self.near[run(a0)]);
                }
            }
            return;
        }
        let w = self.geometry.width as i32;
        let h = self.geometry.height as i32;
        let col = (i % self.geometry.width) as i32;
        let row = (i / self.geometry.width) as i32;
        let bump = |count: &mut u16| {
            *count = if delta > 0 {
                count.saturating_add(1)
            } else {
                count.saturating_sub(1)
            };
        };
        for k in 0..self.stencil_near_len {
            let [dc, dr] = self.stencil[k];
            let c = col + dc as i32;
            let r = row + dr as i32;
            if c < 0 || r < 0 || c >= w || r >= h {
                continue;
            }
            let j = (r * w + c) as usize;
            bump(&mut self.near_band[j]);
            if k < self.stencil_turn_len {
                bump(&mut self.near_turn[j]);
            }
            if k < self.stencil_len {
                bump(&mut self.near[j]);
            }
        }
    }

    /// Class changes to apply as one batch: pass the returned observer to the grid's updates,
    /// then call [`Deferred::finish`].
    pub(crate) fn deferred(&mut self) -> Deferred<'_, N> {
        Deferred {
            layer: self,
            changed: CellBox::EMPTY,
        }
    }

    /// Sets the step code of cell `i`; if the cell changes between blocked and passable,
    /// refreshes the move masks of its 3 x 3 neighbourhood.
    #[inline]
    fn set_code(&mut self, i: usize, code: u8) {
        let was_blocked = self.code[i] == CODE_BLOCKED;
        self.code[i] = code;
        if code != self.unknown_code() {
            let w = self.geometry.width;
            self.marked.include(i % w, i / w);
        }
        if was_blocked != (code == CODE_BLOCKED) {
            let w = self.geometry.width;
            let h = self.geometry.height;
            let (col, row) = (i % w, i / w);
            for r in row.saturating_sub(1)..(row + 2).min(h) {
                for c in col.saturating_sub(1)..(col + 2).min(w) {
                    self.moves[r * w + c] = self.moves_of(c, r);
                }
            }
        }
    }

    fn refresh_all_moves(&mut self) {
        let w = self.geometry.width;
        for r in 0..self.geometry.height {
            for c in 0..w {
                self.moves[r * w + c] = self.moves_of(c, r);
            }
        }
    }

    /// The move mask of cell (`col`, `row`) from the codes around it.
    fn moves_of(&self, col: usize, row: usize) -> u8 {
        let w = self.geometry.width as isize;
        let h = self.geometry.height as isize;
        let (col, row) = (col as isize, row as isize);
        let open = |dc: i8, dr: i8| {
            let (c, r) = (col + dc as isize, row + dr as isize);
            c >= 0 && r >= 0 && c < w && r < h && self.code[(r * w + c) as usize] != CODE_BLOCKED
        };
        if !open(0, 0) {
            return 0;
        }
        let mut mask = 0u8;
        for (k, &(dc, dr)) in MOVES.iter().enumerate() {
            let legal = open(dc, dr) && (dc == 0 || dr == 0 || (open(dc, 0) && open(0, dr)));
            mask |= (legal as u8) << k;
        }
        mask
    }

    /// Size and placement.
    #[inline]
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The configuration in force.
    pub fn config(&self) -> TraversabilityConfig {
        TraversabilityConfig {
            robot_radius_m: self.robot_radius_m,
            unknown_policy: if self.unknown_blocked {
                UnknownPolicy::Blocked
            } else {
                UnknownPolicy::Traversable {
                    cost_factor: self.unknown_cost_factor,
                }
            },
            bands: self.bands,
        }
    }

    /// Offsets (col, row) \[cells\] of the inflation disc, (0, 0) included.
    pub fn inflation_stencil(&self) -> &[[i16; 2]] {
        &self.stencil[..self.stencil_len]
    }

    /// Whether the robot may turn in place on the cell: passable, and outside the no-turn
    /// band. `false` outside the grid.
    #[inline]
    pub fn can_turn(&self, cell: Cell) -> bool {
        self.geometry.index(cell).is_some_and(|i| {
            let code = self.code[i];
            code != CODE_BLOCKED && band_of_code(code) != BAND_NO_TURN
        })
    }

    /// The wall band of the cell: 0 clear of walls, 1 near a wall, 2 where the robot cannot
    /// turn in place; `None` if blocked or outside the grid.
    #[inline]
    pub fn wall_band(&self, cell: Cell) -> Option<u8> {
        let i = self.geometry.index(cell)?;
        let code = self.code[i];
        (code != CODE_BLOCKED).then(|| band_of_code(code))
    }

    /// Whether the robot may stand on the cell; `false` outside the grid.
    #[inline]
    pub fn is_passable(&self, cell: Cell) -> bool {
        self.geometry
            .index(cell)
            .is_some_and(|i| self.code[i] != CODE_BLOCKED)
    }

    /// Whether the cell is within the robot radius of an Occupied cell (or Occupied itself).
    /// `false` outside the grid.
    pub fn is_inflated(&self, cell: Cell) -> bool {
        self.geometry.index(cell).is_some_and(|i| self.near[i] > 0)
    }

    /// Cost factor of entering the cell; `None` if blocked or outside the grid.
    pub fn cost_factor(&self, cell: Cell) -> Option<f32> {
        let i = self.geometry.index(cell)?;
        self.factor_of_code(self.code[i])
    }

    /// Occupied cells within the robot radius of the cell (itself included); `None` outside.
    pub fn obstacles_near(&self, cell: Cell) -> Option<u16> {
        self.geometry.index(cell).map(|i| self.near[i])
    }

    #[inline]
    pub(crate) fn factor_of_code(&self, code: u8) -> Option<f32> {
        (code != CODE_BLOCKED && (code as usize) < CODE_COUNT)
            .then(|| self.step_factors()[code as usize])
    }

    /// Cost factor by step code (index [`CODE_BLOCKED`] holds 0: never entered).
    #[inline]
    pub(crate) fn step_factors(&self) -> [f32; CODE_COUNT] {
        let u = self.unknown_cost_factor;
        let near = self.bands.near_cost_factor;
        let turn = self.bands.no_turn_cost_factor;
        [0.0, 1.0, u, near, u * near, turn, u * turn]
    }

    /// Step codes of the cells in use, flat-index order.
    #[inline]
    pub(crate) fn codes(&self) -> &[u8] {
        &self.code[..self.geometry.cell_count()]
    }

    /// Move masks of the cells in use, flat-index order (bit `k`: step [`MOVES`]`[k]` is
    /// legal).
    #[inline]
    pub(crate) fn move_masks(&self) -> &[u8] {
        &self.moves[..self.geometry.cell_count()]
    }

    /// Whether every legal step costs its plain length: every passable code's factor is 1.
    #[inline]
    pub(crate) fn uniform_costs(&self) -> bool {
        self.step_factors()[1..].iter().all(|&f| f == 1.0)
    }

    /// The largest cost factor of a passable cell (at least 1).
    #[inline]
    pub(crate) fn max_factor(&self) -> f32 {
        self.step_factors()[1..]
            .iter()
            .fold(1.0f32, |m, &f| m.max(f))
    }

    /// Checks that start and goal lie inside and are passable; returns their flat indices.
    pub(crate) fn check_endpoints(
        &self,
        start: Cell,
        goal: Cell,
    ) -> Result<(usize, usize), super::PlanError> {
        let g = &self.geometry;
        let out = |cell| super::PlanError::OutOfBounds {
            cell,
            width: g.width,
            height: g.height,
        };
        let s = g.index(start).ok_or_else(|| out(start))?;
        let t = g.index(goal).ok_or_else(|| out(goal))?;
        if self.code[s] == CODE_BLOCKED {
            return Err(super::PlanError::StartBlocked { cell: start });
        }
        if self.code[t] == CODE_BLOCKED {
            return Err(super::PlanError::GoalBlocked { cell: goal });
        }
        Ok((s, t))
    }

    /// How far \[cells\] a change of one cell's class reaches in this layer: the widest
    /// band's disc, plus one for the move masks around the cells whose code changes.
    pub(crate) fn change_reach_cells(&self) -> usize {
        let mut reach = 0usize;
        for &[dc, dr] in &self.stencil[..self.stencil_near_len] {
            reach = reach
                .max(dc.unsigned_abs() as usize)
                .max(dr.unsigned_abs() as usize);
        }
        reach + 1
    }

    /// Copies the per-cell state of the cells in `area` into `out`. `false` (nothing
    /// copied) when the area leaves the layer or does not fit in `out`.
    pub(crate) fn save_window<const C: usize>(
        &self,
        area: CellBox,
        out: &mut TravWindow<C>,
    ) -> bool {
        let w = self.geometry.width;
        let (Some(cols), Some(rows)) = (
            area.col_end.checked_sub(area.col_min),
            area.row_end.checked_sub(area.row_min),
        ) else {
            return false;
        };
        if area.col_end > w || area.row_end > self.geometry.height || cols * rows > C {
            return false;
        }
        for (k, row) in (area.row_min..area.row_end).enumerate() {
            let (from, to) = (row * w + area.col_min, k * cols);
            let (src, dst) = (from..from + cols, to..to + cols);
            out.class[dst.clone()].copy_from_slice(&self.class[src.clone()]);
            out.near[dst.clone()].copy_from_slice(&self.near[src.clone()]);
            out.near_turn[dst.clone()].copy_from_slice(&self.near_turn[src.clone()]);
            out.near_band[dst.clone()].copy_from_slice(&self.near_band[src.clone()]);
            out.code[dst.clone()].copy_from_slice(&self.code[src.clone()]);
            out.moves[dst].copy_from_slice(&self.moves[src]);
        }
        true
    }

    /// Puts back the cells of `area` saved by [`Self::save_window`]: the state undoing every
    /// class change since, cell by cell, would leave, provided every cell changed since lies
    /// in `area` shrunk by [`Self::change_reach_cells`]. The box of marked cells keeps what it
    /// grew by meanwhile (undoing cell by cell never shrinks it either).
    pub(crate) fn restore_window<const C: usize>(&mut self, area: CellBox, saved: &TravWindow<C>) {
        let w = self.geometry.width;
        let cols = area.col_end - area.col_min;
        for (k, row) in (area.row_min..area.row_end).enumerate() {
            let (to, from) = (row * w + area.col_min, k * cols);
            let (dst, src) = (to..to + cols, from..from + cols);
            self.class[dst.clone()].copy_from_slice(&saved.class[src.clone()]);
            self.near[dst.clone()].copy_from_slice(&saved.near[src.clone()]);
            self.near_turn[dst.clone()].copy_from_slice(&saved.near_turn[src.clone()]);
            self.near_band[dst.clone()].copy_from_slice(&saved.near_band[src.clone()]);
            self.code[dst.clone()].copy_from_slice(&saved.code[src.clone()]);
            self.moves[dst].copy_from_slice(&saved.moves[src]);
        }
    }

    /// Whether this layer's per-cell state equals `other`'s (same geometry, configuration and
    /// cells). Lets tests compare an incrementally updated layer with a rebuilt one.
    pub fn same_state(&self, other: &Self) -> bool {
        let n = self.geometry.cell_count();
        self.geometry == other.geometry
            && self.config() == other.config()
            && self.class[..n] == other.class[..n]
            && self.near[..n] == other.near[..n]
            && self.near_turn[..n] == other.near_turn[..n]
            && self.near_band[..n] == other.near_band[..n]
            && self.code[..n] == other.code[..n]
            && self.moves[..n] == other.moves[..n]
    }
}

/// A batch of class changes to a [`Traversability`] layer ([`Traversability::deferred`]):
/// classes and obstacle counts are updated as the grid reports the changes, the step codes
/// and move masks once per cell at [`Self::finish`], where updating cell by cell refreshes a
/// cell's code each time one of its counts changes between zero and non-zero. The cells end
/// as cell-by-cell updates leave them (codes and move masks are functions of the classes and
/// counts). The box of marked cells grows by the cells whose final code differs from the
/// Unknown cells'; cell by cell, it also grows by the cells whose code differs only in
/// between. The two agree when the batch only adds Occupied cells or only removes them (the
/// counts then move one way: a code away from the Unknown one in between is so at the start,
/// and the cell already marked, or at the end), which is how the missions use it.
/// Side of the largest region whose move masks [`Deferred::finish`] refreshes in one pass.
const DIRTY_SIDE: usize = 64;

pub(crate) struct Deferred<'a, const N: usize> {
    layer: &'a mut Traversability<N>,
    /// The cells whose class changed.
    changed: CellBox,
}

impl<const N: usize> Deferred<'_, N> {
    /// Refreshes the step codes (and, where a cell changes between blocked and passable, the
    /// move masks around it) of the cells the batch can have changed.
    pub(crate) fn finish(self) {
        let layer = self.layer;
        let c = self.changed;
        if c.is_empty() {
            return;
        }
        let reach = layer.change_reach_cells() - 1;
        let (w, h) = (layer.geometry.width, layer.geometry.height);
        let (r0, r1) = (c.row_min.saturating_sub(reach), (c.row_end + reach).min(h));
        let (c0, c1) = (c.col_min.saturating_sub(reach), (c.col_end + reach).min(w));
        // The move masks to refresh, one bit a cell of the region grown by one; a larger
        // region refreshes them cell by cell.
        let (g_r0, g_c0) = (r0.saturating_sub(1), c0.saturating_sub(1));
        let (g_r1, g_c1) = ((r1 + 1).min(h), (c1 + 1).min(w));
        if g_r1 - g_r0 > DIRTY_SIDE || g_c1 - g_c0 > DIRTY_SIDE {
            for row in r0..r1 {
                for col in c0..c1 {
                    let j = row * w + col;
                    let code = layer.code_of(j);
                    if code != layer.code[j] {
                        layer.set_code(j, code);
                    }
                }
            }
            return;
        }
        let mut dirty = [0u64; DIRTY_SIDE];
        let plain = layer.unknown_code();
        for row in r0..r1 {
            for col in c0..c1 {
                let j = row * w + col;
                let code = layer.code_of(j);
                let old = layer.code[j];
                if code == old {
                    continue;
                }
                layer.code[j] = code;
                if code != plain {
                    layer.marked.include(col, row);
                }
                if (old == CODE_BLOCKED) != (code == CODE_BLOCKED) {
                    let (lo, hi) = (col.saturating_sub(1).max(g_c0), (col + 2).min(g_c1));
                    let bits = ((1u64 << (hi - lo)) - 1) << (lo - g_c0);
                    for r in row.saturating_sub(1).max(g_r0)..(row + 2).min(g_r1) {
                        dirty[r - g_r0] |= bits;
                    }
                }
            }
        }
        for (k, &bits) in dirty.iter().enumerate().take(g_r1 - g_r0) {
            let mut bits = bits;
            while bits != 0 {
                let col = g_c0 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let row = g_r0 + k;
                layer.moves[row * w + col] = layer.moves_of(col, row);
            }
        }
    }
}

impl<const N: usize> CellObserver for Deferred<'_, N> {
    fn class_changed(&mut self, index: usize, old: CellClass, new: CellClass) {
        let layer = &mut *self.layer;
        if index >= layer.geometry.cell_count() {
            return;
        }
        let _ = old;
        let was_occupied = layer.class[index] == CLASS_OCCUPIED;
        layer.class[index] = class_code(new);
        let is_occupied = new == CellClass::Occupied;
        if was_occupied != is_occupied {
            layer.bump_disc_deferred(index, if is_occupied { 1 } else { -1 });
        }
        let w = layer.geometry.width;
        self.changed.include(index % w, index / w);
    }
}

/// A saved rectangle of a [`Traversability`] layer's per-cell state, up to `C` cells
/// ([`Traversability::save_window`]).
#[derive(Clone, bytemuck::Zeroable)]
pub(crate) struct TravWindow<const C: usize> {
    class: [u8; C],
    near: [u16; C],
    near_turn: [u16; C],
    near_band: [u16; C],
    code: [u8; C],
    moves: [u8; C],
}

impl<const C: usize> TravWindow<C> {
    /// All zero, built on the stack (or in a `static`).
    pub(crate) const fn new() -> Self {
        Self {
            class: [0; C],
            near: [0; C],
            near_turn: [0; C],
            near_band: [0; C],
            code: [0; C],
            moves: [0; C],
        }
    }
}

fn class_code(c: CellClass) -> u8 {
    match c {
        CellClass::Free => CLASS_FREE,
        CellClass::Unknown => CLASS_UNKNOWN,
        CellClass::Occupied => CLASS_OCCUPIED,
    }
}

impl<const N: usize> CellObserver for Traversability<N> {
    /// Updates the cell's class and, if it became or stopped being Occupied, the inflation
    /// counts around it. Indices outside the layer's geometry are ignored (the layer must be
    /// loaded from the same grid with [`Traversability::rebuild_from`]).
    fn class_changed(&mut self, index: usize, old: CellClass, new: CellClass) {
        if index >= self.geometry.cell_count() {
            return;
        }
        let _ = old;
        let was_occupied = self.class[index] == CLASS_OCCUPIED;
        self.class[index] = class_code(new);
        let is_occupied = new == CellClass::Occupied;
        if was_occupied && !is_occupied {
            self.stamp_disc(index, -1);
        } else if is_occupied && !was_occupied {
            self.stamp_disc(index, 1);
        }
        self.set_code(index, self.code_of(index));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point2;
    use crate::grid::LogOddsBounds;
    use crate::random;

    const CAP: usize = 40 * 30;

    fn geometry() -> GridGeometry {
        GridGeometry::new(40, 30, 0.1, Point2::new(-1.0, 2.0)).unwrap()
    }

    #[test]
    fn p3dx_disc_blocks_cells_closer_than_the_radius() {
        let g = geometry();
        let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
        let mut t = Traversability::<CAP>::new(g, TraversabilityConfig::default()).unwrap();
        let centre = g.index(Cell::new(20, 15)).unwrap();
        grid.set_class(centre, CellClass::Occupied, &mut t);
        // 0.25 m at 0.1 m cells: offsets with dc^2 + dr^2 < 6.25.
        assert_eq!(t.inflation_stencil().len(), 21);
        for dr in -4i32..=4 {
            for dc in -4i32..=4 {
                let cell = Cell::new(20 + dc, 15 + dr);
                let expect = dc * dc + dr * dr <= 6;
                assert_eq!(t.is_inflated(cell), expect, "offset ({dc}, {dr})");
                assert_eq!(!t.is_passable(cell), expect, "offset ({dc}, {dr})");
            }
        }
        grid.set_class(centre, CellClass::Free, &mut t);
        assert!(t.is_passable(Cell::new(20, 15)));
        assert!(t.is_passable(Cell::new(21, 15)));
        assert_eq!(t.cost_factor(Cell::new(20, 15)), Some(1.0));
        assert_eq!(t.cost_factor(Cell::new(0, 0)), Some(1.0));
    }

    #[test]
    fn unknown_policy_decides_unknown_cells() {
        let g = geometry();
        let strict = TraversabilityConfig {
            robot_radius_m: 0.0,
            unknown_policy: UnknownPolicy::Blocked,
            bands: WallBands::NONE,
        };
        let t = Traversability::<CAP>::new(g, strict).unwrap();
        assert!(!t.is_passable(Cell::new(3, 3)));
        let lax = TraversabilityConfig {
            robot_radius_m: 0.0,
            unknown_policy: UnknownPolicy::Traversable { cost_factor: 2.5 },
            bands: WallBands::NONE,
        };
        let t = Traversability::<CAP>::new(g, lax).unwrap();
        assert_eq!(t.cost_factor(Cell::new(3, 3)), Some(2.5));
        assert_eq!(t.cost_factor(Cell::new(-1, 3)), None);
    }

    #[test]
    fn bad_configuration_is_refused() {
        let g = geometry();
        let cfg = |r, f| TraversabilityConfig {
            robot_radius_m: r,
            unknown_policy: UnknownPolicy::Traversable { cost_factor: f },
            bands: WallBands::NONE,
        };
        assert_eq!(
            Traversability::<CAP>::new(g, cfg(-0.1, 1.0)).unwrap_err(),
            TraversabilityError::BadRadius(-0.1)
        );
        assert_eq!(
            Traversability::<CAP>::new(g, cfg(0.2, 0.5)).unwrap_err(),
            TraversabilityError::BadCostFactor(0.5)
        );
        assert!(matches!(
            Traversability::<CAP>::new(g, cfg(5.0, 1.0)).unwrap_err(),
            TraversabilityError::InflationTooLarge { .. }
        ));
        // The same checks without a layer: a radius of a million cells is refused before
        // its disc is walked, and so is a cell size that is no size.
        assert_eq!(cfg(0.2, 1.0).check(0.1), Ok(()));
        for res in [1e-6, f32::MIN_POSITIVE] {
            assert!(matches!(
                cfg(0.2, 1.0).check(res).unwrap_err(),
                TraversabilityError::InflationTooLarge { .. }
            ));
        }
        for res in [0.0, -0.1, f32::NAN] {
            assert!(matches!(
                cfg(0.2, 1.0).check(res).unwrap_err(),
                TraversabilityError::BadResolution(_)
            ));
        }
        assert_eq!(
            Traversability::<100>::new(g, cfg(0.2, 1.0)).unwrap_err(),
            TraversabilityError::CapacityExceeded {
                needed: CAP,
                capacity: 100
            }
        );
    }

    /// Cells within `r` cells of (`col`, `row`) inside the grid, and the box holding them.
    fn disc(g: &GridGeometry, col: i32, row: i32, r: i32) -> (heapless::Vec<usize, 256>, CellBox) {
        let mut cells = heapless::Vec::new();
        let mut area = CellBox::EMPTY;
        for dr in -r..=r {
            for dc in -r..=r {
                if dc * dc + dr * dr > r * r {
                    continue;
                }
                if let Some(i) = g.index(Cell::new(col + dc, row + dr)) {
                    cells.push(i).unwrap();
                    area.include(i % g.width, i / g.width);
                }
            }
        }
        (cells, area)
    }

    /// The mission's lift-and-stamp (`mission/machine/robots.rs`): Occupied cells of one disc
    /// set to weak Free in one batch, then non-Occupied cells of two discs set Occupied, one
    /// batch per disc; then everything put back by copying a saved window. Cells, class
    /// counts and the known and marked boxes equal those of the same changes made and undone
    /// cell by cell, on random maps, with wall bands, under both Unknown policies.
    #[test]
    fn batches_and_window_restore_equal_cell_by_cell() {
        let g = geometry();
        let mut rng = random::seeded(24);
        let bands = WallBands {
            no_turn_radius_m: 0.35,
            no_turn_cost_factor: 2.0,
            near_radius_m: 0.55,
            near_cost_factor: 1.5,
        };
        for policy in [
            UnknownPolicy::Traversable { cost_factor: 1.5 },
            UnknownPolicy::Blocked,
        ] {
            let config = TraversabilityConfig {
                robot_radius_m: 0.25,
                unknown_policy: policy,
                bands,
            };
            for trial in 0..40 {
                let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
                let mut t = Traversability::<CAP>::new(g, config).unwrap();
                // A random map, sparse or dense, some of it still Unknown.
                let fills = 50 + random::below(&mut rng, 1500);
                for _ in 0..fills {
                    let i = random::below(&mut rng, g.cell_count());
                    let l = random::range_f32(&mut rng, -2.0, 2.0);
                    grid.set_log_odds(i, l, &mut t);
                }
                let (w, h) = (g.width as i32, g.height as i32);
                let at = |rng: &mut _| {
                    (
                        random::below(rng, w as usize + 4) as i32 - 2,
                        random::below(rng, h as usize + 4) as i32 - 2,
                    )
                };
                let (body, mut area) = {
                    let (c, r) = at(&mut rng);
                    disc(&g, c, r, 4)
                };
                let others = [at(&mut rng), at(&mut rng)].map(|(c, r)| disc(&g, c, r, 3));
                for (_, b) in &others {
                    if !b.is_empty() {
                        area.include(b.col_min, b.row_min);
                        area.include(b.col_end - 1, b.row_end - 1);
                    }
                }
                let grow = t.change_reach_cells();
                let area = CellBox {
                    col_min: area.col_min.saturating_sub(grow),
                    col_end: (area.col_end + grow).min(g.width),
                    row_min: area.row_min.saturating_sub(grow),
                    row_end: (area.row_end + grow).min(g.height),
                };
                let (mut grid_b, mut t_b) = (grid.clone(), t.clone());
                let mut saved_log_odds = [0.0f32; CAP];
                let mut saved_cells = TravWindow::<CAP>::new();
                let counts = grid_b.save_window(area, &mut saved_log_odds).unwrap();
                assert!(t_b.save_window(area, &mut saved_cells));

                // Cell by cell.
                let mut undo: heapless::Vec<(usize, f32), 512> = heapless::Vec::new();
                for &i in &body {
                    if grid.class(i) == CellClass::Occupied {
                        undo.push((i, grid.log_odds_at(i))).unwrap();
                        grid.set_log_odds(i, -0.4, &mut t);
                    }
                }
                for (cells, _) in &others {
                    for &i in cells {
                        if grid.class(i) != CellClass::Occupied {
                            undo.push((i, grid.log_odds_at(i))).unwrap();
                            grid.set_log_odds(i, 3.5, &mut t);
                        }
                    }
                }
                // In batches.
                let mut batch = t_b.deferred();
                for &i in &body {
                    if grid_b.class(i) == CellClass::Occupied {
                        grid_b.set_log_odds(i, -0.4, &mut batch);
                    }
                }
                batch.finish();
                for (cells, _) in &others {
                    let mut batch = t_b.deferred();
                    for &i in cells {
                        if grid_b.class(i) != CellClass::Occupied {
                            grid_b.set_log_odds(i, 3.5, &mut batch);
                        }
                    }
                    batch.finish();
                }
                let why = format!("{policy:?}, trial {trial}");
                assert!(t_b.same_state(&t), "after the batches: {why}");
                assert_eq!(t_b.marked_box(), t.marked_box(), "{why}");
                assert_eq!(grid_b.log_odds(), grid.log_odds(), "{why}");
                assert_eq!(grid_b.counts(), grid.counts(), "{why}");

                for &(i, l) in undo.iter().rev() {
                    grid.set_log_odds(i, l, &mut t);
                }
                grid_b.restore_window(area, &saved_log_odds, counts);
                t_b.restore_window(area, &saved_cells);
                assert!(t_b.same_state(&t), "after the restore: {why}");
                assert_eq!(t_b.marked_box(), t.marked_box(), "{why}");
                assert_eq!(grid_b.log_odds(), grid.log_odds(), "{why}");
                assert_eq!(grid_b.counts(), grid.counts(), "{why}");
                assert_eq!(grid_b.known_box(), grid.known_box(), "{why}");
            }
        }
    }

    #[test]
    fn incremental_updates_equal_a_rebuild() {
        let g = geometry();
        let mut rng = random::seeded(11);
        for (radius, policy) in [
            (0.25, UnknownPolicy::Traversable { cost_factor: 1.5 }),
            (0.0, UnknownPolicy::Blocked),
            (0.42, UnknownPolicy::Blocked),
        ] {
            let config = TraversabilityConfig {
                robot_radius_m: radius,
                unknown_policy: policy,
                bands: WallBands::NONE,
            };
            let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
            let mut t = Traversability::<CAP>::new(g, config).unwrap();
            for step in 0..20_000 {
                let i = random::below(&mut rng, g.cell_count());
                match random::below(&mut rng, 4) {
                    0 => {
                        grid.add_evidence(i, random::range_f32(&mut rng, -1.0, 1.0), &mut t);
                    }
                    1 => {
                        grid.set_log_odds(i, 0.0, &mut t);
                    }
                    2 => {
                        grid.set_class(i, CellClass::Occupied, &mut t);
                    }
                    _ => {
                        grid.set_class(i, CellClass::Free, &mut t);
                    }
                }
                if step % 2000 == 1999 {
                    let mut fresh = Traversability::<CAP>::new(g, config).unwrap();
                    fresh.rebuild_from(&grid).unwrap();
                    assert!(t.same_state(&fresh), "radius {radius}, step {step}");
                }
            }
        }
    }

    #[test]
    fn from_blocked_marks_exactly_the_walls() {
        let t = Traversability::<64>::from_blocked(8, 8, |c| c.col == 3 && c.row != 5).unwrap();
        for row in 0..8 {
            for col in 0..8 {
                let c = Cell::new(col, row);
                assert_eq!(t.is_passable(c), !(col == 3 && row != 5));
            }
        }
        assert_eq!(t.geometry().resolution_m, 1.0);
    }
}
