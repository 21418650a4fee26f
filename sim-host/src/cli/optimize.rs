//! `papillon-sim optimize`: runs one optimizer on a standard test function several times and
//! prints the median, min and max best fitness, the mean evaluations and the mean time per run
//! ([`crate::optimize`]).

use std::ops::RangeInclusive;
use std::process::ExitCode;

use papillon::optim::functions::Function;
use papillon::optim::{Method, Preset};

use crate::optimize::{Experiment, Outcome, execute};

/// Arguments of `papillon-sim optimize`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Test function: sphere, rastrigin, rosenbrock, ackley or griewank.
    #[arg(long, default_value = "sphere")]
    pub function: String,
    /// Number of genes (1 to 16; rosenbrock needs 2).
    #[arg(long, default_value = "10", allow_negative_numbers = true)]
    pub dim: String,
    /// Method: xboa boa mboa aboa saboa ga pso gwo abc cmaes, or random (baseline).
    #[arg(long, default_value = "xboa")]
    pub method: String,
    /// Hyper-parameters: standard (the literature's defaults, as pygmo's) or thesis (Table 4.1,
    /// tuned on the exploration problem; what the exploration experiments use). Only GA and
    /// PSO differ.
    #[arg(long, default_value = "standard")]
    pub preset: String,
    /// Move the optimum to x_i = SHIFT (inside the bounds); default: the function's own.
    #[arg(long, allow_negative_numbers = true)]
    pub shift: Option<String>,
    /// Population size (2 to 32).
    #[arg(long, default_value = "20", allow_negative_numbers = true)]
    pub pop: String,
    /// Generations per run (1 to 999).
    #[arg(long, default_value = "100", allow_negative_numbers = true)]
    pub gens: String,
    /// Number of runs.
    #[arg(long, default_value = "25", allow_negative_numbers = true)]
    pub runs: String,
    /// Base seed.
    #[arg(long, default_value = "1", allow_negative_numbers = true)]
    pub seed: String,
    /// Stop a run after this many generations without improvement (default: never).
    #[arg(long, allow_negative_numbers = true)]
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
    let preset = args
        .preset
        .parse::<Preset>()
        .map_err(|e| format!("--preset: {e}, got '{}'", args.preset))?;
    let shift = match &args.shift {
        None => None,
        Some(t) => match t.parse::<f32>() {
            Ok(s) if s.is_finite() => Some(s),
            _ => return Err(format!("--shift: expected a number, got '{t}'")),
        },
    };
    let exp = Experiment {
        function,
        dim: number("dim", &args.dim, Experiment::dim_range(function))?,
        method,
        preset,
        shift,
        pop: number("pop", &args.pop, Experiment::POP)?,
        gens: number("gens", &args.gens, Experiment::GENS)?,
        runs: number("runs", &args.runs, Experiment::RUNS)?,
        seed: number("seed", &args.seed, 0..=u64::MAX)?,
        patience: match &args.patience {
            Some(p) => Some(number("patience", p, Experiment::PATIENCE)?),
            None => None,
        },
    };
    exp.problem().map_err(|e| format!("--{e}"))?;
    Ok(exp)
}

fn print(exp: &Experiment, out: &Outcome, json: bool) {
    if json {
        let v = serde_json::json!({
            "method": exp.method.name(),
            "preset": exp.preset.name(),
            "function": exp.function.name(),
            // The f32 as written on the command line, not its f64 widening (1.7000000476...).
            "shift": exp.shift.map(|s| s.to_string().parse::<f64>().unwrap_or(s as f64)),
            "dim": exp.dim,
            "median": out.median,
            "min": out.min,
            "max": out.max,
            "evals": out.evals,
            "mean_ms": out.mean_ms,
            "cpu_ms": out.cpu_ms,
        });
        println!("{v}");
    } else {
        let optimum = match exp.shift {
            Some(s) => format!(", optimum at {s}"),
            None => String::new(),
        };
        println!(
            "{} ({} preset) on {} ({} genes{optimum}), population {}, {} generations, {} runs, seed {}",
            exp.method, exp.preset, exp.function, exp.dim, exp.pop, exp.gens, exp.runs, exp.seed
        );
        println!(
            "best fitness: median {:.6e}  min {:.6e}  max {:.6e}",
            out.median, out.min, out.max
        );
        println!("mean evaluations per run: {:.1}", out.evals);
        println!(
            "mean time per run: {:.4} ms CPU, {:.4} ms wall",
            out.cpu_ms, out.mean_ms
        );
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
            preset: "standard".into(),
            shift: None,
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
        let mut a = args("ga", "4");
        a.preset = "pygmo".into();
        let e = experiment_from_args(&a).unwrap_err();
        assert!(e.starts_with("--preset:") && e.contains("pygmo"), "{e}");
        let mut a = args("ga", "4");
        a.shift = Some("east".into());
        assert!(
            experiment_from_args(&a)
                .unwrap_err()
                .starts_with("--shift:")
        );
        a.shift = Some("9".into());
        let e = experiment_from_args(&a).unwrap_err();
        assert!(e.starts_with("--shift:") && e.contains('9'), "{e}");
    }

    #[test]
    fn arguments_become_the_experiment() {
        let mut a = args("gwo", "4");
        a.patience = Some("7".into());
        a.preset = "thesis".into();
        a.shift = Some("1.7".into());
        let exp = experiment_from_args(&a).unwrap();
        assert_eq!(
            exp,
            Experiment {
                function: Function::Rastrigin,
                dim: 4,
                method: Method::Gwo,
                preset: Preset::Thesis,
                shift: Some(1.7),
                pop: 8,
                gens: 10,
                runs: 3,
                seed: 5,
                patience: Some(7),
            }
        );
    }
}
