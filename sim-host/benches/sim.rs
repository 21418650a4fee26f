//! Speed of the simulator's inner loops: one laser scan and one simulated second of physics on
//! the built-in house.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use papillon::geometry::Pose2;
use papillon::sensor::LaserConfig;
use papillon_sim::laser::LaserSim;
use papillon_sim::physics::{BodyConfig, RobotBody};
use papillon_sim::world::World;

fn laser(c: &mut Criterion) {
    let world = World::load("house", 0.1).unwrap();
    let mut thesis = LaserSim::new(LaserConfig::thesis(), 1);
    let mut lms = LaserSim::new(LaserConfig::lms1xx(), 1);
    let pose = Pose2::new(5.0, 10.5, 0.3);
    c.bench_function("laser_scan_181_beams_house", |b| {
        b.iter(|| black_box(thesis.scan(&world, black_box(pose), &[])))
    });
    c.bench_function("laser_scan_541_beams_house", |b| {
        b.iter(|| black_box(lms.scan(&world, black_box(pose), &[])))
    });
}

fn physics(c: &mut Criterion) {
    let world = World::load("house", 0.1).unwrap();
    c.bench_function("physics_one_simulated_second", |b| {
        let mut body = RobotBody::new(BodyConfig::default(), Pose2::new(2.0, 10.5, 0.0), 1);
        b.iter(|| {
            body.teleport(Pose2::new(2.0, 10.5, 0.0));
            body.command(500.0, 10.0);
            body.advance(1.0, &world, &[]);
            black_box(body.true_pose())
        })
    });
}

fn truth(c: &mut Criterion) {
    let world = World::load("house", 0.1).unwrap();
    c.bench_function("truth_observable_set_house", |b| {
        b.iter(|| black_box(world.truth().len()))
    });
}

criterion_group!(benches, laser, physics, truth);
criterion_main!(benches);
