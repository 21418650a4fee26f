//! Traces one house mission with scan matching on: every 5 s of simulated time (and every
//! scan of the first 3 s), the estimate's and the raw odometry's errors against the true pose,
//! the matcher's counters and its last match's quality.
//!
//! Run: `cargo run --release -p papillon-sim --example localize_trace -- SEED [none|full|thesis|realistic]`
//!
//! The environment sets the matcher's and the tracker's settings (`NOISE`, `MAP`, `LOC_*`,
//! read at the top of `main`; docs/experiments.md, seventh measurement, lists them);
//! `QUIET=1` prints only the last line: final error, coverage, map accuracy, and the run's
//! mean and largest position error. `WINDOW=FROM,TO` prints every scan between FROM and TO
//! seconds of simulated time; `LOC_BLOCK` (the refinement's block half-width, cells) and
//! `LOC_POINTS` (returns used at most) set two more of the matcher's settings. `ODOCHECK=1` also prints the raw odometry's largest error
//! against the truth over the run (0 with `none`: the scans and the odometry are taken at the
//! same instant and pose).
//!
//! Pose graph (`src/localize/graph.rs`): `LOC_GRAPH=1` (keyframes in a pose graph with loop
//! closure), `GRAPH_TRAVEL`/`GRAPH_TURN` (its keyframe spacing), `GRAPH_SM`/`GRAPH_SR` (a
//! closure's σ), `GRAPH_KEYREF=1` (only keyframes into the reference), `GRAPH_GATE` (closure
//! gate, σ), `GRAPH_FLOOR_M`/`GRAPH_FLOOR_RAD` (a step's least σ), `GRAPH_EVERY` (path between
//! closures), `GRAPH_RESID` (a
//! closure's largest residual after the optimisation, σ; 0: none), `GRAPH_AMB=0|1` (the closures'
//! ambiguity test, on by default; `GRAPH_AMB_D`, `GRAPH_AMB_R`: its distance and inlier ratio),
//! `GRAPH_SXY`/`GRAPH_STH` (a closure's search, m and rad each way), `GRAZE` (misses through a
//! confident wall count within this many cells of its centre; negative: every miss counts), `DIAG=1` (each closure's
//! error against the truth, with the old keyframe's true position, and each step's).
//!
//! Odometry self-calibration (`src/localize/odometry_calibration.rs`): `LOC_CAL=0` (off; on by default),
//! `CAL_RANDOM` (the share of the odometry variances kept as random), `CAL_SG`/`CAL_SK` (the
//! priors' σ of the turn gain and of the curvature, rad/m); with it on, a line before the last
//! reports the estimate against the wheels the simulator drew (`Ed`, `Eb`). `SLIP_RANDOM=F`
//! scales the slip model's random walks and fast-turn slip by `F` (0: systematic wheel errors
//! and the end-of-move slide only).
//!
//! Where the error comes from (2026-12-08): `LASER_BEAMS=N` spreads N beams over the laser's
//! field of view (the thesis's 181 by default; with more than `LOC_POINTS`, 270, raise that
//! too); `LOC_MAXSIG` sets the refinement's `max_sigma_m` (a direction is constrained when
//! pinned to this); `GRAPH_NB`, `GRAPH_MAXD`, `GRAPH_MINPATH` a closure's neighbours drawn,
//! its candidates' largest distance and least path. `MATCH_ERR=1` prints, per number of
//! constrained directions, the mean and RMS of the trusted matches' corrections in the
//! robot's frame (forward, left, heading): with `LOC_INFO=0` the map is drawn at the
//! odometry's pose, so with `none` each correction is the match's own error against a map
//! drawn at the true poses. `POSE=1` adds to each printed line a `q` line (the estimate's
//! error in the robot's frame and in the map's, the tracker's σ and heading-x correlation,
//! the last correction) and a `p` line (the true pose, the last match's known fraction and
//! constrained directions, the keyframes so far). With `ATTRIB=1`, `STEPS=FILE` writes every
//! step's heading and position error change to `FILE`.
//!
//! What in the laser's noise makes the drift (2026-12-08, second session): `SIM_SIGMA=M` adds
//! `M` metres of range noise that does not grow with the range to the simulated laser, which
//! the core is not told about (with `NOISE=0`: a laser whose noise the core ignores);
//! `LOC_MINW` and `LOC_THICK` set the refinement's `min_block_weight` and
//! `max_thickness_ratio`.
//!
//! `LOC_L` sets the matcher's length scale (`MatchConfig::length_scale_m`); `LOC_SEARCH_SEE=0`
//! turns off `MatchConfig::search_see_through` (on by default: the search's basin only if its
//! beams cross no more walls).
//! With `WINDOW`, a second line per scan gives the true, odometry and estimated heading (and distance)
//! changes since the scan before, the filter's heading σ, the fused match's heading σ and its
//! null direction `(x, y, θ·1 m)` when it constrains two directions.

use papillon::geometry::normalize_angle;
use papillon::localize::odometry_calibration::gain_and_curvature_of;
use papillon::mission::MissionConfig;
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{RunConfig, Runner};
use papillon_sim::world::World;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(25);
    let map = std::env::var("MAP").unwrap_or_else(|_| "house".into());
    let world = World::load(&map, 0.1).unwrap();
    let mut m = MissionConfig::default();
    m.localize.enabled = true;
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    if let Some(v) = env("LOC_INFO") {
        m.localize.information_scale = v;
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
    if let Some(v) = env("LOC_TRAVEL") {
        m.localize.min_travel_m = v;
    }
    if let Some(v) = env("LOC_TURN") {
        m.localize.min_turn_rad = v;
    }
    if let Some(v) = env("LOC_VRM") {
        m.localize.odometry_var_rad2_per_m = v;
    }
    if let Some(v) = env("NOISE") {
        m.laser.noise_fraction = v;
    }
    if let Some(v) = env("LASER_BEAMS") {
        // The same field of view, `v` beams.
        let span = m.laser.step_rad * f32::from(m.laser.beam_count.saturating_sub(1));
        m.laser.beam_count = v as u16;
        m.laser.step_rad = span / (v - 1.0).max(1.0);
    }
    if let Some(v) = env("LOC_MAXSIG") {
        m.localize.matcher.fine.max_sigma_m = v;
    }
    if let Some(v) = env("GRAPH_NB") {
        m.localize.graph.closure.neighbours = v as usize;
    }
    if let Some(v) = env("GRAPH_MAXD") {
        m.localize.graph.closure.max_distance_m = v;
    }
    if let Some(v) = env("GRAPH_MINPATH") {
        m.localize.graph.closure.min_path_m = v;
    }
    if let Some(v) = env("LOC_N") {
        m.localize.every_n_scans = v as u32;
    }
    if let Some(v) = env("LOC_GRAPH") {
        m.localize.graph.enabled = v != 0.0;
    }
    if let Some(v) = env("GRAPH_TRAVEL") {
        m.localize.graph.keyframe_travel_m = v;
    }
    if let Some(v) = env("GRAPH_TURN") {
        m.localize.graph.keyframe_turn_rad = v;
    }
    if let Some(v) = env("GRAPH_KEYREF") {
        m.localize.graph.reference_keyframes_only = v != 0.0;
    }
    if let Some(v) = env("GRAPH_GATE") {
        m.localize.graph.closure.gate_sigmas = v;
    }
    if let Some(v) = env("GRAPH_FLOOR_M") {
        m.localize.graph.step_floor_m = v;
    }
    if let Some(v) = env("GRAPH_FLOOR_RAD") {
        m.localize.graph.step_floor_rad = v;
    }
    if let Some(v) = env("GRAPH_EVERY") {
        m.localize.graph.closure_every_m = v;
    }
    if let Some(v) = env("GRAPH_RESID") {
        m.localize.graph.closure.residual_sigmas = v;
    }
    if let Some(v) = env("GRAPH_AMB") {
        m.localize.graph.closure.ambiguity = v != 0.0;
    }
    if let Some(v) = env("GRAPH_AMB_D") {
        m.localize.graph.closure.ambiguity_distance_m = v;
    }
    if let Some(v) = env("GRAPH_AMB_R") {
        m.localize.graph.closure.ambiguity_ratio = v;
    }
    if let Some(v) = env("GRAPH_SXY") {
        m.localize.graph.closure.search_xy_m = v;
    }
    if let Some(v) = env("GRAPH_STH") {
        m.localize.graph.closure.search_theta_rad = v;
    }
    if let Some(v) = env("GRAPH_SM") {
        m.localize.graph.closure.sigma_m = v;
    }
    if let Some(v) = env("GRAPH_SR") {
        m.localize.graph.closure.sigma_rad = v;
    }
    if let Some(v) = env("LOC_MAPAGREE") {
        m.localize.map_only_agreeing = v != 0.0;
    }
    if let Some(v) = env("LOC_ANNEAL") {
        m.localize.matcher.fine.anneal_gate_m = v;
    }
    if let Some(v) = env("LOC_BLOCK") {
        m.localize.matcher.fine.block_half_cells = v as i32;
    }
    if let Some(v) = env("LOC_POINTS") {
        m.localize.matcher.max_points = v as usize;
    }
    if let Some(v) = env("LOC_GATE") {
        m.localize.matcher.fine.gate = v;
    }
    if let Some(v) = env("LOC_MINFIT") {
        m.localize.matcher.min_fit_fraction = v;
    }
    if let Some(v) = env("LOC_RATIO") {
        m.localize.matcher.fine.min_information_ratio = v;
    }
    if let Some(v) = env("LOC_SXY") {
        m.localize.matcher.search_xy_m = v;
    }
    if let Some(v) = env("LOC_L") {
        m.localize.matcher.length_scale_m = v;
    }
    if let Some(v) = env("LOC_STH") {
        m.localize.matcher.search_theta_rad = v;
    }
    if let Some(v) = env("LOC_BELOW") {
        m.localize.matcher.search_below_fit = v;
    }
    if let Some(v) = env("LOC_NSIG") {
        m.localize.matcher.fine.normal_sigmas = v;
    }
    if let Some(v) = env("LOC_MAXN") {
        m.localize.matcher.fine.max_normal_sigma_rad = v;
    }
    if let Some(v) = env("LOC_HUBER") {
        m.localize.matcher.fine.huber_k = v;
    }
    if let Some(v) = env("LOC_CAP") {
        m.localize.max_cell_weight = v;
    }
    if let Some(v) = env("LOC_FLOOR") {
        m.localize.matcher.min_sigma_m = v;
    }
    if let Some(v) = env("LOC_SEARCH_SEE") {
        m.localize.matcher.search_see_through = v != 0.0;
    }
    if let Some(v) = env("LOC_INNOV") {
        m.localize.innovation_gate = v;
    }
    if let Some(v) = env("LOC_GRIDAGREE") {
        m.localize.grid_only_agreeing = v != 0.0;
    }
    if let Some(v) = env("LOC_KEYREF") {
        m.localize.reference_keyframes_only = v != 0.0;
    }
    if let Some(v) = env("LOC_STOPM") {
        m.localize.stop_var_m2 = v * v;
    }
    if let Some(v) = env("LOC_STOPDEG") {
        m.localize.stop_var_rad2 = v.to_radians() * v.to_radians();
    }
    if let Some(v) = env("LOC_NFLOOR") {
        m.localize.matcher.fine.sigma_floor_m = v;
    }
    if let Some(v) = env("LOC_REST") {
        m.localize.match_at_rest = v != 0.0;
    }
    if let Some(v) = env("LOC_MINW") {
        m.localize.matcher.fine.min_block_weight = v;
    }
    if let Some(v) = env("LOC_THICK") {
        m.localize.matcher.fine.max_thickness_ratio = v;
    }
    if let Some(v) = env("LOC_CAL") {
        m.localize.calibration.enabled = v != 0.0;
    }
    if let Some(v) = env("CAL_RANDOM") {
        m.localize.calibration.random_scale = v;
    }
    if let Some(v) = env("CAL_SG") {
        m.localize.calibration.turn_gain_sigma = v;
    }
    if let Some(v) = env("CAL_SK") {
        m.localize.calibration.curvature_sigma_rad_per_m = v;
    }
    if let Some(v) = env("WALL_FLOOR") {
        m.localize.wall_band_floor_m = v;
    }
    if let Some(v) = env("WALL_SIGMAS") {
        m.localize.wall_band_sigmas = v;
    }
    if let Some(v) = env("GRAZE") {
        m.localize.grazing_miss_offset_cells = (v >= 0.0).then_some(v);
    }
    let quiet = std::env::var("QUIET").is_ok();
    // WINDOW=FROM,TO: every scan between FROM and TO s of simulated time.
    let window = std::env::var("WINDOW")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once(',')?;
            Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?))
        })
        .unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
    let m_cal = m.localize.calibration.enabled;
    let mut cfg = RunConfig::new(m, 1, seed);
    let track_m = cfg.body.track_m;
    cfg.body.slip = args
        .get(2)
        .and_then(|s| SlipConfig::named(s))
        .unwrap_or_else(SlipConfig::realistic);
    if let Some(v) = env("SLIP_RANDOM") {
        // The slip model's random walks scaled (0: only the systematic wheel errors and the
        // end-of-move slide remain).
        cfg.body.slip.distance_var_m2_per_m *= v;
        cfg.body.slip.rotation_var_rad2_per_rad *= v;
        cfg.body.slip.drift_var_rad2_per_m *= v;
        cfg.body.slip.wheels.fast_turn_var_rad2_per_rad *= v;
    }
    if let Some(v) = env("SIM_SIGMA") {
        cfg.laser_range_sigma_m = v;
    }
    let mut r = Runner::new(world, Dynamics::new(), cfg).unwrap();
    let mut last = -1.0;
    let mut last_trusted = 0;
    let (mut redraw_s, mut redraw_max_s, mut redraws) = (0.0f64, 0.0f64, 0u32);
    let wall = std::time::Instant::now();
    // The true pose of each keyframe (a scan is an `advance` of its own).
    let mut key_truth = Vec::new();
    // ATTRIB=1: where the error grows. Each step's change of the position and heading error
    // is put to the robot's true motion (turning faster than 0.2 rad/s, driving, standing)
    // and to the last match (untrusted, or on ground less than 80 % known: entering new
    // ground); printed at the end with the largest heading jumps.
    let attrib = std::env::var("ATTRIB").is_ok();
    let mut prev: Option<(f64, papillon::geometry::Pose2, f32, f32)> = None;
    let mut sums: std::collections::BTreeMap<&str, (u32, f64, f64, f64)> = Default::default();
    let mut jumps: Vec<(f64, f32, f32, &str)> = Vec::new();
    let (mut err_sum, mut err_n, mut err_max) = (0.0f64, 0u64, 0.0f32);
    // The tracker's own position σ (larger axis), summed like the error for its mean.
    let mut sigma_sum = 0.0f64;
    // The raw odometry's largest error against the truth over the run (0 with `none`).
    let (mut odo_max_m, mut odo_max_rad) = (0.0f32, 0.0f32);
    // The true, odometry and estimated poses at the window's scan before.
    let mut prev_window: Option<(
        papillon::geometry::Pose2,
        papillon::geometry::Pose2,
        papillon::geometry::Pose2,
    )> = None;
    // MATCH_ERR=1: per number of constrained directions (0..=3), the trusted matches' count
    // and the sums of their corrections (forward, left, heading) and of their squares.
    let match_err = std::env::var("MATCH_ERR").is_ok();
    let mut corrections = [[0.0f64; 7]; 4];
    let mut last_counted = 0;
    let pose_lines = std::env::var("POSE").is_ok();
    while !r.finished() {
        let before = r.map().graph.stats().redraws;
        let keys = r.map().graph.keyframes().len();
        let t0 = std::time::Instant::now();
        r.advance().unwrap();
        if r.map().graph.stats().redraws != before {
            // The step that redrew the map: its time is mostly the redraw's.
            let s = t0.elapsed().as_secs_f64();
            redraw_s += s;
            redraw_max_s = redraw_max_s.max(s);
            redraws += 1;
        }
        if r.map().graph.keyframes().len() > keys {
            key_truth.push(r.body(0).true_pose());
        }
        let t = r.sim_time_s();
        {
            let tp = r.body(0).true_pose();
            let ep = r.mission(0).pose_map().position().distance(tp.position());
            err_sum += ep as f64;
            err_n += 1;
            err_max = err_max.max(ep);
            sigma_sum += f64::from(r.mission(0).localizer().position_sigma_m());
            let o = r.body(0).odometry_in_map();
            odo_max_m = odo_max_m.max(o.position().distance(tp.position()));
            odo_max_rad = odo_max_rad.max(normalize_angle(o.theta - tp.theta).abs());
        }
        if match_err
            && r.mission(0).localizer().matches() != last_counted
            && let Some(q) = r.mission(0).localizer().last()
        {
            last_counted = r.mission(0).localizer().matches();
            if q.trusted() {
                let (sin, cos) = r.body(0).true_pose().theta.sin_cos();
                let [dx, dy, dth] = q.correction;
                let c = [cos * dx + sin * dy, -sin * dx + cos * dy, dth];
                let s = &mut corrections[usize::from(q.constrained).min(3)];
                s[0] += 1.0;
                for k in 0..3 {
                    s[1 + k] += f64::from(c[k]);
                    s[4 + k] += f64::from(c[k] * c[k]);
                }
            }
        }
        if attrib {
            let tp = r.body(0).true_pose();
            let e = r.mission(0).pose_map();
            let ep = e.position().distance(tp.position());
            let eh = normalize_angle(e.theta - tp.theta);
            if let Some((t0, p0, ep0, eh0)) = prev {
                let dt = (t - t0).max(1e-3) as f32;
                let w = normalize_angle(tp.theta - p0.theta).abs() / dt;
                let v = tp.position().distance(p0.position()) / dt;
                let motion = if w > 0.2 {
                    "turning"
                } else if v > 0.05 {
                    "driving"
                } else {
                    "standing"
                };
                let ground = match r.mission(0).localizer().last() {
                    Some(q) if !q.trusted() => match q.distrust {
                        Some(papillon::localize::Distrust::MostlyUnknown) => "unt-unknown",
                        Some(papillon::localize::Distrust::PoorFit) => "unt-poorfit",
                        Some(papillon::localize::Distrust::TooFewReturns) => "unt-few",
                        _ => "unt-other",
                    },
                    Some(q) if q.known_fraction < 0.8 => "new-ground",
                    Some(_) => "known",
                    None => "none",
                };
                let key: &'static str =
                    Box::leak(format!("{motion:8} {ground:10}").into_boxed_str());
                let dh = (eh.abs() - eh0.abs()) as f64;
                let dp = (ep - ep0) as f64;
                let s = sums.entry(key).or_default();
                s.0 += 1;
                s.1 += dp;
                s.2 += dh.to_degrees();
                s.3 += (eh - eh0).abs().to_degrees() as f64;
                jumps.push((t, (eh - eh0).to_degrees(), ep - ep0, key));
            }
            prev = Some((t, tp, ep, eh));
        }
        if !quiet && (t - last >= 5.0 || t < 3.0 || (t >= window.0 && t <= window.1)) {
            last = t;
            let b = r.body(0);
            let ms = r.mission(0);
            let tp = b.true_pose();
            let e = ms.pose_map();
            let o = b.odometry_in_map();
            let l = ms.localizer();
            if pose_lines {
                let (sin, cos) = tp.theta.sin_cos();
                let (ex, ey) = (e.x - tp.x, e.y - tp.y);
                let eh = normalize_angle(e.theta - tp.theta).to_degrees();
                let cov = l.covariance();
                let sd = |i: usize| cov[i][i].max(0.0).sqrt();
                let c = l.last().map_or([0.0; 3], |q| q.correction);
                println!(
                    "q {t:7.1} fwd {:+.3} left {:+.3} dth {eh:+.3} | ex {ex:+.3} ey {ey:+.3} sx {:.3} sy {:.3} sth {:.3} cxth {:+.2} | corr {:+.4} {:+.4} {:+.3}",
                    cos * ex + sin * ey,
                    -sin * ex + cos * ey,
                    sd(0),
                    sd(1),
                    sd(2).to_degrees(),
                    cov[0][2] / (sd(0) * sd(2)).max(1e-30),
                    c[0],
                    c[1],
                    c[2].to_degrees(),
                );
                println!(
                    "p {t:7.1} true {:6.2} {:6.2} {:7.1} err {:.3} {eh:+.2} known {:.2} c {} keys {}",
                    tp.x,
                    tp.y,
                    tp.theta.to_degrees(),
                    e.position().distance(tp.position()),
                    l.last().map_or(0.0, |q| q.known_fraction),
                    l.last().map_or(0, |q| q.constrained),
                    r.map().graph.keyframes().len(),
                );
            }
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
            if t >= window.0 && t <= window.1 {
                // Per scan: the true, odometry and estimated heading changes since the scan
                // before, the filter's heading σ, the fused match's heading information and
                // its null direction (x, y, θ·1 m) when it constrains two directions.
                let (pt, po, pe) = prev_window.unwrap_or((tp, o, e));
                let d = |a: f32, b: f32| normalize_angle(a - b).to_degrees();
                let cov = l.covariance();
                let h = l.last_information();
                let rows = [
                    [h[0][0], h[0][1], h[0][2]],
                    [h[1][0], h[1][1], h[1][2]],
                    [h[2][0], h[2][1], h[2][2]],
                ];
                let cross = |a: [f32; 3], b: [f32; 3]| {
                    [
                        a[1] * b[2] - a[2] * b[1],
                        a[2] * b[0] - a[0] * b[2],
                        a[0] * b[1] - a[1] * b[0],
                    ]
                };
                let norm = |v: [f32; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                let mut null = [0.0f32; 3];
                for (i, j) in [(0, 1), (0, 2), (1, 2)] {
                    let c = cross(rows[i], rows[j]);
                    if norm(c) > norm(null) {
                        null = c;
                    }
                }
                let n = norm(null).max(1e-30);
                // Heading information net of the position (Schur complement), 1/rad².
                let det2 = h[0][0] * h[1][1] - h[0][1] * h[1][0];
                let schur = if det2.abs() > 1e-9 {
                    let (a, b, c) = (h[0][0], h[0][1], h[1][1]);
                    let (u, v) = (h[0][2], h[1][2]);
                    h[2][2] - (c * u * u - 2.0 * b * u * v + a * v * v) / det2
                } else {
                    h[2][2]
                };
                println!(
                    "  scan dθ true {:+.3} odo {:+.3} est {:+.3} deg ds true {:.4} odo {:.4} m | σθ {:.3} deg σθ(match) {:.3} deg (net of pos {:.3}) | null ({:+.2} {:+.2} {:+.2})",
                    d(tp.theta, pt.theta),
                    d(o.theta, po.theta),
                    d(e.theta, pe.theta),
                    tp.position().distance(pt.position()),
                    o.position().distance(po.position()),
                    cov[2][2].max(0.0).sqrt().to_degrees(),
                    (1.0 / h[2][2].max(1e-30)).sqrt().to_degrees(),
                    (1.0 / schur.max(1e-30)).sqrt().to_degrees(),
                    null[0] / n,
                    null[1] / n,
                    null[2] / n,
                );
                prev_window = Some((tp, o, e));
            }
        }
    }
    if attrib {
        println!(
            "motion   last match | steps | Δ|pos err| m | Δ|heading err| deg | Σ|Δ heading| deg"
        );
        for (k, (n, dp, dh, ah)) in &sums {
            println!("{k} | {n:6} | {dp:+8.3} | {dh:+8.2} | {ah:8.2}");
        }
        if let Ok(path) = std::env::var("STEPS") {
            use std::io::Write;
            let mut f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
            for (t, dh, dp, k) in &jumps {
                writeln!(
                    f,
                    "{t:.1} {dh:.5} {dp:.5} {}",
                    k.split_whitespace().collect::<Vec<_>>().join("_")
                )
                .unwrap();
            }
        }
        jumps.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        for (t, dh, dp, k) in jumps.iter().take(8) {
            println!("jump t {t:7.1} heading {dh:+.2} deg pos {dp:+.3} m {k}");
        }
    }
    let b = r.body(0);
    let ms = r.mission(0);
    let tp = b.true_pose();
    let e = ms.pose_map();
    let rep = r.report();
    let g = *r.map().graph.stats();
    if match_err {
        for (k, s) in corrections.iter().enumerate().filter(|(_, s)| s[0] > 0.0) {
            let n = s[0];
            let mean = |i: usize| s[1 + i] / n;
            let rms = |i: usize| (s[4 + i] / n).sqrt();
            println!(
                "match error, {k} directions constrained: {n} matches; forward mean {:+.5} rms {:.5} m, left mean {:+.5} rms {:.5} m, heading mean {:+.5} rms {:.5} deg",
                mean(0),
                rms(0),
                mean(1),
                rms(1),
                mean(2).to_degrees(),
                rms(2).to_degrees(),
            );
        }
    }
    if std::env::var("DIAG").is_ok() {
        let graph = r.map().graph.graph();
        for e in graph.edges() {
            let (i, j) = (usize::from(e.from), usize::from(e.to));
            if j == i + 1 || j >= key_truth.len() {
                continue;
            }
            let t = key_truth[j].in_frame_of(key_truth[i]);
            let err = e.measured.in_frame_of(t);
            println!(
                "closure {i:5} -> {j:5} (at {:.2} {:.2}): measured {:6.3} {:6.3} {:6.2}° true {:6.3} {:6.3} {:6.2}° error {:.3} m {:.2}°",
                key_truth[i].x,
                key_truth[i].y,
                e.measured.x,
                e.measured.y,
                e.measured.theta.to_degrees(),
                t.x,
                t.y,
                t.theta.to_degrees(),
                err.x.hypot(err.y),
                err.theta.to_degrees()
            );
        }
        let (mut n, mut st, mut sm, mut sa) = (0, 0.0f32, 0.0f32, 0.0f32);
        for e in graph.edges() {
            let (i, j) = (usize::from(e.from), usize::from(e.to));
            if j != i + 1 || j >= key_truth.len() {
                continue;
            }
            let err = e
                .measured
                .in_frame_of(key_truth[j].in_frame_of(key_truth[i]));
            n += 1;
            st += err.theta;
            sa += err.theta.abs();
            sm += err.x.hypot(err.y);
        }
        println!(
            "steps: {n}, heading error sum {:.2}° (mean |.| {:.3}°), mean position error {:.4} m",
            st.to_degrees(),
            (sa / n.max(1) as f32).to_degrees(),
            sm / n.max(1) as f32
        );
        let errs: Vec<f32> = (0..key_truth.len())
            .filter_map(|i| {
                graph
                    .pose(i)
                    .map(|p| p.position().distance(key_truth[i].position()))
            })
            .collect();
        let mean = errs.iter().sum::<f32>() / errs.len().max(1) as f32;
        let max = errs.iter().cloned().fold(0.0, f32::max);
        println!("keyframes vs truth: mean {mean:.3} m, max {max:.3} m");
    }
    if std::env::var("ODOCHECK").is_ok() {
        println!(
            "raw odometry's largest error over the run: {odo_max_m:.4} m {:.3} deg",
            odo_max_rad.to_degrees()
        );
    }
    if m_cal {
        // The estimate against the wheels the simulator drew for this robot.
        let cal = ms.localizer().calibration();
        let w = b.wheels();
        let (g, k) = gain_and_curvature_of(w.ed, w.eb, track_m);
        let (sg, sk) = cal.sigmas();
        let (ed, eb) = cal.wheel_errors(track_m);
        println!(
            "calibration: turn gain {:.5} ± {:.5} (drawn {:.5}) curvature {:+.5} ± {:.5} rad/m (drawn {:+.5}) | Ed {:.5} (drawn {:.5}) Eb {:.5} (drawn {:.5})",
            cal.turn_gain(),
            sg,
            g,
            cal.curvature_rad_per_m(),
            sk,
            k,
            ed,
            w.ed,
            eb,
            w.eb
        );
    }
    println!(
        "seed {seed} final err {:.3} m {:.2} deg coverage {:.1} % map acc {:.1} % t {:.0} run mean {:.3} max {:.3} m sigma mean {:.3} m | keyframes {} closures {}/{} refused {:?} redraws {} ({:.1} ms mean, {:.1} max) wall {:.1} s",
        e.position().distance(tp.position()),
        normalize_angle(e.theta - tp.theta).to_degrees(),
        100.0 * rep.coverage,
        100.0 * rep.map_accuracy.accuracy,
        r.sim_time_s(),
        err_sum / err_n.max(1) as f64,
        err_max,
        sigma_sum / err_n.max(1) as f64,
        g.keyframes,
        g.closures,
        g.attempts,
        g.refused,
        redraws,
        1e3 * redraw_s / f64::from(redraws.max(1)),
        1e3 * redraw_max_s,
        wall.elapsed().as_secs_f64()
    );
}
