//! Viewpoints the robot can reach: where the [efficient objective](super::objective#objectives)
//! lets a target be.
//!
//! A **frontier viewpoint** is a known Free cell that the robot's distance field reaches and
//! that touches a frontier cell (an Unknown cell with a Free 4-neighbour) on one of its four
//! sides: standing there, the robot looks into Unknown space it can actually get to. Unknown
//! space beyond walls, behind closed structure or outside the building has no such cell next
//! to it, so it can only be looked at from the viewpoints the robot really reaches.
//!
//! One decision lists at most [`MAX_VIEWPOINTS`] of them ([`ReachableViewpoints::collect`]):
//! the grid is cut into square blocks of [`BLOCK_CELLS`] cells a side, and each block holding
//! frontier viewpoints contributes the one with the shortest path from the robot, with the
//! number of frontier cells its block's viewpoints touch. If the blocks with viewpoints
//! outnumber the list, the block side doubles until they fit.
//!
//! The optimizer still searches the whole map (its genes are points in the map bounds); a
//! point is **snapped** ([`ReachableViewpoints::snap`]) to a target the robot can use:
//! the point's own cell when that cell is known Free, passable, reachable and within
//! [`ReachableViewpoints::near_m`] of a listed viewpoint (so close to some frontier), else the
//! nearest listed viewpoint (a Voronoi partition of the map among the viewpoints). Every
//! point then names a reachable target near the frontier, and unknown space far from any
//! reachable viewpoint (outside the building) maps to the viewpoint from which the robot would
//! really look at it.
//!
//! Sources: the candidate viewpoints on the frontier are Yamauchi's ("A frontier-based
//! approach for autonomous exploration", CIRA 1997); restricting candidates to reachable free
//! space near frontiers is the sampling of González-Baños & Latombe ("Navigation strategies
//! for exploring indoor environments", IJRR 21(10–11), 2002), who draw candidate poses in the
//! known free space "near" the frontier.

use crate::grid::{Cell, CellClass, OccupancyGrid};
use crate::planner::{DistanceField, Traversability};

/// Most frontier viewpoints listed per decision.
pub const MAX_VIEWPOINTS: usize = 512;
/// Most frontier cells of a [`Viewpoint::pocket`].
pub const POCKET_FRONTIER_CELLS: u16 = 12;
/// Side of the blocks that each contribute one viewpoint \[cells\] (before any doubling).
pub const BLOCK_CELLS: i32 = 5;
/// Most blocks across the known region in one row of blocks (known regions up to 1280 cells
/// wide at [`BLOCK_CELLS`]; wider ones double the block side).
const MAX_BLOCK_COLUMNS: usize = 256;

/// One listed frontier viewpoint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewpoint {
    /// The cell, known Free and reachable.
    pub cell: Cell,
    /// Path cost from the robot \[m\].
    pub distance_m: f32,
    /// Frontier cells touched by the viewpoints of its block.
    pub frontier_cells: u16,
    /// A small unknown pocket: at most [`POCKET_FRONTIER_CELLS`] frontier cells, and no
    /// neighbouring block (of the 8 around its own) with a viewpoint.
    pub pocket: bool,
    /// Block coordinates (column, row) at the decision's block side.
    block: (i32, i32),
}

/// The frontier viewpoints of one decision.
#[derive(Clone, Debug)]
pub struct ReachableViewpoints {
    list: [Viewpoint; MAX_VIEWPOINTS],
    len: usize,
    block: i32,
    /// A point's own cell is kept when it lies this close to a listed viewpoint \[m\].
    pub near_m: f32,
}

const NO_VIEWPOINT: Viewpoint = Viewpoint {
    cell: Cell::new(0, 0),
    distance_m: 0.0,
    frontier_cells: 0,
    pocket: false,
    block: (0, 0),
};

impl Default for ReachableViewpoints {
    fn default() -> Self {
        Self::new()
    }
}

impl ReachableViewpoints {
    /// An empty list.
    pub const fn new() -> Self {
        Self {
            list: [NO_VIEWPOINT; MAX_VIEWPOINTS],
            len: 0,
            block: BLOCK_CELLS,
            near_m: 1.0,
        }
    }

    /// The listed viewpoints.
    pub fn as_slice(&self) -> &[Viewpoint] {
        &self.list[..self.len]
    }

    /// Side of the blocks of this decision \[cells\].
    pub fn block_cells(&self) -> i32 {
        self.block
    }

    /// Lists the frontier viewpoints of `grid` that `field` (swept from the robot) reaches;
    /// returns how many.
    pub fn collect<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        trav: &Traversability<N>,
        field: &DistanceField<N>,
    ) -> usize {
        let width = grid.geometry().width as i32;
        let mut block = BLOCK_CELLS;
        while !self.collect_with(grid, trav, field, block) {
            block *= 2;
            if block > width.max(grid.geometry().height as i32) * 2 {
                break;
            }
        }
        for i in 0..self.len {
            let v = self.list[i];
            self.list[i].pocket = v.frontier_cells <= POCKET_FRONTIER_CELLS && self.is_isolated(&v);
        }
        self.len
    }

    /// One pass at block side `block`; `false` if the list or the block row overflowed.
    fn collect_with<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        trav: &Traversability<N>,
        field: &DistanceField<N>,
        block: i32,
    ) -> bool {
        self.len = 0;
        self.block = block;
        let geom = *grid.geometry();
        let w = geom.width as i32;
        // Viewpoints are known Free cells: only the grid's known box can hold them, and only
        // its blocks need a slot.
        let area = grid.known_box();
        let (c0, c1) = (area.col_min as i32, area.col_end as i32);
        let first_block = c0 / block;
        if c1 > c0 && (c1 - 1) / block - first_block >= MAX_BLOCK_COLUMNS as i32 {
            return false;
        }
        // Slot in `list` (plus one; 0 = none yet) of each block of the current block row,
        // counted from the known box's first block.
        let mut slots = [0u16; MAX_BLOCK_COLUMNS];
        let mut block_row = -1;
        for row in area.row_min as i32..area.row_end as i32 {
            if row / block != block_row {
                block_row = row / block;
                slots.fill(0);
            }
            for col in c0..c1 {
                let c = Cell::new(col, row);
                let i = (row * w + col) as usize;
                if grid.class(i) != CellClass::Free {
                    continue;
                }
                let touches = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .iter()
                    .filter(|&&(dc, dr)| {
                        grid.class_of(Cell::new(col + dc, row + dr)) == Some(CellClass::Unknown)
                    })
                    .count() as u16;
                if touches == 0 || !trav.is_passable(c) {
                    continue;
                }
                let Some(d) = field.distance_to(c) else {
                    continue;
                };
                let bc = (col / block) as usize;
                let slot = bc - first_block as usize;
                match slots[slot] {
                    0 => {
                        if self.len == MAX_VIEWPOINTS {
                            return false;
                        }
                        self.list[self.len] = Viewpoint {
                            cell: c,
                            distance_m: d,
                            frontier_cells: touches,
                            pocket: false,
                            block: (bc as i32, block_row),
                        };
                        self.len += 1;
                        slots[slot] = self.len as u16;
                    }
                    s => {
                        let v = &mut self.list[s as usize - 1];
                        v.frontier_cells = v.frontier_cells.saturating_add(touches);
                        if d < v.distance_m {
                            v.cell = c;
                            v.distance_m = d;
                        }
                    }
                }
            }
        }
        true
    }

    /// The listed viewpoint nearest `cell` (straight-line), with its squared distance
    /// \[cells²\]; `None` if none is listed.
    pub fn nearest(&self, cell: Cell) -> Option<(&Viewpoint, i32)> {
        self.as_slice()
            .iter()
            .map(|v| {
                let (dc, dr) = (v.cell.col - cell.col, v.cell.row - cell.row);
                (v, dc * dc + dr * dr)
            })
            .min_by_key(|&(_, d2)| d2)
    }

    /// The target cell the robot would use for a point falling in `cell` (see the
    /// [module documentation](self)); `None` if no viewpoint is listed.
    pub fn snap<const N: usize>(
        &self,
        cell: Cell,
        grid: &OccupancyGrid<N>,
        trav: &Traversability<N>,
        field: &DistanceField<N>,
    ) -> Option<Cell> {
        let (nearest, d2) = self.nearest(cell)?;
        let near = self.near_m / grid.geometry().resolution_m;
        let keep = (d2 as f32) <= near * near
            && grid.class_of(cell) == Some(CellClass::Free)
            && trav.is_passable(cell)
            && field.is_reachable(cell);
        Some(if keep { cell } else { nearest.cell })
    }

    /// Whether the viewpoint's block has no neighbouring block (of the 8 around it) with
    /// viewpoints: a small unknown pocket, on its own.
    pub fn is_isolated(&self, v: &Viewpoint) -> bool {
        !self.as_slice().iter().any(|o| {
            o.block != v.block
                && (o.block.0 - v.block.0).abs() <= 1
                && (o.block.1 - v.block.1).abs() <= 1
        })
    }
}
