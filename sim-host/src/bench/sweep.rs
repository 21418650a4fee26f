//! Sweeps: which runs an experiment is made of.
//!
//! A [`Sweep`] is the product maps x strategies x population sizes x robot counts x runs x
//! methods. Each combination is one [`RunSpec`] with a stable index (its place in that product),
//! so a sweep can be cut into shards ([`Shard`]) and the shards' results merged back by index.
//! Run `r` of every combination gets the seed `base_seed + r`, so for a given run index every
//! method starts from the same seeded state, hence the same initial population (the thesis's
//! protocol: all methods compared on the same initial populations).

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

use papillon::optim::{MAX_POP, MIN_POP};

use super::params::ParamMap;

/// The thesis's base seed.
pub const BASE_SEED: u64 = 25;

/// Runs per combination when neither the experiment nor `--runs` says.
pub const DEFAULT_RUNS: usize = 10;

/// The ten optimizers the thesis compares.
pub const OPTIMIZERS: [&str; 10] = [
    "xboa", "boa", "mboa", "aboa", "saboa", "ga", "pso", "gwo", "abc", "cmaes",
];

/// The two frontier-based selectors.
pub const FRONTIER_SELECTORS: [&str; 2] = ["nearest-frontier", "frontier-utility"];

/// The butterfly variants.
pub const BOA_VARIANTS: [&str; 5] = ["boa", "mboa", "aboa", "saboa", "xboa"];

/// The named experiments.
pub const EXPERIMENTS: [&str; 6] = [
    "multi-robot",
    "horizon",
    "methods",
    "population",
    "boa-variants",
    "scale",
];

/// The experiment that runs every named experiment, these and the thesis's
/// ([`super::thesis::EXPERIMENTS`]), as one pool ([`super::run_pooled`]).
pub const ALL: &str = "all";

/// The maps of the `scale` experiment: generated square storeys
/// ([`crate::world::generated`], `gen-floor-SIDEm-SEED`) of 24, 48, 96 and 192 m, at 0.1 m
/// 240², 480², 960² and 1920² cells.
pub const SCALE_MAPS: [&str; 4] = [
    "gen-floor-24m-1",
    "gen-floor-48m-1",
    "gen-floor-96m-1",
    "gen-floor-192m-1",
];

/// The robot counts of the `scale` experiment.
pub const SCALE_ROBOTS: [usize; 4] = [1, 10, 50, 100];

/// Simulated time each run of the `scale` experiment is cut at \[s\].
pub const SCALE_MAX_TIME_S: f64 = 60.0;

/// Runs per combination of a named experiment when `--runs` does not say: one for `scale`
/// (a cost measurement, not a statistic), [`DEFAULT_RUNS`] for the others.
pub fn default_runs_for(name: &str) -> usize {
    if name == "scale" { 1 } else { DEFAULT_RUNS }
}

/// A decision strategy: short-term (one target per decision) or long-term (`targets` per
/// decision).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Strategy {
    /// `short` or `long`.
    pub name: String,
    /// Targets per decision, k (short: 1; long: default 3).
    #[serde(default)]
    pub targets: Option<usize>,
}

impl Strategy {
    /// The short-term strategy.
    pub fn short() -> Self {
        Self {
            name: "short".into(),
            targets: Some(1),
        }
    }

    /// The long-term strategy with `k` targets per decision.
    pub fn long(k: usize) -> Self {
        Self {
            name: "long".into(),
            targets: Some(k),
        }
    }

    /// Targets per decision (the default for the strategy when not given).
    pub fn k(&self) -> usize {
        self.targets
            .unwrap_or(if self.name == "long" { 3 } else { 1 })
    }
}

fn default_runs() -> usize {
    DEFAULT_RUNS
}
fn default_generations() -> u32 {
    30
}
fn default_seed() -> u64 {
    BASE_SEED
}
fn default_resolution() -> f32 {
    0.1
}
fn default_strategies() -> Vec<Strategy> {
    vec![Strategy::short()]
}
fn default_populations() -> Vec<usize> {
    vec![5]
}
fn default_robots() -> Vec<usize> {
    vec![1]
}

/// Most runs per combination of a sweep.
pub const MAX_RUNS: usize = 100_000;
/// Most runs in a sweep.
pub const MAX_SWEEP_RUNS: usize = 1_000_000;

/// A sweep, as named experiments define it or as read from a JSON file (`--config`); every
/// field but `maps` and `methods` has a default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sweep {
    /// Name, used in titles.
    #[serde(default)]
    pub name: String,
    /// Worlds: built-in names or map files.
    pub maps: Vec<String>,
    /// Target selectors (`papillon-sim mission --method` names).
    pub methods: Vec<String>,
    /// Strategies.
    #[serde(default = "default_strategies")]
    pub strategies: Vec<Strategy>,
    /// What the optimizers maximise (`efficient`, the default, or `thesis`).
    #[serde(default = "default_objective")]
    pub objective: String,
    /// The optimizers' parameter set (`thesis` or `standard`, see
    /// [`papillon::optim::Preset`]; default [`papillon::explore::DEFAULT_PRESET`]).
    #[serde(default = "default_preset")]
    pub preset: String,
    /// Presets compared side by side (outside every dimension but `objectives`); empty: the
    /// single `preset`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub presets: Vec<String>,
    /// Population sizes.
    #[serde(default = "default_populations")]
    pub populations: Vec<usize>,
    /// Robot counts.
    #[serde(default = "default_robots")]
    pub robots: Vec<usize>,
    /// Runs per combination.
    #[serde(default = "default_runs")]
    pub runs: usize,
    /// Generations per decision.
    #[serde(default = "default_generations")]
    pub generations: u32,
    /// Battery \[steps\]; `None`: the mission's default.
    #[serde(default)]
    pub battery_steps: Option<f32>,
    /// Seed of run 0; run `r` uses `base_seed + r`.
    #[serde(default = "default_seed")]
    pub base_seed: u64,
    /// Cell size \[m\].
    #[serde(default = "default_resolution")]
    pub resolution_m: f32,
    /// Objectives compared side by side (the outermost dimension of the sweep); empty: the
    /// single `objective`. The `thesis-*` experiments run `thesis` (the reproduction) and
    /// `efficient` (Papillon's default).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objectives: Vec<String>,
    /// Hyper-parameters per method replacing the thesis's Table 4.1 (method name ->
    /// parameter name -> value, see [`super::params`]); `papillon-sim tune` writes them.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, ParamMap>,
    /// Simulated time each run is cut at \[s\] (`mission --max-time`); `None`: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time_s: Option<f64>,
}

/// One run of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSpec {
    /// Place in the sweep (stable across shards).
    pub index: usize,
    /// World: built-in name or map file.
    pub map: String,
    /// Short name of the world for tables and file names.
    pub map_label: String,
    /// Target selector.
    pub method: String,
    /// `short` or `long`.
    pub strategy: String,
    /// What the optimizers maximise (`efficient` or `thesis`; runs recorded before the
    /// objective was an option read as `thesis`).
    #[serde(default = "thesis_objective")]
    pub objective: String,
    /// The optimizers' parameter set (`thesis` or `standard`; runs recorded before the preset
    /// was an option read as `thesis`).
    #[serde(default = "thesis_preset")]
    pub preset: String,
    /// Targets per decision.
    pub targets: usize,
    /// Population size.
    pub population: usize,
    /// Generations per decision.
    pub generations: u32,
    /// Robots.
    pub robots: usize,
    /// Run index (0-based).
    pub run: usize,
    /// Seed.
    pub seed: u64,
    /// Battery \[steps\]; `None`: the mission's default.
    pub battery_steps: Option<f32>,
    /// Cell size \[m\].
    pub resolution_m: f32,
    /// Hyper-parameters replacing the preset's for this run's method (`None`: the preset's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub params: Option<ParamMap>,
    /// Simulated time the run is cut at \[s\]; `None`: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time_s: Option<f64>,
}

/// The label of a world spec: a built-in name as is, a file by its stem.
pub fn map_label(spec: &str) -> String {
    let p = Path::new(spec);
    if p.extension().is_some() {
        p.file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or(spec)
            .to_string()
    } else {
        spec.to_string()
    }
}

fn default_objective() -> String {
    papillon::explore::ObjectiveKind::default().name().into()
}

fn thesis_objective() -> String {
    papillon::explore::ObjectiveKind::Thesis.name().into()
}

fn default_preset() -> String {
    papillon::explore::DEFAULT_PRESET.name().into()
}

fn thesis_preset() -> String {
    papillon::optim::Preset::Thesis.name().into()
}

impl Sweep {
    /// A named experiment (see [`EXPERIMENTS`]), with `runs` runs per combination, on the
    /// built-in maps plus `extra_maps` (the thesis's own maps when present).
    pub fn named(name: &str, runs: usize, extra_maps: &[String]) -> Option<Self> {
        if name.starts_with("thesis-") {
            // The thesis's own maps when found, else the project's drawn after them.
            let maps = match extra_maps {
                [empty, house] => [empty.clone(), house.clone()],
                _ => ["empty".to_string(), "house".to_string()],
            };
            return super::thesis::sweep(name, runs, &maps);
        }
        let owned = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let mut all_methods = owned(&OPTIMIZERS);
        all_methods.extend(owned(&FRONTIER_SELECTORS));
        let (maps, methods, strategies, populations, robots) = match name {
            "multi-robot" => (
                owned(&["house", "empty", "factory"]),
                owned(&["xboa"]),
                vec![Strategy::short()],
                vec![5],
                vec![1, 2, 3],
            ),
            "horizon" => (
                owned(&["house", "empty"]),
                all_methods,
                vec![Strategy::short(), Strategy::long(3)],
                vec![20],
                vec![1],
            ),
            "methods" => (
                owned(&["house", "empty"]),
                all_methods,
                vec![Strategy::short()],
                vec![20],
                vec![1],
            ),
            "population" => (
                owned(&["house", "empty"]),
                owned(&OPTIMIZERS),
                vec![Strategy::short()],
                vec![5, 10, 20],
                vec![1],
            ),
            "boa-variants" => (
                owned(&["house", "empty"]),
                owned(&BOA_VARIANTS),
                vec![Strategy::short()],
                vec![5],
                vec![1],
            ),
            "scale" => (
                owned(&SCALE_MAPS),
                owned(&["xboa"]),
                vec![Strategy::short()],
                vec![5],
                SCALE_ROBOTS.to_vec(),
            ),
            _ => return None,
        };
        let mut maps = maps;
        // `scale` measures cost on its own storeys; the thesis's maps add nothing to it.
        if name != "scale" {
            maps.extend(extra_maps.iter().cloned());
        }
        Some(Self {
            name: name.to_string(),
            maps,
            methods,
            strategies,
            populations,
            robots,
            runs,
            objective: default_objective(),
            preset: default_preset(),
            presets: Vec::new(),
            generations: default_generations(),
            battery_steps: None,
            base_seed: BASE_SEED,
            resolution_m: default_resolution(),
            objectives: Vec::new(),
            params: BTreeMap::new(),
            max_time_s: (name == "scale").then_some(SCALE_MAX_TIME_S),
        })
    }

    /// Reads a sweep file and checks that its methods and maps are known
    /// ([`Sweep::check_runnable`]); a sweep without a name takes the file's stem.
    pub fn from_file(path: &Path) -> Result<Self, String> {
        let text = papillon::files::read_limited_to_string(path, papillon::files::TEXT_MAX_BYTES)
            .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let origin = path.display().to_string();
        let mut s = Sweep::from_json(&text, &origin)?;
        s.check_runnable().map_err(|e| format!("{origin}: {e}"))?;
        if s.name.is_empty() {
            s.name = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("sweep")
                .to_string();
        }
        Ok(s)
    }

    /// Reads a sweep from JSON text; `origin` names the source in errors.
    pub fn from_json(text: &str, origin: &str) -> Result<Self, String> {
        let sweep: Sweep =
            serde_json::from_str(text).map_err(|e| format!("{origin}: bad sweep: {e}"))?;
        sweep.check().map_err(|e| format!("{origin}: {e}"))?;
        Ok(sweep)
    }

    /// Checks the sweep's values (not the maps or method names, which the runs check).
    pub fn check(&self) -> Result<(), String> {
        if self.maps.is_empty() {
            return Err("the sweep has no maps".into());
        }
        if self.methods.is_empty() {
            return Err("the sweep has no methods".into());
        }
        if self.strategies.is_empty() || self.populations.is_empty() || self.robots.is_empty() {
            return Err("strategies, populations and robots must not be empty".into());
        }
        if !(1..=MAX_RUNS).contains(&self.runs) {
            return Err(format!("runs must be 1 to {MAX_RUNS}, got {}", self.runs));
        }
        let combinations = [
            self.objective_list().len(),
            self.preset_list().len(),
            self.maps.len(),
            self.strategies.len(),
            self.populations.len(),
            self.robots.len(),
            self.runs,
            self.methods.len(),
        ]
        .iter()
        .try_fold(1usize, |n, &k| n.checked_mul(k))
        .filter(|&n| n <= MAX_SWEEP_RUNS);
        if combinations.is_none() {
            return Err(format!(
                "objectives x presets x maps x methods x strategies x populations x robots x runs \
                 is more than \
                 {MAX_SWEEP_RUNS} runs"
            ));
        }
        for (i, &p) in self.populations.iter().enumerate() {
            if !(MIN_POP..=MAX_POP).contains(&p) {
                return Err(format!(
                    "populations[{i}]: expected {MIN_POP} to {MAX_POP}, got {p}"
                ));
            }
        }
        for (i, &r) in self.robots.iter().enumerate() {
            if !(1..=crate::runner::MAX_ROBOTS).contains(&r) {
                return Err(format!(
                    "robots[{i}]: expected 1 to {}, got {r}",
                    crate::runner::MAX_ROBOTS
                ));
            }
        }
        if self.generations == 0 {
            return Err("generations must be at least 1".into());
        }
        for s in &self.strategies {
            if s.name != "short" && s.name != "long" {
                return Err(format!("strategy must be short or long, got '{}'", s.name));
            }
        }
        crate::scenario::objective_from_name(&self.objective)
            .map_err(|e| e.replacen("--objective", "objective", 1))?;
        for (i, o) in self.objectives.iter().enumerate() {
            crate::scenario::objective_from_name(o)
                .map_err(|e| e.replacen("--objective", &format!("objectives[{i}]"), 1))?;
        }
        crate::scenario::preset_from_name(&self.preset)
            .map_err(|e| e.replacen("--preset", "preset", 1))?;
        for (i, p) in self.presets.iter().enumerate() {
            crate::scenario::preset_from_name(p)
                .map_err(|e| e.replacen("--preset", &format!("presets[{i}]"), 1))?;
        }
        for (method, values) in &self.params {
            for &p in &self.populations {
                for preset in papillon::optim::Preset::ALL {
                    super::params::tuning(method, p, preset, values)?;
                }
            }
        }
        if !(self.resolution_m.is_finite() && self.resolution_m > 0.0 && self.resolution_m <= 1.0) {
            return Err(format!(
                "resolution_m must be a cell size of more than 0 and at most 1 m, got {}",
                self.resolution_m
            ));
        }
        if let Some(b) = self.battery_steps
            && !(b.is_finite() && b > 0.0)
        {
            return Err(format!("battery_steps must be positive, got {b}"));
        }
        if let Some(t) = self.max_time_s
            && !(t.is_finite() && t > 0.0)
        {
            return Err(format!(
                "max_time_s must be a positive number of seconds, got {t}"
            ));
        }
        Ok(())
    }

    /// Checks that every method is known and every map loads at the sweep's cell size (a
    /// name, a file, its size), so that a bad one is one error naming it rather than every
    /// run failing ([`Sweep::check`] leaves them to the runs).
    pub fn check_runnable(&self) -> Result<(), String> {
        for (i, m) in self.methods.iter().enumerate() {
            crate::scenario::selector_from_name(m)
                .map_err(|e| format!("methods[{i}]: {}", e.trim_start_matches("--method: ")))?;
        }
        for (i, m) in self.maps.iter().enumerate() {
            crate::world::World::load(m, self.resolution_m).map_err(|e| {
                // The world's errors speak of `mission`'s flag; here it is the sweep's field.
                format!("maps[{i}]: {e}").replace("(--resolution)", "(resolution_m)")
            })?;
        }
        Ok(())
    }

    /// Number of runs in the sweep.
    pub fn len(&self) -> usize {
        self.objective_list().len()
            * self.preset_list().len()
            * self.maps.len()
            * self.strategies.len()
            * self.populations.len()
            * self.robots.len()
            * self.runs
            * self.methods.len()
    }

    /// Whether the sweep has no runs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every run, in index order (method innermost, so that the runs of one run index, which
    /// share a seed, are neighbours).
    pub fn specs(&self) -> Vec<RunSpec> {
        let mut out = Vec::with_capacity(self.len());
        let presets = self.preset_list();
        for objective in &self.objective_list() {
            for preset in &presets {
                for map in &self.maps {
                    for strategy in &self.strategies {
                        for &population in &self.populations {
                            for &robots in &self.robots {
                                for run in 0..self.runs {
                                    for method in &self.methods {
                                        out.push(RunSpec {
                                            index: out.len(),
                                            map: map.clone(),
                                            map_label: map_label(map),
                                            method: method.clone(),
                                            strategy: strategy.name.clone(),
                                            objective: objective.clone(),
                                            preset: preset.clone(),
                                            targets: strategy.k(),
                                            population,
                                            generations: self.generations,
                                            robots,
                                            run,
                                            seed: self.base_seed + run as u64,
                                            battery_steps: self.battery_steps,
                                            resolution_m: self.resolution_m,
                                            params: self.params.get(method).cloned(),
                                            max_time_s: self.max_time_s,
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The presets the sweep runs: `presets`, or `preset` alone.
    pub fn preset_list(&self) -> Vec<String> {
        if self.presets.is_empty() {
            vec![self.preset.clone()]
        } else {
            self.presets.clone()
        }
    }

    /// The objectives the sweep runs: `objectives`, or `objective` alone.
    pub fn objective_list(&self) -> Vec<String> {
        if self.objectives.is_empty() {
            vec![self.objective.clone()]
        } else {
            self.objectives.clone()
        }
    }
}

/// Shard `index` of `count` (0-based): the runs whose index, scrambled by a fixed bijective
/// hash, is `index` modulo `count`; the scrambling spreads every map and method over the
/// shards (a plain modulo would give each shard the same methods whenever `count` divides
/// the number of methods), so the shards take about the same time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0..count.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole sweep.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` with 0 <= I < N.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = || format!("--shard: expected I/N with 0 <= I < N, got '{text}'");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether run `index` belongs to this shard.
    pub fn contains(&self, index: usize) -> bool {
        (scramble(index as u64) % self.count as u64) as usize == self.index
    }
}

/// SplitMix64's finaliser (Steele, Lea & Flood 2014): a fixed bijection of the run indices.
fn scramble(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The thesis's own map files (`map-empty.csv`, `map-house.csv`) in `dir`, if both exist.
pub fn thesis_maps_in(dir: &Path) -> Vec<String> {
    let files = ["map-empty.csv", "map-house.csv"];
    let paths: Vec<PathBuf> = files.iter().map(|f| dir.join(f)).collect();
    if paths.iter().all(|p| p.is_file()) {
        paths
            .iter()
            .map(|p| p.to_string_lossy().into_owned())
            .collect()
    } else {
        Vec::new()
    }
}

/// Where the thesis's maps are looked for: `../shared/data/thesis-maps` from the current
/// directory (the project root), then from the project this binary was built from.
pub fn find_thesis_maps() -> Vec<String> {
    let candidates = [
        PathBuf::from("../shared/data/thesis-maps"),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/thesis-maps"),
    ];
    for dir in candidates {
        let found = thesis_maps_in(&dir);
        if !found.is_empty() {
            return found;
        }
    }
    Vec::new()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_of_a_run_index_gets_the_same_seed() {
        let sweep = Sweep::named("boa-variants", 3, &[]).unwrap();
        let specs = sweep.specs();
        assert_eq!(specs.len(), 2 * 5 * 3);
        for s in &specs {
            assert_eq!(s.seed, BASE_SEED + s.run as u64);
        }
        for (i, s) in specs.iter().enumerate() {
            assert_eq!(s.index, i);
        }
        // The five methods of run 1 on the first map are neighbours with seed 26.
        let run1: Vec<&RunSpec> = specs
            .iter()
            .filter(|s| s.run == 1 && s.map == "house")
            .collect();
        assert_eq!(run1.len(), 5);
        assert!(run1.iter().all(|s| s.seed == 26 && s.population == 5));
    }

    #[test]
    fn named_experiments_have_the_thesis_dimensions() {
        let m = Sweep::named("methods", 10, &[]).unwrap();
        assert_eq!(m.methods.len(), 12);
        assert_eq!(m.populations, vec![20]);
        let h = Sweep::named("horizon", 10, &[]).unwrap();
        assert_eq!(h.strategies.len(), 2);
        let r = Sweep::named("multi-robot", 10, &["x.csv".into()]).unwrap();
        assert_eq!(r.robots, vec![1, 2, 3]);
        assert_eq!(r.maps, vec!["house", "empty", "factory", "x.csv"]);
        let p = Sweep::named("population", 10, &[]).unwrap();
        assert_eq!(p.populations, vec![5, 10, 20]);
        assert!(Sweep::named("nope", 1, &[]).is_none());
    }

    #[test]
    fn shards_partition_the_sweep() {
        let sweep = Sweep::named("population", 2, &[]).unwrap();
        let n = sweep.len();
        let mut seen = vec![0; n];
        for i in 0..4 {
            let shard = Shard::parse(&format!("{i}/4")).unwrap();
            for s in sweep.specs() {
                if shard.contains(s.index) {
                    seen[s.index] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        // Two shards of a two-method sweep both get both methods.
        let two = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["a", "b"], "runs": 8}"#,
            "t",
        )
        .unwrap();
        for i in 0..2 {
            let shard = Shard { index: i, count: 2 };
            let methods: std::collections::BTreeSet<String> = two
                .specs()
                .into_iter()
                .filter(|s| shard.contains(s.index))
                .map(|s| s.method)
                .collect();
            assert_eq!(methods.len(), 2);
        }
        assert!(Shard::parse("4/4").is_err());
        assert!(Shard::parse("1").is_err());
        assert!(Shard::parse("a/2").is_err());
    }

    #[test]
    fn json_sweeps_take_defaults_and_reject_unknown_fields() {
        let s = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["xboa", "nearest-frontier"],
                "strategies": [{"name": "long"}], "runs": 2}"#,
            "t.json",
        )
        .unwrap();
        assert_eq!(s.base_seed, 25);
        assert_eq!(s.populations, vec![5]);
        assert_eq!(s.strategies[0].k(), 3);
        assert_eq!(s.len(), 4);
        let e = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["xboa"], "rnus": 2}"#,
            "t.json",
        )
        .unwrap_err();
        assert!(e.starts_with("t.json: bad sweep"), "{e}");
        let e = Sweep::from_json(r#"{"maps": [], "methods": ["xboa"]}"#, "t.json").unwrap_err();
        assert!(e.contains("no maps"), "{e}");
    }

    #[test]
    fn presets_are_a_dimension_of_the_sweep() {
        let s = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["ga"], "runs": 2}"#,
            "t.json",
        )
        .unwrap();
        assert_eq!(s.preset, papillon::explore::DEFAULT_PRESET.name());
        let both = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["ga", "pso"], "runs": 2,
                "presets": ["thesis", "standard"]}"#,
            "t.json",
        )
        .unwrap();
        assert_eq!(both.len(), 8);
        let specs = both.specs();
        let of = |p: &str| specs.iter().filter(|r| r.preset == p).count();
        assert_eq!((of("thesis"), of("standard")), (4, 4));
        // The same seeds under both presets.
        assert_eq!(specs[0].seed, specs[4].seed);
        let e = Sweep::from_json(
            r#"{"maps": ["lab"], "methods": ["ga"], "presets": ["thesis", "pygmo"]}"#,
            "t.json",
        )
        .unwrap_err();
        assert!(e.contains("presets[1]"), "{e}");
        // A run recorded before the preset existed ran Table 4.1's.
        let old: RunSpec = serde_json::from_str(
            r#"{"index": 0, "map": "lab", "map_label": "lab", "method": "ga",
                "strategy": "short", "targets": 1, "population": 5, "generations": 30,
                "robots": 1, "run": 0, "seed": 25, "battery_steps": null, "resolution_m": 0.1}"#,
        )
        .unwrap();
        assert_eq!(old.preset, "thesis");
    }

    #[test]
    fn map_labels_are_names_or_file_stems() {
        assert_eq!(map_label("house"), "house");
        assert_eq!(
            map_label("../shared/data/thesis-maps/map-house.csv"),
            "map-house"
        );
    }
}
