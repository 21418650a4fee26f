//! The thesis's experiments, reproduced side by side.
//!
//! Source of every number here: A. Bendahmane, PhD thesis (USTO-MB, Oran, 2023), chapter 4,
//! Tables 4.2 to 4.5 (final exploration rate \[%\] of the mission: average, min, max), as
//! transcribed in English in the project's shared notes (`docs/thesis-results.md` of the
//! shared data set, §§8 to 10). They are copied here so that the project stands alone. A
//! maximum printed "≥ 99" (the run reached the thesis's 99 % stop) is [`Cell::max_at_stop`].
//!
//! Each `thesis-*` experiment ([`EXPERIMENTS`]) is a sweep in the thesis's set-up (see
//! `docs/experiments.md`, "The thesis reproduced"): the thesis's objective and Papillon's
//! default one side by side (`objectives`), the thesis's slip, 10 cm cells, its laser (4 m,
//! 180°, 181 rays, 5 % noise, the mission's default), Table 4.1's hyper-parameters, 30
//! generations, seeds 25.. so that every method of a run index starts from the same initial
//! population, 10 runs. [`markdown`] writes `thesis.md`: the thesis's numbers, ours (thesis
//! objective) and Papillon's (efficient objective) in adjacent columns.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::record::RunRecord;
use super::summary::{GroupKey, GroupSummary, Stat, summarize};
use super::sweep::{Strategy, Sweep};

/// The thesis's two maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum MapKind {
    /// Empty, 24 m x 24 m.
    Empty,
    /// House, 24 m x 24 m.
    House,
}

impl MapKind {
    /// The thesis map a sweep's map label stands for: the thesis's own files (`map-empty`,
    /// `map-house`) or the project's maps drawn after them (`empty`, `house`).
    pub fn of_label(label: &str) -> Option<Self> {
        match label {
            "map-empty" | "empty" => Some(MapKind::Empty),
            "map-house" | "house" => Some(MapKind::House),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            MapKind::Empty => "Empty",
            MapKind::House => "House",
        }
    }
}

/// One cell of a thesis table: the final exploration rate of one method on one map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Table number (`"4.2"` ...).
    pub table: &'static str,
    /// `short` or `long`.
    pub strategy: &'static str,
    /// Population size.
    pub population: usize,
    /// Map.
    pub map: MapKind,
    /// Method (Papillon's name).
    pub method: &'static str,
    /// Average \[%\].
    pub avg: f32,
    /// Smallest \[%\].
    pub min: f32,
    /// Largest \[%\] (99 when printed "≥ 99").
    pub max: f32,
    /// The maximum is printed "≥ 99": the run reached the 99 % stop.
    pub max_at_stop: bool,
}

// One argument per column of the table rows below, which read best as plain calls.
#[allow(clippy::too_many_arguments)]
const fn c(
    table: &'static str,
    strategy: &'static str,
    population: usize,
    map: MapKind,
    method: &'static str,
    avg: f32,
    min: f32,
    max: f32,
) -> Cell {
    Cell {
        table,
        strategy,
        population,
        map,
        method,
        avg,
        min,
        max,
        max_at_stop: max >= 99.0,
    }
}

use MapKind::{Empty as E, House as H};

/// "≥ 99" in the thesis's tables.
const AT_STOP: f32 = 99.0;

/// Tables 4.2 (short and long term, population 20), 4.3 (BOA, House, short term, population
/// 5, 10, 20), 4.4 (population 5, short term) and 4.5 (BOA variants, House, population 5).
#[rustfmt::skip]
pub const CELLS: &[Cell] = &[
    // Table 4.2, short-term.
    c("4.2", "short", 20, E, "abc", 98.12, 97.22, AT_STOP),
    c("4.2", "short", 20, E, "boa", 96.0, 94.79, AT_STOP),
    c("4.2", "short", 20, E, "cmaes", 98.49, 95.66, AT_STOP),
    c("4.2", "short", 20, E, "ga", 97.38, 82.81, AT_STOP),
    c("4.2", "short", 20, E, "gwo", 93.03, 92.88, 93.05),
    c("4.2", "short", 20, E, "pso", 98.16, 97.39, AT_STOP),
    c("4.2", "short", 20, E, "xboa", 98.23, 93.92, AT_STOP),
    c("4.2", "short", 20, H, "abc", 90.1, 88.36, 92.7),
    c("4.2", "short", 20, H, "boa", 93.4, 91.84, 95.13),
    c("4.2", "short", 20, H, "cmaes", 93.29, 89.4, 96.18),
    c("4.2", "short", 20, H, "ga", 93.0, 92.01, 94.96),
    c("4.2", "short", 20, H, "gwo", 67.7, 67.7, 67.7),
    c("4.2", "short", 20, H, "pso", 93.19, 88.71, 94.79),
    c("4.2", "short", 20, H, "xboa", 91.63, 82.63, 94.44),
    // Table 4.2, long-term.
    c("4.2", "long", 20, E, "abc", 98.02, 96.52, AT_STOP),
    c("4.2", "long", 20, E, "boa", 93.87, 91.49, 97.74),
    c("4.2", "long", 20, E, "cmaes", 94.16, 83.85, AT_STOP),
    c("4.2", "long", 20, E, "ga", 97.63, 96.52, AT_STOP),
    c("4.2", "long", 20, E, "gwo", 93.4, 93.4, 93.4),
    c("4.2", "long", 20, E, "pso", 96.44, 92.88, AT_STOP),
    c("4.2", "long", 20, E, "xboa", 96.37, 93.57, 98.61),
    c("4.2", "long", 20, H, "abc", 86.38, 80.38, 92.18),
    c("4.2", "long", 20, H, "boa", 84.61, 73.26, 92.36),
    c("4.2", "long", 20, H, "cmaes", 82.23, 77.43, 86.45),
    c("4.2", "long", 20, H, "ga", 87.67, 79.86, 95.48),
    c("4.2", "long", 20, H, "gwo", 83.68, 83.68, 83.68),
    c("4.2", "long", 20, H, "pso", 87.06, 84.2, 90.97),
    c("4.2", "long", 20, H, "xboa", 89.9, 79.16, 94.1),
    // Table 4.3: BOA, House, short-term.
    c("4.3", "short", 5, H, "boa", 86.11, 81.77, 95.13),
    c("4.3", "short", 10, H, "boa", 88.66, 79.68, 95.13),
    c("4.3", "short", 20, H, "boa", 92.84, 89.75, 94.27),
    // Table 4.4: population 5, short-term.
    c("4.4", "short", 5, E, "abc", 97.32, 95.83, 98.61),
    c("4.4", "short", 5, E, "boa", 96.09, 92.01, AT_STOP),
    c("4.4", "short", 5, E, "cmaes", 94.46, 89.4, 98.61),
    c("4.4", "short", 5, E, "ga", 96.09, 87.5, AT_STOP),
    c("4.4", "short", 5, E, "gwo", 89.61, 84.37, 92.53),
    c("4.4", "short", 5, E, "pso", 93.03, 84.37, 98.26),
    c("4.4", "short", 5, E, "xboa", 96.14, 92.88, 98.26),
    c("4.4", "short", 5, H, "abc", 90.59, 84.72, 96.0),
    c("4.4", "short", 5, H, "boa", 87.13, 83.68, 95.13),
    c("4.4", "short", 5, H, "cmaes", 82.8, 76.73, 93.22),
    c("4.4", "short", 5, H, "ga", 92.36, 89.23, 96.0),
    c("4.4", "short", 5, H, "gwo", 62.03, 60.76, 62.32),
    c("4.4", "short", 5, H, "pso", 74.9, 70.83, 77.6),
    c("4.4", "short", 5, H, "xboa", 93.35, 92.18, 93.92),
    // Table 4.5: BOA variants, House, short-term, population 5.
    c("4.5", "short", 5, H, "boa", 89.11, 81.77, 95.13),
    c("4.5", "short", 5, H, "aboa", 90.38, 81.77, 95.13),
    c("4.5", "short", 5, H, "mboa", 89.14, 81.07, 95.13),
    c("4.5", "short", 5, H, "saboa", 85.13, 82.98, 85.93),
    c("4.5", "short", 5, H, "xboa", 93.35, 92.18, 93.92),
];

/// The seven methods of Tables 4.2 and 4.4.
pub const TABLE_METHODS: [&str; 7] = ["abc", "boa", "cmaes", "ga", "gwo", "pso", "xboa"];

/// The named thesis experiments, in the order `thesis-all` runs them.
pub const EXPERIMENTS: [&str; 7] = [
    "thesis-methods",
    "thesis-methods-long",
    "thesis-horizon",
    "thesis-population",
    "thesis-pop5",
    "thesis-boa-variants",
    "thesis-multi-robot",
];

/// The experiment that runs every other thesis experiment in turn, each into its own
/// directory.
pub const ALL: &str = "thesis-all";

/// Targets per decision of the long-term strategy: the thesis does not give it; its example
/// figure shows three destinations.
pub const LONG_TARGETS: usize = 3;

/// The tables an experiment is compared with, and what it is (for titles).
pub fn tables_of(name: &str) -> Option<(&'static [&'static str], &'static str)> {
    Some(match name {
        "thesis-methods" => (&["4.2"], "Table 4.2, short-term, population 20"),
        "thesis-methods-long" => (&["4.2"], "Table 4.2, long-term, population 20"),
        "thesis-horizon" => (&["4.2"], "Table 4.2, xBOA rows: short- vs long-term"),
        "thesis-population" => (&["4.3"], "Table 4.3, BOA, House, short-term"),
        "thesis-pop5" => (&["4.4"], "Table 4.4, population 5, short-term"),
        "thesis-boa-variants" => (&["4.5"], "Table 4.5, BOA variants, House, population 5"),
        "thesis-multi-robot" => (
            &[],
            "Experiment 1 (multi-robot): the thesis gives no numbers",
        ),
        _ => return None,
    })
}

/// The thesis experiment `name` as a sweep with `runs` runs per combination on `maps` (the
/// thesis's Empty and House, in that order; the experiments on House alone take the second).
pub fn sweep(name: &str, runs: usize, maps: &[String; 2]) -> Option<Sweep> {
    let own = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let both = maps.to_vec();
    let house = vec![maps[1].clone()];
    let (maps, methods, strategies, populations, robots) = match name {
        "thesis-methods" => (
            both,
            own(&TABLE_METHODS),
            vec![Strategy::short()],
            vec![20],
            vec![1],
        ),
        "thesis-methods-long" => (
            both,
            own(&TABLE_METHODS),
            vec![Strategy::long(LONG_TARGETS)],
            vec![20],
            vec![1],
        ),
        "thesis-horizon" => (
            both,
            own(&["xboa"]),
            vec![Strategy::short(), Strategy::long(LONG_TARGETS)],
            vec![20],
            vec![1],
        ),
        "thesis-population" => (
            house,
            own(&["boa"]),
            vec![Strategy::short()],
            vec![5, 10, 20],
            vec![1],
        ),
        "thesis-pop5" => (
            both,
            own(&TABLE_METHODS),
            vec![Strategy::short()],
            vec![5],
            vec![1],
        ),
        "thesis-boa-variants" => (
            house,
            own(&["boa", "aboa", "mboa", "saboa", "xboa"]),
            vec![Strategy::short()],
            vec![5],
            vec![1],
        ),
        "thesis-multi-robot" => (
            both,
            own(&["xboa"]),
            vec![Strategy::short()],
            vec![20],
            vec![1, 2, 3],
        ),
        _ => return None,
    };
    Some(Sweep {
        name: name.to_string(),
        maps,
        methods,
        strategies,
        objective: "thesis".into(),
        objectives: vec!["thesis".into(), "efficient".into()],
        // Table 4.1's hyper-parameters, whatever Papillon's default preset.
        preset: papillon::optim::Preset::Thesis.name().into(),
        presets: Vec::new(),
        populations,
        robots,
        runs,
        generations: 30,
        battery_steps: None,
        base_seed: super::sweep::BASE_SEED,
        resolution_m: 0.1,
        params: BTreeMap::new(),
        max_time_s: None,
    })
}

/// The thesis's cell for a group of the experiment `name`, if the thesis has one.
pub fn cell_for(name: &str, key: &GroupKey) -> Option<&'static Cell> {
    let (tables, _) = tables_of(name)?;
    if key.robots != 1 {
        return None;
    }
    let map = MapKind::of_label(&key.map)?;
    CELLS.iter().find(|c| {
        tables.contains(&c.table)
            && c.strategy == key.strategy
            && c.population == key.population
            && c.map == map
            && c.method == key.method
    })
}

fn thesis_max(c: &Cell) -> String {
    if c.max_at_stop {
        "≥ 99".into()
    } else {
        format!("{:.2}", c.max)
    }
}

fn pct(s: Option<Stat>, f: fn(&Stat) -> f64) -> String {
    s.map_or("–".into(), |s| format!("{:.2}", 100.0 * f(&s)))
}

fn reached(g: &GroupSummary) -> String {
    match g.steps_to_99 {
        Some(s) => format!("{}/{} ({:.0})", g.reached_99, g.runs, s.avg),
        None => format!("0/{}", g.runs),
    }
}

/// `thesis.md` for the experiment `name`: per map and set-up (strategy, population,
/// robots), one row per method with the thesis's average, min and max next to ours (the
/// thesis's objective), the difference of the averages, then Papillon's (the efficient
/// objective); `None` when `name` is not a thesis experiment.
pub fn markdown(name: &str, records: &[RunRecord]) -> Option<String> {
    let (_, title) = tables_of(name)?;
    let groups = summarize(records);
    // (map, strategy, k, population, robots, method) -> objective -> group.
    type Row = (String, String, usize, usize, usize, String);
    let mut rows: BTreeMap<Row, BTreeMap<String, &GroupSummary>> = BTreeMap::new();
    for g in &groups {
        let k = &g.key;
        rows.entry((
            k.map.clone(),
            k.strategy.clone(),
            k.targets,
            k.population,
            k.robots,
            k.method.clone(),
        ))
        .or_default()
        .insert(k.objective.clone(), g);
    }
    let mut out = String::new();
    let _ = writeln!(out, "# `{name}`: the thesis side by side ({title})\n");
    let _ = writeln!(
        out,
        "Final exploration rate [%] (average, min, max over the runs). **thesis**: the thesis's \
         table (Bendahmane 2023; \"≥ 99\": the run reached the 99 % stop); **ours**: this \
         reproduction (the thesis's objective, slip, laser, hyper-parameters and seeds); \
         **Δ**: ours − thesis (averages, points); **Papillon**: the same runs with Papillon's \
         default (efficient) objective. \"to 99 %\": runs that reached the 99 % stop (mean \
         steps to it). Our missions stop at 99 %, so our rates are censored there. Realistic \
         odometry with localisation: pending issue 18.\n"
    );
    let mut section = None;
    for ((map, strategy, targets, pop, robots, method), by_obj) in &rows {
        let head = (map.clone(), strategy.clone(), *targets, *pop, *robots);
        if section.as_ref() != Some(&head) {
            let kind = MapKind::of_label(map).map_or("not a thesis map", MapKind::name);
            let _ = writeln!(
                out,
                "\n## {map} ({kind}), {strategy}-term (k = {targets}), population {pop}, {robots} robot(s)\n"
            );
            let _ = writeln!(
                out,
                "| method | thesis avg | ours avg | Δ | thesis min | ours min | thesis max | ours max | ours to 99 % | Papillon avg | min | max | Papillon to 99 % | realistic odometry + localisation |"
            );
            let _ = writeln!(
                out,
                "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|"
            );
            section = Some(head);
        }
        let ours = by_obj.get("thesis").copied();
        let papillon = by_obj.get("efficient").copied();
        let key = ours.or(papillon).map(|g| &g.key);
        let cell = key.and_then(|k| cell_for(name, k));
        let ours_cov = ours.and_then(|g| g.coverage);
        let (t_avg, t_min, t_max, delta) = match cell {
            Some(c) => (
                format!("{:.2}", c.avg),
                format!("{:.2}", c.min),
                thesis_max(c),
                ours_cov.map_or("–".into(), |s| {
                    format!("{:+.2}", 100.0 * s.avg - f64::from(c.avg))
                }),
            ),
            None => ("not given".into(), "–".into(), "–".into(), "–".into()),
        };
        let _ = writeln!(
            out,
            "| {method} | {t_avg} | {} | {delta} | {t_min} | {} | {t_max} | {} | {} | {} | {} | {} | {} | pending issue 18 |",
            pct(ours_cov, |s| s.avg),
            pct(ours_cov, |s| s.min),
            pct(ours_cov, |s| s.max),
            ours.map_or("–".into(), reached),
            pct(papillon.and_then(|g| g.coverage), |s| s.avg),
            pct(papillon.and_then(|g| g.coverage), |s| s.min),
            pct(papillon.and_then(|g| g.coverage), |s| s.max),
            papillon.map_or("–".into(), reached),
        );
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_table_has_its_rows() {
        let count = |t: &str| CELLS.iter().filter(|c| c.table == t).count();
        assert_eq!(count("4.2"), 28);
        assert_eq!(count("4.3"), 3);
        assert_eq!(count("4.4"), 14);
        assert_eq!(count("4.5"), 5);
        for c in CELLS {
            assert!(c.min <= c.avg && c.avg <= c.max, "{c:?}");
        }
    }

    #[test]
    fn every_experiment_is_a_sweep_whose_groups_find_their_cells() {
        let maps = ["map-empty.csv".to_string(), "map-house.csv".to_string()];
        for name in EXPERIMENTS {
            let s = sweep(name, 2, &maps).unwrap();
            s.check().unwrap();
            assert_eq!(s.objective_list(), vec!["thesis", "efficient"]);
            assert_eq!(s.preset_list(), vec!["thesis"]);
            let with_cell = s
                .specs()
                .iter()
                .filter(|spec| {
                    let key = GroupKey {
                        objective: spec.objective.clone(),
                        preset: spec.preset.clone(),
                        map: spec.map_label.clone(),
                        method: spec.method.clone(),
                        strategy: spec.strategy.clone(),
                        targets: spec.targets,
                        population: spec.population,
                        robots: spec.robots,
                    };
                    cell_for(name, &key).is_some()
                })
                .count();
            if name == "thesis-multi-robot" {
                assert_eq!(with_cell, 0);
            } else {
                assert_eq!(with_cell, s.len(), "{name}: every run has a thesis cell");
            }
        }
        // BOA, House, pop 5, short: three tables, three numbers (the thesis's contradiction);
        // each experiment takes its own.
        let key = GroupKey {
            objective: "thesis".into(),
            preset: "thesis".into(),
            map: "map-house".into(),
            method: "boa".into(),
            strategy: "short".into(),
            targets: 1,
            population: 5,
            robots: 1,
        };
        assert_eq!(cell_for("thesis-population", &key).unwrap().avg, 86.11);
        assert_eq!(cell_for("thesis-pop5", &key).unwrap().avg, 87.13);
        assert_eq!(cell_for("thesis-boa-variants", &key).unwrap().avg, 89.11);
    }
}
