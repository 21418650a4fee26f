//! `papillon-sim optimize`: runs one optimizer on a standard test function several times and
//! prints the median, min and max best fitness, the mean evaluations and the mean time per run
//! ([`crate::optimize`]).

use std::ops::RangeInclusive;
use std::process::ExitCode;

use papillon::optim::Method;
use papillon::optim::functions::Function;

use crate::optimize::{Experiment, Outcome, execute};

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

/// `text` as an integer in `range`; the error names the option `--name`.
fn number<T>(name: &str, text: &str, range: RangeInclusive<T>) -> Result<T, String>
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy,
{
    match text.parse::<T>() {
        Ok(v) if range.contains(&v) => Ok(v),
        _ => Err(format!(
            "--{name}: expected an integer from {} to {}, got '{text}'",
            range.start(),
            range.end()
        )),
    }
}

/// The experiment the arguments ask for; the error is one line naming the bad option.
pub fn experiment_from_args(args: &Args) -> Result<Experiment, String> {
    let function = args
        .function
        .parse::<Function>()
        .map_err(|e| format!("--function: {e}, got '{}'", args.function))?;
    let method = args
        .method
        .parse::<Method>()
        .map_err(|e| format!("--method: {e}, got '{}'", args.method))?;
    Ok(Experiment {
        function,
        dim: number("dim", &args.dim, Experiment::dim_range(function))?,
        method,
        pop: number("pop", &args.pop, Experiment::POP)?,
        gens: number("gens", &args.gens, Experiment::GENS)?,
        runs: number("runs", &args.runs, Experiment::RUNS)?,
        seed: number("seed", &args.seed, 0..=u64::MAX)?,
        patience: match &args.patience {
            Some(p) => Some(number("patience", p, Experiment::PATIENCE)?),
            None => None,
        },
    })
}

fn print(exp: &Experiment, out: &Outcome, json: bool) {
    if json {
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
}

/// Runs the command.
pub fn run(args: Args) -> ExitCode {
    let exp = match experiment_from_args(&args) {
        Ok(e) => e,
        Err(msg) => {
            eprintln!("papillon-sim optimize: {msg}");
            return ExitCode::from(2);
        }
    };
    match execute(&exp) {
        Ok(out) => {
            print(&exp, &out, args.json);
            ExitCode::SUCCESS
        }
        Err(msg) => {
            eprintln!("papillon-sim optimize: {msg}");
            ExitCode::from(1)
        }
    }
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
        let e = experiment_from_args(&args("xbox", "4")).unwrap_err();
        assert!(
            e.starts_with("--method:") && e.contains("xbox") && !e.contains('\n'),
            "{e}"
        );
        let e = experiment_from_args(&args("xboa", "17")).unwrap_err();
        assert!(e.starts_with("--dim:") && e.contains("17"), "{e}");
        let mut a = args("xboa", "4");
        a.pop = "1".into();
        assert!(experiment_from_args(&a).unwrap_err().starts_with("--pop:"));
    }

    #[test]
    fn arguments_become_the_experiment() {
        let mut a = args("gwo", "4");
        a.patience = Some("7".into());
        let exp = experiment_from_args(&a).unwrap();
        assert_eq!(
            exp,
            Experiment {
                function: Function::Rastrigin,
                dim: 4,
                method: Method::Gwo,
                pop: 8,
                gens: 10,
                runs: 3,
                seed: 5,
                patience: Some(7),
            }
        );
    }
}
