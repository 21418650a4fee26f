//! SABOA: the self-adaptive Butterfly Optimization Algorithm.
//!
//! Source: Y. Fan, J. Shao, G. Sun and X. Shao, "A self-adaptive butterfly optimization
//! algorithm for numerical optimization problems", IEEE Access 8 (2020).
//!
//! SABOA drops BOA's sensory modality `c` and power exponent `a`: the step size no longer
//! depends on the fitness value (whose scale is problem-specific) but on the run's progress.
//! The equations implemented here, per butterfly `i` in index order, at generation `t` of `T`
//! (`t` counts the generations already run):
//!
//! 1. self-adaptive fragrance `f = u * (1 - t / T)`, `u` uniform in `[0, 1)` drawn per butterfly;
//! 2. with the switch probability `p`, the global step toward the best butterfly `g*`:
//!    `x'_d = x_d + 2 * f * r_d * (g*_d - x_d)`, `r_d` uniform per gene (mean step `f` times
//!    the gap, overshoot of `g*` possible up to `2 f`);
//! 3. otherwise the local step along the direction from the worst butterfly `w` to `g*`:
//!    `x'_d = x_d + f * r_d * (g*_d - w_d)`;
//! 4. `x'` clamped, evaluated, kept only if strictly better (greedy acceptance); `g*` follows
//!    every improvement at once, `w` is taken at the start of the generation.
//!
//! Why these forms: the thesis describes SABOA as "f = u (1 - t/T), a global step toward `g*`
//! scaled by `f`, a local step between `g*` and the worst butterfly, greedy acceptance" and gives
//! only `p`. Unlike BOA's `r^2 g* - x`, step 2 moves toward `g*` itself (no pull toward the
//! origin), which is the intent of a step "toward `g*`"; step 3 uses the best–worst difference
//! as a search direction whose length shrinks with the population's spread and with `1 - t/T`,
//! so the search narrows as the run ends. Default: `p = 0.237`.

use rand_core::Rng;

use super::{Engine, OptimError, Optimizer, Population, Problem, engine_accessors};
use crate::random;

/// SABOA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SaboaParams {
    /// Switch probability `p` (global step).
    pub p: f32,
}

impl Default for SaboaParams {
    fn default() -> Self {
        Self { p: 0.237 }
    }
}

/// SABOA state.
#[derive(Debug, Clone)]
pub struct Saboa {
    params: SaboaParams,
    engine: Engine,
}

impl Saboa {
    /// A SABOA with `params`, whose schedule spans `max_generations` generations.
    pub fn new(params: SaboaParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
        }
    }
}

impl Optimizer for Saboa {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.engine.start(problem, initial)
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let e = &mut self.engine;
        let decay = (1.0 - e.progress()).max(0.0);
        let worst = e.pop.genes[e.pop.worst()];
        for i in 0..e.pop.len {
            let x = e.pop.genes[i];
            let f = random::unit_f32(rng) * decay;
            let g = e.best;
            let mut y = x;
            if random::chance(rng, self.params.p) {
                for d in 0..e.dim {
                    y[d] = x[d] + 2.0 * f * random::unit_f32(rng) * (g[d] - x[d]);
                }
            } else {
                for d in 0..e.dim {
                    y[d] = x[d] + f * random::unit_f32(rng) * (g[d] - worst[d]);
                }
            }
            e.clamp(&mut y);
            let fy = e.evaluate(problem, &y);
            if fy < e.pop.fitness[i] {
                e.pop.genes[i] = y;
                e.pop.fitness[i] = fy;
            }
        }
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
