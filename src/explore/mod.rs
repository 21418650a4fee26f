//! Exploration decisions: where the robot goes next.
//!
//! - [`objective`]: the thesis's energy-constrained objective (Bendahmane 2023): the number of
//!   Unknown cells predicted to become known along the planned path through k targets, with the
//!   path's energy in steps checked against the battery; and the default efficient objective
//!   (targets at reachable frontier viewpoints, gain discounted by energy; issue 17).
//! - [`reachable`]: frontier viewpoints the robot can reach, where the efficient objective
//!   puts its targets.
//! - [`optimized`]: targets chosen by any population optimizer of [`crate::optim`] (xBOA in the
//!   thesis) on that objective.
//! - [`near_pocket`]: a small unknown pocket nearer the robot than the optimizer's target is
//!   cleared first (efficient objective), instead of after a trip back at the end.
//! - [`nearest_frontier`]: Yamauchi (1997): the frontier with the shortest path distance.
//! - [`frontier_utility`]: explore_lite's rule (frontier size minus a distance cost), with path
//!   distance and a blacklist of frontiers the robot failed to reach.
//! - [`shut_mouth`]: where to look again when no frontier is reachable: the mouth of a
//!   passage open in Free cells but shut in the planning layer.
//! - [`blacklist`]: places the robot failed to reach, avoided by every selector until the map
//!   around them changes.
//! - [`evaluation`]: a candidate's status and score, what the objective computes and the memo
//!   keeps.
//! - [`view_cache`], [`memo`] and [`leg_memo`]: what one decision computes once and reuses
//!   (each viewpoint's visible Unknown cells; each candidate's evaluation; the waypoints of
//!   each leg between two targets).
//!
//! Every selector implements [`TargetSelector`] and fills the same [`Decision`]; the caller
//! measures the compute time (the core reads no clock).

pub mod blacklist;
pub mod evaluation;
pub mod frontier_utility;
pub mod leg_memo;
pub mod memo;
pub mod near_pocket;
pub mod nearest_frontier;
pub mod objective;
pub mod optimized;
pub mod reachable;
pub mod shut_mouth;
pub mod tour;
pub mod view_cache;

#[cfg(all(test, feature = "std"))]
mod tests;

pub use blacklist::{BLACKLIST_RADIUS_M, Blacklist, MAX_BLACKLISTED};
pub use evaluation::{CandidateStatus, Evaluation, WORST_FITNESS};
pub use frontier_utility::FrontierUtility;
pub use nearest_frontier::NearestFrontier;
pub use objective::ExploreObjective;
pub use optimized::{InitialPopulation, Optimized};
pub use reachable::ReachableViewpoints;
pub use shut_mouth::{MAX_MOUTHS, MouthSearch};
pub use view_cache::{ViewCache, ViewCacheStats};

use crate::control::follower::MAX_WAYPOINTS;
use crate::geometry::{Point2, Pose2};
use crate::grid::{Cell, CellClass, OccupancyGrid};
use crate::planner::{DistanceField, PlanError, Traversability};
use crate::sensor::LaserConfig;

/// Most targets in one decision (k).
pub const MAX_TARGETS: usize = 8;
/// Capacity of a decision's best-fitness history (one entry per generation, initial included).
pub const MAX_DECISION_HISTORY: usize = 64;

/// What a selector is given for one decision.
#[derive(Clone, Copy, Debug)]
pub struct DecisionRequest<'a, const N: usize> {
    /// The current map.
    pub grid: &'a OccupancyGrid<N>,
    /// The traversability layer kept in step with `grid` (same geometry).
    pub trav: &'a Traversability<N>,
    /// Robot pose, map frame \[m, rad\].
    pub pose: Pose2,
    /// Energy left \[steps\] (1 m of travel or 45° of rotation each).
    pub battery_steps: f32,
    /// The laser whose geometry predicts what the robot will see.
    pub laser: &'a LaserConfig,
}

/// A chosen plan.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// Targets, visited in order, map frame \[m\] (cell centres).
    pub targets: heapless::Vec<Point2, MAX_TARGETS>,
    /// Waypoints of the planned path from the robot through the targets, map frame \[m\].
    pub waypoints: heapless::Vec<Point2, MAX_WAYPOINTS>,
    /// Length of the planned path \[m\].
    pub path_length_m: f32,
    /// Unknown cells predicted to become known along the path \[cells\].
    pub predicted_gain_cells: u32,
    /// Energy of the path, rotations included \[steps\].
    pub energy_steps: f32,
    /// Objective evaluations used to decide.
    pub evaluations: u32,
    /// Best fitness per generation (initial population first); empty for the frontier rules.
    pub history: heapless::Vec<f32, MAX_DECISION_HISTORY>,
}

/// The outcome of a decision.
// The core has no allocator, so the decision is held inline rather than boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Go there.
    Go(Decision),
    /// Mission done: no Unknown cell is reachable any more (no frontier cell can be reached).
    Done,
}

/// What the optimizers maximise (see [`objective`](objective#objectives)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ObjectiveKind {
    /// The thesis's objective: predicted gain along the path to any point of the map, with
    /// the energy only checked against the battery (`--objective thesis`, for the
    /// reproduction experiments).
    Thesis,
    /// Targets snapped to viewpoints the robot can reach next to frontiers, scored by gain
    /// discounted by the path's energy and the frontier tour's detour, with a bonus for small
    /// unknown pockets (the default).
    #[default]
    Efficient,
}

impl ObjectiveKind {
    /// The kind named `name` (`thesis` or `efficient`, as the CLI and the board file spell
    /// them).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "thesis" => Some(Self::Thesis),
            "efficient" => Some(Self::Efficient),
            _ => None,
        }
    }

    /// The name [`Self::from_name`] reads.
    pub fn name(self) -> &'static str {
        match self {
            Self::Thesis => "thesis",
            Self::Efficient => "efficient",
        }
    }
}

/// Exploration settings shared by the selectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExploreConfig {
    /// What the optimizers maximise (default [`ObjectiveKind::Efficient`]; the frontier rules
    /// ignore it).
    pub objective: ObjectiveKind,
    /// Targets per decision, k (1 = the thesis's short-term strategy; at most [`MAX_TARGETS`]).
    pub targets: usize,
    /// Energy kept in reserve: a plan costing more than `battery - reserve` is infeasible
    /// \[steps\].
    pub reserve_steps: f32,
    /// The efficient objective's discount per step of energy, lambda in
    /// `gain · exp(-lambda · steps)` \[1/step\] (default
    /// [`objective::EFFICIENCY_LAMBDA_PER_STEP`]).
    pub efficiency_per_step: f32,
    /// The efficient objective's factor on a candidate clearing a small unknown pocket
    /// (default [`objective::POCKET_BONUS`]; 1 = no bonus).
    pub pocket_bonus: f32,
    /// The efficient objective ends each plan this far before the frontier viewpoint it
    /// aims at \[m\] (default [`objective::SETBACK_M`]; 0 = drive up to it).
    pub setback_m: f32,
    /// The efficient objective's optimizer visits a small unknown pocket nearer the robot than
    /// its chosen target first ([`near_pocket`]; default off: measured on the lab and the
    /// house in `docs/experiments.md`, not yet on the generated set, and it breaks one of the
    /// corner starts of the mission's escape test).
    pub near_pockets_first: bool,
    /// The efficient objective's weight on the frontier tour's extra length
    /// ([`tour::FrontierTour::extra_m`]) of going to a candidate's target first: its energy
    /// in the discount becomes `steps + tour_weight · extra_m` (default
    /// [`objective::TOUR_WEIGHT`]; 0 = no tour).
    pub tour_weight: f32,
    /// Optional cost weight lambda: score = gain - lambda * steps (clamped at 0) \[cells/step\].
    /// `None` (default): the thesis's pure gain.
    pub cost_weight: Option<f32>,
    /// Score by gain per step instead of gain (default off).
    pub gain_per_step: bool,
    /// Spacing of the predicted scans along the path \[m\] (default 0.5).
    pub viewpoint_spacing_m: f32,
    /// Population size of the optimizer (default 5).
    pub population: usize,
    /// Generations of the optimizer (default 30).
    pub max_generations: u32,
    /// The optimizers' parameter sets (default [`DEFAULT_PRESET`]; only GA, PSO, GWO and ABC
    /// differ between them, see [`crate::optim::Preset`]).
    pub preset: crate::optim::Preset,
    /// Hyper-parameters replacing the preset's for the optimizer they belong to (`None`, the
    /// default: the preset's; see [`crate::optim::Method::build_tuned`]).
    pub tuning: Option<crate::optim::Tuning>,
}

/// The optimizers' parameter set an exploration gets unless told otherwise
/// ([`ExploreConfig::preset`]): the literature's defaults, which reached 99 % in every one of
/// 320 missions on four maps (thesis preset: 318) in 3 % fewer steps on average; on a
/// battery-limited map the two did not separate (`docs/optimizers.md`, "Which preset the
/// exploration uses"). Only GA, PSO, GWO and ABC differ.
pub const DEFAULT_PRESET: crate::optim::Preset = crate::optim::Preset::Standard;

impl Default for ExploreConfig {
    fn default() -> Self {
        Self {
            objective: ObjectiveKind::default(),
            targets: 1,
            reserve_steps: 0.0,
            efficiency_per_step: objective::EFFICIENCY_LAMBDA_PER_STEP,
            pocket_bonus: objective::POCKET_BONUS,
            setback_m: objective::SETBACK_M,
            near_pockets_first: false,
            tour_weight: objective::TOUR_WEIGHT,
            cost_weight: None,
            gain_per_step: false,
            viewpoint_spacing_m: 0.5,
            population: 5,
            max_generations: 30,
            preset: DEFAULT_PRESET,
            tuning: None,
        }
    }
}

/// Why no decision could be made.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum DecideError {
    /// The robot's own cell is outside the map or blocked.
    Start(PlanError),
    /// `targets` is 0 or above [`MAX_TARGETS`].
    BadTargetCount {
        /// The configured k.
        got: usize,
    },
    /// The grid and the traversability layer have different geometries, or the grid is
    /// larger than the working memory.
    Mismatch {
        /// Cells in the grid.
        grid_cells: usize,
        /// Cells the working memory holds.
        capacity: usize,
    },
    /// The optimizer refused its settings.
    Optimizer(crate::optim::OptimError),
    /// Unknown space is reachable but no candidate was feasible (battery too low).
    NoFeasibleTarget {
        /// Energy left \[steps\].
        battery_steps: f32,
    },
    /// A frontier search ran out of room.
    Frontier(crate::frontier::FrontierError),
    /// Every reachable frontier is blacklisted (the robot failed to reach each of them and the
    /// map around them has not changed since).
    AllBlacklisted {
        /// Blacklist entries.
        entries: usize,
    },
    /// The blacklist is full.
    BlacklistFull {
        /// Its capacity.
        capacity: usize,
    },
}

impl core::fmt::Display for DecideError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecideError::Start(e) => write!(f, "cannot plan from the robot's cell: {e}"),
            DecideError::BadTargetCount { got } => {
                write!(
                    f,
                    "targets per decision must be 1..={MAX_TARGETS}, got {got}"
                )
            }
            DecideError::Mismatch {
                grid_cells,
                capacity,
            } => write!(
                f,
                "grid of {grid_cells} cells does not match the traversability layer or the \
                 working memory of {capacity} cells"
            ),
            DecideError::Optimizer(e) => write!(f, "optimizer: {e}"),
            DecideError::NoFeasibleTarget { battery_steps } => write!(
                f,
                "no feasible target with {battery_steps} steps of battery left"
            ),
            DecideError::Frontier(e) => write!(f, "frontier search: {e}"),
            DecideError::AllBlacklisted { entries } => write!(
                f,
                "every reachable frontier is blacklisted ({entries} entries, map unchanged)"
            ),
            DecideError::BlacklistFull { capacity } => {
                write!(f, "frontier blacklist full ({capacity} entries)")
            }
        }
    }
}

impl core::error::Error for DecideError {}

/// Chooses where the robot goes next.
pub trait TargetSelector<const N: usize> {
    /// One decision from the map and the robot's state; every random choice comes from `rng`.
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        rng: &mut R,
    ) -> Result<Outcome, DecideError>;
}

/// The cell the robot can drive to in order to look at frontier cell `index`: the cell itself
/// if reachable, else its nearest reachable 4-neighbour (Free cells next to it); with the
/// path distance \[m\].
pub(crate) fn reach_frontier_cell<const N: usize>(
    grid: &OccupancyGrid<N>,
    field: &DistanceField<N>,
    index: usize,
) -> Option<(Cell, f32)> {
    let c = grid.geometry().cell(index);
    if let Some(d) = field.distance_to(c) {
        return Some((c, d));
    }
    let mut best: Option<(Cell, f32)> = None;
    for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
        let n = Cell::new(c.col + dc, c.row + dr);
        if grid.class_of(n) != Some(CellClass::Free) {
            continue;
        }
        if let Some(d) = field.distance_to(n)
            && best.is_none_or(|(_, b)| d < b)
        {
            best = Some((n, d));
        }
    }
    best
}

/// What a scan of the frontier cells found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FrontierScan {
    /// No frontier cell can be reached: exploration is done.
    NoneReachable,
    /// Every reachable frontier cell is blacklisted.
    AllBlacklisted,
    /// The cell to drive to for the nearest (by path) frontier cell not blacklisted.
    Nearest(Cell),
}

/// Scans every frontier cell (Unknown with a Free 4-neighbour) for the one with the shortest
/// path distance from the distance field's source whose drive-to cell ([`reach_frontier_cell`])
/// is not blacklisted.
pub(crate) fn nearest_reachable_frontier<const N: usize>(
    grid: &OccupancyGrid<N>,
    field: &DistanceField<N>,
    blacklist: &Blacklist,
) -> FrontierScan {
    let geom = grid.geometry();
    let mut reachable = false;
    let mut best: Option<(Cell, f32)> = None;
    // Frontier cells lie in the frontier box: the same cells, in the same order, as a scan of
    // the whole grid.
    let area = crate::frontier::frontier_box(grid);
    let rows = area.row_min..area.row_end;
    let cells = rows.flat_map(|r| (r * geom.width + area.col_min)..(r * geom.width + area.col_end));
    for i in cells {
        if !crate::frontier::is_frontier_cell(grid, i) {
            continue;
        }
        let Some((c, d)) = reach_frontier_cell(grid, field, i) else {
            continue;
        };
        reachable = true;
        if best.is_none_or(|(_, b)| d < b) && !blacklist.contains(geom.cell_center(c)) {
            best = Some((c, d));
        }
    }
    match best {
        Some((c, _)) => FrontierScan::Nearest(c),
        None if reachable => FrontierScan::AllBlacklisted,
        None => FrontierScan::NoneReachable,
    }
}

/// A reachable frontier cell (as [`reach_frontier_cell`] gives it) found by scanning the grid
/// from a random cell onwards (wrapping round); `None` if there is none. Cells following long
/// runs without frontier are drawn more often than others: a cheap draw, not a uniform one.
pub(crate) fn sample_reachable_frontier<const N: usize, R: rand_core::Rng>(
    grid: &OccupancyGrid<N>,
    field: &DistanceField<N>,
    rng: &mut R,
) -> Option<Cell> {
    let n = grid.cell_count();
    let start = crate::random::below(rng, n);
    // The cells from `start` onwards, then those before it, as a scan of the whole grid would
    // meet them; only the frontier box can hold frontier cells.
    let w = grid.geometry().width;
    let area = crate::frontier::frontier_box(grid);
    let in_box = move |from: usize, to: usize| {
        (area.row_min..area.row_end).flat_map(move |r| {
            let lo = (r * w + area.col_min).max(from);
            let hi = (r * w + area.col_end).min(to);
            lo..hi.max(lo)
        })
    };
    in_box(start, n).chain(in_box(0, start)).find_map(|i| {
        if crate::frontier::is_frontier_cell(grid, i) {
            reach_frontier_cell(grid, field, i).map(|(c, _)| c)
        } else {
            None
        }
    })
}
