//! The simulator's parts together: worlds, physics, laser and dynamic obstacles.

use papillon::geometry::{Point2, Pose2};
use papillon::grid::{CellClass, DEFAULT_CELL_CAPACITY, LogOddsBounds, OccupancyGrid};
use papillon::random;
use papillon::sensor::{LaserConfig, Scan};
use papillon_sim::dynamic::{Door, DoorState, Dynamics, Person};
use papillon_sim::laser::LaserSim;
use papillon_sim::physics::{BodyConfig, BodyOutline, RobotBody, advance_all, body_penetration};
use papillon_sim::world::{World, builtin};

#[test]
fn laser_returns_land_on_walls_in_every_builtin_world() {
    let cfg = LaserConfig {
        noise_fraction: 0.0,
        max_range_m: 8.0,
        ..LaserConfig::thesis()
    };
    let mut rng = random::seeded(11);
    for name in builtin::NAMES {
        let world = World::load(name, 0.1).unwrap();
        let g = *world.geometry();
        let mut laser = LaserSim::new(cfg, 1);
        let mut poses = 0;
        while poses < 30 {
            let p = Point2::new(
                random::range_f32(&mut rng, 0.0, g.width_m()),
                random::range_f32(&mut rng, 0.0, g.height_m()),
            );
            if world.disc_hits_blocked(p, 0.25) {
                continue;
            }
            poses += 1;
            let pose = Pose2::new(p.x, p.y, random::range_f32(&mut rng, -3.1, 3.1));
            for b in laser.scan(&world, pose, &[]).beams() {
                let a = pose.theta + b.angle_rad;
                let at = |r: f32| Point2::new(p.x + r * a.cos(), p.y + r * a.sin());
                match b.range_m {
                    Some(r) => {
                        // A wall at the hit (within 2 mm: a ray may clip a corner).
                        assert!(
                            world.disc_hits_blocked(at(r), 0.002),
                            "{name} {pose:?} {b:?}"
                        );
                        // Nothing blocked along the way.
                        let mut s = 0.0;
                        while s < r - 1e-3 {
                            assert!(!world.is_blocked_at(at(s)), "{name} {pose:?} {b:?} at {s}");
                            s += 0.02;
                        }
                    }
                    None => {
                        let mut s = 0.0;
                        while s <= 8.0 {
                            assert!(!world.is_blocked_at(at(s)), "{name} {pose:?} {b:?} at {s}");
                            s += 0.02;
                        }
                    }
                }
            }
        }
    }
}

/// Two robots in the lab, a door that closes, a person crossing, slip and laser noise on.
fn run(seed: u64) -> (Vec<Pose2>, Vec<Pose2>, Vec<Scan>) {
    let mut world = World::load("lab", 0.1).unwrap();
    let (x0, y0, x1, y1) = builtin::LAB_DOOR;
    let mut dynamics = Dynamics::new()
        .with_door(Door::new(&world, x0, y0, x1, y1, DoorState::Open).at(6.0, DoorState::Closed))
        .with_person(Person::new(
            vec![Point2::new(2.0, 7.0), Point2::new(2.0, 2.5)],
            0.6,
            0.2,
            false,
            1.0,
        ));
    let mut bodies = vec![
        RobotBody::new(BodyConfig::default(), Pose2::new(1.0, 1.0, 0.8), seed),
        RobotBody::new(BodyConfig::default(), Pose2::new(6.0, 2.0, 2.0), seed + 1),
    ];
    let mut lasers = [
        LaserSim::new(LaserConfig::thesis(), seed + 2),
        LaserSim::new(LaserConfig::lms1xx(), seed + 3),
    ];
    let mut scans = Vec::new();
    for tick in 0..200 {
        let t = tick as f64 * 0.1;
        let robots: Vec<_> = bodies.iter().map(|b| b.disc()).collect();
        dynamics.update(t, &mut world, &robots);
        let people = dynamics.people_discs(t);
        for (i, b) in bodies.iter_mut().enumerate() {
            let turn = if (tick / 20) % 2 == 0 { 20.0 } else { -30.0 };
            b.command(300.0 + 50.0 * i as f32, turn);
        }
        advance_all(&mut bodies, 0.1, &world, &people);
        let mut discs = people.clone();
        discs.extend(bodies.iter().map(|b| b.disc()));
        for (b, l) in bodies.iter().zip(lasers.iter_mut()) {
            scans.push(l.scan(&world, b.true_pose(), &discs));
        }
    }
    (
        bodies.iter().map(|b| b.true_pose()).collect(),
        bodies.iter().map(|b| b.odometry_in_map()).collect(),
        scans,
    )
}

#[test]
fn a_run_is_deterministic_per_seed() {
    let a = run(25);
    let b = run(25);
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
    assert!(a.2 == b.2, "scans differ");
    let c = run(26);
    assert_ne!(a.0, c.0);
    // Slip made odometry drift from the truth.
    for (t, o) in a.0.iter().zip(&a.1) {
        assert!(t.position().distance(o.position()) > 1e-4);
    }
}

#[test]
fn robots_never_end_up_inside_walls() {
    let (poses, _, _) = run(3);
    let world = World::load("lab", 0.1).unwrap();
    let body = BodyOutline::p3dx();
    for p in poses {
        // The body's outline, checked against the static walls (the door cells are free in a
        // freshly loaded lab).
        assert!(
            body_penetration(&world, &[], p, &body, 0.25) <= 1e-3,
            "{p:?}"
        );
    }
}

#[test]
fn a_map_of_the_observable_set_has_full_coverage() {
    for name in builtin::NAMES {
        let world = World::load(name, 0.1).unwrap();
        let truth = world.truth();
        let mut map = OccupancyGrid::<DEFAULT_CELL_CAPACITY>::new_boxed(
            *world.geometry(),
            LogOddsBounds::default(),
        )
        .unwrap();
        assert_eq!(truth.coverage(&map), 0.0);
        for &i in truth.cells() {
            let class = if world.is_blocked_index(i) {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            map.set_class(i, class, &mut ());
        }
        assert_eq!(truth.coverage(&map), 1.0, "{name}");
        assert_eq!(truth.known_cells(&map), truth.len());
    }
}
