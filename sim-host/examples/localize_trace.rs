//! Traces one house mission with scan matching on: every 5 s of simulated time (and every
//! scan of the first 3 s), the estimate's and the raw odometry's errors against the true pose,
//! the matcher's counters and its last match's quality.
//!
//! Run: `cargo run --release -p papillon-sim --example localize_trace -- SEED [none|realistic]`
//!
//! Environment: `MAP=lab` (default `house`), `NOISE=0.003` (the laser's range noise, default
//! the mission's), `LOC_TRAVEL`/`LOC_TURN` (the tracker's minimum travel and turn),
//! `LOC_GRAPH=1` (keyframes in a pose graph with loop closure, `src/localize/graph.rs`),
//! `GRAPH_TRAVEL`/`GRAPH_TURN` (its keyframe spacing), `GRAPH_SM`/`GRAPH_SR` (a closure's σ),
//! `GRAPH_KEYREF=1` (only keyframes into the reference), `GRAPH_GATE` (closure gate, σ),
//! `GRAPH_FLOOR_M`/`GRAPH_FLOOR_RAD` (a step's least σ), `GRAPH_EVERY` (path between closures),
//! `GRAPH_INFO` (a closure's least information per return), `GRAPH_RESID` (a closure's largest
//! residual after the optimisation, σ; 0: none), `DIAG=1`
//! (each closure's and each step's error against the truth),
//! `QUIET=1` (the last line only).

use papillon::geometry::normalize_angle;
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
    if let Some(v) = env("NOISE") {
        m.laser.noise_fraction = v;
    }
    if let Some(v) = env("LOC_TRAVEL") {
        m.localize.min_travel_m = v;
    }
    if let Some(v) = env("LOC_TURN") {
        m.localize.min_turn_rad = v;
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
    if let Some(v) = env("GRAPH_INFO") {
        m.localize.graph.closure.min_information = v;
    }
    if let Some(v) = env("GRAPH_SM") {
        m.localize.graph.closure.sigma_m = v;
    }
    if let Some(v) = env("GRAPH_SR") {
        m.localize.graph.closure.sigma_rad = v;
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
    let (mut err_sum, mut err_n, mut err_max) = (0.0f64, 0u64, 0.0f32);
    let (mut redraw_s, mut redraw_max_s, mut redraws) = (0.0f64, 0.0f64, 0u32);
    let wall = std::time::Instant::now();
    // The true pose of each keyframe (a scan is an `advance` of its own).
    let mut key_truth = Vec::new();
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
            let e = r.mission(0).pose_map();
            let d = e.position().distance(r.body(0).true_pose().position());
            err_sum += f64::from(d);
            err_n += 1;
            err_max = err_max.max(d);
        }
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
    let g = *r.map().graph.stats();
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
                "closure {i:5} -> {j:5}: measured {:6.3} {:6.3} {:6.2}° true {:6.3} {:6.3} {:6.2}° error {:.3} m {:.2}°",
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
    println!(
        "seed {seed} final err {:.3} m {:.2} deg coverage {:.1} % map acc {:.1} % t {:.0} run mean {:.3} max {:.3} m | keyframes {} closures {}/{} refused {:?} redraws {} ({:.1} ms mean, {:.1} max) wall {:.1} s",
        e.position().distance(tp.position()),
        normalize_angle(e.theta - tp.theta).to_degrees(),
        100.0 * rep.coverage,
        100.0 * rep.map_accuracy.accuracy,
        r.sim_time_s(),
        err_sum / err_n.max(1) as f64,
        err_max,
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
