//! One exploration decision on a mid-mission snapshot of the project's House world: xBOA with
//! population 5 and 20 (30 generations, k = 1) and the two frontier selectors.
//!
//! The snapshot is the fixture `fixtures/house-mid-mission.yaml` (240 x 240 cells at 10 cm;
//! cells within 6 m of the robot at (1.5 m, 1.5 m) known, the rest Unknown; see
//! `fixtures/README.md` and `sim-host/examples/house_snapshot.rs`, which regenerates it).
//!
//! Run: `cargo bench -p papillon --no-default-features --features std --bench explore --
//! --warm-up-time 1 --measurement-time 3`

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, FrontierUtility, NearestFrontier, Optimized,
    TargetSelector, ViewCache,
};
use papillon::frontier::FrontierWorkspace;
use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::mapfile::read_map;
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::LaserConfig;

const SIDE: usize = 240;
const CELLS: usize = SIDE * SIDE;

fn snapshot() -> (Box<OccupancyGrid<CELLS>>, Box<Traversability<CELLS>>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/house-mid-mission.yaml");
    let map = read_map(&path).expect("House snapshot fixture");
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(map.geometry, LogOddsBounds::default())
        .expect("fixture fits the grid");
    map.load_into(&mut grid).expect("fixture fits the grid");
    let mut trav =
        Traversability::<CELLS>::new_boxed(map.geometry, TraversabilityConfig::default()).unwrap();
    trav.rebuild_from(&grid).unwrap();
    (grid, trav)
}

fn bench(c: &mut Criterion) {
    let (grid, trav) = snapshot();
    let laser = LaserConfig::thesis();
    let req = DecisionRequest {
        grid: &grid,
        trav: &trav,
        pose: Pose2::new(1.5, 1.5, 0.0),
        battery_steps: 60.0,
        laser: &laser,
    };
    let mut field = DistanceField::<CELLS>::new_boxed();
    let mut astar = AStar::<CELLS>::new_boxed();
    let mut stamps = vec![0u32; CELLS];
    let mut views = ViewCache::new_boxed();
    let mut ws = FrontierWorkspace::<8192, 256>::new_boxed();
    let mut group = c.benchmark_group("explore_decision");
    {
        let mut obj =
            ExploreObjective::with_view_cache(&mut field, &mut astar, &mut stamps, &mut views);
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
    let mut obj = ExploreObjective::new(&mut field, &mut astar, &mut stamps);
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
