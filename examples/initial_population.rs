//! Does starting xBOA partly on frontier cells help? One decision on the House snapshot
//! (`fixtures/house-mid-mission.yaml`, robot at (1.5 m, 1.5 m) facing east, 60 steps of
//! battery) per seed, 30 generations, k = 1, for populations 5 and 20 and several shares of the
//! initial population started on reachable frontier cells; prints the mean (and standard
//! deviation) over the seeds of the best predicted gain after the initial population and after
//! the last generation.
//!
//! Run: `cargo run --release --example initial_population --no-default-features --features std`

#[path = "../tests/house_fixture/mod.rs"]
mod house_fixture;

use house_fixture::{CELLS, DecisionMemory, HouseSnapshot};
use papillon::explore::{ExploreConfig, InitialPopulation, Optimized, Outcome, TargetSelector};
use papillon::optim::Method;
use papillon::random::seeded;

const SEEDS: u64 = 40;

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    let v = x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (x.len() as f64 - 1.0);
    (m, v.sqrt())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let house = HouseSnapshot::load();
    let req = house.request();
    let mut memory = DecisionMemory::new();
    let mut obj = memory.cached();
    let unknown = (CELLS - house.grid.counts().known()) as f64;
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
