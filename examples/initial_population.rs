//! Does starting xBOA partly on frontier cells help? One decision on the House snapshot
//! (`fixtures/house-mid-mission.yaml`, robot at (1.5 m, 1.5 m) facing east, 60 steps of
//! battery) per seed, 30 generations, k = 1, for populations 5 and 20 and several shares of the
//! initial population started on reachable frontier cells; prints the mean (and standard
//! deviation) over the seeds of the best predicted gain after the initial population and after
//! the last generation.
//!
//! Run: `cargo run --release --example initial_population --no-default-features --features std`

use std::path::Path;

use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, InitialPopulation, Optimized, Outcome,
    TargetSelector, ViewCache,
};
use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::mapfile::read_map;
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::LaserConfig;

const CELLS: usize = 240 * 240;
const SEEDS: u64 = 40;

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    let v = x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (x.len() as f64 - 1.0);
    (m, v.sqrt())
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
    let unknown = (CELLS - grid.counts().known()) as f64;
    println!("population | frontier share | initial best gain [cells] | final best gain [cells]");
    println!("---|---|---|---");
    for pop in [5usize, 20] {
        for share in [0.0f32, 0.5, 1.0] {
            let config = ExploreConfig {
                population: pop,
                max_generations: 30,
                ..ExploreConfig::default()
            };
            let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
            if share > 0.0 {
                sel.initial = InitialPopulation::NearFrontiers { share };
            }
            let (mut first, mut last) = (Vec::new(), Vec::new());
            for seed in 1..=SEEDS {
                let Outcome::Go(d) = sel.decide(&req, &mut seeded(seed))? else {
                    return Err("no decision".into());
                };
                first.push(-d.history[0] as f64 * unknown);
                last.push(-*d.history.last().unwrap() as f64 * unknown);
            }
            let ((m0, s0), (m1, s1)) = (mean_sd(&first), mean_sd(&last));
            println!("{pop} | {share} | {m0:.0} ± {s0:.0} | {m1:.0} ± {s1:.0}");
        }
    }
    Ok(())
}
