//! One scan-to-map match: a 541-beam SICK LMS1xx scan (5 % range noise) on a half-explored
//! House map drawn by the inverse sensor model from a short tour (`tests/localize_fixture`),
//! from an odometry prediction 6 cm and 1.1° off the true pose.
//!
//! Run: `cargo bench -p papillon --bench localize -- --warm-up-time 1 --measurement-time 3`

#[path = "../tests/localize_fixture/mod.rs"]
mod localize_fixture;

use criterion::{Criterion, criterion_group, criterion_main};
use localize_fixture::HalfExplored;
use papillon::geometry::Pose2;
use papillon::localize::{MatchConfig, ScanMatcher, WINDOW_CELLS};

fn bench(c: &mut Criterion) {
    let mut house = HalfExplored::new();
    let truth = Pose2::new(2.0, 1.8, 0.8);
    let scan = house.scan(truth);
    let predicted = Pose2::new(2.05, 1.77, 0.82);
    let config = MatchConfig::default();
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    let r = matcher.match_scan(
        &house.grid,
        &house.hits,
        &scan,
        &house.laser,
        predicted,
        &config,
    );
    assert!(r.quality.trusted(), "{:?}", r.quality);
    assert_eq!(scan.len(), 541);
    c.bench_function("localize_match_lms1xx_541", |b| {
        b.iter(|| {
            matcher.match_scan(
                &house.grid,
                &house.hits,
                &scan,
                &house.laser,
                predicted,
                &config,
            )
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
