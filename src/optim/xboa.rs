//! xBOA: the Butterfly Optimization Algorithm with crossover, Papillon's target selector.
//!
//! Source: A. Bendahmane and R. Tlemsani, Soft Computing (2022), the paper introducing xBOA for
//! energy-constrained exploration, and the 2023 PhD thesis (Bendahmane, USTO Oran) built on it; BOA itself is Arora & Singh (2019),
//! see [`super::boa`].
//!
//! Per butterfly `i`, in index order, with fragrance `f = c * I^a` (`I` the scaled
//! fitness of [`super::boa`]):
//! - with the crossover probability `p_c`: single-point crossover with a mate drawn uniformly
//!   among the *other* butterflies, cut point uniform in `1..D-1` (genes before the cut from one
//!   parent, after it from the other), giving two children, both clamped and evaluated; the
//!   butterfly is replaced by the better child only if that child is strictly better than it;
//!   the mate is unchanged and the population size stays fixed;
//! - otherwise BOA's local step `x + f * (r1 * r2 * x_j - x_k)` (`j`, `k` uniform), clamped,
//!   evaluated, kept only if strictly better.
//!
//! After each generation `c <- c + 0.025 / (c * T)`, `T` the horizon. With a single gene
//! (`D = 1`) there is no cut point, so every butterfly takes the local step.
//!
//! Defaults (thesis tuning): pop 20: `a = 0.905, c = 0.257, p_c = 0.593`; pop 5:
//! `a = 0.994, c = 0.518, p_c = 0.583`. [`XboaParams::for_population`] interpolates linearly in
//! the population size between those tunings, and keeps the nearest one outside `5..=20`.

use rand_core::Rng;

use super::boa::{interpolate, local_move, next_c, try_replace};
use super::{Engine, OptimError, Optimizer, Population, Problem, engine_accessors, fragrance};
use crate::random;

/// xBOA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XboaParams {
    /// Power exponent `a`.
    pub a: f32,
    /// Initial sensory modality `c`.
    pub c: f32,
    /// Crossover probability `p_c`.
    pub p_c: f32,
}

impl XboaParams {
    /// Thesis tuning for `population` butterflies (see the module doc).
    pub fn for_population(population: usize) -> Self {
        Self {
            a: interpolate(population, 0.994, 0.905),
            c: interpolate(population, 0.518, 0.257),
            p_c: interpolate(population, 0.583, 0.593),
        }
    }
}

impl Default for XboaParams {
    /// The pop-20 tuning.
    fn default() -> Self {
        Self::for_population(20)
    }
}

/// xBOA state.
#[derive(Debug, Clone)]
pub struct Xboa {
    params: XboaParams,
    c: f32,
    engine: Engine,
}

impl Xboa {
    /// An xBOA with `params`, whose `c` schedule spans `max_generations` generations.
    pub fn new(params: XboaParams, max_generations: u32) -> Self {
        Self {
            params,
            c: params.c,
            engine: Engine::new(max_generations),
        }
    }
}

impl Optimizer for Xboa {
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
        let (n, dim) = (e.pop.len, e.dim);
        for i in 0..n {
            let x = e.pop.genes[i];
            if dim >= 2 && random::chance(rng, self.params.p_c) {
                // Mate uniform among the others: draw in 0..n-1 and skip i.
                let mut m = random::below(rng, n - 1);
                if m >= i {
                    m += 1;
                }
                let cut = 1 + random::below(rng, dim - 1);
                let mate = e.pop.genes[m];
                let (mut c1, mut c2) = (x, mate);
                c1[cut..dim].copy_from_slice(&mate[cut..dim]);
                c2[cut..dim].copy_from_slice(&x[cut..dim]);
                e.clamp(&mut c1);
                e.clamp(&mut c2);
                let f1 = e.evaluate(problem, &c1);
                let f2 = e.evaluate(problem, &c2);
                let (child, fc) = if f2 < f1 { (c2, f2) } else { (c1, f1) };
                if fc < e.pop.fitness[i] {
                    e.pop.genes[i] = child;
                    e.pop.fitness[i] = fc;
                }
            } else {
                let f = fragrance(self.c, e.pop.fitness[i], self.params.a);
                let y = local_move(e, &x, f, rng);
                try_replace(e, problem, i, &y);
            }
        }
        self.c = next_c(self.c, e.horizon);
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
