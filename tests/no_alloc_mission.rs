//! A whole mission allocates nothing in the core: a robot explores the built-in lab from its
//! start to the mission's end (coverage reached, nothing reachable or the battery), with every
//! call into the core's mission state machine (odometry, scan integration with scan matching
//! on, control steps with their decisions, plans and re-plans) counted by the counting global
//! allocator. The world, the body's physics and the simulated laser are the simulator's (they
//! allocate as they like, outside the counted calls); the pump is the runner's, reduced to one
//! robot: a scan every 1/rate s, a control period every 100 ms.
#![cfg(feature = "std")]

mod alloc_count;

use alloc_count::allocations_in;
use papillon::control::Time;
use papillon::grid::{CellClass, DEFAULT_CELL_CAPACITY};
use papillon::mission::{Mission, MissionConfig, MissionState, SharedMap, Workspace};
use papillon::random::seeded;
use papillon::sensor::Scan;
use papillon_sim::laser::LaserSim;
use papillon_sim::physics::{BodyConfig, RobotBody, SlipConfig, advance_all};
use papillon_sim::runner::{apply, flags};
use papillon_sim::world::World;

const CONTROL_PERIOD_US: u64 = 100_000;

#[test]
fn a_whole_lab_mission_allocates_nothing_in_the_core() {
    lab_mission(false);
}

/// With the pose graph on (keyframes, loop closures, optimisation, redraws).
#[test]
fn a_whole_lab_mission_with_the_pose_graph_allocates_nothing_in_the_core() {
    let stats = lab_mission(true);
    eprintln!("pose graph: {stats:?}");
    assert!(stats.keyframes > 0 && stats.attempts > 0, "{stats:?}");
    assert!(
        stats.closures > 0 && stats.redraws > 0,
        "no closure to check: {stats:?}"
    );
}

fn lab_mission(graph: bool) -> papillon::localize::graph::GraphStats {
    let world = World::load("lab", 0.1).expect("the built-in lab");
    let truth = world.truth_mask();
    let observable = truth.iter().filter(|&&t| t).count();
    let mut config = MissionConfig::default();
    config.localize.enabled = true;
    config.localize.graph.enabled = graph;
    let start = world.start();
    let mut body = RobotBody::new(
        BodyConfig {
            slip: SlipConfig::thesis(),
            ..BodyConfig::default()
        },
        start,
        7,
    );
    let mut laser = LaserSim::new(config.laser, 8);
    let mut rng = seeded(9);
    let mut scan = Scan::new();

    // Set-up allocates (the boxed map and working memory); the mission itself does not.
    let mut map = SharedMap::<DEFAULT_CELL_CAPACITY>::new_boxed(*world.geometry(), &config)
        .expect("the lab fits");
    let mut ws = Workspace::<DEFAULT_CELL_CAPACITY>::new_boxed();
    let scan_period_us = (1e6 / config.laser.rate_hz as f64).round() as u64;
    let mut mission = Mission::new(0, config, start).expect("a valid mission");

    let (mut now_us, mut next_scan_us, mut next_control_us) = (0u64, 0u64, 0u64);
    let (mut allocations, mut core_calls, mut decisions) = (0usize, 0usize, 0usize);
    let limit_us = 1_200 * 1_000_000;
    while !matches!(mission.state(), MissionState::Done(_)) && now_us < limit_us {
        let next = next_control_us.min(next_scan_us);
        if next > now_us {
            advance_all(
                std::slice::from_mut(&mut body),
                (next - now_us) as f32 * 1e-6,
                &world,
                &[],
            );
            now_us = next;
        }
        let now = Time::from_micros(now_us);
        if next_scan_us == now_us {
            laser
                .scan_into(&world, body.true_pose(), &[], &mut scan)
                .expect("the laser's beams fit a scan");
            let odom = body.odometry_pose();
            let f = flags(&body);
            let (r, n) = allocations_in(|| {
                mission.on_odometry(now, odom, f);
                mission.on_scan(now, &scan, &mut map)
            });
            r.expect("the scan is integrated");
            allocations += n;
            core_calls += 2;
            next_scan_us += scan_period_us;
        }
        if next_control_us == now_us {
            // The coverage of the truth, counted outside the core (the runner's ideal pump).
            let known = (0..truth.len())
                .filter(|&i| truth[i] && map.grid.class(i) != CellClass::Unknown)
                .count();
            let coverage = known as f32 / observable as f32;
            let odom = body.odometry_pose();
            let f = flags(&body);
            let (out, n) = allocations_in(|| {
                mission.on_odometry(now, odom, f);
                mission.set_coverage(coverage);
                mission.step(now, &mut map, &mut ws, &mut rng)
            });
            allocations += n;
            core_calls += 3;
            decisions += out
                .events
                .iter()
                .filter(|e| matches!(e, papillon::mission::MissionEvent::Decided { .. }))
                .count();
            apply(&mut body, out.command);
            next_control_us += CONTROL_PERIOD_US;
        }
    }
    let state = mission.state();
    eprintln!(
        "lab mission: {state:?} at {:.1} s, {decisions} decisions, {core_calls} core calls",
        now_us as f64 * 1e-6
    );
    assert!(
        matches!(state, MissionState::Done(_)),
        "the mission did not end within 1200 s of simulated time: {state:?}"
    );
    assert!(
        decisions >= 3,
        "a whole mission makes several decisions ({decisions})"
    );
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {core_calls} calls into the mission ({decisions} decisions, ended {state:?})"
    );
    *map.graph.stats()
}
