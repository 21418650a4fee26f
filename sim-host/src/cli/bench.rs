//! `papillon-sim bench`: run an experiment (a named one or a JSON sweep) in parallel, or merge
//! the results of its shards ([`crate::bench`]; the sweep is chosen by
//! [`crate::bench::select`]).
//!
//! Bad arguments and unreadable files exit with status 2 and one line on standard error; a
//! sweep whose runs failed exits with status 1 after writing its outputs.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::bench::exec::ProgressMode;
use crate::bench::select::{Overrides, SelectError, Source, ThesisMaps, select};
use crate::bench::sweep::{Shard, Sweep};
use crate::bench::{self as b, run_sweep};

/// Arguments of `papillon-sim bench`.
#[derive(clap::Args, Debug, Clone)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    /// Merge shard directories.
    #[command(subcommand)]
    pub command: Option<BenchCommand>,
    /// Named experiment: multi-robot, horizon, methods, population, boa-variants, scale (cost
    /// on generated storeys of 240² to 1920² cells, 1 to 100 robots, 1 run); the
    /// thesis's, side by side with its tables: thesis-methods, thesis-methods-long,
    /// thesis-horizon, thesis-population, thesis-pop5, thesis-boa-variants,
    /// thesis-multi-robot, or thesis-all (all of them, each into OUT/NAME); or all (every
    /// named experiment, each into OUT/NAME); or a comma-separated list of experiments (each
    /// into OUT/NAME). thesis-all, all and a list run their experiments' runs as one pool, a
    /// run that several of them ask for once (with --shard: one experiment after the other).
    #[arg(long, conflicts_with = "config")]
    pub experiment: Option<String>,
    /// Sweep file (JSON: maps, methods, strategies, populations, robots, runs, generations,
    /// battery_steps, base_seed, resolution_m, objective(s), preset(s), params, max_time_s).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Runs per combination (default: the sweep's; 10 for the named experiments, 1 for scale).
    #[arg(long, allow_negative_numbers = true)]
    pub runs: Option<usize>,
    /// Worker threads (default: one per core; at most 1024).
    #[arg(long, default_value = "0", allow_negative_numbers = true)]
    pub jobs: usize,
    /// Output directory (default: bench-results/NAME).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run only shard I of N (0 <= I < N): the runs whose index is I modulo N.
    #[arg(long)]
    pub shard: Option<String>,
    /// Replace the sweep's maps (comma-separated built-in names or files).
    #[arg(long, value_delimiter = ',')]
    pub maps: Option<Vec<String>>,
    /// Replace the sweep's battery (steps).
    #[arg(long, allow_negative_numbers = true)]
    pub battery: Option<f32>,
    /// Replace the sweep's objective: efficient (the default) or thesis.
    #[arg(long)]
    pub objective: Option<String>,
    /// Replace the sweep's optimizer preset: standard (the literature's defaults; Papillon's
    /// default) or thesis (Table 4.1; what the thesis-* experiments and tune run). Default: the
    /// sweep's; see docs/optimizers.md.
    #[arg(long, value_parser = ["thesis", "standard"])]
    pub preset: Option<String>,
    /// Hyper-parameters replacing the preset's (a partial set keeps the preset's other
    /// values): a JSON file with {"params": {METHOD: {NAME: VALUE}}}, such as a `tune` run's
    /// best.json.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Directory with the thesis's map-empty.csv and map-house.csv, added to the named
    /// experiments' maps (e.g. ../shared/data/thesis-maps). Without it the named experiments
    /// run on the project's own maps only, whatever exists beside the project.
    #[arg(long, conflicts_with = "no_thesis_maps")]
    pub thesis_maps: Option<PathBuf>,
    /// Do not add the thesis's maps to the named experiments (the default; kept for scripts).
    #[arg(long)]
    pub no_thesis_maps: bool,
    /// Print one line per finished run even on a terminal.
    #[arg(long)]
    pub plain: bool,
}

/// Subcommands of `papillon-sim bench`.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// Combine the results of shard directories into one set of outputs.
    Merge(MergeArgs),
}

/// Arguments of `papillon-sim bench merge`.
#[derive(clap::Args, Debug, Clone)]
pub struct MergeArgs {
    /// Shard directories (each with sweep.json and runs.jsonl).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "bench-results/merged")]
    pub out: PathBuf,
}

/// The sweep the arguments ask for.
pub fn sweep_from_args(args: &Args) -> Result<Sweep, String> {
    let source = match (&args.experiment, &args.config) {
        (Some(name), None) => Source::Named {
            name: name.clone(),
            thesis_maps: match (&args.thesis_maps, args.no_thesis_maps) {
                (_, true) => ThesisMaps::Skip,
                (Some(dir), false) => ThesisMaps::In(dir.clone()),
                (None, false) => ThesisMaps::Skip,
            },
        },
        (None, Some(path)) => Source::File(path.clone()),
        _ => return Err("give --experiment NAME or --config FILE".into()),
    };
    let params = match &args.params {
        Some(p) => Some(crate::bench::tune::read_params(p).map_err(|e| format!("--params: {e}"))?),
        None => None,
    };
    let overrides = Overrides {
        params,
        runs: args.runs,
        maps: args.maps.clone(),
        battery_steps: args.battery,
        objective: args.objective.clone(),
        preset: args.preset.clone(),
    };
    select(&source, &overrides).map_err(|e| match e {
        SelectError::UnknownExperiment(_) => format!("--experiment: {e}"),
        SelectError::NoThesisMaps(_) => format!("--thesis-maps: {e}"),
        SelectError::Sweep(_) => e.to_string(),
    })
}

/// Most worker threads: far more than the cores of any machine this runs on, and few enough
/// that their stacks fit in memory.
pub const MAX_JOBS: usize = 1024;

fn fail(msg: &str) -> ExitCode {
    eprintln!("papillon-sim bench: {msg}");
    ExitCode::from(2)
}

/// Runs `papillon-sim bench`.
pub fn run(args: Args) -> ExitCode {
    if let Some(BenchCommand::Merge(m)) = &args.command {
        return merge(m);
    }
    if let Err(e) = super::check_jobs(args.jobs) {
        return fail(&e);
    }
    match args.experiment.as_deref() {
        Some(crate::bench::thesis::ALL) => {
            let names = crate::bench::thesis::EXPERIMENTS;
            return run_group(&args, crate::bench::thesis::ALL, &names);
        }
        Some(crate::bench::sweep::ALL) => {
            let names: Vec<&str> = crate::bench::sweep::EXPERIMENTS
                .into_iter()
                .chain(crate::bench::thesis::EXPERIMENTS)
                .collect();
            return run_group(&args, crate::bench::sweep::ALL, &names);
        }
        Some(list) if list.contains(',') => {
            let names: Vec<&str> = list.split(',').map(str::trim).collect();
            let group = |n: &str| n == crate::bench::sweep::ALL || n == crate::bench::thesis::ALL;
            let bad = names
                .iter()
                .enumerate()
                .find(|&(i, n)| n.is_empty() || group(n) || names[..i].contains(n));
            if let Some((_, bad)) = bad {
                return fail(&format!(
                    "--experiment: a list names single experiments, each once; got '{bad}' in \
                     '{list}'"
                ));
            }
            return run_group(&args, "pool", &names);
        }
        _ => {}
    }
    let sweep = match sweep_from_args(&args) {
        Ok(s) => s,
        Err(e) => return fail(&e),
    };
    let (shard, out) = match super::shard_and_out(
        args.shard.as_deref(),
        args.out.as_deref(),
        "bench-results",
        &sweep.name,
    ) {
        Ok(x) => x,
        Err(e) => return fail(&e),
    };
    run_one(&sweep, shard, args.jobs, &out, progress_mode(&args))
}

/// A terminal's progress bar, or one line per run with `--plain`.
fn progress_mode(args: &Args) -> ProgressMode {
    if args.plain {
        ProgressMode::Lines
    } else {
        ProgressMode::auto()
    }
}

/// Runs one experiment's `shard` into `out` and reports where its summary is (status 0), how
/// many runs failed (1) or why it could not run (2).
fn run_one(sweep: &Sweep, shard: Shard, jobs: usize, out: &Path, mode: ProgressMode) -> ExitCode {
    match run_sweep(sweep, shard, jobs, out, &crate::bench::sim::run, mode) {
        Ok(0) => {
            println!("{}", out.join("summary.md").display());
            ExitCode::SUCCESS
        }
        Ok(n) => {
            eprintln!(
                "papillon-sim bench: {n} runs failed (see the status column of {})",
                out.join("results.csv").display()
            );
            ExitCode::from(1)
        }
        Err(e) => fail(&e),
    }
}

/// `--experiment thesis-all`, `all` or a list `A,B,...`: the experiments `names`, each into
/// `OUT/NAME` (default OUT: `bench-results/GROUP`, GROUP `pool` for a list), then
/// `OUT/thesis.md` with the side-by-side tables of the thesis's among them. Their runs form
/// one pool ([`b::run_pooled`]); with `--shard` each experiment runs its own shard in turn
/// instead, to be merged experiment by experiment.
fn run_group(args: &Args, group: &str, names: &[&str]) -> ExitCode {
    let base = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("bench-results").join(group));
    // Every experiment's sweep first: a bad name or option stops the group before any run.
    let mut sweeps = Vec::with_capacity(names.len());
    for name in names {
        let one = Args {
            experiment: Some(name.to_string()),
            ..args.clone()
        };
        match sweep_from_args(&one) {
            Ok(s) => sweeps.push(s),
            Err(e) => return fail(&e),
        }
    }
    let start = std::time::Instant::now();
    let mut status = ExitCode::SUCCESS;
    let mode = progress_mode(args);
    if let Some(text) = args.shard.as_deref() {
        let shard = match Shard::parse(text) {
            Ok(s) => s,
            Err(e) => return fail(&e),
        };
        for sweep in &sweeps {
            let code = run_one(sweep, shard, args.jobs, &base.join(&sweep.name), mode);
            if code != ExitCode::SUCCESS {
                status = code;
            }
            if code == ExitCode::from(2) {
                return code;
            }
        }
    } else {
        match b::run_pooled(&sweeps, args.jobs, &base, &crate::bench::sim::run, mode) {
            Ok(p) => {
                eprintln!(
                    "papillon-sim bench: {group}: {} runs, {} of them distinct and run",
                    p.runs, p.distinct
                );
                if p.failed > 0 {
                    eprintln!(
                        "papillon-sim bench: {} runs failed (see the status column of each \
                         experiment's results.csv)",
                        p.failed
                    );
                    status = ExitCode::from(1);
                }
            }
            Err(e) => return fail(&e),
        }
    }
    let wall = start.elapsed().as_secs_f64();
    let mut index = format!("# The thesis reproduced side by side (`{group}`)\n");
    let mut thesis_tables = false;
    for name in names {
        if let Ok(md) = std::fs::read_to_string(base.join(name).join("thesis.md")) {
            index.push('\n');
            index += &md.replacen("# ", "## ", 1).replace("\n## ", "\n### ");
            thesis_tables = true;
        }
    }
    if thesis_tables {
        index += &format!("\nWall time of `{group}`: {wall:.0} s.\n");
        let path = base.join("thesis.md");
        if let Err(e) = std::fs::write(&path, index) {
            return fail(&format!("{}: cannot write: {e}", path.display()));
        }
    }
    eprintln!("papillon-sim bench: {group} took {wall:.0} s");
    // thesis-all's result is its side-by-side tables; all's, the directory of every table.
    if group == crate::bench::thesis::ALL {
        println!("{}", base.join("thesis.md").display());
    } else {
        println!("{}", base.display());
    }
    status
}

fn merge(m: &MergeArgs) -> ExitCode {
    let merged = match b::merge_into(&m.dirs, &m.out) {
        Ok(x) => x,
        Err(e) => return fail(&e),
    };
    if !merged.missing.is_empty() {
        eprintln!(
            "papillon-sim bench merge: {} of {} runs missing (first: index {})",
            merged.missing.len(),
            merged.sweep.len(),
            merged.missing[0]
        );
    }
    println!("{}", m.out.join("summary.md").display());
    if merged.missing.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
