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
//!
//! Two parameter sets: [`AbcParams::karaboga`] (the [`Default`], `Preset::Thesis`) is the
//! above; [`AbcParams::standard`] (`Preset::Standard`) adds the global-best term of GABC
//! (G. Zhu and S. Kwong, "Gbest-guided artificial bee colony algorithm for numerical function
//! optimization", Applied Mathematics and Computation 217(7), 3166–3173 (2010)) to every
//! neighbour move: `v_j = x_ij + phi (x_ij - x_kj) + psi (y_j - x_ij)`, `psi` uniform in
//! `[0, C)` with their recommended `C = 1.5` and `y` the best source found so far. Karaboga's
//! ABC (which pygmo's `bee_colony` implements) explores well but converges slowly on smooth
//! basins; GABC's pull toward the best source is their remedy and is translation-invariant (no
//! pull toward the origin).

use rand_core::Rng;

use super::{Engine, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors};
use crate::random;

/// ABC hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbcParams {
    /// Trials without improvement before a source is abandoned.
    pub limit: u32,
    /// GABC's `C`: the global-best term's weight is uniform in `[0, C)` (0: Karaboga's ABC).
    pub gbest: f32,
}

impl AbcParams {
    /// Karaboga's ABC, limit 20 (pygmo's `bee_colony` default).
    pub fn karaboga() -> Self {
        Self {
            limit: 20,
            gbest: 0.0,
        }
    }

    /// GABC (Zhu & Kwong 2010), `C = 1.5`, limit 20.
    pub fn standard() -> Self {
        Self {
            limit: 20,
            gbest: 1.5,
        }
    }
}

impl Default for AbcParams {
    fn default() -> Self {
        Self::karaboga()
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
        let pull = if self.params.gbest > 0.0 {
            random::range_f32(rng, 0.0, self.params.gbest) * (e.best[j] - v[j])
        } else {
            0.0
        };
        v[j] += phi * (v[j] - e.pop.genes[k][j]) + pull;
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
        // Each source's quality, recomputed only when its fitness changes (the roulette sees
        // every improvement an onlooker before it made).
        let mut q = [0.0f32; MAX_POP];
        for (q, &f) in q[..n].iter_mut().zip(&self.engine.pop.fitness[..n]) {
            *q = quality(f);
        }
        for _ in 0..n {
            let total: f32 = q[..n].iter().sum();
            let mut pick = random::unit_f32(rng) * total;
            let mut chosen = n - 1;
            for (s, &qs) in q[..n].iter().enumerate() {
                pick -= qs;
                if pick < 0.0 {
                    chosen = s;
                    break;
                }
            }
            self.explore(problem, chosen, rng);
            q[chosen] = quality(self.engine.pop.fitness[chosen]);
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
