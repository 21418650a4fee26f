//! GWO: the Grey Wolf Optimizer.
//!
//! Source: S. Mirjalili, S. M. Mirjalili and A. Lewis, "Grey Wolf Optimizer", Advances in
//! Engineering Software 69, 46–61 (2014).
//!
//! The three best wolves found so far lead: alpha, beta, delta. Each generation, with
//! `a = 2 - 2 t / T` (`T` the horizon, `t` as the [`Schedule`] says, so `a` falls linearly
//! from 2 toward 0),
//! every wolf moves to the mean of `X_l - A_l * |C_l * X_l - x|` over the three leaders `l`,
//! with `A = 2 a r1 - a` and `C = 2 r2` drawn per gene; the new position is clamped and
//! evaluated, and replaces the old one (no greedy acceptance, as in the paper). Leaders are
//! updated after the whole pack has moved; a wolf better than alpha pushes alpha to beta and
//! beta to delta (the reference code overwrites instead, which can lose a good leader).
//! No hyper-parameters.

use rand_core::Rng;

use super::{
    Engine, Genome, MAX_DIM, OptimError, Optimizer, Population, Problem, engine_accessors,
};
use crate::{math, random};

/// Which `t` enters `a = 2 - 2 t / T` in a generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Schedule {
    /// `t` = the generations already run (0 to `T - 1`): the last generation runs with
    /// `a = 2 / T`. Papillon's schedule before issue 23, kept by [`super::Preset::Thesis`] so
    /// the exploration experiments stay reproducible.
    Started,
    /// `t` = the generation being run (1 to `T`): `a` reaches 0 in the last generation, where
    /// every wolf moves to the mean of the three leaders; the paper's "decreased linearly from
    /// 2 to 0". On the 10-gene sphere with the optimum at 1.7 (population 20, 100
    /// generations) it halves the median best fitness (`docs/optimizers.md`).
    Paper,
}

/// GWO state.
#[derive(Debug, Clone)]
pub struct Gwo {
    schedule: Schedule,
    engine: Engine,
    leaders: [Genome; 3],
    leader_fitness: [f32; 3],
}

impl Gwo {
    /// A GWO whose `a` schedule spans `max_generations` generations ([`Schedule::Started`]).
    pub fn new(max_generations: u32) -> Self {
        Self::with_schedule(Schedule::Started, max_generations)
    }

    /// A GWO with `schedule` spanning `max_generations` generations.
    pub fn with_schedule(schedule: Schedule, max_generations: u32) -> Self {
        Self {
            schedule,
            engine: Engine::new(max_generations),
            leaders: [[0.0; MAX_DIM]; 3],
            leader_fitness: [f32::INFINITY; 3],
        }
    }

    fn offer(&mut self, x: &Genome, f: f32) {
        for l in 0..3 {
            if f < self.leader_fitness[l] {
                for k in (l + 1..3).rev() {
                    self.leaders[k] = self.leaders[k - 1];
                    self.leader_fitness[k] = self.leader_fitness[k - 1];
                }
                self.leaders[l] = *x;
                self.leader_fitness[l] = f;
                return;
            }
        }
    }

    fn refresh_leaders(&mut self) {
        for i in 0..self.engine.pop.len {
            let (x, f) = (self.engine.pop.genes[i], self.engine.pop.fitness[i]);
            self.offer(&x, f);
        }
        // With fewer than three distinct wolves, missing leaders copy alpha.
        for l in 1..3 {
            if self.leader_fitness[l] == f32::INFINITY {
                self.leaders[l] = self.leaders[l - 1];
            }
        }
    }
}

impl Optimizer for Gwo {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.engine.start(problem, initial)?;
        self.leader_fitness = [f32::INFINITY; 3];
        self.leaders = [self.engine.pop.genes[0]; 3];
        self.refresh_leaders();
        Ok(())
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let t = match self.schedule {
            Schedule::Started => self.engine.progress(),
            Schedule::Paper => (self.engine.generation + 1) as f32 / self.engine.horizon as f32,
        };
        let a = 2.0 - 2.0 * t.min(1.0);
        let e = &mut self.engine;
        for i in 0..e.pop.len {
            let x = e.pop.genes[i];
            let mut y = x;
            for d in 0..e.dim {
                let mut sum = 0.0;
                for leader in &self.leaders {
                    let big_a = 2.0 * a * random::unit_f32(rng) - a;
                    let big_c = 2.0 * random::unit_f32(rng);
                    sum += leader[d] - big_a * math::abs(big_c * leader[d] - x[d]);
                }
                y[d] = sum / 3.0;
            }
            e.clamp(&mut y);
            let f = e.evaluate(problem, &y);
            e.pop.genes[i] = y;
            e.pop.fitness[i] = f;
        }
        self.refresh_leaders();
        self.engine.end_step();
        Ok(())
    }

    engine_accessors!();
}
