//! `papillon-sim tune`: TPE search of one method's hyper-parameters on exploration missions
//! ([`crate::bench::tune`]); writes `tune.json`, `trials.jsonl`, `trials.csv`, `trials.md`
//! and `best.json` (the best parameters, which `bench --params` reads).
//!
//! Bad arguments exit with status 2 and one line on standard error; a failed mission exits
//! with status 1.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::bench::tune::{Settings, best, tune};

/// Arguments of `papillon-sim tune`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Method: xboa boa mboa aboa saboa ga pso (the others have no hyper-parameters).
    #[arg(long)]
    pub method: String,
    /// Trials (the thesis: 30).
    #[arg(long, default_value = "30", allow_negative_numbers = true)]
    pub trials: usize,
    /// Missions per trial, seeds SEED.. (the thesis: 3).
    #[arg(long, default_value = "3", allow_negative_numbers = true)]
    pub runs: usize,
    /// World (default: the project's house; the thesis's House only when named, e.g.
    /// ../shared/data/thesis-maps/map-house.csv).
    #[arg(long)]
    pub map: Option<String>,
    /// Population.
    #[arg(long, default_value = "5", allow_negative_numbers = true)]
    pub pop: usize,
    /// Generations per decision.
    #[arg(long, default_value = "30", allow_negative_numbers = true)]
    pub gens: u32,
    /// Strategy: short or long.
    #[arg(long, default_value = "short")]
    pub strategy: String,
    /// Targets per decision of the long-term strategy.
    #[arg(long, default_value = "3", allow_negative_numbers = true)]
    pub targets: usize,
    /// What the optimizers maximise: thesis (the default here, as the thesis tuned) or
    /// efficient.
    #[arg(long, default_value = "thesis")]
    pub objective: String,
    /// Battery in steps (default: the mission's, 500).
    #[arg(long, allow_negative_numbers = true)]
    pub battery: Option<f32>,
    /// Seed of every trial's first mission.
    #[arg(long, default_value = "25")]
    pub seed: u64,
    /// Seed of the TPE sampler.
    #[arg(long, default_value = "25")]
    pub sampler_seed: u64,
    /// Trials proposed together: each from the trials of the earlier batches only (1: every
    /// earlier trial, as Hyperopt; more lets shards run a batch in parallel).
    #[arg(long, default_value = "1", allow_negative_numbers = true)]
    pub batch: usize,
    /// Run only shard I of N (0 <= I < N): the trials whose scrambled index is I modulo N, as
    /// bench splits runs.
    #[arg(long)]
    pub shard: Option<String>,
    /// Other shards' directories whose trials count (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub with: Vec<PathBuf>,
    /// Worker threads for a trial's missions (default: one per core).
    #[arg(long, default_value = "0", allow_negative_numbers = true)]
    pub jobs: usize,
    /// Output directory (default: tune-results/METHOD).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

fn fail(msg: &str) -> ExitCode {
    eprintln!("papillon-sim tune: {msg}");
    ExitCode::from(2)
}

/// The settings the arguments describe.
pub fn settings_from_args(args: &Args) -> Result<Settings, String> {
    let map = match &args.map {
        Some(m) => m.clone(),
        None => "house".into(),
    };
    if args.strategy != "short" && args.strategy != "long" {
        return Err(format!(
            "--strategy: expected short or long, got '{}'",
            args.strategy
        ));
    }
    let s = Settings {
        method: args.method.clone(),
        map,
        population: args.pop,
        strategy: args.strategy.clone(),
        targets: if args.strategy == "long" {
            args.targets
        } else {
            1
        },
        objective: args.objective.clone(),
        generations: args.gens,
        battery_steps: args.battery,
        runs: args.runs,
        base_seed: args.seed,
        trials: args.trials,
        batch: args.batch,
        sampler_seed: args.sampler_seed,
        resolution_m: 0.1,
    };
    s.check()?;
    s.sweep(&Default::default()).check_runnable()?;
    Ok(s)
}

/// Runs `papillon-sim tune`.
pub fn run(args: Args) -> ExitCode {
    if let Err(e) = super::check_jobs(args.jobs) {
        return fail(&e);
    }
    let settings = match settings_from_args(&args) {
        Ok(s) => s,
        Err(e) => return fail(&e),
    };
    let (shard, out) = match super::shard_and_out(
        args.shard.as_deref(),
        args.out.as_deref(),
        "tune-results",
        &settings.method,
    ) {
        Ok(x) => x,
        Err(e) => return fail(&e),
    };
    let total = settings.trials;
    let mut progress = |t: &crate::bench::tune::Trial| {
        let cov =
            t.coverage.iter().map(|&c| f64::from(c)).sum::<f64>() / t.coverage.len().max(1) as f64;
        eprintln!(
            "trial {}/{total}: {:?} loss {:.3}, coverage {:.2} %",
            t.index + 1,
            t.params,
            t.loss,
            100.0 * cov
        );
    };
    match tune(&settings, shard, args.jobs, &out, &args.with, &mut progress) {
        Ok(o) => {
            if o.waiting > 0 {
                eprintln!(
                    "papillon-sim tune: {} trials of shard {shard} wait for other shards' earlier batches; run again with --with their directories once they finish",
                    o.waiting
                );
            }
            if let Some(b) = best(&o.trials) {
                eprintln!(
                    "best: trial {} {:?} (loss {:.3})",
                    b.index, b.params, b.loss
                );
            }
            println!("{}", out.join("best.json").display());
            ExitCode::SUCCESS
        }
        Err(e) if e.starts_with("trial ") => {
            eprintln!("papillon-sim tune: {e}");
            ExitCode::from(1)
        }
        Err(e) => fail(&e),
    }
}
