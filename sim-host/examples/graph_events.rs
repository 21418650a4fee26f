//! Prints each pose-graph event of one mission with the pose graph on (`src/localize/graph.rs`):
//! every accepted closure and every redraw, with the simulated time, the estimate's position
//! and heading error against the true pose just before and just after the step, and the
//! graph's counters; then the summary line of `localize_trace`'s kind.
//!
//! Run: `cargo run --release -p papillon-sim --example graph_events -- SEED [none|realistic|...]`
//! (`MAP`, `NOISE` as in `localize_trace`; `GRAPH_SM`/`GRAPH_SR`: a closure's σ).

use papillon::geometry::normalize_angle;
use papillon::mission::MissionConfig;
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{RunConfig, Runner};
use papillon_sim::world::World;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(25);
    let map = std::env::var("MAP").unwrap_or_else(|_| "house".into());
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    let world = World::load(&map, 0.1).expect("a built-in map");
    let mut m = MissionConfig::default();
    m.localize.enabled = true;
    m.localize.graph.enabled = true;
    if let Some(v) = env("NOISE") {
        m.laser.noise_fraction = v;
    }
    if let Some(v) = env("GRAPH_SM") {
        m.localize.graph.closure.sigma_m = v;
    }
    if let Some(v) = env("GRAPH_SR") {
        m.localize.graph.closure.sigma_rad = v;
    }
    let mut cfg = RunConfig::new(m, 1, seed);
    cfg.body.slip = args
        .get(2)
        .and_then(|s| SlipConfig::named(s))
        .unwrap_or_else(SlipConfig::realistic);
    let mut r = Runner::new(world, Dynamics::new(), cfg).expect("a runner");
    let error = |r: &Runner| {
        let t = r.body(0).true_pose();
        let e = r.mission(0).pose_map();
        (
            e.position().distance(t.position()),
            normalize_angle(e.theta - t.theta).to_degrees(),
        )
    };
    while !r.finished() {
        let before = *r.map().graph.stats();
        let (e0, h0) = error(&r);
        r.advance().expect("a step");
        let after = *r.map().graph.stats();
        if after.closures != before.closures || after.redraws != before.redraws {
            let (e1, h1) = error(&r);
            println!(
                "t {:7.1} {}{} err {:.3} m {:6.2}° -> {:.3} m {:6.2}° | keyframes {} closures {}/{} refused {:?} largest move so far {:.3} m",
                r.sim_time_s(),
                if after.closures != before.closures {
                    "closure "
                } else {
                    ""
                },
                if after.redraws != before.redraws {
                    "redraw"
                } else {
                    ""
                },
                e0,
                h0,
                e1,
                h1,
                after.keyframes,
                after.closures,
                after.attempts,
                after.refused,
                after.max_move_m
            );
        }
    }
    let (e, h) = error(&r);
    let rep = r.report();
    println!(
        "seed {seed} final err {e:.3} m {h:.2} deg coverage {:.1} % map acc {:.1} %",
        100.0 * rep.coverage,
        100.0 * rep.map_accuracy.accuracy
    );
}
