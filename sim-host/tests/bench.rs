//! `papillon-sim bench` end to end: a tiny sweep (2 methods x 2 runs on the `lab` world, small
//! battery) through the real mission runner; the CSV, the summaries and the plots must exist
//! and agree with each other; shards merge into the same results.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use papillon_sim::bench::exec::ProgressMode;
use papillon_sim::bench::sweep::{Shard, Sweep};
use papillon_sim::bench::{self, record, run_sweep, sim, sweep};

fn tiny() -> Sweep {
    Sweep::from_json(
        r#"{"name": "tiny", "maps": ["lab"], "methods": ["xboa", "nearest-frontier"],
            "runs": 2, "battery_steps": 40}"#,
        "tiny.json",
    )
    .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("papillon-bench-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    d
}

/// The CSV's rows as maps from column name to text.
fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.join(","), record::CSV_HEADER);
    lines
        .map(|l| {
            let cols: Vec<&str> = l.split(',').collect();
            assert_eq!(cols.len(), header.len(), "row {l}");
            header
                .iter()
                .zip(cols)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

#[test]
fn a_tiny_sweep_writes_consistent_csv_summaries_and_plots() {
    let sweep = tiny();
    let out = scratch("tiny");
    let failed = run_sweep(&sweep, Shard::ALL, 2, &out, &sim::run, ProgressMode::Quiet).unwrap();
    assert_eq!(failed, 0);

    // One CSV row per run, every run finished, both methods of a run index on the same seed.
    let rows = csv_rows(&out.join("results.csv"));
    assert_eq!(rows.len(), 4);
    for r in &rows {
        assert_eq!(r["status"], "ok");
        assert_eq!(r["map"], "lab");
        let run: u64 = r["run"].parse().unwrap();
        assert_eq!(r["seed"], (25 + run).to_string());
        let c: f64 = r["coverage"].parse().unwrap();
        assert!(c > 0.3 && c <= 1.0, "coverage {c}");
        let steps: f64 = r["steps"].parse().unwrap();
        assert!(
            steps > 0.0 && steps <= 40.0 + 2.0,
            "steps {steps} with a battery of 40"
        );
    }

    // The CSV agrees with runs.jsonl.
    let records = record::read_jsonl(&out.join(bench::RUNS_FILE)).unwrap();
    assert_eq!(records.len(), 4);
    for (row, rec) in rows.iter().zip(&records) {
        let m = rec.result.as_ref().unwrap();
        assert_eq!(row["method"], rec.spec.method);
        assert_eq!(row["coverage"], format!("{:.5}", m.coverage));
        assert_eq!(row["decisions"], m.decisions.to_string());
        assert_eq!(row["fitness_evals"], m.fitness_evals.to_string());
        // The optimizer's first decision has a convergence curve (initial best + 30
        // generations, never worse), the frontier rule none.
        if rec.spec.method == "xboa" {
            assert_eq!(m.convergence.len(), 31);
            assert!(m.convergence.windows(2).all(|w| w[1] <= w[0]));
        } else {
            assert!(m.convergence.is_empty());
        }
    }

    // summary.json: one group per method whose statistics are those of its CSV rows.
    let summary: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["experiment"], "tiny");
    assert_eq!(summary["runs"], 4);
    let groups = summary["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 2);
    let md = fs::read_to_string(out.join("summary.md")).unwrap();
    for g in groups {
        let method = g["method"].as_str().unwrap();
        let cov: Vec<f64> = rows
            .iter()
            .filter(|r| r["method"] == method)
            .map(|r| r["coverage"].parse().unwrap())
            .collect();
        assert_eq!(g["runs"], 2);
        let avg = cov.iter().sum::<f64>() / 2.0;
        let min = cov.iter().copied().fold(f64::INFINITY, f64::min);
        let max = cov.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        for (key, want) in [("avg", avg), ("min", min), ("max", max)] {
            let got = g["coverage"][key].as_f64().unwrap();
            assert!(
                (got - want).abs() < 1e-4,
                "{method} coverage {key}: {got} vs {want}"
            );
        }
        let evals: Vec<f64> = rows
            .iter()
            .filter(|r| r["method"] == method)
            .map(|r| r["fitness_evals"].parse().unwrap())
            .collect();
        let e = g["fitness_evals"]["avg"].as_f64().unwrap();
        assert!((e - evals.iter().sum::<f64>() / 2.0).abs() < 1e-6);
        // summary.md has the same numbers.
        let row = format!(
            "| {method} | short (1) | 5 | 1 | 2 | {:.2} | {:.2} | {:.2} |",
            100.0 * g["coverage"]["avg"].as_f64().unwrap(),
            100.0 * g["coverage"]["min"].as_f64().unwrap(),
            100.0 * g["coverage"]["max"].as_f64().unwrap()
        );
        assert!(md.contains(&row), "summary.md lacks {row}:\n{md}");
    }

    // The plots: PNG pictures that decode, SVGs naming both methods.
    for plot in ["coverage-lab", "pareto-lab", "convergence-lab"] {
        let png = image::open(out.join(format!("{plot}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (960, 640));
        let svg = fs::read_to_string(out.join(format!("{plot}.svg"))).unwrap();
        assert!(svg.starts_with("<svg"), "{plot}.svg");
        assert!(svg.contains("xboa"), "{plot}.svg names xboa");
        if plot != "convergence-lab" {
            assert!(svg.contains("nearest-frontier"), "{plot}.svg");
        }
    }

    // Two shards merged give the same runs (wall-clock times aside).
    let mut dirs = Vec::new();
    for i in 0..2 {
        let d = out.join(format!("shard-{i}"));
        run_sweep(
            &sweep,
            Shard { index: i, count: 2 },
            1,
            &d,
            &sim::run,
            ProgressMode::Quiet,
        )
        .unwrap();
        dirs.push(d);
    }
    let merged = bench::merge(&dirs).unwrap();
    assert!(merged.missing.is_empty());
    assert_eq!(merged.records.len(), 4);
    for (a, b) in merged.records.iter().zip(&records) {
        let (ma, mb) = (a.result.as_ref().unwrap(), b.result.as_ref().unwrap());
        assert_eq!(a.spec, b.spec);
        assert_eq!(ma.coverage, mb.coverage);
        assert_eq!(ma.steps, mb.steps);
        assert_eq!(ma.coverage_curve, mb.coverage_curve);
        assert_eq!(ma.convergence, mb.convergence);
    }
    let _ = fs::remove_dir_all(&out);
}

/// Two sweeps that share runs, run as one pool: each shared run runs once, and each sweep's
/// directory holds what running it alone writes (its own spec and index on every record).
#[test]
fn pooled_sweeps_run_a_shared_run_once_and_write_what_each_alone_writes() {
    let first = tiny();
    let second = Sweep::from_json(
        r#"{"name": "tiny2", "maps": ["lab"], "methods": ["boa", "xboa"],
            "runs": 2, "battery_steps": 40}"#,
        "tiny2.json",
    )
    .unwrap();
    let out = scratch("pool");
    // A run function is `'static`: the count lives in a static of this test's own.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let counted = |spec: &sweep::RunSpec| {
        CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        sim::run(spec)
    };
    let sweeps = [first, second];
    let pooled = bench::run_pooled(&sweeps, 2, &out, &counted, ProgressMode::Quiet).unwrap();
    // xBOA's two runs are in both sweeps: 8 runs asked for, 6 distinct, each run once.
    assert_eq!(
        pooled,
        bench::Pooled {
            runs: 8,
            distinct: 6,
            failed: 0
        }
    );
    assert_eq!(CALLS.load(std::sync::atomic::Ordering::Relaxed), 6);
    assert_eq!(
        record::read_jsonl(&out.join(bench::POOL_FILE))
            .unwrap()
            .len(),
        6
    );
    for sweep in &sweeps {
        let alone = out.join(format!("alone-{}", sweep.name));
        run_sweep(sweep, Shard::ALL, 1, &alone, &sim::run, ProgressMode::Quiet).unwrap();
        let dir = out.join(&sweep.name);
        assert_eq!(bench::read_sweep_file(&dir).unwrap().sweep, *sweep);
        let pooled = record::read_jsonl(&dir.join(bench::RUNS_FILE)).unwrap();
        let alone = record::read_jsonl(&alone.join(bench::RUNS_FILE)).unwrap();
        assert_eq!(pooled.len(), sweep.len());
        for (p, a) in pooled.iter().zip(&alone) {
            assert_eq!(p.spec, a.spec);
            let (mp, ma) = (p.result.as_ref().unwrap(), a.result.as_ref().unwrap());
            assert_eq!(mp.coverage, ma.coverage);
            assert_eq!(mp.steps, ma.steps);
            assert_eq!(mp.coverage_curve, ma.coverage_curve);
            assert_eq!(mp.convergence, ma.convergence);
        }
        assert!(dir.join("summary.md").exists() && dir.join("results.csv").exists());
    }
    let _ = fs::remove_dir_all(&out);
}

#[test]
fn bad_bench_arguments_exit_with_status_2_and_one_line() {
    let bin = env!("CARGO_BIN_EXE_papillon-sim");
    for args in [
        vec!["bench", "--experiment", "nope"],
        vec!["bench", "--experiment", "methods", "--shard", "3/3"],
        vec!["bench", "--experiment", "methods,nope"],
        vec!["bench", "--experiment", "methods,,horizon"],
        vec!["bench", "--experiment", "methods,methods"],
        vec!["bench", "--experiment", "all,methods"],
        vec!["bench", "--config", "/nonexistent/sweep.json"],
        vec!["bench"],
    ] {
        let out = Command::new(bin).args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}

/// The `scale` experiment, shrunk: two small generated storeys (240² and 320² cells), one and
/// two robots, 3 simulated seconds each; every run is cut by the time limit and the cost table
/// has a row per run with its cells, CPU time and rates.
#[test]
fn a_tiny_scale_experiment_writes_its_cost_table() {
    let mut sweep = bench::select::named("scale", &bench::select::ThesisMaps::Find, 1).unwrap();
    // The named experiment: four storeys from 24 to 192 m, 1 to 100 robots, cut in time.
    assert_eq!(sweep.maps.len(), 4);
    assert_eq!(sweep.robots, vec![1, 10, 50, 100]);
    assert!(sweep.max_time_s.is_some());
    sweep.maps = vec!["gen-floor-24m-1".into(), "gen-floor-32m-2".into()];
    sweep.robots = vec![1, 2];
    sweep.max_time_s = Some(3.0);
    sweep.check_runnable().unwrap();
    let out = scratch("scale");
    let failed = run_sweep(&sweep, Shard::ALL, 1, &out, &sim::run, ProgressMode::Quiet).unwrap();
    assert_eq!(failed, 0);
    let records = record::read_jsonl(&out.join(bench::RUNS_FILE)).unwrap();
    assert_eq!(records.len(), 4);
    for r in &records {
        let m = r.result.as_ref().unwrap();
        let side = if r.spec.map_label == "gen-floor-24m-1" {
            240
        } else {
            320
        };
        assert_eq!(m.cells, Some(side * side), "{}", r.spec.map_label);
        assert_eq!(m.reason, "time-limit", "{}", r.spec.map_label);
        assert!((m.sim_time_s - 3.0).abs() < 0.5, "{}", m.sim_time_s);
        assert!(m.cpu_time_s.is_some_and(|c| c > 0.0), "{:?}", m.cpu_time_s);
        assert!(m.decisions >= r.spec.robots as u32, "{}", m.decisions);
    }
    let cost = fs::read_to_string(out.join("cost.md")).unwrap();
    let rows: Vec<&str> = cost
        .lines()
        .filter(|l| l.starts_with("| gen-floor"))
        .collect();
    assert_eq!(rows.len(), 4, "{cost}");
    assert!(
        rows[0].starts_with("| gen-floor-24m-1 | 57600 | 1 |"),
        "{}",
        rows[0]
    );
    assert!(
        rows[3].starts_with("| gen-floor-32m-2 | 102400 | 2 |"),
        "{}",
        rows[3]
    );
    let _ = fs::remove_dir_all(&out);
}
