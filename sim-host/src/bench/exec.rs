//! Running a sweep's runs in parallel (rayon), with a progress bar and ETA on a terminal
//! (indicatif) or one plain line per finished run otherwise, appending each record to
//! `runs.jsonl` as it finishes so an interrupted shard keeps its finished runs.

use std::fs::File;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

use super::record::{RunRecord, RunResult, append_jsonl};
use super::sweep::RunSpec;

/// What runs one run of a sweep: the real simulator ([`super::sim::run`]) or a test double.
pub type RunFn = dyn Fn(&RunSpec) -> Result<RunResult, String> + Sync;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressMode {
    /// A bar with an ETA (on a terminal).
    Bar,
    /// One line per finished run on standard error.
    Lines,
    /// Nothing.
    Quiet,
}

impl ProgressMode {
    /// A bar when standard error is a terminal, lines otherwise.
    pub fn auto() -> Self {
        if std::io::stderr().is_terminal() {
            ProgressMode::Bar
        } else {
            ProgressMode::Lines
        }
    }
}

fn short(spec: &RunSpec) -> String {
    format!(
        "{} {} {}-k{} pop{} {}r run{}",
        spec.map_label,
        spec.method,
        spec.strategy,
        spec.targets,
        spec.population,
        spec.robots,
        spec.run
    )
}

fn outcome(r: &Result<RunResult, String>) -> String {
    match r {
        Ok(m) => format!(
            "coverage {:.2} %, {:.1} steps, {} decisions, {:.1} s",
            100.0 * m.coverage,
            m.steps,
            m.decisions,
            m.wall_time_s
        ),
        Err(e) => format!("error: {e}"),
    }
}

fn eta(start: Instant, done: usize, total: usize) -> String {
    if done == 0 {
        return "?".into();
    }
    let per = start.elapsed().as_secs_f64() / done as f64;
    let left = Duration::from_secs_f64(per * (total - done) as f64);
    let s = left.as_secs();
    format!("{}h{:02}m{:02}s", s / 3600, (s / 60) % 60, s % 60)
}

/// Runs `specs` on `jobs` threads (0: one per core) with `run`, appending each record to
/// `jsonl` when given; returns the records in index order.
pub fn execute(
    specs: &[RunSpec],
    jobs: usize,
    run: &RunFn,
    jsonl: Option<File>,
    mode: ProgressMode,
) -> Result<Vec<RunRecord>, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| format!("--jobs: cannot start the worker threads: {e}"))?;
    let total = specs.len();
    let bar = match mode {
        ProgressMode::Bar => {
            let b = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:40} {pos}/{len} runs, ETA {eta_precise} {msg}",
            ) {
                b.set_style(style);
            }
            Some(b)
        }
        _ => None,
    };
    let start = Instant::now();
    let done = Mutex::new((0usize, jsonl, None::<String>));
    let mut records: Vec<RunRecord> = pool.install(|| {
        specs
            .par_iter()
            // One run per rayon job: runs last from a fraction of a second to tens of
            // seconds, and rayon's default splitting leaves a worker idle while the other
            // works through an unsplit block of runs (boa-variants, 2 workers: 1.6 of 2 cores
            // busy; with one run per job, 1.9). See docs/benchmarks.md.
            .with_max_len(1)
            .map(|spec| {
                let result = run(spec);
                let record = RunRecord {
                    spec: spec.clone(),
                    result,
                };
                let mut guard = done.lock().unwrap_or_else(|e| e.into_inner());
                let (count, file, write_error) = &mut *guard;
                *count += 1;
                if let Some(f) = file.as_mut()
                    && let Err(e) = append_jsonl(f, &record)
                {
                    write_error.get_or_insert(e);
                }
                match mode {
                    ProgressMode::Bar => {
                        if let Some(b) = &bar {
                            b.set_message(format!("{}: {}", short(spec), outcome(&record.result)));
                            b.inc(1);
                        }
                    }
                    ProgressMode::Lines => eprintln!(
                        "[{}/{}] {}: {} (ETA {})",
                        count,
                        total,
                        short(spec),
                        outcome(&record.result),
                        eta(start, *count, total)
                    ),
                    ProgressMode::Quiet => {}
                }
                record
            })
            .collect()
    });
    if let Some(b) = bar {
        b.finish_with_message(format!("done in {:.1} s", start.elapsed().as_secs_f64()));
    }
    if let Some(e) = done.into_inner().unwrap_or_else(|e| e.into_inner()).2 {
        return Err(e);
    }
    records.sort_by_key(|r| r.spec.index);
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::sweep::Sweep;

    #[test]
    fn every_run_is_executed_once_and_errors_are_kept() {
        let specs = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["xboa", "boa", "bad"], "runs": 3}"#,
            "t",
        )
        .unwrap()
        .specs();
        let double = |s: &RunSpec| {
            if s.method == "bad" {
                Err(format!("unknown method {}", s.method))
            } else {
                Ok(RunResult {
                    coverage: s.seed as f32 / 100.0,
                    ..RunResult::default()
                })
            }
        };
        let records = execute(&specs, 2, &double, None, ProgressMode::Quiet).unwrap();
        assert_eq!(records.len(), 9);
        for (i, r) in records.iter().enumerate() {
            assert_eq!(r.spec.index, i);
            match &r.result {
                Ok(m) => assert_eq!(m.coverage, r.spec.seed as f32 / 100.0),
                Err(e) => assert_eq!(e, "unknown method bad"),
            }
        }
        assert_eq!(records.iter().filter(|r| r.result.is_err()).count(), 3);
    }
}
