//! Statistics per group of runs (same map, method, strategy, population and robot count):
//! `summary.json` and `summary.md`.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::record::{RunRecord, quantile};

/// What identifies a group of runs: everything but the run index.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct GroupKey {
    /// What the optimizers maximised (`thesis` or `efficient`).
    #[serde(default)]
    pub objective: String,
    /// The optimizers' parameter set (`thesis` or `standard`; summaries written before the
    /// preset was an option read as `thesis`).
    #[serde(default = "thesis_preset")]
    pub preset: String,
    /// Map label.
    pub map: String,
    /// Target selector.
    pub method: String,
    /// `short` or `long`.
    pub strategy: String,
    /// Targets per decision.
    pub targets: usize,
    /// Population size.
    pub population: usize,
    /// Robots.
    pub robots: usize,
}

fn thesis_preset() -> String {
    papillon::optim::Preset::Thesis.name().into()
}

impl GroupKey {
    /// The group of run `r`.
    pub fn of(r: &RunRecord) -> Self {
        let s = &r.spec;
        Self {
            objective: s.objective.clone(),
            preset: s.preset.clone(),
            map: s.map_label.clone(),
            method: s.method.clone(),
            strategy: s.strategy.clone(),
            targets: s.targets,
            population: s.population,
            robots: s.robots,
        }
    }
}

/// Average, smallest and largest of some values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    /// Mean.
    pub avg: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Stat {
    /// Of `values`; `None` when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let avg = values.iter().sum::<f64>() / values.len() as f64;
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some(Self { avg, min, max })
    }
}

/// The statistics of one group.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupSummary {
    /// Which runs.
    #[serde(flatten)]
    pub key: GroupKey,
    /// Runs that finished.
    pub runs: usize,
    /// Runs that failed with an error.
    pub errors: usize,
    /// Final coverage (0..1).
    pub coverage: Option<Stat>,
    /// Steps (summed over robots) to reach 90 % coverage, over the runs that reached it.
    pub steps_to_90: Option<Stat>,
    /// Runs that reached 90 %.
    pub reached_90: usize,
    /// Steps to reach 99 %, over the runs that reached it.
    pub steps_to_99: Option<Stat>,
    /// Runs that reached 99 %.
    pub reached_99: usize,
    /// Steps (summed over robots) at the end.
    pub steps: Option<Stat>,
    /// Metres (summed over robots).
    pub distance_m: Option<Stat>,
    /// Fitness evaluations per run.
    pub fitness_evals: Option<Stat>,
    /// Decisions per run.
    pub decisions: Option<Stat>,
    /// Median of all the group's decision times \[ms\].
    pub decision_ms_p50: Option<f64>,
    /// 99th percentile of all the group's decision times \[ms\].
    pub decision_ms_p99: Option<f64>,
    /// Mean decision time \[ms\].
    pub decision_ms_mean: Option<f64>,
    /// Wall-clock time per run \[s\].
    pub wall_time_s: Option<Stat>,
}

/// Groups the records (in key order) and computes each group's statistics.
pub fn summarize(records: &[RunRecord]) -> Vec<GroupSummary> {
    let mut groups: BTreeMap<GroupKey, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        groups.entry(GroupKey::of(r)).or_default().push(r);
    }
    groups
        .into_iter()
        .map(|(key, rs)| {
            let ok: Vec<_> = rs.iter().filter_map(|r| r.result.as_ref().ok()).collect();
            let col = |f: &dyn Fn(&super::record::RunResult) -> f64| {
                Stat::of(&ok.iter().map(|m| f(m)).collect::<Vec<_>>())
            };
            let to90: Vec<f64> = ok
                .iter()
                .filter_map(|m| m.steps_to(0.90))
                .map(f64::from)
                .collect();
            let to99: Vec<f64> = ok
                .iter()
                .filter_map(|m| m.steps_to(0.99))
                .map(f64::from)
                .collect();
            let mut times: Vec<f64> = ok
                .iter()
                .flat_map(|m| m.decision_ms.iter().copied())
                .collect();
            times.sort_by(f64::total_cmp);
            let mean = if times.is_empty() {
                None
            } else {
                Some(times.iter().sum::<f64>() / times.len() as f64)
            };
            GroupSummary {
                key,
                runs: ok.len(),
                errors: rs.len() - ok.len(),
                coverage: col(&|m| m.coverage as f64),
                steps_to_90: Stat::of(&to90),
                reached_90: to90.len(),
                steps_to_99: Stat::of(&to99),
                reached_99: to99.len(),
                steps: col(&|m| m.steps as f64),
                distance_m: col(&|m| m.distance_m),
                fitness_evals: col(&|m| m.fitness_evals as f64),
                decisions: col(&|m| m.decisions as f64),
                decision_ms_p50: quantile(&times, 0.5),
                decision_ms_p99: quantile(&times, 0.99),
                decision_ms_mean: mean,
                wall_time_s: col(&|m| m.wall_time_s),
            }
        })
        .collect()
}

/// `summary.json`: the sweep's name and the groups.
pub fn json(name: &str, total_runs: usize, groups: &[GroupSummary]) -> serde_json::Value {
    serde_json::json!({
        "experiment": name,
        "runs": total_runs,
        "groups": groups,
    })
}

fn pct(s: &Option<Stat>) -> String {
    match s {
        Some(s) => format!(
            "{:.2} | {:.2} | {:.2}",
            100.0 * s.avg,
            100.0 * s.min,
            100.0 * s.max
        ),
        None => "– | – | –".into(),
    }
}

fn reach(s: &Option<Stat>, reached: usize, runs: usize) -> String {
    match s {
        Some(s) if reached == runs => format!("{:.1}", s.avg),
        Some(s) => format!("{:.1} ({reached}/{runs})", s.avg),
        None => format!("– (0/{runs})"),
    }
}

fn avg(s: &Option<Stat>, digits: usize) -> String {
    s.map_or("–".into(), |s| format!("{:.*}", digits, s.avg))
}

fn ms(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.2}"))
}

/// `summary.md`: one table per map, one row per group.
pub fn markdown(name: &str, groups: &[GroupSummary]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Experiment `{name}`\n");
    let _ = writeln!(
        out,
        "Coverage is the final exploration rate [%]; steps are summed over robots (1 m of travel or 45° of rotation); \"to 90 %\" and \"to 99 %\" average the runs that reached the level (how many in brackets when not all); decision times are the median and 99th percentile over every decision of the group's runs.\n"
    );
    let mut maps: Vec<&str> = groups.iter().map(|g| g.key.map.as_str()).collect();
    maps.sort();
    maps.dedup();
    let objectives_vary = groups
        .iter()
        .any(|g| g.key.objective != groups[0].key.objective);
    let presets_vary = groups.iter().any(|g| g.key.preset != groups[0].key.preset);
    for map in maps {
        let _ = writeln!(out, "## {map}\n");
        let _ = writeln!(
            out,
            "| method | strategy (k) | pop | robots | runs | coverage avg | min | max | steps to 90 % | steps to 99 % | steps | metres | fitness evals | decision ms p50 | p99 |"
        );
        let _ = writeln!(
            out,
            "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
        );
        for g in groups.iter().filter(|g| g.key.map == map) {
            let k = &g.key;
            let runs = if g.errors > 0 {
                format!("{} ({} failed)", g.runs, g.errors)
            } else {
                g.runs.to_string()
            };
            let _ = writeln!(
                out,
                "| {} | {} ({}) | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                match (objectives_vary, presets_vary) {
                    (false, false) => k.method.clone(),
                    (true, false) => format!("{} ({})", k.method, k.objective),
                    (false, true) => format!("{} ({} preset)", k.method, k.preset),
                    (true, true) => format!("{} ({}, {} preset)", k.method, k.objective, k.preset),
                },
                k.strategy,
                k.targets,
                k.population,
                k.robots,
                runs,
                pct(&g.coverage),
                reach(&g.steps_to_90, g.reached_90, g.runs),
                reach(&g.steps_to_99, g.reached_99, g.runs),
                avg(&g.steps, 1),
                avg(&g.distance_m, 1),
                avg(&g.fitness_evals, 0),
                ms(g.decision_ms_p50),
                ms(g.decision_ms_p99),
            );
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::record::RunResult;
    use crate::bench::sweep::Sweep;

    #[test]
    fn groups_pool_their_runs() {
        let specs = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["xboa", "boa"], "runs": 2}"#,
            "t",
        )
        .unwrap()
        .specs();
        let records: Vec<RunRecord> = specs
            .into_iter()
            .map(|spec| {
                let c = 0.9 + 0.01 * spec.index as f32;
                RunRecord {
                    result: Ok(RunResult {
                        coverage: c,
                        steps: 10.0 * (1 + spec.run) as f32,
                        decision_ms: vec![1.0 + spec.run as f64],
                        coverage_curve: vec![(0.0, 0.1), (5.0 + spec.run as f32, c)],
                        ..RunResult::default()
                    }),
                    spec,
                }
            })
            .collect();
        let groups = summarize(&records);
        assert_eq!(groups.len(), 2);
        let boa = &groups[0];
        assert_eq!(boa.key.method, "boa");
        assert_eq!(boa.runs, 2);
        let cov = boa.coverage.unwrap();
        assert!((cov.min - 0.91).abs() < 1e-6 && (cov.max - 0.93).abs() < 1e-6);
        assert_eq!(boa.steps.unwrap().avg, 15.0);
        assert_eq!(boa.reached_90, 2);
        assert_eq!(boa.reached_99, 0);
        assert_eq!(boa.steps_to_90.unwrap().avg, 5.5);
        assert_eq!(boa.decision_ms_p50, Some(1.0));
        assert_eq!(boa.decision_ms_p99, Some(2.0));
        let md = markdown("t", &groups);
        assert!(md.contains("## lab"));
        assert!(
            md.contains("| boa | short (1) | 5 | 1 | 2 | 92.00 | 91.00 | 93.00 | 5.5 | – (0/2) |"),
            "{md}"
        );
    }
}
