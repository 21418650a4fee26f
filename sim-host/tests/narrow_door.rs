//! A P3-DX (0.381 m wide) explores two rooms joined only by one door: through a 0.6 m door it
//! plans with its footprint, drives through straight and never touches a wall; a 0.4 m door it
//! never plans through. The 0.5 m door of issue 17 (6 cm to spare on each side) is passed
//! without contact with exact odometry, with the thesis's 5 % laser noise and with a SICK
//! LMS1xx's 0.3 %; with the thesis's odometry slip (the runner's default) the map drifts by a
//! cell or two against the true walls and it is not passed in most seeds yet (ignored test).

use papillon::geometry::Pose2;
use papillon::mission::{MissionConfig, SelectorKind};
use papillon_sim::dynamic::Dynamics;
use papillon_sim::physics::SlipConfig;
use papillon_sim::runner::{RunConfig, RunReport, Runner};
use papillon_sim::world::builtin;

/// Two 5.75 m x 5 m rooms side by side (0.1 m cells), the wall between them at x = 6.4 m with
/// one door of `door_m` centred on y = 3 m.
fn run(door_m: f32, seed: u64) -> RunReport {
    run_with(door_m, seed, None, true)
}

/// [`run`] with the laser's range noise (`None`: the thesis's 5 %) and the thesis's odometry
/// slip on or off (exact odometry).
fn run_with(door_m: f32, seed: u64, noise: Option<f32>, slip: bool) -> RunReport {
    run_from(door_m, seed, noise, slip, None)
}

/// [`run_with`] from the start pose `start` (`None`: the world's).
fn run_from(
    door_m: f32,
    seed: u64,
    noise: Option<f32>,
    slip: bool,
    start: Option<Pose2>,
) -> RunReport {
    let mut world = builtin::empty(0.1).unwrap();
    // Keep the south-west 12 m x 6 m: wall off the rest.
    world.fill_rect(0.5, 6.0, 23.5, 23.5, true);
    world.fill_rect(12.5, 0.5, 23.5, 6.0, true);
    world.fill_rect(6.4, 0.5, 6.5, 3.0 - door_m / 2.0, true);
    world.fill_rect(6.4, 3.0 + door_m / 2.0, 6.5, 6.0, true);
    let mut mission = MissionConfig {
        selector: SelectorKind::NearestFrontier,
        ..MissionConfig::default()
    };
    if let Some(n) = noise {
        mission.laser.noise_fraction = n;
    }
    let mut config = RunConfig::new(mission, 1, seed);
    if !slip {
        config.body.slip = SlipConfig::none();
    }
    config.starts = start.map(|p| vec![p]);
    Runner::new(world, Dynamics::new(), config)
        .unwrap()
        .run()
        .unwrap()
}

/// Through the 0.5 m door with exact odometry and laser noise `noise`, seeds 25..27.
fn half_metre_door_with_exact_odometry(noise: f32) {
    for seed in [25, 26, 27] {
        let r = run_with(0.5, seed, Some(noise), false);
        assert_eq!(r.collisions(), 0, "noise {noise}, seed {seed}: contacts");
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 7.0);
        assert!(
            crossed,
            "noise {noise}, seed {seed}: never went through the door"
        );
        assert!(
            r.coverage >= 0.95,
            "noise {noise}, seed {seed}: coverage {} ({:?})",
            r.coverage,
            r.reason
        );
    }
}

#[test]
fn a_half_metre_door_is_driven_through_with_the_thesis_laser_noise() {
    half_metre_door_with_exact_odometry(0.05);
}

#[test]
fn a_half_metre_door_is_driven_through_with_a_precise_laser() {
    half_metre_door_with_exact_odometry(0.003);
}

#[test]
fn a_forty_centimetre_door_is_never_planned_through_with_a_precise_laser() {
    for seed in [25, 26] {
        let r = run_with(0.4, seed, Some(0.003), false);
        assert_eq!(r.collisions(), 0);
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 6.5);
        assert!(!crossed, "seed {seed}: went through a 0.4 m door");
        // The body never enters the doorway. (This replaced `coverage < 0.6`: a mission that
        // finds nothing reachable now looks through a passage shut on its map from the
        // passage's mouth, as a 0.5 m door narrowed by drift needs, and from there sees part of
        // the room behind a truly narrow door too: 64 % with seed 25. Not driving into the
        // door is what the test is about, and this checks it at every sample.)
        let front_m = max_x(&r) + BODY_FRONT_M;
        assert!(front_m < WALL_X_M, "seed {seed}: front at x = {front_m} m");
    }
}

/// The body's front ahead of the wheel axle \[m\] (P3-DX: 210 mm).
const BODY_FRONT_M: f32 = 0.21;
/// The west face of the wall with the door \[m\].
const WALL_X_M: f32 = 6.4;

/// The easternmost true position of the robot's axle centre \[m\].
fn max_x(r: &RunReport) -> f32 {
    r.robots[0]
        .trajectory
        .iter()
        .map(|p| p.x)
        .fold(f32::MIN, f32::max)
}

#[test]
#[ignore = "fails with the thesis's odometry slip (issue 17 open): the map drifts a cell against the true frames and the door is shut on it or the monitor stops the robot in it (2 of 5 seeds pass)"]
fn a_half_metre_door_is_driven_through_without_contact() {
    for seed in [25, 26, 27] {
        let r = run(0.5, seed);
        assert_eq!(r.collisions(), 0, "seed {seed}: contacts");
        assert!(
            r.coverage >= 0.95,
            "seed {seed}: coverage {} ({:?})",
            r.coverage,
            r.reason
        );
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 7.0);
        assert!(crossed, "seed {seed}: never went through the door");
    }
}

#[test]
fn a_sixty_centimetre_door_is_driven_through_without_contact() {
    for seed in [25, 26, 27] {
        let r = run(0.6, seed);
        assert_eq!(r.collisions(), 0, "seed {seed}: contacts");
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 7.0);
        assert!(crossed, "seed {seed}: never went through the door");
        assert!(r.coverage >= 0.95, "seed {seed}: coverage {}", r.coverage);
    }
}

#[test]
fn a_forty_centimetre_door_is_never_planned_through() {
    let r = run(0.4, 25);
    assert_eq!(r.collisions(), 0);
    let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 6.5);
    assert!(!crossed, "went through a 0.4 m door");
    let front_m = max_x(&r) + BODY_FRONT_M;
    assert!(front_m < WALL_X_M, "front at x = {front_m} m");
    assert!(r.coverage < 0.6, "coverage {}", r.coverage);
}

/// A robot that comes at the 0.5 m door askew (issue 17: gen-10 seed 25 with exact odometry
/// drove at a 0.5 m door 0.34 rad off its axis, was stopped in front of it again and again and
/// gave the room behind it up). Started 0.3-0.45 m beside the door's axis, 0.4-0.7 m from its wall,
/// facing the wall, with exact odometry and the thesis's 5 % laser: it gets
/// through without contact and explores the room behind.
#[test]
fn a_half_metre_door_approached_askew_is_driven_through_without_contact() {
    // Each of these fails on the planner before the approach point (commit 26c8184): the robot
    // re-plans about 40 times in front of the door and ends "nothing reachable" at 53-57 %.
    let starts = [
        (Pose2::new(5.7, 3.45, 0.0), 25),
        (Pose2::new(5.7, 2.55, 0.0), 26),
        (Pose2::new(6.0, 3.3, 0.0), 25),
        (Pose2::new(6.0, 2.7, 0.0), 26),
    ];
    for (start, seed) in starts {
        let r = run_from(0.5, seed, Some(0.05), false, Some(start));
        assert_eq!(r.collisions(), 0, "start {start:?}, seed {seed}: contacts");
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 7.0);
        assert!(
            crossed,
            "start {start:?}, seed {seed}: never went through the door ({:?}, coverage {})",
            r.reason, r.coverage
        );
        assert!(
            r.coverage >= 0.95,
            "start {start:?}, seed {seed}: coverage {} ({:?})",
            r.coverage,
            r.reason
        );
    }
}
