//! Targets chosen by a population optimizer on the energy-constrained objective: the thesis's
//! method with [`Method::Xboa`] (Bendahmane, PhD thesis, USTO Oran 2023), or any of the other
//! methods of [`crate::optim`] for comparison.
//!
//! The initial population is drawn uniformly in the map bounds from the caller's seeded RNG;
//! the run stops after [`ExploreConfig::max_generations`] generations (no early stop, so the
//! history has one entry per generation). The best genome is evaluated once more to produce
//! the plan.

use crate::optim::{self, Method, Optimizer, Population, StopRules};

use super::objective::{ExploreObjective, WORST_FITNESS};
use super::{
    DecideError, DecisionRequest, ExploreConfig, MAX_TARGETS, Outcome, TargetSelector,
    any_reachable_frontier,
};
use crate::geometry::Point2;

/// Optimizer-based target selection.
#[derive(Debug)]
pub struct Optimized<'o, 'm, const N: usize> {
    /// The optimization method.
    pub method: Method,
    /// Decision settings (k, reserve, population, generations).
    pub config: ExploreConfig,
    objective: &'o mut ExploreObjective<'m, N>,
}

impl<'o, 'm, const N: usize> Optimized<'o, 'm, N> {
    /// A selector running `method` over `objective`'s working memory.
    pub fn new(
        method: Method,
        config: ExploreConfig,
        objective: &'o mut ExploreObjective<'m, N>,
    ) -> Self {
        Self {
            method,
            config,
            objective,
        }
    }
}

impl<const N: usize> TargetSelector<N> for Optimized<'_, '_, N> {
    fn decide<R: rand_core::Rng>(
        &mut self,
        req: &DecisionRequest<'_, N>,
        rng: &mut R,
    ) -> Result<Outcome, DecideError> {
        self.objective.prepare(req, &self.config)?;
        if !any_reachable_frontier(req.grid, self.objective.field()) {
            return Ok(Outcome::Done);
        }
        let rules = StopRules {
            max_generations: self.config.max_generations,
            patience: None,
            max_evaluations: None,
        };
        let mut opt = self
            .method
            .build(self.config.population, rules.max_generations);
        let (best, evaluations, history_len) = {
            let mut problem = self.objective.problem(req);
            let initial = Population::uniform(&problem, self.config.population, rng)
                .map_err(DecideError::Optimizer)?;
            optim::run(&mut opt, &mut problem, &initial, &rules, rng)
                .map_err(DecideError::Optimizer)?;
            let mut best = [0.0f32; 2 * MAX_TARGETS];
            let g = opt.best_genome();
            best[..g.len()].copy_from_slice(g);
            (best, opt.evaluations(), g.len())
        };
        if opt.best_fitness() >= WORST_FITNESS {
            return Err(DecideError::NoFeasibleTarget {
                battery_steps: req.battery_steps,
            });
        }
        let mut pts = [Point2::new(0.0, 0.0); MAX_TARGETS];
        let k = history_len / 2;
        for (i, p) in pts[..k].iter_mut().enumerate() {
            *p = Point2::new(best[2 * i], best[2 * i + 1]);
        }
        let eval = self.objective.evaluate_targets(req, &pts[..k]);
        self.objective
            .decision(&eval, evaluations, opt.history())
            .map(Outcome::Go)
            .ok_or(DecideError::NoFeasibleTarget {
                battery_steps: req.battery_steps,
            })
    }
}
