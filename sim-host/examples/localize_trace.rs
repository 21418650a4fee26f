//! Traces one house mission with scan matching on: every 5 s of simulated time (and every
//! scan of the first 3 s), the estimate's and the raw odometry's errors against the true pose,
//! the matcher's counters and its last match's quality.
//!
//! Run: `cargo run --release -p papillon-sim --example localize_trace -- SEED [none|realistic]`

use papillon::geometry::normalize_angle;
use papillon::mission::MissionConfig;
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{RunConfig, Runner};
use papillon_sim::world::World;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(25);
    let world = World::load("house", 0.1).unwrap();
    let mut m = MissionConfig::default();
    m.localize.enabled = true;
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    if let Some(v) = env("LOC_SM") {
        m.localize.match_sigma_m = v;
    }
    if let Some(v) = env("LOC_SR") {
        m.localize.match_sigma_rad = v;
    }
    if let Some(v) = env("LOC_WR") {
        m.localize.matcher.weight_range_m = v;
    }
    if let Some(v) = env("LOC_VM") {
        m.localize.odometry_var_m2_per_m = v;
    }
    if let Some(v) = env("LOC_VR") {
        m.localize.odometry_var_rad2_per_rad = v;
    }
    if let Some(v) = env("LOC_N") {
        m.localize.every_n_scans = v as u32;
    }
    let quiet = std::env::var("QUIET").is_ok();
    let mut cfg = RunConfig::new(m, 1, seed);
    cfg.body.slip = if args.get(2).map(|s| s.as_str()) == Some("none") {
        SlipConfig::none()
    } else {
        SlipConfig::realistic()
    };
    let mut r = Runner::new(world, Dynamics::new(), cfg).unwrap();
    let mut last = -1.0;
    let mut last_trusted = 0;
    while !r.finished() {
        r.advance().unwrap();
        let t = r.sim_time_s();
        if !quiet && (t - last >= 5.0 || t < 3.0) {
            last = t;
            let b = r.body(0);
            let ms = r.mission(0);
            let tp = b.true_pose();
            let e = ms.pose_map();
            let o = b.odometry_in_map();
            let l = ms.localizer();
            println!(
                "t {:7.1} err {:.3} m {:6.2} deg | odo {:.2} m {:6.1} deg | trusted {}/{} (+{}) last {:?}",
                t,
                e.position().distance(tp.position()),
                normalize_angle(e.theta - tp.theta).to_degrees(),
                o.position().distance(tp.position()),
                normalize_angle(o.theta - tp.theta).to_degrees(),
                l.trusted(),
                l.matches(),
                l.trusted() - last_trusted,
                l.last().map(|q| (
                    q.constrained,
                    q.score,
                    q.known_fraction,
                    q.distrust,
                    q.correction,
                    q.eigenvalues
                ))
            );
            last_trusted = l.trusted();
        }
    }
    let b = r.body(0);
    let ms = r.mission(0);
    let tp = b.true_pose();
    let e = ms.pose_map();
    let rep = r.report();
    println!(
        "seed {seed} final err {:.3} m {:.2} deg coverage {:.1} % map acc {:.1} % t {:.0}",
        e.position().distance(tp.position()),
        normalize_angle(e.theta - tp.theta).to_degrees(),
        100.0 * rep.coverage,
        100.0 * rep.map_accuracy.accuracy,
        r.sim_time_s()
    );
}
