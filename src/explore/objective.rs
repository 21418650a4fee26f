//! The energy-constrained exploration objective (Bendahmane, PhD thesis, USTO Oran 2023,
//! chapter on energy-aware exploration with xBOA).
//!
//! A candidate is k target points in the map bounds, visited in order from the robot's pose.
//! Its **gain** is the number of currently Unknown cells predicted to become known while the
//! robot drives the planned path: simulated scans are taken at the start pose, every
//! [`ExploreConfig::viewpoint_spacing_m`] along each straight segment and at each waypoint,
//! heading along the segment; each beam of the laser is traced over the grid up to the usable
//! range, stops at the first Occupied cell, and crosses Unknown cells (what lies there is not
//! known, so the prediction is optimistic). Cells are counted once per candidate (generation
//! stamps, so nothing is cleared between evaluations).
//!
//! **Energy** is counted in steps (1 m of travel or 45° of rotation, [`crate::units::steps`]):
//! the length of the waypoint polyline plus the turn from the robot's heading onto the first
//! segment and at every waypoint. A candidate over `battery - reserve`, or with a target
//! outside the grid, on a blocked (Occupied, inflated) or unreachable cell, scores the worst
//! fitness, [`WORST_FITNESS`]; so does, in the optimizer's view
//! ([`ExploreObjective::problem_avoiding`]), a candidate with a target near a place the robot
//! failed to reach (the mission's [`Blacklist`]).
//!
//! # Objectives
//!
//! [`ExploreConfig::objective`] chooses what the optimizers maximise; both share the path,
//! energy and gain models above.
//!
//! - **Thesis** ([`ObjectiveKind::Thesis`], `--objective thesis`): the thesis's score, the
//!   gain alone (or the variants [`ExploreConfig::cost_weight`] and
//!   [`ExploreConfig::gain_per_step`]), with targets anywhere in the map bounds. Its
//!   decisions on the house fixture are pinned by a test, for the reproduction experiments.
//!   Its targets often lie in Unknown space beyond the outer walls, where the robot can never
//!   stand (issue 17).
//! - **Efficient** ([`ObjectiveKind::Efficient`], the default):
//!   1. *Gains the robot can get.* Every target is snapped to a cell the robot can reach next
//!      to a frontier ([`super::reachable`]): its own cell if known Free, passable, reachable
//!      and within [`NEAR_FRONTIER_SHARE_OF_RANGE`] of the laser's range of a frontier
//!      viewpoint, else the nearest listed frontier viewpoint. The memo and the blacklist see
//!      the snapped cells. Unknown space that can only be seen from outside the reachable
//!      region is then only counted from where the robot can really look at it.
//!   2. *Gain against cost.* The score is `gain · exp(-lambda · steps)`
//!      ([`ExploreConfig::efficiency_per_step`], default [`EFFICIENCY_LAMBDA_PER_STEP`]): the
//!      utility of González-Baños & Latombe ("Navigation strategies for exploring indoor
//!      environments", IJRR 21(10–11), 2002), with the path's energy in steps (turns
//!      included) as its cost. The gain still counts every predicted scan along the path,
//!      so information on the way counts.
//!   3. *No pockets left behind.* A candidate whose target clears a small unknown pocket (a
//!      frontier viewpoint with few frontier cells and no neighbouring block with one,
//!      [`super::reachable::Viewpoint::pocket`]) scores [`ExploreConfig::pocket_bonus`] times
//!      more (default [`POCKET_BONUS`]), so that the robot clears it while near rather than
//!      after a long trip back.
//!   4. *Stop when the frontier is in view.* A plan ends [`ExploreConfig::setback_m`] before
//!      the viewpoint it aims at (default [`SETBACK_M`]; a shorter last leg is kept whole);
//!      its end is the decision's target. Re-plans ([`ExploreObjective::prepare_plan`]) go to
//!      the targets as given.
//!
//!   5. *Visit the frontier in a good order.* A candidate's energy in the discount also
//!      carries [`ExploreConfig::tour_weight`] (default [`TOUR_WEIGHT`]) times the extra
//!      length of the decision's frontier tour when the candidate's first target is visited
//!      first ([`super::tour`]: Kulich et al. 2011's TSP distance cost over coarse frontier
//!      clusters), so the robot finishes the side of the frontier it is on instead of
//!      leaving it half-seen for a trip back.
//!
//!   The optimizer's initial population puts half its individuals on the frontier
//!   viewpoints ranked best by `frontier cells · exp(-lambda · (path distance + tour_weight ·
//!   tour extra))` (see [`super::optimized`]). Measured against the frontier baselines in `docs/experiments.md`
//!   ("Issue 17: the efficient objective").
//!
//! # Speed
//!
//! One distance field from the robot's cell per decision ([`ExploreObjective::prepare`])
//! serves every candidate's first leg; later legs use A*. All working memory is owned by the
//! objective or borrowed from the caller: an evaluation allocates nothing. Within a decision,
//! the optimizer's evaluations are remembered by target cells ([`super::memo`]: exact, since
//! an evaluation depends only on those cells).
//!
//! Two ways to predict the gain, chosen by the constructor:
//! - **traced** ([`ExploreObjective::new`]): every beam of every viewpoint is traced from the
//!   viewpoint's exact pose (Amanatides & Woo traversal) and seen cells are stamped;
//! - **cached** ([`ExploreObjective::with_view_cache`]): each viewpoint's scan is taken from
//!   the centre of its cell with beams along fixed directions (1° apart for the thesis laser),
//!   its visible Unknown cells are computed once per decision as a bit window and cached by
//!   (cell, direction), and a candidate's gain is the population count of the union of its
//!   viewpoints' windows ([`super::view_cache`]). The path, its viewpoints and its energy are
//!   the same as in the traced model; only where each scan's beams start (at most half a
//!   cell's diagonal away) and their directions (at most half a beam step away) differ. If the
//!   laser or grid does not fit the cache's capacities, the traced model is used.
//!
//! With a cache, paths are also pruned to waypoints with its table of blocked cells
//! ([`crate::planner::BlockedBoxes`]: the same waypoints, found without walking every line of
//! sight).
//!
//! **Scaling**: the optimizers minimise `-(score / unknown_cells)`, in `[-1, 0]`, where
//! `unknown_cells` is the number of Unknown cells in the grid (the largest possible gain);
//! large fitness magnitudes upset the butterfly methods' fragrance `c·|F|^a`.

use core::ops::ControlFlow;

use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::grid::{Cell, CellClass, OccupancyGrid};
use crate::math;
use crate::optim::Problem;
use crate::planner::{
    AStar, DistanceField, Planner, prune_to_waypoints, prune_to_waypoints_with_boxes,
};
use crate::raycast;
use crate::sensor::LaserConfig;
use crate::units;

use super::evaluation::{CandidateStatus, Evaluation, WORST_FITNESS};
use super::leg_memo::{LEG_SLOTS, Leg, LegMemo};
use super::memo::EvalMemo;
use super::reachable::ReachableViewpoints;
use super::tour::FrontierTour;
use super::view_cache::{ViewCache, ViewCacheStats};
use super::{Blacklist, DecideError, DecisionRequest, ExploreConfig, MAX_TARGETS, ObjectiveKind};
use crate::control::follower::MAX_WAYPOINTS;

/// Most cells in one leg of a planned path.
pub const MAX_LEG_CELLS: usize = 4096;
/// Most predicted scans along one candidate's path.
pub const MAX_VIEWPOINTS: usize = 1024;
/// Discount of the efficient objective's gain per step of energy, lambda in
/// `gain · exp(-lambda · steps)` \[1/step\].
pub const EFFICIENCY_LAMBDA_PER_STEP: f32 = 0.5;
/// How far before the frontier viewpoint the efficient objective ends a plan \[m\]
/// ([`ExploreConfig::setback_m`]).
pub const SETBACK_M: f32 = 1.0;
/// How far back along its path a plan's end may move to a cell where the robot can turn in
/// place, when its end lies where it cannot (efficient objective and frontier rules) \[m\]:
/// as far as the set-back ([`SETBACK_M`]), from where the laser still sees what lies ahead.
pub const TURN_BACK_M: f32 = 1.0;
/// The shortest last leg that moving a plan's end back to a turnable cell leaves \[m\]: two
/// and a half 10 cm cells.
pub const MIN_TURN_BACK_LEG_M: f32 = 0.25;
/// Factor on the efficient objective's score of a candidate that clears a small unknown
/// pocket ([`super::reachable::Viewpoint::pocket`]), so that it is not left behind for a long
/// trip back.
pub const POCKET_BONUS: f32 = 2.0;
/// Weight of the frontier tour's extra length in the efficient objective's energy
/// ([`ExploreConfig::tour_weight`]) \[steps/m\].
pub const TOUR_WEIGHT: f32 = 1.0;
/// Under the efficient objective, a point within this share of the laser's range of a
/// frontier viewpoint is kept as a target if its cell is reachable and known Free.
pub const NEAR_FRONTIER_SHARE_OF_RANGE: f32 = 0.5;

/// The objective's working memory and the state of the current decision. Paths through the
/// targets are planned by `P` (A* unless a test double stands in).
pub struct ExploreObjective<'m, const N: usize, P: Planner<N> = AStar<N>> {
    field: &'m mut DistanceField<N>,
    planner: &'m mut P,
    stamps: &'m mut [u32],
    generation: u32,
    leg: [Cell; MAX_LEG_CELLS],
    waypoints: [Point2; MAX_WAYPOINTS],
    waypoint_len: usize,
    viewpoints: [Pose2; MAX_VIEWPOINTS],
    viewpoint_len: usize,
    targets: [Point2; MAX_TARGETS],
    target_len: usize,
    start: Pose2,
    start_cell: Cell,
    unknown_cells: u32,
    budget_steps: f32,
    config: ExploreConfig,
    memo: EvalMemo,
    /// Legs planned in this decision, when there is no visibility cache (whose larger table
    /// serves otherwise: [`remembered_leg`]).
    legs: LegMemo<LEG_SLOTS>,
    views: Option<&'m mut ViewCache>,
    cached: bool,
    reachable: ReachableViewpoints,
    tour: FrontierTour,
    /// Extra tour length of the last planned candidate's first target \[m\].
    tour_extra_m: f32,
    /// Plans of this decision end [`ExploreConfig::setback_m`] short (efficient objective,
    /// not a re-plan).
    set_back_plans: bool,
    /// Plans of this decision end where the robot can turn in place
    /// ([`TURN_BACK_M`]; efficient objective and the frontier rules, not a re-plan).
    turnable_ends: bool,
}

impl<const N: usize, P: Planner<N>> core::fmt::Debug for ExploreObjective<'_, N, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ExploreObjective")
            .field("start", &self.start)
            .field("unknown_cells", &self.unknown_cells)
            .field("budget_steps", &self.budget_steps)
            .finish_non_exhaustive()
    }
}

impl<'m, const N: usize, P: Planner<N>> ExploreObjective<'m, N, P> {
    /// An objective over the caller's planner memory and a visited-cell stamp slice of at
    /// least the grid's cell count (on a host: `DistanceField::new_boxed()`,
    /// `AStar::new_boxed()` and `vec![0; N]`).
    pub fn new(field: &'m mut DistanceField<N>, planner: &'m mut P, stamps: &'m mut [u32]) -> Self {
        Self::build(field, planner, stamps, None)
    }

    /// An objective predicting gains with the cached model (see [Speed](self#speed)), over the
    /// caller's planner memory, stamp slice (as for [`Self::new`]) and visibility cache (on a
    /// host: `ViewCache::new_boxed()`).
    pub fn with_view_cache(
        field: &'m mut DistanceField<N>,
        planner: &'m mut P,
        stamps: &'m mut [u32],
        views: &'m mut ViewCache,
    ) -> Self {
        Self::build(field, planner, stamps, Some(views))
    }

    fn build(
        field: &'m mut DistanceField<N>,
        planner: &'m mut P,
        stamps: &'m mut [u32],
        views: Option<&'m mut ViewCache>,
    ) -> Self {
        stamps.fill(0);
        Self {
            field,
            planner,
            stamps,
            generation: 0,
            leg: [Cell::new(0, 0); MAX_LEG_CELLS],
            waypoints: [Point2::new(0.0, 0.0); MAX_WAYPOINTS],
            waypoint_len: 0,
            viewpoints: [Pose2::default(); MAX_VIEWPOINTS],
            viewpoint_len: 0,
            targets: [Point2::new(0.0, 0.0); MAX_TARGETS],
            target_len: 0,
            start: Pose2::default(),
            start_cell: Cell::new(0, 0),
            unknown_cells: 0,
            budget_steps: 0.0,
            config: ExploreConfig::default(),
            memo: EvalMemo::new(),
            legs: LegMemo::new(),
            views,
            cached: false,
            reachable: ReachableViewpoints::new(),
            tour: FrontierTour::new(),
            tour_extra_m: 0.0,
            set_back_plans: false,
            turnable_ends: false,
        }
    }

    /// Starts a decision: starts the distance field's sweep from the robot's cell (it runs
    /// lazily, as far as the questions need) and records the budget. Must be called before
    /// [`Self::evaluate_targets`] whenever the map or the pose changed.
    pub fn prepare(
        &mut self,
        req: &DecisionRequest<'_, N>,
        config: &ExploreConfig,
    ) -> Result<(), DecideError> {
        self.prepare_with(req, config, true)
    }

    /// Starts a re-plan: as [`Self::prepare`], but without the visibility cache's
    /// per-decision pass, for [`Self::plan_targets`] (which predicts no gain).
    pub fn prepare_plan(
        &mut self,
        req: &DecisionRequest<'_, N>,
        config: &ExploreConfig,
    ) -> Result<(), DecideError> {
        self.prepare_with(req, config, false)
    }

    fn prepare_with(
        &mut self,
        req: &DecisionRequest<'_, N>,
        config: &ExploreConfig,
        predict: bool,
    ) -> Result<(), DecideError> {
        let cells = req.grid.cell_count();
        if cells > self.stamps.len() || req.trav.geometry() != req.grid.geometry() {
            return Err(DecideError::Mismatch {
                grid_cells: cells,
                capacity: self.stamps.len(),
            });
        }
        if config.targets == 0 || config.targets > MAX_TARGETS {
            return Err(DecideError::BadTargetCount {
                got: config.targets,
            });
        }
        let geom = req.grid.geometry();
        let start_cell = geom.cell_at_unchecked(req.pose.position());
        self.field
            .start(req.trav, start_cell)
            .map_err(DecideError::Start)?;
        self.start = req.pose;
        self.start_cell = start_cell;
        self.unknown_cells = (cells - req.grid.counts().known()) as u32;
        self.budget_steps = req.battery_steps - config.reserve_steps;
        self.config = *config;
        self.memo.clear();
        self.legs.clear();
        if let Some(v) = self.views.as_deref_mut() {
            v.legs.clear();
        }
        let efficient = predict && config.objective == ObjectiveKind::Efficient;
        self.set_back_plans = efficient && config.setback_m > 0.0;
        self.turnable_ends = efficient;
        if efficient {
            self.reachable.near_m = req.laser.max_range_m * NEAR_FRONTIER_SHARE_OF_RANGE;
            self.reachable.collect(req.grid, req.trav, self.field);
            if config.tour_weight > 0.0 {
                self.tour
                    .build(self.reachable.as_slice(), req.grid.geometry().resolution_m);
            } else {
                self.tour = FrontierTour::new();
            }
        } else {
            self.tour = FrontierTour::new();
        }
        self.cached = match self.views.as_deref_mut() {
            Some(v) => {
                v.boxes.build(req.trav);
                predict && v.begin(req.grid, req.laser)
            }
            None => false,
        };
        Ok(())
    }

    /// Whether this decision predicts gains with the cached model (a visibility cache was
    /// given and the laser and grid fit it).
    pub fn uses_view_cache(&self) -> bool {
        self.cached
    }

    /// The planner of the legs between targets.
    #[cfg(test)]
    pub(crate) fn planner(&self) -> &P {
        self.planner
    }

    /// The visibility cache, if one was given.
    #[cfg(test)]
    pub(crate) fn view_cache(&self) -> Option<&ViewCache> {
        self.views.as_deref()
    }

    /// Counters of the visibility cache for the current decision (zero without one).
    pub fn view_stats(&self) -> ViewCacheStats {
        self.views.as_deref().map(|v| v.stats()).unwrap_or_default()
    }

    /// Optimizer evaluations of the current decision answered from remembered ones.
    pub fn remembered_evaluations(&self) -> u32 {
        self.memo.hits()
    }

    /// The distance field from the robot's cell (valid after [`Self::prepare`]).
    pub fn field(&self) -> &DistanceField<N> {
        self.field
    }

    /// Unknown cells in the grid at [`Self::prepare`]: the largest possible gain.
    pub fn unknown_cells(&self) -> u32 {
        self.unknown_cells
    }

    /// Waypoints of the last evaluated candidate, map frame \[m\].
    pub fn waypoints(&self) -> &[Point2] {
        &self.waypoints[..self.waypoint_len]
    }

    /// Poses of the predicted scans of the last evaluated candidate (robot frame poses in the
    /// map frame).
    pub fn viewpoints(&self) -> &[Pose2] {
        &self.viewpoints[..self.viewpoint_len]
    }

    /// Targets of the last evaluated candidate, snapped to their cell centres \[m\].
    pub fn targets(&self) -> &[Point2] {
        &self.targets[..self.target_len]
    }

    /// Evaluates the candidate visiting `targets` in order (map frame \[m\]).
    pub fn evaluate_targets(
        &mut self,
        req: &DecisionRequest<'_, N>,
        targets: &[Point2],
    ) -> Evaluation {
        let mut eval = self.plan_targets(req, targets);
        if eval.status != CandidateStatus::Feasible {
            return eval;
        }
        if let Err(status) = self.sample_viewpoints() {
            eval.status = status;
            return eval;
        }
        eval.gain_cells = match self.views.as_deref_mut() {
            Some(views) if self.cached => {
                views.gain(req.laser, &self.viewpoints[..self.viewpoint_len])
            }
            _ => self.predict_gain(req.grid, req.laser),
        };
        let pocket =
            self.config.objective == ObjectiveKind::Efficient && self.clears_pocket(req.grid);
        let tour = self.config.tour_weight * self.tour_extra_m;
        eval.fitness = self.fitness_of(eval.gain_cells, eval.energy_steps + tour, pocket);
        eval
    }

    /// Plans the path from the robot through `targets` in order, as
    /// [`Self::evaluate_targets`] does (same legs, waypoints, length, energy and status), but
    /// predicts no gain: `gain_cells` is 0 and `fitness` the worst. For re-planning towards
    /// targets already chosen; call [`Self::prepare_plan`] (or [`Self::prepare`]) first.
    pub fn plan_targets(&mut self, req: &DecisionRequest<'_, N>, targets: &[Point2]) -> Evaluation {
        self.waypoint_len = 0;
        self.viewpoint_len = 0;
        self.target_len = 0;
        let mut eval = Evaluation {
            status: CandidateStatus::Feasible,
            gain_cells: 0,
            energy_steps: 0.0,
            path_length_m: 0.0,
            fitness: WORST_FITNESS,
        };
        if let Err(status) = self.plan(req, targets, &mut eval) {
            eval.status = status;
        } else if eval.energy_steps > self.budget_steps {
            eval.status = CandidateStatus::OverBudget;
        }
        eval
    }

    /// Plans of this decision end short of their viewpoints ([`ExploreConfig::setback_m`]) or
    /// (`false`) go all the way, until the next [`Self::prepare`].
    pub(crate) fn set_back(&mut self, on: bool) -> bool {
        core::mem::replace(&mut self.set_back_plans, on)
    }

    /// Plans of this decision end where the robot can turn in place ([`TURN_BACK_M`]) or
    /// (`false`) where they lead, until the next [`Self::prepare`]. The efficient objective
    /// turns it on; the frontier rules, which plan with the thesis's objective, turn it on
    /// after [`Self::prepare`].
    pub(crate) fn end_where_turnable(&mut self, on: bool) -> bool {
        core::mem::replace(&mut self.turnable_ends, on)
    }

    /// The frontier tour of the current decision (built by [`Self::prepare`] for the
    /// efficient objective; empty otherwise).
    pub fn frontier_tour(&self) -> &FrontierTour {
        &self.tour
    }

    /// The frontier viewpoints of the current decision (listed by [`Self::prepare`] for the
    /// efficient objective).
    pub fn reachable_viewpoints(&self) -> &ReachableViewpoints {
        &self.reachable
    }

    /// Moves each target to the cell the robot would use for it ([`ReachableViewpoints::snap`])
    /// under the efficient objective (the thesis's targets stay where they are). Returns
    /// `false` if a target could not be snapped (no frontier viewpoint listed, or outside the
    /// grid).
    pub fn snap_targets(&self, req: &DecisionRequest<'_, N>, targets: &mut [Point2]) -> bool {
        if self.config.objective != ObjectiveKind::Efficient {
            return true;
        }
        let geom = req.grid.geometry();
        for t in targets.iter_mut() {
            let Some(cell) = geom.cell_at(*t) else {
                return false;
            };
            match self.reachable.snap(cell, req.grid, req.trav, self.field) {
                Some(c) => *t = geom.cell_center(c),
                None => return false,
            }
        }
        true
    }

    /// Whether a target of the last planned candidate clears a small unknown pocket: it lies
    /// in the block of a listed viewpoint that is a [pocket](super::reachable::Viewpoint::pocket).
    fn clears_pocket(&self, grid: &OccupancyGrid<N>) -> bool {
        let geom = grid.geometry();
        let side = self.reachable.block_cells();
        self.targets().iter().any(|&t| {
            let c = geom.cell_at_unchecked(t);
            self.reachable
                .nearest(c)
                .is_some_and(|(v, d2)| v.pocket && d2 <= side * side)
        })
    }

    /// The scaled fitness of a feasible plan.
    fn fitness_of(&self, gain: u32, steps: f32, pocket: bool) -> f32 {
        if self.config.objective == ObjectiveKind::Efficient {
            let bonus = if pocket {
                self.config.pocket_bonus
            } else {
                1.0
            };
            let lambda = self.config.efficiency_per_step;
            let score = bonus * gain as f32 * math::exp(-lambda * steps);
            let max = (self.unknown_cells as f32).max(1.0);
            return -(score / max).min(1.0);
        }
        let gain = gain as f32;
        let mut score = match self.config.cost_weight {
            Some(lambda) => (gain - lambda * steps).max(0.0),
            None => gain,
        };
        if self.config.gain_per_step {
            // Gain per step, scaled by the largest gain so that it stays within [0, 1] for
            // plans of at least one step.
            score /= steps.max(1.0);
        }
        let max = (self.unknown_cells as f32).max(1.0);
        -(score / max).min(1.0)
    }

    /// Plans the legs, fills targets and waypoints, computes length and energy.
    fn plan(
        &mut self,
        req: &DecisionRequest<'_, N>,
        targets: &[Point2],
        eval: &mut Evaluation,
    ) -> Result<(), CandidateStatus> {
        let geom = *req.grid.geometry();
        let mut prev = self.start_cell;
        let mut last_leg = 0;
        self.tour_extra_m = match targets.first().and_then(|&t| geom.cell_at(t)) {
            Some(c) if !self.tour.is_empty() => self.tour.extra_m(c),
            _ => 0.0,
        };
        for (k, &t) in targets.iter().enumerate() {
            last_leg = self.waypoint_len.saturating_sub(1);
            let cell = geom.cell_at(t).ok_or(CandidateStatus::OutOfBounds)?;
            if !req.trav.is_passable(cell) {
                return Err(CandidateStatus::Blocked);
            }
            if k < MAX_TARGETS {
                self.targets[k] = geom.cell_center(cell);
                self.target_len = k + 1;
            }
            let out = &mut self.waypoints[self.waypoint_len..];
            // A leg planned earlier in this decision (a first leg apart from an A* leg
            // between the same cells): the same waypoints, copied (see `leg_memo`).
            let remembered = remembered_leg(&self.views, &self.legs, prev, cell, k == 0);
            let n = match remembered {
                Some(Ok(w)) => {
                    out.get_mut(..w.len())
                        .ok_or(CandidateStatus::TooLong)?
                        .copy_from_slice(w);
                    w.len()
                }
                Some(Err(status)) => return Err(status),
                // A target the robot's distance field does not reach cannot be reached from
                // the previous target either, which the field reaches: the same moves on the
                // same layer. Answered here, the planner does not flood the whole reachable
                // region to find no path (the thesis objective's targets fall anywhere); the
                // field, swept lazily, settles that region at most once per decision.
                None if k > 0 && !self.field.is_reachable(cell) => {
                    remember_leg(
                        &mut self.views,
                        &mut self.legs,
                        (prev, cell, false),
                        Err(CandidateStatus::Unreachable),
                    );
                    return Err(CandidateStatus::Unreachable);
                }
                None => {
                    let planned = if k == 0 {
                        self.field.path_to(cell, &mut self.leg)
                    } else {
                        self.planner.plan(req.trav, prev, cell, &mut self.leg)
                    };
                    let planned = planned.map_err(|e| match e {
                        crate::planner::PlanError::CapacityExceeded { .. } => {
                            CandidateStatus::TooLong
                        }
                        _ => CandidateStatus::Unreachable,
                    });
                    let planned = match planned {
                        Ok(p) => p,
                        Err(status) => {
                            remember_leg(
                                &mut self.views,
                                &mut self.legs,
                                (prev, cell, k == 0),
                                Err(status),
                            );
                            return Err(status);
                        }
                    };
                    let leg = &self.leg[..planned.len];
                    let n = match self.views.as_deref() {
                        Some(v) => prune_to_waypoints_with_boxes(req.trav, &v.boxes, leg, out),
                        None => prune_to_waypoints(req.trav, leg, out),
                    }
                    .map_err(|_| CandidateStatus::TooLong)?;
                    remember_leg(
                        &mut self.views,
                        &mut self.legs,
                        (prev, cell, k == 0),
                        Ok(&out[..n]),
                    );
                    n
                }
            };
            // Later legs start where the previous one ended: drop the repeated waypoint.
            if self.waypoint_len > 0 && n > 0 {
                self.waypoints.copy_within(
                    self.waypoint_len + 1..self.waypoint_len + n,
                    self.waypoint_len,
                );
                self.waypoint_len += n - 1;
            } else {
                self.waypoint_len += n;
            }
            prev = cell;
        }
        // The path starts at the robot's own position, not at the centre of its cell.
        if self.waypoint_len > 0 {
            self.waypoints[0] = self.start.position();
        }
        if self.set_back_plans {
            self.trim_last_leg(last_leg, &geom);
        }
        if self.turnable_ends {
            self.end_where_turnable_on(req.trav, last_leg);
        }
        let mut heading = self.start.theta;
        let mut length = 0.0f32;
        let mut rotation = 0.0f32;
        let mut from = self.start.position();
        for &w in &self.waypoints[..self.waypoint_len] {
            let d = from.distance(w);
            if d > 1e-6 {
                let bearing = from.bearing_to(w);
                rotation += normalize_angle(bearing - heading).abs();
                heading = bearing;
                length += d;
                from = w;
            }
        }
        eval.path_length_m = length;
        eval.energy_steps = units::steps(length, rotation);
        Ok(())
    }

    /// Ends the last leg (from waypoint `from` on) [`ExploreConfig::setback_m`] before its
    /// end, at the centre of the cell there, which becomes the last target: the laser sees the
    /// frontier ahead from there without the drive up to it. A leg no longer than the setback
    /// is kept whole.
    fn trim_last_leg(&mut self, from: usize, geom: &crate::grid::GridGeometry) {
        let mut left = self.config.setback_m;
        let mut end = self.waypoint_len;
        while end >= 2 && end - 1 > from {
            let (a, b) = (self.waypoints[end - 2], self.waypoints[end - 1]);
            let d = a.distance(b);
            if d > left {
                let f = (d - left) / d;
                let cut = Point2::new(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f);
                let centre = geom.cell_center(geom.cell_at_unchecked(cut));
                self.waypoints[end - 1] = centre;
                self.waypoint_len = end;
                if self.target_len > 0 {
                    self.targets[self.target_len - 1] = centre;
                }
                return;
            }
            left -= d;
            end -= 1;
        }
    }

    /// Moves the end of the last leg (from waypoint `from` on) back along the path, at most
    /// [`TURN_BACK_M`], to the first cell where the robot can turn in place
    /// ([`crate::planner::Traversability::can_turn`]), which becomes the last target. The
    /// follower turns in place at the start of the next plan, so a plan ending in the no-turn
    /// band (beside a wall, in a door) leaves the robot where the next one's first turn does
    /// not fit, and the safety monitor refuses it again and again (nearest-frontier, house,
    /// seed 32: driven up to the frontier 0.3 m from a wall, heading towards it). The end stays
    /// where it is if no such cell lies within reach, or if the new end would leave less than
    /// [`MIN_TURN_BACK_LEG_M`] of the leg: a plan that hardly moves the robot makes no
    /// progress, so the robot then drives the whole way (a narrow corridor, a door it must
    /// pass).
    fn end_where_turnable_on(&mut self, trav: &crate::planner::Traversability<N>, from: usize) {
        let end = self.waypoint_len;
        if end < 2 || end - 1 <= from {
            return;
        }
        let geom = *trav.geometry();
        let last = self.waypoints[end - 1];
        if geom.cell_at(last).is_none_or(|c| trav.can_turn(c)) {
            return;
        }
        // The leg's length from its first waypoint, for the shortest leg kept.
        let leg_m: f32 = (from + 1..end)
            .map(|j| self.waypoints[j - 1].distance(self.waypoints[j]))
            .sum();
        let step = 0.5 * geom.resolution_m;
        let mut back = 0.0f32;
        let mut seg = end - 1;
        while seg > from {
            let (a, b) = (self.waypoints[seg - 1], self.waypoints[seg]);
            let d = a.distance(b);
            // Points on the segment from b back to a, every half cell.
            let mut t = if seg == end - 1 { step } else { 0.0 };
            while t <= d {
                if back + t > TURN_BACK_M || leg_m - (back + t) < MIN_TURN_BACK_LEG_M {
                    return;
                }
                let f = if d > 0.0 { (d - t) / d } else { 0.0 };
                let p = Point2::new(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f);
                if let Some(c) = geom.cell_at(p)
                    && trav.can_turn(c)
                {
                    let centre = geom.cell_center(c);
                    self.waypoints[seg] = centre;
                    self.waypoint_len = seg + 1;
                    if self.target_len > 0 {
                        self.targets[self.target_len - 1] = centre;
                    }
                    return;
                }
                t += step;
            }
            back += d;
            seg -= 1;
        }
    }

    /// Predicted scan poses along the waypoint polyline.
    fn sample_viewpoints(&mut self) -> Result<(), CandidateStatus> {
        let spacing = self.config.viewpoint_spacing_m.max(0.05);
        let push = |vp: &mut [Pose2; MAX_VIEWPOINTS], len: &mut usize, p: Pose2| {
            if *len == MAX_VIEWPOINTS {
                return Err(CandidateStatus::TooLong);
            }
            vp[*len] = p;
            *len += 1;
            Ok(())
        };
        let mut len = 0usize;
        push(&mut self.viewpoints, &mut len, self.start)?;
        let mut from = self.start.position();
        for &w in &self.waypoints[..self.waypoint_len] {
            let d = from.distance(w);
            if d <= 1e-6 {
                continue;
            }
            let heading = from.bearing_to(w);
            let n = math::ceil(d / spacing) as usize;
            for s in 1..=n {
                let f = (s as f32 / n as f32).min(1.0);
                let p = Pose2::new(
                    from.x + (w.x - from.x) * f,
                    from.y + (w.y - from.y) * f,
                    heading,
                );
                push(&mut self.viewpoints, &mut len, p)?;
            }
            from = w;
        }
        self.viewpoint_len = len;
        Ok(())
    }

    /// Unknown cells seen from the viewpoints, each counted once.
    fn predict_gain(&mut self, grid: &OccupancyGrid<N>, laser: &LaserConfig) -> u32 {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamps.fill(0);
            self.generation = 1;
        }
        let stamp = self.generation;
        let geom = *grid.geometry();
        let stamps = &mut *self.stamps;
        let mut gain = 0u32;
        for vp in &self.viewpoints[..self.viewpoint_len] {
            let pose = vp.compose(laser.mount);
            let origin = pose.position();
            for b in 0..laser.beam_count as usize {
                let angle = pose.theta + laser.beam_angle(b);
                let end = Point2::new(
                    origin.x + math::cos(angle) * laser.max_range_m,
                    origin.y + math::sin(angle) * laser.max_range_m,
                );
                raycast::traverse(&geom, origin, end, |_, i| match grid.class(i) {
                    CellClass::Occupied => ControlFlow::Break(()),
                    CellClass::Free => ControlFlow::Continue(()),
                    CellClass::Unknown => {
                        if stamps[i] != stamp {
                            stamps[i] = stamp;
                            gain += 1;
                        }
                        ControlFlow::Continue(())
                    }
                });
            }
        }
        gain
    }

    /// This objective bound to one decision's request, as an optimizer [`Problem`] over
    /// `2 * config.targets` genes (x0, y0, x1, y1, ...).
    pub fn problem<'s, 'r>(
        &'s mut self,
        req: &'s DecisionRequest<'r, N>,
    ) -> BoundObjective<'s, 'm, 'r, N, P> {
        BoundObjective {
            objective: self,
            req,
            blacklist: None,
        }
    }

    /// As [`Self::problem`], and a candidate with a target near a place of `blacklist` (one the
    /// robot failed to reach) scores [`WORST_FITNESS`], as a blocked one does.
    pub fn problem_avoiding<'s, 'r>(
        &'s mut self,
        req: &'s DecisionRequest<'r, N>,
        blacklist: &'s Blacklist,
    ) -> BoundObjective<'s, 'm, 'r, N, P> {
        BoundObjective {
            objective: self,
            req,
            blacklist: Some(blacklist),
        }
    }
}

/// An [`ExploreObjective`] bound to a request: the optimizer's view.
pub struct BoundObjective<'s, 'm, 'r, const N: usize, P: Planner<N> = AStar<N>> {
    objective: &'s mut ExploreObjective<'m, N, P>,
    req: &'s DecisionRequest<'r, N>,
    blacklist: Option<&'s Blacklist>,
}

impl<const N: usize, P: Planner<N>> core::fmt::Debug for BoundObjective<'_, '_, '_, N, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.objective.fmt(f)
    }
}

impl<const N: usize, P: Planner<N>> BoundObjective<'_, '_, '_, N, P> {
    /// The decision's distance field.
    pub(crate) fn field(&self) -> &DistanceField<N> {
        self.objective.field
    }

    /// The decision's settings.
    pub(crate) fn config(&self) -> &ExploreConfig {
        &self.objective.config
    }

    /// The decision's frontier viewpoints (efficient objective).
    pub(crate) fn viewpoints(&self) -> &ReachableViewpoints {
        &self.objective.reachable
    }

    /// The decision's frontier tour (efficient objective).
    pub(crate) fn tour(&self) -> &FrontierTour {
        &self.objective.tour
    }
}

impl<const N: usize, P: Planner<N>> Problem for BoundObjective<'_, '_, '_, N, P> {
    fn dim(&self) -> usize {
        2 * self.objective.config.targets
    }

    fn bounds(&self, gene: usize) -> (f32, f32) {
        let g = self.req.grid.geometry();
        // Half a millimetre inside, so the upper bound still falls in the last cell.
        let margin = 5e-4;
        if gene.is_multiple_of(2) {
            (g.origin.x, g.origin.x + g.width_m() - margin)
        } else {
            (g.origin.y, g.origin.y + g.height_m() - margin)
        }
    }

    fn evaluate(&mut self, genes: &[f32]) -> f32 {
        let mut pts = [Point2::new(0.0, 0.0); MAX_TARGETS];
        let mut cells = [0u32; MAX_TARGETS];
        let k = (genes.len() / 2).min(MAX_TARGETS);
        let geom = self.req.grid.geometry();
        let mut inside = true;
        for (i, p) in pts[..k].iter_mut().enumerate() {
            *p = Point2::new(genes[2 * i], genes[2 * i + 1]);
            match geom.cell_at(*p).and_then(|c| geom.index(c)) {
                Some(index) => cells[i] = index as u32,
                None => inside = false,
            }
        }
        if !inside {
            return self.objective.evaluate_targets(self.req, &pts[..k]).fitness;
        }
        if self.objective.config.objective == ObjectiveKind::Efficient {
            if !self.objective.snap_targets(self.req, &mut pts[..k]) {
                return WORST_FITNESS;
            }
            for (i, p) in pts[..k].iter().enumerate() {
                // Snapped points are cell centres inside the grid.
                cells[i] = geom.index(geom.cell_at_unchecked(*p)).unwrap_or(0) as u32;
            }
        }
        if let Some(list) = self.blacklist
            && pts[..k]
                .iter()
                .any(|&p| list.contains(geom.cell_center(geom.cell_at_unchecked(p))))
        {
            return WORST_FITNESS;
        }
        if let Some(eval) = self.objective.memo.get(&cells[..k]) {
            return eval.fitness;
        }
        let mut eval = self.objective.evaluate_targets(self.req, &pts[..k]);
        // A plan set back short of its viewpoint ends elsewhere: that end must not be a
        // place the robot failed to reach either.
        if let Some(list) = self.blacklist
            && self.objective.set_back_plans
            && self.objective.targets().iter().any(|&t| list.contains(t))
        {
            eval.fitness = WORST_FITNESS;
        }
        self.objective.memo.put(&cells[..k], eval);
        eval.fitness
    }
}

impl<const N: usize, P: Planner<N>> ExploreObjective<'_, N, P> {
    /// The [`super::Decision`] for the last evaluated candidate, if it was feasible.
    pub(crate) fn decision(
        &self,
        eval: &Evaluation,
        evaluations: u32,
        history: &[f32],
    ) -> Option<super::Decision> {
        if eval.status != CandidateStatus::Feasible {
            return None;
        }
        let mut d = super::Decision {
            targets: heapless::Vec::new(),
            waypoints: heapless::Vec::new(),
            path_length_m: eval.path_length_m,
            predicted_gain_cells: eval.gain_cells,
            energy_steps: eval.energy_steps,
            evaluations,
            history: heapless::Vec::new(),
        };
        // Capacities match the objective's buffers, so these cannot fail.
        d.targets.extend_from_slice(self.targets()).ok()?;
        d.waypoints.extend_from_slice(self.waypoints()).ok()?;
        let h = &history[..history.len().min(super::MAX_DECISION_HISTORY)];
        d.history.extend_from_slice(h).ok()?;
        Some(d)
    }
}

/// The leg from `from` to `to` (from the robot's cell if `from_robot`) if this decision
/// planned it already: in the visibility cache's table when there is a cache, else in the
/// objective's own.
fn remembered_leg<'a>(
    views: &'a Option<&mut ViewCache>,
    own: &'a LegMemo<LEG_SLOTS>,
    from: Cell,
    to: Cell,
    from_robot: bool,
) -> Option<Leg<'a>> {
    match views.as_deref() {
        Some(v) => v.legs.get(from, to, from_robot),
        None => own.get(from, to, from_robot),
    }
}

/// Remembers the leg `(from, to, from_robot)` where [`remembered_leg`] looks for it.
fn remember_leg(
    views: &mut Option<&mut ViewCache>,
    own: &mut LegMemo<LEG_SLOTS>,
    (from, to, from_robot): (Cell, Cell, bool),
    leg: Leg<'_>,
) {
    match views.as_deref_mut() {
        Some(v) => v.legs.put(from, to, from_robot, leg),
        None => own.put(from, to, from_robot, leg),
    }
}
