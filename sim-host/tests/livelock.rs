//! Missions make progress or end (issue 17): no method runs into the runner's time limit on
//! the house. Each optimizer at population 20 (short-term) and xBOA long-term (k = 3), seeds
//! 25..34, the CLI's defaults otherwise (thesis slip, the mission's battery). A mission that
//! keeps deciding and re-planning without reaching its targets ends on the time limit
//! (issue 17: GWO, population 20, seed 27 once made 3280 decisions and ended so at 93 %).
//!
//! Slow (110 missions: both tests together 110 s in a release build on the shared 2-core
//! machine, 2026-11-27), so ignored by default:
//! `cargo test --release -p papillon-sim --test livelock -- --ignored --test-threads 1`.
//! One fast test (not ignored) runs a generated plan with a precise laser that used to
//! livelock: a target whose predicted gain never came, chosen every control period.

use clap::Parser;
use papillon::mission::SelectorKind;
use papillon::optim::Method;
use papillon_sim::cli::mission::{Args, setup_from_args};
use papillon_sim::dynamic::Dynamics;
use papillon_sim::runner::{EndReason, Runner};
use papillon_sim::scenario::{ScenarioSpec, Setup, Strategy};

const SEEDS: std::ops::RangeInclusive<u64> = 25..=34;

/// Runs one mission; returns a line describing it when it ended on the time limit.
fn time_limited(spec: &ScenarioSpec) -> Option<String> {
    let setup = Setup::new(spec).unwrap();
    let mut runner = Runner::new(setup.world.clone(), Dynamics::new(), setup.run.clone()).unwrap();
    let report = runner.run().unwrap();
    (report.reason == Some(EndReason::TimeLimit)).then(|| {
        format!(
            "{} pop {} k {:?} seed {}: time limit at {:.1} % after {} decisions, {} re-plans",
            setup.method(),
            spec.population,
            spec.targets,
            spec.seed,
            report.coverage * 100.0,
            report.decisions(),
            report.replans()
        )
    })
}

#[test]
#[ignore = "slow: 100 missions at population 20 (about 1.5 min in a release build)"]
fn every_optimizer_at_population_20_finishes_on_the_house() {
    let mut stuck = Vec::new();
    for method in Method::ALL {
        for seed in SEEDS {
            let spec = ScenarioSpec {
                selector: SelectorKind::Optimized(method),
                population: 20,
                seed,
                ..ScenarioSpec::default()
            };
            stuck.extend(time_limited(&spec));
        }
    }
    assert!(stuck.is_empty(), "{stuck:#?}");
}

#[test]
#[ignore = "slow: 10 long-term missions (about 20 s in a release build)"]
fn a_long_term_mission_finishes_on_the_house() {
    let mut stuck = Vec::new();
    for seed in SEEDS {
        let spec = ScenarioSpec {
            strategy: Strategy::Long,
            targets: Some(3),
            seed,
            ..ScenarioSpec::default()
        };
        stuck.extend(time_limited(&spec));
    }
    assert!(stuck.is_empty(), "{stuck:#?}");
}

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: Args,
}

/// gen-10 seed 25 with the thesis slide and a precise laser (docs/experiments.md, "What
/// realistic defaults would do"): on main before the fix the robot stood at a target whose
/// predicted 42 cells never came and chose it again every control period (12 282 decisions
/// in the first 1500 s, 53 282 to the time limit).
#[test]
fn a_target_that_gains_nothing_is_not_chosen_again_and_again() {
    let cli = Cli::parse_from([
        "livelock",
        "--map",
        "gen-10",
        "--seed",
        "25",
        "--slip",
        "thesis",
        "--laser-noise",
        "0.003",
    ]);
    let mut setup = setup_from_args(&cli.args).unwrap();
    setup.run.max_sim_time_s = 1500.0;
    let mut runner = Runner::new(setup.world.clone(), Dynamics::new(), setup.run.clone()).unwrap();
    let report = runner.run().unwrap();
    let decisions = report.robots[0].decisions;
    // A real mission decides every few seconds (the built-in maps: about one per 10 s); one
    // per simulated second is a robot deciding instead of exploring.
    assert!(
        f64::from(decisions) < report.sim_time_s,
        "{decisions} decisions in {:.0} s (reason {:?}, coverage {:.3})",
        report.sim_time_s,
        report.reason,
        report.coverage
    );
}
