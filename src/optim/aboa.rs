//! ABOA: the Butterfly Optimization Algorithm with a non-linear sensory-modality schedule.
//!
//! Source: Zhang et al. (2020), the adaptive BOA with a non-linear parameter schedule that the
//! thesis (Bendahmane 2023) compares under the name ABOA; the schedule below is the one the
//! thesis states.
//!
//! BOA ([`super::boa`]) whose sensory modality follows, at generation `t` of `T`,
//! `c(t) = 0.1 + 0.2 * sin((pi / mu) * (t / T)^2)` instead of BOA's increment; `t` counts the
//! generations already run (0 in the first one). Global step with probability `p`, local step
//! otherwise, greedy acceptance. Defaults (thesis tuning): `a = 0.992, p = 0.983, mu = 1.356`.

use rand_core::Rng;

use super::boa::sweep;
use super::{Engine, OptimError, Optimizer, Population, Problem, engine_accessors};
use crate::math;

/// ABOA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AboaParams {
    /// Power exponent `a`.
    pub a: f32,
    /// Switch probability `p`.
    pub p: f32,
    /// Shape `mu` of the sensory-modality schedule.
    pub mu: f32,
}

impl Default for AboaParams {
    fn default() -> Self {
        Self {
            a: 0.992,
            p: 0.983,
            mu: 1.356,
        }
    }
}

/// ABOA state.
#[derive(Debug, Clone)]
pub struct Aboa {
    params: AboaParams,
    engine: Engine,
}

impl Aboa {
    /// An ABOA with `params`, whose schedule spans `max_generations` generations.
    pub fn new(params: AboaParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
        }
    }

    /// Sensory modality at fraction `progress = t / T` of the run.
    pub fn sensory_modality(&self, progress: f32) -> f32 {
        0.1 + 0.2 * math::sin((core::f32::consts::PI / self.params.mu) * progress * progress)
    }
}

impl Optimizer for Aboa {
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
        let c = self.sensory_modality(self.engine.progress());
        sweep(
            &mut self.engine,
            problem,
            rng,
            self.params.a,
            c,
            self.params.p,
        );
        self.engine.end_step();
        Ok(())
    }

    engine_accessors!();
}
