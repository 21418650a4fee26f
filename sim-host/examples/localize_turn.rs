//! The minimal localisation experiment: a robot turning in place at the house's start with
//! exact poses. Each scan is matched at the true pose against the map drawn so far, then
//! integrated (open loop: at the truth; closed: at the matched pose). Prints the mean and
//! spread of the corrections; with an unbiased matcher the mean is ~0.
//!
//! Run: `cargo run --release -p papillon-sim --example localize_turn -- [open|closed] [noise] [depth_per_sigma] [turn_rad_per_scan]`

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
    let depth: f32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(1.0);
    let turn: f32 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let world = World::load("house", 0.1).unwrap();
    let m = MissionConfig::default();
    let mut laser_cfg = m.laser;
    laser_cfg.noise_fraction = noise;
    let mut laser = LaserSim::new(laser_cfg, 7);
    laser.set_noise(noise > 0.0);
    let mut grid: Box<OccupancyGrid<DEFAULT_CELL_CAPACITY>> =
        OccupancyGrid::new_boxed(*world.geometry(), m.grid_bounds).unwrap();
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    let _ = depth;
    let mut cfg = MatchConfig::default();
    if let Some(w) = std::env::var("WR").ok().and_then(|v| v.parse::<f32>().ok()) {
        cfg.weight_range_m = w;
    }
    if let Some(w) = std::env::var("SIG").ok().and_then(|v| v.parse::<f32>().ok()) {
        cfg.sigma_m = w;
    }
    let mut hits: Box<HitMap<DEFAULT_CELL_CAPACITY>> = Box::new(bytemuck_zeroed());
    hits.set_up_zeroed(*world.geometry());
    let start = world.start();
    let mut est = start;
    let (mut sum, mut sum2, mut n) = ([0.0f64; 3], [0.0f64; 3], 0);
    for k in 0..250 {
        let truth = Pose2::new(start.x, start.y, start.theta + turn * k as f32);
        let scan = laser.scan(&world, truth, &[]);
        let predicted = if closed {
            Pose2::new(est.x, est.y, truth.theta + (est.theta - start.theta - turn * (k as f32 - 1.0)).max(-10.0))
        } else {
            truth
        };
        let _ = predicted;
        let at = if closed { Pose2::new(est.x, est.y, normalize_angle(est.theta + turn)) } else { truth };
        let mut pose = at;
        if k > 0 {
            let mut mscan = scan.clone();
            if let Some(e) = std::env::var("EDGE").ok().and_then(|v| v.parse::<usize>().ok()) {
                let n = mscan.beams().len();
                for (i, b) in mscan.beams_mut().iter_mut().enumerate() {
                    if (turn > 0.0 && i + e >= n) || (turn < 0.0 && i < e) {
                        b.range_m = None;
                    }
                }
            }
            let r = matcher.match_scan(&grid, &hits, &mscan, &laser_cfg, at, &cfg);
            if r.quality.trusted() {
                let c = r.quality.correction;
                for i in 0..3 {
                    sum[i] += c[i] as f64;
                    sum2[i] += (c[i] as f64).powi(2);
                }
                n += 1;
                pose = r.pose;
            }
            if k % 25 == 0 || k < 6 {
                let q = r.quality;
                if std::env::var("DUMP").ok().and_then(|v| v.parse::<i32>().ok()) == Some(k) { dump("/tmp/loc/k25.png", &grid, &scan, &laser_cfg, truth, r.pose); }
                println!("  score at truth {:.3} at result {:.3} pose {:?} truth {:?}", score_at(&hits, &scan, &laser_cfg, truth), score_at(&hits, &scan, &laser_cfg, r.pose), r.pose, truth);
                println!(
                    "k {k:3} corr {:+.3} {:+.3} {:+.2}deg  est err {:+.3} {:+.3} {:+.2}deg c{} s{:.2}",
                    q.correction[0],
                    q.correction[1],
                    q.correction[2].to_degrees(),
                    pose.x - truth.x,
                    pose.y - truth.y,
                    normalize_angle(pose.theta - truth.theta).to_degrees(),
                    q.constrained,
                    q.score
                );
            }
        }
        est = pose;
        let pose = if closed { pose } else { truth };
        hits.add_scan(&scan, &laser_cfg, pose);
        integrate_scan(&mut *grid, &scan, pose, &laser_cfg, &m.sensor, &mut ()).unwrap();
    }
    let end = Pose2::new(start.x, start.y, start.theta + turn * 249.0);
    println!(
        "final estimate error {:+.3} {:+.3} m {:+.2} deg",
        est.x - end.x,
        est.y - end.y,
        normalize_angle(est.theta - end.theta).to_degrees()
    );
    let nf = n as f64;
    let mean = sum.map(|s| s / nf);
    let sd: Vec<f64> = (0..3).map(|i| (sum2[i] / nf - mean[i] * mean[i]).sqrt()).collect();
    println!(
        "{n} trusted: mean {:+.4} {:+.4} m {:+.3} deg; sd {:.4} {:.4} m {:.3} deg",
        mean[0], mean[1], mean[2].to_degrees(), sd[0], sd[1], sd[2].to_degrees()
    );
}

/// Mean field value of the scan's returns at `pose`.
#[allow(dead_code)]
pub fn score_at(
    grid: &HitMap<DEFAULT_CELL_CAPACITY>,
    scan: &papillon::sensor::Scan,
    laser: &papillon::sensor::LaserConfig,
    pose: Pose2,
) -> f32 {
    use papillon::geometry::Point2;
    use papillon::localize::likelihood::LikelihoodField;
    let mut f = Box::new(LikelihoodField::<WINDOW_CELLS>::new());
    let lo = Point2::new(pose.x - 5.0, pose.y - 5.0);
    let hi = Point2::new(pose.x + 5.0, pose.y + 5.0);
    assert!(f.build(grid, lo, hi, 0.1));
    let (mut s, mut n) = (0.0, 0);
    for b in scan.beams() {
        if let Some(r) = b.range_m.filter(|r| *r < laser.max_range_m && *r >= laser.min_range_m) {
            let p = pose.transform_point(Point2::new(r * b.angle_rad.cos(), r * b.angle_rad.sin()));
            let v = f.sample(p).0;
            if std::env::var("LOW").is_ok() && v < 0.5 {
                println!("    low {v:.2} at r {r:.2} a {:.2} p ({:.3}, {:.3})", b.angle_rad, p.x, p.y);
            }
            s += v;
            n += 1;
        }
    }
    s / n as f32
}

/// Writes the map around `pose` (4 px per cell: log-odds grey) with the returns at `pose` (red)
/// and at `other` (green) to `path` as PPM.
#[allow(dead_code)]
pub fn dump(
    path: &str,
    grid: &OccupancyGrid<DEFAULT_CELL_CAPACITY>,
    scan: &papillon::sensor::Scan,
    laser: &papillon::sensor::LaserConfig,
    pose: Pose2,
    other: Pose2,
) {
    use papillon::geometry::Point2;
    let g = *grid.geometry();
    let (c0, r0) = (0i32, 0i32);
    let (w, h) = (60i32, 60i32);
    let px = 8;
    let mut img = vec![[0u8; 3]; (w * px * h * px) as usize];
    for r in 0..h {
        for c in 0..w {
            let i = (r0 + r) as usize * g.width + (c0 + c) as usize;
            let l = grid.log_odds_at(i);
            let v = (128.0 - l * 30.0).clamp(0.0, 255.0) as u8;
            for dy in 0..px {
                for dx in 0..px {
                    let y = (h - 1 - r) * px + (px - 1 - dy);
                    img[(y * w * px + c * px + dx) as usize] = [v, v, v];
                }
            }
        }
    }
    for (p, col) in [(pose, [255u8, 0, 0]), (other, [0, 200, 0])] {
        for b in scan.beams() {
            if let Some(rng) = b.range_m.filter(|r| *r < laser.max_range_m) {
                let q = p.transform_point(Point2::new(rng * b.angle_rad.cos(), rng * b.angle_rad.sin()));
                let x = ((q.x - g.origin.x) / g.resolution_m * px as f32) as i32 - c0 * px;
                let y = h * px - 1 - (((q.y - g.origin.y) / g.resolution_m * px as f32) as i32 - r0 * px);
                if x >= 0 && y >= 0 && x < w * px && y < h * px {
                    img[(y * w * px + x) as usize] = col;
                }
            }
        }
    }
    let flat: Vec<u8> = img.into_iter().flatten().collect();
    image::RgbImage::from_raw((w * px) as u32, (h * px) as u32, flat)
        .unwrap()
        .save(path)
        .unwrap();
}

fn bytemuck_zeroed<T>() -> T {
    // SAFETY: HitMap is plain data (u16 weights and a geometry of numbers); all zeroes is valid.
    unsafe { std::mem::zeroed() }
}
