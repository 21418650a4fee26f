//! What a decision and a simulated second cost as the *map* grows while the *explored* region
//! stays the same (issue 24): the mid-mission House snapshot (`fixtures/house-mid-mission.yaml`,
//! 240 x 240 cells at 0.1 m, the robot at (1.5 m, 1.5 m)) is laid into the south-west corner of
//! an all-Unknown map of 240², 480², 960² or 1920² cells; the rest of the map is space the
//! robot has never seen. Each size runs with a grid capacity equal to its cell count (const
//! generics, boxed), not through the runner, whose capacity is fixed.
//!
//! - **decide**: one xBOA decision (population 5, 30 generations, the mission's default
//!   objective and visibility cache) from the snapshot, as `examples/decision_timing.rs` does
//!   on the 240² map: one warm-up decision, then `SCALE_RUNS` timed ones (min and median).
//! - **simulate**: the mission state machine from the snapshot (its map preloaded, the robot at
//!   the snapshot's pose in the `house` world, the runner's ideal pump: a scan at the laser's
//!   rate, a control period every 100 ms, no coverage counter) for `SCALE_SIM_S` simulated
//!   seconds (default 30); reports the wall time per simulated second and the decisions,
//!   replans and known cells at the end, so that runs at different sizes can be compared.
//!
//! The functions `scale_decide_once` and `scale_simulate` hold exactly the measured work, for
//! instruction counts:
//!
//! ```text
//! cargo build --release -p papillon-sim --example scale_cost
//! SCALE_RUNS=1 valgrind --tool=callgrind --toggle-collect='*scale_decide_once*' \
//!     target/release/examples/scale_cost decide 960
//! SCALE_SIM_S=10 valgrind --tool=callgrind --toggle-collect='*scale_simulate*' \
//!     target/release/examples/scale_cost simulate 960
//! ```
//!
//! Run: `cargo run --release -p papillon-sim --example scale_cost -- [decide|simulate|both]
//! [SIZE...]` (sizes in cells a side: 240, 480, 960, 1920; default 240 480 960).

use std::path::Path;
use std::time::{Duration, Instant};

use papillon::control::Time;
use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, Optimized, TargetSelector, ViewCache,
};
use papillon::geometry::Pose2;
use papillon::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::mapfile::{MapImage, read_map};
use papillon::mission::{Mission, MissionConfig, MissionEvent, SharedMap, Workspace};
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::{LaserConfig, Scan};
use papillon_sim::laser::LaserSim;
use papillon_sim::physics::{RobotBody, advance_all};
use papillon_sim::runner::{CONTROL_PERIOD_US, RunConfig, apply, flags};
use papillon_sim::world::World;

/// The snapshot's robot pose (map frame).
fn pose() -> Pose2 {
    Pose2::new(1.5, 1.5, 0.0)
}
/// Energy left at the decision \[steps\] (as the House fixture's decision).
const BATTERY_STEPS: f32 = 60.0;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&n| n > 0)
        .unwrap_or(default)
}

/// The explored state every size starts from: a 240² map's log-odds and the robot's pose.
struct Explored {
    geometry: GridGeometry,
    log_odds: Vec<f32>,
    pose: Pose2,
}

impl Explored {
    /// The House snapshot, then `SCALE_EXPLORE_S` simulated seconds (default 120) of the
    /// mission on the 240² map: a house-size explored region with its frontiers.
    fn build() -> Result<Self, Box<dyn std::error::Error>> {
        let snap = snapshot();
        let mut grid =
            OccupancyGrid::<{ 240 * 240 }>::new_boxed(snap.geometry, LogOddsBounds::default())?;
        load_into(&snap, &mut grid, &mut ());
        let base = Self {
            geometry: snap.geometry,
            log_odds: grid.log_odds().to_vec(),
            pose: pose(),
        };
        let seconds = std::env::var("SCALE_EXPLORE_S")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(120u64);
        let mut sim = Sim::<{ 240 * 240 }>::new(&base, 240)?;
        sim.run_until(seconds * 1_000_000, &mut SimOutcome::default())?;
        Ok(Self {
            geometry: snap.geometry,
            log_odds: sim.map.grid.log_odds().to_vec(),
            pose: sim.bodies[0].true_pose(),
        })
    }

    /// Lays the state's cells into the south-west corner of `grid`.
    fn load_into<const N: usize>(
        &self,
        grid: &mut OccupancyGrid<N>,
        observer: &mut impl papillon::grid::CellObserver,
    ) {
        let (w, side) = (self.geometry.width, grid.geometry().width);
        for (i, &l) in self.log_odds.iter().enumerate() {
            if l != 0.0 {
                grid.set_log_odds((i / w) * side + i % w, l, observer);
            }
        }
    }

    /// The state's cells in the south-west corner of an all-Unknown `side`² grid.
    fn grid<const N: usize>(
        &self,
        side: usize,
    ) -> Result<Box<OccupancyGrid<N>>, Box<dyn std::error::Error>> {
        let g = GridGeometry::new(side, side, self.geometry.resolution_m, self.geometry.origin)?;
        let mut grid = OccupancyGrid::<N>::new_boxed(g, LogOddsBounds::default())?;
        self.load_into(&mut grid, &mut ());
        Ok(grid)
    }
}

fn snapshot() -> MapImage {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/house-mid-mission.yaml");
    read_map(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn load_into<const N: usize>(
    map: &MapImage,
    grid: &mut OccupancyGrid<N>,
    observer: &mut impl papillon::grid::CellObserver,
) {
    let (w, side) = (map.geometry.width, grid.geometry().width);
    for (i, &c) in map.cells.iter().enumerate() {
        if c.is_known() {
            grid.set_class((i / w) * side + i % w, c, observer);
        }
    }
}

#[inline(never)]
fn scale_decide_once<const N: usize>(
    sel: &mut Optimized<'_, '_, N>,
    req: &DecisionRequest<'_, N>,
) -> Result<papillon::explore::Outcome, papillon::explore::DecideError> {
    sel.decide(req, &mut seeded(1))
}

fn decide<const N: usize>(state: &Explored, side: usize) -> Result<(), Box<dyn std::error::Error>> {
    let grid = state.grid::<N>(side)?;
    let mut trav =
        Traversability::<N>::new_boxed(*grid.geometry(), TraversabilityConfig::default())?;
    trav.rebuild_from(&grid)?;
    let laser = LaserConfig::thesis();
    let req = DecisionRequest {
        grid: &grid,
        trav: &trav,
        pose: state.pose,
        battery_steps: BATTERY_STEPS,
        laser: &laser,
    };
    let mut field = DistanceField::<N>::new_boxed();
    let mut astar = AStar::<N>::new_boxed();
    let mut stamps = vec![0u32; N];
    let mut views = ViewCache::new_boxed();
    let mut obj =
        ExploreObjective::with_view_cache(&mut field, &mut *astar, &mut stamps, &mut views);
    let config = ExploreConfig {
        population: 5,
        max_generations: 30,
        ..ExploreConfig::default()
    };
    let known = grid.counts().known();
    let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
    let first = scale_decide_once(&mut sel, &req)?;
    let runs = env_usize("SCALE_RUNS", 20);
    let mut times = Vec::with_capacity(runs);
    for _ in 0..runs {
        let t = Instant::now();
        let d = scale_decide_once(&mut sel, &req)?;
        times.push(t.elapsed());
        assert_eq!(
            format!("{d:?}"),
            format!("{first:?}"),
            "a decision is deterministic"
        );
    }
    times.sort();
    let (min, median) = (times[0], times[times.len() / 2]);
    println!(
        "decide {side}x{side}: known {known} cells ({:.1} %), min {min:.2?} median {median:.2?}; {first:?}",
        100.0 * known as f64 / (side * side) as f64,
    );
    Ok(())
}

/// What a run of the mission from the snapshot did.
#[derive(Debug, Default)]
struct SimOutcome {
    decisions: u32,
    replans: u32,
    scans: u32,
}

struct Sim<const N: usize> {
    world: World,
    bodies: Vec<RobotBody>,
    laser: LaserSim,
    mission: Mission<N>,
    map: Box<SharedMap<N>>,
    ws: Box<Workspace<N>>,
    rng: papillon::random::ProjectRng,
    scan: Scan,
    now_us: u64,
    next_scan_us: u64,
    next_control_us: u64,
    scan_period_us: u64,
}

impl<const N: usize> Sim<N> {
    fn new(state: &Explored, side: usize) -> Result<Self, Box<dyn std::error::Error>> {
        let res = state.geometry.resolution_m;
        let world = World::load("house", res)?;
        let run = RunConfig::new(MissionConfig::default(), 1, 25);
        let g = GridGeometry::new(side, side, res, state.geometry.origin)?;
        let mut map = SharedMap::<N>::new_boxed(g, &run.mission)?;
        {
            let SharedMap { grid, trav, .. } = &mut *map;
            state.load_into(grid, trav);
        }
        map.rebuild_traversability()?;
        let rate = run.mission.laser.rate_hz as f64;
        Ok(Self {
            bodies: vec![RobotBody::new(run.body, state.pose, 1)],
            laser: LaserSim::new(run.mission.laser, 2),
            mission: Mission::new(0, run.mission.clone(), state.pose)?,
            map,
            ws: Workspace::<N>::new_boxed(),
            rng: seeded(3),
            scan: Scan::new(),
            world,
            now_us: 0,
            next_scan_us: 0,
            next_control_us: 0,
            scan_period_us: ((1e6 / rate).round() as u64).max(1_000),
        })
    }

    /// Runs the mission until simulated time `until_us`, as the runner's ideal pump does.
    fn run_until(
        &mut self,
        until_us: u64,
        out: &mut SimOutcome,
    ) -> Result<(), Box<dyn std::error::Error>> {
        while self.now_us < until_us {
            let next = self.next_control_us.min(self.next_scan_us);
            if next > self.now_us {
                advance_all(
                    &mut self.bodies,
                    (next - self.now_us) as f32 * 1e-6,
                    &self.world,
                    &[],
                );
                self.now_us = next;
            }
            let now = Time::from_micros(self.now_us);
            let body = &mut self.bodies[0];
            if self.next_scan_us == self.now_us {
                let _ = self
                    .laser
                    .scan_into(&self.world, body.true_pose(), &[], &mut self.scan);
                self.mission
                    .on_odometry(now, body.odometry_pose(), flags(body));
                self.mission.on_scan(now, &self.scan, &mut self.map)?;
                out.scans += 1;
                self.next_scan_us += self.scan_period_us;
            }
            if self.next_control_us == self.now_us {
                self.mission
                    .on_odometry(now, body.odometry_pose(), flags(body));
                let step = self
                    .mission
                    .step(now, &mut self.map, &mut self.ws, &mut self.rng);
                apply(body, step.command);
                out.decisions += step
                    .events
                    .iter()
                    .filter(|e| matches!(e, MissionEvent::Decided { .. }))
                    .count() as u32;
                self.next_control_us += CONTROL_PERIOD_US;
            }
        }
        out.replans = self.mission.stats().replans;
        Ok(())
    }
}

#[inline(never)]
fn scale_simulate<const N: usize>(
    sim: &mut Sim<N>,
    until_us: u64,
    out: &mut SimOutcome,
) -> Result<(), Box<dyn std::error::Error>> {
    sim.run_until(until_us, out)
}

fn simulate<const N: usize>(
    state: &Explored,
    side: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let seconds = env_usize("SCALE_SIM_S", 30);
    let mut sim = Sim::<N>::new(state, side)?;
    let mut out = SimOutcome::default();
    let t = Instant::now();
    scale_simulate(&mut sim, seconds as u64 * 1_000_000, &mut out)?;
    let wall: Duration = t.elapsed();
    let known = sim.map.grid.counts().known();
    println!(
        "simulate {side}x{side}: {seconds} s simulated in {wall:.2?} ({:.2} ms per simulated second, {:.0}x); \
         {} decisions, {} replans, {} scans; known at the end {known} cells; pose {:?}",
        wall.as_secs_f64() * 1e3 / seconds as f64,
        seconds as f64 / wall.as_secs_f64(),
        out.decisions,
        out.replans,
        out.scans,
        sim.mission.pose_map()
    );
    Ok(())
}

fn run<const N: usize>(
    state: &Explored,
    mode: &str,
    side: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    if mode == "decide" || mode == "both" {
        decide::<N>(state, side)?;
    }
    if mode == "simulate" || mode == "both" {
        simulate::<N>(state, side)?;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map(String::as_str).unwrap_or("both");
    if !["decide", "simulate", "both"].contains(&mode) {
        return Err(format!("unknown mode {mode:?}: decide, simulate or both").into());
    }
    let sizes: Vec<usize> = if args.len() > 1 {
        args[1..]
            .iter()
            .map(|s| s.parse().map_err(|_| format!("bad size {s:?}")))
            .collect::<Result<_, _>>()?
    } else {
        vec![240, 480, 960]
    };
    let state = Explored::build()?;
    println!(
        "explored state: {} known cells, robot at {:?}",
        state.log_odds.iter().filter(|&&l| l != 0.0).count(),
        state.pose
    );
    for side in sizes {
        match side {
            240 => run::<{ 240 * 240 }>(&state, mode, side)?,
            480 => run::<{ 480 * 480 }>(&state, mode, side)?,
            960 => run::<{ 960 * 960 }>(&state, mode, side)?,
            1920 => run::<{ 1920 * 1920 }>(&state, mode, side)?,
            _ => return Err(format!("size {side}: one of 240, 480, 960, 1920").into()),
        }
    }
    Ok(())
}
