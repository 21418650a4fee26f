//! Visibility of the predicted scans, computed once per viewpoint and cached within a decision.
//!
//! **Model** (the objective's [cached model](super::objective#speed)): a predicted scan is taken
//! from the centre of the cell holding the laser, and its beams follow `M = round(2π / step)`
//! fixed directions `j · 2π / M` (for the thesis laser, 1° apart, so a beam's direction is its
//! true direction rounded to the nearest degree). Along each direction the cells a segment of
//! the usable range from a cell centre crosses are listed once ("templates", computed with the
//! exact traversal of [`crate::raycast`]: Amanatides & Woo, "A Fast Voxel Traversal Algorithm
//! for Ray Tracing", Eurographics 1987). A beam walks its template from the viewpoint's cell,
//! stops at the first Occupied cell or at the grid edge, crosses Free and Unknown cells, and
//! sees the Unknown cells it crosses, as in the traced model.
//!
//! **Representation**: the Unknown cells one viewpoint (cell, direction of its first beam)
//! sees are stored as a window of `2R + 1` rows of 128 bits centred on its cell (`R` the range
//! in cells, at most [`MAX_VIEW_RADIUS_CELLS`]), with the rows where it sees nothing at either
//! end noted so as to skip them. A candidate's gain is the population count of the bitwise OR
//! of its viewpoints' windows in a grid-sized bit set, so a cell seen from several viewpoints
//! counts once (the "bitmap" union of classic visibility-based coverage planners; here it
//! replaces per-cell generation stamps).
//!
//! **Bit sheets**: the grid's Unknown and Occupied cells and the union are bit sets laid out
//! row by row with a whole number of 64-bit words per row and a margin of zero bits (one word
//! west of column 0, at least two east of the last column, [`SHEET_MARGIN_ROWS`] rows south
//! and north). A window then starts at the same word and bit offset in every one of its rows,
//! and never reaches past the sheet: a window row is three word reads and a shift, with no
//! test for the grid's edges (cells off the grid read as neither Unknown nor Occupied).
//!
//! **Fast case**: when no Occupied cell lies among the cells the fan's templates cover, no beam
//! is stopped, and the window is the fan's cells (precomputed per direction) AND the grid's
//! Unknown cells, a few word operations per row instead of a walk.
//!
//! **Beam walk** (otherwise), with two shortcuts that give the same cells: a group of
//! [`SECTOR_BEAMS`] consecutive beams whose templates (their "sector", precomputed per
//! direction) meet no Occupied cell passes all its cells at once; and a beam is walked only
//! from the first cell where its template leaves the previous beam's (if the previous beam
//! stopped before that cell, this one stops at the same cell and reaches nothing new). The
//! cells the beams pass, AND the Unknown cells, are the window.
//!
//! **Cache**: an open-addressing table keyed by (cell, direction), cleared in O(1) per decision
//! by a generation number. When the table or its arena is full, a window is computed into
//! scratch space and used without being stored: the same result, only slower. Nothing is
//! allocated; every capacity is a constant (16.7 MB in all, built on the heap by
//! [`ViewCache::new_boxed`] on a host).
//!
//! The cache also carries the decision's [`BlockedBoxes`], with which the objective prunes
//! its paths to waypoints without walking every line of sight (same waypoints), and the legs
//! it planned ([`super::leg_memo`]).

use crate::geometry::{Point2, Pose2};
use crate::grid::{Cell, GridGeometry, OccupancyGrid};
use crate::math;
use crate::planner::BlockedBoxes;
use crate::raycast;
use crate::sensor::{LaserConfig, MAX_BEAMS};

use super::leg_memo::{DECISION_LEG_SLOTS, LegMemo};

/// Largest usable range the cache handles \[cells\] (a window row is 128 bits wide).
pub const MAX_VIEW_RADIUS_CELLS: usize = 63;
/// Most beam directions (`round(2π / step)`; 1440 = a quarter of a degree).
pub const MAX_DIRECTIONS: usize = 1440;
/// Most template cells over all directions.
pub const MAX_TEMPLATE_CELLS: usize = 1 << 16;
/// Rows of the per-direction fan windows (all directions' windows together).
pub const FAN_ROWS: usize = 1 << 16;
/// Most cached viewpoints per decision.
pub const MAX_VIEWS: usize = 8192;
/// Rows of the cached viewpoint windows (all viewpoints together; 8 MB).
pub const VIEW_ROWS: usize = 1 << 19;
/// Largest grid the cache handles \[cells\].
pub const MAX_GRID_CELLS: usize = 1 << 20;
/// Words of each bit sheet: a grid of `width` x `height` cells takes
/// `(height + 2 * SHEET_MARGIN_ROWS) * (width.div_ceil(64) + 3)` (2 576 for a 240 x 240 grid,
/// 21 888 for 1024 x 1024).
pub const SHEET_WORDS: usize = 1 << 15;
/// Rows of zero bits south and north of the grid in a bit sheet (at least the view radius).
pub const SHEET_MARGIN_ROWS: usize = 64;

/// Consecutive beams whose templates are tested together in a beam walk.
pub const SECTOR_BEAMS: usize = 8;
/// Rows of the per-direction sector windows (all directions' together; 1 MB).
pub const SECTOR_ROWS: usize = 1 << 16;

const MAX_WINDOW_ROWS: usize = 2 * MAX_VIEW_RADIUS_CELLS + 1;
/// Viewpoints whose table slots a gain reads ahead at once.
const GAIN_BATCH: usize = 32;
const TABLE_SLOTS: usize = 2 * MAX_VIEWS;
/// Rows `[first, last]` of a window holding its non-zero rows (`first > last`: none).
type Extent = [u8; 2];
const NO_ROWS: Extent = [1, 0];

/// Counters of the current decision.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct ViewCacheStats {
    /// Viewpoints found in the cache.
    pub hits: u32,
    /// Viewpoints computed and stored.
    pub misses: u32,
    /// Viewpoints computed without being stored (cache full).
    pub overflows: u32,
    /// Computed viewpoints whose fan met no Occupied cell (word operations only).
    pub unobstructed: u32,
}

#[derive(Clone, Copy, bytemuck::Zeroable)]
struct Slot {
    generation: u32,
    cell: u32,
    direction: u32,
    entry: u32,
}

/// The laser and resolution the templates were built for.
#[derive(Clone, Copy, PartialEq, bytemuck::Zeroable)]
struct TemplateKey {
    beam_count: u16,
    first_angle_rad: f32,
    step_rad: f32,
    max_range_m: f32,
    resolution_m: f32,
}

/// Where a viewpoint's window lives.
#[derive(Clone, Copy)]
enum Window {
    Entry(usize),
    Scratch,
}

/// Per-decision visibility cache of predicted scans; see the [module documentation](self).
#[derive(bytemuck::Zeroable)]
pub struct ViewCache {
    // Templates: depend on the laser and the resolution only, kept across decisions.
    key: TemplateKey,
    templates_ok: bool,
    directions: usize,
    radius: usize,
    rows: usize,
    beams: usize,
    beam_direction: [u16; MAX_BEAMS],
    template: [[i8; 2]; MAX_TEMPLATE_CELLS],
    /// Per template cell: its window word (`2 * row + half`) times 256 plus its bit in that
    /// word, for the walk.
    template_spot: [u16; MAX_TEMPLATE_CELLS],
    template_start: [u32; MAX_DIRECTIONS + 1],
    /// Per direction `j`: how many first cells its template shares with direction `j + 1`'s.
    shared_prefix: [u16; MAX_DIRECTIONS],
    fan_ready: [bool; MAX_DIRECTIONS],
    fans: [u128; FAN_ROWS],
    /// Per direction `j`: the cells of the templates of directions `j` to
    /// `j + SECTOR_BEAMS - 1` (at `sectors[j * rows..]`), and the rows they cover.
    sectors_ready: bool,
    sectors: [u128; SECTOR_ROWS],
    sector_rows: [Extent; MAX_DIRECTIONS],
    /// Per group of [`SECTOR_BEAMS`] beams: whether their directions are consecutive.
    group_consecutive: [bool; MAX_BEAMS / SECTOR_BEAMS + 1],
    // The decision's grid, as bit sheets of `stride` words per row.
    ready: bool,
    geometry: GridGeometry,
    stride: usize,
    unknown: [u64; SHEET_WORDS],
    occupied: [u64; SHEET_WORDS],
    union: [u64; SHEET_WORDS],
    // The cache.
    generation: u32,
    table: [Slot; TABLE_SLOTS],
    entries: usize,
    entry_limit: usize,
    /// Windows the arena holds (`VIEW_ROWS / rows`, at most [`MAX_VIEWS`]).
    arena_views: usize,
    views: [u128; VIEW_ROWS],
    extents: [Extent; MAX_VIEWS],
    scratch: [u128; MAX_WINDOW_ROWS],
    scratch_extent: Extent,
    stats: ViewCacheStats,
    /// Blocked-cell counts of the decision's traversability layer.
    pub(crate) boxes: BlockedBoxes,
    /// The legs the decision planned (the objective clears it per decision).
    pub(crate) legs: LegMemo<DECISION_LEG_SLOTS>,
}

impl core::fmt::Debug for ViewCache {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ViewCache")
            .field("ready", &self.ready)
            .field("directions", &self.directions)
            .field("radius", &self.radius)
            .field("entries", &self.entries)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// Bits `shift..shift + 64` (`shift` below 64) of the 128-bit number `hi:lo` (one
/// double-width shift).
#[inline(always)]
fn shift_down(hi: u64, lo: u64, shift: u32) -> u64 {
    (((hi as u128) << 64 | lo as u128) >> (shift & 63)) as u64
}

/// Bits `64 - shift..128 - shift` (`shift` below 64) of the 128-bit number `hi:lo` (one
/// double-width shift).
#[inline(always)]
fn shift_up(hi: u64, lo: u64, shift: u32) -> u64 {
    ((((hi as u128) << 64 | lo as u128) << (shift & 63)) >> 64) as u64
}

/// The 128 bits of a bit sheet from bit `shift` (below 64) of word `at` on (the sheet must
/// hold the words `at` to `at + 2`).
#[inline(always)]
fn read128(sheet: &[u64], at: usize, shift: u32) -> u128 {
    let w = &sheet[at..at + 3];
    let (lo, hi) = (shift_down(w[1], w[0], shift), shift_down(w[2], w[1], shift));
    lo as u128 | (hi as u128) << 64
}

/// ORs `v` into a bit sheet from bit `shift` (below 64) of word `at` on (the sheet must hold
/// the words `at` to `at + 2`).
#[inline(always)]
fn or128(sheet: &mut [u64], at: usize, shift: u32, v: u128) {
    let (lo, hi) = (v as u64, (v >> 64) as u64);
    let w = &mut sheet[at..at + 3];
    if shift == 0 {
        w[0] |= lo;
        w[1] |= hi;
    } else {
        w[0] |= lo << (shift & 63);
        w[1] |= shift_up(hi, lo, shift);
        w[2] |= hi >> (64 - shift);
    }
}

/// The Unknown and the Occupied cells among eight log-odds, as bits 0 to 7
/// ([`crate::grid::LogOddsBounds::class_of`] with the Occupied threshold `occupied_above`,
/// without branches, which vector compares serve).
#[inline(always)]
fn classes_of_eight(l: &[f32; 8], occupied_above: f32) -> (u64, u64) {
    let (mut unknown, mut occupied) = (0u64, 0u64);
    for (b, &l) in l.iter().enumerate() {
        unknown |= ((l == 0.0 || l.is_nan()) as u64) << b;
        occupied |= ((l > occupied_above) as u64) << b;
    }
    (unknown, occupied)
}

/// The window of a viewpoint whose fan (`fan`, one 128-bit row per window row) meets no
/// Occupied cell: its fan's Unknown cells, written into `window`. `occupied` and `unknown` are
/// the bit sheets from the window's first word on (`stride` words per row, the window at bit
/// `shift`). Returns `false`, leaving `window` partly written, if the fan meets an Occupied
/// cell.
#[inline(always)]
fn fan_window(
    occupied: &[u64],
    unknown: &[u64],
    stride: usize,
    shift: u32,
    fan: &[u128],
    window: &mut [u128],
) -> bool {
    for (k, (out, &cover)) in window.iter_mut().zip(fan).enumerate() {
        let at = k * stride;
        if read128(occupied, at, shift) & cover != 0 {
            return false;
        }
        *out = read128(unknown, at, shift) & cover;
    }
    true
}

/// The first and last non-empty rows of a window.
#[inline]
fn extent_of(window: &[u128]) -> Extent {
    match window.iter().position(|&b| b != 0) {
        Some(first) => {
            let last = window.iter().rposition(|&b| b != 0).unwrap_or(first);
            [first as u8, last as u8]
        }
        None => NO_ROWS,
    }
}

impl Default for ViewCache {
    fn default() -> Self {
        Self::new()
    }
}

const EMPTY_SLOT: Slot = Slot {
    generation: 0,
    cell: 0,
    direction: 0,
    entry: 0,
};

impl ViewCache {
    /// An empty cache, for a `static` without an allocator (16.7 MB: on a host prefer
    /// [`Self::new_boxed`]).
    pub const fn new() -> Self {
        Self {
            key: TemplateKey {
                beam_count: 0,
                first_angle_rad: 0.0,
                step_rad: 0.0,
                max_range_m: 0.0,
                resolution_m: 0.0,
            },
            templates_ok: false,
            directions: 0,
            radius: 0,
            rows: 0,
            beams: 0,
            beam_direction: [0; MAX_BEAMS],
            template: [[0; 2]; MAX_TEMPLATE_CELLS],
            template_spot: [0; MAX_TEMPLATE_CELLS],
            template_start: [0; MAX_DIRECTIONS + 1],
            shared_prefix: [0; MAX_DIRECTIONS],
            fan_ready: [false; MAX_DIRECTIONS],
            fans: [0; FAN_ROWS],
            sectors_ready: false,
            sectors: [0; SECTOR_ROWS],
            sector_rows: [NO_ROWS; MAX_DIRECTIONS],
            group_consecutive: [false; MAX_BEAMS / SECTOR_BEAMS + 1],
            ready: false,
            geometry: GridGeometry {
                width: 0,
                height: 0,
                resolution_m: 0.0,
                origin: Point2::new(0.0, 0.0),
            },
            stride: 0,
            unknown: [0; SHEET_WORDS],
            occupied: [0; SHEET_WORDS],
            union: [0; SHEET_WORDS],
            generation: 0,
            table: [EMPTY_SLOT; TABLE_SLOTS],
            entries: 0,
            entry_limit: MAX_VIEWS,
            arena_views: 0,
            views: [0; VIEW_ROWS],
            extents: [NO_ROWS; MAX_VIEWS],
            scratch: [0; MAX_WINDOW_ROWS],
            scratch_extent: NO_ROWS,
            stats: ViewCacheStats {
                hits: 0,
                misses: 0,
                overflows: 0,
                unobstructed: 0,
            },
            boxes: BlockedBoxes::new(),
            legs: LegMemo::new(),
        }
    }

    /// An empty cache built directly on the heap (16.7 MB).
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        let mut cache = crate::heap::boxed_zeroed::<Self>();
        cache.entry_limit = MAX_VIEWS;
        cache
    }

    /// Caps the number of viewpoints stored per decision (at most [`MAX_VIEWS`]); further
    /// viewpoints are computed without being stored. For memory-bounded runs and tests.
    pub fn set_entry_limit(&mut self, limit: usize) {
        self.entry_limit = limit.min(MAX_VIEWS);
    }

    /// Counters of the current decision.
    pub fn stats(&self) -> ViewCacheStats {
        self.stats
    }

    /// Starts a decision on `grid` seen by `laser`. Returns `false` when the cached model
    /// cannot serve this grid or laser (range above [`MAX_VIEW_RADIUS_CELLS`], more than
    /// [`MAX_DIRECTIONS`] directions or [`MAX_BEAMS`] beams, templates over
    /// [`MAX_TEMPLATE_CELLS`], grid over [`MAX_GRID_CELLS`] or its bit sheets over
    /// [`SHEET_WORDS`]); the objective then traces the beams instead.
    pub(crate) fn begin<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        laser: &LaserConfig,
    ) -> bool {
        self.ready = false;
        self.stats = ViewCacheStats::default();
        let geometry = *grid.geometry();
        let cells = geometry.cell_count();
        if cells > MAX_GRID_CELLS {
            return false;
        }
        let key = TemplateKey {
            beam_count: laser.beam_count,
            first_angle_rad: laser.first_angle_rad,
            step_rad: laser.step_rad,
            max_range_m: laser.max_range_m,
            resolution_m: geometry.resolution_m,
        };
        if key != self.key {
            self.key = key;
            self.templates_ok = self.build_templates(laser, geometry.resolution_m);
        }
        if !self.templates_ok {
            return false;
        }
        let (w, h) = (geometry.width, geometry.height);
        let stride = w.div_ceil(64) + 3;
        let words = (h + 2 * SHEET_MARGIN_ROWS) * stride;
        if words > SHEET_WORDS {
            return false;
        }
        self.unknown[..words].fill(0);
        self.occupied[..words].fill(0);
        self.union[..words].fill(0);
        // Column c of row r is bit c % 64 of word `(r + margin) * stride + 1 + c / 64`.
        // Outside the grid's known box every cell is Unknown: its words are set without
        // reading the cells, so the pass costs what the explored region holds plus one word
        // per 64 cells.
        let log_odds = grid.log_odds();
        let occupied_above = grid.bounds().occupied_above;
        let known = grid.known_box();
        for r in 0..h {
            let at = (r + SHEET_MARGIN_ROWS) * stride + 1;
            let known_row = (known.row_min..known.row_end).contains(&r);
            for (i, run) in log_odds[r * w..(r + 1) * w].chunks(64).enumerate() {
                let first = 64 * i;
                if !known_row || first + run.len() <= known.col_min || first >= known.col_end {
                    self.unknown[at + i] = u64::MAX >> (64 - run.len());
                    continue;
                }
                let (mut unknown, mut occupied) = (0u64, 0u64);
                let eights = run.chunks_exact(8);
                let tail = eights.remainder();
                for (k, eight) in eights.enumerate() {
                    let (u, o) =
                        classes_of_eight(eight.try_into().unwrap_or(&[0.0; 8]), occupied_above);
                    unknown |= u << (8 * k);
                    occupied |= o << (8 * k);
                }
                for (b, &l) in tail.iter().enumerate() {
                    let b = run.len() - tail.len() + b;
                    unknown |= ((l == 0.0 || l.is_nan()) as u64) << b;
                    occupied |= ((l > occupied_above) as u64) << b;
                }
                self.unknown[at + i] = unknown;
                self.occupied[at + i] = occupied;
            }
        }
        self.stride = stride;
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            for s in self.table.iter_mut() {
                s.generation = 0;
            }
            self.generation = 1;
        }
        self.entries = 0;
        self.geometry = geometry;
        self.ready = true;
        true
    }

    /// Lists each direction's template cells; `false` if the laser does not fit.
    fn build_templates(&mut self, laser: &LaserConfig, resolution_m: f32) -> bool {
        self.directions = 0;
        self.fan_ready = [false; MAX_DIRECTIONS];
        let tau = 2.0 * core::f32::consts::PI;
        let len = laser.max_range_m / resolution_m;
        let beams = laser.beam_count as usize;
        if !(len.is_finite() && len > 0.0 && laser.step_rad.is_finite() && laser.step_rad > 0.0)
            || beams == 0
            || beams > MAX_BEAMS
            || len > MAX_VIEW_RADIUS_CELLS as f32 - 1.0
        {
            return false;
        }
        let m = math::round(tau / laser.step_rad) as usize;
        if m == 0 || m > MAX_DIRECTIONS {
            return false;
        }
        let delta = tau / m as f32;
        for b in 0..beams {
            let d = math::round(b as f32 * laser.step_rad / delta) as i64;
            self.beam_direction[b] = d.rem_euclid(m as i64) as u16;
        }
        // Template of direction j: the cells the segment of length `len` from the centre of
        // cell (r0, r0) of a unit grid crosses, as offsets from that cell.
        let r0 = MAX_VIEW_RADIUS_CELLS as i32 + 1;
        let side = 2 * r0 as usize + 1;
        let Ok(unit) = GridGeometry::new(side, side, 1.0, Point2::new(-(r0 as f32), -(r0 as f32)))
        else {
            return false;
        };
        let from = Point2::new(0.5, 0.5);
        let mut n = 0usize;
        let mut radius = 0i32;
        let mut overflow = false;
        for j in 0..m {
            self.template_start[j] = n as u32;
            let a = j as f32 * delta;
            let to = Point2::new(0.5 + len * math::cos(a), 0.5 + len * math::sin(a));
            raycast::traverse(&unit, from, to, |c, _| {
                if n == MAX_TEMPLATE_CELLS {
                    overflow = true;
                    return core::ops::ControlFlow::Break(());
                }
                let (dc, dr) = (c.col - r0, c.row - r0);
                radius = radius.max(dc.abs()).max(dr.abs());
                self.template[n] = [dc as i8, dr as i8];
                n += 1;
                core::ops::ControlFlow::Continue(())
            });
            if overflow {
                return false;
            }
        }
        self.template_start[m] = n as u32;
        if radius as usize > MAX_VIEW_RADIUS_CELLS {
            return false;
        }
        for j in 0..m {
            let (a, b) = (self.template_of(j), self.template_of((j + 1) % m));
            self.shared_prefix[j] = a.iter().zip(b).take_while(|(x, y)| x == y).count() as u16;
        }
        for t in 0..n {
            let [dc, dr] = self.template[t];
            let (k, bit) = ((dr as i32 + radius) as u16, (dc as i32 + radius) as u32);
            self.template_spot[t] = (2 * k + (bit / 64) as u16) << 8 | (bit % 64) as u16;
        }
        self.directions = m;
        self.beams = beams;
        self.radius = radius as usize;
        self.rows = 2 * self.radius + 1;
        self.arena_views = (VIEW_ROWS / self.rows).min(MAX_VIEWS);
        self.build_sectors();
        true
    }

    /// Builds the sectors, if they fit in [`SECTOR_ROWS`].
    fn build_sectors(&mut self) {
        let (m, rows, r) = (self.directions, self.rows, self.radius as i32);
        self.sectors_ready = m * rows <= SECTOR_ROWS;
        if !self.sectors_ready {
            return;
        }
        for j in 0..m {
            let mut sector = [0u128; MAX_WINDOW_ROWS];
            for i in 0..SECTOR_BEAMS {
                for &[dc, dr] in self.template_of((j + i) % m) {
                    sector[(dr as i32 + r) as usize] |= 1 << (dc as i32 + r);
                }
            }
            let first = sector.iter().position(|&b| b != 0).unwrap_or(rows);
            let last = sector.iter().rposition(|&b| b != 0).unwrap_or(0);
            self.sector_rows[j] = if first <= last {
                [first as u8, last as u8]
            } else {
                NO_ROWS
            };
            self.sectors[j * rows..(j + 1) * rows].copy_from_slice(&sector[..rows]);
        }
        for (g, consecutive) in self.group_consecutive.iter_mut().enumerate() {
            let beams = g * SECTOR_BEAMS..(g + 1) * SECTOR_BEAMS;
            *consecutive = beams.end <= self.beams
                && beams.clone().skip(1).all(|b| {
                    let step =
                        self.beam_direction[b] as usize + m - self.beam_direction[b - 1] as usize;
                    step % m == 1
                });
        }
    }

    /// The direction index of a beam at `angle` \[rad\].
    #[inline]
    fn direction_of(&self, angle: f32) -> usize {
        let delta = 2.0 * core::f32::consts::PI / self.directions as f32;
        let (j, m) = (math::round(angle / delta) as i64, self.directions as i64);
        // Angles within a turn either side of 0 (the usual case) need no division.
        if (0..m).contains(&j) {
            j as usize
        } else if (-m..0).contains(&j) {
            (j + m) as usize
        } else {
            j.rem_euclid(m) as usize
        }
    }

    /// The viewpoint's cell and the direction of its first beam; `None` if the laser is
    /// outside the grid (such a scan counts nothing).
    pub(crate) fn key_of(&self, laser: &LaserConfig, viewpoint: Pose2) -> Option<(Cell, usize)> {
        let m = laser.mount;
        let pose = if m.x == 0.0 && m.y == 0.0 {
            // A laser on the robot's centre: the same pose without the rotation of (0, 0).
            Pose2::new(viewpoint.x, viewpoint.y, viewpoint.theta + m.theta)
        } else {
            viewpoint.compose(m)
        };
        let cell = self.geometry.cell_at(pose.position())?;
        Some((cell, self.direction_of(pose.theta + laser.first_angle_rad)))
    }

    /// Cells of the template of direction `j`.
    #[inline]
    fn template_of(&self, j: usize) -> &[[i8; 2]] {
        &self.template[self.template_start[j] as usize..self.template_start[j + 1] as usize]
    }

    /// Calls `visit` with the flat index of every Unknown cell the scan from `cell` with first
    /// direction `first` sees, beam by beam (a cell seen by several beams is visited several
    /// times). Reads the grid's classes directly: the reference the windows are checked
    /// against.
    #[cfg(test)]
    pub(crate) fn visit_visible_unknown<const N: usize>(
        &self,
        grid: &OccupancyGrid<N>,
        cell: Cell,
        first: usize,
        mut visit: impl FnMut(usize),
    ) {
        use crate::grid::CellClass;
        let g = grid.geometry();
        for b in 0..self.beams {
            let j = (first + self.beam_direction[b] as usize) % self.directions;
            for &[dc, dr] in self.template_of(j) {
                let Some(i) = g.index(Cell::new(cell.col + dc as i32, cell.row + dr as i32)) else {
                    break;
                };
                match grid.class(i) {
                    CellClass::Occupied => break,
                    CellClass::Unknown => visit(i),
                    CellClass::Free => {}
                }
            }
        }
    }

    /// Builds the fan of direction `j` (all its beams' template cells) if the fans fit;
    /// returns whether it is available at `fans[j * rows..]`.
    fn ensure_fan(&mut self, j: usize) -> bool {
        let rows = self.rows;
        if self.directions * rows > FAN_ROWS {
            return false;
        }
        if !self.fan_ready[j] {
            let r = self.radius as i32;
            let mut fan = [0u128; MAX_WINDOW_ROWS];
            for b in 0..self.beams {
                let k = (j + self.beam_direction[b] as usize) % self.directions;
                for &[dc, dr] in self.template_of(k) {
                    fan[(dr as i32 + r) as usize] |= 1 << (dc as i32 + r);
                }
            }
            self.fans[j * rows..(j + 1) * rows].copy_from_slice(&fan[..rows]);
            self.fan_ready[j] = true;
        }
        true
    }

    /// Where the window of a viewpoint at `cell` starts in the bit sheets: the word of its
    /// first row and the bit in that word (the same in every row).
    #[inline]
    fn sheet_origin(&self, cell: Cell) -> (usize, u32) {
        // Cells are inside the grid, so both are non-negative (the margins exceed the radius).
        let col = (cell.col as i64 - self.radius as i64 + 64) as usize;
        let row = (cell.row as i64 - self.radius as i64 + SHEET_MARGIN_ROWS as i64) as usize;
        (row * self.stride + col / 64, (col % 64) as u32)
    }

    /// Computes the window of (`cell`, `first`) into the entry or the scratch rows.
    fn compute(&mut self, cell: Cell, first: usize, at: Window) {
        let rows = self.rows;
        let stride = self.stride;
        let (origin, shift) = self.sheet_origin(cell);
        let fan_ok = self.ensure_fan(first);
        let (dst, extent) = match at {
            Window::Entry(e) => (
                &mut self.views[e * rows..(e + 1) * rows],
                &mut self.extents[e],
            ),
            Window::Scratch => (&mut self.scratch[..rows], &mut self.scratch_extent),
        };
        if fan_ok {
            let fan = &self.fans[first * rows..(first + 1) * rows];
            let sheet = origin..origin + (rows - 1) * stride + 3;
            let (occupied, unknown) = (&self.occupied[sheet.clone()], &self.unknown[sheet]);
            if fan_window(occupied, unknown, stride, shift, fan, dst) {
                *extent = extent_of(dst);
                self.stats.unobstructed += 1;
                return;
            }
        }
        self.walk_beams(origin, shift, first, at);
    }

    /// Computes the window of a viewpoint whose beams may stop early (at the sheet position
    /// `origin`, `shift`, with first direction `first`) by walking its beams (see the
    /// [module documentation](self)); out of line, so that the fast case stays small.
    #[inline(never)]
    fn walk_beams(&mut self, origin: usize, shift: u32, first: usize, at: Window) {
        let rows = self.rows;
        let stride = self.stride;
        // Some beam may stop early: walk each beam over the window's Occupied and Unknown
        // bits (cells outside the grid are neither, and a beam that left the grid never
        // comes back, so walking on past the edge adds nothing).
        // Word `2 * row + half` of the window (at most 253: a byte indexes them).
        let mut occupied = [0u64; 256];
        let mut unknown = [0u64; 256];
        // Cells some beam reached: Free or Unknown.
        let mut passed = [0u64; 256];
        for k in 0..rows {
            let at = origin + k * stride;
            let o = read128(&self.occupied, at, shift);
            let u = read128(&self.unknown, at, shift);
            (occupied[2 * k], occupied[2 * k + 1]) = (o as u64, (o >> 64) as u64);
            (unknown[2 * k], unknown[2 * k + 1]) = (u as u64, (u >> 64) as u64);
        }
        // A beam stops at the first Occupied cell of its template (at `stop`, the template's
        // length if none). The next beam's template shares its first `shared` cells: if the
        // stop is among them, the next beam stops there too and reaches no new cell;
        // otherwise it passes them (already marked) and is walked from the first cell that
        // differs.
        let mut last: Option<(usize, usize)> = None;
        let mut b = 0;
        while b < self.beams {
            let j = (first + self.beam_direction[b] as usize) % self.directions;
            // A group of beams whose templates meet no Occupied cell passes all their cells.
            if self.sectors_ready
                && b % SECTOR_BEAMS == 0
                && self.group_consecutive[b / SECTOR_BEAMS]
            {
                let sector = &self.sectors[j * rows..(j + 1) * rows];
                let [k0, k1] = self.sector_rows[j];
                let (k0, k1) = (k0 as usize, k1 as usize);
                let clear = (k0..=k1).all(|k| {
                    let cells = sector[k];
                    occupied[2 * k] & cells as u64 | occupied[2 * k + 1] & (cells >> 64) as u64 == 0
                });
                if clear {
                    for (k, &cells) in sector.iter().enumerate().take(k1 + 1).skip(k0) {
                        passed[2 * k] |= cells as u64;
                        passed[2 * k + 1] |= (cells >> 64) as u64;
                    }
                    let j = (j + SECTOR_BEAMS - 1) % self.directions;
                    let length = self.template_start[j + 1] - self.template_start[j];
                    last = Some((j, length as usize));
                    b += SECTOR_BEAMS;
                    continue;
                }
            }
            b += 1;
            let (start, end) = (
                self.template_start[j] as usize,
                self.template_start[j + 1] as usize,
            );
            let from = match last {
                None => 0,
                Some((i, stop)) => {
                    let shared = if i == j {
                        end - start
                    } else if (i + 1) % self.directions == j {
                        self.shared_prefix[i] as usize
                    } else {
                        0
                    };
                    if stop < shared {
                        last = Some((j, stop));
                        continue;
                    }
                    shared
                }
            };
            let mut stop = end - start;
            for (t, &spot) in self.template_spot[start + from..end].iter().enumerate() {
                let word = (spot >> 8) as usize;
                let bit = 1u64 << (spot & 63);
                if occupied[word] & bit != 0 {
                    stop = from + t;
                    break;
                }
                passed[word] |= bit;
            }
            last = Some((j, stop));
        }
        let seen = |i: usize| passed[i] & unknown[i];
        let (dst, extent) = match at {
            Window::Entry(e) => (
                &mut self.views[e * rows..(e + 1) * rows],
                &mut self.extents[e],
            ),
            Window::Scratch => (&mut self.scratch[..rows], &mut self.scratch_extent),
        };
        for (k, out) in dst.iter_mut().enumerate() {
            *out = seen(2 * k) as u128 | (seen(2 * k + 1) as u128) << 64;
        }
        *extent = extent_of(dst);
    }

    /// The window of (`cell`, `first`): from the cache, or computed (and stored if room).
    /// The table slot where the search for (`cell`, `first`) starts, and the cell's index.
    #[inline]
    fn slot_of(&self, cell: Cell, first: usize) -> (usize, u32) {
        let index = cell.row as u32 * self.geometry.width as u32 + cell.col as u32;
        let h = index.wrapping_mul(0x9E37_79B1) ^ (first as u32).wrapping_mul(0x85EB_CA77);
        (h as usize & (TABLE_SLOTS - 1), index)
    }

    fn window(&mut self, cell: Cell, first: usize) -> Window {
        let (mut h, index) = self.slot_of(cell, first);
        let direction = first as u32;
        let mask = TABLE_SLOTS - 1;
        let limit = self.entry_limit.min(self.arena_views);
        for _ in 0..TABLE_SLOTS {
            let slot = self.table[h];
            if slot.generation != self.generation {
                if self.entries >= limit {
                    break;
                }
                let e = self.entries;
                self.entries += 1;
                self.table[h] = Slot {
                    generation: self.generation,
                    cell: index,
                    direction,
                    entry: e as u32,
                };
                self.compute(cell, first, Window::Entry(e));
                self.stats.misses += 1;
                return Window::Entry(e);
            }
            if slot.cell == index && slot.direction == direction {
                self.stats.hits += 1;
                return Window::Entry(slot.entry as usize);
            }
            h = (h + 1) & mask;
        }
        self.compute(cell, first, Window::Scratch);
        self.stats.overflows += 1;
        Window::Scratch
    }

    /// Unknown cells seen from `viewpoints` (robot poses; the laser is at `laser.mount` on the
    /// robot), each counted once. Call [`Self::begin`] first (and only if it returned `true`).
    pub(crate) fn gain(&mut self, laser: &LaserConfig, viewpoints: &[Pose2]) -> u32 {
        debug_assert!(self.ready);
        let rows = self.rows;
        let stride = self.stride;
        // Sheet rows the windows touched.
        let (mut lo, mut hi) = (usize::MAX, 0usize);
        for batch in viewpoints.chunks(GAIN_BATCH) {
            let mut keys = [(Cell::new(0, 0), 0usize); GAIN_BATCH];
            let mut n = 0;
            for &vp in batch {
                if let Some(key) = self.key_of(laser, vp) {
                    keys[n] = key;
                    n += 1;
                }
            }
            // Read each key's first table slot ahead: independent loads, which the processor
            // overlaps, so that the searches below find the table in the cache.
            let mut ahead = 0u32;
            for &(cell, first) in &keys[..n] {
                ahead ^= self.table[self.slot_of(cell, first).0].generation;
            }
            core::hint::black_box(ahead);
            for &(cell, first) in &keys[..n] {
                let at = self.window(cell, first);
                let (src, [k0, k1]) = match at {
                    Window::Entry(e) => (&self.views[e * rows..(e + 1) * rows], self.extents[e]),
                    Window::Scratch => (&self.scratch[..rows], self.scratch_extent),
                };
                if k0 > k1 {
                    continue;
                }
                let (k0, k1) = (k0 as usize, k1 as usize);
                let (origin, shift) = self.sheet_origin(cell);
                let row0 = origin / stride;
                (lo, hi) = (lo.min(row0 + k0), hi.max(row0 + k1));
                let union = &mut self.union[origin + k0 * stride..origin + k1 * stride + 3];
                for (k, &bits) in src[k0..=k1].iter().enumerate() {
                    or128(union, k * stride, shift, bits);
                }
            }
        }
        if lo > hi {
            return 0;
        }
        // Window bits are all on the grid: only the grid's words of each row can be set.
        let grid_words = self.geometry.width.div_ceil(64);
        let mut gain = 0;
        for row in self.union[lo * stride..(hi + 1) * stride].chunks_exact_mut(stride) {
            let words = &mut row[1..1 + grid_words];
            gain += words.iter().map(|x| x.count_ones()).sum::<u32>();
            words.fill(0);
        }
        gain
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::grid::{CellClass, LogOddsBounds};
    use crate::random::{below, range_f32, seeded};

    const W: usize = 70;
    const H: usize = 45;

    /// Random Occupied (8 %), Free (40 %) and Unknown cells, seeded, and 4 % of cells with
    /// weak evidence of an obstacle (log-odds 0.3): Occupied under the thesis's rule, Free
    /// with an Occupied threshold of `occupied_thresh` 0.65.
    fn grid(seed: u64, occupied_thresh: f32) -> std::boxed::Box<OccupancyGrid<{ W * H }>> {
        let g = GridGeometry::new(W, H, 0.1, Point2::new(-1.0, 2.0)).unwrap();
        let bounds = LogOddsBounds::default()
            .with_occupied_thresh(occupied_thresh)
            .unwrap();
        let mut grid = OccupancyGrid::new_boxed(g, bounds).unwrap();
        let mut rng = seeded(seed);
        for i in 0..W * H {
            let x = range_f32(&mut rng, 0.0, 1.0);
            if x < 0.08 {
                grid.set_class(i, CellClass::Occupied, &mut ());
            } else if x < 0.48 {
                grid.set_class(i, CellClass::Free, &mut ());
            } else if x < 0.52 {
                grid.set_log_odds(i, 0.3, &mut ());
            }
        }
        grid
    }

    /// Lasers whose beams take consecutive directions, skip or repeat one, or wrap round.
    fn lasers() -> [LaserConfig; 4] {
        let tau = 2.0 * core::f32::consts::PI;
        [
            LaserConfig::thesis(),
            LaserConfig::lms1xx(),
            // 100.49 beams per turn: 100 directions, and every ~100th beam repeats one.
            LaserConfig {
                beam_count: 260,
                step_rad: tau / 100.49,
                max_range_m: 2.5,
                ..LaserConfig::thesis()
            },
            // 99.51 beams per turn: 100 directions, and every ~100th beam skips one.
            LaserConfig {
                beam_count: 250,
                step_rad: tau / 99.51,
                first_angle_rad: 0.3,
                max_range_m: 1.7,
                ..LaserConfig::thesis()
            },
        ]
    }

    #[test]
    fn gains_equal_the_cells_the_beams_reach_for_any_laser() {
        let mut cache = ViewCache::new_boxed();
        let mut rng = seeded(5);
        let mut blocked = 0;
        // The bit sheets classify as the grid does, whatever its Occupied threshold.
        for (seed, occupied_thresh) in [(0, 0.5), (1, 0.65), (2, 0.5), (3, 0.65)] {
            let grid = grid(40 + seed, occupied_thresh);
            let g = *grid.geometry();
            for laser in lasers() {
                assert!(cache.begin(&*grid, &laser));
                for _ in 0..150 {
                    let views = 1 + below(&mut rng, 3);
                    let mut poses = [Pose2::default(); 3];
                    for p in poses.iter_mut().take(views) {
                        let c = g.cell(below(&mut rng, W * H));
                        let at = g.cell_center(c);
                        *p = Pose2::new(at.x, at.y, range_f32(&mut rng, -4.0, 4.0));
                    }
                    let mut seen = std::collections::HashSet::new();
                    for &p in &poses[..views] {
                        let Some((cell, first)) = cache.key_of(&laser, p) else {
                            continue;
                        };
                        cache.visit_visible_unknown(&*grid, cell, first, |i| {
                            seen.insert(i);
                        });
                    }
                    let gain = cache.gain(&laser, &poses[..views]);
                    assert_eq!(gain as usize, seen.len(), "{laser:?} {:?}", &poses[..views]);
                }
                let stats = cache.stats();
                blocked += stats.misses + stats.overflows - stats.unobstructed;
            }
        }
        assert!(blocked > 100, "{blocked}");
    }
}
