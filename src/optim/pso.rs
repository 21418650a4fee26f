//! PSO: particle swarm optimization with a ring neighbourhood (local best).
//!
//! Sources: J. Kennedy and R. Eberhart, "Particle swarm optimization", Proc. IEEE ICNN (1995);
//! Y. Shi and R. Eberhart, "A modified particle swarm optimizer", Proc. IEEE CEC (1998) for the
//! inertia weight; J. Kennedy and R. Mendes, "Population structure and particle swarm
//! performance", Proc. CEC (2002) for ring neighbourhoods.
//!
//! Velocity per gene: `v <- w v + c1 r1 (pbest - x) + c2 r2 (lbest - x)`, `r1`, `r2` uniform per
//! gene, clamped to `±vmax` with `vmax = vmax_fraction * (upper - lower)`; then `x <- x + v`,
//! clamped to the bounds, evaluated; the personal best follows strict improvements. `lbest` is
//! the best personal best among the particle and its `neighbours` nearest indices on the ring
//! (`neighbours / 2` on each side; with fewer particles, all the others, one more on the
//! right when their number is odd), taken at the start of the generation (synchronous update).
//! Velocities start at zero, so the first move is pulled by the neighbourhood only.
//!
//! Defaults are the thesis's tuned values: 4 neighbours, inertia 0.449, cognitive 3.379,
//! social 1.506, maximum velocity 0.329 of the box width.

use rand_core::Rng;

use super::{
    Engine, Genome, MAX_DIM, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors,
};
use crate::random;

/// PSO hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsoParams {
    /// Ring neighbours (besides the particle itself), split evenly on both sides.
    pub neighbours: usize,
    /// Inertia weight `w`.
    pub inertia: f32,
    /// Cognitive coefficient `c1`.
    pub cognitive: f32,
    /// Social coefficient `c2`.
    pub social: f32,
    /// Maximum speed per gene as a fraction of the box width.
    pub vmax_fraction: f32,
}

impl Default for PsoParams {
    fn default() -> Self {
        Self {
            neighbours: 4,
            inertia: 0.449,
            cognitive: 3.379,
            social: 1.506,
            vmax_fraction: 0.329,
        }
    }
}

/// PSO state.
#[derive(Debug, Clone)]
pub struct Pso {
    params: PsoParams,
    engine: Engine,
    velocity: [Genome; MAX_POP],
    pbest: [Genome; MAX_POP],
    pbest_fitness: [f32; MAX_POP],
}

impl Pso {
    /// A PSO with `params` (`max_generations` is kept for symmetry with the other methods).
    pub fn new(params: PsoParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
            velocity: [[0.0; MAX_DIM]; MAX_POP],
            pbest: [[0.0; MAX_DIM]; MAX_POP],
            pbest_fitness: [f32::INFINITY; MAX_POP],
        }
    }
}

impl Optimizer for Pso {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.engine.start(problem, initial)?;
        let n = self.engine.pop.len;
        self.velocity = [[0.0; MAX_DIM]; MAX_POP];
        self.pbest[..n].copy_from_slice(&self.engine.pop.genes[..n]);
        self.pbest_fitness[..n].copy_from_slice(&self.engine.pop.fitness[..n]);
        Ok(())
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let e = &mut self.engine;
        let n = e.pop.len;
        // k distinct neighbours: ceil(k/2) on the right, floor(k/2) on the left.
        let k = self.params.neighbours.min(n - 1);
        let (right_count, left_count) = (k - k / 2, k / 2);
        let mut lbest = [0usize; MAX_POP];
        for (i, lb) in lbest[..n].iter_mut().enumerate() {
            let mut b = i;
            for off in 1..=right_count {
                let right = (i + off) % n;
                if self.pbest_fitness[right] < self.pbest_fitness[b] {
                    b = right;
                }
                if off <= left_count {
                    let left = (i + n - off) % n;
                    if self.pbest_fitness[left] < self.pbest_fitness[b] {
                        b = left;
                    }
                }
            }
            *lb = b;
        }
        let p = self.params;
        for i in 0..n {
            let mut x = e.pop.genes[i];
            let l = self.pbest[lbest[i]];
            for d in 0..e.dim {
                let vmax = p.vmax_fraction * (e.upper[d] - e.lower[d]);
                let v = p.inertia * self.velocity[i][d]
                    + p.cognitive * random::unit_f32(rng) * (self.pbest[i][d] - x[d])
                    + p.social * random::unit_f32(rng) * (l[d] - x[d]);
                let v = v.clamp(-vmax, vmax);
                self.velocity[i][d] = v;
                x[d] += v;
            }
            e.clamp(&mut x);
            let f = e.evaluate(problem, &x);
            e.pop.genes[i] = x;
            e.pop.fitness[i] = f;
            if f < self.pbest_fitness[i] {
                self.pbest[i] = x;
                self.pbest_fitness[i] = f;
            }
        }
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
