//! The thesis reproduced side by side, and tuned: a tiny `thesis-*` sweep writes `thesis.md`
//! with the thesis's numbers and ours filled in adjacent columns; a 3-trial `tune` writes its
//! outputs, and its best parameters feed a bench sweep.

use std::fs;
use std::path::PathBuf;

use papillon_sim::bench::exec::ProgressMode;
use papillon_sim::bench::sweep::{Shard, Sweep};
use papillon_sim::bench::tune::{self, Settings};
use papillon_sim::bench::{run_sweep, sim};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("papillon-thesis-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    d
}

/// The numeric cells of a markdown row.
fn cells(row: &str) -> Vec<String> {
    row.trim()
        .trim_matches('|')
        .split('|')
        .map(|c| c.trim().to_string())
        .collect()
}

#[test]
fn a_tiny_thesis_sweep_writes_the_side_by_side_table() {
    // Table 4.5's set-up on the project's house (the thesis's own map is not needed), one run,
    // two methods, a small battery to keep it short.
    let mut sweep = Sweep::named("thesis-boa-variants", 1, &[]).unwrap();
    assert_eq!(sweep.objective_list(), vec!["thesis", "efficient"]);
    sweep.methods = vec!["xboa".into(), "saboa".into()];
    sweep.battery_steps = Some(30.0);
    let out = scratch("sweep");
    let failed = run_sweep(&sweep, Shard::ALL, 2, &out, &sim::run, ProgressMode::Quiet).unwrap();
    assert_eq!(failed, 0);
    let md = fs::read_to_string(out.join("thesis.md")).unwrap();
    assert!(md.contains("Table 4.5"), "{md}");
    let header = md
        .lines()
        .find(|l| l.starts_with("| method |"))
        .expect("a table");
    let h = cells(header);
    assert_eq!(&h[1..3], ["thesis avg", "ours avg"]);
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    for (method, thesis_avg) in [("xboa", "93.35"), ("saboa", "85.13")] {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| {method} |")))
            .unwrap_or_else(|| panic!("no {method} row in {md}"));
        let c = cells(row);
        assert_eq!(c[col("thesis avg")], thesis_avg);
        // Ours (thesis objective) and Papillon's (efficient) are filled with rates of runs
        // cut short by the 30-step battery.
        for name in ["ours avg", "ours min", "ours max", "Papillon avg"] {
            let v: f64 = c[col(name)]
                .parse()
                .unwrap_or_else(|_| panic!("{method} {name}: '{}'", c[col(name)]));
            assert!(v > 1.0 && v < 99.5, "{method} {name} = {v}");
        }
        let ours: f64 = c[col("ours avg")].parse().unwrap();
        let delta: f64 = c[col("Δ")].parse().unwrap();
        let t: f64 = thesis_avg.parse().unwrap();
        assert!(
            (ours - t - delta).abs() < 0.011,
            "Δ {delta} for {ours} vs {t}"
        );
    }
    let _ = fs::remove_dir_all(&out);
}

#[test]
fn a_three_trial_tune_writes_its_outputs_and_feeds_a_sweep() {
    let settings = Settings {
        method: "xboa".into(),
        map: "lab".into(),
        population: 5,
        strategy: "short".into(),
        targets: 1,
        objective: "thesis".into(),
        generations: 10,
        battery_steps: Some(30.0),
        runs: 1,
        base_seed: 25,
        trials: 3,
        batch: 1,
        sampler_seed: 25,
        resolution_m: 0.1,
    };
    let out = scratch("tune");
    let mut seen = Vec::new();
    let o = tune::tune(&settings, Shard::ALL, 1, &out, &[], &mut |t| {
        seen.push(t.index)
    })
    .unwrap();
    assert_eq!(seen, vec![0, 1, 2]);
    assert_eq!((o.ran, o.waiting, o.trials.len()), (3, 0, 3));
    for f in [
        "tune.json",
        "trials.jsonl",
        "trials.csv",
        "trials.md",
        "best.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = fs::read_to_string(out.join("trials.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    assert!(csv.starts_with("trial,a,c,p_c,loss,"), "{csv}");
    let md = fs::read_to_string(out.join("trials.md")).unwrap();
    assert!(md.contains("| Table 4.1 | 0.994 | 0.518 | 0.583 |"), "{md}");
    assert_eq!(md.matches("(best)").count(), 1, "{md}");
    // best.json holds the best trial's parameters, in range, and a sweep takes them.
    let best = tune::best(&o.trials).unwrap();
    let params = tune::read_params(&out.join("best.json")).unwrap();
    assert_eq!(params["xboa"], best.params);
    let mut sweep = settings.sweep(&Default::default());
    sweep.params = params;
    sweep.check().unwrap();
    assert_eq!(sweep.specs()[0].params.as_ref(), Some(&best.params));
    // Running again finds every trial done and runs none.
    let again = tune::tune(&settings, Shard::ALL, 1, &out, &[], &mut |_| panic!("ran")).unwrap();
    assert_eq!((again.ran, again.trials.len()), (0, 3));
    // A shard's directory with other settings is refused.
    let other = Settings {
        runs: 2,
        ..settings.clone()
    };
    let e = tune::tune(&other, Shard::ALL, 1, &out, &[], &mut |_| {}).unwrap_err();
    assert!(e.contains("differs"), "{e}");
    let _ = fs::remove_dir_all(&out);
}
