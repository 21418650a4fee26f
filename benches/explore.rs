//! One exploration decision on a mid-mission snapshot of the project's House world: xBOA with
//! population 5 and 20 (30 generations, k = 1) on the default (efficient) objective, population 5
//! on the thesis's objective, and the two frontier selectors.
//!
//! The snapshot is the fixture `fixtures/house-mid-mission.yaml` (240 x 240 cells at 10 cm;
//! cells within 6 m of the robot at (1.5 m, 1.5 m) known, the rest Unknown; see
//! `fixtures/README.md` and `sim-host/examples/house_snapshot.rs`, which regenerates it).
//!
//! Run: `cargo bench -p papillon --no-default-features --features std --bench explore --
//! --warm-up-time 1 --measurement-time 3`

#[path = "../tests/house_fixture/mod.rs"]
mod house_fixture;

use criterion::{Criterion, criterion_group, criterion_main};
use house_fixture::{DecisionMemory, HouseSnapshot};
use papillon::explore::{
    ExploreConfig, FrontierUtility, NearestFrontier, ObjectiveKind, Optimized, TargetSelector,
};
use papillon::frontier::FrontierWorkspace;
use papillon::optim::Method;
use papillon::random::seeded;

fn bench(c: &mut Criterion) {
    let house = HouseSnapshot::load();
    let req = house.request();
    let mut memory = DecisionMemory::new();
    let mut ws = FrontierWorkspace::<8192, 256>::new_boxed();
    let mut group = c.benchmark_group("explore_decision");
    {
        let mut obj = memory.cached();
        for pop in [5usize, 20] {
            let config = ExploreConfig {
                population: pop,
                max_generations: 30,
                ..ExploreConfig::default()
            };
            let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
            group.bench_function(format!("xboa_pop{pop}_gen30"), |b| {
                b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
            });
        }
        {
            // The thesis's objective (`--objective thesis`): the decision before issue 17.
            let config = ExploreConfig {
                objective: ObjectiveKind::Thesis,
                population: 5,
                max_generations: 30,
                ..ExploreConfig::default()
            };
            let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
            group.bench_function("xboa_pop5_gen30_thesis", |b| {
                b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
            });
        }
        {
            let mut sel = NearestFrontier::new(ExploreConfig::default(), &mut obj, &mut ws);
            group.bench_function("nearest_frontier", |b| {
                b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
            });
        }
        {
            let mut sel = FrontierUtility::new(ExploreConfig::default(), &mut obj, &mut ws);
            group.bench_function("frontier_utility", |b| {
                b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
            });
        }
    }
    // Baseline: the traced model (every beam of every viewpoint traced from its exact pose),
    // with the same remembered evaluations.
    let mut obj = memory.traced();
    let config = ExploreConfig::default();
    let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
    group.bench_function("xboa_pop5_gen30_traced", |b| {
        b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
