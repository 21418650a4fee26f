//! Experiments: sweeps of exploration missions, run in parallel, summarised and plotted
//! (`papillon-sim bench`), after the thesis's benchmarking platform (parameters, repetitions,
//! statistics, graphs).
//!
//! - [`sweep`]: what runs an experiment is made of, seeds, shards;
//! - [`select`]: which sweep (a named experiment or a file) and the caller's overrides;
//! - [`exec`]: running them in parallel with progress;
//! - [`sim`]: one run in the simulator ([`crate::runner`]);
//! - [`record`]: per-run records (`runs.jsonl`, `results.csv`);
//! - [`summary`]: per-group statistics (`summary.json`, `summary.md`);
//! - [`plot`]: the plots;
//! - [`cost`]: what a run costs the machine (CPU, peak memory) and the `scale` experiment's
//!   cost table (`cost.md`).
//!
//! Every output is rebuilt from `runs.jsonl` ([`write_outputs`]), so the shards of a sweep
//! run anywhere and [`merge`] combines their directories.

pub mod cost;
pub mod exec;
pub mod params;
pub mod plot;
pub mod record;
pub mod select;
pub mod sim;
pub mod summary;
pub mod sweep;
pub mod thesis;
pub mod tune;

use std::collections::{BTreeMap, HashMap};
use std::fs::{self, OpenOptions};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use exec::{ProgressMode, RunFn, execute};
use record::RunRecord;
use sweep::{RunSpec, Shard, Sweep};

/// `sweep.json`: the sweep a directory's runs come from, and which shard.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepFile {
    /// The sweep.
    pub sweep: Sweep,
    /// Shard index (0-based).
    pub shard_index: usize,
    /// Number of shards.
    pub shard_count: usize,
}

/// Name of the per-run records file.
pub const RUNS_FILE: &str = "runs.jsonl";
/// Name of the sweep file.
pub const SWEEP_FILE: &str = "sweep.json";
/// Name of the log of a pool of sweeps ([`run_pooled`]), in its output directory: one record
/// per run actually run, appended as it finishes, numbered by its place in the pool.
pub const POOL_FILE: &str = "pool.jsonl";

/// Creates `dir` and writes its `sweep.json`.
pub fn write_sweep_file(dir: &Path, sweep: &Sweep, shard: Shard) -> Result<(), String> {
    fs::create_dir_all(dir).map_err(|e| format!("--out {}: cannot create: {e}", dir.display()))?;
    let f = SweepFile {
        sweep: sweep.clone(),
        shard_index: shard.index,
        shard_count: shard.count,
    };
    let path = dir.join(SWEEP_FILE);
    let text = serde_json::to_string_pretty(&f).map_err(|e| e.to_string())?;
    fs::write(&path, text + "\n").map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// Creates (or empties) a file of run records.
fn create_records_file(path: &Path) -> Result<fs::File, String> {
    OpenOptions::new()
        .create(true)
        .write(true)
        .truncate(true)
        .open(path)
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The worker threads `--jobs` asks for (0: one per core).
fn worker_count(jobs: usize) -> usize {
    if jobs == 0 {
        rayon::current_num_threads()
    } else {
        jobs
    }
}

/// Runs the sweep's shard with `run` into `out`; returns the number of failed runs.
pub fn run_sweep(
    sweep: &Sweep,
    shard: Shard,
    jobs: usize,
    out: &Path,
    run: &RunFn,
    mode: ProgressMode,
) -> Result<usize, String> {
    write_sweep_file(out, sweep, shard)?;
    let specs: Vec<_> = sweep
        .specs()
        .into_iter()
        .filter(|s| shard.contains(s.index))
        .collect();
    let file = create_records_file(&out.join(RUNS_FILE))?;
    if mode != ProgressMode::Quiet {
        eprintln!(
            "bench {}: {} runs (shard {shard} of a sweep of {}), {} worker threads, into {}",
            sweep.name,
            specs.len(),
            sweep.len(),
            worker_count(jobs),
            out.display()
        );
    }
    let records = execute(&specs, jobs, run, Some(file), mode)?;
    write_outputs(out, &sweep.name, &records)?;
    Ok(records.iter().filter(|r| r.result.is_err()).count())
}

/// What [`run_pooled`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pooled {
    /// Runs the sweeps ask for, all together.
    pub runs: usize,
    /// Runs actually run: those asked for by no earlier sweep (or earlier in the same one).
    pub distinct: usize,
    /// Failed runs, counted in every sweep that asks for them.
    pub failed: usize,
}

/// What makes two runs the same run: everything in the spec but its place in its sweep
/// (a run is a pure function of it: every random choice comes from its seed).
fn same_run_key(spec: &RunSpec) -> Result<String, String> {
    serde_json::to_string(&RunSpec {
        index: 0,
        ..spec.clone()
    })
    .map_err(|e| format!("run {}: {e}", spec.index))
}

/// Runs whole `sweeps` as one pool of runs, each sweep's outputs written into `out/NAME` as
/// [`run_sweep`] writes them. A run that several sweeps ask for (the same world, method,
/// objective, preset, strategy, population, robots, seed, battery, ...: the named
/// experiments share many) runs once and its record serves each of them, and the runs of
/// every sweep share the worker threads, so no sweep waits on another's last run. The pool's
/// records are appended to `out/`[`POOL_FILE`] as they finish.
pub fn run_pooled(
    sweeps: &[Sweep],
    jobs: usize,
    out: &Path,
    run: &RunFn,
    mode: ProgressMode,
) -> Result<Pooled, String> {
    let mut pool: Vec<RunSpec> = Vec::new();
    let mut slot_of: HashMap<String, usize> = HashMap::new();
    let mut asked: Vec<Vec<(RunSpec, usize)>> = Vec::with_capacity(sweeps.len());
    for sweep in sweeps {
        let mut runs = Vec::with_capacity(sweep.len());
        for spec in sweep.specs() {
            let slot = *slot_of.entry(same_run_key(&spec)?).or_insert_with(|| {
                // Numbered by its place in the pool, which `execute` sorts by.
                pool.push(RunSpec {
                    index: pool.len(),
                    ..spec.clone()
                });
                pool.len() - 1
            });
            runs.push((spec, slot));
        }
        asked.push(runs);
    }
    for sweep in sweeps {
        write_sweep_file(&out.join(&sweep.name), sweep, Shard::ALL)?;
    }
    let file = create_records_file(&out.join(POOL_FILE))?;
    let runs = asked.iter().map(Vec::len).sum();
    if mode != ProgressMode::Quiet {
        eprintln!(
            "bench: {} experiments, {runs} runs of which {} distinct, {} worker threads, into {}",
            sweeps.len(),
            pool.len(),
            worker_count(jobs),
            out.display()
        );
    }
    let done = execute(&pool, jobs, run, Some(file), mode)?;
    let mut failed = 0;
    for (sweep, runs) in sweeps.iter().zip(asked) {
        let records: Vec<RunRecord> = runs
            .into_iter()
            .map(|(spec, slot)| RunRecord {
                spec,
                result: done[slot].result.clone(),
            })
            .collect();
        failed += records.iter().filter(|r| r.result.is_err()).count();
        write_outputs(&out.join(&sweep.name), &sweep.name, &records)?;
    }
    Ok(Pooled {
        runs,
        distinct: pool.len(),
        failed,
    })
}

/// Reads a directory's `sweep.json`.
pub fn read_sweep_file(dir: &Path) -> Result<SweepFile, String> {
    let path = dir.join(SWEEP_FILE);
    let text = papillon::files::read_limited_to_string(&path, papillon::files::TEXT_MAX_BYTES)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: not a sweep file: {e}", path.display()))
}

/// Writes `runs.jsonl` (sorted), `results.csv`, `summary.json`, `summary.md` and the plots
/// of `records` into `dir`; returns the files written.
pub fn write_outputs(
    dir: &Path,
    name: &str,
    records: &[RunRecord],
) -> Result<Vec<PathBuf>, String> {
    fs::create_dir_all(dir).map_err(|e| format!("--out {}: cannot create: {e}", dir.display()))?;
    let write = |file: &str, text: String| -> Result<PathBuf, String> {
        let p = dir.join(file);
        fs::write(&p, text).map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
        Ok(p)
    };
    let mut files = Vec::new();
    let runs = dir.join(RUNS_FILE);
    record::write_jsonl(&runs, records)?;
    files.push(runs);
    files.push(write("results.csv", record::csv(records))?);
    let groups = summary::summarize(records);
    let json = serde_json::to_string_pretty(&summary::json(name, records.len(), &groups))
        .map_err(|e| e.to_string())?;
    files.push(write("summary.json", json + "\n")?);
    files.push(write("summary.md", summary::markdown(name, &groups))?);
    if let Some(md) = thesis::markdown(name, records) {
        files.push(write("thesis.md", md)?);
    }
    if name == "scale" {
        files.push(write("cost.md", cost::markdown(name, records))?);
    }
    files.extend(plot::write_plots(dir, records)?);
    Ok(files)
}

/// What [`merge`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct Merged {
    /// The sweep.
    pub sweep: Sweep,
    /// Every record found, in index order (one per index).
    pub records: Vec<RunRecord>,
    /// Indices of the sweep with no record in any directory.
    pub missing: Vec<usize>,
}

/// Reads the shards in `dirs` (each with `sweep.json` and `runs.jsonl`): they must come from
/// the same sweep; a run found twice must agree on its spec (the later copy is kept).
pub fn merge(dirs: &[PathBuf]) -> Result<Merged, String> {
    let mut sweep: Option<(Sweep, &Path)> = None;
    let mut by_index: BTreeMap<usize, RunRecord> = BTreeMap::new();
    for dir in dirs {
        let f = read_sweep_file(dir)?;
        match &sweep {
            None => sweep = Some((f.sweep.clone(), dir)),
            Some((s, first)) if *s != f.sweep => {
                return Err(format!(
                    "{} and {} come from different sweeps",
                    first.display(),
                    dir.display()
                ));
            }
            Some(_) => {}
        }
        let specs = f.sweep.specs();
        for r in record::read_jsonl(&dir.join(RUNS_FILE))? {
            if specs.get(r.spec.index) != Some(&r.spec) {
                return Err(format!(
                    "{}: run {} does not belong to the sweep in {SWEEP_FILE}",
                    dir.join(RUNS_FILE).display(),
                    r.spec.index
                ));
            }
            by_index.insert(r.spec.index, r);
        }
    }
    let (sweep, _) = sweep.ok_or_else(|| "merge: no directories given".to_string())?;
    let missing = (0..sweep.len())
        .filter(|i| !by_index.contains_key(i))
        .collect();
    Ok(Merged {
        sweep,
        records: by_index.into_values().collect(),
        missing,
    })
}

/// [`merge`]s the shards in `dirs` and writes the whole sweep's outputs (`sweep.json` and
/// everything [`write_outputs`] writes) into `out`, even when runs are missing.
pub fn merge_into(dirs: &[PathBuf], out: &Path) -> Result<Merged, String> {
    let merged = merge(dirs)?;
    write_sweep_file(out, &merged.sweep, Shard::ALL)?;
    write_outputs(out, &merged.sweep.name, &merged.records)?;
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::exec::{ProgressMode, execute};
    use crate::bench::record::RunResult;
    use crate::bench::sweep::RunSpec;

    fn double(s: &RunSpec) -> Result<RunResult, String> {
        let c = 0.8 + 0.02 * s.run as f32 + if s.method == "xboa" { 0.1 } else { 0.0 };
        Ok(RunResult {
            coverage: c,
            steps: 30.0,
            steps_per_robot: vec![30.0],
            decisions: 2,
            fitness_evals: 100,
            decision_ms: vec![1.0, 2.0 + s.run as f64],
            reason: "battery-exhausted".into(),
            coverage_curve: vec![(0.0, 0.1), (15.0, 0.5), (30.0, c)],
            convergence: if s.method == "xboa" {
                vec![-10.0, -12.0, -15.0]
            } else {
                vec![-10.0, -11.0]
            },
            ..RunResult::default()
        })
    }

    #[test]
    fn shards_merge_into_the_whole_sweep() {
        let sweep = Sweep::from_json(
            r#"{"name": "t", "maps": ["lab"], "methods": ["xboa", "boa"], "runs": 3}"#,
            "t",
        )
        .unwrap();
        let base = std::env::temp_dir().join(format!("papillon-merge-{}", std::process::id()));
        let _ = fs::remove_dir_all(&base);
        let mut dirs = Vec::new();
        for i in 0..2 {
            let shard = Shard { index: i, count: 2 };
            let dir = base.join(format!("shard-{i}"));
            write_sweep_file(&dir, &sweep, shard).unwrap();
            let specs: Vec<RunSpec> = sweep
                .specs()
                .into_iter()
                .filter(|s| shard.contains(s.index))
                .collect();
            let records = execute(&specs, 1, &double, None, ProgressMode::Quiet).unwrap();
            write_outputs(&dir, "t", &records).unwrap();
            dirs.push(dir);
        }
        let merged = merge(&dirs).unwrap();
        assert!(merged.missing.is_empty());
        assert_eq!(merged.records.len(), 6);
        let whole = execute(&sweep.specs(), 1, &double, None, ProgressMode::Quiet).unwrap();
        assert_eq!(merged.records, whole);
        // A shard alone misses the other's runs.
        let half = merge(&dirs[..1]).unwrap();
        let other_half: Vec<usize> = (0..6)
            .filter(|&i| !Shard { index: 0, count: 2 }.contains(i))
            .collect();
        assert!(!other_half.is_empty());
        assert_eq!(half.missing, other_half);
        // Shards of another sweep are refused.
        let other = Sweep {
            runs: 4,
            ..sweep.clone()
        };
        let odir = base.join("other");
        write_sweep_file(&odir, &other, Shard::ALL).unwrap();
        write_outputs(&odir, "t", &[]).unwrap();
        let e = merge(&[dirs[0].clone(), odir]).unwrap_err();
        assert!(e.contains("different sweeps"), "{e}");
        let _ = fs::remove_dir_all(&base);
    }
}
