//! `papillon-sim bench` end to end: a tiny sweep (2 methods x 2 runs on the `lab` world, small
//! battery) through the real mission runner; the CSV, the summaries and the plots must exist
//! and agree with each other; shards merge into the same results.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use papillon_sim::bench::exec::ProgressMode;
use papillon_sim::bench::sweep::{Shard, Sweep};
use papillon_sim::bench::{self, record, run_sweep, sim};

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

#[test]
fn bad_bench_arguments_exit_with_status_2_and_one_line() {
    let bin = env!("CARGO_BIN_EXE_papillon-sim");
    for args in [
        vec!["bench", "--experiment", "nope"],
        vec!["bench", "--experiment", "methods", "--shard", "3/3"],
        vec!["bench", "--config", "/nonexistent/sweep.json"],
        vec!["bench"],
    ] {
        let out = Command::new(bin).args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}
