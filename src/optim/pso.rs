//! PSO: particle swarm optimization with a ring neighbourhood (local best).
//!
//! Sources: J. Kennedy and R. Eberhart, "Particle swarm optimization", Proc. IEEE ICNN (1995);
//! Y. Shi and R. Eberhart, "A modified particle swarm optimizer", Proc. IEEE CEC (1998) for the
//! inertia weight; J. Kennedy and R. Mendes, "Population structure and particle swarm
//! performance", Proc. CEC (2002) for ring neighbourhoods.
//!
//! Each particle follows its personal best `pbest` and `lbest`, the best personal best among
//! the particle and its `neighbours` nearest indices on the ring (`neighbours / 2` on each
//! side; with fewer particles, all the others, one more on the right when their number is
//! odd). `r1`, `r2` are uniform in `[0, 1)`, drawn per gene; the speed per gene is clamped to
//! `±vmax` with `vmax = vmax_fraction * (upper - lower)`; the new position is clamped to the
//! bounds and evaluated; the personal best follows strict improvements. Two variants
//! ([`PsoVariant`]):
//!
//! - [`PsoVariant::InertiaWeight`] (Shi & Eberhart 1998), the thesis's formula:
//!   `v <- w v + c1 r1 (pbest - x) + c2 r2 (lbest - x)`; velocities start at zero (the first
//!   move is pulled by the neighbourhood only); `lbest` is taken at the start of the generation
//!   (synchronous update); a coordinate clamped to a bound keeps its velocity.
//! - [`PsoVariant::Constriction`] (M. Clerc and J. Kennedy, "The particle swarm — explosion,
//!   stability, and convergence in a multidimensional complex space", IEEE Trans. Evol. Comput.
//!   6(1), 58–73 (2002)): `v <- chi (v + c1 r1 (pbest - x) + c2 r2 (lbest - x))`, with
//!   `chi = 2 kappa / |2 - phi - sqrt(phi^2 - 4 phi)| = 0.7298` for `kappa = 1` and
//!   `phi = c1 + c2 = 4.1`; velocities start uniform in `±vmax`; `lbest` is looked up when the
//!   particle moves, so it sees the personal bests the particles before it improved in the
//!   same generation (asynchronous update,
//!   A. Carlisle and G. Dozier, "An off-the-shelf PSO", Proc. Workshop on PSO (2001)); a
//!   coordinate clamped to a bound loses its velocity ("absorbing walls", J. Robinson and
//!   Y. Rahmat-Samii, IEEE Trans. Antennas Propag. 52(2) (2004)).
//!
//! Two parameter sets: [`PsoParams::thesis`] (the [`Default`]), the thesis's Table 4.1 tuning
//! for the exploration problem (inertia weight 0.449, cognitive 3.379, social 1.506, maximum
//! velocity 0.329 of the box width, 4 neighbours); [`PsoParams::standard`], Clerc and
//! Kennedy's constriction with `vmax` half the box width and a ring of 4, the defaults of
//! pygmo 2's `pso` (its variant 5, `neighb_type` 2). On the 10-gene sphere the standard set
//! reaches a median best fitness about 100 times lower (`docs/optimizers.md`).

use rand_core::Rng;

use super::{
    Engine, Genome, MAX_DIM, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors,
};
use crate::random;

/// The velocity rule and the bookkeeping that goes with it (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PsoVariant {
    /// Inertia weight, zero start velocities, synchronous neighbourhood bests.
    InertiaWeight,
    /// Constriction factor, random start velocities, asynchronous neighbourhood bests,
    /// absorbing walls.
    Constriction,
}

/// PSO hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsoParams {
    /// Velocity rule.
    pub variant: PsoVariant,
    /// Ring neighbours (besides the particle itself), split evenly on both sides.
    pub neighbours: usize,
    /// Inertia weight `w` ([`PsoVariant::InertiaWeight`]) or constriction factor `chi`
    /// ([`PsoVariant::Constriction`]).
    pub inertia: f32,
    /// Cognitive coefficient `c1`.
    pub cognitive: f32,
    /// Social coefficient `c2`.
    pub social: f32,
    /// Maximum speed per gene as a fraction of the box width.
    pub vmax_fraction: f32,
}

impl PsoParams {
    /// The thesis's Table 4.1 tuning (see the module doc).
    pub fn thesis() -> Self {
        Self {
            variant: PsoVariant::InertiaWeight,
            neighbours: 4,
            inertia: 0.449,
            cognitive: 3.379,
            social: 1.506,
            vmax_fraction: 0.329,
        }
    }

    /// Clerc and Kennedy's constriction on a ring of 4, as in pygmo's `pso` (see the module
    /// doc).
    pub fn standard() -> Self {
        Self {
            variant: PsoVariant::Constriction,
            neighbours: 4,
            inertia: 0.7298,
            cognitive: 2.05,
            social: 2.05,
            vmax_fraction: 0.5,
        }
    }
}

impl Default for PsoParams {
    /// [`PsoParams::thesis`].
    fn default() -> Self {
        Self::thesis()
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

    /// Index of the best personal best among particle `i` and its ring neighbours.
    fn neighbourhood_best(&self, i: usize, n: usize) -> usize {
        // k distinct neighbours: ceil(k/2) on the right, floor(k/2) on the left.
        let k = self.params.neighbours.min(n - 1);
        let (right_count, left_count) = (k - k / 2, k / 2);
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
        b
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
        let n = self.engine.pop.len;
        let p = self.params;
        let constriction = p.variant == PsoVariant::Constriction;
        if constriction && self.engine.generation == 0 {
            // Start velocities uniform in ±vmax (drawn here: start() takes no generator).
            let e = &self.engine;
            for v in &mut self.velocity[..n] {
                for d in 0..e.dim {
                    let vmax = p.vmax_fraction * (e.upper[d] - e.lower[d]);
                    v[d] = random::range_f32(rng, -vmax, vmax);
                }
            }
        }
        // Synchronous: every neighbourhood best as the generation starts (the constriction
        // variant looks them up as each particle moves instead).
        let mut lbest = [0usize; MAX_POP];
        if !constriction {
            for (i, lb) in lbest[..n].iter_mut().enumerate() {
                *lb = self.neighbourhood_best(i, n);
            }
        }
        for i in 0..n {
            let l = if constriction {
                self.pbest[self.neighbourhood_best(i, n)]
            } else {
                self.pbest[lbest[i]]
            };
            let e = &mut self.engine;
            let mut x = e.pop.genes[i];
            for d in 0..e.dim {
                let vmax = p.vmax_fraction * (e.upper[d] - e.lower[d]);
                let cognitive = p.cognitive * random::unit_f32(rng) * (self.pbest[i][d] - x[d]);
                let social = p.social * random::unit_f32(rng) * (l[d] - x[d]);
                let v = if constriction {
                    p.inertia * (self.velocity[i][d] + cognitive + social)
                } else {
                    p.inertia * self.velocity[i][d] + cognitive + social
                };
                let v = v.clamp(-vmax, vmax);
                self.velocity[i][d] = v;
                x[d] += v;
                if constriction && !(e.lower[d]..=e.upper[d]).contains(&x[d]) {
                    self.velocity[i][d] = 0.0;
                }
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
        let e = &mut self.engine;
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
