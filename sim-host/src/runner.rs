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
//! The run ends when every mission is done, or at a simulated-time limit
//! ([`RunConfig::max_sim_time_s`]) so that a stuck mission ends with a reason instead of
//! running forever. What is recorded is listed on [`RunReport`] and [`RobotReport`].

use std::fmt;
use std::time::Instant;

use papillon::control::Time;
use papillon::control::command::RobotCommand;
use papillon::control::safety::RobotFlags;
use papillon::geometry::{Point2, Pose2};
use papillon::grid::{DEFAULT_CELL_CAPACITY, GridGeometry, OccupancyGrid};
use papillon::mission::{
    DoneReason, Mission, MissionConfig, MissionError, MissionEvent, MissionState, SharedMap,
    Workspace,
};
use papillon::random::{self, ProjectRng};
use papillon::sensor::{LaserConfig, Scan};

use crate::dynamic::Dynamics;
use crate::laser::LaserSim;
use crate::localization_report::LocalizationReport;
use crate::map_accuracy::{self, MapAccuracy};
use crate::physics::{BodyConfig, Disc, RobotBody, SlipConfig, advance_all};
use crate::render::Track;
use crate::world::{Truth, World};

/// Largest map the runner holds \[cells\] (the core's default: the factory at 0.1 m fits).
pub const MAP_CAPACITY: usize = DEFAULT_CELL_CAPACITY;

/// Control period \[µs\] (10 Hz).
pub const CONTROL_PERIOD_US: u64 = 100_000;

/// Most robots in one run (the core's shared-map limit).
pub const MAX_ROBOTS: usize = papillon::mission::MAX_ROBOTS;

/// Full recount of the coverage every this many control periods (between recounts, the cells
/// around each scan are updated).
const RECOUNT_PERIODS: u64 = 10;

/// Trajectory points closer than this to the previous one are not recorded \[m\].
const TRACK_SPACING_M: f32 = 0.05;

/// A seed for stream `stream` of robot `robot`, derived from the run's seed (SplitMix64's
/// finaliser over the three, Steele, Lea & Flood 2014), so that streams do not overlap.
pub fn derive_seed(seed: u64, robot: usize, stream: u64) -> u64 {
    let mut z =
        seed.wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(1 + robot as u64 * 8 + stream));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

const STREAM_BODY: u64 = 1;
const STREAM_LASER: u64 = 2;
const STREAM_DECIDE: u64 = 3;

/// Settings of one run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// The missions' configuration (the same for every robot); its laser is also the
    /// simulated laser.
    pub mission: MissionConfig,
    /// Number of robots (1..=[`MAX_ROBOTS`]).
    pub robots: usize,
    /// The run's seed.
    pub seed: u64,
    /// The simulated robots' body.
    pub body: BodyConfig,
    /// Start poses, one per robot; `None`: robot 0 at the world's start, the others placed
    /// next to it ([`start_poses`]).
    pub starts: Option<Vec<Pose2>>,
    /// Simulated-time limit \[s\].
    pub max_sim_time_s: f64,
}

impl RunConfig {
    /// A run of `robots` robots with `mission`, seed `seed`, P3-DX bodies with the thesis's
    /// odometry slip ([`SlipConfig::thesis`]: a slide at the end of each move; the full
    /// default slip adds heading random walks that the core, without scan matching, cannot
    /// correct) and a time limit of [`default_time_limit_s`].
    pub fn new(mission: MissionConfig, robots: usize, seed: u64) -> Self {
        let max_sim_time_s = default_time_limit_s(mission.battery_steps);
        Self {
            mission,
            robots,
            seed,
            body: BodyConfig {
                slip: SlipConfig::thesis(),
                ..BodyConfig::default()
            },
            starts: None,
            max_sim_time_s,
        }
    }
}

/// The default simulated-time limit for a battery of `battery_steps`: 10 s per step (a step
/// takes 2.5 s at the exploration speed of 0.4 m/s) plus 10 minutes.
pub fn default_time_limit_s(battery_steps: f32) -> f64 {
    600.0 + 10.0 * battery_steps.max(0.0) as f64
}

/// Why a run cannot start or could not go on.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum RunError {
    /// Robot count outside 1..=[`MAX_ROBOTS`].
    Robots(usize),
    /// The world has more cells than the runner's map holds.
    MapTooLarge {
        /// Cells of the world.
        cells: usize,
    },
    /// A start pose puts the robot in or against an obstacle, or outside the world.
    StartBlocked {
        /// Which robot.
        robot: usize,
        /// The pose.
        pose: Pose2,
    },
    /// Fewer start poses than robots were given, or no free place was found for a robot.
    NoStart {
        /// Which robot.
        robot: usize,
    },
    /// The core mission refused its configuration or input.
    Mission(MissionError),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Robots(n) => write!(f, "robots must be 1 to {MAX_ROBOTS}, got {n}"),
            RunError::MapTooLarge { cells } => write!(
                f,
                "the world has {cells} cells, more than the {MAP_CAPACITY} the runner's map holds (use a coarser resolution)"
            ),
            RunError::StartBlocked { robot, pose } => write!(
                f,
                "start of robot {robot} at ({:.2} m, {:.2} m) is inside or against an obstacle or outside the map",
                pose.x, pose.y
            ),
            RunError::NoStart { robot } => {
                write!(f, "no free start pose for robot {robot} near the start")
            }
            RunError::Mission(e) => write!(f, "mission: {e:?}"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<MissionError> for RunError {
    fn from(e: MissionError) -> Self {
        RunError::Mission(e)
    }
}

/// Start poses for `n` robots: the first at `start`, each next one at the nearest free place
/// (searched on rings 0.8 m apart around `start`, from the start heading on,
/// counter-clockwise) whose disc of `radius_m` plus 0.1 m is clear of walls and at least
/// 0.8 m from every robot placed before. All robots keep the start heading.
pub fn start_poses(
    world: &World,
    start: Pose2,
    n: usize,
    radius_m: f32,
) -> Result<Vec<Pose2>, RunError> {
    let clearance = radius_m + 0.1;
    let spacing = (2.0 * radius_m + 0.3).max(0.8);
    let truth = world.truth();
    let mut poses = vec![start];
    'robots: for robot in 1..n {
        for ring in 1..=30 {
            let r = spacing * ring as f32;
            let count = (2.0 * core::f32::consts::PI * r / spacing).floor().max(6.0) as usize;
            for k in 0..count {
                let a = start.theta + 2.0 * core::f32::consts::PI * k as f32 / count as f32;
                let p = Point2::new(start.x + r * a.cos(), start.y + r * a.sin());
                if world.disc_hits_blocked(p, clearance)
                    || poses.iter().any(|q| q.position().distance(p) < spacing)
                {
                    continue;
                }
                // Reachable from the start: in the start's free component.
                let reachable = world
                    .geometry()
                    .cell_at(p)
                    .and_then(|c| world.geometry().index(c))
                    .is_some_and(|i| truth.mask()[i]);
                if reachable {
                    poses.push(Pose2::new(p.x, p.y, start.theta));
                    continue 'robots;
                }
            }
        }
        return Err(RunError::NoStart { robot });
    }
    Ok(poses)
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EndReason {
    /// The coverage target was reached.
    CoverageReached,
    /// Every mission ran out of energy (or the last one to finish did).
    BatteryExhausted,
    /// Nothing reachable was left unknown (for the last mission to finish).
    NothingReachable,
    /// The simulated-time limit was hit with missions still running.
    TimeLimit,
}

impl EndReason {
    /// Name in reports: `coverage-reached`, `battery-exhausted`, `nothing-reachable`,
    /// `time-limit`.
    pub fn name(self) -> &'static str {
        match self {
            EndReason::CoverageReached => "coverage-reached",
            EndReason::BatteryExhausted => "battery-exhausted",
            EndReason::NothingReachable => "nothing-reachable",
            EndReason::TimeLimit => "time-limit",
        }
    }
}

impl From<DoneReason> for EndReason {
    fn from(r: DoneReason) -> Self {
        match r {
            DoneReason::CoverageReached => EndReason::CoverageReached,
            DoneReason::BatteryExhausted => EndReason::BatteryExhausted,
            DoneReason::NothingReachable => EndReason::NothingReachable,
        }
    }
}

impl fmt::Display for EndReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One recorded mission event.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedEvent {
    /// Simulated time \[s\].
    pub time_s: f64,
    /// Robot index.
    pub robot: usize,
    /// The event.
    pub event: MissionEvent,
}

/// What one robot did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotReport {
    /// Energy used, from odometry \[steps\] (1 m of travel or 45° of rotation each).
    pub steps: f32,
    /// Distance travelled, from odometry \[m\].
    pub distance_m: f64,
    /// Rotation, absolute, summed, from odometry \[rad\].
    pub rotation_rad: f64,
    /// True distance travelled (physics) \[m\].
    pub true_distance_m: f64,
    /// Decisions made.
    pub decisions: u32,
    /// Objective (fitness) evaluations over all decisions.
    pub fitness_evals: u64,
    /// Wall-clock compute time of each decision \[ms\]: the `step` call that emitted it.
    pub decision_ms: Vec<f64>,
    /// Best fitness per generation of each decision, initial population first (the
    /// optimizer's convergence curve; empty for the frontier rules).
    pub decision_histories: Vec<Vec<f32>>,
    /// Replans.
    pub replans: u32,
    /// Times the robot gave way to another.
    pub yields: u32,
    /// Faults.
    pub faults: u32,
    /// Contacts: times the body's stall flag rose (a wall, door, robot or person hit).
    pub collisions: u32,
    /// Energy left \[steps\].
    pub battery_steps: f32,
    /// How the robot's mission ended, if it did.
    pub done: Option<DoneReason>,
    /// True positions, every 5 cm of motion.
    pub trajectory: Vec<Point2>,
    /// Targets chosen, in order.
    pub targets: Vec<Point2>,
    /// Final true pose.
    pub final_pose: Pose2,
    /// Final distance between the true and the estimated position \[m\].
    pub pose_error_m: f32,
    /// Final poses and pose errors of the estimate and of the raw odometry.
    pub localization: LocalizationReport,
}

/// What the run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunReport {
    /// Final coverage of the shared map (0..1).
    pub coverage: f32,
    /// Observable cells.
    pub observable_cells: usize,
    /// Known observable cells at the end.
    pub known_cells: usize,
    /// Per robot.
    pub robots: Vec<RobotReport>,
    /// Simulated time \[s\].
    pub sim_time_s: f64,
    /// Wall-clock time of the run \[s\], not counting the observer's (pictures).
    pub wall_time_s: f64,
    /// Why it ended (`None` while running).
    pub reason: Option<EndReason>,
    /// Coverage over steps: (steps summed over robots, coverage), sampled every second of
    /// simulated time when something changed, at each decision and at the end.
    pub coverage_curve: Vec<(f32, f32)>,
    /// Coverage over simulated time: (time \[s\], coverage), same samples.
    pub coverage_time_curve: Vec<(f64, f32)>,
    /// Decisions, replans, yields, faults and ends, in order.
    pub events: Vec<LoggedEvent>,
    /// The final map against the truth.
    pub map_accuracy: MapAccuracy,
}

impl RunReport {
    /// Steps summed over robots.
    pub fn steps(&self) -> f32 {
        self.robots.iter().map(|r| r.steps).sum()
    }

    /// Metres summed over robots (odometry).
    pub fn distance_m(&self) -> f64 {
        self.robots.iter().map(|r| r.distance_m).sum()
    }

    /// Rotation summed over robots (odometry) \[rad\].
    pub fn rotation_rad(&self) -> f64 {
        self.robots.iter().map(|r| r.rotation_rad).sum()
    }

    /// Decisions summed over robots.
    pub fn decisions(&self) -> u32 {
        self.robots.iter().map(|r| r.decisions).sum()
    }

    /// Fitness evaluations summed over robots.
    pub fn fitness_evals(&self) -> u64 {
        self.robots.iter().map(|r| r.fitness_evals).sum()
    }

    /// Contacts summed over robots.
    pub fn collisions(&self) -> u32 {
        self.robots.iter().map(|r| r.collisions).sum()
    }

    /// Every decision's compute time \[ms\], sorted ascending.
    pub fn decision_ms_sorted(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .robots
            .iter()
            .flat_map(|r| r.decision_ms.iter().copied())
            .collect();
        v.sort_by(f64::total_cmp);
        v
    }

    /// The `q`-quantile (0..=1, nearest rank) of the decision times \[ms\]; 0 without decisions.
    pub fn decision_ms_quantile(&self, q: f64) -> f64 {
        let v = self.decision_ms_sorted();
        if v.is_empty() {
            return 0.0;
        }
        let rank = (q.clamp(0.0, 1.0) * v.len() as f64).ceil().max(1.0) as usize;
        v[rank.min(v.len()) - 1]
    }

    /// Total decision compute time \[ms\].
    pub fn decision_ms_total(&self) -> f64 {
        self.robots.iter().flat_map(|r| r.decision_ms.iter()).sum()
    }

    /// Replans summed over robots.
    pub fn replans(&self) -> u32 {
        self.robots.iter().map(|r| r.replans).sum()
    }
}

/// Coverage of the shared map against the truth, kept up to date cheaply: after each scan only
/// the cells it may have changed are re-read (its laser's field of view and the cells near the
/// robot); a full recount every second catches the rest.
struct CoverageCounter {
    truth: Truth,
    /// Per cell, 1 when it is observable (the truth's mask, in 32-bit lanes like the
    /// log-odds, so that the count vectorises without widening or narrowing).
    observable: Vec<u32>,
    /// Per cell, 1 when it is observable and was known at its last reading.
    known: Vec<u32>,
    count: usize,
}

impl CoverageCounter {
    fn new(truth: Truth) -> Self {
        let n = truth.mask().len();
        Self {
            observable: truth.mask().iter().map(|&m| u32::from(m)).collect(),
            truth,
            known: vec![0; n],
            count: 0,
        }
    }

    /// Recounts every cell (the same sum as counting the observable cells that are known).
    fn recount<const N: usize>(&mut self, grid: &OccupancyGrid<N>) {
        let g = *grid.geometry();
        let all = CellRect {
            cols: 0..g.width,
            rows: 0..g.height,
        };
        self.update(grid, &[all]);
    }

    /// Re-reads the cells a scan integrated at `pose_map` may have changed: the cells the
    /// beams can reach (the bounding box of the laser's field of view out to its range), and
    /// those within [`NEAR_ROBOT_M`] of the robot (its own trail, cleared at each scan, and the
    /// obstacles marked in front of it).
    fn update_after_scan<const N: usize>(
        &mut self,
        grid: &OccupancyGrid<N>,
        pose_map: Pose2,
        laser: &LaserConfig,
        scan: &Scan,
    ) {
        let g = *grid.geometry();
        let near = CellRect::around(&g, pose_map.position(), NEAR_ROBOT_M, NEAR_ROBOT_M);
        let (lo, hi) = field_of_view_box(pose_map, laser, scan);
        let seen = CellRect::around(
            &g,
            Point2::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y)),
            0.5 * (hi.x - lo.x) + FIELD_MARGIN_M,
            0.5 * (hi.y - lo.y) + FIELD_MARGIN_M,
        );
        self.update(grid, &[near, seen]);
    }

    /// Re-reads the cells of the union of `rects`: row by row, the columns between the first
    /// and the last a rectangle covers in that row.
    fn update<const N: usize>(&mut self, grid: &OccupancyGrid<N>, rects: &[CellRect]) {
        let width = grid.geometry().width;
        let rows_from = rects.iter().map(|r| r.rows.start).min().unwrap_or(0);
        let rows_to = rects.iter().map(|r| r.rows.end).max().unwrap_or(0);
        let log_odds = grid.log_odds();
        // Branch-free over each row (the compiler vectorises it): a cell counts when it is
        // observable and known; `known` only ever holds observable cells.
        let (mut now_known, mut was_known) = (0usize, 0usize);
        for row in rows_from..rows_to {
            let in_row = || {
                rects
                    .iter()
                    .filter(|r| r.rows.contains(&row) && !r.cols.is_empty())
            };
            let (Some(c0), Some(c1)) = (
                in_row().map(|r| r.cols.start).min(),
                in_row().map(|r| r.cols.end).max(),
            ) else {
                continue;
            };
            let span = row * width + c0..row * width + c1;
            let (mut now_row, mut was_row) = (0u32, 0u32);
            for ((known, &observable), &l) in self.known[span.clone()]
                .iter_mut()
                .zip(&self.observable[span.clone()])
                .zip(&log_odds[span])
            {
                let k = observable & u32::from((l > 0.0) | (l < 0.0));
                now_row += k;
                was_row += *known;
                *known = k;
            }
            now_known += now_row as usize;
            was_known += was_row as usize;
        }
        self.count = self.count + now_known - was_known;
    }

    fn coverage(&self) -> f32 {
        if self.truth.is_empty() {
            0.0
        } else {
            self.count as f32 / self.truth.len() as f32
        }
    }
}

/// Cells within this distance \[m\] of a robot are re-read after each of its scans, whatever
/// its laser's field of view: its trail (the last metre, cleared of Occupied evidence at each
/// scan, out to its body's radius) and the obstacles marked just in front of it.
const NEAR_ROBOT_M: f32 = 2.5;

/// Margin \[m\] around a laser's field of view for the cells its beams' ends round into.
const FIELD_MARGIN_M: f32 = 0.3;

/// A rectangle of cells, clipped to the grid.
#[derive(Clone, Debug)]
struct CellRect {
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
}

impl CellRect {
    /// The cells within `half_x` and `half_y` \[m\] of `p` along each axis.
    fn around(g: &GridGeometry, p: Point2, half_x: f32, half_y: f32) -> Self {
        let r = g.resolution_m;
        let lo = |v: f32, o: f32, h: f32| (((v - h - o) / r).floor() as i64).max(0) as usize;
        let hi = |v: f32, o: f32, h: f32, n: usize| {
            (((v + h - o) / r).ceil() as i64).clamp(0, n as i64) as usize
        };
        let cols = lo(p.x, g.origin.x, half_x)..hi(p.x, g.origin.x, half_x, g.width);
        let rows = lo(p.y, g.origin.y, half_y)..hi(p.y, g.origin.y, half_y, g.height);
        Self { cols, rows }
    }
}

/// Corners (south-west, north-east) of the box holding every beam of `scan` taken at
/// `pose_map` by `laser`, out to its usable range: the laser's position, the ends of its first
/// and last beams, and the points due east, north, west and south of it when the field of view
/// faces them.
fn field_of_view_box(pose_map: Pose2, laser: &LaserConfig, scan: &Scan) -> (Point2, Point2) {
    let pose = pose_map.compose(laser.mount);
    let o = pose.position();
    let range = laser.max_range_m;
    let (mut lo, mut hi) = (o, o);
    let mut grow = |x: f32, y: f32| {
        lo = Point2::new(lo.x.min(x), lo.y.min(y));
        hi = Point2::new(hi.x.max(x), hi.y.max(y));
    };
    let angles = scan.beams().iter().map(|b| b.angle_rad);
    let first = angles.clone().fold(f32::INFINITY, f32::min);
    let last = angles.fold(f32::NEG_INFINITY, f32::max);
    if !(first <= last && range.is_finite()) {
        // No beam with a finite angle, or a range the scan cannot be integrated with.
        return (lo, hi);
    }
    let (a0, span) = (pose.theta + first, last - first);
    for a in [a0, a0 + span] {
        grow(o.x + range * a.cos(), o.y + range * a.sin());
    }
    for (k, (dx, dy)) in [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let axis = k as f32 * std::f32::consts::FRAC_PI_2;
        if (axis - a0).rem_euclid(std::f32::consts::TAU) <= span || span >= std::f32::consts::TAU {
            grow(o.x + range * dx, o.y + range * dy);
        }
    }
    (lo, hi)
}

/// One simulated robot's laser, mission and decision generator (its body lives in
/// [`Runner::bodies`], so that the physics can step all bodies together).
struct Robot {
    laser: LaserSim,
    mission: Mission<MAP_CAPACITY>,
    rng: ProjectRng,
    report: RobotReport,
    last_odom: Option<Pose2>,
    was_stalled: bool,
}

impl Robot {
    fn flags(b: &RobotBody) -> RobotFlags {
        RobotFlags {
            front_bumper: b.front_bumper(),
            rear_bumper: b.rear_bumper(),
            left_stall: b.stalled(),
            right_stall: b.stalled(),
            motors_enabled: b.motors_enabled(),
            estop: b.e_stop(),
        }
    }

    /// Feeds the body's odometry to the mission and accumulates distance and rotation.
    fn feed_odometry(&mut self, now: Time, body: &RobotBody) {
        let odom = body.odometry_pose();
        if let Some(prev) = self.last_odom {
            self.report.distance_m += prev.position().distance(odom.position()) as f64;
            self.report.rotation_rad +=
                papillon::geometry::normalize_angle(odom.theta - prev.theta).abs() as f64;
        }
        self.last_odom = Some(odom);
        self.mission.on_odometry(now, odom, Self::flags(body));
    }
}

/// Applies a mission command to a body. `SetLimits` and `KeepAlive` change nothing in the
/// simulation (the body has the P3-DX's limits; there is no watchdog).
fn apply(body: &mut RobotBody, command: RobotCommand) {
    match command {
        RobotCommand::Velocity(v) => {
            body.command(v.speed_mm_s() as f32, v.turn_rate_deg_s() as f32)
        }
        RobotCommand::Stop | RobotCommand::EmergencyStop => body.stop(),
        RobotCommand::EnableMotors(on) => body.set_motors_enabled(on),
        _ => {}
    }
}

/// What [`Runner::run_with`] reports to its observer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// Robot `robot` made a decision (its targets are in the report).
    Decided {
        /// Robot index.
        robot: usize,
    },
    /// The run ended.
    Finished,
}

/// A run in progress: the world, the robots and the shared map.
pub struct Runner {
    world: World,
    dynamics: Dynamics,
    bodies: Vec<RobotBody>,
    robots: Vec<Robot>,
    map: Box<SharedMap<MAP_CAPACITY>>,
    ws: Box<Workspace<MAP_CAPACITY>>,
    coverage: CoverageCounter,
    config: RunConfig,
    now_us: u64,
    next_control_us: u64,
    next_scan_us: u64,
    scan_period_us: u64,
    periods: u64,
    report: RunReport,
    scan: Scan,
    last_sample: Option<(f32, f32)>,
}

impl fmt::Debug for Runner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Runner")
            .field("world", &self.world.name())
            .field("robots", &self.robots.len())
            .field("now_s", &(self.now_us as f64 * 1e-6))
            .finish_non_exhaustive()
    }
}

impl Runner {
    /// Sets up a run in `world` (the truth is taken from its current state and start pose),
    /// with `dynamics` (doors and people; empty for none).
    pub fn new(world: World, dynamics: Dynamics, config: RunConfig) -> Result<Self, RunError> {
        if config.robots == 0 || config.robots > MAX_ROBOTS {
            return Err(RunError::Robots(config.robots));
        }
        let g = *world.geometry();
        if g.cell_count() > MAP_CAPACITY {
            return Err(RunError::MapTooLarge {
                cells: g.cell_count(),
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
            None => start_poses(&world, world.start(), config.robots, radius)?,
        };
        let mut robots = Vec::with_capacity(config.robots);
        let mut bodies = Vec::with_capacity(config.robots);
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
                derive_seed(config.seed, k, STREAM_BODY),
            ));
            robots.push(Robot {
                laser: LaserSim::new(
                    config.mission.laser,
                    derive_seed(config.seed, k, STREAM_LASER),
                ),
                mission,
                rng: random::seeded(derive_seed(config.seed, k, STREAM_DECIDE)),
                report: RobotReport {
                    trajectory: vec![pose.position()],
                    final_pose: pose,
                    ..RobotReport::default()
                },
                last_odom: None,
                was_stalled: false,
            });
        }
        let map = SharedMap::<MAP_CAPACITY>::new_boxed(g, &config.mission)?;
        let ws = Workspace::<MAP_CAPACITY>::new_boxed();
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
            scan: Scan::new(),
            last_sample: None,
        })
    }

    /// The world as it is now (doors in their current state).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The shared map.
    pub fn map(&self) -> &SharedMap<MAP_CAPACITY> {
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
    pub fn mission(&self, k: usize) -> &Mission<MAP_CAPACITY> {
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

    /// Whether the run has ended.
    pub fn finished(&self) -> bool {
        self.report.reason.is_some()
    }

    /// Runs to the end and returns the report.
    pub fn run(&mut self) -> Result<RunReport, RunError> {
        self.run_with(|_, _| {})
    }

    /// Runs to the end, calling `observer` after each decision and at the end.
    pub fn run_with(
        &mut self,
        mut observer: impl FnMut(&Runner, Progress),
    ) -> Result<RunReport, RunError> {
        let wall = Instant::now();
        let mut observing_s = 0.0;
        while !self.finished() {
            let decided = self.advance()?;
            if !decided.is_empty() {
                let t = Instant::now();
                for robot in decided {
                    observer(self, Progress::Decided { robot });
                }
                observing_s += t.elapsed().as_secs_f64();
            }
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
        r.map_accuracy = map_accuracy::measure(&self.map.grid, &self.world, &self.coverage.truth);
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
        for (r, body) in self.robots.iter_mut().zip(&self.bodies) {
            let pose = body.true_pose();
            // A laser with more beams than a scan holds keeps the first ones.
            let _ = r.laser.scan_into(&self.world, pose, &discs, &mut self.scan);
            r.feed_odometry(now, body);
            r.mission.on_scan(now, &self.scan, &mut self.map)?;
            self.coverage.update_after_scan(
                &self.map.grid,
                r.mission.pose_map(),
                &self.config.mission.laser,
                &self.scan,
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
        for k in 0..self.robots.len() {
            let r = &mut self.robots[k];
            let body = &mut self.bodies[k];
            r.feed_odometry(now, body);
            r.mission.set_coverage(coverage);
            let t0 = Instant::now();
            let out = r.mission.step(now, &mut self.map, &mut self.ws, &mut r.rng);
            let elapsed_ms = t0.elapsed().as_secs_f64() * 1e3;
            apply(body, out.command);
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
            self.coverage.recount(&self.map.grid);
            self.last_sample = None;
            self.sample();
            self.report.reason = Some(reason);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::builtin;

    #[test]
    fn the_field_of_view_box_holds_every_beam() {
        let mut rng = random::seeded(12);
        for (layout, laser) in [LaserConfig::thesis(), LaserConfig::lms1xx()]
            .into_iter()
            .enumerate()
        {
            let mut scan = Scan::new();
            for i in 0..laser.beam_count as usize {
                scan.push(papillon::sensor::Beam {
                    angle_rad: laser.beam_angle(i),
                    range_m: None,
                })
                .unwrap();
            }
            for case in 0..500 {
                let pose = Pose2::new(
                    random::range_f32(&mut rng, -5.0, 5.0),
                    random::range_f32(&mut rng, -5.0, 5.0),
                    random::range_f32(&mut rng, -4.0, 4.0),
                );
                let (lo, hi) = field_of_view_box(pose, &laser, &scan);
                let eye = pose.compose(laser.mount);
                let mut touched = [false; 4];
                for b in scan.beams() {
                    let a = eye.theta + b.angle_rad;
                    let end = Point2::new(
                        eye.x + laser.max_range_m * a.cos(),
                        eye.y + laser.max_range_m * a.sin(),
                    );
                    let slack = 1e-4;
                    assert!(
                        end.x >= lo.x - slack
                            && end.x <= hi.x + slack
                            && end.y >= lo.y - slack
                            && end.y <= hi.y + slack,
                        "layout {layout} case {case}: {end:?} outside {lo:?}..{hi:?}"
                    );
                    // How close the beams come to each side of the box.
                    let near = 0.01 * laser.max_range_m;
                    touched[0] |= end.x - lo.x < near;
                    touched[1] |= hi.x - end.x < near;
                    touched[2] |= end.y - lo.y < near;
                    touched[3] |= hi.y - end.y < near;
                }
                // The box is tight: each side is reached by a beam or is the laser itself.
                for (side, &t) in touched.iter().enumerate() {
                    let at_eye = [lo.x == eye.x, hi.x == eye.x, lo.y == eye.y, hi.y == eye.y];
                    assert!(
                        t || at_eye[side],
                        "layout {layout} case {case}: side {side}"
                    );
                }
            }
        }
    }

    #[test]
    fn seeds_differ_per_robot_and_stream() {
        let a = derive_seed(25, 0, STREAM_BODY);
        assert_ne!(a, derive_seed(25, 1, STREAM_BODY));
        assert_ne!(a, derive_seed(25, 0, STREAM_LASER));
        assert_ne!(a, derive_seed(26, 0, STREAM_BODY));
        assert_eq!(a, derive_seed(25, 0, STREAM_BODY));
    }

    #[test]
    fn extra_robots_start_clear_of_walls_and_each_other() {
        let w = builtin::house(0.1).unwrap();
        let poses = start_poses(&w, w.start(), 4, 0.25).unwrap();
        assert_eq!(poses.len(), 4);
        assert_eq!(poses[0], w.start());
        for (i, p) in poses.iter().enumerate() {
            assert!(!w.disc_hits_blocked(p.position(), 0.35), "{p:?}");
            for q in &poses[..i] {
                assert!(p.position().distance(q.position()) >= 0.8 - 1e-4);
            }
        }
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
