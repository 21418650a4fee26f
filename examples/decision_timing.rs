//! Wall-clock time of one exploration decision on the House snapshot (the decision of
//! `benches/explore.rs`), repeated in one process: the minimum approaches an unloaded core
//! on a shared machine, the median shows the load. Also times `ExploreObjective::prepare`
//! (the distance-field sweep and the caches' per-decision passes) and prints the caches'
//! counters of one decision.
//!
//! Run: `cargo run --release --example decision_timing --no-default-features --features std`
//! (`DECISION_TIMING_RUNS=2` for fewer repetitions, e.g. under `valgrind --tool=callgrind`;
//! `DECISION_TIMING_POPULATION=5` for one population only; `DECISION_TIMING_SHOW=1` to print
//! each decision, to check that a change of speed left it unchanged).

use std::time::{Duration, Instant};

#[path = "../tests/house_fixture/mod.rs"]
mod house_fixture;

use house_fixture::{DecisionMemory, HouseSnapshot};
use papillon::explore::{ExploreConfig, Optimized, TargetSelector};
use papillon::optim::Method;
use papillon::random::seeded;

/// Timed decisions per configuration, unless `DECISION_TIMING_RUNS` says otherwise.
const RUNS: usize = 40;

fn runs() -> usize {
    std::env::var("DECISION_TIMING_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&n| n > 0)
        .unwrap_or(RUNS)
}

fn min_median(mut t: Vec<Duration>) -> (Duration, Duration) {
    t.sort();
    (t[0], t[t.len() / 2])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let house = HouseSnapshot::load();
    let req = house.request();
    let mut memory = DecisionMemory::new();
    let mut obj = memory.cached();
    let runs = runs();
    let only: Option<usize> = std::env::var("DECISION_TIMING_POPULATION")
        .ok()
        .and_then(|v| v.parse().ok());
    for pop in [5usize, 20] {
        if only.is_some_and(|p| p != pop) {
            continue;
        }
        let config = ExploreConfig {
            population: pop,
            max_generations: 30,
            ..ExploreConfig::default()
        };
        let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
        let outcome = sel.decide(&req, &mut seeded(1))?;
        if std::env::var_os("DECISION_TIMING_SHOW").is_some() {
            println!("xboa pop {pop} gen 30 decides: {outcome:?}");
        }
        let mut times = Vec::new();
        for _ in 0..runs {
            let t = Instant::now();
            sel.decide(&req, &mut seeded(1))?;
            times.push(t.elapsed());
        }
        let (min, median) = min_median(times);
        println!(
            "xboa pop {pop} gen 30: min {min:.2?} median {median:.2?}; remembered evaluations {}, {:?}",
            obj.remembered_evaluations(),
            obj.view_stats()
        );
    }
    let mut times = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        obj.prepare(&req, &ExploreConfig::default())?;
        times.push(t.elapsed());
    }
    let (min, median) = min_median(times);
    println!("prepare: min {min:.2?} median {median:.2?}");
    Ok(())
}
