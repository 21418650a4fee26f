//! BOA: the Butterfly Optimization Algorithm.
//!
//! Source: S. Arora and S. Singh, "Butterfly optimization algorithm: a novel approach for global
//! optimization", Soft Computing 23, 715–734 (2019).
//!
//! Each butterfly, in index order, emits the fragrance `f = c * I^a`: `c` the sensory
//! modality, `a` the power exponent, `I = min(|F|, 1)` the stimulus intensity from its fitness
//! `F`. The cap keeps the thesis's tuned `c` and `a` (meant for intensities of order one; the
//! exploration objective lies in `[-1, 0]`, where `I = |F|`) from producing steps hundreds of
//! box widths long on fitnesses in the hundreds. With the switch probability `p` it takes
//! the global step `x + f * (r1 * r2 * g* - x)` toward the best butterfly `g*`, otherwise the
//! local step `x + f * (r1 * r2 * x_j - x_k)` with `j`, `k` drawn uniformly in the population;
//! `r1`, `r2` are uniform in `[0, 1)` and drawn once per move (as in the authors' reference
//! code, which multiplies a whole vector by one `rand`). The moved butterfly is clamped to the
//! bounds, evaluated, and kept only if strictly better (greedy acceptance); `g*` follows every
//! improvement at once. After each generation `c <- c + 0.025 / (c * T)`, `T` the horizon.
//!
//! Defaults are the thesis's tuned values: pop 20: `a = 0.547, c = 0.602, p = 0.395`; pop 5:
//! `a = 0.73, c = 0.577, p = 0.331`. For other sizes [`BoaParams::for_population`] interpolates
//! linearly in the population size between those two tunings and keeps the nearest one outside
//! `5..=20`.

use rand_core::Rng;

use super::{
    Engine, Genome, OptimError, Optimizer, Population, Problem, engine_accessors, fragrance,
};
use crate::random;

/// BOA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoaParams {
    /// Power exponent `a`.
    pub a: f32,
    /// Initial sensory modality `c`.
    pub c: f32,
    /// Switch probability `p` (global step).
    pub p: f32,
}

/// Linear interpolation of a pop-5 and a pop-20 tuning, clamped outside `5..=20`.
pub(crate) fn interpolate(population: usize, at5: f32, at20: f32) -> f32 {
    let t = ((population as f32 - 5.0) / 15.0).clamp(0.0, 1.0);
    at5 + (at20 - at5) * t
}

impl BoaParams {
    /// Thesis tuning for `population` butterflies (see the module doc).
    pub fn for_population(population: usize) -> Self {
        Self {
            a: interpolate(population, 0.73, 0.547),
            c: interpolate(population, 0.577, 0.602),
            p: interpolate(population, 0.331, 0.395),
        }
    }
}

impl Default for BoaParams {
    /// The pop-20 tuning.
    fn default() -> Self {
        Self::for_population(20)
    }
}

/// BOA's global step toward `best`.
pub(crate) fn global_move<R: Rng>(
    engine: &Engine,
    x: &Genome,
    best: &Genome,
    f: f32,
    rng: &mut R,
) -> Genome {
    let r = random::unit_f32(rng) * random::unit_f32(rng);
    let mut y = *x;
    for d in 0..engine.dim {
        y[d] = x[d] + f * (r * best[d] - x[d]);
    }
    engine.clamp(&mut y);
    y
}

/// BOA's local step with two uniformly drawn butterflies.
pub(crate) fn local_move<R: Rng>(engine: &Engine, x: &Genome, f: f32, rng: &mut R) -> Genome {
    let n = engine.pop.len;
    let j = random::below(rng, n);
    let k = random::below(rng, n);
    let r = random::unit_f32(rng) * random::unit_f32(rng);
    let (xj, xk) = (&engine.pop.genes[j], &engine.pop.genes[k]);
    let mut y = *x;
    for d in 0..engine.dim {
        y[d] = x[d] + f * (r * xj[d] - xk[d]);
    }
    engine.clamp(&mut y);
    y
}

/// Evaluates `y` as a candidate for butterfly `i` and keeps it if strictly better.
pub(crate) fn try_replace<P: Problem + ?Sized>(
    engine: &mut Engine,
    problem: &mut P,
    i: usize,
    y: &Genome,
) {
    let fy = engine.evaluate(problem, y);
    if fy < engine.pop.fitness[i] {
        engine.pop.genes[i] = *y;
        engine.pop.fitness[i] = fy;
    }
}

/// One BOA sweep over the population with sensory modality `c`.
pub(crate) fn sweep<P: Problem + ?Sized, R: Rng>(
    engine: &mut Engine,
    problem: &mut P,
    rng: &mut R,
    a: f32,
    c: f32,
    p: f32,
) {
    for i in 0..engine.pop.len {
        let x = engine.pop.genes[i];
        let f = fragrance(c, engine.pop.fitness[i], a);
        let y = if random::chance(rng, p) {
            let best = engine.best;
            global_move(engine, &x, &best, f, rng)
        } else {
            local_move(engine, &x, f, rng)
        };
        try_replace(engine, problem, i, &y);
    }
}

/// The sensory-modality update `c + 0.025 / (c * T)`.
pub(crate) fn next_c(c: f32, horizon: u32) -> f32 {
    c + 0.025 / (c * horizon as f32)
}

/// BOA state.
#[derive(Debug, Clone)]
pub struct Boa {
    params: BoaParams,
    c: f32,
    engine: Engine,
}

impl Boa {
    /// A BOA with `params`, whose `c` schedule spans `max_generations` generations.
    pub fn new(params: BoaParams, max_generations: u32) -> Self {
        Self {
            params,
            c: params.c,
            engine: Engine::new(max_generations),
        }
    }
}

impl Optimizer for Boa {
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
        sweep(
            &mut self.engine,
            problem,
            rng,
            self.params.a,
            self.c,
            self.params.p,
        );
        self.c = next_c(self.c, self.engine.horizon);
        self.engine.end_step();
        Ok(())
    }

    engine_accessors!();
}
