//! The minimal localisation experiment: a robot turning in place at the house's start with
//! exact poses and the thesis laser. Each scan is matched at the true pose (open loop) or at
//! the previous estimate turned by the exact odometry (closed loop) against the map drawn so
//! far, then integrated into the occupancy grid and the returns layer at the truth (open) or
//! at the matched pose (closed). Prints the mean and spread of the corrections and the final
//! error of the estimate; with an unbiased matcher the mean correction is ~0 and the closed
//! loop stays at the truth.
//!
//! Run: `cargo run --release -p papillon-sim --example localize_turn -- [open|closed] [noise] [turn_rad_per_scan]`
//! (defaults: open, the thesis's 5 %, 0.05 rad per scan, 250 scans).

use papillon::geometry::{Pose2, normalize_angle};
use papillon::grid::{DEFAULT_CELL_CAPACITY, OccupancyGrid};
use papillon::localize::{HitMap, MatchConfig, ScanMatcher, WINDOW_CELLS};
use papillon::mission::MissionConfig;
use papillon::sensor::integrate_scan;
use papillon_sim::laser::LaserSim;
use papillon_sim::world::World;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let closed = args.get(1).map(|s| s.as_str()) == Some("closed");
    let noise: f32 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let turn: f32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let world = World::load("house", 0.1).unwrap();
    let m = MissionConfig::default();
    let mut laser_cfg = m.laser;
    laser_cfg.noise_fraction = noise;
    let mut laser = LaserSim::new(laser_cfg, 7);
    laser.set_noise(noise > 0.0);
    let geom = *world.geometry();
    let mut grid: Box<OccupancyGrid<DEFAULT_CELL_CAPACITY>> =
        OccupancyGrid::new_boxed(geom, m.grid_bounds).unwrap();
    let mut hits: Box<HitMap<DEFAULT_CELL_CAPACITY>> = HitMap::new_boxed(geom);
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    let mut cfg = MatchConfig::default();
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    if let Some(v) = env("SIGMA") {
        cfg.sigma_m = v;
    }
    if let Some(v) = env("WEIGHT_RANGE") {
        cfg.weight_range_m = v;
    }
    let mut start = world.start();
    if let (Some(x), Some(y)) = (env("START_X"), env("START_Y")) {
        start = Pose2::new(x, y, start.theta);
    }
    let mut est = start;
    let (mut sum, mut sum2, mut n) = ([0.0f64; 3], [0.0f64; 3], 0);
    let scans = 250;
    for k in 0..scans {
        let truth = Pose2::new(start.x, start.y, start.theta + turn * k as f32);
        let scan = laser.scan(&world, truth, &[]);
        let at = if closed {
            Pose2::new(est.x, est.y, normalize_angle(est.theta + turn))
        } else {
            truth
        };
        let mut pose = if k == 0 { truth } else { at };
        if k > 0 {
            let r = matcher.match_scan(&grid, &hits, &scan, &laser_cfg, at, &cfg);
            if std::env::var("VERBOSE").is_ok() {
                let q = r.quality;
                println!(
                    "{k:3} {:+.3} {:+.3} {:+.2}° c{} s{:.2} kf{:.2} n{} {:?}",
                    q.correction[0],
                    q.correction[1],
                    q.correction[2].to_degrees(),
                    q.constrained,
                    q.score,
                    q.known_fraction,
                    q.points,
                    q.eigenvalues
                );
            }
            if r.quality.trusted() {
                for (i, c) in r.quality.correction.iter().enumerate() {
                    sum[i] += *c as f64;
                    sum2[i] += (*c as f64).powi(2);
                }
                n += 1;
                pose = r.pose;
            }
        }
        est = pose;
        let mapped = if closed { pose } else { truth };
        hits.add_scan(&scan, &laser_cfg, mapped);
        integrate_scan(&mut *grid, &scan, mapped, &laser_cfg, &m.sensor, &mut ()).unwrap();
    }
    let end = Pose2::new(start.x, start.y, start.theta + turn * (scans - 1) as f32);
    let nf = (n as f64).max(1.0);
    let mean = sum.map(|s| s / nf);
    let sd: Vec<f64> = (0..3)
        .map(|i| (sum2[i] / nf - mean[i] * mean[i]).max(0.0).sqrt())
        .collect();
    println!(
        "{} loop, noise {noise}, {turn} rad/scan: {n} of {} matches trusted; correction mean \
         {:+.4} {:+.4} m {:+.3}°, sd {:.4} {:.4} m {:.3}°; final error {:+.3} {:+.3} m {:+.2}°",
        if closed { "closed" } else { "open" },
        scans - 1,
        mean[0],
        mean[1],
        mean[2].to_degrees(),
        sd[0],
        sd[1],
        sd[2].to_degrees(),
        est.x - end.x,
        est.y - end.y,
        normalize_angle(est.theta - end.theta).to_degrees()
    );
}
