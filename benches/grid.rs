//! Occupancy grid benchmarks: integrating one thesis scan (181 beams, 4 m) into a 240 x 240
//! grid at 10 cm (into an all-Unknown grid, and repeatedly into the same grid), tracing the
//! same 181 rays alone, and finding the frontiers afterwards.
//!
//! `cargo bench -p papillon --bench grid -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::ops::ControlFlow;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use papillon::frontier::{FrontierConfig, FrontierWorkspace, find_frontiers};
use papillon::geometry::{Point2, Pose2};
use papillon::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::math;
use papillon::raycast::traverse;
use papillon::sensor::{Beam, LaserConfig, Scan, SensorModel, integrate_scan};

const CELLS: usize = 240 * 240;

/// A scan from the middle of the map: walls 3 m away ahead, some beams without return.
fn scan(laser: &LaserConfig) -> Scan {
    let mut s = Scan::new();
    for i in 0..laser.beam_count as usize {
        let a = laser.beam_angle(i);
        let r = 3.0 / math::cos(a).abs().max(0.1);
        s.push(Beam {
            angle_rad: a,
            range_m: (r <= laser.max_range_m).then_some(r),
        })
        .unwrap();
    }
    s
}

fn grid_benches(c: &mut Criterion) {
    let geom = GridGeometry::new(240, 240, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(geom, LogOddsBounds::default()).unwrap();
    let laser = LaserConfig::thesis();
    let model = SensorModel::default();
    let s = scan(&laser);
    let pose = Pose2::new(12.0, 12.0, 0.3);

    // Into an all-Unknown grid: no cell saturated yet, every update weighs its evidence.
    let fresh = OccupancyGrid::<CELLS>::new_boxed(geom, LogOddsBounds::default()).unwrap();
    c.bench_function("integrate_scan 181 beams 4 m, 240x240, first scan", |b| {
        b.iter_batched_ref(
            || fresh.clone(),
            |g| integrate_scan(g, black_box(&s), black_box(pose), &laser, &model, &mut ()).unwrap(),
            BatchSize::LargeInput,
        )
    });

    // The same scan again and again: the steady state of a robot scanning at 10 Hz, where
    // most cells it crosses are already saturated.
    c.bench_function("integrate_scan 181 beams 4 m, 240x240", |b| {
        b.iter(|| {
            integrate_scan(
                &mut grid,
                black_box(&s),
                black_box(pose),
                &laser,
                &model,
                &mut (),
            )
            .unwrap()
        })
    });

    c.bench_function("traverse 181 rays of 4 m", |b| {
        b.iter(|| {
            let mut cells = 0usize;
            for beam in s.beams() {
                let a = pose.theta + beam.angle_rad;
                let end = Point2::new(12.0 + 4.0 * math::cos(a), 12.0 + 4.0 * math::sin(a));
                cells += traverse(&geom, black_box(pose.position()), end, |_, i| {
                    black_box(i);
                    ControlFlow::Continue(())
                })
                .visited;
            }
            cells
        })
    });

    let mut ws = FrontierWorkspace::<16384, 512>::new_boxed();
    let query = Point2::new(12.0, 12.0);
    let cfg = FrontierConfig::default();
    c.bench_function("find_frontiers 240x240 after one scan", |b| {
        b.iter(|| {
            find_frontiers(&grid, black_box(query), &cfg, &mut ws)
                .unwrap()
                .len()
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = grid_benches
}
criterion_main!(benches);
