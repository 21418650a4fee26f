//! Path planning on the occupancy grid: traversability, A*, distance fields, waypoints.
//!
//! - [`traversability`]: which cells the robot may enter and at what cost (obstacles inflated
//!   by the robot radius, Unknown cells optimistic or blocked), kept current incrementally as
//!   the grid changes.
//! - [`astar`]: single-query shortest paths (Hart, Nilsson & Raphael 1968).
//! - [`distance_field`]: one-to-all shortest paths (Dijkstra 1959), answering "how far and which
//!   way" for every candidate target of an exploration decision.
//! - [`waypoints`]: pruning a cell path to line-of-sight waypoints in the map frame.
//!
//! All searches use the same move model: 8-connected, orthogonal step 1 cell, diagonal step
//! sqrt(2) cells, **no corner cutting** (a diagonal move needs both orthogonal neighbours
//! passable), and a step's cost multiplied by the cost factor of the cell it enters (1 for Free
//! cells, the configured factor for Unknown cells). Costs are reported in metres (cells times
//! the grid resolution). Working memory has a fixed capacity and is reused across queries
//! without clearing (generation stamps): no query allocates.

pub mod astar;
pub mod blocked_boxes;
pub mod distance_field;
mod search;
pub mod traversability;
pub mod waypoints;

pub use astar::AStar;
pub use blocked_boxes::BlockedBoxes;
pub use distance_field::DistanceField;
pub(crate) use traversability::TravWindow;
pub use traversability::{
    Traversability, TraversabilityConfig, TraversabilityError, UnknownPolicy, WallBands,
};
pub use waypoints::{has_line_of_sight, prune_to_waypoints, prune_to_waypoints_with_boxes};

use crate::grid::Cell;

/// Why a path could not be planned.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum PlanError {
    /// The start cell is blocked (an obstacle, inflated, or Unknown in strict mode).
    StartBlocked {
        /// The start cell.
        cell: Cell,
    },
    /// The goal cell is blocked (an obstacle, inflated, or Unknown in strict mode).
    GoalBlocked {
        /// The goal cell.
        cell: Cell,
    },
    /// A cell lies outside the grid.
    OutOfBounds {
        /// The cell asked for.
        cell: Cell,
        /// Grid width \[cells\].
        width: usize,
        /// Grid height \[cells\].
        height: usize,
    },
    /// No path joins start and goal.
    NoPath {
        /// The start cell.
        start: Cell,
        /// The goal cell.
        goal: Cell,
    },
    /// A fixed-capacity buffer is too small (path or waypoint output, or working memory smaller
    /// than the grid).
    CapacityExceeded {
        /// Entries needed.
        needed: usize,
        /// Entries available.
        capacity: usize,
    },
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::StartBlocked { cell } => {
                write!(f, "start cell ({}, {}) is blocked", cell.col, cell.row)
            }
            PlanError::GoalBlocked { cell } => {
                write!(f, "goal cell ({}, {}) is blocked", cell.col, cell.row)
            }
            PlanError::OutOfBounds {
                cell,
                width,
                height,
            } => write!(
                f,
                "cell ({}, {}) is outside the {width} x {height} grid",
                cell.col, cell.row
            ),
            PlanError::NoPath { start, goal } => write!(
                f,
                "no path from ({}, {}) to ({}, {})",
                start.col, start.row, goal.col, goal.row
            ),
            PlanError::CapacityExceeded { needed, capacity } => write!(
                f,
                "planner needs {needed} entries but has room for {capacity}"
            ),
        }
    }
}

impl core::error::Error for PlanError {}

/// A planned path; its cells were written, start first and goal last, to the first
/// [`PlannedPath::len`] entries of the caller's buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannedPath {
    /// Cells in the path, start and goal included.
    pub len: usize,
    /// Geometric length of the path \[m\].
    pub length_m: f32,
    /// Cost minimised: the length with each step weighted by the cost factor of the cell it
    /// enters \[m\]. Equals `length_m` when the path crosses no Unknown cell.
    pub cost_m: f32,
    /// Cells expanded (closed) by the search.
    pub expansions: u32,
}

/// A shortest-path planner over a traversability layer of capacity `N` cells.
pub trait Planner<const N: usize> {
    /// Plans from `start` to `goal`, writing the cells (start first) into `path`.
    fn plan(
        &mut self,
        trav: &Traversability<N>,
        start: Cell,
        goal: Cell,
        path: &mut [Cell],
    ) -> Result<PlannedPath, PlanError>;
}

/// A test double: returns the two-cell path `[start, goal]` with its straight-line length,
/// ignoring obstacles (but still checking bounds and the endpoints). For testing the layers
/// above the planner without a map.
#[derive(Clone, Copy, Debug, Default, bytemuck::Zeroable)]
pub struct StraightLinePlanner;

impl<const N: usize> Planner<N> for StraightLinePlanner {
    fn plan(
        &mut self,
        trav: &Traversability<N>,
        start: Cell,
        goal: Cell,
        path: &mut [Cell],
    ) -> Result<PlannedPath, PlanError> {
        let (s, _) = trav.check_endpoints(start, goal)?;
        let cells: &[Cell] = if s == trav.geometry().index(goal).unwrap_or(s) {
            &[start]
        } else {
            &[start, goal]
        };
        if path.len() < cells.len() {
            return Err(PlanError::CapacityExceeded {
                needed: cells.len(),
                capacity: path.len(),
            });
        }
        path[..cells.len()].copy_from_slice(cells);
        let res = trav.geometry().resolution_m;
        let length_m = crate::math::hypot(
            (goal.col - start.col) as f32 * res,
            (goal.row - start.row) as f32 * res,
        );
        Ok(PlannedPath {
            len: cells.len(),
            length_m,
            cost_m: length_m,
            expansions: 0,
        })
    }
}

/// Geometric length of a cell path \[m\]: the sum of its steps (1 or sqrt(2) cells each, or the
/// Euclidean distance between cell centres for longer steps) times `resolution_m`.
pub fn path_length_m(cells: &[Cell], resolution_m: f32) -> f32 {
    let mut sum = 0.0f32;
    for w in cells.windows(2) {
        let dc = (w[1].col - w[0].col).abs();
        let dr = (w[1].row - w[0].row).abs();
        sum += match (dc, dr) {
            (0, 0) => 0.0,
            (1, 0) | (0, 1) => 1.0,
            (1, 1) => core::f32::consts::SQRT_2,
            _ => crate::math::hypot(dc as f32, dr as f32),
        };
    }
    sum * resolution_m
}

#[cfg(all(test, feature = "std"))]
mod tests;
