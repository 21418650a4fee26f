//! What one run of a sweep produced, and how it is stored: `runs.jsonl` (one JSON object per
//! run, curves included, the source every other output is built from, so that shards can be
//! merged) and `results.csv` (one row per run, scalars only).

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::sweep::RunSpec;

/// The measurements of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// Final coverage (0..1).
    pub coverage: f32,
    /// Steps summed over robots (1 m of travel or 45° of rotation each).
    pub steps: f32,
    /// Steps of each robot.
    pub steps_per_robot: Vec<f32>,
    /// Metres summed over robots (odometry).
    pub distance_m: f64,
    /// Rotation summed over robots \[rad\].
    pub rotation_rad: f64,
    /// Decisions summed over robots.
    pub decisions: u32,
    /// Fitness evaluations summed over robots.
    pub fitness_evals: u64,
    /// Compute time of every decision \[ms\], all robots.
    pub decision_ms: Vec<f64>,
    /// Simulated time \[s\].
    pub sim_time_s: f64,
    /// Wall-clock time of the run \[s\].
    pub wall_time_s: f64,
    /// Why the run ended.
    pub reason: String,
    /// Coverage over steps: (steps summed over robots, coverage).
    pub coverage_curve: Vec<(f32, f32)>,
    /// Best fitness per generation of the run's first decision (robot 0), initial population
    /// first; empty for the frontier selectors.
    pub convergence: Vec<f32>,
    /// Cells of the map (the world's grid at the run's cell size).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<u64>,
    /// CPU time of the thread that ran the mission's run loop (the span of `wall_time_s`, not
    /// the world's generation nor the runner's set-up) \[s\]; `None` where the platform gives
    /// none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_time_s: Option<f64>,
    /// Peak resident memory of the whole process during the run \[MB\] (Linux's `VmHWM`,
    /// reset before the run): the run's own peak only when runs do not overlap (`--jobs 1`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rss_mb: Option<f64>,
}

/// One run: what was asked and what came out (or the error that stopped it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// The run.
    pub spec: RunSpec,
    /// Its measurements, or the error.
    pub result: Result<RunResult, String>,
}

/// Nearest-rank quantile `q` (0..=1) of sorted `v`; `None` when empty.
pub fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (q.clamp(0.0, 1.0) * sorted.len() as f64).ceil().max(1.0) as usize;
    Some(sorted[rank.min(sorted.len()) - 1])
}

impl RunResult {
    /// Steps (summed over robots) at which the coverage first reached `level` (0..1).
    pub fn steps_to(&self, level: f32) -> Option<f32> {
        self.coverage_curve
            .iter()
            .find(|&&(_, c)| c >= level)
            .map(|&(s, _)| s)
    }

    /// The `q`-quantile of the decision times \[ms\].
    pub fn decision_ms_quantile(&self, q: f64) -> Option<f64> {
        let mut v = self.decision_ms.clone();
        v.sort_by(f64::total_cmp);
        quantile(&v, q)
    }

    /// Mean decision time \[ms\].
    pub fn decision_ms_mean(&self) -> Option<f64> {
        if self.decision_ms.is_empty() {
            None
        } else {
            Some(self.decision_ms.iter().sum::<f64>() / self.decision_ms.len() as f64)
        }
    }
}

/// The columns of `results.csv`.
pub const CSV_HEADER: &str = "index,map,method,strategy,targets,population,generations,robots,run,seed,battery_steps,status,coverage,steps,steps_per_robot,steps_to_90,steps_to_99,distance_m,rotation_rad,decisions,fitness_evals,decision_ms_p50,decision_ms_p99,decision_ms_total,sim_time_s,wall_time_s,reason";

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `results.csv`: the header and one row per record, in index order.
pub fn csv(records: &[RunRecord]) -> String {
    let mut out = String::new();
    out.push_str(CSV_HEADER);
    out.push('\n');
    for r in records {
        let s = &r.spec;
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},",
            s.index,
            field(&s.map_label),
            field(&s.method),
            field(&s.strategy),
            s.targets,
            s.population,
            s.generations,
            s.robots,
            s.run,
            s.seed,
            opt(s.battery_steps),
        );
        match &r.result {
            Ok(m) => {
                let per: Vec<String> = m
                    .steps_per_robot
                    .iter()
                    .map(|x| format!("{x:.2}"))
                    .collect();
                let _ = writeln!(
                    out,
                    "ok,{:.5},{:.2},{},{},{},{:.3},{:.4},{},{},{},{},{:.3},{:.1},{:.3},{}",
                    m.coverage,
                    m.steps,
                    per.join(";"),
                    opt(m.steps_to(0.90).map(|x| format!("{x:.2}"))),
                    opt(m.steps_to(0.99).map(|x| format!("{x:.2}"))),
                    m.distance_m,
                    m.rotation_rad,
                    m.decisions,
                    m.fitness_evals,
                    opt(m.decision_ms_quantile(0.5).map(|x| format!("{x:.4}"))),
                    opt(m.decision_ms_quantile(0.99).map(|x| format!("{x:.4}"))),
                    m.decision_ms.iter().sum::<f64>(),
                    m.sim_time_s,
                    m.wall_time_s,
                    field(&m.reason),
                );
            }
            Err(e) => {
                let _ = writeln!(out, "error,,,,,,,,,,,,,,,{}", field(e));
            }
        }
    }
    out
}

/// Writes `runs.jsonl`: one JSON object per record.
pub fn write_jsonl(path: &Path, records: &[RunRecord]) -> Result<(), String> {
    let mut out = String::new();
    for r in records {
        let line = serde_json::to_string(r).map_err(|e| format!("{}: {e}", path.display()))?;
        out.push_str(&line);
        out.push('\n');
    }
    fs::write(path, out).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// Appends one record to `runs.jsonl` (so an interrupted shard keeps what it finished).
pub fn append_jsonl(file: &mut fs::File, record: &RunRecord) -> Result<(), String> {
    use std::io::Write;
    let line = serde_json::to_string(record).map_err(|e| e.to_string())?;
    writeln!(file, "{line}").map_err(|e| format!("cannot append to runs.jsonl: {e}"))
}

/// Reads `runs.jsonl`; an error names the file and line.
pub fn read_jsonl(path: &Path) -> Result<Vec<RunRecord>, String> {
    let text = papillon::files::read_limited_to_string(path, papillon::files::MAP_MAX_BYTES)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let r: RunRecord = serde_json::from_str(line)
            .map_err(|e| format!("{} line {}: not a run record: {e}", path.display(), n + 1))?;
        out.push(r);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::sweep::Sweep;

    fn result() -> RunResult {
        RunResult {
            coverage: 0.995,
            steps: 40.0,
            steps_per_robot: vec![40.0],
            decisions: 3,
            fitness_evals: 300,
            decision_ms: vec![3.0, 1.0, 2.0],
            reason: "coverage-reached".into(),
            coverage_curve: vec![(0.0, 0.2), (10.0, 0.85), (20.0, 0.92), (40.0, 0.995)],
            ..RunResult::default()
        }
    }

    #[test]
    fn steps_to_a_level_is_the_first_sample_reaching_it() {
        let r = result();
        assert_eq!(r.steps_to(0.9), Some(20.0));
        assert_eq!(r.steps_to(0.99), Some(40.0));
        assert_eq!(r.steps_to(0.999), None);
        assert_eq!(r.decision_ms_quantile(0.5), Some(2.0));
        assert_eq!(r.decision_ms_quantile(0.99), Some(3.0));
    }

    #[test]
    fn csv_has_one_row_per_run_and_jsonl_round_trips() {
        let spec = Sweep::from_json(r#"{"maps": ["lab"], "methods": ["xboa"], "runs": 2}"#, "t")
            .unwrap()
            .specs();
        let records = vec![
            RunRecord {
                spec: spec[0].clone(),
                result: Ok(result()),
            },
            RunRecord {
                spec: spec[1].clone(),
                result: Err("start, blocked".into()),
            },
        ];
        let text = csv(&records);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        let cols = CSV_HEADER.split(',').count();
        assert_eq!(lines[1].split(',').count(), cols);
        assert!(lines[1].contains(",ok,0.99500,40.00,40.00,20.00,40.00,"));
        assert!(lines[2].ends_with(",\"start, blocked\""));
        let dir = std::env::temp_dir().join(format!("papillon-record-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("runs.jsonl");
        write_jsonl(&path, &records).unwrap();
        assert_eq!(read_jsonl(&path).unwrap(), records);
        fs::write(&path, "{\"spec\": 1}\n").unwrap();
        let e = read_jsonl(&path).unwrap_err();
        assert!(e.contains("line 1"), "{e}");
        let _ = fs::remove_dir_all(&dir);
    }
}
