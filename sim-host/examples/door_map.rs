//! How the inverse sensor model maps a narrow door: scans from true poses in front of a door of
//! `DOOR_M` (default 0.5 m) in a 0.1 m wall, the laser's noise `NOISE` (default 0.05), and
//! prints the map around the door and whether the P3-DX's planning layer passes it.
//!
//! `NOISE=0.003 DOOR_M=0.5 cargo run --release -p papillon-sim --example door_map`

use papillon::geometry::{Point2, Pose2};
use papillon::grid::{Cell, CellClass, LogOddsBounds, OccupancyGrid};
use papillon::mission::footprint;
use papillon::planner::{Traversability, UnknownPolicy};
use papillon::random;
use papillon::sensor::{LaserConfig, SensorModel, integrate_scan};
use papillon_sim::laser::LaserSim;
use papillon_sim::runner::FIXED_CAPACITY;
use papillon_sim::world::builtin;

fn env(name: &str, default: f32) -> f32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let door_m = env("DOOR_M", 0.5);
    let noise = env("NOISE", 0.05);
    let scans = env("SCANS", 80.0) as usize;
    let seeds = env("SEEDS", 5.0) as u64;
    let mut world = builtin::empty(0.1).unwrap();
    world.fill_rect(0.5, 6.0, 23.5, 23.5, true);
    world.fill_rect(12.5, 0.5, 23.5, 6.0, true);
    world.fill_rect(6.4, 0.5, 6.5, 3.0 - door_m / 2.0, true);
    world.fill_rect(6.4, 3.0 + door_m / 2.0, 6.5, 6.0, true);
    let geom = *world.geometry();
    if std::env::var_os("MONITOR").is_some() {
        monitor(&world, noise);
        return;
    }
    if std::env::var_os("MISSION").is_some() {
        mission(world, noise, seeds);
        return;
    }
    let mut laser_cfg = LaserConfig::thesis();
    laser_cfg.noise_fraction = noise;
    let model = SensorModel::default();
    let safety = papillon::control::safety::SafetyConfig::default();
    let layer = footprint::planning_layer(
        &safety,
        footprint::DEFAULT_CLEARANCE_M,
        0.1,
        UnknownPolicy::Traversable { cost_factor: 1.0 },
    );
    let mut passed = 0;
    for seed in 0..seeds {
        let mut grid =
            OccupancyGrid::<FIXED_CAPACITY>::new_boxed(geom, LogOddsBounds::default()).unwrap();
        let mut trav = Traversability::<FIXED_CAPACITY>::new_boxed(geom, layer).unwrap();
        let mut laser = LaserSim::new(laser_cfg, 1000 + seed);
        let mut rng = random::seeded(seed);
        for _ in 0..scans {
            let x = 3.0 + 3.0 * random::unit_f32(&mut rng);
            let y = 1.2 + 3.6 * random::unit_f32(&mut rng);
            let theta = (3.0 - y).atan2(6.45 - x) + (random::unit_f32(&mut rng) - 0.5) * 2.0;
            let pose = Pose2::new(x, y, theta);
            let scan = laser.scan(&world, pose, &[]);
            integrate_scan(&mut grid, &scan, pose, &laser_cfg, &model, &mut *trav).unwrap();
        }
        // Passable chain from the robot's room to the far side, through x = 6.45.
        let start = geom.cell_at(Point2::new(5.0, 3.0)).unwrap();
        let goal_col = geom.cell_at(Point2::new(7.2, 3.0)).unwrap().col;
        let mut seen = vec![false; geom.cell_count()];
        let mut stack = vec![start];
        let mut ok = false;
        while let Some(c) = stack.pop() {
            if c.col >= goal_col {
                ok = true;
                break;
            }
            for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let n = Cell::new(c.col + dc, c.row + dr);
                if n.col < 40 || n.col > 80 || n.row < 5 || n.row > 58 {
                    continue;
                }
                if let Some(j) = geom.index(n)
                    && !seen[j]
                    && trav.is_passable(n)
                {
                    seen[j] = true;
                    stack.push(n);
                }
            }
        }
        passed += ok as usize;
        if seed == 0 || std::env::var_os("ALL").is_some() {
            println!("seed {seed}: door passable: {ok}");
            for row in (22..=37).rev() {
                let mut line = format!("{:4.2} ", 0.1 * row as f32 + 0.05);
                for col in 56..=72 {
                    let c = Cell::new(col, row);
                    let truth = world.is_blocked(c);
                    let ch = match (grid.class_of(c).unwrap(), truth) {
                        (CellClass::Occupied, true) => '#',
                        (CellClass::Occupied, false) => 'X',
                        (CellClass::Free, true) => 'o',
                        (CellClass::Free, false) => {
                            if trav.is_passable(c) {
                                '.'
                            } else {
                                ','
                            }
                        }
                        (CellClass::Unknown, true) => '=',
                        (CellClass::Unknown, false) => ' ',
                    };
                    line.push(ch);
                }
                println!("{line}");
            }
        }
    }
    println!("noise {noise} door {door_m}: passable in {passed}/{seeds}");
}

fn mission(world: papillon_sim::world::World, noise: f32, seeds: u64) {
    use papillon::mission::{MissionConfig, SelectorKind};
    use papillon_sim::dynamic::Dynamics;
    use papillon_sim::runner::{RunConfig, Runner};
    let geom = *world.geometry();
    for seed in 25..25 + seeds {
        let mut mission = MissionConfig {
            selector: SelectorKind::NearestFrontier,
            ..MissionConfig::default()
        };
        mission.laser.noise_fraction = noise;
        let mut run = RunConfig::new(mission, 1, seed);
        if std::env::var_os("NOSLIP").is_some() {
            run.body.slip = papillon_sim::physics::SlipConfig::none();
        }
        let mut runner = Runner::new(world.clone(), Dynamics::new(), run).unwrap();
        let r = runner.run().unwrap();
        let crossed = r.robots[0].trajectory.iter().any(|p| p.x > 7.0);
        println!(
            "seed {seed}: coverage {:.3} {:?} crossed {crossed} contacts {}",
            r.coverage,
            r.reason,
            r.collisions()
        );
        if std::env::var_os("EVENTS").is_some() {
            let ev = runner.events();
            for e in &ev[ev.len().saturating_sub(30)..] {
                println!("{:8.1} {:?}", e.time_s, e.event);
            }
        }
        let map = &runner.map().grid;
        let p = runner.body(0).true_pose();
        let rc = geom.cell_at(Point2::new(p.x, p.y)).unwrap();
        println!("end pose {p:?} map pose {:?}", runner.mission(0).pose_map());
        let trav = &runner.map().trav;
        for row in (20..=39).rev() {
            let mut line = format!("{:4.2} ", 0.1 * row as f32 + 0.05);
            for col in 54..=74 {
                let c = Cell::new(col, row);
                let truth = world.is_blocked(c);
                let ch = if c == rc {
                    'R'
                } else {
                    match (map.class_of(c).unwrap(), truth) {
                        (CellClass::Occupied, true) => '#',
                        (CellClass::Occupied, false) => 'X',
                        (CellClass::Free, true) => 'o',
                        (CellClass::Free, false) => match trav.wall_band(c) {
                            None => ',',
                            Some(b) => char::from(b'0' + b),
                        },
                        (CellClass::Unknown, true) => '=',
                        (CellClass::Unknown, false) => ' ',
                    }
                };
                line.push(ch);
            }
            println!("{line}");
        }
    }
}

fn monitor(world: &papillon_sim::world::World, noise: f32) {
    use papillon::control::command::{Limits, MotionCommand};
    use papillon::control::safety::{SafetyConfig, SafetyMonitor};
    let mut cfg = LaserConfig::thesis();
    cfg.noise_fraction = noise;
    let m = SafetyMonitor::new(SafetyConfig::default(), Limits::default());
    let v = Limits::default().clamp(MotionCommand::from_si(0.15, 0.0));
    let mut laser = LaserSim::new(cfg, 7);
    for dy in [0.0f32, 0.01, 0.02, 0.03] {
        for dth in [0.0f32, 0.03] {
            let mut line = format!("dy {dy:.2} dth {dth:.2}:");
            for k in 0..10 {
                let x = 5.5 + 0.1 * k as f32;
                let pose = Pose2::new(x, 2.95 + dy, dth);
                let mut stops = 0;
                for _ in 0..200 {
                    let scan = laser.scan(world, pose, &[]);
                    stops += m.obstacle_in_path(v, &scan, &cfg).is_some() as usize;
                }
                line.push_str(&format!(" {x:.1}:{:3}", stops / 2));
            }
            println!("{line}");
        }
    }
}
