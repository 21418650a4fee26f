//! mBOA: the modified Butterfly Optimization Algorithm.
//!
//! Source: S. Arora, S. Singh and K. Yetilmezsoy, "A modified butterfly optimization algorithm
//! for mechanical design optimization problems", Journal of the Brazilian Society of Mechanical
//! Sciences and Engineering 40, 21 (2018).
//!
//! A BOA generation ([`super::boa`]: fragrance `c * I^a`, global step with probability `p`,
//! local step otherwise, greedy acceptance), followed by an intensive exploitation phase: with
//! probability `p`, one extra point `g* + (r1 - r2) * g*` around the best butterfly `g*`
//! (`r1`, `r2` uniform in `[0, 1)`, drawn per gene), clamped and evaluated. It is kept if it is
//! strictly better than `g*`, by replacing the worst butterfly (the best one stays, so the
//! population keeps its size and never loses its best). The thesis gives one probability `p`
//! for mBOA; we read it as both the switch probability and the probability of the extra phase,
//! and run that phase once per generation (one extra evaluation at most), which follows the
//! paper's intent of a cheap local refinement of the best. `c <- c + 0.025 / (c * T)` after
//! each generation. Defaults: `a = 0.61, c = 0.356, p = 0.762`.

use rand_core::Rng;

use super::boa::{next_c, sweep};
use super::{Engine, OptimError, Optimizer, Population, Problem, engine_accessors};
use crate::random;

/// mBOA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MboaParams {
    /// Power exponent `a`.
    pub a: f32,
    /// Initial sensory modality `c`.
    pub c: f32,
    /// Switch probability, also the probability of the exploitation point.
    pub p: f32,
}

impl Default for MboaParams {
    fn default() -> Self {
        Self {
            a: 0.61,
            c: 0.356,
            p: 0.762,
        }
    }
}

/// mBOA state.
#[derive(Debug, Clone)]
pub struct Mboa {
    params: MboaParams,
    c: f32,
    engine: Engine,
}

impl Mboa {
    /// An mBOA with `params`, whose `c` schedule spans `max_generations` generations.
    pub fn new(params: MboaParams, max_generations: u32) -> Self {
        Self {
            params,
            c: params.c,
            engine: Engine::new(max_generations),
        }
    }
}

impl Optimizer for Mboa {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.c = self.params.c;
        self.engine.start(problem, initial)
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let e = &mut self.engine;
        sweep(e, problem, rng, self.params.a, self.c, self.params.p);
        if random::chance(rng, self.params.p) {
            let g = e.best;
            let g_fitness = e.best_fitness;
            let mut y = g;
            for d in 0..e.dim {
                y[d] = g[d] + (random::unit_f32(rng) - random::unit_f32(rng)) * g[d];
            }
            e.clamp(&mut y);
            let fy = e.evaluate(problem, &y);
            if fy < g_fitness {
                let w = e.pop.worst();
                e.pop.genes[w] = y;
                e.pop.fitness[w] = fy;
            }
        }
        self.c = next_c(self.c, e.horizon);
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
