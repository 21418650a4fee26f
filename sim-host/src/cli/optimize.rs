//! `papillon-sim optimize`: runs one optimizer on a standard test function several times and
//! prints the median, min and max best fitness, the mean evaluations and the mean time per run.
//!
//! Protocol (the thesis's): run `r` starts from a population drawn uniformly in the bounds from
//! a seed derived from `(seed, r)` only, so every method starts each run from the same
//! population; the optimizer's own draws come from a second seed derived from `(seed, r)`.
//! Runs go the full `--gens` generations unless `--patience` is given.

use std::process::ExitCode;
use std::time::Instant;

use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{self, MAX_DIM, MAX_POP, MIN_POP, Method, Population, StopRules};
use papillon::random::seeded;

/// Arguments of `papillon-sim optimize`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Test function: sphere, rastrigin, rosenbrock, ackley or griewank.
    #[arg(long, default_value = "sphere")]
    pub function: String,
    /// Number of genes (1 to 16; rosenbrock needs 2).
    #[arg(long, default_value = "10")]
    pub dim: String,
    /// Method: xboa boa mboa aboa saboa ga pso gwo abc cmaes, or random (baseline).
    #[arg(long, default_value = "xboa")]
    pub method: String,
    /// Population size (2 to 32).
    #[arg(long, default_value = "20")]
    pub pop: String,
    /// Generations per run (1 to 999).
    #[arg(long, default_value = "100")]
    pub gens: String,
    /// Number of runs.
    #[arg(long, default_value = "25")]
    pub runs: String,
    /// Base seed.
    #[arg(long, default_value = "1")]
    pub seed: String,
    /// Stop a run after this many generations without improvement (default: never).
    #[arg(long)]
    pub patience: Option<String>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// A validated experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    /// Test function.
    pub function: Function,
    /// Genes.
    pub dim: usize,
    /// Method.
    pub method: Method,
    /// Population size.
    pub pop: usize,
    /// Generations per run.
    pub gens: u32,
    /// Runs.
    pub runs: u32,
    /// Base seed.
    pub seed: u64,
    /// Early stop after this many generations without improvement.
    pub patience: Option<u32>,
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
}

fn number<T>(name: &str, text: &str, lo: T, hi: T) -> Result<T, String>
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy,
{
    match text.parse::<T>() {
        Ok(v) if v >= lo && v <= hi => Ok(v),
        _ => Err(format!(
            "--{name}: expected an integer from {lo} to {hi}, got '{text}'"
        )),
    }
}

impl Experiment {
    /// Checks the command-line arguments; the error is one line naming the bad option.
    pub fn from_args(args: &Args) -> Result<Self, String> {
        let function = args
            .function
            .parse::<Function>()
            .map_err(|e| format!("--function: {e}, got '{}'", args.function))?;
        let method = args
            .method
            .parse::<Method>()
            .map_err(|e| format!("--method: {e}, got '{}'", args.method))?;
        let min_dim = if function == Function::Rosenbrock {
            2
        } else {
            1
        };
        let dim = number("dim", &args.dim, min_dim, MAX_DIM)?;
        let pop = number("pop", &args.pop, MIN_POP, MAX_POP)?;
        let gens = number("gens", &args.gens, 1, (optim::MAX_HISTORY - 1) as u32)?;
        let runs = number("runs", &args.runs, 1, 100_000)?;
        let seed = number("seed", &args.seed, 0, u64::MAX)?;
        let patience = match &args.patience {
            Some(p) => Some(number("patience", p, 1, u32::MAX)?),
            None => None,
        };
        Ok(Self {
            function,
            dim,
            method,
            pop,
            gens,
            runs,
            seed,
            patience,
        })
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

/// Initial population of run `run`.
pub fn initial_population(problem: &TestFunction, pop: usize, seed: u64, run: u32) -> Population {
    Population::uniform(problem, pop, &mut seeded(population_seed(seed, run)))
        .expect("validated dimension and population")
}

/// Runs the experiment.
pub fn execute(exp: &Experiment) -> Result<Outcome, String> {
    let mut bests = Vec::with_capacity(exp.runs as usize);
    let (mut evals, mut ms) = (0f64, 0f64);
    for run in 0..exp.runs {
        let mut problem = TestFunction::new(exp.function, exp.dim).map_err(|e| e.to_string())?;
        let initial = initial_population(&problem, exp.pop, exp.seed, run);
        let rules = StopRules {
            max_generations: exp.gens,
            patience: exp.patience,
            max_evaluations: None,
        };
        let mut rng = seeded(optimizer_seed(exp.seed, run));
        let t0 = Instant::now();
        let mut opt = exp.method.build(exp.pop, exp.gens);
        let s = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng)
            .map_err(|e| e.to_string())?;
        ms += t0.elapsed().as_secs_f64() * 1e3;
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
    })
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    let exp = match Experiment::from_args(&args) {
        Ok(e) => e,
        Err(msg) => {
            eprintln!("papillon-sim optimize: {msg}");
            return ExitCode::from(2);
        }
    };
    let out = match execute(&exp) {
        Ok(o) => o,
        Err(msg) => {
            eprintln!("papillon-sim optimize: {msg}");
            return ExitCode::from(1);
        }
    };
    if args.json {
        let v = serde_json::json!({
            "method": exp.method.name(),
            "function": exp.function.name(),
            "dim": exp.dim,
            "median": out.median,
            "min": out.min,
            "max": out.max,
            "evals": out.evals,
            "mean_ms": out.mean_ms,
        });
        println!("{v}");
    } else {
        println!(
            "{} on {} ({} genes), population {}, {} generations, {} runs, seed {}",
            exp.method, exp.function, exp.dim, exp.pop, exp.gens, exp.runs, exp.seed
        );
        println!(
            "best fitness: median {:.6e}  min {:.6e}  max {:.6e}",
            out.median, out.min, out.max
        );
        println!("mean evaluations per run: {:.1}", out.evals);
        println!("mean time per run: {:.3} ms", out.mean_ms);
    }
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(method: &str, dim: &str) -> Args {
        Args {
            function: "rastrigin".into(),
            dim: dim.into(),
            method: method.into(),
            pop: "8".into(),
            gens: "10".into(),
            runs: "3".into(),
            seed: "5".into(),
            patience: None,
            json: false,
        }
    }

    #[test]
    fn bad_arguments_name_the_option() {
        let e = Experiment::from_args(&args("xbox", "4")).unwrap_err();
        assert!(
            e.starts_with("--method:") && e.contains("xbox") && !e.contains('\n'),
            "{e}"
        );
        let e = Experiment::from_args(&args("xboa", "17")).unwrap_err();
        assert!(e.starts_with("--dim:") && e.contains("17"), "{e}");
        let mut a = args("xboa", "4");
        a.pop = "1".into();
        assert!(Experiment::from_args(&a).unwrap_err().starts_with("--pop:"));
    }

    #[test]
    fn every_method_starts_from_the_same_population() {
        let problem = TestFunction::new(Function::Sphere, 4).unwrap();
        let a = initial_population(&problem, 6, 9, 2);
        let b = initial_population(&problem, 6, 9, 2);
        let c = initial_population(&problem, 6, 9, 3);
        for i in 0..6 {
            assert_eq!(a.genome(i), b.genome(i));
        }
        assert_ne!(a.genome(0), c.genome(0));
    }

    #[test]
    fn outcome_is_ordered_and_reproducible() {
        let exp = Experiment::from_args(&args("gwo", "4")).unwrap();
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
