//! The fast mission runner: the core's exploration mission for one or several robots sharing
//! one map, in process and in simulated time.
//!
//! Time advances event by event: a control period every [`CONTROL_PERIOD_US`] (100 ms, the
//! P3-DX's SIP cycle) and a scan every `1 / laser.rate_hz` seconds; between events the bodies'
//! physics runs ([`crate::physics::advance_all`], each robot seeing the others as discs), and
//! doors and people move ([`crate::dynamic`]). At a scan, each robot's laser
//! ([`crate::laser::LaserSim`], other robots and people as discs) measures from its **true**
//! pose and the mission integrates it at its **estimated** pose, fed from the body's drifting
//! odometry ([`crate::physics::RobotBody::odometry_pose`]). At a control period, each mission
//! gets its odometry and flags (bumpers, stall, motors, e-stop), the shared coverage (from the
//! world's truth, [`crate::world::truth`]) and one [`Mission::step`], whose command drives the
//! body. Robots decide one after the other in id order, so the whole run is deterministic per
//! seed: every robot's body, laser and decision generator is a seeded Xoshiro stream derived
//! from the run's seed ([`derive_seed`]).
//!
//! How the missions are pumped is [`RunConfig::pump`]: the runner's ideal pump (the coverage
//! of the truth reported to the missions, decisions taking no simulated time, every scan
//! mapped), or `papillon run`'s ([`PumpModel::onboard`]: no coverage, decisions taking the
//! binary's time while the robot stands, no scan mapped while turning faster than 20 deg/s, the
//! run ended when decisions stop adding to the map), so that a run predicts the binary.
//!
//! The run ends when every mission is done, or at a simulated-time limit
//! ([`RunConfig::max_sim_time_s`]) so that a stuck mission ends with a reason instead of
//! running forever. What is recorded is listed on [`RunReport`] and [`RobotReport`].

use std::fmt;
use std::time::Instant;

use papillon::control::Time;
use papillon::control::command::RobotCommand;
use papillon::control::safety::RobotFlags;
use papillon::geometry::Pose2;
use papillon::grid::CellClass;
use papillon::mission::{DoneReason, Mission, MissionEvent, MissionState, SharedMap, Workspace};
use papillon::random::{self, ProjectRng};
use papillon::sensor::{LaserConfig, Scan};

use crate::dynamic::Dynamics;
use crate::laser::LaserSim;
use crate::localization_report::LocalizationReport;
use crate::map_accuracy;
use crate::physics::{Disc, RobotBody, advance_all};
use crate::placement::start_poses;
use crate::render::Track;
use crate::world::World;

mod config;
mod coverage;
mod report;

pub use config::{
    PumpModel, RunConfig, RunError, STALL_DECISIONS, STALL_IDLE_DECISIONS, STALL_NEW_CELLS,
    STALL_STEPS, default_time_limit_s, derive_seed,
};
use config::{STREAM_BODY, STREAM_DECIDE, STREAM_LASER};
use coverage::CoverageCounter;
pub use report::{EndReason, LoggedEvent, RobotReport, RunReport};

/// Largest map the runner holds \[cells\]: the largest of the capacities it picks from
/// ([`papillon::capacity`]; [`run_sized`] and [`papillon::with_cell_capacity!`] pick the
/// smallest that holds the world).
pub const MAP_CAPACITY: usize = papillon::capacity::MAX_CELLS;

/// The capacity of [`Runner::new`]'s runner \[cells\] (tests and examples on small maps; a
/// program sizes its runner to the map with [`Runner::sized`] through
/// [`papillon::with_cell_capacity!`], or [`run_sized`]).
pub const FIXED_CAPACITY: usize = papillon::capacity::FIXED_CELLS;

/// Control period \[µs\] (10 Hz).
pub const CONTROL_PERIOD_US: u64 = 100_000;

/// Most robots in one run (the core's shared-map limit).
pub const MAX_ROBOTS: usize = papillon::mission::MAX_ROBOTS;

/// Full recount of the coverage every this many control periods (between recounts, the cells
/// around each scan are updated).
const RECOUNT_PERIODS: u64 = 10;

/// Trajectory points closer than this to the previous one are not recorded \[m\].
const TRACK_SPACING_M: f32 = 0.05;

/// One simulated robot's laser, mission and decision generator (its body lives in
/// [`Runner::bodies`], so that the physics can step all bodies together).
struct Robot<const N: usize> {
    laser: LaserSim,
    mission: Mission<N>,
    rng: ProjectRng,
    report: RobotReport,
    last_odom: Option<Pose2>,
    was_stalled: bool,
    /// Until when the mission is deciding ([`PumpModel::decision_latency_s`]) \[µs\].
    busy_until_us: u64,
    /// (known cells of the map, energy used) at the latest decisions
    /// ([`PumpModel::nothing_observable_end`]).
    stall: std::collections::VecDeque<(usize, f32)>,
}

impl<const N: usize> Robot<N> {
    /// Feeds the body's odometry to the mission and accumulates distance and rotation.
    fn feed_odometry(&mut self, now: Time, body: &RobotBody) {
        let odom = body.odometry_pose();
        if let Some(prev) = self.last_odom {
            self.report.distance_m += prev.position().distance(odom.position()) as f64;
            self.report.rotation_rad +=
                papillon::geometry::normalize_angle(odom.theta - prev.theta).abs() as f64;
        }
        self.last_odom = Some(odom);
        self.mission.on_odometry(now, odom, flags(body));
    }
}

/// What a body's status tells its mission: bumpers, stall, motors, e-stop.
pub fn flags(b: &RobotBody) -> RobotFlags {
    RobotFlags {
        front_bumper: b.front_bumper(),
        rear_bumper: b.rear_bumper(),
        left_stall: b.stalled(),
        right_stall: b.stalled(),
        motors_enabled: b.motors_enabled(),
        estop: b.e_stop(),
    }
}

/// Applies a mission command to a body. `SetLimits` and `KeepAlive` change nothing in the
/// simulation (the body has the P3-DX's limits; there is no watchdog).
pub fn apply(body: &mut RobotBody, command: RobotCommand) {
    match command {
        RobotCommand::Velocity(v) => {
            body.command(v.speed_mm_s() as f32, v.turn_rate_deg_s() as f32)
        }
        RobotCommand::Stop | RobotCommand::EmergencyStop => body.stop(),
        RobotCommand::EnableMotors(on) => body.set_motors_enabled(on),
        _ => {}
    }
}

/// Whether a step's events hold a decision.
fn deciding_now(events: &[MissionEvent]) -> bool {
    events
        .iter()
        .any(|e| matches!(e, MissionEvent::Decided { .. }))
}

/// The discs of `discs` a laser on a robot at `pose` can see: those whose boundary comes
/// within the laser's maximum range of the laser's origin (with a centimetre to spare), into
/// `out` in their order. A beam returns from a disc only at a distance within the range
/// ([`crate::laser::LaserSim::scan_into`] takes the nearest return), so a scan against these
/// is the scan against all of `discs`, bit for bit; the filter is one squared distance per
/// disc, against the beams x discs ray tests it saves (a hundred robots: 100 discs for each
/// of 181 beams).
pub fn discs_in_reach(laser: &LaserConfig, pose: Pose2, discs: &[Disc], out: &mut Vec<Disc>) {
    let origin = pose.compose(laser.mount).position();
    out.clear();
    out.extend(discs.iter().copied().filter(|d| {
        let reach = laser.max_range_m + d.radius_m + 0.01;
        let (dx, dy) = (d.center.x - origin.x, d.center.y - origin.y);
        // A NaN range keeps every disc (no ordering), as the laser would test them all.
        (dx * dx + dy * dy).partial_cmp(&(reach * reach)) != Some(std::cmp::Ordering::Greater)
    }));
}

/// What [`Runner::run_with`] reports to its observer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// Robot `robot` made a decision (its targets are in the report).
    Decided {
        /// Robot index.
        robot: usize,
    },
    /// Robot `robot`'s laser took a scan ([`Runner::last_scan`]), mapped or not.
    Scanned {
        /// Robot index.
        robot: usize,
    },
    /// A control period ran (every robot got its odometry and, unless deciding, a step).
    Controlled,
    /// The run ended.
    Finished,
}

/// A run in progress: the world, the robots and the shared map.
pub struct Runner<const N: usize = FIXED_CAPACITY> {
    world: World,
    dynamics: Dynamics,
    bodies: Vec<RobotBody>,
    robots: Vec<Robot<N>>,
    map: Box<SharedMap<N>>,
    ws: Box<Workspace<N>>,
    coverage: CoverageCounter,
    config: RunConfig,
    now_us: u64,
    next_control_us: u64,
    next_scan_us: u64,
    scan_period_us: u64,
    periods: u64,
    report: RunReport,
    /// Each robot's latest scan.
    scans: Vec<Scan>,
    /// What the latest [`Runner::advance`] did: scanned, ran a control period.
    last_event: (bool, bool),
    last_sample: Option<(f32, f32)>,
}

impl<const N: usize> fmt::Debug for Runner<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Runner")
            .field("world", &self.world.name())
            .field("robots", &self.robots.len())
            .field("capacity", &N)
            .field("now_s", &(self.now_us as f64 * 1e-6))
            .finish_non_exhaustive()
    }
}

/// Sets up a run sized to `world` (the smallest capacity of [`papillon::capacity`] that
/// holds it) and runs it to the end: [`Runner::sized`] and [`Runner::run`] in one call.
pub fn run_sized(
    world: World,
    dynamics: Dynamics,
    config: RunConfig,
) -> Result<RunReport, RunError> {
    let cells = world.geometry().cell_count();
    papillon::with_cell_capacity!(cells, N => {
        Runner::<N>::sized(world, dynamics, config)?.run()
    })
    .unwrap_or(Err(RunError::MapTooLarge {
        cells,
        capacity: MAP_CAPACITY,
    }))
}

impl Runner {
    /// Sets up a run in `world` (the truth is taken from its current state and start pose),
    /// with `dynamics` (doors and people; empty for none), on a map of [`FIXED_CAPACITY`]
    /// cells (a bigger world is refused: size the runner with [`Runner::sized`]).
    pub fn new(world: World, dynamics: Dynamics, config: RunConfig) -> Result<Self, RunError> {
        Self::sized(world, dynamics, config)
    }
}

impl<const N: usize> Runner<N> {
    /// [`Runner::new`] on a map of `N` cells (pick `N` with [`papillon::with_cell_capacity!`]).
    pub fn sized(world: World, dynamics: Dynamics, config: RunConfig) -> Result<Self, RunError> {
        if config.robots == 0 || config.robots > MAX_ROBOTS {
            return Err(RunError::Robots(config.robots));
        }
        let g = *world.geometry();
        if g.cell_count() > N {
            return Err(RunError::MapTooLarge {
                cells: g.cell_count(),
                capacity: N,
            });
        }
        config.mission.validate()?;
        let radius = config.body.radius_m;
        if !world.start_is_clear(radius) {
            return Err(RunError::StartBlocked {
                robot: 0,
                pose: world.start(),
            });
        }
        let starts = match &config.starts {
            Some(s) => {
                if s.len() < config.robots {
                    return Err(RunError::NoStart { robot: s.len() });
                }
                s[..config.robots].to_vec()
            }
            None => start_poses(&world, world.start(), config.robots, radius)
                .map_err(|e| RunError::NoStart { robot: e.robot })?,
        };
        let mut robots = Vec::with_capacity(config.robots);
        let mut bodies = Vec::with_capacity(config.robots);
        // The streams of the laser noise and the wheel slip: the run's seed's own (draw 0),
        // or another draw of the same seed (`PumpModel::noise_draw`).
        let world_seed = config
            .seed
            .wrapping_add(config.pump.noise_draw.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        for (k, &pose) in starts.iter().enumerate() {
            if world.disc_hits_blocked(pose.position(), radius)
                || starts[..k]
                    .iter()
                    .any(|q| q.position().distance(pose.position()) < 2.0 * radius)
            {
                return Err(RunError::StartBlocked { robot: k, pose });
            }
            let mission = Mission::new(k as u8, config.mission.clone(), pose)?;
            bodies.push(RobotBody::new(
                config.body,
                pose,
                derive_seed(world_seed, k, STREAM_BODY),
            ));
            robots.push(Robot {
                laser: {
                    let laser = LaserSim::new(
                        config.mission.laser,
                        derive_seed(world_seed, k, STREAM_LASER),
                    )
                    .with_range_sigma_m(config.laser_range_sigma_m);
                    match config.pump.laser_reach_m {
                        Some(reach_m) => laser.with_reach_m(reach_m),
                        None => laser,
                    }
                },
                mission,
                rng: random::seeded(if config.pump.board_seeded_decisions {
                    config.seed.wrapping_add(k as u64)
                } else {
                    derive_seed(config.seed, k, STREAM_DECIDE)
                }),
                report: RobotReport {
                    trajectory: vec![pose.position()],
                    final_pose: pose,
                    ..RobotReport::default()
                },
                last_odom: None,
                was_stalled: false,
                busy_until_us: 0,
                stall: std::collections::VecDeque::new(),
            });
        }
        let map = SharedMap::<N>::new_boxed(g, &config.mission)?;
        let ws = Workspace::<N>::new_boxed();
        let truth = world.truth();
        let rate = config.mission.laser.rate_hz;
        let scan_period_us = if rate.is_finite() && rate > 0.0 {
            ((1e6 / rate as f64).round() as u64).max(1_000)
        } else {
            CONTROL_PERIOD_US
        };
        let report = RunReport {
            observable_cells: truth.len(),
            robots: Vec::new(),
            ..RunReport::default()
        };
        Ok(Self {
            world,
            dynamics,
            bodies,
            robots,
            map,
            ws,
            coverage: CoverageCounter::new(truth),
            config,
            now_us: 0,
            next_control_us: 0,
            next_scan_us: 0,
            scan_period_us,
            periods: 0,
            report,
            scans: vec![Scan::new(); starts.len()],
            last_event: (false, false),
            last_sample: None,
        })
    }

    /// The world as it is now (doors in their current state).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The shared map.
    pub fn map(&self) -> &SharedMap<N> {
        &self.map
    }

    /// Simulated time \[s\].
    pub fn sim_time_s(&self) -> f64 {
        self.now_us as f64 * 1e-6
    }

    /// Current coverage (0..1).
    pub fn coverage(&self) -> f32 {
        self.coverage.coverage()
    }

    /// Robot `k`'s mission.
    pub fn mission(&self, k: usize) -> &Mission<N> {
        &self.robots[k].mission
    }

    /// Robot `k`'s body.
    pub fn body(&self, k: usize) -> &RobotBody {
        &self.bodies[k]
    }

    /// Number of robots.
    pub fn robot_count(&self) -> usize {
        self.robots.len()
    }

    /// The tracks to draw: each robot's trajectory so far and its targets.
    pub fn tracks(&self) -> Vec<Track> {
        self.robots
            .iter()
            .map(|r| Track {
                trajectory: r.report.trajectory.clone(),
                targets: r.report.targets.clone(),
            })
            .collect()
    }

    /// Robot `k`'s latest scan (empty before the first).
    pub fn last_scan(&self, k: usize) -> &Scan {
        &self.scans[k]
    }

    /// The events logged so far, in order.
    pub fn events(&self) -> &[LoggedEvent] {
        &self.report.events
    }

    /// Whether the run has ended.
    pub fn finished(&self) -> bool {
        self.report.reason.is_some()
    }

    /// Runs to the end and returns the report.
    pub fn run(&mut self) -> Result<RunReport, RunError> {
        self.run_with(|_, _| {})
    }

    /// Runs to the end, calling `observer` after each scan ([`Progress::Scanned`], robot by
    /// robot), each control period ([`Progress::Controlled`]), each decision and at the end.
    /// The time spent in `observer` is left out of the report's wall time.
    pub fn run_with(
        &mut self,
        mut observer: impl FnMut(&Runner<N>, Progress),
    ) -> Result<RunReport, RunError> {
        let wall = Instant::now();
        let mut observing_s = 0.0;
        while !self.finished() {
            let decided = self.advance()?;
            let t = Instant::now();
            let (scanned, controlled) = self.last_event;
            if scanned {
                for robot in 0..self.robots.len() {
                    observer(self, Progress::Scanned { robot });
                }
            }
            if controlled {
                observer(self, Progress::Controlled);
            }
            for robot in decided {
                observer(self, Progress::Decided { robot });
            }
            observing_s += t.elapsed().as_secs_f64();
            self.report.wall_time_s = wall.elapsed().as_secs_f64() - observing_s;
        }
        observer(self, Progress::Finished);
        Ok(self.report())
    }

    /// The report so far (final once [`Self::finished`]).
    pub fn report(&self) -> RunReport {
        let mut r = self.report.clone();
        r.coverage = self.coverage.coverage();
        r.known_cells = self.coverage.count;
        r.sim_time_s = self.sim_time_s();
        r.robots = self
            .robots
            .iter()
            .zip(&self.bodies)
            .map(|(rb, body)| {
                let mut rep = rb.report.clone();
                let s = rb.mission.stats();
                rep.steps = s.steps;
                rep.decisions = s.decisions;
                rep.fitness_evals = s.fitness_evals;
                rep.replans = s.replans;
                rep.yields = s.yields;
                rep.faults = s.faults;
                rep.battery_steps = rb.mission.battery_steps();
                rep.done = match rb.mission.state() {
                    MissionState::Done(d) => Some(d),
                    _ => None,
                };
                rep.true_distance_m = body.distance_m();
                rep.final_pose = body.true_pose();
                rep.pose_error_m = body
                    .true_pose()
                    .position()
                    .distance(rb.mission.pose_map().position());
                rep.localization = LocalizationReport::of(body, &rb.mission);
                rep
            })
            .collect();
        r.map_accuracy = map_accuracy::measure(&self.map.grid, &self.world, self.coverage.truth());
        r
    }

    /// Runs up to and including the next event (scan or control period); returns the robots
    /// that decided.
    pub fn advance(&mut self) -> Result<Vec<usize>, RunError> {
        let next = self.next_control_us.min(self.next_scan_us);
        if next > self.now_us {
            let dt = (next - self.now_us) as f32 * 1e-6;
            let people = self.dynamics.people_discs(self.sim_time_s());
            advance_all(&mut self.bodies, dt, &self.world, &people);
            self.now_us = next;
        }
        let now = Time::from_micros(self.now_us);
        self.last_event = (
            self.next_scan_us == self.now_us,
            self.next_control_us == self.now_us,
        );
        if self.next_scan_us == self.now_us {
            self.scan_all(now)?;
            self.next_scan_us += self.scan_period_us;
        }
        let mut decided = Vec::new();
        if self.next_control_us == self.now_us {
            decided = self.control(now);
            self.next_control_us += CONTROL_PERIOD_US;
        }
        Ok(decided)
    }

    fn robot_discs(&self) -> Vec<Disc> {
        self.bodies.iter().map(RobotBody::disc).collect()
    }

    fn scan_all(&mut self, now: Time) -> Result<(), RunError> {
        let mut discs = self.robot_discs();
        discs.extend(self.dynamics.people_discs(self.sim_time_s()));
        let mut near = Vec::with_capacity(discs.len());
        for ((r, body), scan) in self
            .robots
            .iter_mut()
            .zip(&self.bodies)
            .zip(&mut self.scans)
        {
            let pose = body.true_pose();
            // Only the discs within the laser's reach can return (`discs_in_reach`): the
            // same scan as against all of them, at a cost that does not grow with the robots
            // far away.
            discs_in_reach(r.laser.config(), pose, &discs, &mut near);
            // A laser with more beams than a scan holds keeps the first ones.
            let _ = r.laser.scan_into(&self.world, pose, &near, scan);
            r.feed_odometry(now, body);
            let turning = self
                .config
                .pump
                .unmapped_turn_deg_s
                .is_some_and(|limit| body.turn_deg_s().abs() > limit);
            if turning {
                r.mission.on_scan_unmapped(now, scan);
                continue;
            }
            r.mission.on_scan(now, scan, &mut self.map)?;
            if !r.mission.last_scan_mapped() {
                // Held back by the motion filter: the map is as it was.
                continue;
            }
            self.coverage.update_after_scan(
                &self.map.grid,
                r.mission.pose_map(),
                &self.config.mission.laser,
                scan,
            );
        }
        Ok(())
    }

    fn control(&mut self, now: Time) -> Vec<usize> {
        let time_s = self.sim_time_s();
        let discs = self.robot_discs();
        if !self.dynamics.is_empty() {
            self.dynamics.update(time_s, &mut self.world, &discs);
        }
        if self.periods.is_multiple_of(RECOUNT_PERIODS) {
            self.coverage.recount(&self.map.grid);
            self.sample();
        }
        self.periods += 1;
        let coverage = self.coverage.coverage();
        let mut decided = Vec::new();
        let mut nothing_observable = false;
        for k in 0..self.robots.len() {
            let r = &mut self.robots[k];
            let body = &mut self.bodies[k];
            r.feed_odometry(now, body);
            if self.now_us < r.busy_until_us {
                // Still deciding: the robot stands, the mission is not stepped.
                continue;
            }
            if self.config.pump.coverage_known {
                r.mission.set_coverage(coverage);
            }
            let t0 = Instant::now();
            let out = r.mission.step(now, &mut self.map, &mut self.ws, &mut r.rng);
            let elapsed_ms = t0.elapsed().as_secs_f64() * 1e3;
            let latency_us = (self.config.pump.decision_latency_s.max(0.0) * 1e6).round() as u64;
            let deciding = latency_us > 0 && deciding_now(&out.events);
            if deciding_now(&out.events) && self.config.pump.nothing_observable_end {
                let known = (0..self.map.grid.cell_count())
                    .filter(|&i| self.map.grid.class(i) != CellClass::Unknown)
                    .count();
                if r.stall.len() > STALL_IDLE_DECISIONS {
                    r.stall.pop_front();
                }
                let steps = r.mission.stats().steps;
                r.stall.push_back((known, steps));
                let n = r.stall.len();
                let driven = n > STALL_DECISIONS && {
                    let (k0, s0) = r.stall[n - 1 - STALL_DECISIONS];
                    known.saturating_sub(k0) < STALL_NEW_CELLS && steps - s0 >= STALL_STEPS
                };
                let idle = n > STALL_IDLE_DECISIONS
                    && known.saturating_sub(r.stall[0].0) < STALL_NEW_CELLS;
                nothing_observable |= driven || idle;
            }
            if deciding {
                // The decision's command comes `latency` later; until then the robot stops.
                // (A simplification: the binary holds the last command up to 0.3 s first.)
                r.busy_until_us = self.now_us + latency_us;
                body.stop();
            } else {
                apply(body, out.command);
            }
            for e in out.events {
                match &e {
                    MissionEvent::Decided { targets, .. } => {
                        r.report.decision_ms.push(elapsed_ms);
                        r.report
                            .decision_histories
                            .push(r.mission.last_decision_history().to_vec());
                        r.report.targets.extend(targets.iter().copied());
                        decided.push(k);
                    }
                    MissionEvent::WaypointReached { .. } => continue,
                    _ => {}
                }
                self.report.events.push(LoggedEvent {
                    time_s,
                    robot: k,
                    event: e,
                });
            }
            // Contacts and the trajectory.
            let stalled = body.stalled();
            if stalled && !r.was_stalled {
                r.report.collisions += 1;
                if std::env::var_os("PAPILLON_DEBUG_CONTACTS").is_some() {
                    eprintln!(
                        "contact t={time_s:.1} true={:?} state={:?} speed={:.0} turn={:.0}",
                        body.true_pose(),
                        r.mission.state(),
                        body.speed_mm_s(),
                        body.turn_deg_s()
                    );
                }
            }
            r.was_stalled = stalled;
            let p = body.true_pose().position();
            if r.report
                .trajectory
                .last()
                .is_none_or(|q| q.distance(p) >= TRACK_SPACING_M)
            {
                r.report.trajectory.push(p);
            }
        }
        if !decided.is_empty() {
            self.sample();
        }
        if nothing_observable {
            if self.config.mission.return_to_start {
                // Each robot drives back first; the run ends when all are done (their
                // `Requested` end is reported as nothing-observable).
                for r in &mut self.robots {
                    r.mission.end(DoneReason::Requested);
                }
            } else {
                self.end(EndReason::NothingObservable);
            }
        }
        self.check_end();
        decided
    }

    fn steps_so_far(&self) -> f32 {
        self.robots.iter().map(|r| r.mission.stats().steps).sum()
    }

    fn sample(&mut self) {
        let s = (self.steps_so_far(), self.coverage.coverage());
        if self.last_sample == Some(s) {
            return;
        }
        self.last_sample = Some(s);
        self.report.coverage_curve.push(s);
        self.report
            .coverage_time_curve
            .push((self.sim_time_s(), s.1));
        let metres = self
            .robots
            .iter()
            .map(|r| r.mission.stats().distance_m)
            .sum();
        self.report.coverage_distance_curve.push((metres, s.1));
    }

    fn check_end(&mut self) {
        let mut last: Option<DoneReason> = None;
        let mut all_done = true;
        let mut any_coverage = false;
        for r in &self.robots {
            match r.mission.state() {
                MissionState::Done(d) => {
                    any_coverage |= d == DoneReason::CoverageReached;
                    last = Some(d);
                }
                _ => all_done = false,
            }
        }
        let reason = if all_done {
            if any_coverage {
                Some(EndReason::CoverageReached)
            } else {
                last.map(EndReason::from)
            }
        } else if self.sim_time_s() >= self.config.max_sim_time_s {
            Some(EndReason::TimeLimit)
        } else {
            None
        };
        if let Some(reason) = reason {
            self.end(reason);
        }
    }

    fn end(&mut self, reason: EndReason) {
        if self.report.reason.is_some() {
            return;
        }
        self.coverage.recount(&self.map.grid);
        self.last_sample = None;
        self.sample();
        self.report.reason = Some(reason);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::SlipConfig;
    use crate::world::builtin;
    use papillon::mission::MissionConfig;

    #[test]
    fn a_laser_sees_the_same_against_the_discs_in_reach() {
        // Random robots and poses in the house, the thesis's and the LMS1xx's lasers (4 m and
        // 20 m, one mounted ahead of the centre): the scan against the discs in reach is the
        // scan against all of them, bit for bit, and most discs are out of the 4 m reach.
        let w = builtin::house(0.1).unwrap();
        let g = *w.geometry();
        let (wm, hm) = (g.width as f32 * 0.1, g.height as f32 * 0.1);
        let mut rng = random::seeded(11);
        let mut near = Vec::new();
        let (mut kept, mut total) = (0, 0);
        for laser in [LaserConfig::thesis(), LaserConfig::lms1xx()] {
            for trial in 0..200 {
                let discs: Vec<Disc> = (0..30)
                    .map(|_| {
                        Disc::new(
                            papillon::geometry::Point2::new(
                                random::range_f32(&mut rng, 0.0, wm),
                                random::range_f32(&mut rng, 0.0, hm),
                            ),
                            0.25,
                        )
                    })
                    .collect();
                let pose = Pose2::new(
                    random::range_f32(&mut rng, 0.0, wm),
                    random::range_f32(&mut rng, 0.0, hm),
                    random::range_f32(&mut rng, -3.2, 3.2),
                );
                discs_in_reach(&laser, pose, &discs, &mut near);
                if laser.max_range_m < 5.0 {
                    kept += near.len();
                    total += discs.len();
                }
                let all = LaserSim::new(laser, trial).scan(&w, pose, &discs);
                let some = LaserSim::new(laser, trial).scan(&w, pose, &near);
                assert_eq!(all, some, "trial {trial} at {pose:?}");
            }
        }
        assert!(kept < total / 2, "{kept} of {total} discs kept at 4 m");
    }

    #[test]
    fn bad_setups_are_refused() {
        let w = builtin::lab(0.1).unwrap();
        let cfg = RunConfig::new(MissionConfig::default(), 0, 1);
        assert_eq!(
            Runner::new(w.clone(), Dynamics::new(), cfg).unwrap_err(),
            RunError::Robots(0)
        );
        let blocked = w.clone().with_start(Pose2::new(0.1, 0.1, 0.0));
        let cfg = RunConfig::new(MissionConfig::default(), 1, 1);
        let e = Runner::new(blocked, Dynamics::new(), cfg).unwrap_err();
        assert!(matches!(e, RunError::StartBlocked { robot: 0, .. }), "{e}");
        assert!(e.to_string().contains("(0.10 m, 0.10 m)"), "{e}");
    }

    #[test]
    fn a_runner_sized_to_the_world_holds_what_the_fixed_one_refuses() {
        // The factory at 0.05 m: more cells than Runner::new's capacity, fewer than the
        // largest.
        let w = builtin::factory(0.05).unwrap();
        let cells = w.geometry().cell_count();
        assert!(cells > FIXED_CAPACITY && cells <= MAP_CAPACITY, "{cells}");
        let mut cfg = RunConfig::new(MissionConfig::default(), 1, 3);
        cfg.max_sim_time_s = 1.0;
        let e = Runner::new(w.clone(), Dynamics::new(), cfg.clone()).unwrap_err();
        assert_eq!(
            e,
            RunError::MapTooLarge {
                cells,
                capacity: FIXED_CAPACITY
            }
        );
        assert!(e.to_string().contains(&FIXED_CAPACITY.to_string()), "{e}");
        let report = run_sized(w, Dynamics::new(), cfg.clone()).unwrap();
        assert_eq!(report.reason, Some(EndReason::TimeLimit));
        assert!(report.known_cells > 0);
        // Beyond the largest capacity: refused, the limit named.
        let g = papillon::grid::GridGeometry::from_extent(
            210.0,
            210.0,
            0.1,
            papillon::geometry::Point2::default(),
        )
        .unwrap();
        let big = World::new("big".to_string(), g);
        let e = run_sized(big, Dynamics::new(), cfg).unwrap_err();
        assert!(matches!(e, RunError::MapTooLarge { .. }), "{e}");
        assert!(e.to_string().contains(&MAP_CAPACITY.to_string()), "{e}");
    }

    #[test]
    fn a_time_limit_ends_a_run_with_its_reason() {
        let w = builtin::lab(0.1).unwrap();
        let mut cfg = RunConfig::new(MissionConfig::default(), 1, 3);
        cfg.max_sim_time_s = 2.0;
        let mut runner = Runner::new(w, Dynamics::new(), cfg).unwrap();
        let report = runner.run().unwrap();
        assert_eq!(report.reason, Some(EndReason::TimeLimit));
        assert!(
            (report.sim_time_s - 2.0).abs() < 0.11,
            "{}",
            report.sim_time_s
        );
        assert!(report.coverage > 0.0, "the first scans are integrated");
        assert_eq!(report.robots.len(), 1);
        assert!(!report.coverage_curve.is_empty());
    }

    #[test]
    fn without_slip_the_estimate_follows_the_true_pose() {
        let w = builtin::lab(0.1).unwrap();
        let mission = MissionConfig {
            selector: papillon::mission::SelectorKind::NearestFrontier,
            ..MissionConfig::default()
        };
        let mut cfg = RunConfig::new(mission, 1, 3);
        cfg.body.slip = SlipConfig::none();
        cfg.max_sim_time_s = 60.0;
        let mut runner = Runner::new(w, Dynamics::new(), cfg).unwrap();
        let report = runner.run().unwrap();
        let r = &report.robots[0];
        assert!(r.true_distance_m > 2.0, "{r:?}");
        assert!(r.pose_error_m < 0.01, "pose error {} m", r.pose_error_m);
    }
}
