//! Choosing the sweep of a bench: a named experiment (plus the thesis's own maps) or a sweep
//! file, then the overrides a caller gives (runs, maps, battery). `papillon-sim bench` maps its
//! flags onto these types.

use std::fmt;
use std::path::{Path, PathBuf};

use super::sweep::{self, EXPERIMENTS, Sweep};

/// Where a named experiment finds the thesis's `map-empty.csv` and `map-house.csv`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ThesisMaps {
    /// Look in the usual places ([`sweep::find_thesis_maps`]); none found adds none.
    Find,
    /// This directory, which must hold both files.
    In(PathBuf),
    /// Do not add them.
    Skip,
}

/// Which sweep.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// A named experiment (one of [`EXPERIMENTS`]).
    Named {
        /// Its name.
        name: String,
        /// The thesis's maps added to its maps.
        thesis_maps: ThesisMaps,
    },
    /// A sweep file (JSON, [`Sweep::from_file`]).
    File(PathBuf),
}

/// Values that replace the sweep's own; `None` keeps it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Runs per combination (a named experiment without it has [`sweep::DEFAULT_RUNS`]).
    pub runs: Option<usize>,
    /// Maps (built-in names or files).
    pub maps: Option<Vec<String>>,
    /// Battery \[steps\].
    pub battery_steps: Option<f32>,
    /// What the optimizers maximise (`efficient` or `thesis`).
    pub objective: Option<String>,
    /// The optimizers' parameter set (`thesis` or `standard`).
    pub preset: Option<String>,
    /// Hyper-parameters per method (`bench --params`, a `tune` run's `best.json`).
    pub params: Option<std::collections::BTreeMap<String, super::params::ParamMap>>,
}

/// Why no sweep could be chosen.
#[derive(Clone, Debug, PartialEq)]
pub enum SelectError {
    /// No named experiment has this name.
    UnknownExperiment(String),
    /// The thesis-maps directory lacks one of the two files.
    NoThesisMaps(PathBuf),
    /// The sweep file is unreadable or bad, or the result fails [`Sweep::check`].
    Sweep(String),
}

impl fmt::Display for SelectError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SelectError::UnknownExperiment(name) => write!(
                f,
                "unknown experiment '{name}', expected one of: {}, {}, {}, {}",
                EXPERIMENTS.join(", "),
                super::thesis::EXPERIMENTS.join(", "),
                super::thesis::ALL,
                super::sweep::ALL
            ),
            SelectError::NoThesisMaps(dir) => write!(
                f,
                "{} has no map-empty.csv and map-house.csv",
                dir.display()
            ),
            SelectError::Sweep(e) => f.write_str(e),
        }
    }
}

impl std::error::Error for SelectError {}

/// The thesis's map files `choice` asks for.
pub fn thesis_maps(choice: &ThesisMaps) -> Result<Vec<String>, SelectError> {
    match choice {
        ThesisMaps::Skip => Ok(Vec::new()),
        ThesisMaps::Find => Ok(sweep::find_thesis_maps()),
        ThesisMaps::In(dir) => {
            let found = sweep::thesis_maps_in(dir);
            if found.is_empty() {
                Err(SelectError::NoThesisMaps(dir.clone()))
            } else {
                Ok(found)
            }
        }
    }
}

/// The named experiment `name` with the thesis's maps `choice` gives and `runs` runs per
/// combination.
pub fn named(name: &str, choice: &ThesisMaps, runs: usize) -> Result<Sweep, SelectError> {
    let extra = thesis_maps(choice)?;
    Sweep::named(name, runs, &extra).ok_or_else(|| SelectError::UnknownExperiment(name.into()))
}

/// Reads a sweep file.
pub fn from_file(path: &Path) -> Result<Sweep, SelectError> {
    Sweep::from_file(path).map_err(SelectError::Sweep)
}

/// `overrides` applied to `sweep`.
pub fn apply(mut sweep: Sweep, overrides: &Overrides) -> Sweep {
    if let Some(r) = overrides.runs {
        sweep.runs = r;
    }
    if let Some(maps) = &overrides.maps {
        sweep.maps = maps.clone();
    }
    if let Some(b) = overrides.battery_steps {
        sweep.battery_steps = Some(b);
    }
    if let Some(o) = &overrides.objective {
        sweep.objective = o.clone();
        sweep.objectives.clear();
    }
    if let Some(p) = &overrides.preset {
        sweep.preset = p.clone();
        sweep.presets.clear();
    }
    if let Some(p) = &overrides.params {
        sweep.params.extend(p.clone());
    }
    sweep
}

/// Checks the overrides on their own, so that a bad one is named by its flag.
pub fn check_overrides(overrides: &Overrides) -> Result<(), SelectError> {
    let bad = |e: String| Err(SelectError::Sweep(e));
    if let Some(r) = overrides.runs
        && !(1..=sweep::MAX_RUNS).contains(&r)
    {
        return bad(format!(
            "--runs: expected 1 to {}, got {r}",
            sweep::MAX_RUNS
        ));
    }
    if let Some(b) = overrides.battery_steps
        && !(b.is_finite() && b > 0.0)
    {
        return bad(format!(
            "--battery: battery_steps must be positive, got {b}"
        ));
    }
    if let Some(o) = &overrides.objective
        && let Err(e) = crate::scenario::objective_from_name(o)
    {
        return bad(e);
    }
    if let Some(p) = &overrides.preset
        && let Err(e) = crate::scenario::preset_from_name(p)
    {
        return bad(e);
    }
    if let Some(maps) = &overrides.maps
        && (maps.is_empty() || maps.iter().any(|m| m.trim().is_empty()))
    {
        return bad("--maps: expected comma-separated world names or map files".into());
    }
    Ok(())
}

/// The sweep `source` names with `overrides` applied, checked.
pub fn select(source: &Source, overrides: &Overrides) -> Result<Sweep, SelectError> {
    let sweep = match source {
        Source::Named { name, thesis_maps } => {
            let runs = overrides
                .runs
                .unwrap_or_else(|| sweep::default_runs_for(name));
            named(name, thesis_maps, runs)?
        }
        Source::File(path) => from_file(path)?,
    };
    check_overrides(overrides)?;
    let sweep = apply(sweep, overrides);
    sweep.check().map_err(SelectError::Sweep)?;
    if overrides.maps.is_some() {
        sweep
            .check_runnable()
            .map_err(|e| SelectError::Sweep(format!("--maps: {e}")))?;
    }
    Ok(sweep)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named_source(name: &str) -> Source {
        Source::Named {
            name: name.into(),
            thesis_maps: ThesisMaps::Skip,
        }
    }

    #[test]
    fn a_named_experiment_takes_the_overrides() {
        let o = Overrides {
            runs: Some(2),
            maps: Some(vec!["lab".into()]),
            battery_steps: Some(50.0),
            objective: Some("thesis".into()),
            preset: Some("standard".into()),
            params: None,
        };
        let s = select(&named_source("boa-variants"), &o).unwrap();
        assert_eq!((s.runs, s.maps.clone()), (2, vec!["lab".to_string()]));
        assert_eq!(s.battery_steps, Some(50.0));
        assert_eq!(s.objective, "thesis");
        assert_eq!(s.preset_list(), vec!["standard"]);
        assert!(s.specs().iter().all(|r| r.preset == "standard"));
        let d = select(&named_source("boa-variants"), &Overrides::default()).unwrap();
        assert_eq!(d.runs, sweep::DEFAULT_RUNS);
        assert_eq!(d.objective, "efficient");
        assert_eq!(d.maps, vec!["house", "empty"]);
        assert_eq!(d.preset, papillon::explore::DEFAULT_PRESET.name());
    }

    #[test]
    fn bad_choices_say_what_is_wrong() {
        let e = select(&named_source("nope"), &Overrides::default()).unwrap_err();
        assert!(matches!(e, SelectError::UnknownExperiment(_)));
        assert!(e.to_string().contains("boa-variants"), "{e}");
        let dir = std::env::temp_dir().join(format!("papillon-no-maps-{}", std::process::id()));
        let e = thesis_maps(&ThesisMaps::In(dir.clone())).unwrap_err();
        assert_eq!(e, SelectError::NoThesisMaps(dir));
        let bad = Overrides {
            battery_steps: Some(-1.0),
            ..Overrides::default()
        };
        let e = select(&named_source("methods"), &bad).unwrap_err();
        assert!(e.to_string().contains("battery_steps"), "{e}");
        let bad_objective = Overrides {
            objective: Some("thesys".into()),
            ..Overrides::default()
        };
        let e = select(&named_source("methods"), &bad_objective).unwrap_err();
        assert!(e.to_string().contains("--objective"), "{e}");
        let bad_preset = Overrides {
            preset: Some("pygmo".into()),
            ..Overrides::default()
        };
        let e = select(&named_source("methods"), &bad_preset).unwrap_err();
        assert!(e.to_string().contains("--preset"), "{e}");
        let e = select(&Source::File("/nonexistent/s.json".into()), &bad).unwrap_err();
        assert!(e.to_string().contains("cannot read"), "{e}");
    }
}
