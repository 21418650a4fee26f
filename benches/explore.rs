//! One exploration decision on a mid-mission snapshot of the project's House world: xBOA with
//! population 5 and 20 (30 generations, k = 1) on the default (efficient) objective, population 5
//! on the thesis's objective, and the two frontier selectors.
//!
//! The snapshot is the fixture `fixtures/house-mid-mission.yaml` (240 x 240 cells at 10 cm;
//! cells within 6 m of the robot at (1.5 m, 1.5 m) known, the rest Unknown; see
//! `fixtures/README.md` and `sim-host/examples/house_snapshot.rs`, which regenerates it).
//!
//! Group `explore_decision_big_map` (issue 24): the same snapshot laid into the south-west
//! corner of an all-Unknown map of 240² and of 960² cells (the rest of the map space the robot
//! has never seen), one xBOA decision (population 5, 30 generations) on each: what a decision
//! costs as the *map* grows while the *explored* region stays the same (the instruction counts
//! of `sim-host/examples/scale_cost.rs`, timed here).
//!
//! Run: `cargo bench -p papillon --no-default-features --features std --bench explore --
//! --warm-up-time 1 --measurement-time 3`

#[path = "../tests/house_fixture/mod.rs"]
mod house_fixture;

use criterion::{Criterion, criterion_group, criterion_main};
use house_fixture::{DecisionMemory, HouseSnapshot};
use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, FrontierUtility, NearestFrontier,
    ObjectiveKind, Optimized, TargetSelector, ViewCache,
};
use papillon::frontier::FrontierWorkspace;
use papillon::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
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

/// One xBOA decision (population 5, 30 generations) from the House snapshot laid into the
/// south-west corner of an all-Unknown `SIDE` x `SIDE` map (`N` = `SIDE²` cells).
fn big_map_decision<const N: usize>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    house: &HouseSnapshot,
    side: usize,
) {
    let small = *house.grid.geometry();
    let g =
        GridGeometry::new(side, side, small.resolution_m, small.origin).expect("a valid geometry");
    let mut grid = OccupancyGrid::<N>::new_boxed(g, LogOddsBounds::default())
        .expect("the map fits its capacity");
    for i in 0..small.cell_count() {
        let (col, row) = (i % small.width, i / small.width);
        grid.set_log_odds(row * side + col, house.grid.log_odds_at(i), &mut ());
    }
    let mut trav = Traversability::<N>::new_boxed(g, TraversabilityConfig::default())
        .expect("default traversability settings are valid");
    trav.rebuild_from(&grid).expect("same geometry");
    let small_req = house.request();
    let req = DecisionRequest {
        grid: &grid,
        trav: &trav,
        pose: small_req.pose,
        battery_steps: small_req.battery_steps,
        laser: small_req.laser,
    };
    let mut field = DistanceField::<N>::new_boxed();
    let mut astar = AStar::<N>::new_boxed();
    let mut stamps = vec![0u32; N];
    let mut views = ViewCache::new_boxed();
    let mut obj =
        ExploreObjective::with_view_cache(&mut field, &mut *astar, &mut stamps, &mut views);
    let config = ExploreConfig {
        population: 5,
        max_generations: 30,
        ..ExploreConfig::default()
    };
    let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
    group.bench_function(format!("xboa_pop5_gen30_{side}x{side}"), |b| {
        b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
    });
}

fn bench_big_map(c: &mut Criterion) {
    let house = HouseSnapshot::load();
    let mut group = c.benchmark_group("explore_decision_big_map");
    big_map_decision::<{ 240 * 240 }>(&mut group, &house, 240);
    big_map_decision::<{ 960 * 960 }>(&mut group, &house, 960);
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench, bench_big_map
}
criterion_main!(benches);
