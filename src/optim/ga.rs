//! GA: a real-coded genetic algorithm.
//!
//! Sources: D. E. Goldberg, "Genetic Algorithms in Search, Optimization and Machine Learning"
//! (1989) for tournament selection and elitism; K. Deb and R. B. Agrawal, "Simulated binary
//! crossover for continuous search space", Complex Systems 9 (1995); K. Deb and M. Goyal,
//! "A combined genetic adaptive search (GeneAS) for engineering design", Computer Science and
//! Informatics 26 (1996) for the bounded polynomial mutation.
//!
//! Each generation builds a full offspring population: two parents by binary tournaments (the
//! fitter of two uniformly drawn individuals), with the crossover probability simulated binary
//! crossover (SBX, each gene swapped-and-spread with probability 1/2, distribution index
//! `eta_c`), then polynomial mutation of each gene with the mutation probability (distribution
//! index `eta_m`), children clamped to the bounds. A child identical to its parent (neither
//! crossed nor mutated) keeps the parent's fitness and is not re-evaluated. Elitist
//! reinsertion: the offspring replace the parents, except that the best parent replaces the
//! worst child when it is strictly better than the best child, so the best never gets worse.
//!
//! Defaults are the thesis's tuned values: crossover probability 0.11, mutation probability
//! 0.215 (per gene), `eta_m = 76.026`. The thesis gives no crossover distribution index; we use
//! Deb's customary `eta_c = 20`.

use rand_core::Rng;

use super::{
    Engine, Genome, MAX_DIM, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors,
};
use crate::{math, random};

/// GA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaParams {
    /// Probability that a pair of parents is crossed.
    pub crossover: f32,
    /// Per-gene mutation probability.
    pub mutation: f32,
    /// Polynomial-mutation distribution index.
    pub eta_m: f32,
    /// SBX distribution index.
    pub eta_c: f32,
}

impl Default for GaParams {
    fn default() -> Self {
        Self {
            crossover: 0.11,
            mutation: 0.215,
            eta_m: 76.026,
            eta_c: 20.0,
        }
    }
}

/// GA state.
#[derive(Debug, Clone)]
pub struct Ga {
    params: GaParams,
    engine: Engine,
    children: [Genome; MAX_POP],
    child_fitness: [f32; MAX_POP],
}

impl Ga {
    /// A GA with `params` (`max_generations` is kept for symmetry with the other methods).
    pub fn new(params: GaParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
            children: [[0.0; MAX_DIM]; MAX_POP],
            child_fitness: [f32::NAN; MAX_POP],
        }
    }
}

fn tournament<R: Rng>(e: &Engine, rng: &mut R) -> usize {
    let a = random::below(rng, e.pop.len);
    let b = random::below(rng, e.pop.len);
    if e.pop.fitness[b] < e.pop.fitness[a] {
        b
    } else {
        a
    }
}

/// Bounded polynomial mutation of one gene.
fn polynomial<R: Rng>(y: f32, lo: f32, hi: f32, eta: f32, rng: &mut R) -> f32 {
    let width = hi - lo;
    let d1 = (y - lo) / width;
    let d2 = (hi - y) / width;
    let r = random::unit_f32(rng);
    let pow = 1.0 / (eta + 1.0);
    let dq = if r < 0.5 {
        let v = 2.0 * r + (1.0 - 2.0 * r) * math::powf(1.0 - d1, eta + 1.0);
        math::powf(v, pow) - 1.0
    } else {
        let v = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * math::powf(1.0 - d2, eta + 1.0);
        1.0 - math::powf(v, pow)
    };
    y + dq * width
}

impl Optimizer for Ga {
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
        let (n, dim) = (e.pop.len, e.dim);
        let mut k = 0;
        while k < n {
            let (i, j) = (tournament(e, rng), tournament(e, rng));
            let (mut c1, mut c2) = (e.pop.genes[i], e.pop.genes[j]);
            let mut changed = [false; 2];
            if random::chance(rng, self.params.crossover) {
                for d in 0..dim {
                    if random::chance(rng, 0.5) {
                        let u = random::unit_f32(rng);
                        let ex = 1.0 / (self.params.eta_c + 1.0);
                        let beta = if u <= 0.5 {
                            math::powf(2.0 * u, ex)
                        } else {
                            math::powf(1.0 / (2.0 * (1.0 - u)), ex)
                        };
                        let (p1, p2) = (c1[d], c2[d]);
                        c1[d] = 0.5 * ((1.0 + beta) * p1 + (1.0 - beta) * p2);
                        c2[d] = 0.5 * ((1.0 - beta) * p1 + (1.0 + beta) * p2);
                    }
                }
                changed = [true; 2];
            }
            for (c, ch) in [&mut c1, &mut c2].into_iter().zip(changed.iter_mut()) {
                for d in 0..dim {
                    if random::chance(rng, self.params.mutation) {
                        c[d] = polynomial(c[d], e.lower[d], e.upper[d], self.params.eta_m, rng);
                        *ch = true;
                    }
                }
                e.clamp(c);
            }
            for (slot, (c, ch, parent)) in [(c1, changed[0], i), (c2, changed[1], j)]
                .into_iter()
                .enumerate()
            {
                if k + slot >= n {
                    break;
                }
                let unchanged = !ch || c[..dim] == e.pop.genes[parent][..dim];
                self.child_fitness[k + slot] = if unchanged {
                    e.pop.fitness[parent]
                } else {
                    e.evaluate(problem, &c)
                };
                self.children[k + slot] = c;
            }
            k += 2;
        }
        // Elitist reinsertion.
        let (best_parent, best_parent_f) = e.pop.best().unwrap_or((0, e.pop.fitness[0]));
        let mut best_child = f32::INFINITY;
        let mut worst_child = 0;
        for c in 0..n {
            best_child = best_child.min(self.child_fitness[c]);
            if self.child_fitness[c] > self.child_fitness[worst_child] {
                worst_child = c;
            }
        }
        if best_parent_f < best_child {
            self.children[worst_child] = e.pop.genes[best_parent];
            self.child_fitness[worst_child] = best_parent_f;
        }
        e.pop.genes[..n].copy_from_slice(&self.children[..n]);
        e.pop.fitness[..n].copy_from_slice(&self.child_fitness[..n]);
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
