//! Hyper-parameter tuning of one method on exploration missions (`papillon-sim tune`), like
//! the thesis's Hyperopt run (section 4.5: 30 trials per method, each repeated 3 times), with
//! TPE ([`crate::tpe`]).
//!
//! A trial sets the method's parameters ([`super::params::space`]) and runs `runs` missions,
//! seeds `base_seed ..`, the same for every trial. Its loss is
//! `99 − mean final coverage [%] + 0.001 × mean steps`, each coverage counted up to the
//! mission's 99 % stop: coverage first
//! (the thesis's criterion), steps (energy) only separating trials whose coverage is equal,
//! which happens whenever they all reach the stop (where the last scan's overshoot above 99 %
//! is not a merit).
//!
//! **Shards.** Trials are proposed in batches of `batch`: trial `t` is in batch `t / batch`,
//! and its parameters are drawn by TPE from the trials of the earlier batches only, with a
//! generator seeded from (`sampler_seed`, `t`). So the trials of a batch are independent
//! given the earlier batches, and the result does not depend on how they are spread: shard
//! `I/N` runs the trials whose index, scrambled as `bench` scrambles run indices
//! ([`Shard::contains`]), is `I` modulo `N`; it reads the trials already in its `--out`
//! and in the other shards' directories (`--with`), runs those of its trials whose earlier
//! batches are complete, and stops, saying so, at the first one that must wait for another
//! shard. Re-running every shard (with `--with` the others) until none has trials left, then
//! once more with no shard, writes the combined outputs. With `batch = 1` (the default) TPE
//! sees every earlier trial, as Hyperopt does, and sharding cannot help.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::exec::{ProgressMode, execute};
use super::params::{self, ParamMap};
use super::sweep::{Shard, Strategy, Sweep};
use crate::tpe::{self, Bounds, TpeConfig};

/// What a tuning run is: everything that must agree between shards.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Method tuned.
    pub method: String,
    /// World.
    pub map: String,
    /// Population size.
    pub population: usize,
    /// `short` or `long`.
    pub strategy: String,
    /// Targets per decision.
    pub targets: usize,
    /// Objective of the missions (`thesis` or `efficient`).
    pub objective: String,
    /// Generations per decision.
    pub generations: u32,
    /// Battery \[steps\]; `None`: the mission's default.
    pub battery_steps: Option<f32>,
    /// Missions per trial.
    pub runs: usize,
    /// Seed of the first mission of every trial.
    pub base_seed: u64,
    /// Trials.
    pub trials: usize,
    /// Trials proposed together (see the module doc).
    pub batch: usize,
    /// Seed of the sampler.
    pub sampler_seed: u64,
    /// Cell size \[m\].
    pub resolution_m: f32,
}

/// One finished trial.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trial {
    /// Index (0-based).
    pub index: usize,
    /// Parameters by name.
    pub params: ParamMap,
    /// Final coverage of each mission (0..1).
    pub coverage: Vec<f32>,
    /// Steps of each mission.
    pub steps: Vec<f32>,
    /// Loss (lower is better).
    pub loss: f64,
}

/// Settings file of a tuning directory.
pub const SETTINGS_FILE: &str = "tune.json";
/// Trials file of a tuning directory (one JSON object per line).
pub const TRIALS_FILE: &str = "trials.jsonl";

impl Settings {
    /// Checks the values and that the method has parameters.
    pub fn check(&self) -> Result<(), String> {
        if params::space(&self.method).is_empty() {
            return Err(format!(
                "--method: {} has no hyper-parameters to tune (expected xboa boa mboa aboa saboa ga pso)",
                self.method
            ));
        }
        if !(1..=10_000).contains(&self.trials) {
            return Err(format!(
                "--trials: expected 1 to 10000, got {}",
                self.trials
            ));
        }
        if !(1..=self.trials).contains(&self.batch) {
            return Err(format!(
                "--batch: expected 1 to the number of trials, got {}",
                self.batch
            ));
        }
        self.sweep(&ParamMap::new()).check()?;
        Ok(())
    }

    /// The missions of one trial with `values`.
    pub fn sweep(&self, values: &ParamMap) -> Sweep {
        let strategy = if self.strategy == "long" {
            Strategy::long(self.targets)
        } else {
            Strategy {
                name: self.strategy.clone(),
                targets: Some(self.targets),
            }
        };
        let mut params = BTreeMap::new();
        if !values.is_empty() {
            params.insert(self.method.clone(), values.clone());
        }
        Sweep {
            name: format!("tune-{}", self.method),
            maps: vec![self.map.clone()],
            methods: vec![self.method.clone()],
            strategies: vec![strategy],
            objective: self.objective.clone(),
            objectives: Vec::new(),
            // Tuning like the thesis: what a tuning does not set is Table 4.1's.
            preset: papillon::optim::Preset::Thesis.name().into(),
            presets: Vec::new(),
            populations: vec![self.population],
            robots: vec![1],
            runs: self.runs,
            generations: self.generations,
            battery_steps: self.battery_steps,
            base_seed: self.base_seed,
            resolution_m: self.resolution_m,
            params,
            max_time_s: None,
        }
    }

    fn bounds(&self) -> Vec<Bounds> {
        params::space(&self.method)
            .iter()
            .map(|r| Bounds {
                low: f64::from(r.low),
                high: f64::from(r.high),
            })
            .collect()
    }

    /// The parameters of trial `t` given the finished trials (TPE on those of the earlier
    /// batches); `None` when one of those is missing.
    pub fn propose(&self, t: usize, done: &BTreeMap<usize, Trial>) -> Option<ParamMap> {
        let first_of_batch = (t / self.batch) * self.batch;
        let space = params::space(&self.method);
        let mut history = Vec::with_capacity(first_of_batch);
        for i in 0..first_of_batch {
            let trial = done.get(&i)?;
            let x = space
                .iter()
                .map(|r| f64::from(trial.params.get(r.name).copied().unwrap_or(r.low)))
                .collect();
            history.push((x, trial.loss));
        }
        let seed = self
            .sampler_seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(t as u64);
        let mut rng = papillon::random::seeded(seed);
        let x = tpe::suggest(&TpeConfig::default(), &self.bounds(), &history, &mut rng);
        Some(
            space
                .iter()
                .zip(x)
                .map(|(r, v)| (r.name.to_string(), (v as f32).clamp(r.low, r.high)))
                .collect(),
        )
    }
}

/// The mission's coverage stop (`MissionConfig::coverage_target`'s default).
pub const COVERAGE_STOP: f64 = 0.99;

/// The loss of missions with these coverages and steps (see the module doc).
pub fn loss(coverage: &[f32], steps: &[f32]) -> f64 {
    let n = coverage.len().max(1) as f64;
    let cov = coverage
        .iter()
        .map(|&c| f64::from(c).min(COVERAGE_STOP))
        .sum::<f64>()
        / n;
    let st = steps.iter().map(|&s| f64::from(s)).sum::<f64>() / n;
    100.0 * (COVERAGE_STOP - cov) + 0.001 * st
}

/// Runs trial `t` with `values`.
pub fn run_trial(
    settings: &Settings,
    t: usize,
    values: ParamMap,
    jobs: usize,
) -> Result<Trial, String> {
    let sweep = settings.sweep(&values);
    let records = execute(
        &sweep.specs(),
        jobs,
        &super::sim::run,
        None,
        ProgressMode::Quiet,
    )?;
    let mut coverage = Vec::new();
    let mut steps = Vec::new();
    for r in &records {
        let m = r
            .result
            .as_ref()
            .map_err(|e| format!("trial {t}, seed {}: {e}", r.spec.seed))?;
        coverage.push(m.coverage);
        steps.push(m.steps);
    }
    Ok(Trial {
        index: t,
        loss: loss(&coverage, &steps),
        params: values,
        coverage,
        steps,
    })
}

/// Reads a tuning directory: its settings and trials (none when it does not exist yet).
pub fn read_dir(dir: &Path) -> Result<Option<(Settings, Vec<Trial>)>, String> {
    let path = dir.join(SETTINGS_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text = papillon::files::read_limited_to_string(&path, papillon::files::TEXT_MAX_BYTES)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let settings: Settings = serde_json::from_str(&text)
        .map_err(|e| format!("{}: not a tuning settings file: {e}", path.display()))?;
    let tpath = dir.join(TRIALS_FILE);
    let mut trials = Vec::new();
    if tpath.is_file() {
        let text = papillon::files::read_limited_to_string(&tpath, papillon::files::TEXT_MAX_BYTES)
            .map_err(|e| format!("{}: cannot read: {e}", tpath.display()))?;
        for (i, line) in text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
        {
            trials.push(
                serde_json::from_str(line)
                    .map_err(|e| format!("{}:{}: bad trial: {e}", tpath.display(), i + 1))?,
            );
        }
    }
    Ok(Some((settings, trials)))
}

/// What [`tune`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Every known trial, by index.
    pub trials: BTreeMap<usize, Trial>,
    /// Trials run now.
    pub ran: usize,
    /// Trials of this shard still waiting for other shards' earlier batches.
    pub waiting: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Runs this shard's remaining trials into `out` (reading the trials already there and in
/// `with`), then writes the outputs for every known trial. `progress` is told each trial.
pub fn tune(
    settings: &Settings,
    shard: Shard,
    jobs: usize,
    out: &Path,
    with: &[PathBuf],
    progress: &mut dyn FnMut(&Trial),
) -> Result<Outcome, String> {
    settings.check()?;
    let mut done: BTreeMap<usize, Trial> = BTreeMap::new();
    for dir in std::iter::once(&out.to_path_buf()).chain(with) {
        if let Some((s, trials)) = read_dir(dir)? {
            if s != *settings {
                return Err(format!(
                    "{}: its {SETTINGS_FILE} differs from this tuning's settings",
                    dir.display()
                ));
            }
            for t in trials {
                done.insert(t.index, t);
            }
        } else if dir != out {
            return Err(format!("--with {}: no {SETTINGS_FILE}", dir.display()));
        }
    }
    fs::create_dir_all(out).map_err(|e| format!("--out {}: cannot create: {e}", out.display()))?;
    let spath = out.join(SETTINGS_FILE);
    let text = serde_json::to_string_pretty(settings).map_err(|e| e.to_string())?;
    fs::write(&spath, text + "\n")
        .map_err(|e| format!("{}: cannot write: {e}", spath.display()))?;
    let mut ran = 0;
    let mut waiting = 0;
    for t in 0..settings.trials {
        if done.contains_key(&t) || !shard.contains(t) {
            continue;
        }
        let Some(values) = settings.propose(t, &done) else {
            waiting = (t..settings.trials)
                .filter(|&i| shard.contains(i) && !done.contains_key(&i))
                .count();
            break;
        };
        let trial = run_trial(settings, t, values, jobs)?;
        progress(&trial);
        done.insert(t, trial);
        ran += 1;
        // Keep this directory's own trials on disk as they finish.
        write_trials(out, &done, shard)?;
    }
    write_trials(out, &done, shard)?;
    let files = write_outputs(out, settings, &done)?;
    Ok(Outcome {
        trials: done,
        ran,
        waiting,
        files,
    })
}

fn write_trials(out: &Path, done: &BTreeMap<usize, Trial>, shard: Shard) -> Result<(), String> {
    let mut text = String::new();
    for t in done.values().filter(|t| shard.contains(t.index)) {
        text += &serde_json::to_string(t).map_err(|e| e.to_string())?;
        text.push('\n');
    }
    let p = out.join(TRIALS_FILE);
    fs::write(&p, text).map_err(|e| format!("{}: cannot write: {e}", p.display()))
}

/// The best trial (lowest loss, then lowest index).
pub fn best(trials: &BTreeMap<usize, Trial>) -> Option<&Trial> {
    trials
        .values()
        .min_by(|a, b| a.loss.total_cmp(&b.loss).then(a.index.cmp(&b.index)))
}

/// Writes `best.json` (the best parameters as a sweep fragment, `{"params": {METHOD:
/// {...}}}`, which `bench --params` reads), `trials.csv` and `trials.md` (every trial, Table
/// 4.1's values first for reference).
pub fn write_outputs(
    out: &Path,
    settings: &Settings,
    trials: &BTreeMap<usize, Trial>,
) -> Result<Vec<PathBuf>, String> {
    let write = |file: &str, text: String| -> Result<PathBuf, String> {
        let p = out.join(file);
        fs::write(&p, text).map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
        Ok(p)
    };
    let space = params::space(&settings.method);
    let names: Vec<&str> = space.iter().map(|r| r.name).collect();
    let mut files = Vec::new();
    let mut csv = format!(
        "trial,{},loss,coverage_mean,coverage_min,steps_mean\n",
        names.join(",")
    );
    let mean = |v: &[f32]| v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len().max(1) as f64;
    let minimum = |v: &[f32]| v.iter().copied().fold(f32::INFINITY, f32::min);
    for t in trials.values() {
        let vals: Vec<String> = names
            .iter()
            .map(|n| {
                t.params
                    .get(*n)
                    .map_or(String::new(), |v| format!("{v:.4}"))
            })
            .collect();
        let _ = writeln!(
            csv,
            "{},{},{:.5},{:.5},{:.5},{:.1}",
            t.index,
            vals.join(","),
            t.loss,
            mean(&t.coverage),
            minimum(&t.coverage),
            mean(&t.steps)
        );
    }
    files.push(write("trials.csv", csv)?);
    let table_4_1 = params::thesis_values(&settings.method, settings.population);
    let mut md = format!(
        "# Tuning `{}` (population {}, {}-term, {} objective) on `{}`\n\n{} trials x {} missions \
         (seeds {}..{}), TPE (Bergstra et al. 2011), batches of {}. Loss: 99 − mean coverage \
         [%] (each counted up to the 99 % stop) + 0.001 × mean steps (lower is better).\n\n| trial | {} | loss | coverage mean [%] | \
         min [%] | steps mean |\n|--:|{}--:|--:|--:|--:|\n",
        settings.method,
        settings.population,
        settings.strategy,
        settings.objective,
        super::sweep::map_label(&settings.map),
        settings.trials,
        settings.runs,
        settings.base_seed,
        settings.base_seed + settings.runs as u64 - 1,
        settings.batch,
        names.join(" | "),
        "--:|".repeat(names.len()),
    );
    let best_index = best(trials).map(|t| t.index);
    let _ = writeln!(
        md,
        "| Table 4.1 | {} | | | | |",
        names
            .iter()
            .map(|n| table_4_1.get(*n).map_or("–".into(), |v| format!("{v:.3}")))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    for t in trials.values() {
        let mark = if Some(t.index) == best_index {
            " (best)"
        } else {
            ""
        };
        let _ = writeln!(
            md,
            "| {}{mark} | {} | {:.3} | {:.2} | {:.2} | {:.1} |",
            t.index,
            names
                .iter()
                .map(|n| t.params.get(*n).map_or("–".into(), |v| format!("{v:.3}")))
                .collect::<Vec<_>>()
                .join(" | "),
            t.loss,
            100.0 * mean(&t.coverage),
            100.0 * f64::from(minimum(&t.coverage)),
            mean(&t.steps)
        );
    }
    files.push(write("trials.md", md)?);
    if let Some(b) = best(trials) {
        let mut params = BTreeMap::new();
        params.insert(settings.method.clone(), b.params.clone());
        let fragment = serde_json::json!({
            "params": params,
            "tuned": {
                "trial": b.index,
                "loss": b.loss,
                "population": settings.population,
                "map": settings.map,
                "objective": settings.objective,
            }
        });
        let text = serde_json::to_string_pretty(&fragment).map_err(|e| e.to_string())?;
        files.push(write("best.json", text + "\n")?);
    }
    Ok(files)
}

/// Reads a `best.json` (or any JSON object with a `params` member) into a sweep's `params`.
pub fn read_params(path: &Path) -> Result<BTreeMap<String, ParamMap>, String> {
    let text = papillon::files::read_limited_to_string(path, papillon::files::TEXT_MAX_BYTES)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    #[derive(Deserialize)]
    struct Fragment {
        params: BTreeMap<String, ParamMap>,
    }
    let f: Fragment = serde_json::from_str(&text).map_err(|e| {
        format!(
            "{}: expected {{\"params\": {{METHOD: {{NAME: VALUE}}}}}}: {e}",
            path.display()
        )
    })?;
    Ok(f.params)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(batch: usize) -> Settings {
        Settings {
            method: "xboa".into(),
            map: "lab".into(),
            population: 5,
            strategy: "short".into(),
            targets: 1,
            objective: "thesis".into(),
            generations: 30,
            battery_steps: Some(40.0),
            runs: 1,
            base_seed: 25,
            trials: 30,
            batch,
            sampler_seed: 25,
            resolution_m: 0.1,
        }
    }

    fn fake(t: usize, params: ParamMap) -> Trial {
        let a = params["a"];
        Trial {
            index: t,
            loss: f64::from((a - 0.3).abs()),
            params,
            coverage: vec![0.9],
            steps: vec![30.0],
        }
    }

    /// Proposals depend only on the earlier batches, so a batch's trials can be run in any
    /// order (by any shard) and give the same parameters.
    #[test]
    fn a_proposal_depends_only_on_the_earlier_batches() {
        let s = settings(5);
        let mut done = BTreeMap::new();
        for t in 0..15 {
            let p = s.propose(t, &done).unwrap();
            for r in params::space("xboa") {
                assert!((r.low..=r.high).contains(&p[r.name]));
            }
            done.insert(t, fake(t, p));
        }
        // Trial 13 (batch 2) again, with only batches 0 and 1 known: the same parameters.
        let earlier: BTreeMap<usize, Trial> = done
            .iter()
            .filter(|(i, _)| **i < 10)
            .map(|(i, t)| (*i, t.clone()))
            .collect();
        assert_eq!(s.propose(13, &earlier), Some(done[&13].params.clone()));
        // With trial 7 missing, batch 2 must wait.
        let mut gap = earlier.clone();
        gap.remove(&7);
        assert_eq!(s.propose(13, &gap), None);
        assert!(s.propose(7, &gap).is_some());
    }
}
