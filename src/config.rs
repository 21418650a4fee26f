//! Board configuration: one JSON file per robot set-up (`boards/*.json`).
//!
//! A board file describes the robot (geometry and motion limits), the link to its
//! microcontroller, the laser (model, address, beam layout, mount), the map grid, the mission
//! settings, the PID gains, the safety distances and how often the mission state is saved.
//! Every quantity carries its unit in its name (`radius_m`, `max_speed_mm_s`, `first_angle_deg`).
//!
//! Parsing uses `serde-json-core` into fixed-capacity types, so it works without an allocator.
//! [`BoardConfig::from_json`] checks the syntax and the shape (unknown or missing keys, wrong
//! types); [`BoardConfig::validate`] then checks every semantic constraint and reports each
//! problem with its JSON path (`$.mission.population`).
//!
//! The defaults ([`BoardConfig::default`]) describe a Pioneer P3-DX with a SICK LMS1xx, with the
//! values of AriaCoda's `p3dx-sh-lms1xx.p` parameter file where they exist (radius 250 mm,
//! laser 55 mm ahead of the centre, switch to 38400 baud).

use core::fmt;
use core::ops::Deref;

use crate::geometry::Pose2;
use crate::math;
use crate::sensor::{LaserConfig, MAX_BEAMS};
use crate::units::deg_to_rad;

/// Largest optimizer population a board may ask for: what every optimizer holds
/// ([`crate::optim::MAX_POP`]), so that a population the board accepts also runs.
pub const MAX_POPULATION: u16 = crate::optim::MAX_POP as u16;

/// Target-selection methods a board may name in `mission.method`.
pub const KNOWN_METHODS: [&str; 12] = [
    "xboa",
    "boa",
    "mboa",
    "aboa",
    "saboa",
    "ga",
    "pso",
    "gwo",
    "abc",
    "cmaes",
    "nearest-frontier",
    "frontier-utility",
];

/// Robot subclasses (ARCOS SYNC2/CONFIG subtype) a P3-DX board may expect, compared without
/// regard to case: those with conversion factors in
/// [`ConversionFactors`](crate::control::odometry::ConversionFactors).
pub use crate::control::odometry::KNOWN_SUBCLASSES;

/// Serial speeds the ARCOS HOSTBAUD command can select \[baud\], indexed by HOSTBAUD code.
pub const ARCOS_BAUD_RATES: [u32; 5] = [9600, 19200, 38400, 57600, 115200];

/// Serial speeds a SICK LMS200 can be switched to \[baud\].
pub const LMS200_BAUD_RATES: [u32; 3] = [9600, 19200, 38400];

/// Absolute translational speed limit of a P3-DX \[mm/s\] (AriaCoda p3dx-sh.p MaxVelocity).
pub const P3DX_MAX_SPEED_MM_S: f32 = 2200.0;

/// Absolute rotational speed limit of a P3-DX \[deg/s\] (AriaCoda p3dx-sh.p MaxRVelocity).
pub const P3DX_MAX_TURN_RATE_DEG_S: f32 = 500.0;

/// Default ARCOS firmware watchdog \[s\]: a stale timeout longer than this means the firmware
/// stops the robot before the onboard program notices.
pub const ARCOS_WATCHDOG_S: f32 = 2.0;

/// A string of at most `N` bytes, parsed from JSON without an allocator.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BoundedStr<const N: usize>(heapless::String<N>);

impl<const N: usize> BoundedStr<N> {
    /// Copies `s`; `None` if it is longer than `N` bytes.
    pub fn new(s: &str) -> Option<Self> {
        let mut out = heapless::String::new();
        out.push_str(s).ok()?;
        Some(Self(out))
    }

    /// The text.
    pub fn as_str(&self) -> &str {
        self.0.as_str()
    }
}

impl<const N: usize> Deref for BoundedStr<N> {
    type Target = str;
    fn deref(&self) -> &str {
        self.0.as_str()
    }
}

impl<const N: usize> fmt::Display for BoundedStr<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl<'de, const N: usize> serde::Deserialize<'de> for BoundedStr<N> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor<const M: usize>;
        impl<const M: usize> serde::de::Visitor<'_> for Visitor<M> {
            type Value = BoundedStr<M>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a string of at most {M} bytes")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
                BoundedStr::new(v).ok_or_else(|| E::invalid_length(v.len(), &self))
            }
        }
        deserializer.deserialize_str(Visitor::<N>)
    }
}

/// A short name (robot name, subclass, method, model, strategy).
pub type Name = BoundedStr<32>;

/// A device path or a network address (`/dev/ttyS0`, `192.168.0.1:2111`).
pub type Address = BoundedStr<64>;

/// The robot: identity, geometry and motion limits.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotConfig {
    /// A name for logs (the robot reports its own name in SYNC2).
    pub name: Name,
    /// The ARCOS subclass the robot must report (`p3dx-sh`), compared without regard to case.
    pub subclass: Name,
    /// Radius of the circle around the robot that `check` compares the grid's cells and the
    /// laser's blind zone with \[m\]. What the planner and the safety monitor take for the
    /// body is [`Self::footprint`].
    pub radius_m: f32,
    /// Translational speed limit sent as SETV \[mm/s\].
    pub max_speed_mm_s: f32,
    /// Rotational speed limit sent as SETRV \[deg/s\].
    pub max_turn_rate_deg_s: f32,
    /// Translational acceleration sent as SETA \[mm/s²\].
    pub accel_mm_s2: f32,
    /// Translational deceleration sent as SETA with a negative argument \[mm/s²\].
    pub decel_mm_s2: f32,
    /// Rotational acceleration and deceleration sent as SETRA \[deg/s²\].
    pub rot_accel_deg_s2: f32,
    /// Odometry correction: the ratio of the right and left wheels' effective diameters,
    /// `Ed = D_R / D_L` (Borenstein & Feng 1996; `papillon calibrate` measures it); absent:
    /// 1, no correction.
    #[serde(default)]
    pub wheel_diameter_ratio: Option<f32>,
    /// Odometry correction: the effective wheelbase over the one the firmware assumes,
    /// `Eb` (Borenstein & Feng 1996; `papillon calibrate` measures it); absent: 1.
    #[serde(default)]
    pub wheelbase_ratio: Option<f32>,
    /// The nominal wheelbase `papillon calibrate` computed the corrections with \[m\];
    /// absent: 0.33.
    #[serde(default)]
    pub wheelbase_m: Option<f32>,
    /// The body's outline, for planning and the safety monitor (optional; each absent key
    /// takes the P3-DX datasheet's value, [`crate::control::safety::RobotFootprint::p3dx`]).
    #[serde(default)]
    pub footprint: FootprintBoardConfig,
}

/// The robot's outline seen from above (`$.robot.footprint`, optional): a rectangle around
/// the centre of rotation and the circle it sweeps turning in place. Every key is optional;
/// an absent one takes the P3-DX's (0.381 m wide, 0.21 m ahead of the axle, 0.245 m behind
/// it, 0.267 m swing radius).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FootprintBoardConfig {
    /// Overall width \[m\].
    #[serde(default)]
    pub width_m: Option<f32>,
    /// From the centre of rotation to the front edge \[m\].
    #[serde(default)]
    pub front_m: Option<f32>,
    /// From the centre of rotation to the rear edge \[m\].
    #[serde(default)]
    pub rear_m: Option<f32>,
    /// Radius of the circle swept turning in place \[m\].
    #[serde(default)]
    pub swing_radius_m: Option<f32>,
}

/// How the planner treats the body (`$.planning`, an optional section). Every key is
/// optional.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanningBoardConfig {
    /// Room kept between the body's side and a wall on a planned path, each side \[m\]; absent:
    /// [`crate::mission::footprint::DEFAULT_CLEARANCE_M`] (0.05).
    #[serde(default)]
    pub clearance_m: Option<f32>,
}

/// The link to the robot's microcontroller.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkConfig {
    /// Serial device (`/dev/ttyS0`).
    pub port: Address,
    /// A TCP address (`host:port`) to use instead of the serial port (MobileSim, AMRISim,
    /// `papillon-sim serve`, serial-to-ethernet bridges).
    #[serde(default)]
    pub tcp: Option<Address>,
    /// Serial speed the connection starts at \[baud\] (ARCOS robots start at 9600).
    pub baud: u32,
    /// Serial speed to switch to with HOSTBAUD when the robot allows it \[baud\].
    pub switch_to_baud: u32,
}

/// Which laser rangefinder a board carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LaserModel {
    /// SICK LMS1xx (LMS111 etc.), CoLa-A over TCP.
    Lms1xx,
    /// SICK LMS200, binary telegrams over RS-232.
    Lms200,
}

impl LaserModel {
    /// The model named `name` in a board file (`lms1xx`, `lms200`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "lms1xx" => Some(Self::Lms1xx),
            "lms200" => Some(Self::Lms200),
            _ => None,
        }
    }
}

/// Laser mount on the robot (base frame: x forward, y left).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountConfig {
    /// Forward offset from the robot's centre \[m\].
    pub x_m: f32,
    /// Leftward offset \[m\].
    pub y_m: f32,
    /// Yaw, counter-clockwise \[deg\].
    pub theta_deg: f32,
}

/// The laser rangefinder.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaserBoardConfig {
    /// `lms1xx` or `lms200`.
    pub model: Name,
    /// TCP address of an LMS1xx (`192.168.0.1:2111`).
    #[serde(default)]
    pub address: Option<Address>,
    /// Serial device of an LMS200 (`/dev/ttyS2`).
    #[serde(default)]
    pub port: Option<Address>,
    /// Serial speed of an LMS200 after start-up \[baud\].
    #[serde(default)]
    pub baud: Option<u32>,
    /// Beams per scan.
    pub beam_count: u16,
    /// Angle of the first beam in the laser frame \[deg\], counter-clockwise from forward.
    pub first_angle_deg: f32,
    /// Angle between consecutive beams \[deg\].
    pub step_deg: f32,
    /// Usable range \[m\].
    pub max_range_m: f32,
    /// Blind zone \[m\].
    pub min_range_m: f32,
    /// Range noise standard deviation as a fraction of the range.
    pub noise_fraction: f32,
    /// Scans per second the mission may expect.
    pub rate_hz: f32,
    /// Where the laser sits on the robot.
    pub mount: MountConfig,
}

/// Size, resolution and placement of the occupancy grid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridConfig {
    /// East-west extent \[m\].
    pub width_m: f32,
    /// North-south extent \[m\].
    pub height_m: f32,
    /// Cell side \[m\].
    pub resolution_m: f32,
    /// Map-frame east coordinate of the grid's south-west corner \[m\].
    pub origin_x_m: f32,
    /// Map-frame north coordinate of the grid's south-west corner \[m\].
    pub origin_y_m: f32,
}

impl GridConfig {
    /// Columns and rows the grid needs \[cells\] (each extent rounded up to whole cells).
    pub fn size_cells(&self) -> (usize, usize) {
        let cols = math::ceil(self.width_m / self.resolution_m);
        let rows = math::ceil(self.height_m / self.resolution_m);
        (cols as usize, rows as usize)
    }
}

/// How far ahead the target selection looks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Strategy {
    /// Choose among nearby targets (the thesis's short-term strategy).
    Short,
    /// Choose among all frontier targets (long-term).
    Long,
}

impl Strategy {
    /// The strategy named `name` in a board file (`short`, `long`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "short" => Some(Self::Short),
            "long" => Some(Self::Long),
            _ => None,
        }
    }
}

/// Mission settings: target selection and energy budget.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionConfig {
    /// Target-selection method, one of [`KNOWN_METHODS`].
    pub method: Name,
    /// Optimizer population \[individuals\], 2..=[`MAX_POPULATION`].
    pub population: u16,
    /// Optimizer generations per decision.
    pub generations: u16,
    /// `short` or `long`.
    pub strategy: Name,
    /// What the optimizers maximise: `efficient` (the default when absent) or `thesis`
    /// ([`crate::explore::ObjectiveKind`]).
    #[serde(default)]
    pub objective: Option<Name>,
    /// The optimizers' parameter sets: `standard` (the default when absent) or `thesis`
    /// ([`crate::optim::Preset`]; only GA, PSO, GWO and ABC differ).
    #[serde(default)]
    pub preset: Option<Name>,
    /// Candidate targets considered per decision.
    pub targets: u16,
    /// Energy budget \[steps\] (one step = 1 m of travel or 45° of rotation).
    pub battery_steps: f32,
    /// Energy kept in reserve \[steps\]; the mission ends when only this is left.
    pub reserve_steps: f32,
    /// Known-area fraction at which the mission is complete (0..=1).
    pub coverage_target: f32,
    /// Seed of the mission's random number generator.
    pub seed: u64,
    /// Battery voltage below which the mission ends once it stays there for
    /// `low_voltage_hold_s` (and until it is back 0.3 V above) \[V\]; absent: 11.5 V; 0: off.
    #[serde(default)]
    pub low_voltage_v: Option<f32>,
    /// How long the voltage must stay low before the mission ends \[s\]; absent: 5 s.
    #[serde(default)]
    pub low_voltage_hold_s: Option<f32>,
    /// Drive back to the start position when the mission ends (`papillon run
    /// --return-to-start` sets it too); absent: false.
    #[serde(default)]
    pub return_to_start: Option<bool>,
}

/// PID gains of the path follower.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PidConfig {
    /// Heading loop proportional gain \[(deg/s)/deg\].
    pub heading_kp: f32,
    /// Heading loop integral gain.
    pub heading_ki: f32,
    /// Heading loop derivative gain.
    pub heading_kd: f32,
    /// Distance loop proportional gain \[(mm/s)/mm\].
    pub distance_kp: f32,
    /// Distance loop integral gain.
    pub distance_ki: f32,
    /// Distance loop derivative gain.
    pub distance_kd: f32,
}

/// Safety distances and timeouts.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SafetyConfig {
    /// Stop when a laser return is closer than this to the robot's edge \[m\].
    pub obstacle_stop_m: f32,
    /// Stop when no status packet or no scan arrived for this long \[s\].
    pub stale_timeout_s: f32,
    /// Distance to back off after a bump or a too-close obstacle \[m\].
    pub back_off_m: f32,
}

/// How often the mission state is saved.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersistenceConfig {
    /// Interval between two saves of the mission state \[s\].
    pub save_every_s: f32,
}

/// Scan matching (`$.localize`, an optional section): each scan aligned to the map before it
/// is integrated, so the map stays true while the odometry drifts ([`crate::localize`]).
/// Every key is optional; an absent one takes the core's default
/// ([`crate::localize::LocalizeConfig::default`], [`crate::localize::MatchConfig::default`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalizeBoardConfig {
    /// Match scans at all; absent: false (the map is drawn at the odometry pose).
    #[serde(default)]
    pub enabled: Option<bool>,
    /// Match every this many scans (1: every scan that passes the travel test); absent: 1.
    #[serde(default)]
    pub every_n_scans: Option<u16>,
    /// A scan is matched only once the odometry has moved this far since the last match
    /// \[m\]...; absent: 0 (every scan is matched).
    #[serde(default)]
    pub min_travel_m: Option<f32>,
    /// ...or turned this much \[deg\]; absent: 0.
    #[serde(default)]
    pub min_turn_deg: Option<f32>,
    /// Translation searched around the odometry prediction, each way \[m\]; absent: 0.3.
    #[serde(default)]
    pub search_xy_m: Option<f32>,
    /// Rotation searched around the prediction, each way \[deg\]; absent: 5.7 (0.1 rad).
    #[serde(default)]
    pub search_theta_deg: Option<f32>,
    /// Keyframes in a pose graph with loop closures behind the matcher
    /// ([`crate::localize::graph`]); absent: false. Needs `enabled`.
    #[serde(default)]
    pub pose_graph: Option<bool>,
    /// Estimate the odometry's systematic errors (turn gain, curvature per metre) from the
    /// matches and correct each odometry increment with them
    /// ([`crate::localize::odometry_calibration`]); absent: true.
    #[serde(default)]
    pub self_calibration: Option<bool>,
}

/// Which scans go into the map (`$.mapping`, an optional section): with `motion_filter` on,
/// a scan is integrated only once the robot moved or turned enough since the last integrated
/// scan, or after a time ([`crate::mission::motion_filter`]). Every key is optional; absent
/// thresholds take [`crate::mission::MotionFilterConfig::standard`]'s.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MappingBoardConfig {
    /// Filter the scans at all; absent: false (every scan is mapped, as in the thesis).
    #[serde(default)]
    pub motion_filter: Option<bool>,
    /// A scan is mapped once the robot moved this far since the last mapped one \[m\]...
    #[serde(default)]
    pub min_travel_m: Option<f32>,
    /// ...or turned this much \[deg\]...
    #[serde(default)]
    pub min_turn_deg: Option<f32>,
    /// ...or this long has passed \[s\].
    #[serde(default)]
    pub max_interval_s: Option<f32>,
    /// Probability above which a cell is an obstacle (ROS `map_server`'s `occupied_thresh`);
    /// absent: [`crate::grid::DEFAULT_OCCUPIED_THRESH`] (0.5, the thesis's rule; 0.65 for a
    /// noisy laser, [`crate::grid::NOISY_LASER_OCCUPIED_THRESH`]).
    #[serde(default)]
    pub occupied_thresh: Option<f32>,
}

/// A whole board file.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoardConfig {
    /// The robot.
    pub robot: RobotConfig,
    /// The microcontroller link.
    pub link: LinkConfig,
    /// The laser.
    pub laser: LaserBoardConfig,
    /// The map grid.
    pub grid: GridConfig,
    /// The mission.
    pub mission: MissionConfig,
    /// The PID gains.
    pub pid: PidConfig,
    /// The safety settings.
    pub safety: SafetyConfig,
    /// The persistence settings.
    pub persistence: PersistenceConfig,
    /// Scan matching (optional; absent: off).
    #[serde(default)]
    pub localize: LocalizeBoardConfig,
    /// Which scans are mapped (optional; absent: every scan).
    #[serde(default)]
    pub mapping: MappingBoardConfig,
    /// How the planner treats the body (optional; absent: the defaults).
    #[serde(default)]
    pub planning: PlanningBoardConfig,
}

fn name(s: &str) -> Name {
    // Every literal used below fits; an empty name would be caught by `validate`.
    Name::new(s).unwrap_or_default()
}

fn address(s: &str) -> Address {
    Address::new(s).unwrap_or_default()
}

impl Default for BoardConfig {
    /// A P3-DX with an LMS1xx on the onboard PC's first serial port.
    fn default() -> Self {
        Self {
            robot: RobotConfig {
                name: name("p3dx"),
                subclass: name("p3dx-sh"),
                radius_m: 0.25,
                max_speed_mm_s: 400.0,
                max_turn_rate_deg_s: 60.0,
                accel_mm_s2: 300.0,
                decel_mm_s2: 300.0,
                rot_accel_deg_s2: 100.0,
                wheel_diameter_ratio: None,
                wheelbase_ratio: None,
                wheelbase_m: None,
                footprint: FootprintBoardConfig::default(),
            },
            link: LinkConfig {
                port: address("/dev/ttyS0"),
                tcp: None,
                baud: 9600,
                switch_to_baud: 38400,
            },
            laser: LaserBoardConfig {
                model: name("lms1xx"),
                address: Some(address("192.168.0.1:2111")),
                port: None,
                baud: None,
                beam_count: 541,
                first_angle_deg: -135.0,
                step_deg: 0.5,
                max_range_m: 4.0,
                min_range_m: 0.30,
                noise_fraction: 0.05,
                rate_hz: 25.0,
                mount: MountConfig {
                    x_m: 0.055,
                    y_m: 0.0,
                    theta_deg: 0.0,
                },
            },
            grid: GridConfig {
                width_m: 24.0,
                height_m: 24.0,
                resolution_m: 0.10,
                origin_x_m: -12.0,
                origin_y_m: -12.0,
            },
            mission: MissionConfig {
                method: name("xboa"),
                population: 20,
                generations: 30,
                strategy: name("short"),
                objective: None,
                preset: None,
                targets: 16,
                battery_steps: 400.0,
                reserve_steps: 20.0,
                coverage_target: 0.95,
                seed: 1,
                low_voltage_v: None,
                low_voltage_hold_s: None,
                return_to_start: None,
            },
            pid: PidConfig {
                heading_kp: 2.0,
                heading_ki: 0.0,
                heading_kd: 0.1,
                distance_kp: 1.0,
                distance_ki: 0.0,
                distance_kd: 0.05,
            },
            safety: SafetyConfig {
                obstacle_stop_m: 0.15,
                stale_timeout_s: 0.5,
                back_off_m: 0.2,
            },
            persistence: PersistenceConfig { save_every_s: 5.0 },
            localize: LocalizeBoardConfig::default(),
            mapping: MappingBoardConfig::default(),
            planning: PlanningBoardConfig::default(),
        }
    }
}

/// Errors reading a board file.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigError {
    /// The text is not well-formed JSON.
    Syntax {
        /// Byte offset of the first offending byte (0-based).
        offset: usize,
        /// Line of that byte (1-based).
        line: usize,
        /// Column of that byte (1-based, in bytes).
        column: usize,
        /// What was expected there.
        expected: &'static str,
    },
    /// A key a board file does not have (often a typo).
    UnknownKey {
        /// JSON path of the key, such as `$.mission.populaton`.
        path: heapless::String<96>,
        /// Line of the key (1-based).
        line: usize,
        /// Column of the key's opening quote (1-based, in bytes).
        column: usize,
    },
    /// A required key is absent.
    MissingKey {
        /// JSON path of the key, such as `$.mission.population`.
        path: &'static str,
    },
    /// A key given twice in the same object.
    DuplicateKey {
        /// JSON path of the key, such as `$.mission.seed`.
        path: &'static str,
        /// Line of the second occurrence (1-based).
        line: usize,
        /// Column of its opening quote (1-based, in bytes).
        column: usize,
    },
    /// Well-formed JSON with every key in place, but a value of the wrong type (a string
    /// where a number belongs, a negative count, a fraction for a count) or a string too long
    /// for its field.
    Value {
        /// JSON path of the value, such as `$.mission.population` (empty if the parser could
        /// not tell).
        path: &'static str,
        /// Line of the value (1-based; 0 if unknown).
        line: usize,
        /// Column of its first byte (1-based, in bytes; 0 if unknown).
        column: usize,
        /// What the field holds (`a whole number from 0 to 65535`); empty if unknown.
        expected: &'static str,
        /// What was found (the value's first bytes, or a string's length), or the parser's
        /// description when `path` is empty.
        found: heapless::String<48>,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Syntax {
                offset,
                line,
                column,
                expected,
            } => write!(
                f,
                "JSON syntax error at line {line}, column {column} (byte {offset}): expected {expected}"
            ),
            ConfigError::UnknownKey { path, line, column } => {
                write!(f, "unknown key {path} at line {line}, column {column}")
            }
            ConfigError::MissingKey { path } => write!(f, "missing key {path}"),
            ConfigError::DuplicateKey { path, line, column } => {
                write!(f, "duplicate key {path} at line {line}, column {column}")
            }
            ConfigError::Value {
                path,
                line,
                column,
                expected,
                found,
            } if !path.is_empty() => write!(
                f,
                "{path} at line {line}, column {column}: expected {expected}, found {found}"
            ),
            ConfigError::Value { found, .. } => write!(
                f,
                "a value has the wrong type or is too long for its field ({found}); see docs/user-guide.md for the types"
            ),
        }
    }
}

impl core::error::Error for ConfigError {}

impl BoardConfig {
    /// Parses a board file. Syntax errors carry their line, column and byte offset; shape
    /// errors (missing or unknown keys, wrong types) carry the parser's message naming the key.
    /// Semantic constraints are checked separately by [`BoardConfig::validate`].
    pub fn from_json(json: &[u8]) -> Result<BoardConfig, ConfigError> {
        let seen = syntax::check_syntax(json)?;
        if let Some(path) = syntax::SCHEMA
            .iter()
            .enumerate()
            .find(|(i, (_, required, _))| *required && seen & (1u128 << i) == 0)
            .map(|(_, (path, ..))| *path)
        {
            return Err(ConfigError::MissingKey { path });
        }
        match serde_json_core::from_slice::<BoardConfig>(json) {
            Ok((config, _)) => Ok(config),
            Err(e) => {
                let mut message = heapless::String::new();
                let _ = fmt::write(&mut message, format_args!("{e}"));
                Err(ConfigError::Value {
                    path: "",
                    line: 0,
                    column: 0,
                    expected: "",
                    found: message,
                })
            }
        }
    }

    /// The laser description the core's sensor model uses.
    pub fn laser_config(&self) -> LaserConfig {
        let l = &self.laser;
        LaserConfig {
            beam_count: l.beam_count,
            first_angle_rad: deg_to_rad(l.first_angle_deg),
            step_rad: deg_to_rad(l.step_deg),
            max_range_m: l.max_range_m,
            min_range_m: l.min_range_m,
            noise_fraction: l.noise_fraction,
            mount: Pose2::new(l.mount.x_m, l.mount.y_m, deg_to_rad(l.mount.theta_deg)),
            rate_hz: l.rate_hz,
        }
    }

    /// The laser model, `None` if the board names an unknown one.
    pub fn laser_model(&self) -> Option<LaserModel> {
        LaserModel::from_name(&self.laser.model)
    }

    /// What the optimizers maximise (the default when the board names none), `None` if the
    /// board names an unknown objective.
    pub fn objective(&self) -> Option<crate::explore::ObjectiveKind> {
        match &self.mission.objective {
            Some(name) => crate::explore::ObjectiveKind::from_name(name),
            None => Some(crate::explore::ObjectiveKind::default()),
        }
    }

    /// The optimizers' parameter sets (the exploration's default when the board names none),
    /// `None` if the board names an unknown preset.
    pub fn preset(&self) -> Option<crate::optim::Preset> {
        match &self.mission.preset {
            Some(name) => name.parse().ok(),
            None => Some(crate::explore::DEFAULT_PRESET),
        }
    }

    /// The scan matching the board asks for: the core's defaults
    /// ([`crate::localize::LocalizeConfig::default`]) with what `$.localize` gives.
    pub fn localize_config(&self) -> crate::localize::LocalizeConfig {
        let l = &self.localize;
        let mut c = crate::localize::LocalizeConfig::default();
        c.enabled = l.enabled.unwrap_or(c.enabled);
        c.every_n_scans = l.every_n_scans.map_or(c.every_n_scans, u32::from);
        c.min_travel_m = l.min_travel_m.unwrap_or(c.min_travel_m);
        c.min_turn_rad = l.min_turn_deg.map_or(c.min_turn_rad, deg_to_rad);
        c.matcher.search_xy_m = l.search_xy_m.unwrap_or(c.matcher.search_xy_m);
        c.matcher.search_theta_rad = l
            .search_theta_deg
            .map_or(c.matcher.search_theta_rad, deg_to_rad);
        c.graph.enabled = l.pose_graph.unwrap_or(c.graph.enabled);
        c.calibration.enabled = l.self_calibration.unwrap_or(c.calibration.enabled);
        c
    }

    /// The mapping motion filter the board asks for: off unless `$.mapping.motion_filter`
    /// is true, then [`crate::mission::MotionFilterConfig::standard`] with what `$.mapping`
    /// gives.
    pub fn motion_filter_config(&self) -> crate::mission::MotionFilterConfig {
        let m = &self.mapping;
        if m.motion_filter != Some(true) {
            return crate::mission::MotionFilterConfig::off();
        }
        let mut c = crate::mission::MotionFilterConfig::standard();
        c.min_travel_m = m.min_travel_m.unwrap_or(c.min_travel_m);
        c.min_turn_rad = m.min_turn_deg.map_or(c.min_turn_rad, deg_to_rad);
        c.max_interval_s = m.max_interval_s.unwrap_or(c.max_interval_s);
        c
    }

    /// The grid's log-odds bounds with `$.mapping.occupied_thresh` (the default's where
    /// absent; `None` for a value [`crate::grid::LogOddsBounds::with_occupied_thresh`]
    /// refuses, which validation reports).
    pub fn grid_bounds(&self) -> Option<crate::grid::LogOddsBounds> {
        let b = crate::grid::LogOddsBounds::default();
        match self.mapping.occupied_thresh {
            Some(p) => b.with_occupied_thresh(p),
            None => Some(b),
        }
    }

    /// The body's outline: `$.robot.footprint`'s values, the P3-DX's where absent.
    pub fn footprint(&self) -> crate::control::safety::RobotFootprint {
        let f = &self.robot.footprint;
        let p3dx = crate::control::safety::RobotFootprint::p3dx();
        crate::control::safety::RobotFootprint {
            width_m: f.width_m.unwrap_or(p3dx.width_m),
            front_m: f.front_m.unwrap_or(p3dx.front_m),
            rear_m: f.rear_m.unwrap_or(p3dx.rear_m),
            radius_m: f.swing_radius_m.unwrap_or(p3dx.radius_m),
        }
    }

    /// The clearance kept each side of the body on planned paths \[m\]: `$.planning.clearance_m`,
    /// or [`crate::mission::footprint::DEFAULT_CLEARANCE_M`].
    pub fn clearance_m(&self) -> f32 {
        self.planning
            .clearance_m
            .unwrap_or(crate::mission::footprint::DEFAULT_CLEARANCE_M)
    }

    /// The planning layer the board's body and clearance make at its cell size
    /// ([`crate::mission::footprint::planning_layer`], Unknown cells crossed at the default
    /// factor): what `papillon run` plans with and `check` tests.
    pub fn planning_layer(&self) -> crate::planner::TraversabilityConfig {
        let safety = crate::control::safety::SafetyConfig {
            footprint: self.footprint(),
            ..Default::default()
        };
        crate::mission::footprint::planning_layer(
            &safety,
            self.clearance_m(),
            self.grid.resolution_m,
            crate::planner::UnknownPolicy::Traversable {
                cost_factor: crate::planner::traversability::DEFAULT_UNKNOWN_COST_FACTOR,
            },
        )
    }

    /// The target-selection strategy, `None` if the board names an unknown one.
    pub fn strategy(&self) -> Option<Strategy> {
        Strategy::from_name(&self.mission.strategy)
    }
}

/// `host:port` with a non-empty host and a port in 1..=65535.
pub fn is_host_port(s: &str) -> bool {
    let Some((host, port)) = s.rsplit_once(':') else {
        return false;
    };
    !host.is_empty()
        && !port.is_empty()
        && port.bytes().all(|b| b.is_ascii_digit())
        && port.len() <= 5
        && matches!(port.parse::<u32>(), Ok(1..=65535))
}

mod syntax;
mod validate;

#[cfg(test)]
mod tests;
