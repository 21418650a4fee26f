//! Mission tests: the state machine driven with the kinematic double
//! ([`crate::control::sim_double::Unicycle`]) in hand-made worlds, with a tiny ray caster
//! ([`crate::raycast::traverse`] over a boolean world at 5 cm) producing the scans. Other
//! robots appear in the scans as discs.

use core::ops::ControlFlow;
use core::time::Duration;

use super::*;
use crate::control::Time;
use crate::control::command::{Limits, RobotCommand};
use crate::control::odometry::MapFromOdom;
use crate::control::safety::{RobotFlags, RobotFootprint};
use crate::control::sim_double::{Slip, Unicycle};
use crate::geometry::{Point2, Pose2};
use crate::grid::{CellClass, GridGeometry};
use crate::math;
use crate::planner::{AStar, PlanError, PlannedPath, Planner, Traversability};
use crate::random::{ProjectRng, below, chance, range_f32, seeded};
use crate::raycast;
use crate::sensor::{Beam, LaserConfig, Scan};

/// Map capacity for every test world.
const CELLS: usize = 5000;
/// Control period.
const PERIOD_MS: u64 = 100;
/// Radius of a robot as other robots' lasers see it \[m\].
const BODY_RADIUS_M: f32 = 0.22;

/// The true world: a boolean grid at 5 cm.
#[derive(Clone)]
struct World {
    geom: GridGeometry,
    occupied: Vec<bool>,
}

impl World {
    fn new(width_m: f32, height_m: f32) -> Self {
        let geom = GridGeometry::new(
            (width_m / 0.05).round() as usize,
            (height_m / 0.05).round() as usize,
            0.05,
            Point2::new(0.0, 0.0),
        )
        .unwrap();
        let occupied = vec![false; geom.cell_count()];
        let mut w = Self { geom, occupied };
        w.fill(0.0, 0.0, width_m, 0.1, true);
        w.fill(0.0, height_m - 0.1, width_m, height_m, true);
        w.fill(0.0, 0.0, 0.1, height_m, true);
        w.fill(width_m - 0.1, 0.0, width_m, height_m, true);
        w
    }

    /// Sets the rectangle `[x0, x1) x [y0, y1)` occupied or free.
    fn fill(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, occupied: bool) {
        for i in 0..self.geom.cell_count() {
            let c = self.geom.cell_center(self.geom.cell(i));
            if c.x >= x0 && c.x < x1 && c.y >= y0 && c.y < y1 {
                self.occupied[i] = occupied;
            }
        }
    }

    fn is_occupied(&self, p: Point2) -> bool {
        self.geom
            .cell_at(p)
            .and_then(|c| self.geom.index(c))
            .is_none_or(|i| self.occupied[i])
    }

    /// Distance from `p` to the nearest occupied cell centre within 1 m (1 m if none).
    fn clearance(&self, p: Point2) -> f32 {
        let mut best = 1.0f32;
        let c = self.geom.cell_at_unchecked(p);
        for row in c.row - 20..=c.row + 20 {
            for col in c.col - 20..=c.col + 20 {
                let cell = crate::grid::Cell::new(col, row);
                if let Some(i) = self.geom.index(cell)
                    && self.occupied[i]
                {
                    best = best.min(self.geom.cell_center(cell).distance(p) - 0.025);
                }
            }
        }
        best
    }

    /// The range along one ray, to the first wall cell or robot disc.
    fn range(&self, origin: Point2, angle: f32, max_m: f32, robots: &[Point2]) -> Option<f32> {
        let (dx, dy) = (math::cos(angle), math::sin(angle));
        let end = Point2::new(origin.x + dx * max_m, origin.y + dy * max_m);
        let mut hit: Option<f32> = None;
        let res = self.geom.resolution_m;
        raycast::traverse(&self.geom, origin, end, |cell, i| {
            if !self.occupied[i] {
                return ControlFlow::Continue(());
            }
            // Entry distance into the cell's square (slab method).
            let lo = Point2::new(
                self.geom.origin.x + cell.col as f32 * res,
                self.geom.origin.y + cell.row as f32 * res,
            );
            let slab = |o: f32, d: f32, a: f32| {
                if d.abs() < 1e-9 {
                    f32::NEG_INFINITY
                } else {
                    let (t0, t1) = ((a - o) / d, (a + res - o) / d);
                    t0.min(t1)
                }
            };
            let t = slab(origin.x, dx, lo.x)
                .max(slab(origin.y, dy, lo.y))
                .max(0.0);
            hit = Some(t);
            ControlFlow::Break(())
        });
        for &c in robots {
            // Ray-circle intersection.
            let (ox, oy) = (origin.x - c.x, origin.y - c.y);
            let b = ox * dx + oy * dy;
            let q = ox * ox + oy * oy - BODY_RADIUS_M * BODY_RADIUS_M;
            let disc = b * b - q;
            if disc >= 0.0 {
                let t = -b - disc.sqrt();
                if t > 0.0 && hit.is_none_or(|h| t < h) {
                    hit = Some(t);
                }
            }
        }
        hit.filter(|&t| t <= max_m)
    }

    /// A scan from the robot at `pose`.
    fn scan(&self, pose: Pose2, laser: &LaserConfig, robots: &[Point2]) -> Scan {
        let at = pose.compose(laser.mount);
        let mut scan = Scan::new();
        for b in 0..laser.beam_count as usize {
            let a = laser.beam_angle(b);
            let r = self.range(at.position(), at.theta + a, laser.max_range_m, robots);
            scan.push(Beam {
                angle_rad: a,
                range_m: r,
            })
            .unwrap();
        }
        scan
    }

    /// The map geometry (10 cm) covering this world.
    fn map_geometry(&self) -> GridGeometry {
        GridGeometry::new(
            (self.geom.width as f32 * 0.05 / 0.1).round() as usize,
            (self.geom.height as f32 * 0.05 / 0.1).round() as usize,
            0.1,
            Point2::new(0.0, 0.0),
        )
        .unwrap()
    }

    /// Map cells that are truly free (every 5 cm sub-cell free).
    fn free_mask(&self, map: &GridGeometry) -> Vec<bool> {
        (0..map.cell_count())
            .map(|i| {
                let c = map.cell_center(map.cell(i));
                [
                    (-0.025, -0.025),
                    (0.025, -0.025),
                    (-0.025, 0.025),
                    (0.025, 0.025),
                ]
                .iter()
                .all(|&(dx, dy)| !self.is_occupied(Point2::new(c.x + dx, c.y + dy)))
            })
            .collect()
    }

    /// Writes the truth into a map (every cell known).
    fn reveal(&self, map: &mut SharedMap<CELLS>) {
        let g = *map.grid.geometry();
        let free = self.free_mask(&g);
        for (i, &f) in free.iter().enumerate() {
            let class = if f {
                CellClass::Free
            } else {
                CellClass::Occupied
            };
            map.grid.set_class(i, class, &mut ());
        }
        map.rebuild_traversability().unwrap();
    }
}

/// One simulated robot: the double, its flags, its mission.
struct Bot {
    mission: Mission<CELLS>,
    body: Unicycle,
    /// Where the body's own (odometry) frame sits in the map.
    map_from_odom: MapFromOdom,
    flags: RobotFlags,
    feed_odometry: bool,
    feed_scans: bool,
    /// The wheels turn but the body does not move (and no stall is reported): a robot
    /// wedged on a threshold, or lifted.
    wheels_spin: bool,
    log: Vec<(Time, MissionEvent)>,
    last_command: RobotCommand,
}

impl Bot {
    fn new(id: u8, config: MissionConfig, start: Pose2, slip: Slip, seed: u64) -> Self {
        // The odometry frame starts wherever the robot's counters were: here at (5, -3, 1).
        let odom_start = Pose2::new(5.0, -3.0, 1.0);
        Self {
            mission: Mission::new(id, config, start).unwrap(),
            body: Unicycle::new(odom_start, slip, seed),
            map_from_odom: MapFromOdom::from_start(start, odom_start),
            flags: RobotFlags::nominal(),
            feed_odometry: true,
            feed_scans: true,
            wheels_spin: false,
            log: Vec::new(),
            last_command: RobotCommand::Stop,
        }
    }

    fn true_pose(&self) -> Pose2 {
        self.map_from_odom.map_pose(self.body.pose())
    }
}

/// Several robots in one world, one shared map, stepped at 10 Hz; decisions plan their paths
/// with `P`.
struct Sim<P: Planner<CELLS> = AStar<CELLS>> {
    world: World,
    map: Box<SharedMap<CELLS>>,
    ws: Box<Workspace<CELLS, P>>,
    bots: Vec<Bot>,
    rng: ProjectRng,
    now: Time,
    limits: Limits,
}

impl Sim {
    fn new(world: World, config: &MissionConfig, seed: u64) -> Self {
        Self::with_planner(world, config, seed)
    }
}

impl<P: Planner<CELLS> + bytemuck::Zeroable> Sim<P> {
    fn with_planner(world: World, config: &MissionConfig, seed: u64) -> Self {
        let map = SharedMap::new_boxed(world.map_geometry(), config).unwrap();
        Self {
            world,
            map,
            ws: Workspace::new_boxed(),
            bots: Vec::new(),
            rng: seeded(seed),
            now: Time::ZERO,
            limits: config.limits,
        }
    }

    fn add(&mut self, config: MissionConfig, start: Pose2, slip: Slip) -> usize {
        let id = self.bots.len() as u8;
        let seed = rand_core::Rng::next_u64(&mut self.rng);
        self.bots.push(Bot::new(id, config, start, slip, seed));
        self.bots.len() - 1
    }

    /// One period: sense, step, act. Returns the commands.
    fn period(&mut self) -> Vec<RobotCommand> {
        let poses: Vec<Point2> = self.bots.iter().map(|b| b.true_pose().position()).collect();
        for (k, bot) in self.bots.iter_mut().enumerate() {
            if bot.feed_odometry {
                bot.mission
                    .on_odometry(self.now, bot.body.pose(), bot.flags);
            }
            if bot.feed_scans {
                let others: Vec<Point2> = poses
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != k)
                    .map(|(_, &p)| p)
                    .collect();
                let laser = bot.mission.config().laser;
                let scan = self.world.scan(bot.true_pose(), &laser, &others);
                bot.mission.on_scan(self.now, &scan, &mut self.map).unwrap();
            }
        }
        let mut commands = Vec::new();
        for bot in &mut self.bots {
            let out = bot
                .mission
                .step(self.now, &mut self.map, &mut self.ws, &mut self.rng);
            if let Some(v) = out.command.velocity() {
                assert!(self.limits.allows(v), "{v:?} beyond the limits");
            }
            for e in out.events {
                bot.log.push((self.now, e));
            }
            bot.last_command = out.command;
            if !bot.wheels_spin {
                bot.body.apply(out.command, PERIOD_MS as f32 * 1e-3);
            }
            commands.push(out.command);
        }
        self.now = self.now + Duration::from_millis(PERIOD_MS);
        commands
    }

    fn secs(&self) -> f32 {
        self.now.as_secs_f64() as f32
    }
}

fn moving(cmd: RobotCommand) -> bool {
    cmd.velocity()
        .is_some_and(|v| v.speed_mm_s() != 0 || v.turn_rate_deg_s() != 0)
}

/// Two rooms, 8 m x 5 m, joined by two 1 m doors in the wall at x = 4.
fn two_rooms() -> World {
    let mut w = World::new(8.0, 5.0);
    w.fill(3.95, 0.0, 4.05, 5.0, true);
    w.fill(3.95, 2.0, 4.05, 3.0, false);
    w.fill(3.95, 3.8, 4.05, 4.8, false);
    // A pillar in the east room.
    w.fill(5.8, 1.2, 6.2, 1.6, true);
    w
}

fn frontier_config() -> MissionConfig {
    MissionConfig {
        selector: SelectorKind::NearestFrontier,
        ..MissionConfig::default()
    }
}

/// Runs one robot until Done or `max_s`; returns the sim.
fn explore(config: MissionConfig, slip: Slip, seed: u64, max_s: f32) -> Sim {
    explore_with(config, slip, seed, max_s)
}

/// As [`explore`], the decisions planning their paths with `P`.
fn explore_with<P: Planner<CELLS> + bytemuck::Zeroable>(
    config: MissionConfig,
    slip: Slip,
    seed: u64,
    max_s: f32,
) -> Sim<P> {
    let world = two_rooms();
    let mut sim = Sim::with_planner(world, &config, seed);
    sim.add(config, Pose2::new(1.0, 1.0, 0.3), slip);
    while sim.secs() < max_s {
        sim.period();
        let bot = &sim.bots[0];
        let p = bot.true_pose().position();
        assert!(
            sim.world.clearance(p) > 0.18,
            "seed {seed}: the robot hit a wall at {p:?} at {} s",
            sim.secs()
        );
        if matches!(bot.mission.state(), MissionState::Done(_)) {
            break;
        }
    }
    sim
}

fn known_fraction<P: Planner<CELLS>>(sim: &Sim<P>) -> f32 {
    let g = *sim.map.grid.geometry();
    let free = sim.world.free_mask(&g);
    let total = free.iter().filter(|&&f| f).count();
    let known = free
        .iter()
        .enumerate()
        .filter(|&(i, &f)| f && sim.map.grid.class(i).is_known())
        .count();
    known as f32 / total as f32
}

/// The two-room mission ended with nothing left to reach, nearly every free cell known.
fn assert_two_rooms_explored(sim: &Sim, seed: u64) {
    let bot = &sim.bots[0];
    assert_eq!(
        bot.mission.state(),
        MissionState::Done(DoneReason::NothingReachable),
        "seed {seed}: {:?} after {} s",
        bot.mission.stats(),
        sim.secs()
    );
    let known = known_fraction(sim);
    assert!(
        known > 0.97,
        "seed {seed}: only {known} of the free cells known"
    );
}

/// (a) A two-room world is explored to Done under slip; every waypoint is reached within
/// tolerance and the heading does not oscillate.
#[test]
fn explores_two_rooms_to_done_under_slip() {
    for (seed, selector) in [
        (1, SelectorKind::NearestFrontier),
        (2, SelectorKind::FrontierUtility),
        (3, SelectorKind::Optimized(crate::optim::Method::Xboa)),
    ] {
        let config = MissionConfig {
            selector,
            ..MissionConfig::default()
        };
        let sim = explore(config, Slip::thesis(), seed, 1500.0);
        assert_two_rooms_explored(&sim, seed);
        let bot = &sim.bots[0];
        let stats = bot.mission.stats();
        assert!(stats.decisions >= 1, "{stats:?}");
        // Every decision ends with its target reached or given up.
        assert!(
            stats.waypoints_reached + stats.abandoned_targets + 1 >= stats.decisions,
            "{stats:?}"
        );
        assert!(
            stats.abandoned_targets <= stats.decisions / 2 + 1,
            "{stats:?}"
        );
        assert!(stats.steps > 0.0 && bot.mission.battery_steps() < 500.0);
        assert!(
            (bot.mission.battery_steps() + stats.steps - 500.0).abs() < 1e-2,
            "battery accounts for the steps driven"
        );
    }
}

/// (a) Waypoint tracking inside the mission: every reached waypoint is within the follower's
/// tolerance of the true pose (odometry here is exact; slip acts on the motion), and the turn
/// command does not swing from side to side while driving.
#[test]
fn waypoints_are_reached_within_tolerance_without_oscillation() {
    let config = frontier_config();
    let world = two_rooms();
    let mut sim = Sim::new(world, &config, 7);
    sim.add(config, Pose2::new(1.0, 1.0, 0.0), Slip::thesis());
    let mut sign_changes = 0u32;
    let mut last_sign = 0i32;
    let mut legs = 0u32;
    let mut checked = 0;
    while sim.secs() < 1500.0 {
        let before = sim.bots[0].log.len();
        let path_before = sim.bots[0].mission.path().to_vec();
        let cmds = sim.period();
        let bot = &sim.bots[0];
        for (_, e) in &bot.log[before..] {
            if let MissionEvent::WaypointReached { .. } = e {
                legs += 1;
                last_sign = 0;
            }
            if let MissionEvent::Decided { .. } | MissionEvent::Replanned { .. } = e {
                last_sign = 0;
            }
        }
        if let Some(v) = cmds[0].velocity()
            && v.speed_mm_s() > 0
            && v.turn_rate_deg_s().abs() >= 3
        {
            let s = v.turn_rate_deg_s().signum() as i32;
            if last_sign != 0 && s != last_sign {
                sign_changes += 1;
            }
            last_sign = s;
        }
        for (_, e) in &bot.log[before..] {
            if let MissionEvent::WaypointReached { index } = e {
                // The follower reports the waypoint once the robot has settled on it.
                let path_point = path_before.get(*index).copied();
                if let Some(w) = path_point {
                    let err = w.distance(bot.true_pose().position());
                    assert!(err <= 0.06, "waypoint {index} reached {err} m off");
                    checked += 1;
                }
            }
        }
        if matches!(bot.mission.state(), MissionState::Done(_)) {
            break;
        }
    }
    assert!(matches!(sim.bots[0].mission.state(), MissionState::Done(_)));
    assert!(checked > 0 && legs > 3, "{checked} {legs}");
    assert!(
        sign_changes <= legs,
        "turn command changed sign {sign_changes} times over {legs} legs"
    );
}

/// A robot cruising east in an open room toward a far goal, its mission acknowledged and
/// driving.
fn cruising(seed: u64) -> Sim {
    let config = frontier_config();
    let world = World::new(8.0, 5.0);
    let mut sim = Sim::new(world.clone(), &config, seed);
    world.reveal(&mut sim.map);
    sim.add(config, Pose2::new(1.0, 2.5, 0.0), Slip::none());
    sim.bots[0].mission.go_to(&[Point2::new(7.0, 2.5)]).unwrap();
    for _ in 0..40 {
        sim.period();
    }
    assert_eq!(sim.bots[0].mission.state(), MissionState::Driving);
    assert!(sim.bots[0].body.velocity().0 > 0.2, "cruising");
    sim
}

/// After a stop, no motion until a fresh plan (a Decided or Replanned event at or before
/// the first moving command). Returns the events seen.
fn no_motion_before_fresh_plan(
    sim: &mut Sim,
    periods: usize,
    allow_backing: bool,
) -> Vec<MissionEvent> {
    let mut fresh = false;
    let mut seen = Vec::new();
    for _ in 0..periods {
        let before = sim.bots[0].log.len();
        let cmd = sim.period()[0];
        for (_, e) in &sim.bots[0].log[before..] {
            if matches!(
                e,
                MissionEvent::Replanned { .. } | MissionEvent::Decided { .. }
            ) {
                fresh = true;
            }
            seen.push(e.clone());
        }
        if moving(cmd) && !fresh {
            let v = cmd.velocity().unwrap();
            assert!(
                allow_backing && v.speed_mm_s() < 0 && v.turn_rate_deg_s() == 0,
                "moved ({v:?}) before a fresh plan"
            );
        }
    }
    assert!(fresh, "never replanned: {seen:?}");
    seen
}

/// (b) Obstacle ahead: stop in the same period, then replan before moving.
#[test]
fn an_obstacle_ahead_stops_the_robot_in_the_period_it_appears() {
    let mut sim = cruising(11);
    let p = sim.bots[0].true_pose();
    // A box 0.45 m ahead of the laser, across the path.
    let x = p.x + 0.45;
    sim.world.fill(x, p.y - 0.3, x + 0.2, p.y + 0.3, true);
    let before = sim.bots[0].log.len();
    let cmd = sim.period()[0];
    // The period the box appears in: no forward motion; turning only on a plan made now.
    assert_eq!(cmd.velocity().unwrap().speed_mm_s(), 0, "{cmd:?}");
    let mut seen: Vec<MissionEvent> = sim.bots[0].log[before..]
        .iter()
        .map(|(_, e)| e.clone())
        .collect();
    let replanned = seen
        .iter()
        .any(|e| matches!(e, MissionEvent::Replanned { .. }));
    if moving(cmd) {
        assert!(replanned, "{cmd:?} without a fresh plan");
    } else {
        seen.extend(no_motion_before_fresh_plan(&mut sim, 100, false));
    }
    assert!(seen.iter().any(|e| matches!(
        e,
        MissionEvent::Replanned {
            cause: ReplanCause::ObstacleAhead | ReplanCause::PathBlocked
        }
    )));
}

/// (b) Obstacle ahead that only the safety monitor sees (inside the mapping blind zone,
/// 0.30 m, so never on the map by scans): `Stop` in the period it appears, the return put on
/// the map, a replan for `ObstacleAhead` before any motion.
#[test]
fn an_obstacle_in_the_blind_zone_is_caught_by_the_safety_monitor() {
    let mut sim = cruising(17);
    let p = sim.bots[0].true_pose();
    // A thin pole 0.27 m ahead of the centre (6 cm off the bumper), in the laser's blind zone.
    let x = p.x + 0.27;
    sim.world.fill(x, p.y - 0.05, x + 0.05, p.y + 0.05, true);
    let cmd = sim.period()[0];
    assert_eq!(cmd, RobotCommand::Stop);
    let seen = no_motion_before_fresh_plan(&mut sim, 100, false);
    assert!(
        seen.iter().any(|e| matches!(
            e,
            MissionEvent::Replanned {
                cause: ReplanCause::ObstacleAhead
            }
        )),
        "{seen:?}"
    );
}

/// (b) Bumper and stall: stop in the same period, back off, replan before driving on.
#[test]
fn bumper_and_stall_stop_the_robot_in_the_same_period() {
    for which in 0..3 {
        let mut sim = cruising(12 + which);
        match which {
            0 => sim.bots[0].flags.front_bumper = true,
            1 => sim.bots[0].flags.left_stall = true,
            _ => sim.bots[0].flags.right_stall = true,
        }
        let cmd = sim.period()[0];
        assert_eq!(cmd, RobotCommand::Stop, "case {which}");
        sim.bots[0].flags = RobotFlags::nominal();
        let seen = no_motion_before_fresh_plan(&mut sim, 100, true);
        assert!(
            seen.iter().any(|e| matches!(
                e,
                MissionEvent::Replanned {
                    cause: ReplanCause::Contact
                }
            )),
            "case {which}: {seen:?}"
        );
    }
}

/// (b) Stale odometry, stale scans: zero velocity in the first period the input is too old;
/// a fresh plan before moving again.
#[test]
fn stale_odometry_or_scans_stop_the_robot_within_one_period() {
    for odometry in [true, false] {
        let mut sim = cruising(20);
        if odometry {
            sim.bots[0].feed_odometry = false;
        } else {
            sim.bots[0].feed_scans = false;
        }
        let last_fresh = Time::from_micros(sim.now.as_micros() - PERIOD_MS * 1000);
        let mut stopped_at = None;
        for _ in 0..10 {
            let at = sim.now;
            let cmd = sim.period()[0];
            let age = at.saturating_since(last_fresh);
            if age > Duration::from_millis(500) {
                assert!(!moving(cmd), "age {age:?}: {cmd:?}");
                stopped_at.get_or_insert(at);
            }
        }
        assert!(stopped_at.is_some());
        assert!(matches!(
            sim.bots[0].mission.state(),
            MissionState::Fault(FaultReason::StaleInputs)
        ));
        sim.bots[0].feed_odometry = true;
        sim.bots[0].feed_scans = true;
        let seen = no_motion_before_fresh_plan(&mut sim, 50, false);
        assert!(seen.contains(&MissionEvent::FaultCleared), "{seen:?}");
    }
}

/// (b) E-stop and motors disabled: stop in the same period, a fault reported, a fresh plan
/// after it clears.
#[test]
fn estop_and_disabled_motors_stop_the_robot_and_need_a_fresh_plan() {
    for estop in [true, false] {
        let mut sim = cruising(30);
        if estop {
            sim.bots[0].flags.estop = true;
        } else {
            sim.bots[0].flags.motors_enabled = false;
        }
        let before = sim.bots[0].log.len();
        let cmd = sim.period()[0];
        assert!(!moving(cmd), "{cmd:?}");
        let reason = if estop {
            FaultReason::EmergencyStop
        } else {
            FaultReason::MotorsDisabled
        };
        assert!(
            sim.bots[0].log[before..]
                .iter()
                .any(|(_, e)| *e == MissionEvent::Fault(reason))
        );
        for _ in 0..20 {
            assert!(!moving(sim.period()[0]));
        }
        assert_eq!(sim.bots[0].mission.state(), MissionState::Fault(reason));
        sim.bots[0].flags = RobotFlags::nominal();
        let seen = no_motion_before_fresh_plan(&mut sim, 50, false);
        assert!(seen.contains(&MissionEvent::FaultCleared), "{seen:?}");
        assert!(seen.iter().any(|e| matches!(
            e,
            MissionEvent::Replanned {
                cause: ReplanCause::FaultCleared
            }
        )));
    }
}

/// (c) Property: whatever the inputs (random poses, flags, scans, gaps, limits), no command
/// exceeds the limits.
#[test]
fn no_command_ever_exceeds_the_limits_whatever_the_inputs() {
    let mut rng = seeded(0x5afe);
    let world = two_rooms();
    for round in 0..12 {
        let limits = Limits::new(
            below(&mut rng, 600) as u16,
            below(&mut rng, 120) as u16,
            300,
            300,
            100,
            100,
        );
        let config = MissionConfig {
            limits,
            selector: if round % 2 == 0 {
                SelectorKind::NearestFrontier
            } else {
                SelectorKind::FrontierUtility
            },
            ..MissionConfig::default()
        };
        let mut map = SharedMap::<CELLS>::new_boxed(world.map_geometry(), &config).unwrap();
        let mut ws = Workspace::<CELLS>::new_boxed();
        let mut mission =
            Mission::<CELLS>::new(0, config.clone(), Pose2::new(1.0, 1.0, 0.0)).unwrap();
        let mut now = Time::ZERO;
        let mut pose = Pose2::new(0.0, 0.0, 0.0);
        for _ in 0..400 {
            now = now + Duration::from_millis(below(&mut rng, 400) as u64);
            pose = Pose2::new(
                pose.x + range_f32(&mut rng, -0.05, 0.05),
                pose.y + range_f32(&mut rng, -0.05, 0.05),
                pose.theta + range_f32(&mut rng, -0.3, 0.3),
            );
            let flags = RobotFlags {
                front_bumper: chance(&mut rng, 0.03),
                rear_bumper: chance(&mut rng, 0.03),
                left_stall: chance(&mut rng, 0.02),
                right_stall: chance(&mut rng, 0.02),
                motors_enabled: !chance(&mut rng, 0.03),
                estop: chance(&mut rng, 0.02),
            };
            if chance(&mut rng, 0.9) {
                mission.on_odometry(now, pose, flags);
            }
            if chance(&mut rng, 0.8) {
                let mut scan = Scan::new();
                for b in 0..config.laser.beam_count as usize {
                    let r = match below(&mut rng, 10) {
                        0 => None,
                        1 => Some(range_f32(&mut rng, 0.0, 0.4)),
                        _ => Some(range_f32(&mut rng, 0.3, 6.0)),
                    };
                    scan.push(Beam {
                        angle_rad: config.laser.beam_angle(b),
                        range_m: r,
                    })
                    .unwrap();
                }
                // Scans from a pose outside the map are refused, not a panic.
                let _ = mission.on_scan(now, &scan, &mut map);
            }
            if chance(&mut rng, 0.05) {
                mission.set_coverage(range_f32(&mut rng, 0.0, 1.2));
            }
            let out = mission.step(now, &mut map, &mut ws, &mut rng);
            if let Some(v) = out.command.velocity() {
                assert!(limits.allows(v), "round {round}: {v:?} beyond {limits:?}");
            }
            assert!(!matches!(out.command, RobotCommand::EnableMotors(_)));
        }
    }
}

/// A 1 m corridor 6 m long between two rooms (3 m x 4 m each).
fn corridor_world() -> World {
    let mut w = World::new(12.0, 4.0);
    w.fill(3.0, 0.0, 9.0, 1.5, true);
    w.fill(3.0, 2.5, 9.0, 4.0, true);
    w
}

/// (d) Two robots meeting head-on in a 1 m corridor: one steps back, both reach their goals,
/// no deadlock, no collision.
#[test]
fn two_robots_meeting_head_on_in_a_corridor_never_deadlock() {
    for seed in 0..6u64 {
        let config = MissionConfig {
            selector: SelectorKind::NearestFrontier,
            ..MissionConfig::default()
        };
        let world = corridor_world();
        let mut sim = Sim::new(world.clone(), &config, seed);
        world.reveal(&mut sim.map);
        let a = sim.add(config.clone(), Pose2::new(1.5, 2.0, 0.0), Slip::thesis());
        let b = sim.add(
            config,
            Pose2::new(10.5, 2.0, core::f32::consts::PI),
            Slip::thesis(),
        );
        let goal_a = Point2::new(10.5, 3.0);
        let goal_b = Point2::new(1.5, 1.0);
        sim.bots[a].mission.go_to(&[goal_a]).unwrap();
        sim.bots[b].mission.go_to(&[goal_b]).unwrap();
        let mut closest = f32::INFINITY;
        let mut reached = [false, false];
        let mut still_both = 0u32;
        while sim.secs() < 400.0 && !(reached[0] && reached[1]) {
            let cmds = sim.period();
            let pa = sim.bots[a].true_pose().position();
            let pb = sim.bots[b].true_pose().position();
            closest = closest.min(pa.distance(pb));
            reached[0] |= pa.distance(goal_a) < 0.1;
            reached[1] |= pb.distance(goal_b) < 0.1;
            // Deadlock: both standing still for long while neither is done.
            if cmds.iter().all(|&c| !moving(c)) {
                still_both += 1;
            } else {
                still_both = 0;
            }
            assert!(
                still_both < 300,
                "seed {seed}: both robots stood still for 30 s at {pa:?} and {pb:?}: {:?} / {:?}",
                sim.bots[a].mission.state(),
                sim.bots[b].mission.state()
            );
            for bot in &sim.bots {
                let p = bot.true_pose().position();
                assert!(
                    sim.world.clearance(p) > 0.18,
                    "seed {seed}: wall hit at {p:?}"
                );
            }
        }
        assert!(
            reached[0] && reached[1],
            "seed {seed}: goals reached {reached:?} after {} s; a {:?} {:?}, b {:?} {:?}",
            sim.secs(),
            sim.bots[a].mission.state(),
            sim.bots[a].true_pose(),
            sim.bots[b].mission.state(),
            sim.bots[b].true_pose()
        );
        assert!(closest > 0.45, "seed {seed}: robots came {closest} m close");
        let yielded = sim.bots[b]
            .log
            .iter()
            .any(|(_, e)| matches!(e, MissionEvent::Yielding { .. }));
        assert!(
            yielded,
            "seed {seed}: the robot with the higher id never yielded"
        );
    }
}

/// (e) A door closing across the path causes a replan, not a collision.
#[test]
fn a_door_closing_across_the_path_causes_a_replan() {
    let config = frontier_config();
    let world = two_rooms();
    let mut sim = Sim::new(world.clone(), &config, 5);
    world.reveal(&mut sim.map);
    sim.add(config, Pose2::new(1.0, 2.5, 0.0), Slip::thesis());
    sim.bots[0].mission.go_to(&[Point2::new(6.5, 2.5)]).unwrap();
    let mut closed = false;
    while sim.secs() < 120.0 {
        sim.period();
        let p = sim.bots[0].true_pose().position();
        if !closed && p.x > 2.0 {
            sim.world.fill(3.95, 2.0, 4.05, 3.0, true);
            closed = true;
        }
        assert!(sim.world.clearance(p) > 0.18, "hit the door at {p:?}");
        if p.distance(Point2::new(6.5, 2.5)) < 0.1 {
            break;
        }
    }
    assert!(closed);
    let end = sim.bots[0].true_pose().position();
    assert!(
        end.distance(Point2::new(6.5, 2.5)) < 0.1,
        "stopped at {end:?}, {:?}",
        sim.bots[0].mission.state()
    );
    let log = &sim.bots[0].log;
    assert!(
        log.iter().any(|(_, e)| matches!(
            e,
            MissionEvent::Replanned {
                cause: ReplanCause::PathBlocked
            }
        )),
        "{log:?}"
    );
}

/// Replans count against a decision only while the robot gets nowhere: posts appearing one
/// after another across a long path cut it more often than the limit of replans, but the
/// robot moves on between cuts, so the goal is kept and reached (were every replan counted,
/// it would be dropped and adopted again as a new decision).
#[test]
fn replans_after_progress_do_not_drop_the_decision() {
    let config = frontier_config();
    let limit = config.max_replans_per_decision as usize;
    let world = World::new(12.0, 4.0);
    let mut sim = Sim::new(world.clone(), &config, 8);
    world.reveal(&mut sim.map);
    sim.add(config, Pose2::new(1.0, 2.0, 0.0), Slip::none());
    let goal = Point2::new(11.0, 2.0);
    sim.bots[0].mission.go_to(&[goal]).unwrap();
    // Each post appears 1.5 m ahead of the robot, across the straight line to the goal.
    let mut posts = [2.6f32, 3.8, 5.0, 6.2, 7.4, 8.6, 9.8]
        .into_iter()
        .peekable();
    while sim.secs() < 200.0 {
        sim.period();
        let p = sim.bots[0].true_pose().position();
        if let Some(&x) = posts.peek()
            && p.x > x - 1.5
        {
            sim.world.fill(x - 0.15, 1.85, x + 0.15, 2.15, true);
            posts.next();
        }
        assert!(sim.world.clearance(p) > 0.18, "hit a post at {p:?}");
        if p.distance(goal) < 0.1 {
            break;
        }
    }
    assert!(posts.peek().is_none(), "not every post was placed");
    let bot = &sim.bots[0];
    let end = bot.true_pose().position();
    assert!(end.distance(goal) < 0.1, "stopped at {end:?}");
    let count = |f: fn(&MissionEvent) -> bool| bot.log.iter().filter(|(_, e)| f(e)).count();
    let cut = count(|e| {
        matches!(
            e,
            MissionEvent::Replanned {
                cause: ReplanCause::PathBlocked
            }
        )
    });
    let decided = count(|e| matches!(e, MissionEvent::Decided { .. }));
    assert!(cut > limit, "{cut} cuts");
    assert_eq!(decided, 1, "the goal was dropped and adopted again");
}

/// Battery: a mission with a small battery ends BatteryExhausted, having driven about what
/// it had.
#[test]
fn a_small_battery_ends_the_mission() {
    let config = MissionConfig {
        battery_steps: 12.0,
        explore: crate::explore::ExploreConfig {
            reserve_steps: 1.0,
            ..crate::explore::ExploreConfig::default()
        },
        ..frontier_config()
    };
    let sim = explore(config, Slip::thesis(), 9, 600.0);
    let m = &sim.bots[0].mission;
    assert_eq!(m.state(), MissionState::Done(DoneReason::BatteryExhausted));
    assert!(m.battery_steps() <= 1.0 + 10.0, "{}", m.battery_steps());
}

/// A robot that cannot move (its wheels spin, no stall reported) gets nowhere; the mission
/// ends `Stuck` instead of deciding, replanning and escaping for ever.
#[test]
fn a_robot_that_gets_nowhere_ends_the_mission_stuck() {
    for config in [frontier_config(), MissionConfig::default()] {
        let mut sim = Sim::new(two_rooms(), &config, 4);
        let timeout_s = config.progress_timeout_s;
        sim.add(config, Pose2::new(1.0, 1.0, 0.3), Slip::thesis());
        sim.bots[0].wheels_spin = true;
        while sim.secs() < 3600.0 && !matches!(sim.bots[0].mission.state(), MissionState::Done(_)) {
            sim.period();
        }
        let m = &sim.bots[0].mission;
        assert_eq!(
            m.state(),
            MissionState::Done(DoneReason::Stuck),
            "at {} s",
            sim.secs()
        );
        assert!(sim.secs() <= 2.0 * timeout_s, "ended at {} s", sim.secs());
    }
}

/// Coverage reported by the caller ends the mission at the target.
#[test]
fn reported_coverage_ends_the_mission() {
    let config = frontier_config();
    let mut sim = Sim::new(two_rooms(), &config, 4);
    sim.add(config, Pose2::new(1.0, 1.0, 0.0), Slip::none());
    for _ in 0..30 {
        sim.period();
    }
    sim.bots[0].mission.set_coverage(0.995);
    sim.period();
    assert_eq!(
        sim.bots[0].mission.state(),
        MissionState::Done(DoneReason::CoverageReached)
    );
    assert!(!moving(sim.period()[0]));
}

/// A mission's own memory does not grow with the map: the map and the decision memory are
/// shared, borrowed per step. Most of it is the latest scan the safety monitor checks
/// (1081 beams of 12 bytes).
#[test]
fn a_mission_stays_small_whatever_the_map() {
    let small = core::mem::size_of::<Mission<CELLS>>();
    let large = core::mem::size_of::<Mission<150_000>>();
    assert_eq!(small, large);
    let scan = core::mem::size_of::<Scan>();
    assert!(
        small < scan + 8 * 1024,
        "{small} bytes, {scan} of them the scan"
    );
}

#[test]
fn bad_configs_are_refused_with_the_field_named() {
    let config = MissionConfig {
        coverage_target: 1.5,
        ..MissionConfig::default()
    };
    assert!(matches!(
        Mission::<CELLS>::new(0, config, Pose2::default()),
        Err(MissionError::BadConfig {
            field: "coverage_target",
            ..
        })
    ));
    assert!(matches!(
        Mission::<CELLS>::new(0, MissionConfig::default(), Pose2::new(f32::NAN, 0.0, 0.0)),
        Err(MissionError::NotFinite { .. })
    ));
    for (field, config) in [
        (
            "progress_distance_m",
            MissionConfig {
                progress_distance_m: 0.0,
                ..MissionConfig::default()
            },
        ),
        (
            "progress_timeout_s",
            MissionConfig {
                progress_timeout_s: f32::NAN,
                ..MissionConfig::default()
            },
        ),
    ] {
        assert!(
            matches!(
                Mission::<CELLS>::new(0, config, Pose2::default()),
                Err(MissionError::BadConfig { field: f, .. }) if f == field
            ),
            "{field}"
        );
    }
    // A huge wait is no panic: it saturates.
    let config = MissionConfig {
        yield_wait_s: 1e30,
        stuck_timeout_s: 1e30,
        progress_timeout_s: 1e30,
        ..MissionConfig::default()
    };
    assert!(Mission::<CELLS>::new(0, config, Pose2::default()).is_ok());
}

/// Figures for the module docs: stop time with and without deciding while driving (run with
/// `--ignored --nocapture`). Simulated time does not see the decision's compute time, so the
/// harness models it: a decision taken while stopped holds the robot still for its compute
/// time; one taken ahead while driving lets the robot run on its last command for that
/// long (what a runtime blocked in `step` would do).
#[test]
#[ignore = "prints figures for the docs"]
fn report_decide_while_driving() {
    // One decision on the House snapshot, from docs/benchmarks.md, rounded: xBOA (population
    // 5, 30 generations) 575 ms, nearest frontier 3.5 ms.
    for (selector, think_s) in [
        (SelectorKind::NearestFrontier, 0.0035f32),
        (SelectorKind::Optimized(crate::optim::Method::Xboa), 0.6),
    ] {
        let think_periods = (think_s * 1000.0 / PERIOD_MS as f32).round() as u32;
        for ahead in [false, true] {
            let (mut stopped, mut total, mut runs, mut used, mut done) = (0.0f32, 0.0f32, 0, 0, 0);
            for seed in 0..8 {
                let config = MissionConfig {
                    decide_while_driving: ahead,
                    selector,
                    ..MissionConfig::default()
                };
                let mut sim = Sim::new(two_rooms(), &config, 40 + seed);
                sim.add(config, Pose2::new(1.0, 1.0, 0.3), Slip::thesis());
                let mut think_stopped = 0.0f32;
                while sim.secs() < 1500.0 {
                    let before = *sim.bots[0].mission.stats();
                    sim.period();
                    let after = *sim.bots[0].mission.stats();
                    let fresh = after.decisions > before.decisions
                        && after.decisions_ahead_used == before.decisions_ahead_used;
                    let computed_ahead = after.decisions_ahead > before.decisions_ahead;
                    if (fresh || computed_ahead) && think_periods > 0 {
                        let bot = &mut sim.bots[0];
                        let cmd = if fresh {
                            RobotCommand::Stop
                        } else {
                            bot.last_command
                        };
                        for _ in 0..think_periods {
                            bot.body.apply(cmd, PERIOD_MS as f32 * 1e-3);
                        }
                        if fresh {
                            think_stopped += think_periods as f32 * PERIOD_MS as f32 * 1e-3;
                        }
                        sim.now = sim.now + Duration::from_millis(PERIOD_MS * think_periods as u64);
                    }
                    if matches!(sim.bots[0].mission.state(), MissionState::Done(_)) {
                        done += 1;
                        break;
                    }
                }
                let s = sim.bots[0].mission.stats();
                stopped += s.stopped_s + think_stopped;
                total += sim.secs();
                used += s.decisions_ahead_used;
                runs += 1;
            }
            std::eprintln!(
                "{selector:?} ahead {ahead}: {runs} runs ({done} done), mean mission {:.1} s, \
                 mean stopped {:.1} s, decisions used from ahead {used}",
                total / runs as f32,
                stopped / runs as f32
            );
        }
    }
}

/// A pane of glass across a door: the laser sees through it, the bumper finds it. The
/// mission backs off, puts it on the map, replans through the other door, and does not keep
/// ramming the glass.
#[test]
fn an_obstacle_only_the_bumper_finds_is_avoided_without_looping() {
    let config = frontier_config();
    let world = two_rooms();
    let mut sim = Sim::new(world.clone(), &config, 8);
    world.reveal(&mut sim.map);
    sim.add(config, Pose2::new(2.0, 2.5, 0.0), Slip::thesis());
    let goal = Point2::new(6.5, 2.5);
    sim.bots[0].mission.go_to(&[goal]).unwrap();
    let in_glass = |p: Point2| (3.85..4.15).contains(&p.x) && (2.0..3.0).contains(&p.y);
    let mut contacts = 0;
    let mut pressed = false;
    while sim.secs() < 300.0 {
        let before = sim.bots[0].body.pose();
        sim.period();
        let bot = &mut sim.bots[0];
        let pose = bot.true_pose();
        // The bumper ring: 0.21 m ahead of the centre, 0.30 m behind.
        let front = pose.transform_point(Point2::new(0.21, 0.0));
        let rear = pose.transform_point(Point2::new(-0.30, 0.0));
        let hit_front = in_glass(front);
        let hit_rear = in_glass(rear);
        if hit_front || hit_rear {
            // Blocked: the pose stays where it was (the wheels push in vain).
            bot.body.set_pose(before);
            if !pressed {
                contacts += 1;
            }
        }
        pressed = hit_front || hit_rear;
        bot.flags.front_bumper = hit_front;
        bot.flags.rear_bumper = hit_rear;
        if pose.position().distance(goal) < 0.1 {
            break;
        }
    }
    let m = &sim.bots[0].mission;
    let end = sim.bots[0].true_pose().position();
    assert!(
        end.distance(goal) < 0.1,
        "stopped at {end:?}: {:?} {:?}",
        m.state(),
        m.stats()
    );
    assert!(contacts >= 1, "never touched the glass");
    assert!(contacts <= 6, "rammed the glass {contacts} times");
    assert!(sim.bots[0].log.iter().any(|(_, e)| matches!(
        e,
        MissionEvent::Replanned {
            cause: ReplanCause::Contact
        }
    )));
}

/// Two robots exploring the two rooms on one shared map: both finish, the map is complete,
/// they never touch.
#[test]
fn two_robots_explore_one_shared_map_to_done() {
    for (seed, selector) in [
        (61, SelectorKind::NearestFrontier),
        (62, SelectorKind::FrontierUtility),
        (63, SelectorKind::Optimized(crate::optim::Method::Xboa)),
    ] {
        let config = MissionConfig {
            selector,
            ..MissionConfig::default()
        };
        let mut sim = Sim::new(two_rooms(), &config, seed);
        sim.add(config.clone(), Pose2::new(1.0, 1.0, 0.3), Slip::thesis());
        sim.add(config, Pose2::new(7.0, 4.0, -2.8), Slip::thesis());
        let mut closest = f32::INFINITY;
        while sim.secs() < 900.0 {
            sim.period();
            let (pa, pb) = (
                sim.bots[0].true_pose().position(),
                sim.bots[1].true_pose().position(),
            );
            closest = closest.min(pa.distance(pb));
            for p in [pa, pb] {
                assert!(
                    sim.world.clearance(p) > 0.18,
                    "seed {seed}: wall hit at {p:?}"
                );
            }
            if sim
                .bots
                .iter()
                .all(|b| matches!(b.mission.state(), MissionState::Done(_)))
            {
                break;
            }
        }
        for b in &sim.bots {
            assert_eq!(
                b.mission.state(),
                MissionState::Done(DoneReason::NothingReachable),
                "seed {seed} after {} s: {:?}",
                sim.secs(),
                b.mission.stats()
            );
        }
        let known = known_fraction(&sim);
        assert!(known > 0.97, "seed {seed}: {known}");
        assert!(closest > 0.45, "seed {seed}: robots came {closest} m close");
    }
}

/// "Nothing reachable" is concluded from looks a second apart, not from the same map read
/// once a period: the failed decisions that end a mission are spread over
/// `max_failed_decisions - 1` retry periods (a mark that fresh scans clear, or a bumper
/// contact's stamp, cut a robot off for a moment; issue 17, branch `doors`).
#[test]
fn nothing_reachable_is_concluded_from_looks_a_second_apart() {
    let config = MissionConfig {
        selector: SelectorKind::NearestFrontier,
        ..MissionConfig::default()
    };
    let max_failed = config.max_failed_decisions;
    let world = two_rooms();
    let mut sim = Sim::new(world, &config, 5);
    sim.add(config, Pose2::new(1.0, 1.0, 0.3), Slip::none());
    let mut first_failure_s = None;
    while sim.secs() < 1500.0 {
        sim.period();
        let m = &sim.bots[0].mission;
        if first_failure_s.is_none() && m.stats().failed_decisions > 0 {
            first_failure_s = Some(sim.secs());
        }
        if matches!(m.state(), MissionState::Done(_)) {
            break;
        }
    }
    let m = &sim.bots[0].mission;
    assert_eq!(
        m.state(),
        MissionState::Done(DoneReason::NothingReachable),
        "{:?}",
        m.stats()
    );
    assert_eq!(m.stats().failed_decisions, max_failed);
    let first = first_failure_s.expect("a failed decision");
    let spread = sim.secs() - first;
    assert!(
        spread >= (max_failed - 1) as f32 * 0.95,
        "{max_failed} failed decisions within {spread} s"
    );
}

/// The outline of `body` at `pose` touches a wall of `world`.
fn touches(world: &World, body: &RobotFootprint, pose: Pose2) -> bool {
    let (front, rear, half) = (body.front_m, -body.rear_m, body.width_m / 2.0);
    let n = 30;
    (0..=n).any(|k| {
        let t = k as f32 / n as f32;
        let x = rear + t * (front - rear);
        let y = -half + t * 2.0 * half;
        [
            Point2::new(x, -half),
            Point2::new(x, half),
            Point2::new(front, y),
            Point2::new(rear, y),
        ]
        .iter()
        .any(|&p| world.is_occupied(pose.transform_point(p)))
    })
}

/// A robot starting 2 cm from a wall, facing it (head on, at an angle, or into a corner),
/// can neither drive nor turn in place: the safety monitor refuses every plan's first
/// command. After two holds it backs (or turns) away slowly, plans again, and explores the
/// two rooms to the end without ever touching a wall.
#[test]
fn a_robot_facing_a_wall_too_close_to_turn_backs_away_and_explores() {
    let cases = [
        (31u64, core::f32::consts::PI, false),
        (32, 2.8, false),
        (33, -2.8, false),
        (34, -2.8, true),
    ];
    for (seed, heading, corner) in cases {
        let config = MissionConfig::default();
        // The body the mission is configured for (the datasheet P3-DX, without bumpers).
        let body = config.safety.footprint;
        let mut sim = Sim::new(two_rooms(), &config, seed);
        // How far the outline reaches west and south of the centre at this heading.
        let half = body.width_m / 2.0;
        let corners = [
            (body.front_m, half),
            (body.front_m, -half),
            (-body.rear_m, half),
            (-body.rear_m, -half),
        ];
        let reach = |f: fn(Point2) -> f32| {
            corners
                .iter()
                .map(|&(x, y)| f(Pose2::new(0.0, 0.0, heading).transform_point(Point2::new(x, y))))
                .fold(0.0f32, f32::max)
        };
        let west = reach(|p| -p.x);
        let south = reach(|p| -p.y);
        let gap = 0.02;
        let y = if corner { 0.1 + south + gap } else { 2.5 };
        let start = Pose2::new(0.1 + west + gap, y, heading);
        assert!(!touches(&sim.world, &body, start));
        sim.add(config, start, Slip::thesis());
        // Too close to turn in place: the turning circle (0.25 m + 0.05 m) holds the wall.
        assert!(sim.world.clearance(start.position()) < 0.3);
        while sim.secs() < 900.0 {
            sim.period();
            let pose = sim.bots[0].true_pose();
            assert!(
                !touches(&sim.world, &body, pose),
                "seed {seed}: touched a wall at {pose:?} at {} s",
                sim.secs()
            );
            if matches!(sim.bots[0].mission.state(), MissionState::Done(_)) {
                break;
            }
        }
        let m = &sim.bots[0].mission;
        assert_eq!(
            m.state(),
            MissionState::Done(DoneReason::NothingReachable),
            "seed {seed} after {} s: {:?}",
            sim.secs(),
            m.stats()
        );
        assert!(m.stats().escapes >= 1, "seed {seed}: {:?}", m.stats());
        assert!(m.stats().escapes <= 6, "seed {seed}: {:?}", m.stats());
        let known = known_fraction(&sim);
        assert!(
            known > 0.97,
            "seed {seed}: only {known} known, {:?}",
            m.stats()
        );
    }
}

/// A room with a dead-end pocket 0.55 m wide and 0.7 m deep in its east wall (a narrow
/// corridor's closed end, a door into a cupboard), from x = 5 to 5.7 around y = 2.
fn room_with_pocket() -> World {
    let mut w = World::new(8.0, 4.0);
    w.fill(5.0, 0.0, 8.0, 4.0, true);
    w.fill(5.0, 1.75, 5.7, 2.3, false);
    w
}

/// A robot deep in a narrow dead end, facing out of it a little askew, its back 5 cm from
/// the dead end's wall, which the map knows (the robot saw it driving in) but its 180° laser
/// cannot see: the side walls are too close to turn in place, so the plans' first turn is
/// refused. Its escape must not back into the wall behind it (issue 17: gen-15 seed 27 backed
/// into a wall only the map knew, again and again, and gave the mission up at 5 %): it drives
/// out the way it faces, to where it can turn, and explores the room without touching a
/// wall.
#[test]
fn a_wedged_robot_escapes_the_way_it_fits_not_into_the_wall_behind_it() {
    for (seed, skew) in [(51u64, 0.15f32), (52, -0.15), (53, 0.2)] {
        let config = MissionConfig::default();
        let body = config.safety.footprint;
        let world = room_with_pocket();
        let mut sim = Sim::new(world, &config, seed);
        // The dead end's wall on the map, as seen when the robot drove in.
        let g = *sim.map.grid.geometry();
        for i in 0..g.cell_count() {
            let c = g.cell_center(g.cell(i));
            if c.x > 5.7 && c.x < 6.0 && c.y > 1.6 && c.y < 2.5 {
                sim.map.grid.set_class(i, CellClass::Occupied, &mut ());
            }
        }
        sim.map.rebuild_traversability().unwrap();
        let heading = core::f32::consts::PI - skew;
        // How far the outline reaches east of the centre at this heading.
        let half = body.width_m / 2.0;
        let east = [
            (body.front_m, half),
            (body.front_m, -half),
            (-body.rear_m, half),
            (-body.rear_m, -half),
        ]
        .iter()
        .map(|&(x, y)| {
            Pose2::new(0.0, 0.0, heading)
                .transform_point(Point2::new(x, y))
                .x
        })
        .fold(0.0f32, f32::max);
        let start = Pose2::new(5.7 - 0.05 - east, 2.025, heading);
        assert!(!touches(&sim.world, &body, start));
        sim.add(config, start, Slip::thesis());
        // Too close to the side walls to turn in place.
        assert!(sim.world.clearance(start.position()) < 0.29);
        while sim.secs() < 900.0 {
            sim.period();
            let pose = sim.bots[0].true_pose();
            assert!(
                !touches(&sim.world, &body, pose),
                "seed {seed}: touched a wall at {pose:?} at {} s, {:?}",
                sim.secs(),
                sim.bots[0].mission.stats()
            );
            if matches!(sim.bots[0].mission.state(), MissionState::Done(_)) {
                break;
            }
        }
        let m = &sim.bots[0].mission;
        assert_eq!(
            m.state(),
            MissionState::Done(DoneReason::NothingReachable),
            "seed {seed} after {} s: {:?}",
            sim.secs(),
            m.stats()
        );
        assert!(m.stats().escapes >= 1, "seed {seed}: {:?}", m.stats());
        let known = known_fraction(&sim);
        assert!(
            known > 0.97,
            "seed {seed}: only {known} known, {:?}",
            m.stats()
        );
    }
}

/// Scans given with [`Mission::on_scan_unmapped`] keep the safety monitor fresh (no stale
/// fault, the robot keeps driving) and leave the map as it was.
#[test]
fn unmapped_scans_keep_the_robot_going_and_the_map_unchanged() {
    let mut sim = cruising(21);
    sim.bots[0].feed_scans = false;
    let before = sim.map.grid.log_odds().to_vec();
    let mut moved = 0;
    for _ in 0..20 {
        let pose = sim.bots[0].true_pose();
        let laser = sim.bots[0].mission.config().laser;
        let scan = sim.world.scan(pose, &laser, &[]);
        sim.bots[0].mission.on_scan_unmapped(sim.now, &scan);
        if moving(sim.period()[0]) {
            moved += 1;
        }
        assert!(
            !matches!(sim.bots[0].mission.state(), MissionState::Fault(_)),
            "{:?}",
            sim.bots[0].mission.state()
        );
    }
    assert!(moved >= 15, "moved in {moved} of 20 periods");
    assert!(
        sim.map.grid.log_odds() == before.as_slice(),
        "the map changed"
    );
}

/// A planner double: A* that counts the paths it was asked for.
#[derive(bytemuck::Zeroable)]
struct CountingPlanner {
    astar: AStar<CELLS>,
    plans: u32,
}

impl Planner<CELLS> for CountingPlanner {
    fn plan(
        &mut self,
        trav: &Traversability<CELLS>,
        start: crate::grid::Cell,
        goal: crate::grid::Cell,
        path: &mut [crate::grid::Cell],
    ) -> Result<PlannedPath, PlanError> {
        self.plans += 1;
        self.astar.find_path(trav, start, goal, path)
    }
}

#[test]
fn the_mission_plans_its_paths_through_the_planner_it_is_given() {
    // Two targets per decision: the leg from the robot comes from the distance field, the
    // leg between the targets from the planner.
    let config = || {
        let mut c = MissionConfig::default();
        c.explore.targets = 2;
        c.explore.max_generations = 5;
        c
    };
    let plain = explore(config(), Slip::thesis(), 4, 40.0);
    let counted = explore_with::<CountingPlanner>(config(), Slip::thesis(), 4, 40.0);
    let stats = counted.bots[0].mission.stats();
    assert!(stats.decisions > 0, "{stats:?}");
    assert!(counted.ws.planner().plans > 0, "{stats:?}");
    // The double, being A*, changes nothing.
    assert_eq!(plain.bots[0].mission.stats(), stats);
    assert_eq!(plain.bots[0].true_pose(), counted.bots[0].true_pose());
}

/// Runs robot 0 until Done or `max_s`, feeding `volts(t)` as its battery voltage every
/// period; returns when the mission tripped on the voltage (if it did).
fn run_with_voltage(sim: &mut Sim, max_s: f32, volts: impl Fn(f32) -> f32) -> Option<f32> {
    let mut tripped_at = None;
    while sim.secs() < max_s {
        let t = sim.secs();
        let now = sim.now;
        if sim.bots[0].mission.on_battery_voltage(now, volts(t)) {
            tripped_at = Some(t);
        }
        sim.period();
        let bot = &sim.bots[0];
        let p = bot.true_pose().position();
        assert!(sim.world.clearance(p) > 0.18, "hit a wall at {p:?}");
        if matches!(bot.mission.state(), MissionState::Done(_)) {
            break;
        }
    }
    tripped_at
}

fn events_of(bot: &Bot) -> Vec<MissionEvent> {
    bot.log.iter().map(|(_, e)| e.clone()).collect()
}

/// Return to start: the battery (or the end of exploring) ends the mission, the robot drives back to where it started
/// (same planner, follower and safety monitor: no wall touched), then the mission is done
/// with the battery as its reason.
#[test]
fn with_return_to_start_an_ended_mission_drives_back_to_its_start() {
    for seed in [3, 9] {
        let config = MissionConfig {
            battery_steps: 40.0,
            explore: crate::explore::ExploreConfig {
                reserve_steps: 4.0,
                ..crate::explore::ExploreConfig::default()
            },
            return_to_start: true,
            ..frontier_config()
        };
        let start = Pose2::new(1.0, 1.0, 0.3);
        let mut sim = Sim::new(two_rooms(), &config, seed);
        sim.add(config, start, Slip::thesis());
        run_with_voltage(&mut sim, 900.0, |_| 0.0);
        let bot = &sim.bots[0];
        let events = events_of(bot);
        // The end (the battery, or the two rooms explored first) sent it back, and is the
        // mission's reason once it is there.
        let (returning, reason) = events
            .iter()
            .enumerate()
            .find_map(|(i, e)| match e {
                MissionEvent::Returning(r) => Some((i, *r)),
                _ => None,
            })
            .expect("a Returning event");
        assert_eq!(
            bot.mission.state(),
            MissionState::Done(reason),
            "seed {seed}"
        );
        // It had gone somewhere first.
        assert!(bot.mission.stats().distance_m > 5.0, "seed {seed}");
        assert!(
            events[returning..]
                .iter()
                .any(|e| matches!(e, MissionEvent::Decided { .. })),
            "seed {seed}: the way back is planned"
        );
        let home = bot.mission.pose_map().position().distance(start.position());
        assert!(home <= 0.1, "seed {seed}: estimate {home} m from the start");
        let truth = bot.true_pose().position().distance(start.position());
        assert!(truth <= 0.5, "seed {seed}: {truth} m from the start");
        assert_eq!(bot.mission.returning(), None);
    }
}

/// Voltage: a sag under load (1.5 s below the threshold at a time) never ends the mission; a
/// voltage that stays low ends it after the hold time, with `VoltageLow`, and (with return to
/// start) only once the robot is back.
#[test]
fn a_low_voltage_ends_the_mission_only_when_it_stays_low() {
    let config = MissionConfig {
        return_to_start: true,
        ..frontier_config()
    };
    let start = Pose2::new(1.0, 1.0, 0.3);
    let mut sim = Sim::new(two_rooms(), &config, 5);
    sim.add(config.clone(), start, Slip::thesis());
    // 12.4 V, sagging to 11.0 V for 1.5 s of every 4 s, for 30 s; then 11.3 V for good.
    let low_from_s = 30.0;
    let volts = |t: f32| {
        if t >= low_from_s {
            11.3
        } else if t % 4.0 < 1.5 {
            11.0
        } else {
            12.4
        }
    };
    let tripped = run_with_voltage(&mut sim, 600.0, volts).expect("the watch tripped");
    let hold = config.voltage.hold_s;
    assert!(
        tripped >= low_from_s + hold && tripped <= low_from_s + hold + 0.2,
        "tripped at {tripped} s"
    );
    let bot = &sim.bots[0];
    assert_eq!(
        bot.mission.state(),
        MissionState::Done(DoneReason::VoltageLow)
    );
    let events = events_of(bot);
    let returning = bot
        .log
        .iter()
        .find(|(_, e)| *e == MissionEvent::Returning(DoneReason::VoltageLow))
        .map(|(t, _)| t.as_secs_f64() as f32)
        .expect("a Returning event");
    assert!(returning >= tripped && returning <= tripped + 0.2);
    assert_eq!(
        events
            .iter()
            .filter(|e| matches!(e, MissionEvent::Done(_)))
            .count(),
        1
    );
    let truth = bot.true_pose().position().distance(start.position());
    assert!(truth <= 0.5, "{truth} m from the start");

    // Without return to start, the same voltage stops the robot where it is.
    let config = frontier_config();
    let mut sim = Sim::new(two_rooms(), &config, 5);
    sim.add(config, start, Slip::thesis());
    run_with_voltage(&mut sim, 600.0, volts).expect("the watch tripped");
    let bot = &sim.bots[0];
    assert_eq!(
        bot.mission.state(),
        MissionState::Done(DoneReason::VoltageLow)
    );
    assert!(
        !events_of(bot)
            .iter()
            .any(|e| matches!(e, MissionEvent::Returning(_)))
    );
    assert!(!moving(sim.period()[0]));
}

/// `end` stops a mission at the next step; with return to start it returns first. Ending a
/// mission already at its start (or a finished one) needs no way back.
#[test]
fn the_caller_can_end_a_mission() {
    let config = frontier_config();
    let start = Pose2::new(1.0, 1.0, 0.0);
    let mut sim = Sim::new(two_rooms(), &config, 4);
    sim.add(config.clone(), start, Slip::none());
    sim.period();
    // Still at its start: done at once, even with return to start.
    sim.bots[0].mission.end(DoneReason::Requested);
    sim.period();
    assert_eq!(
        sim.bots[0].mission.state(),
        MissionState::Done(DoneReason::Requested)
    );
    let config = MissionConfig {
        return_to_start: true,
        ..config
    };
    let mut sim = Sim::new(two_rooms(), &config, 4);
    sim.add(config, start, Slip::none());
    while sim.bots[0]
        .true_pose()
        .position()
        .distance(start.position())
        < 1.0
    {
        assert!(sim.secs() < 120.0, "the robot never left its start");
        sim.period();
    }
    sim.bots[0].mission.end(DoneReason::Requested);
    sim.period();
    assert_eq!(sim.bots[0].mission.returning(), Some(DoneReason::Requested));
    // A second end while returning changes nothing.
    sim.bots[0].mission.end(DoneReason::VoltageLow);
    run_with_voltage(&mut sim, 300.0, |_| 0.0);
    assert_eq!(
        sim.bots[0].mission.state(),
        MissionState::Done(DoneReason::Requested)
    );
    let truth = sim.bots[0]
        .true_pose()
        .position()
        .distance(start.position());
    assert!(truth <= 0.2, "{truth}");
}

/// Heading turned (sum of the per-period changes) and distance driven by robot 0 until its
/// first decision, and whether it decided at all within `max_s`.
fn motion_before_first_decision(config: MissionConfig, max_s: f32) -> (f32, f32, bool) {
    let start = Pose2::new(1.0, 1.0, 0.3);
    let mut sim = Sim::new(two_rooms(), &config, 3);
    sim.add(config, start, Slip::none());
    let mut turned = 0.0;
    let mut last = sim.bots[0].true_pose();
    while sim.secs() < max_s {
        sim.period();
        let bot = &sim.bots[0];
        let decided = bot
            .log
            .iter()
            .any(|(_, e)| matches!(e, MissionEvent::Decided { .. }));
        if decided {
            let driven = start.position().distance(last.position());
            return (turned, driven, true);
        }
        let pose = bot.true_pose();
        turned += crate::geometry::normalize_angle(pose.theta - last.theta).abs();
        last = pose;
    }
    (turned, start.position().distance(last.position()), false)
}

/// With `look_around` on, the efficient objective's optimizer first turns in place by the
/// laser's blind sector (the thesis laser sees 180°: 180° + 10° turned) before it decides;
/// the thesis objective and the frontier rules decide at once, without turning.
#[test]
fn the_look_around_turns_by_the_blind_sector_before_the_first_decision_only_when_efficient() {
    let on = MissionConfig {
        look_around: true,
        ..MissionConfig::default()
    };
    assert_eq!(
        on.explore.objective,
        crate::explore::ObjectiveKind::Efficient
    );
    let (turned, driven, decided) = motion_before_first_decision(on.clone(), 40.0);
    assert!(decided, "no decision within 40 s");
    let blind = core::f32::consts::TAU - 180f32.to_radians();
    assert!(
        turned >= blind && turned < blind + 30f32.to_radians(),
        "turned {} deg before deciding",
        turned.to_degrees()
    );
    assert!(driven < 0.05, "drove {driven} m while looking around");

    let thesis = MissionConfig {
        explore: crate::explore::ExploreConfig {
            objective: crate::explore::ObjectiveKind::Thesis,
            ..on.explore
        },
        ..on.clone()
    };
    let frontier = MissionConfig {
        look_around: true,
        ..frontier_config()
    };
    for (name, config) in [("thesis", thesis), ("nearest frontier", frontier)] {
        let (turned, _, decided) = motion_before_first_decision(config, 40.0);
        assert!(decided, "{name}: no decision within 40 s");
        assert!(
            turned < 1e-3,
            "{name}: turned {} deg before deciding",
            turned.to_degrees()
        );
    }
}

/// With the motion filter on, a scan goes into the map only once the robot moved past the
/// threshold since the last mapped scan: the others leave the map as it was, and the robot
/// keeps driving on them (the safety monitor sees every scan).
#[test]
fn the_motion_filter_maps_a_scan_only_after_the_robot_moved_far_enough() {
    use super::MotionFilterConfig;
    let config = MissionConfig {
        motion_filter: MotionFilterConfig::on(0.3, core::f32::consts::PI, 100.0),
        ..frontier_config()
    };
    let world = World::new(8.0, 5.0);
    let mut sim = Sim::new(world.clone(), &config, 21);
    world.reveal(&mut sim.map);
    sim.add(config, Pose2::new(1.0, 2.5, 0.0), Slip::none());
    sim.bots[0].mission.go_to(&[Point2::new(7.0, 2.5)]).unwrap();
    let mut last_mapped: Option<Point2> = None;
    let (mut mapped, mut held) = (0, 0);
    for _ in 0..100 {
        let before = sim.map.grid.log_odds().to_vec();
        sim.period();
        let m = &sim.bots[0].mission;
        assert!(
            !matches!(m.state(), MissionState::Fault(_)),
            "{:?}",
            m.state()
        );
        let here = m.pose_map().position();
        if m.last_scan_mapped() {
            mapped += 1;
            if let Some(p) = last_mapped {
                assert!(
                    p.distance(here) >= 0.3 - 1e-4,
                    "mapped after {} m",
                    p.distance(here)
                );
            }
            last_mapped = Some(here);
        } else {
            held += 1;
            assert!(
                sim.map.grid.log_odds() == before.as_slice(),
                "a held-back scan changed the map"
            );
            let p = last_mapped.expect("the first scan is mapped");
            assert!(
                p.distance(here) < 0.3,
                "held back after {} m",
                p.distance(here)
            );
        }
    }
    let driven = sim.bots[0].mission.stats().distance_m;
    assert!(driven > 1.5, "drove {driven} m");
    assert!(held > mapped, "{mapped} mapped, {held} held back");
    assert!(mapped >= 3, "{mapped} mapped");
}

/// A mission with the standard motion filter explores the two rooms as one mapping every
/// scan does.
#[test]
fn explores_two_rooms_to_done_with_the_motion_filter() {
    for seed in [1, 3] {
        let config = MissionConfig {
            selector: SelectorKind::Optimized(crate::optim::Method::Xboa),
            motion_filter: super::MotionFilterConfig::standard(),
            ..MissionConfig::default()
        };
        let sim = explore(config, Slip::thesis(), seed, 1500.0);
        assert_two_rooms_explored(&sim, seed);
    }
}

/// A bad grazing-miss offset is refused when the mission is made, not at its first scan
/// (where the sensor model would refuse it under another name).
#[test]
fn a_bad_grazing_miss_offset_is_refused_by_name() {
    let mut config = MissionConfig::default();
    config.localize.enabled = true;
    config.localize.grazing_miss_offset_cells = Some(f32::NAN);
    match Mission::<CELLS>::new(0, config, Pose2::new(1.0, 1.0, 0.0)) {
        Err(MissionError::BadConfig { field, .. }) => {
            assert_eq!(field, "localize.grazing_miss_offset_cells")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_bad_motion_filter_threshold_is_refused_by_name() {
    let config = MissionConfig {
        motion_filter: super::MotionFilterConfig::on(0.2, -1.0, 2.0),
        ..MissionConfig::default()
    };
    match Mission::<CELLS>::new(0, config, Pose2::new(1.0, 1.0, 0.0)) {
        Err(MissionError::BadConfig { field, .. }) => {
            assert_eq!(field, "motion_filter.min_turn_rad")
        }
        other => panic!("{other:?}"),
    }
}
