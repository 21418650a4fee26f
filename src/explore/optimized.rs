//! Targets chosen by a population optimizer on the energy-constrained objective: the thesis's
//! method with [`Method::Xboa`] (Bendahmane, PhD thesis, USTO Oran 2023), or any of the other
//! methods of [`crate::optim`] for comparison.
//!
//! The initial population is drawn from the caller's seeded RNG, uniformly in the map bounds
//! (the thesis; the default, with half the individuals then moved onto the best frontier
//! viewpoints under the efficient objective) or partly on reachable frontier cells
//! ([`InitialPopulation::NearFrontiers`]; measured in `docs/benchmarks.md`); the run stops after [`ExploreConfig::max_generations`] generations (no early stop, so the
//! history has one entry per generation). The best genome is evaluated once more to produce
//! the plan.
//!
//! Candidates with a target near a place the robot failed to reach ([`Optimized::blacklist`])
//! score worst. When the run ends with no feasible candidate, or with one predicted to see
//! nothing Unknown (both happen late in a mission, when little reachable space is left
//! Unknown and a small population can miss it), the decision falls back to the nearest
//! reachable frontier (by path distance) that is not blacklisted, so a decision is never
//! wasted while Unknown space is reachable: the selector answers [`Outcome::Done`] only when
//! no frontier can be reached, and [`DecideError::AllBlacklisted`] when every reachable one is
//! blacklisted.

use crate::optim::{self, MAX_DIM, Method, Optimizer, Population, Problem, StopRules};
use crate::planner::{AStar, Planner};
use crate::random;

use super::evaluation::WORST_FITNESS;
use super::objective::{BoundObjective, ExploreObjective};
use super::{
    Blacklist, DecideError, DecisionRequest, ExploreConfig, FrontierScan, MAX_TARGETS,
    ObjectiveKind, Outcome, TargetSelector, nearest_reachable_frontier, sample_reachable_frontier,
};
use crate::geometry::Point2;

/// How the optimizer's initial population is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InitialPopulation {
    /// Every gene uniform in the map bounds (the thesis).
    Uniform,
    /// The first `round(share * population)` individuals put each target on a reachable
    /// frontier cell (the cell the robot would drive to, see [`super::NearestFrontier`]),
    /// drawn by scanning the grid from a random cell to the next such cell; the others are
    /// uniform.
    NearFrontiers {
        /// Fraction of the population started on frontiers, 0 to 1.
        share: f32,
    },
}

/// Optimizer-based target selection.
#[derive(Debug)]
pub struct Optimized<'o, 'm, const N: usize, P: Planner<N> = AStar<N>> {
    /// The optimization method.
    pub method: Method,
    /// Decision settings (k, reserve, population, generations).
    pub config: ExploreConfig,
    /// How the initial population is drawn ([`InitialPopulation::Uniform`] by default).
    pub initial: InitialPopulation,
    /// Places the robot failed to reach: candidates with a target near one score worst, and
    /// the fallback frontier avoids them (empty by default).
    pub blacklist: Blacklist,
    objective: &'o mut ExploreObjective<'m, N, P>,
}

impl<'o, 'm, const N: usize, P: Planner<N>> Optimized<'o, 'm, N, P> {
    /// A selector running `method` over `objective`'s working memory.
    pub fn new(
        method: Method,
        config: ExploreConfig,
        objective: &'o mut ExploreObjective<'m, N, P>,
    ) -> Self {
        Self {
            method,
            config,
            initial: InitialPopulation::Uniform,
            blacklist: Blacklist::default(),
            objective,
        }
    }
}

impl<const N: usize, P: Planner<N>> TargetSelector<N> for Optimized<'_, '_, N, P> {
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        self.objective.prepare(req, &self.config)?;
        // Entries lapse once the map around them changed.
        self.blacklist.forget_changed(req.grid);
        let fallback =
            match nearest_reachable_frontier(req.grid, self.objective.field(), &self.blacklist) {
                FrontierScan::NoneReachable => return Ok(Outcome::Done),
                FrontierScan::AllBlacklisted => {
                    return Err(DecideError::AllBlacklisted {
                        entries: self.blacklist.len(),
                    });
                }
                FrontierScan::Nearest(cell) => req.grid.geometry().cell_center(cell),
            };
        let rules = StopRules {
            max_generations: self.config.max_generations,
            patience: None,
            max_evaluations: None,
        };
        let mut opt = self.method.build_tuned(
            self.config.preset,
            self.config.tuning,
            self.config.population,
            rules.max_generations,
        );
        let (best, evaluations, history_len) = {
            let mut problem = self.objective.problem_avoiding(req, &self.blacklist);
            let efficient = self.config.objective == ObjectiveKind::Efficient;
            let initial = match self.initial {
                InitialPopulation::Uniform if efficient => {
                    near_viewpoints(&problem, req, self.config.population, rng)
                }
                InitialPopulation::Uniform => {
                    Population::uniform(&problem, self.config.population, rng)
                }
                InitialPopulation::NearFrontiers { share } => {
                    near_frontiers(&problem, req, self.config.population, share, rng)
                }
            }
            .map_err(DecideError::Optimizer)?;
            optim::run(&mut opt, &mut problem, &initial, &rules, rng)
                .map_err(DecideError::Optimizer)?;
            let mut best = [0.0f32; 2 * MAX_TARGETS];
            let g = opt.best_genome();
            best[..g.len()].copy_from_slice(g);
            (best, opt.evaluations(), g.len())
        };
        let found = opt.best_fitness() < WORST_FITNESS;
        if found {
            let mut pts = [Point2::new(0.0, 0.0); MAX_TARGETS];
            let k = history_len / 2;
            for (i, p) in pts[..k].iter_mut().enumerate() {
                *p = Point2::new(best[2 * i], best[2 * i + 1]);
            }
            // The efficient objective scored the targets the points snap to.
            let snapped = self.objective.snap_targets(req, &mut pts[..k]);
            if snapped
                && self.config.objective == ObjectiveKind::Efficient
                && self.config.near_pockets_first
                && let Some(d) = self.pocket_first(req, pts[0], evaluations, opt.history())
            {
                return Ok(Outcome::Go(d));
            }
            let eval = self.objective.evaluate_targets(req, &pts[..k]);
            if snapped
                && eval.gain_cells > 0
                && let Some(d) = self.objective.decision(&eval, evaluations, opt.history())
            {
                return Ok(Outcome::Go(d));
            }
        }
        // Every candidate was infeasible, blacklisted or blind (nothing Unknown in view), yet
        // reachable Unknown space is left: go to the nearest frontier the robot has not
        // failed to reach, so that a decision is never wasted.
        // It drives up to that frontier, as nearest-frontier would (no set-back).
        let was = self.objective.set_back(false);
        let eval = self.objective.evaluate_targets(req, &[fallback]);
        self.objective.set_back(was);
        self.objective
            .decision(&eval, evaluations + 1, opt.history())
            .map(Outcome::Go)
            .ok_or(DecideError::NoFeasibleTarget {
                battery_steps: req.battery_steps,
            })
    }
}

impl<const N: usize, P: Planner<N>> Optimized<'_, '_, N, P> {
    /// The plan to a small unknown pocket nearer the robot than `target` (the optimizer's
    /// first target, snapped), driven up to its viewpoint (no set-back), if there is one and
    /// it is predicted to see at least [`super::near_pocket::worth_cells`] Unknown cells
    /// ([`super::near_pocket`]).
    fn pocket_first(
        &mut self,
        req: &DecisionRequest<'_, N>,
        target: Point2,
        evaluations: u32,
        history: &[f32],
    ) -> Option<super::Decision> {
        let geom = *req.grid.geometry();
        let cell = super::near_pocket::pocket_before(
            self.objective.reachable_viewpoints(),
            self.objective.field(),
            geom.cell_at(target)?,
            geom.resolution_m,
            &self.blacklist,
            |c| geom.cell_center(c),
        )?;
        let was = self.objective.set_back(false);
        let eval = self
            .objective
            .evaluate_targets(req, &[geom.cell_center(cell)]);
        self.objective.set_back(was);
        if (eval.gain_cells as f32) < super::near_pocket::worth_cells(req) {
            return None;
        }
        self.objective.decision(&eval, evaluations + 1, history)
    }
}

/// An initial population with `share` of its individuals on reachable frontier cells.
fn near_frontiers<const N: usize, P: Planner<N>, R: rand_core::Rng>(
    problem: &BoundObjective<'_, '_, '_, N, P>,
    req: &DecisionRequest<'_, N>,
    size: usize,
    share: f32,
    rng: &mut R,
) -> Result<Population, optim::OptimError> {
    let dim = problem.dim();
    let mut pop = Population::new(dim)?;
    let on_frontiers = (share.clamp(0.0, 1.0) * size as f32 + 0.5) as usize;
    let geom = req.grid.geometry();
    let mut g = [0.0f32; MAX_DIM];
    for n in 0..size {
        for (i, x) in g[..dim].iter_mut().enumerate() {
            let (lo, hi) = problem.bounds(i);
            *x = random::range_f32(rng, lo, hi);
        }
        if n < on_frontiers {
            for t in 0..dim / 2 {
                if let Some(cell) = sample_reachable_frontier(req.grid, problem.field(), rng) {
                    let c = geom.cell_center(cell);
                    (g[2 * t], g[2 * t + 1]) = (c.x, c.y);
                }
            }
        }
        pop.push(&g[..dim])?;
    }
    Ok(pop)
}

/// Viewpoints whose individuals start on the most promising frontier viewpoints, under the
/// efficient objective: half the population, rounded up.
const SEEDED_SHARE: f32 = 0.5;

/// An initial population for the efficient objective: drawn uniformly as the thesis's, then
/// the first `ceil(SEEDED_SHARE * size)` individuals put every target on one of the listed
/// frontier viewpoints ([`super::ReachableViewpoints`]) ranked best by
/// `frontier_cells · exp(-lambda · (distance + tour_weight · tour extra))` (the objective's
/// discount applied to a cheap estimate of the gain), the best first.
fn near_viewpoints<const N: usize, P: Planner<N>, R: rand_core::Rng>(
    problem: &BoundObjective<'_, '_, '_, N, P>,
    req: &DecisionRequest<'_, N>,
    size: usize,
    rng: &mut R,
) -> Result<Population, optim::OptimError> {
    let uniform = Population::uniform(problem, size, rng)?;
    let dim = problem.dim();
    let seeded = crate::math::ceil(SEEDED_SHARE * size as f32) as usize;
    let list = problem.viewpoints().as_slice();
    let lambda = problem.config().efficiency_per_step;
    let (tour, weight) = (problem.tour(), problem.config().tour_weight);
    let rank = |v: &super::reachable::Viewpoint| {
        let cost = v.distance_m + weight * tour.extra_m(v.cell);
        v.frontier_cells as f32 * crate::math::exp(-lambda * cost)
    };
    // The `seeded` best viewpoints, best first (insertion into a short list).
    let mut best: heapless::Vec<(f32, usize), { optim::MAX_POP }> = heapless::Vec::new();
    for (i, v) in list.iter().enumerate() {
        let r = rank(v);
        let at = best.iter().position(|&(b, _)| r > b).unwrap_or(best.len());
        if at < seeded.min(optim::MAX_POP) {
            if best.len() == seeded.min(optim::MAX_POP) {
                best.pop();
            }
            let _ = best.insert(at, (r, i));
        }
    }
    let geom = req.grid.geometry();
    let mut pop = Population::new(dim)?;
    let mut g = [0.0f32; MAX_DIM];
    for n in 0..size {
        g[..dim].copy_from_slice(uniform.genome(n));
        if let Some(&(_, i)) = best.get(n) {
            let c = geom.cell_center(list[i].cell);
            for t in 0..dim / 2 {
                (g[2 * t], g[2 * t + 1]) = (c.x, c.y);
            }
        }
        pop.push(&g[..dim])?;
    }
    Ok(pop)
}
