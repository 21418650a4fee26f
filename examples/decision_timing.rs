//! Wall-clock time of one exploration decision on the House snapshot (the decision of
//! `benches/explore.rs`), repeated in one process: the minimum approaches an unloaded core
//! on a shared machine, the median shows the load. Also times `ExploreObjective::prepare`
//! (the distance-field sweep and the caches' per-decision passes) and prints the caches'
//! counters of one decision.
//!
//! Run: `cargo run --release --example decision_timing --no-default-features --features std`

use std::path::Path;
use std::time::{Duration, Instant};

use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, Optimized, TargetSelector, ViewCache,
};
use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::mapfile::read_map;
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::LaserConfig;

const CELLS: usize = 240 * 240;
const RUNS: usize = 40;

fn min_median(mut t: Vec<Duration>) -> (Duration, Duration) {
    t.sort();
    (t[0], t[t.len() / 2])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/house-mid-mission.yaml");
    let map = read_map(&path)?;
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(map.geometry, LogOddsBounds::default())?;
    map.load_into(&mut grid)?;
    let mut trav =
        Traversability::<CELLS>::new_boxed(map.geometry, TraversabilityConfig::default())?;
    trav.rebuild_from(&grid)?;
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
    let mut obj =
        ExploreObjective::with_view_cache(&mut field, &mut astar, &mut stamps, &mut views);
    for pop in [5usize, 20] {
        let config = ExploreConfig {
            population: pop,
            max_generations: 30,
            ..ExploreConfig::default()
        };
        let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
        sel.decide(&req, &mut seeded(1))?;
        let mut times = Vec::new();
        for _ in 0..RUNS {
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
    for _ in 0..RUNS {
        let t = Instant::now();
        obj.prepare(&req, &ExploreConfig::default())?;
        times.push(t.elapsed());
    }
    let (min, median) = min_median(times);
    println!("prepare: min {min:.2?} median {median:.2?}");
    Ok(())
}
