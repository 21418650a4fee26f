//! The matcher's own error in a real mission, open loop: a house mission runs with exact
//! odometry (its map drawn at the true pose); beside it, every scan is matched against a map of
//! the scans before it (occupancy grid and returns layer, drawn at the truth) from a
//! prediction the truth displaced by a random offset, and the matched pose is compared with the
//! truth. An unbiased, precise matcher ends near the truth whatever the offset; the statistics
//! name its bias (mean, in the robot's frame), its spread and its outliers (percentiles).
//!
//! Run: `cargo run --release -p papillon-sim --example localize_open -- SEED [OFFSET_M] [OFFSET_DEG]`
//! (defaults: seed 25, offsets drawn uniformly within ±0.05 m and ±1°). Environment variables
//! override the matcher's settings (SIGMA, WR, WF, SMOOTH, GAIN; the refinement's BLOCK, MINW,
//! THICK, HUBER, GATE, MAXSIG; POINTS, SEARCHFIT) and the
//! laser's range noise (NOISE); PROFILE=1 prints, every 500 scans, where the mean field value
//! of the scan peaks around the truth (WEIGHTED=1: returns weighted as the matcher does,
//! CUBIC=1: cubic instead of bilinear interpolation, DUMPRET=1: every return's value).
//! NFLOOR sets the refinement's floor under a return's range noise (`sigma_floor_m`). The
//! summary also gives the spread of the means of consecutive windows of heading errors (a
//! local bias keeps them apart), the fit's own heading σ and the fraction of the prediction's
//! heading error a match keeps.
//!
//! `CLOSED=truth|estimate` runs instead a replica of the mission's tracker closed loop on
//! exact odometry (the mission's own path, drawn with matching off), every scan, with the map
//! drawn at the truth or at the tracker's estimate (INFO scales the fit's information; DEBUG=1
//! prints the error every 250 scans): the difference between the two is what the map drawn at
//! the estimate adds (docs/experiments.md, ninth measurement).

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
    if let Some(v) = env("BLOCK") {
        cfg.fine.block_half_cells = v as i32;
    }
    if let Some(v) = env("MINW") {
        cfg.fine.min_block_weight = v;
    }
    if let Some(v) = env("THICK") {
        cfg.fine.max_thickness_ratio = v;
    }
    if let Some(v) = env("HUBER") {
        cfg.fine.huber_k = v;
    }
    if let Some(v) = env("GATE") {
        cfg.fine.gate = v;
    }
    if let Some(v) = env("MAXSIG") {
        cfg.fine.max_sigma_m = v;
    }
    if let Some(v) = env("ITER") {
        cfg.fine.iterations = v as u32;
    }
    if let Some(v) = env("NFLOOR") {
        cfg.fine.sigma_floor_m = v;
    }
    if let Some(v) = env("POINTS") {
        cfg.max_points = v as usize;
    }
    if let Some(v) = env("SEARCHFIT") {
        cfg.search_below_fit = v;
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
    let mut hits: Box<HitMap<DEFAULT_CELL_CAPACITY>> = HitMap::new_boxed(geom);
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
    // Signed heading errors in scan order and the fit's own heading σ (from its information).
    let (mut signed_th, mut claimed_th): (Vec<f64>, Vec<f32>) = (Vec::new(), Vec::new());
    // The heading error after a match against the one before: 0 a matcher that removes the
    // prediction's error, 1 one that keeps it.
    let (mut slope_ab, mut slope_bb) = (0.0f64, 0.0f64);
    // CLOSED=truth|estimate: instead of the open-loop matches, a replica of the mission's
    // tracker runs closed loop on exact odometry (its default settings), and the map is drawn
    // at the truth or at its estimate; the run's heading and position errors are printed.
    let closed = std::env::var("CLOSED").ok();
    let mut tracker = papillon::localize::Tracker::new();
    let mut lcfg = papillon::localize::LocalizeConfig {
        enabled: true,
        matcher: cfg,
        ..Default::default()
    };
    if let Some(v) = env("INFO") {
        lcfg.information_scale = v;
    }
    let mut mfo = papillon::control::odometry::MapFromOdom::from_start(
        r.body(0).true_pose(),
        r.body(0).true_pose(),
    );
    let (mut c_n, mut c_sum_th, mut c_max_th, mut c_max_m) = (0usize, 0.0f64, 0.0f32, 0.0f32);
    let mut c_by = [(0usize, 0.0f64); 4];
    let mut c_prev_th = 0.0f32;
    while !r.finished() {
        r.advance().unwrap();
        let scan = r.last_scan(0);
        let ranges: Vec<Option<f32>> = scan.beams().iter().map(|b| b.range_m).collect();
        if ranges == last_ranges {
            continue;
        }
        last_ranges = ranges;
        let truth = r.body(0).true_pose();
        if let Some(at) = closed.as_deref() {
            if grid.cell_count() > 0 {
                tracker.on_scan(
                    &lcfg,
                    &grid,
                    &hits,
                    &mut matcher,
                    scan,
                    &laser,
                    truth,
                    &mut mfo,
                );
            }
            let est = mfo.map_pose(truth);
            let eth = normalize_angle(est.theta - truth.theta);
            // Where the heading error changes: by the truth's motion since the last scan.
            let turn = normalize_angle(truth.theta - last_true.theta);
            let bin = if turn > 0.005 {
                0
            } else if turn < -0.005 {
                1
            } else if truth.position().distance(last_true.position()) > 0.002 {
                2
            } else {
                3
            };
            c_by[bin].0 += 1;
            c_by[bin].1 += (eth - c_prev_th).to_degrees() as f64;
            c_prev_th = eth;
            last_true = truth;
            c_n += 1;
            c_sum_th += eth.abs().to_degrees() as f64;
            c_max_th = c_max_th.max(eth.abs().to_degrees());
            c_max_m = c_max_m.max(est.position().distance(truth.position()));
            if std::env::var("DEBUG").is_ok() && c_n % 250 == 0 {
                println!(
                    "scan {c_n} err {:.4} m {:+.3} deg",
                    est.position().distance(truth.position()),
                    eth.to_degrees()
                );
            }
            let draw = if at == "truth" { truth } else { est };
            hits.add_scan(scan, &laser, draw);
            integrate_scan(&mut *grid, scan, draw, &laser, &sensor, &mut ()).unwrap();
            continue;
        }
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
            if std::env::var("DEBUG").is_ok() && matched % 200 == 0 {
                println!("{:?}", res.quality);
            }
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
                signed_th.push(e[2].to_degrees() as f64);
                let b = normalize_angle(predicted.theta - truth.theta) as f64;
                slope_ab += e[2] as f64 * b;
                slope_bb += b * b;
                let h = res.information[2][2];
                if h > 0.0 {
                    claimed_th.push((1.0 / h.sqrt()).to_degrees());
                }
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
    if closed.is_some() {
        let est = mfo.map_pose(r.body(0).true_pose());
        let truth = r.body(0).true_pose();
        println!(
            "seed {seed} closed loop, map at the {}: final {:.4} m {:+.3} deg, run mean |heading| {:.3} deg, max {:.3} deg {:.4} m ({} matches, {} trusted)",
            closed.as_deref().unwrap_or(""),
            est.position().distance(truth.position()),
            normalize_angle(est.theta - truth.theta).to_degrees(),
            c_sum_th / c_n.max(1) as f64,
            c_max_th,
            c_max_m,
            tracker.matches(),
            tracker.trusted()
        );
        for ((n, sum), name) in
            c_by.iter()
                .zip(["turning left", "turning right", "driving", "standing"])
        {
            println!("  {name:>13}: {n:6} scans, heading error changed {sum:+.3} deg in all");
        }
        return;
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
    // Whether the errors are independent from scan to scan: the spread of the means of
    // consecutive windows against the spread of single errors over the window's root (a local
    // bias, one that holds while the robot sees the same walls, keeps the windows' means apart).
    for w in [25usize, 100, 400] {
        let means: Vec<f64> = signed_th
            .chunks_exact(w)
            .map(|c| c.iter().sum::<f64>() / w as f64)
            .collect();
        let n = signed_th.len().max(1) as f64;
        let m = signed_th.iter().sum::<f64>() / n;
        let sd = (signed_th.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt();
        let k = means.len().max(1) as f64;
        let mm = means.iter().sum::<f64>() / k;
        let sdm = (means.iter().map(|v| (v - mm).powi(2)).sum::<f64>() / k).sqrt();
        println!(
            "heading windows of {w}: sd of means {sdm:.4} deg (independent errors: {:.4})",
            sd / (w as f64).sqrt()
        );
    }
    println!("fit's own heading sigma deg {}", pct(&mut claimed_th));
    println!(
        "heading error kept from the prediction's: {:.3}",
        slope_ab / slope_bb.max(1e-30)
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
