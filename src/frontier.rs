//! Frontiers: the boundary between known free space and the unknown.
//!
//! A frontier cell is an Unknown cell with at least one Free 4-neighbour (Yamauchi, "A
//! Frontier-Based Approach for Autonomous Exploration", IEEE CIRA 1997). Frontier cells group
//! into 8-connected frontiers, each with its size \[cells\], its centroid \[m\] and the frontier
//! cell nearest a given point. Only the box around the cells known so far is scanned
//! ([`frontier_box`]), so a search costs what the explored region holds, not the map.
//!
//! Grouping is a two-pass connected-component labelling with union-find (Rosenfeld & Pfaltz,
//! "Sequential Operations in Digital Picture Processing", JACM 1966) over the list of frontier
//! cells, which is built in flat-index (row-major) order: each cell is joined with its west
//! neighbour and its three neighbours in the row below, all of them earlier in the list. No
//! grid-sized scratch memory is needed: the caller's [`FrontierWorkspace`] holds a few words per
//! frontier cell, with capacities fixed at compile time; running out is an error.

use crate::geometry::Point2;
use crate::grid::{Cell, CellBox, CellClass, OccupancyGrid};

/// Frontier search settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub struct FrontierConfig {
    /// Frontiers with fewer cells than this are dropped \[cells\].
    pub min_size_cells: usize,
}

impl Default for FrontierConfig {
    /// Three cells (30 cm at 10 cm): smaller gaps are sensor noise rather than openings.
    fn default() -> Self {
        Self { min_size_cells: 3 }
    }
}

/// Errors from [`find_frontiers`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FrontierError {
    /// More frontier cells than the workspace holds.
    TooManyCells {
        /// The workspace's cell capacity.
        capacity: usize,
    },
    /// More frontiers (of at least the minimum size) than the workspace holds.
    TooManyFrontiers {
        /// The workspace's frontier capacity.
        capacity: usize,
    },
    /// The grid has more cells than a 32-bit index addresses.
    GridTooLarge {
        /// Cells in the grid.
        cells: usize,
    },
}

impl core::fmt::Display for FrontierError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrontierError::TooManyCells { capacity } => {
                write!(f, "more than {capacity} frontier cells")
            }
            FrontierError::TooManyFrontiers { capacity } => {
                write!(f, "more than {capacity} frontiers")
            }
            FrontierError::GridTooLarge { cells } => {
                write!(f, "grid of {cells} cells is too large for frontier search")
            }
        }
    }
}

impl core::error::Error for FrontierError {}

/// One 8-connected frontier.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Zeroable)]
pub struct Frontier {
    /// Number of cells \[cells\].
    pub size_cells: usize,
    /// Mean of the cell centres, map frame \[m\].
    pub centroid: Point2,
    /// The frontier cell whose centre is nearest the query point.
    pub nearest_cell: Cell,
    /// Flat index of [`Self::nearest_cell`].
    pub nearest_index: usize,
    /// Distance from the query point to the centre of [`Self::nearest_cell`] \[m\].
    pub nearest_distance_m: f32,
    /// Where this frontier's cells start in the workspace's grouped list.
    first: u32,
}

impl Frontier {
    const EMPTY: Frontier = Frontier {
        size_cells: 0,
        centroid: Point2::new(0.0, 0.0),
        nearest_cell: Cell::new(0, 0),
        nearest_index: 0,
        nearest_distance_m: 0.0,
        first: 0,
    };
}

/// Scratch memory and results of a frontier search: up to `CELLS` frontier cells and `FRONTIERS`
/// frontiers. About `16 · CELLS` bytes plus 40 bytes per frontier; build a large one with
/// [`Self::new_boxed`] on a host.
#[derive(bytemuck::Zeroable)]
pub struct FrontierWorkspace<const CELLS: usize, const FRONTIERS: usize> {
    /// Frontier cells in flat-index order.
    cells: [u32; CELLS],
    /// Union-find parent (always an earlier position), then the group number.
    links: [u32; CELLS],
    /// Frontier cells ordered by group.
    grouped: [u32; CELLS],
    /// Per group: cell count, then start, then end in `grouped`.
    ends: [u32; CELLS],
    cell_len: usize,
    frontiers: [Frontier; FRONTIERS],
    frontier_len: usize,
}

impl<const CELLS: usize, const FRONTIERS: usize> Default for FrontierWorkspace<CELLS, FRONTIERS> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CELLS: usize, const FRONTIERS: usize> FrontierWorkspace<CELLS, FRONTIERS> {
    /// An empty workspace (built on the stack).
    pub const fn new() -> Self {
        Self {
            cells: [0; CELLS],
            links: [0; CELLS],
            grouped: [0; CELLS],
            ends: [0; CELLS],
            cell_len: 0,
            frontiers: [Frontier::EMPTY; FRONTIERS],
            frontier_len: 0,
        }
    }

    /// An empty workspace built directly on the heap.
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        // Zero lengths mean empty.
        crate::heap::boxed_zeroed::<Self>()
    }

    /// The frontiers of the last search, in the order of their lowest flat index.
    pub fn frontiers(&self) -> &[Frontier] {
        &self.frontiers[..self.frontier_len]
    }

    /// Flat indices of a frontier's cells (in flat-index order).
    pub fn cells_of(&self, frontier: &Frontier) -> &[u32] {
        let start = frontier.first as usize;
        &self.grouped[start..start + frontier.size_cells]
    }

    /// All frontier cells of the last search, whatever the size of their frontier, in
    /// flat-index order.
    pub fn frontier_cells(&self) -> &[u32] {
        &self.cells[..self.cell_len]
    }

    /// Root of a union-find tree (halving the path on the way).
    #[inline]
    fn find(&mut self, mut i: u32) -> u32 {
        while self.links[i as usize] != i {
            let grand = self.links[self.links[i as usize] as usize];
            self.links[i as usize] = grand;
            i = grand;
        }
        i
    }

    #[inline]
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        // The later root points to the earlier: parents always precede their children.
        match ra.cmp(&rb) {
            core::cmp::Ordering::Less => self.links[rb as usize] = ra,
            core::cmp::Ordering::Greater => self.links[ra as usize] = rb,
            core::cmp::Ordering::Equal => {}
        }
    }
}

/// Whether the cell at flat index `index` is a frontier cell: Unknown with a Free 4-neighbour
/// (false for an index outside the grid).
pub fn is_frontier_cell<const N: usize>(grid: &OccupancyGrid<N>, index: usize) -> bool {
    if index >= grid.cell_count() || grid.class(index) != CellClass::Unknown {
        return false;
    }
    let geom = grid.geometry();
    let c = geom.cell(index);
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .iter()
        .any(|&(dc, dr)| grid.class_of(Cell::new(c.col + dc, c.row + dr)) == Some(CellClass::Free))
}

/// The cells where frontier cells can be: the grid's [known box](OccupancyGrid::known_box)
/// grown by one cell (a frontier cell is Unknown next to a Free cell), clipped to the grid.
/// Scanning it instead of the whole grid finds the same cells in the same (flat-index) order,
/// at a cost that follows the explored region rather than the map.
pub fn frontier_box<const N: usize>(grid: &OccupancyGrid<N>) -> CellBox {
    grid.known_box().grown(1, grid.geometry())
}

/// Finds the frontiers of `grid` with at least `config.min_size_cells` cells, and in each the
/// cell nearest `query` (map frame \[m\]). The results live in `workspace` and are returned as a
/// slice. Allocation-free; a workspace too small for the grid's frontier is an error.
pub fn find_frontiers<'w, const N: usize, const CELLS: usize, const FRONTIERS: usize>(
    grid: &OccupancyGrid<N>,
    query: Point2,
    config: &FrontierConfig,
    workspace: &'w mut FrontierWorkspace<CELLS, FRONTIERS>,
) -> Result<&'w [Frontier], FrontierError> {
    let ws = workspace;
    ws.cell_len = 0;
    ws.frontier_len = 0;
    let geom = *grid.geometry();
    let (w, h) = (geom.width, geom.height);
    if geom.cell_count() > u32::MAX as usize {
        return Err(FrontierError::GridTooLarge {
            cells: geom.cell_count(),
        });
    }
    let bounds = grid.bounds();
    let free = |i: usize| bounds.class_of(grid.log_odds_at(i)) == CellClass::Free;

    // Pass 1: collect frontier cells in flat-index order, from the box where they can be.
    let area = frontier_box(grid);
    for row in area.row_min..area.row_end {
        for col in area.col_min..area.col_end {
            let i = row * w + col;
            if grid.log_odds_at(i) != 0.0 {
                continue;
            }
            let frontier = (col > 0 && free(i - 1))
                || (col + 1 < w && free(i + 1))
                || (row > 0 && free(i - w))
                || (row + 1 < h && free(i + w));
            if frontier {
                if ws.cell_len == CELLS {
                    ws.cell_len = 0;
                    return Err(FrontierError::TooManyCells { capacity: CELLS });
                }
                ws.cells[ws.cell_len] = i as u32;
                ws.links[ws.cell_len] = ws.cell_len as u32;
                ws.cell_len += 1;
            }
        }
    }
    let n = ws.cell_len;

    // Pass 2: join each cell with its earlier 8-neighbours (west, and the row below).
    let mut below = 0usize;
    for k in 0..n {
        let i = ws.cells[k] as usize;
        let (col, row) = (i % w, i / w);
        if k > 0 && col > 0 && ws.cells[k - 1] as usize == i - 1 {
            ws.union(k as u32 - 1, k as u32);
        }
        if row == 0 {
            continue;
        }
        let lowest = (i - w).saturating_sub(1);
        while below < k && (ws.cells[below] as usize) < lowest {
            below += 1;
        }
        let mut q = below;
        while q < k && ws.cells[q] as usize <= i - w + 1 {
            let j = ws.cells[q] as usize;
            if j / w == row - 1 && (j % w).abs_diff(col) <= 1 {
                ws.union(q as u32, k as u32);
            }
            q += 1;
        }
    }

    // Pass 3: number the groups (roots in list order) and count their cells. A parent always
    // precedes its child, so by the time a cell is reached its parent holds its group number.
    let mut groups = 0usize;
    for k in 0..n {
        let parent = ws.links[k] as usize;
        if parent == k {
            ws.links[k] = groups as u32;
            ws.ends[groups] = 0;
            groups += 1;
        } else {
            ws.links[k] = ws.links[parent];
        }
        ws.ends[ws.links[k] as usize] += 1;
    }
    // Counting sort by group (stable: flat-index order within a group). `ends[g]` becomes
    // group g's start, then its cursor, and finally its end.
    let mut start = 0u32;
    for g in 0..groups {
        let size = ws.ends[g];
        ws.ends[g] = start;
        start += size;
    }
    for k in 0..n {
        let g = ws.links[k] as usize;
        ws.grouped[ws.ends[g] as usize] = ws.cells[k];
        ws.ends[g] += 1;
    }

    // Pass 4: describe the groups large enough.
    for g in 0..groups {
        let first = if g == 0 { 0 } else { ws.ends[g - 1] as usize };
        let end = ws.ends[g] as usize;
        let size = end - first;
        if size < config.min_size_cells.max(1) {
            continue;
        }
        if ws.frontier_len == FRONTIERS {
            ws.frontier_len = 0;
            return Err(FrontierError::TooManyFrontiers {
                capacity: FRONTIERS,
            });
        }
        let (mut sum_col, mut sum_row) = (0f64, 0f64);
        let mut best = (f32::INFINITY, 0usize);
        for &i in &ws.grouped[first..end] {
            let cell = geom.cell(i as usize);
            sum_col += cell.col as f64;
            sum_row += cell.row as f64;
            let d = geom.cell_center(cell).distance(query);
            if d < best.0 {
                best = (d, i as usize);
            }
        }
        let res = geom.resolution_m as f64;
        ws.frontiers[ws.frontier_len] = Frontier {
            size_cells: size,
            centroid: Point2::new(
                (geom.origin.x as f64 + (sum_col / size as f64 + 0.5) * res) as f32,
                (geom.origin.y as f64 + (sum_row / size as f64 + 0.5) * res) as f32,
            ),
            nearest_cell: geom.cell(best.1),
            nearest_index: best.1,
            nearest_distance_m: best.0,
            first: first as u32,
        };
        ws.frontier_len += 1;
    }
    Ok(&ws.frontiers[..ws.frontier_len])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridGeometry, LogOddsBounds};
    use crate::random::{below, chance, seeded};
    use std::collections::BTreeSet;
    use std::vec::Vec;

    type Grid = OccupancyGrid<{ 32 * 24 }>;

    /// A random map of blobs: free rooms and occupied walls on an unknown background.
    fn random_grid(rng: &mut crate::random::ProjectRng) -> Grid {
        let w = 8 + below(rng, 25);
        let h = 5 + below(rng, 20);
        let geom = GridGeometry::new(w, h, 0.1, Point2::new(-1.2, 0.7)).unwrap();
        let mut g = Grid::new(geom, LogOddsBounds::default()).unwrap();
        for _ in 0..below(rng, 12) {
            let (c0, r0) = (below(rng, w), below(rng, h));
            let (bw, bh) = (1 + below(rng, 8), 1 + below(rng, 6));
            let class = if chance(rng, 0.7) {
                CellClass::Free
            } else {
                CellClass::Occupied
            };
            for r in r0..(r0 + bh).min(h) {
                for c in c0..(c0 + bw).min(w) {
                    if chance(rng, 0.85) {
                        g.set_class(r * w + c, class, &mut ());
                    }
                }
            }
        }
        g
    }

    /// Brute force: frontier cells by the definition, groups by breadth-first flood fill.
    fn flood_fill_groups(g: &Grid) -> Vec<Vec<u32>> {
        let geom = *g.geometry();
        let is_frontier = |c: Cell| {
            g.class_of(c) == Some(CellClass::Unknown)
                && [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dc, dr)| {
                    g.class_of(Cell::new(c.col + dc, c.row + dr)) == Some(CellClass::Free)
                })
        };
        let mut seen = BTreeSet::new();
        let mut groups = Vec::new();
        for i in 0..geom.cell_count() {
            let c = geom.cell(i);
            if !is_frontier(c) || seen.contains(&i) {
                continue;
            }
            let mut group = Vec::new();
            let mut queue = std::collections::VecDeque::from([c]);
            seen.insert(i);
            while let Some(c) = queue.pop_front() {
                group.push(geom.index(c).unwrap() as u32);
                for dr in -1..=1 {
                    for dc in -1..=1 {
                        let n = Cell::new(c.col + dc, c.row + dr);
                        if let Some(j) = geom.index(n)
                            && is_frontier(n)
                            && seen.insert(j)
                        {
                            queue.push_back(n);
                        }
                    }
                }
            }
            group.sort();
            groups.push(group);
        }
        groups
    }

    #[test]
    fn grouping_matches_a_flood_fill_on_random_grids() {
        let mut rng = seeded(4);
        let mut ws = FrontierWorkspace::<{ 32 * 24 }, 128>::new();
        let mut total_groups = 0;
        for case in 0..600 {
            let g = random_grid(&mut rng);
            let geom = *g.geometry();
            let min = below(&mut rng, 4);
            let query = Point2::new(-1.0 + below(&mut rng, 30) as f32 * 0.1, 1.0);
            let mut want = flood_fill_groups(&g);
            want.retain(|grp| grp.len() >= min.max(1));
            let cfg = FrontierConfig {
                min_size_cells: min,
            };
            let found: Vec<Frontier> = find_frontiers(&g, query, &cfg, &mut ws).unwrap().to_vec();
            let got: Vec<Vec<u32>> = found.iter().map(|f| ws.cells_of(f).to_vec()).collect();
            assert_eq!(got, want, "case {case}");
            total_groups += got.len();
            for f in &found {
                let cells = ws.cells_of(f);
                assert_eq!(f.size_cells, cells.len());
                let n = cells.len() as f32;
                let cx = cells
                    .iter()
                    .map(|&i| geom.cell_center(geom.cell(i as usize)).x)
                    .sum::<f32>()
                    / n;
                let cy = cells
                    .iter()
                    .map(|&i| geom.cell_center(geom.cell(i as usize)).y)
                    .sum::<f32>()
                    / n;
                assert!((f.centroid.x - cx).abs() < 1e-4 && (f.centroid.y - cy).abs() < 1e-4);
                let best = cells
                    .iter()
                    .map(|&i| geom.cell_center(geom.cell(i as usize)).distance(query))
                    .fold(f32::INFINITY, f32::min);
                assert_eq!(f.nearest_distance_m, best);
                assert!(cells.contains(&(f.nearest_index as u32)));
                assert_eq!(geom.index(f.nearest_cell), Some(f.nearest_index));
            }
            for i in 0..geom.cell_count() {
                assert_eq!(
                    is_frontier_cell(&g, i),
                    ws.frontier_cells().contains(&(i as u32))
                );
            }
        }
        assert!(total_groups > 500, "{total_groups} frontiers exercised");
    }

    #[test]
    fn a_small_workspace_reports_overflow() {
        let geom = GridGeometry::new(10, 10, 0.1, Point2::new(0.0, 0.0)).unwrap();
        let mut g = OccupancyGrid::<100>::new(geom, LogOddsBounds::default()).unwrap();
        // Free column 5: Unknown columns 4 and 6 are two frontiers of 10 cells each.
        for row in 0..10 {
            g.set_class(row * 10 + 5, CellClass::Free, &mut ());
        }
        let q = Point2::new(0.0, 0.0);
        let cfg = FrontierConfig::default();
        let mut small = FrontierWorkspace::<19, 4>::new();
        assert_eq!(
            find_frontiers(&g, q, &cfg, &mut small).unwrap_err(),
            FrontierError::TooManyCells { capacity: 19 }
        );
        let mut few = FrontierWorkspace::<20, 1>::new();
        assert_eq!(
            find_frontiers(&g, q, &cfg, &mut few).unwrap_err(),
            FrontierError::TooManyFrontiers { capacity: 1 }
        );
        let mut ok = FrontierWorkspace::<20, 2>::new();
        let found = find_frontiers(&g, q, &cfg, &mut ok).unwrap();
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].size_cells, 10);
        assert_eq!(found[0].nearest_cell, Cell::new(4, 0));
        assert!((found[0].centroid.x - 0.45).abs() < 1e-6);
        assert!((found[0].centroid.y - 0.5).abs() < 1e-6);
        // A larger minimum size drops both.
        let cfg = FrontierConfig { min_size_cells: 11 };
        assert!(find_frontiers(&g, q, &cfg, &mut ok).unwrap().is_empty());
    }
}
