//! Planner benchmarks: Papillon's A* against the `pathfinding` crate's `astar` on the same grids
//! and queries (the Moving AI arena problems; 100 random queries on a 240 x 240 house-like
//! map), and a distance-field sweep of the 240 x 240 map.
//!
//! Run: `cargo bench -p papillon --bench planner`. Each benchmark times a whole batch of
//! queries; divide by the batch size for the time per query.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use papillon::grid::Cell;
use papillon::planner::{AStar, DistanceField, Traversability};

#[path = "common/planner_maps.rs"]
mod planner_maps;

use planner_maps::*;

fn check_same_costs<const N: usize>(
    map: &Map,
    trav: &Traversability<N>,
    astar: &mut AStar<N>,
    queries: &[(Cell, Cell)],
) {
    let mut expansions = 0u64;
    for &(a, b) in queries {
        let (ours, e) = astar.path_cost(trav, a, b).unwrap();
        expansions += e as u64;
        let theirs = pathfinding_cost(map, a, b).unwrap() as f32 / ORTHO as f32;
        assert!(
            (ours - theirs).abs() < 1e-2,
            "{a:?}->{b:?}: {ours} vs {theirs}"
        );
    }
    eprintln!(
        "{} queries on {} x {}: mean {:.0} expansions, {} passable cells",
        queries.len(),
        map.width,
        map.height,
        expansions as f64 / queries.len() as f64,
        map.blocked.iter().filter(|b| !**b).count()
    );
}

fn bench_planner(c: &mut Criterion) {
    let (arena_map, arena_queries) = arena();
    let arena_trav = arena_map.traversability::<ARENA_CAP>();
    let mut arena_astar = AStar::<ARENA_CAP>::new_boxed();
    check_same_costs(&arena_map, &arena_trav, &mut arena_astar, &arena_queries);

    let house_map = house();
    let house_trav = house_map.traversability::<HOUSE_CAP>();
    let queries = house_queries(&house_map, &house_trav);
    let mut house_astar = AStar::<HOUSE_CAP>::new_boxed();
    check_same_costs(&house_map, &house_trav, &mut house_astar, &queries);

    let mut g = c.benchmark_group("arena_130_queries");
    g.bench_function("papillon_astar", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(s, t) in &arena_queries {
                sum += arena_astar.path_cost(&arena_trav, s, t).unwrap().0;
            }
            black_box(sum)
        })
    });
    g.bench_function("pathfinding_astar", |b| {
        b.iter(|| {
            let mut sum = 0u64;
            for &(s, t) in &arena_queries {
                sum += pathfinding_cost(&arena_map, s, t).unwrap() as u64;
            }
            black_box(sum)
        })
    });
    g.finish();

    let mut g = c.benchmark_group("house240_100_queries");
    g.bench_function("papillon_astar", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(s, t) in &queries {
                sum += house_astar.path_cost(&house_trav, s, t).unwrap().0;
            }
            black_box(sum)
        })
    });
    g.bench_function("pathfinding_astar", |b| {
        b.iter(|| {
            let mut sum = 0u64;
            for &(s, t) in &queries {
                sum += pathfinding_cost(&house_map, s, t).unwrap() as u64;
            }
            black_box(sum)
        })
    });
    g.finish();

    let mut field = DistanceField::<HOUSE_CAP>::new_boxed();
    let source = queries[0].0;
    c.bench_function("house240_distance_field_sweep", |b| {
        b.iter(|| black_box(field.compute(&house_trav, source).unwrap()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = bench_planner
}
criterion_main!(benches);
