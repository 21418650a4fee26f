//! The scenario builder: a typed description of one simulated mission ([`ScenarioSpec`]: world,
//! robots, selector, optimizer budget, strategy, seed, battery, start, slip) checked and turned
//! into a world and a run configuration ([`Setup`]) for the fast runner ([`crate::runner`]).
//!
//! `papillon-sim mission` builds its spec from its options, and every run of a bench sweep
//! ([`crate::bench::sim`]) from its run spec, so both run the very same set-up. Errors are one
//! line, named by the `papillon-sim mission` option that sets the field (`--pop: ...`).

use papillon::explore::ObjectiveKind;
use std::fmt;

use papillon::geometry::Pose2;
use papillon::mission::{MissionConfig, SelectorKind, footprint};
use papillon::optim::{MAX_POP, MIN_POP, Method, Preset};

use crate::physics::SlipConfig;
use crate::runner::{self, RunConfig};
use crate::world::World;

/// Targets per decision of the long-term strategy when none are given.
pub const DEFAULT_LONG_TARGETS: usize = 3;

/// How many targets a decision picks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// One target per decision.
    Short,
    /// Several targets per decision (k, at most [`papillon::explore::MAX_TARGETS`]).
    Long,
}

impl Strategy {
    /// `short` or `long`.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Short => "short",
            Strategy::Long => "long",
        }
    }

    /// The strategy named `name`.
    pub fn from_name(name: &str) -> Result<Self, String> {
        match name {
            "short" => Ok(Strategy::Short),
            "long" => Ok(Strategy::Long),
            other => Err(format!("--strategy: expected short or long, got '{other}'")),
        }
    }
}

impl fmt::Display for Strategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The simulated robots' odometry slip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slip {
    /// A 1.5 cm slide at the end of each move, what the thesis saw ([`SlipConfig::thesis`]).
    Thesis,
    /// Also heading and distance random walks ([`SlipConfig::default`]).
    Full,
    /// Per-robot wheel-diameter and wheelbase errors, random errors, fast-turn slip and the
    /// end-of-move slide ([`SlipConfig::realistic`], [`crate::odometry_error`]).
    Realistic,
    /// Perfect odometry.
    None,
}

impl Slip {
    /// `thesis`, `full`, `realistic` or `none`.
    pub fn name(self) -> &'static str {
        match self {
            Slip::Thesis => "thesis",
            Slip::Full => "full",
            Slip::Realistic => "realistic",
            Slip::None => "none",
        }
    }

    /// The slip named `name`.
    pub fn from_name(name: &str) -> Result<Self, String> {
        match name {
            "thesis" => Ok(Slip::Thesis),
            "full" => Ok(Slip::Full),
            "realistic" => Ok(Slip::Realistic),
            "none" => Ok(Slip::None),
            other => Err(format!(
                "--slip: expected thesis, full, realistic or none, got '{other}'"
            )),
        }
    }

    /// The body's slip configuration.
    pub fn config(self) -> SlipConfig {
        match self {
            Slip::Thesis => SlipConfig::thesis(),
            Slip::Full => SlipConfig::default(),
            Slip::Realistic => SlipConfig::realistic(),
            Slip::None => SlipConfig::none(),
        }
    }
}

impl fmt::Display for Slip {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The selector named `name`: an optimizer (`xboa`, `boa`, ... see [`Method`]),
/// `nearest-frontier` or `frontier-utility`.
pub fn selector_from_name(name: &str) -> Result<SelectorKind, String> {
    match name {
        "nearest-frontier" => Ok(SelectorKind::NearestFrontier),
        "frontier-utility" => Ok(SelectorKind::FrontierUtility),
        m => m.parse::<Method>().map(SelectorKind::Optimized).map_err(|_| {
            format!(
                "--method: unknown method '{m}', expected one of: xboa boa mboa aboa saboa ga pso gwo abc cmaes nearest-frontier frontier-utility"
            )
        }),
    }
}

/// The name [`selector_from_name`] reads back as `selector`.
pub fn selector_name(selector: SelectorKind) -> &'static str {
    match selector {
        SelectorKind::NearestFrontier => "nearest-frontier",
        SelectorKind::FrontierUtility => "frontier-utility",
        SelectorKind::Optimized(m) => m.name(),
    }
}

/// One simulated mission, as typed values; [`Default`] is the thesis's set-up.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioSpec {
    /// World: a built-in name (house, empty, factory, lab) or a map file.
    pub map: String,
    /// Cell size \[m\] (a `.yaml` map's own resolution wins).
    pub resolution_m: f32,
    /// Robots sharing the map (1..=[`runner::MAX_ROBOTS`]).
    pub robots: usize,
    /// Target selector.
    pub selector: SelectorKind,
    /// What the optimizers maximise (`--objective`; the frontier rules ignore it).
    pub objective: ObjectiveKind,
    /// Population of the optimizer (2..=64).
    pub population: usize,
    /// Generations of the optimizer (at least 1).
    pub generations: u32,
    /// Strategy.
    pub strategy: Strategy,
    /// Targets per decision; `None`: 1 for the short-term strategy, [`DEFAULT_LONG_TARGETS`]
    /// for the long-term one.
    pub targets: Option<usize>,
    /// Seed of every random choice.
    pub seed: u64,
    /// Energy at the start \[steps\]; `None`: the core mission's default.
    pub battery_steps: Option<f32>,
    /// Start pose of robot 0 in the map frame; `None`: the world's own.
    pub start: Option<Pose2>,
    /// Odometry slip.
    pub slip: Slip,
    /// Scan-to-map matching before each scan is integrated ([`papillon::localize`]).
    pub localize: bool,
    /// Keyframes in a pose graph with loop closures behind the matcher
    /// ([`papillon::localize::graph`]); only with `localize`.
    pub pose_graph: bool,
    /// The matcher's online estimate of the odometry's systematic errors
    /// ([`papillon::localize::odometry_calibration`]); only with `localize`.
    pub self_calibration: bool,
    /// Range noise of the simulated laser, a fraction of the range (standard deviation);
    /// `None`: the mission's laser's (the thesis's 5 %). A SICK LMS1xx is nearer 0.3 %
    /// (about 12 mm at 4 m).
    pub laser_noise: Option<f32>,
    /// Range noise of the simulated laser that does not grow with the range, standard
    /// deviation \[m\] (the simulator's only, [`crate::laser::LaserSim::with_range_sigma_m`]);
    /// `None`: none.
    pub laser_noise_m: Option<f32>,
    /// The optimizer's parameter set (`--preset`; default
    /// [`papillon::explore::DEFAULT_PRESET`]; the frontier rules ignore it).
    pub preset: Preset,
    /// Hyper-parameters replacing the preset's for the selector's optimizer
    /// (`None`: the preset's; see [`papillon::optim::Method::build_tuned`]).
    pub tuning: Option<papillon::optim::Tuning>,
    /// Room the planner keeps between the body's side and a wall, each side \[m\]
    /// ([`footprint::planning_layer`]; `--clearance`, a board's `$.planning.clearance_m`).
    pub clearance_m: f32,
    /// Probability above which a map cell is an obstacle (`--occupied-thresh`; 0.5 is the
    /// thesis's rule; [`papillon::grid::LogOddsBounds::with_occupied_thresh`]).
    pub occupied_thresh: f32,
}

impl Default for ScenarioSpec {
    fn default() -> Self {
        Self {
            map: "house".into(),
            resolution_m: 0.1,
            robots: 1,
            selector: SelectorKind::Optimized(Method::Xboa),
            objective: ObjectiveKind::default(),
            population: 5,
            generations: 30,
            strategy: Strategy::Short,
            targets: None,
            seed: 25,
            battery_steps: None,
            start: None,
            slip: Slip::Thesis,
            localize: false,
            pose_graph: false,
            self_calibration: true,
            laser_noise: None,
            laser_noise_m: None,
            preset: papillon::explore::DEFAULT_PRESET,
            tuning: None,
            clearance_m: footprint::DEFAULT_CLEARANCE_M,
            occupied_thresh: papillon::grid::DEFAULT_OCCUPIED_THRESH,
        }
    }
}

/// A checked mission set-up: the world (start set) and the run.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The world.
    pub world: World,
    /// The run.
    pub run: RunConfig,
    /// The strategy.
    pub strategy: Strategy,
    /// The slip.
    pub slip: Slip,
    /// Room kept between the body's side and a wall on a planned path \[m\] (`--clearance`).
    pub clearance_m: f32,
    /// Probability above which a map cell is an obstacle (`--occupied-thresh`).
    pub occupied_thresh: f32,
}

/// Most generations per decision (as a board's `$.mission.generations`).
pub const MAX_GENERATIONS: u32 = u16::MAX as u32;
/// Largest battery \[steps\]: 1000 km of travel.
pub const MAX_BATTERY_STEPS: f32 = 1.0e6;

impl Setup {
    /// Checks `spec` and loads its world; the error is one line naming the option or the file.
    pub fn new(spec: &ScenarioSpec) -> Result<Self, String> {
        let robots = spec.robots;
        if !(1..=runner::MAX_ROBOTS).contains(&robots) {
            return Err(format!(
                "--robots: expected 1 to {}, got {robots}",
                runner::MAX_ROBOTS
            ));
        }
        let pop = spec.population;
        if !(MIN_POP..=MAX_POP).contains(&pop) {
            return Err(format!("--pop: expected {MIN_POP} to {MAX_POP}, got {pop}"));
        }
        if !(1..=MAX_GENERATIONS).contains(&spec.generations) {
            return Err(format!(
                "--gens: expected 1 to {MAX_GENERATIONS}, got {}",
                spec.generations
            ));
        }
        let max_k = papillon::explore::MAX_TARGETS;
        let targets = match spec.strategy {
            Strategy::Short => match spec.targets {
                None | Some(1) => 1,
                Some(k) => {
                    return Err(format!(
                        "--targets: the short-term strategy has one target per decision, got {k} (use --strategy long)"
                    ));
                }
            },
            Strategy::Long => {
                let k = spec.targets.unwrap_or(DEFAULT_LONG_TARGETS);
                if !(1..=max_k).contains(&k) {
                    return Err(format!("--targets: expected 1 to {max_k}, got {k}"));
                }
                k
            }
        };
        let mut mission = MissionConfig {
            selector: spec.selector,
            ..MissionConfig::default()
        };
        mission.explore.objective = spec.objective;
        mission.explore.preset = spec.preset;
        mission.explore.population = pop;
        mission.explore.max_generations = spec.generations;
        mission.explore.targets = targets;
        if let Some(t) = spec.tuning {
            if spec.selector != SelectorKind::Optimized(t.method()) {
                return Err(format!(
                    "hyper-parameters of {} given to the selector {}",
                    t.method(),
                    selector_name(spec.selector)
                ));
            }
            mission.explore.tuning = Some(t);
        }
        if let Some(b) = spec.battery_steps {
            if !(b.is_finite() && b > 0.0 && b <= MAX_BATTERY_STEPS) {
                return Err(format!(
                    "--battery: expected a positive number of steps up to {MAX_BATTERY_STEPS}, got {b}"
                ));
            }
            mission.battery_steps = b;
        }
        if !footprint::is_valid_clearance(spec.clearance_m) {
            return Err(format!(
                "--clearance: expected 0 to {} m, got {}",
                footprint::MAX_CLEARANCE_M,
                spec.clearance_m
            ));
        }
        mission.grid_bounds = mission
            .grid_bounds
            .with_occupied_thresh(spec.occupied_thresh)
            .ok_or_else(|| {
                format!(
                    "--occupied-thresh: expected {}, got {}",
                    mission.grid_bounds.occupied_thresh_range(),
                    spec.occupied_thresh
                )
            })?;
        let mut world = World::load(&spec.map, spec.resolution_m).map_err(|e| e.to_string())?;
        // The planning layer follows the body at the world's own cell size.
        mission.traversability = footprint::planning_layer(
            &mission.safety,
            spec.clearance_m,
            world.geometry().resolution_m,
            mission.traversability.unknown_policy,
        );
        if let Some(pose) = spec.start {
            if !(pose.x.is_finite() && pose.y.is_finite() && pose.theta.is_finite()) {
                return Err("--start: expected finite numbers".into());
            }
            if pose.theta.abs() > std::f32::consts::TAU {
                return Err(format!(
                    "--start: THETA {} is more than a turn; expected -2π to 2π rad",
                    pose.theta
                ));
            }
            world.set_start(pose);
            if let Some(why) = world.start_outside() {
                return Err(format!("--start: {why}"));
            }
        }
        let mut run = RunConfig::new(mission, robots, spec.seed);
        run.body.slip = spec.slip.config();
        run.mission.localize.enabled = spec.localize;
        if spec.pose_graph && !spec.localize {
            return Err(
                "--pose-graph: on needs the scan matcher, --localize on (the graph's keyframes are its matched scans)"
                    .into(),
            );
        }
        run.mission.localize.graph.enabled = spec.pose_graph;
        run.mission.localize.calibration.enabled = spec.self_calibration;
        if let Some(noise) = spec.laser_noise {
            run.mission.laser.noise_fraction = noise;
        }
        run.laser_range_sigma_m = spec.laser_noise_m.unwrap_or(0.0);
        if !world.start_is_clear(run.body.radius_m) {
            let s = world.start();
            return Err(format!(
                "--start: ({:.2} m, {:.2} m) on {} is inside an obstacle or too close to one for a robot of radius {} m",
                s.x,
                s.y,
                world.name(),
                run.body.radius_m
            ));
        }
        Ok(Self {
            world,
            run,
            strategy: spec.strategy,
            slip: spec.slip,
            clearance_m: spec.clearance_m,
            occupied_thresh: spec.occupied_thresh,
        })
    }

    /// The selector's name (`xboa`, `nearest-frontier`, ...).
    pub fn method(&self) -> &'static str {
        selector_name(self.run.mission.selector)
    }
}

/// The preset named `name` (`--preset`, a sweep's `preset`); the error is one line.
pub fn preset_from_name(name: &str) -> Result<Preset, String> {
    name.parse::<Preset>()
        .map_err(|_| format!("--preset: expected thesis or standard, got '{name}'"))
}

/// The objective named `name` (`--objective`, a sweep's `objective`); the error is one line.
pub fn objective_from_name(name: &str) -> Result<ObjectiveKind, String> {
    ObjectiveKind::from_name(name)
        .ok_or_else(|| format!("--objective: expected efficient or thesis, got '{name}'"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back() {
        for name in [
            "xboa",
            "boa",
            "cmaes",
            "nearest-frontier",
            "frontier-utility",
        ] {
            assert_eq!(selector_name(selector_from_name(name).unwrap()), name);
        }
        for s in [Strategy::Short, Strategy::Long] {
            assert_eq!(Strategy::from_name(s.name()), Ok(s));
        }
        for s in [Slip::Thesis, Slip::Full, Slip::None] {
            assert_eq!(Slip::from_name(s.name()), Ok(s));
        }
    }

    #[test]
    fn the_default_spec_is_the_thesis_setup_on_the_house() {
        let s = Setup::new(&ScenarioSpec::default()).unwrap();
        assert_eq!(s.world.name(), "house");
        assert_eq!(s.method(), "xboa");
        assert_eq!(s.run.mission.explore.targets, 1);
        assert_eq!(s.run.body.slip, SlipConfig::thesis());
    }
}
