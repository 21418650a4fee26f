//! Uniform random search, the baseline every method must beat.
//!
//! Source: J. Bergstra and Y. Bengio, "Random search for hyper-parameter optimization", JMLR 13
//! (2012) use it as the reference baseline; here each generation draws as many points as the
//! population holds, uniformly in the bounds, and evaluates them. The reported population is
//! the last draw; the best genome is the best point ever drawn (initial population included).

use rand_core::Rng;

use super::{Engine, OptimError, Optimizer, Population, Problem, engine_accessors};

/// Random-search state.
#[derive(Debug, Clone)]
pub struct RandomSearch {
    engine: Engine,
}

impl RandomSearch {
    /// A random search (`max_generations` is kept for symmetry with the other methods).
    pub fn new(max_generations: u32) -> Self {
        Self {
            engine: Engine::new(max_generations),
        }
    }
}

impl Optimizer for RandomSearch {
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
        for i in 0..e.pop.len {
            let x = e.uniform(rng);
            let f = e.evaluate(problem, &x);
            e.pop.genes[i] = x;
            e.pop.fitness[i] = f;
        }
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}
