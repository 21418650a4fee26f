//! Optimizer experiments on standard test functions: one method, several seeded runs, the
//! median, min and max best fitness, the mean evaluations and the mean time per run
//! (`papillon-sim optimize` parses its arguments into an [`Experiment`] and prints the
//! [`Outcome`]). The function's optimum may be moved to `x_i = shift`
//! ([`TestFunction::shifted`]), and the method built with either parameter set ([`Preset`]).
//!
//! Protocol (the thesis's): run `r` starts from a population drawn uniformly in the bounds from
//! a seed derived from `(seed, r)` only ([`population_seed`]), so every method starts each run
//! from the same population; the optimizer's own draws come from a second seed derived from
//! `(seed, r)` ([`optimizer_seed`]). Runs go the full [`Experiment::gens`] generations unless
//! [`Experiment::patience`] is given.

use std::ops::RangeInclusive;
use std::time::Instant;

use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{
    self, MAX_DIM, MAX_POP, MIN_POP, Method, Population, Preset, Problem, StopRules,
};
use papillon::random::seeded;

/// One experiment: a method on a test function, `runs` seeded runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    /// Test function.
    pub function: Function,
    /// Genes ([`Experiment::dim_range`]).
    pub dim: usize,
    /// Method.
    pub method: Method,
    /// Hyper-parameters of the method.
    pub preset: Preset,
    /// Where the optimum lies (every gene; `None`: the function's own optimum).
    pub shift: Option<f32>,
    /// Population size ([`Experiment::POP`]).
    pub pop: usize,
    /// Generations per run ([`Experiment::GENS`]).
    pub gens: u32,
    /// Runs ([`Experiment::RUNS`]).
    pub runs: u32,
    /// Base seed.
    pub seed: u64,
    /// Early stop after this many generations without improvement ([`Experiment::PATIENCE`];
    /// `None`: never).
    pub patience: Option<u32>,
}

impl Default for Experiment {
    /// xBOA (standard preset) on the unshifted sphere, 10 genes, population 20, 100
    /// generations, 25 runs, seed 1, no early stop (the defaults of `papillon-sim optimize`).
    fn default() -> Self {
        Self {
            function: Function::Sphere,
            dim: 10,
            method: Method::Xboa,
            preset: Preset::Standard,
            shift: None,
            pop: 20,
            gens: 100,
            runs: 25,
            seed: 1,
            patience: None,
        }
    }
}

/// Results over the runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// Median best fitness.
    pub median: f64,
    /// Smallest best fitness.
    pub min: f64,
    /// Largest best fitness.
    pub max: f64,
    /// Mean evaluations per run.
    pub evals: f64,
    /// Mean wall time per run \[ms\].
    pub mean_ms: f64,
    /// Mean CPU time per run \[ms\]: the thread's CPU clock around drawing the initial
    /// population, building the method and running it (pygmo's `population` + `evolve`), so
    /// a shared machine's waits for a core do not count.
    pub cpu_ms: f64,
}

/// CPU time used by the calling thread \[s\] (`CLOCK_THREAD_CPUTIME_ID`).
fn thread_cpu_s() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own; the clock id is a constant.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return f64::NAN;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn within<T: PartialOrd + std::fmt::Display>(
    name: &str,
    value: T,
    range: &RangeInclusive<T>,
) -> Result<(), String> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(format!(
            "{name}: expected an integer from {} to {}, got {value}",
            range.start(),
            range.end()
        ))
    }
}

impl Experiment {
    /// Accepted population sizes.
    pub const POP: RangeInclusive<usize> = MIN_POP..=MAX_POP;
    /// Accepted generations per run (the optimizers keep a history of `MAX_HISTORY` bests).
    pub const GENS: RangeInclusive<u32> = 1..=(optim::MAX_HISTORY - 1) as u32;
    /// Accepted numbers of runs.
    pub const RUNS: RangeInclusive<u32> = 1..=100_000;
    /// Accepted patience.
    pub const PATIENCE: RangeInclusive<u32> = 1..=u32::MAX;

    /// Accepted dimensions for `function` (Rosenbrock needs 2 genes).
    pub fn dim_range(function: Function) -> RangeInclusive<usize> {
        let min = if function == Function::Rosenbrock {
            2
        } else {
            1
        };
        min..=MAX_DIM
    }

    /// Checks every setting against its range; the error is one line naming the setting.
    pub fn check(&self) -> Result<(), String> {
        within("dim", self.dim, &Self::dim_range(self.function))?;
        within("pop", self.pop, &Self::POP)?;
        within("gens", self.gens, &Self::GENS)?;
        within("runs", self.runs, &Self::RUNS)?;
        if let Some(p) = self.patience {
            within("patience", p, &Self::PATIENCE)?;
        }
        self.problem().map(|_| ())
    }

    /// The problem every run optimizes; the error names the setting at fault.
    pub fn problem(&self) -> Result<TestFunction, String> {
        match self.shift {
            None => TestFunction::new(self.function, self.dim).map_err(|e| format!("dim: {e}")),
            Some(s) => TestFunction::shifted(self.function, self.dim, s)
                .map_err(|e| format!("shift: {e} of {}", self.function)),
        }
    }

    /// When a run stops.
    pub fn stop_rules(&self) -> StopRules {
        StopRules {
            max_generations: self.gens,
            patience: self.patience,
            max_evaluations: None,
        }
    }
}

/// SplitMix64 finaliser: decorrelates nearby seeds.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of run `run`'s initial population (the same for every method).
pub fn population_seed(seed: u64, run: u32) -> u64 {
    mix(mix(seed) ^ (2 * run as u64))
}

/// Seed of run `run`'s optimizer draws.
pub fn optimizer_seed(seed: u64, run: u32) -> u64 {
    mix(mix(seed) ^ (2 * run as u64 + 1))
}

/// Initial population of run `run`: `pop` individuals drawn uniformly in `problem`'s bounds.
pub fn initial_population<P: Problem + ?Sized>(
    problem: &P,
    pop: usize,
    seed: u64,
    run: u32,
) -> Result<Population, String> {
    Population::uniform(problem, pop, &mut seeded(population_seed(seed, run)))
        .map_err(|e| e.to_string())
}

/// Runs the experiment: checks it, then its runs one after the other.
pub fn execute(exp: &Experiment) -> Result<Outcome, String> {
    exp.check()?;
    let rules = exp.stop_rules();
    let mut bests = Vec::with_capacity(exp.runs as usize);
    let (mut evals, mut ms, mut cpu_s) = (0f64, 0f64, 0f64);
    for run in 0..exp.runs {
        let mut problem = exp.problem()?;
        let (t0, c0) = (Instant::now(), thread_cpu_s());
        let initial = initial_population(&problem, exp.pop, exp.seed, run)?;
        let mut rng = seeded(optimizer_seed(exp.seed, run));
        let mut opt = exp.method.build_preset(exp.preset, exp.pop, exp.gens);
        let s = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng)
            .map_err(|e| e.to_string())?;
        ms += t0.elapsed().as_secs_f64() * 1e3;
        cpu_s += thread_cpu_s() - c0;
        evals += s.evaluations as f64;
        bests.push(s.best_fitness as f64);
    }
    bests.sort_by(f64::total_cmp);
    let n = bests.len();
    let median = if n % 2 == 1 {
        bests[n / 2]
    } else {
        0.5 * (bests[n / 2 - 1] + bests[n / 2])
    };
    Ok(Outcome {
        median,
        min: bests[0],
        max: bests[n - 1],
        evals: evals / n as f64,
        mean_ms: ms / n as f64,
        cpu_ms: cpu_s * 1e3 / n as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn experiment(method: Method, dim: usize) -> Experiment {
        Experiment {
            function: Function::Rastrigin,
            dim,
            method,
            preset: Preset::Standard,
            shift: None,
            pop: 8,
            gens: 10,
            runs: 3,
            seed: 5,
            patience: None,
        }
    }

    #[test]
    fn settings_out_of_range_name_the_setting() {
        let e = experiment(Method::Xboa, 17).check().unwrap_err();
        assert!(e.starts_with("dim:") && e.contains("17"), "{e}");
        let e = execute(&experiment(Method::Xboa, 17)).unwrap_err();
        assert!(e.starts_with("dim:"), "{e}");
        let mut x = experiment(Method::Xboa, 4);
        x.pop = 1;
        assert!(x.check().unwrap_err().starts_with("pop:"));
        x = experiment(Method::Xboa, 1);
        x.function = Function::Rosenbrock;
        assert!(x.check().unwrap_err().starts_with("dim:"));
        assert_eq!(experiment(Method::Xboa, 4).check(), Ok(()));
        x = experiment(Method::Xboa, 4);
        x.shift = Some(5.2);
        let e = execute(&x).unwrap_err();
        assert!(e.starts_with("shift:") && e.contains("5.2"), "{e}");
        x.shift = Some(1.7);
        assert_eq!(x.check(), Ok(()));
    }

    #[test]
    fn the_shift_moves_the_optimum_the_runs_approach() {
        // CMA-ES on the 4-gene sphere gets close to wherever the optimum is; the unshifted
        // problem scores the shifted run's best point far worse.
        let mut x = experiment(Method::CmaEs, 4);
        x.function = Function::Sphere;
        x.gens = 60;
        x.shift = Some(1.7);
        let shifted = execute(&x).unwrap();
        assert!(shifted.max < 1e-3, "{shifted:?}");
        let mut p = x.problem().unwrap();
        assert!(p.evaluate(&[1.7; 4]) < 1e-9);
        assert!(p.evaluate(&[0.0; 4]) > 11.0);
    }

    #[test]
    fn every_method_starts_from_the_same_population() {
        let problem = TestFunction::new(Function::Sphere, 4).unwrap();
        let a = initial_population(&problem, 6, 9, 2).unwrap();
        let b = initial_population(&problem, 6, 9, 2).unwrap();
        let c = initial_population(&problem, 6, 9, 3).unwrap();
        for i in 0..6 {
            assert_eq!(a.genome(i), b.genome(i));
        }
        assert_ne!(a.genome(0), c.genome(0));
    }

    #[test]
    fn outcome_is_ordered_and_reproducible() {
        let exp = experiment(Method::Gwo, 4);
        let a = execute(&exp).unwrap();
        let b = execute(&exp).unwrap();
        assert!(a.min <= a.median && a.median <= a.max);
        assert_eq!(
            (a.median, a.min, a.max, a.evals),
            (b.median, b.min, b.max, b.evals)
        );
        assert_eq!(a.evals, 8.0 + 8.0 * 10.0);
    }
}
