//! The matcher's own error in a real mission, open loop: a house mission runs with exact
//! odometry (its map drawn at the true pose); beside it, every scan is matched against a map of
//! the scans before it (occupancy grid and returns layer, drawn at the truth) from a
//! prediction the truth displaced by a random offset, and the matched pose is compared with the
//! truth. An unbiased, precise matcher ends near the truth whatever the offset; the statistics
//! name its bias (mean, in the robot's frame), its spread and its outliers (percentiles).
//!
//! Run: `cargo run --release -p papillon-sim --example localize_open -- SEED [OFFSET_M] [OFFSET_DEG]`
//! (defaults: seed 25, offsets drawn uniformly within ±0.05 m and ±1°). Environment variables
//! override the matcher's settings (SIGMA, MINRET, WR, WF, SMOOTH, BOUNDARY, GAIN) and the
//! laser's range noise (NOISE); PROFILE=1 prints, every 500 scans, where the mean field value
//! of the scan peaks around the truth (WEIGHTED=1: returns weighted as the matcher does,
//! CUBIC=1: cubic instead of bilinear interpolation, DUMPRET=1: every return's value).

use papillon::geometry::{Pose2, normalize_angle};
use papillon::grid::{DEFAULT_CELL_CAPACITY, OccupancyGrid};
use papillon::localize::{HitMap, ScanMatcher, WINDOW_CELLS};
use papillon::mission::MissionConfig;
use papillon::sensor::integrate_scan;
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{RunConfig, Runner};
use papillon_sim::world::World;

#[derive(Default)]
struct Stats {
    n: usize,
    sum: [f64; 3],
    sq: [f64; 3],
}

impl Stats {
    fn add(&mut self, c: [f32; 3]) {
        self.n += 1;
        for ((sum, sq), &c) in self.sum.iter_mut().zip(&mut self.sq).zip(&c) {
            *sum += c as f64;
            *sq += (c as f64).powi(2);
        }
    }
    fn line(&self, name: &str) -> String {
        let n = self.n.max(1) as f64;
        let m = self.sum.map(|s| s / n);
        let sd: Vec<f64> = (0..3)
            .map(|k| (self.sq[k] / n - m[k] * m[k]).max(0.0).sqrt())
            .collect();
        format!(
            "{name:>14}: n {:6} error mean along {:+.4} m across {:+.4} m th {:+.3} deg | sd {:.4} {:.4} m {:.3} deg",
            self.n,
            m[0],
            m[1],
            m[2].to_degrees(),
            sd[0],
            sd[1],
            sd[2].to_degrees()
        )
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(25);
    let off_m: f32 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let off_rad: f32 = args
        .get(3)
        .map(|s| s.parse::<f32>().unwrap())
        .unwrap_or(1.0)
        .to_radians();
    let world = World::load("house", 0.1).unwrap();
    let geom = *world.geometry();
    let mut m = MissionConfig::default();
    if let Ok(v) = std::env::var("NOISE") {
        m.laser.noise_fraction = v.parse().unwrap();
    }
    let mut cfg = m.localize.matcher;
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    if let Some(v) = env("SIGMA") {
        cfg.sigma_m = v;
    }
    if let Some(v) = env("MINRET") {
        cfg.min_return_value = v;
    }
    if let Some(v) = env("WR") {
        cfg.weight_range_m = v;
    }
    if let Some(v) = env("WF") {
        cfg.wall_fraction = v;
    }
    if let Some(v) = env("SMOOTH") {
        cfg.smooth = v > 0.0;
    }
    if let Some(v) = env("BOUNDARY") {
        cfg.boundary_m = v;
    }
    if let Some(v) = env("GAIN") {
        cfg.min_search_gain = v;
    }
    let laser = m.laser;
    let sensor = m.sensor;
    let grid_bounds = m.grid_bounds;
    let mut run = RunConfig::new(m, 1, seed);
    run.body.slip = SlipConfig::none();
    let mut r = Runner::new(world, Dynamics::new(), run).unwrap();
    let mut grid: Box<OccupancyGrid<DEFAULT_CELL_CAPACITY>> =
        OccupancyGrid::new_boxed(geom, grid_bounds).unwrap();
    let mut hits: Box<HitMap<DEFAULT_CELL_CAPACITY>> = Box::new(HitMap::new(geom));
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    // A small deterministic generator for the offsets (xorshift).
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32 * 2.0 - 1.0
    };
    let mut last_ranges: Vec<Option<f32>> = Vec::new();
    let mut last_true = r.body(0).true_pose();
    let (mut matched, mut trusted) = (0usize, 0usize);
    let mut by = [
        Stats::default(),
        Stats::default(),
        Stats::default(),
        Stats::default(),
    ];
    let (mut all_th, mut all_xy, mut before_th, mut before_xy) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    while !r.finished() {
        r.advance().unwrap();
        let scan = r.last_scan(0);
        let ranges: Vec<Option<f32>> = scan.beams().iter().map(|b| b.range_m).collect();
        if ranges == last_ranges {
            continue;
        }
        last_ranges = ranges;
        let truth = r.body(0).true_pose();
        let dth = normalize_angle(truth.theta - last_true.theta);
        let d = truth.position().distance(last_true.position());
        last_true = truth;
        if matched > 0 || grid.cell_count() == 0 {
            let predicted = Pose2::new(
                truth.x + off_m * uniform(),
                truth.y + off_m * uniform(),
                truth.theta + off_rad * uniform(),
            );
            let res = matcher.match_scan(&grid, &hits, scan, &laser, predicted, &cfg);
            if res.quality.trusted() {
                trusted += 1;
                let e = [
                    res.pose.x - truth.x,
                    res.pose.y - truth.y,
                    normalize_angle(res.pose.theta - truth.theta),
                ];
                let (s, c) = truth.theta.sin_cos();
                let k = [c * e[0] + s * e[1], -s * e[0] + c * e[1], e[2]];
                all_th.push(e[2].abs().to_degrees());
                all_xy.push(e[0].hypot(e[1]));
                before_th.push(
                    normalize_angle(predicted.theta - truth.theta)
                        .abs()
                        .to_degrees(),
                );
                before_xy.push(predicted.position().distance(truth.position()));
                let bin = if dth > 0.01 {
                    0
                } else if dth < -0.01 {
                    1
                } else if d > 0.01 {
                    2
                } else {
                    3
                };
                by[bin].add(k);
            }
        }
        if std::env::var("PROFILE").is_ok() && matched % 500 == 250 {
            profile(&hits, scan, &laser, truth, &cfg);
        }
        matched += 1;
        hits.add_scan(scan, &laser, truth);
        integrate_scan(&mut *grid, scan, truth, &laser, &sensor, &mut ()).unwrap();
    }
    let pct = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        let at = |p: f32| v[((v.len() - 1) as f32 * p) as usize];
        format!("p50 {:.3} p90 {:.3} p99 {:.3}", at(0.5), at(0.9), at(0.99))
    };
    println!(
        "seed {seed}, offsets ±{off_m} m ±{:.2} deg: {matched} scans, {trusted} trusted",
        off_rad.to_degrees()
    );
    println!(
        "|heading| deg after {} (before {})",
        pct(&mut all_th),
        pct(&mut before_th)
    );
    println!(
        "|position| m after {} (before {})",
        pct(&mut all_xy),
        pct(&mut before_xy)
    );
    for (b, name) in by
        .iter()
        .zip(["turning left", "turning right", "driving", "standing"])
    {
        println!("{}", b.line(name));
    }
}

/// Prints the mean field value of `scan`'s returns at the truth turned and shifted a little:
/// the field's optimum should be at the truth.
fn profile(
    hits: &HitMap<DEFAULT_CELL_CAPACITY>,
    scan: &papillon::sensor::Scan,
    laser: &papillon::sensor::LaserConfig,
    truth: Pose2,
    cfg: &papillon::localize::MatchConfig,
) {
    use papillon::geometry::Point2;
    use papillon::localize::likelihood::LikelihoodField;
    let mut field = Box::new(LikelihoodField::<WINDOW_CELLS>::new());
    let lo = Point2::new(truth.x - 4.8, truth.y - 4.8);
    let hi = Point2::new(truth.x + 4.8, truth.y + 4.8);
    if !field.build(hits, lo, hi, cfg.sigma_m, cfg.wall_fraction, cfg.smooth) {
        return;
    }
    let weighted = std::env::var("WEIGHTED").is_ok();
    let cubic = std::env::var("CUBIC").is_ok();
    let value = |p: Point2| {
        if cubic {
            field.sample_cubic(p).0
        } else {
            field.sample(p).0
        }
    };
    let pts: Vec<(Point2, f32)> = scan
        .beams()
        .iter()
        .filter_map(|b| {
            let r = b
                .range_m
                .filter(|r| *r >= laser.min_range_m && *r < laser.max_range_m)?;
            let w = if weighted {
                1.0 / r.max(1.0).powi(2)
            } else {
                1.0
            };
            Some((
                laser
                    .mount
                    .transform_point(Point2::new(r * b.angle_rad.cos(), r * b.angle_rad.sin())),
                w,
            ))
        })
        .collect();
    let score = |p: Pose2| {
        pts.iter()
            .map(|&(q, w)| w * value(p.transform_point(q)))
            .sum::<f32>()
            / pts.iter().map(|x| x.1).sum::<f32>()
    };
    let best = |f: &dyn Fn(i32) -> Pose2| {
        (-20..=20)
            .map(|k| (k, score(f(k))))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap()
    };
    if std::env::var("DUMPRET").is_ok() {
        for &(q, w) in &pts {
            let m0 = value(truth.transform_point(q));
            let m1 = value(Pose2::new(truth.x, truth.y - 0.1, truth.theta).transform_point(q));
            let t = truth.transform_point(q);
            println!(
                "  ret r {:.2} w {:.2} at ({:.3},{:.3}) M truth {:.3} M y-0.1 {:.3}",
                q.x.hypot(q.y),
                w,
                t.x,
                t.y,
                m0,
                m1
            );
        }
    }
    let th = best(&|k| {
        Pose2::new(
            truth.x,
            truth.y,
            truth.theta + (k as f32 * 0.1).to_radians(),
        )
    });
    let x = best(&|k| Pose2::new(truth.x + k as f32 * 0.005, truth.y, truth.theta));
    let y = best(&|k| Pose2::new(truth.x, truth.y + k as f32 * 0.005, truth.theta));
    println!(
        "profile: at truth {:.3}; best th {:+.1} deg ({:.3}), x {:+.3} m ({:.3}), y {:+.3} m ({:.3})",
        score(truth),
        th.0 as f32 * 0.1,
        th.1,
        x.0 as f32 * 0.005,
        x.1,
        y.0 as f32 * 0.005,
        y.1
    );
}
