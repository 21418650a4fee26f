//! ABC: the Artificial Bee Colony algorithm.
//!
//! Source: D. Karaboga, "An idea based on honey bee swarm for numerical optimization",
//! Technical Report TR06, Erciyes University (2005).
//!
//! The given population is the set of food sources (one employed bee each; as many onlookers).
//! Each cycle:
//! 1. employed phase: for every source `i`, a neighbour `v = x_i` with one gene `j` moved,
//!    `v_j = x_ij + phi (x_ij - x_kj)`, `phi` uniform in `[-1, 1)`, `k != i` uniform, `j`
//!    uniform; clamped, evaluated, kept if strictly better, else the source's trial counter
//!    grows;
//! 2. onlooker phase: as many onlookers as sources, each picks a source by roulette on
//!    `fit = 1 / (1 + F)` (`F >= 0`) or `1 + |F|` (`F < 0`) and makes the same neighbour move;
//! 3. scout phase: the source with the most trials, if above the abandonment limit, is replaced
//!    by a uniform point in the bounds (evaluated) and its counter reset (at most one per cycle).
//!
//! A cycle therefore costs `2 N` evaluations, plus one when a scout flies. Default limit: 20.

use rand_core::Rng;

use super::{Engine, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors};
use crate::random;

/// ABC hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbcParams {
    /// Trials without improvement before a source is abandoned.
    pub limit: u32,
}

impl Default for AbcParams {
    fn default() -> Self {
        Self { limit: 20 }
    }
}

/// ABC state.
#[derive(Debug, Clone)]
pub struct Abc {
    params: AbcParams,
    engine: Engine,
    trials: [u32; MAX_POP],
}

impl Abc {
    /// An ABC with `params` (`max_generations` is kept for symmetry with the other methods).
    pub fn new(params: AbcParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
            trials: [0; MAX_POP],
        }
    }

    fn explore<P: Problem + ?Sized, R: Rng>(&mut self, problem: &mut P, i: usize, rng: &mut R) {
        let e = &mut self.engine;
        let n = e.pop.len;
        let mut k = random::below(rng, n - 1);
        if k >= i {
            k += 1;
        }
        let j = random::below(rng, e.dim);
        let mut v = e.pop.genes[i];
        let phi = random::range_f32(rng, -1.0, 1.0);
        v[j] += phi * (v[j] - e.pop.genes[k][j]);
        e.clamp(&mut v);
        let f = e.evaluate(problem, &v);
        if f < e.pop.fitness[i] {
            e.pop.genes[i] = v;
            e.pop.fitness[i] = f;
            self.trials[i] = 0;
        } else {
            self.trials[i] += 1;
        }
    }
}

fn quality(f: f32) -> f32 {
    if f >= 0.0 { 1.0 / (1.0 + f) } else { 1.0 - f }
}

impl Optimizer for Abc {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.trials = [0; MAX_POP];
        self.engine.start(problem, initial)
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let n = self.engine.pop.len;
        for i in 0..n {
            self.explore(problem, i, rng);
        }
        for _ in 0..n {
            let total: f32 = self.engine.pop.fitness[..n]
                .iter()
                .map(|&f| quality(f))
                .sum();
            let mut pick = random::unit_f32(rng) * total;
            let mut chosen = n - 1;
            for (s, &f) in self.engine.pop.fitness[..n].iter().enumerate() {
                pick -= quality(f);
                if pick < 0.0 {
                    chosen = s;
                    break;
                }
            }
            self.explore(problem, chosen, rng);
        }
        let mut scout = 0;
        for s in 1..n {
            if self.trials[s] > self.trials[scout] {
                scout = s;
            }
        }
        if self.trials[scout] > self.params.limit {
            let e = &mut self.engine;
            let x = e.uniform(rng);
            let f = e.evaluate(problem, &x);
            e.pop.genes[scout] = x;
            e.pop.fitness[scout] = f;
            self.trials[scout] = 0;
        }
        self.engine.end_step();
        Ok(())
    }

    engine_accessors!();
}
