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
use crate::grid::DEFAULT_CELL_CAPACITY;
use crate::math;
use crate::sensor::{LaserConfig, MAX_BEAMS};
use crate::units::deg_to_rad;

/// Largest optimizer population a board may ask for.
pub const MAX_POPULATION: u16 = 64;

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
/// regard to case.
pub const KNOWN_SUBCLASSES: [&str; 4] = ["p3dx", "p3dx-sh", "p3dx-sh-lms1xx", "p3dx-sh-lms500"];

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
    /// Radius of the robot's footprint \[m\].
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
                targets: 16,
                battery_steps: 400.0,
                reserve_steps: 20.0,
                coverage_target: 0.95,
                seed: 1,
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
    /// Well-formed JSON with every key in place, but a value of the wrong type (a string
    /// where a number belongs, a negative count) or a string too long for its field.
    Value {
        /// The parser's description of the mismatch.
        message: heapless::String<96>,
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
            ConfigError::Value { message } => write!(
                f,
                "a value has the wrong type or is too long for its field ({message}); see docs/user-guide.md for the types"
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
        let seen = check_syntax(json)?;
        if let Some(path) = SCHEMA
            .iter()
            .enumerate()
            .find(|(i, (_, required))| *required && seen & (1u128 << i) == 0)
            .map(|(_, (path, _))| *path)
        {
            return Err(ConfigError::MissingKey { path });
        }
        match serde_json_core::from_slice::<BoardConfig>(json) {
            Ok((config, _)) => Ok(config),
            Err(e) => {
                let mut message = heapless::String::new();
                let _ = fmt::write(&mut message, format_args!("{e}"));
                Err(ConfigError::Value { message })
            }
        }
    }

    /// Checks every semantic constraint and calls `report(path, problem)` once per problem,
    /// with `path` a JSON path such as `$.mission.population`. Returns the number of problems.
    pub fn validate(&self, mut report: impl FnMut(&str, &str)) -> usize {
        let mut count = 0usize;
        let mut r = |path: &str, problem: &str| {
            count += 1;
            report(path, problem);
        };
        self.validate_robot(&mut r);
        self.validate_link(&mut r);
        self.validate_laser(&mut r);
        self.validate_grid(&mut r);
        self.validate_mission(&mut r);
        self.validate_pid(&mut r);
        self.validate_safety(&mut r);
        if !positive(self.persistence.save_every_s) {
            r(
                "$.persistence.save_every_s",
                "must be a positive number of seconds",
            );
        }
        count
    }

    fn validate_robot(&self, r: &mut impl FnMut(&str, &str)) {
        let robot = &self.robot;
        if robot.name.is_empty() {
            r("$.robot.name", "must not be empty");
        }
        if !KNOWN_SUBCLASSES
            .iter()
            .any(|k| k.eq_ignore_ascii_case(&robot.subclass))
        {
            r(
                "$.robot.subclass",
                "unknown P3-DX subclass; expected one of p3dx, p3dx-sh, p3dx-sh-lms1xx, p3dx-sh-lms500",
            );
        }
        if !(positive(robot.radius_m) && robot.radius_m <= 1.0) {
            r("$.robot.radius_m", "must be in (0, 1] m");
        }
        if !(positive(robot.max_speed_mm_s) && robot.max_speed_mm_s <= P3DX_MAX_SPEED_MM_S) {
            r(
                "$.robot.max_speed_mm_s",
                "must be in (0, 2200] mm/s (the P3-DX absolute limit)",
            );
        }
        if !(positive(robot.max_turn_rate_deg_s)
            && robot.max_turn_rate_deg_s <= P3DX_MAX_TURN_RATE_DEG_S)
        {
            r(
                "$.robot.max_turn_rate_deg_s",
                "must be in (0, 500] deg/s (the P3-DX absolute limit)",
            );
        }
        for (path, v) in [
            ("$.robot.accel_mm_s2", robot.accel_mm_s2),
            ("$.robot.decel_mm_s2", robot.decel_mm_s2),
            ("$.robot.rot_accel_deg_s2", robot.rot_accel_deg_s2),
        ] {
            if !(positive(v) && v <= i16::MAX as f32) {
                r(path, "must be in (0, 32767] (an ARCOS integer argument)");
            }
        }
    }

    fn validate_link(&self, r: &mut impl FnMut(&str, &str)) {
        let link = &self.link;
        match &link.tcp {
            Some(tcp) => {
                if !is_host_port(tcp) {
                    r("$.link.tcp", "must be host:port with a port in 1..=65535");
                }
            }
            None => {
                if link.port.is_empty() {
                    r(
                        "$.link.port",
                        "must name a serial device when no tcp is given",
                    );
                }
            }
        }
        if !ARCOS_BAUD_RATES.contains(&link.baud) {
            r(
                "$.link.baud",
                "must be one of 9600, 19200, 38400, 57600, 115200",
            );
        }
        if !ARCOS_BAUD_RATES.contains(&link.switch_to_baud) {
            r(
                "$.link.switch_to_baud",
                "must be one of 9600, 19200, 38400, 57600, 115200",
            );
        }
    }

    fn validate_laser(&self, r: &mut impl FnMut(&str, &str)) {
        let laser = &self.laser;
        match LaserModel::from_name(&laser.model) {
            None => r("$.laser.model", "must be \"lms1xx\" or \"lms200\""),
            Some(LaserModel::Lms1xx) => match &laser.address {
                Some(a) if is_host_port(a) => {}
                Some(_) => r(
                    "$.laser.address",
                    "must be host:port with a port in 1..=65535",
                ),
                None => r("$.laser.address", "an lms1xx needs a TCP address host:port"),
            },
            Some(LaserModel::Lms200) => {
                match &laser.port {
                    Some(p) if !p.is_empty() => {}
                    _ => r("$.laser.port", "an lms200 needs a serial device"),
                }
                if let Some(b) = laser.baud
                    && !LMS200_BAUD_RATES.contains(&b)
                {
                    r("$.laser.baud", "must be one of 9600, 19200, 38400");
                }
            }
        }
        let count_ok = laser.beam_count >= 2 && laser.beam_count as usize <= MAX_BEAMS;
        if !count_ok {
            r("$.laser.beam_count", "must be in 2..=1081 beams");
        }
        if !(laser.first_angle_deg.is_finite() && math::abs(laser.first_angle_deg) <= 180.0) {
            r("$.laser.first_angle_deg", "must be in [-180, 180] deg");
        }
        if !positive(laser.step_deg) {
            r("$.laser.step_deg", "must be a positive angle in degrees");
        } else if count_ok && (laser.beam_count - 1) as f32 * laser.step_deg > 360.0 {
            r(
                "$.laser.step_deg",
                "beam_count and step_deg span more than 360 deg",
            );
        }
        if !(laser.min_range_m.is_finite() && laser.min_range_m >= 0.0) {
            r("$.laser.min_range_m", "must be zero or positive [m]");
        }
        if !positive(laser.max_range_m) {
            r("$.laser.max_range_m", "must be a positive range [m]");
        } else if laser.min_range_m >= laser.max_range_m {
            r("$.laser.max_range_m", "must be larger than min_range_m");
        }
        if !(laser.noise_fraction.is_finite()
            && laser.noise_fraction >= 0.0
            && laser.noise_fraction < 1.0)
        {
            r("$.laser.noise_fraction", "must be in [0, 1)");
        }
        if !positive(laser.rate_hz) {
            r("$.laser.rate_hz", "must be a positive rate [Hz]");
        }
        let m = &laser.mount;
        for (path, v) in [("$.laser.mount.x_m", m.x_m), ("$.laser.mount.y_m", m.y_m)] {
            if !(v.is_finite() && math::abs(v) <= 1.0) {
                r(path, "must be within 1 m of the robot's centre");
            }
        }
        if !(m.theta_deg.is_finite() && math::abs(m.theta_deg) <= 180.0) {
            r("$.laser.mount.theta_deg", "must be in [-180, 180] deg");
        }
    }

    fn validate_grid(&self, r: &mut impl FnMut(&str, &str)) {
        let g = &self.grid;
        let mut sizes_ok = true;
        for (path, v) in [
            ("$.grid.width_m", g.width_m),
            ("$.grid.height_m", g.height_m),
        ] {
            if !positive(v) {
                r(path, "must be a positive size [m]");
                sizes_ok = false;
            }
        }
        if !positive(g.resolution_m) {
            r("$.grid.resolution_m", "must be a positive cell size [m]");
            sizes_ok = false;
        }
        if sizes_ok {
            let (cols, rows) = g.size_cells();
            if cols.saturating_mul(rows) > DEFAULT_CELL_CAPACITY {
                r(
                    "$.grid",
                    "width_m x height_m at resolution_m needs more cells than the grid holds (150000)",
                );
            }
            if positive(self.robot.radius_m) && g.resolution_m > self.robot.radius_m {
                r(
                    "$.grid.resolution_m",
                    "cells larger than the robot's radius cannot represent passages",
                );
            }
        }
        for (path, v) in [
            ("$.grid.origin_x_m", g.origin_x_m),
            ("$.grid.origin_y_m", g.origin_y_m),
        ] {
            if !v.is_finite() {
                r(path, "must be a finite coordinate [m]");
            }
        }
        if sizes_ok
            && g.origin_x_m.is_finite()
            && g.origin_y_m.is_finite()
            && !(g.origin_x_m <= 0.0
                && g.origin_y_m <= 0.0
                && g.origin_x_m + g.width_m > 0.0
                && g.origin_y_m + g.height_m > 0.0)
        {
            r(
                "$.grid",
                "the start pose (0, 0) must lie inside the grid: origin must be <= 0 and origin + size > 0",
            );
        }
    }

    fn validate_mission(&self, r: &mut impl FnMut(&str, &str)) {
        let m = &self.mission;
        if !KNOWN_METHODS.contains(&m.method.as_str()) {
            r(
                "$.mission.method",
                "unknown method; expected one of xboa, boa, mboa, aboa, saboa, ga, pso, gwo, abc, cmaes, nearest-frontier, frontier-utility",
            );
        }
        if !(2..=MAX_POPULATION).contains(&m.population) {
            r("$.mission.population", "must be in 2..=64");
        }
        if m.generations == 0 {
            r("$.mission.generations", "must be at least 1");
        }
        if Strategy::from_name(&m.strategy).is_none() {
            r("$.mission.strategy", "must be \"short\" or \"long\"");
        }
        if m.targets == 0 {
            r("$.mission.targets", "must be at least 1");
        }
        if !positive(m.battery_steps) {
            r(
                "$.mission.battery_steps",
                "must be a positive energy [steps]",
            );
        }
        if !(m.reserve_steps.is_finite() && m.reserve_steps >= 0.0) {
            r(
                "$.mission.reserve_steps",
                "must be zero or positive [steps]",
            );
        } else if positive(m.battery_steps) && m.reserve_steps >= m.battery_steps {
            r("$.mission.reserve_steps", "must be less than battery_steps");
        }
        if !(positive(m.coverage_target) && m.coverage_target <= 1.0) {
            r("$.mission.coverage_target", "must be a fraction in (0, 1]");
        }
    }

    fn validate_pid(&self, r: &mut impl FnMut(&str, &str)) {
        let p = &self.pid;
        for (path, v) in [
            ("$.pid.heading_kp", p.heading_kp),
            ("$.pid.distance_kp", p.distance_kp),
        ] {
            if !positive(v) {
                r(path, "must be a positive gain");
            }
        }
        for (path, v) in [
            ("$.pid.heading_ki", p.heading_ki),
            ("$.pid.heading_kd", p.heading_kd),
            ("$.pid.distance_ki", p.distance_ki),
            ("$.pid.distance_kd", p.distance_kd),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                r(path, "must be zero or a positive gain");
            }
        }
    }

    fn validate_safety(&self, r: &mut impl FnMut(&str, &str)) {
        let s = &self.safety;
        if !positive(s.obstacle_stop_m) {
            r(
                "$.safety.obstacle_stop_m",
                "must be a positive distance [m]",
            );
        } else if positive(self.robot.radius_m)
            && self.laser.min_range_m.is_finite()
            && s.obstacle_stop_m < self.laser.min_range_m - self.robot.radius_m
        {
            r(
                "$.safety.obstacle_stop_m",
                "is inside the laser's blind zone, so it can never trigger",
            );
        }
        if !(positive(s.stale_timeout_s) && s.stale_timeout_s < ARCOS_WATCHDOG_S) {
            r(
                "$.safety.stale_timeout_s",
                "must be in (0, 2) s (below the ARCOS firmware watchdog)",
            );
        }
        if !(s.back_off_m.is_finite() && s.back_off_m >= 0.0 && s.back_off_m <= 1.0) {
            r("$.safety.back_off_m", "must be in [0, 1] m");
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

    /// The target-selection strategy, `None` if the board names an unknown one.
    pub fn strategy(&self) -> Option<Strategy> {
        Strategy::from_name(&self.mission.strategy)
    }
}

fn positive(v: f32) -> bool {
    v.is_finite() && v > 0.0
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

/// Every key a board file may hold, as a JSON path, and whether it is required.
const SCHEMA: &[(&str, bool)] = &[
    ("$.robot", true),
    ("$.robot.name", true),
    ("$.robot.subclass", true),
    ("$.robot.radius_m", true),
    ("$.robot.max_speed_mm_s", true),
    ("$.robot.max_turn_rate_deg_s", true),
    ("$.robot.accel_mm_s2", true),
    ("$.robot.decel_mm_s2", true),
    ("$.robot.rot_accel_deg_s2", true),
    ("$.link", true),
    ("$.link.port", true),
    ("$.link.tcp", false),
    ("$.link.baud", true),
    ("$.link.switch_to_baud", true),
    ("$.laser", true),
    ("$.laser.model", true),
    ("$.laser.address", false),
    ("$.laser.port", false),
    ("$.laser.baud", false),
    ("$.laser.beam_count", true),
    ("$.laser.first_angle_deg", true),
    ("$.laser.step_deg", true),
    ("$.laser.max_range_m", true),
    ("$.laser.min_range_m", true),
    ("$.laser.noise_fraction", true),
    ("$.laser.rate_hz", true),
    ("$.laser.mount", true),
    ("$.laser.mount.x_m", true),
    ("$.laser.mount.y_m", true),
    ("$.laser.mount.theta_deg", true),
    ("$.grid", true),
    ("$.grid.width_m", true),
    ("$.grid.height_m", true),
    ("$.grid.resolution_m", true),
    ("$.grid.origin_x_m", true),
    ("$.grid.origin_y_m", true),
    ("$.mission", true),
    ("$.mission.method", true),
    ("$.mission.population", true),
    ("$.mission.generations", true),
    ("$.mission.strategy", true),
    ("$.mission.targets", true),
    ("$.mission.battery_steps", true),
    ("$.mission.reserve_steps", true),
    ("$.mission.coverage_target", true),
    ("$.mission.seed", true),
    ("$.pid", true),
    ("$.pid.heading_kp", true),
    ("$.pid.heading_ki", true),
    ("$.pid.heading_kd", true),
    ("$.pid.distance_kp", true),
    ("$.pid.distance_ki", true),
    ("$.pid.distance_kd", true),
    ("$.safety", true),
    ("$.safety.obstacle_stop_m", true),
    ("$.safety.stale_timeout_s", true),
    ("$.safety.back_off_m", true),
    ("$.persistence", true),
    ("$.persistence.save_every_s", true),
];

// The seen-set is a `u128`.
const _: () = assert!(SCHEMA.len() <= 128);

/// A strict JSON syntax check (RFC 8259) that locates the first error, because
/// `serde-json-core` reports what went wrong but not where. It also checks every key against
/// [`SCHEMA`] and returns the set of schema entries seen (bit `i` for entry `i`).
fn check_syntax(json: &[u8]) -> Result<u128, ConfigError> {
    let mut s = Scanner {
        json,
        pos: 0,
        path: heapless::String::new(),
        seen: 0,
        unknown: None,
    };
    s.ws();
    s.value(0)?;
    s.ws();
    if s.pos < json.len() {
        return Err(s.error("end of input after the top-level value"));
    }
    if let Some(e) = s.unknown {
        return Err(e);
    }
    Ok(s.seen)
}

/// Nesting depth the syntax check accepts.
const MAX_DEPTH: usize = 32;

struct Scanner<'a> {
    json: &'a [u8],
    pos: usize,
    /// JSON path of the object being scanned (`$` at the top level; empty inside arrays).
    path: heapless::String<96>,
    /// Schema entries seen so far.
    seen: u128,
    /// The first unknown key.
    unknown: Option<ConfigError>,
}

impl Scanner<'_> {
    fn line_column(&self, pos: usize) -> (usize, usize) {
        let upto = &self.json[..pos.min(self.json.len())];
        let line = 1 + upto.iter().filter(|&&b| b == b'\n').count();
        let line_start = upto.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        (line, pos - line_start + 1)
    }

    fn error(&self, expected: &'static str) -> ConfigError {
        let (line, column) = self.line_column(self.pos);
        ConfigError::Syntax {
            offset: self.pos,
            line,
            column,
            expected,
        }
    }

    /// Records the key spanning `start..end` (quotes included) of the current object.
    fn key(&mut self, start: usize, end: usize) -> usize {
        let restore = self.path.len();
        let key = core::str::from_utf8(&self.json[start + 1..end - 1]).unwrap_or("?");
        let fits = self.path.push('.').is_ok() && self.path.push_str(key).is_ok();
        if !fits {
            // Deeper than any schema path: unknown for sure; keep the prefix readable.
            self.path.truncate(restore);
        }
        match SCHEMA
            .iter()
            .position(|(p, _)| fits && *p == self.path.as_str())
        {
            Some(i) => self.seen |= 1u128 << i,
            None if self.unknown.is_none() => {
                let (line, column) = self.line_column(start);
                let mut path = self.path.clone();
                if !fits {
                    let _ = path.push_str(".?");
                }
                self.unknown = Some(ConfigError::UnknownKey { path, line, column });
            }
            None => {}
        }
        restore
    }

    fn peek(&self) -> Option<u8> {
        self.json.get(self.pos).copied()
    }

    fn ws(&mut self) {
        while let Some(b' ' | b'\t' | b'\n' | b'\r') = self.peek() {
            self.pos += 1;
        }
    }

    fn value(&mut self, depth: usize) -> Result<(), ConfigError> {
        if depth == 0 {
            self.path.clear();
            let _ = self.path.push('$');
        }
        if depth > MAX_DEPTH {
            return Err(self.error("less deeply nested values"));
        }
        match self.peek() {
            Some(b'{') => self.object(depth),
            Some(b'[') => self.array(depth),
            Some(b'"') => self.string(),
            Some(b'-' | b'0'..=b'9') => self.number(),
            Some(b't') => self.literal(b"true"),
            Some(b'f') => self.literal(b"false"),
            Some(b'n') => self.literal(b"null"),
            _ => Err(self.error("a value (object, array, string, number, true, false or null)")),
        }
    }

    fn literal(&mut self, word: &[u8]) -> Result<(), ConfigError> {
        for &b in word {
            if self.peek() != Some(b) {
                return Err(self.error("true, false or null"));
            }
            self.pos += 1;
        }
        Ok(())
    }

    fn object(&mut self, depth: usize) -> Result<(), ConfigError> {
        self.pos += 1;
        self.ws();
        if self.peek() == Some(b'}') {
            self.pos += 1;
            return Ok(());
        }
        loop {
            self.ws();
            if self.peek() != Some(b'"') {
                return Err(self.error("a quoted key"));
            }
            let start = self.pos;
            self.string()?;
            let restore = self.key(start, self.pos);
            self.ws();
            if self.peek() != Some(b':') {
                return Err(self.error("':' after the key"));
            }
            self.pos += 1;
            self.ws();
            self.value(depth + 1)?;
            self.path.truncate(restore);
            self.ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b'}') => {
                    self.pos += 1;
                    return Ok(());
                }
                _ => return Err(self.error("',' or '}'")),
            }
        }
    }

    fn array(&mut self, depth: usize) -> Result<(), ConfigError> {
        self.pos += 1;
        self.ws();
        if self.peek() == Some(b']') {
            self.pos += 1;
            return Ok(());
        }
        let restore = self.path.len();
        let _ = self.path.push_str("[]");
        loop {
            self.ws();
            self.value(depth + 1)?;
            self.ws();
            match self.peek() {
                Some(b',') => self.pos += 1,
                Some(b']') => {
                    self.pos += 1;
                    self.path.truncate(restore);
                    return Ok(());
                }
                _ => return Err(self.error("',' or ']'")),
            }
        }
    }

    fn string(&mut self) -> Result<(), ConfigError> {
        self.pos += 1;
        loop {
            match self.peek() {
                None => return Err(self.error("a closing '\"'")),
                Some(b'"') => {
                    self.pos += 1;
                    return Ok(());
                }
                Some(b'\\') => {
                    self.pos += 1;
                    match self.peek() {
                        Some(b'"' | b'\\' | b'/' | b'b' | b'f' | b'n' | b'r' | b't') => {
                            self.pos += 1
                        }
                        Some(b'u') => {
                            self.pos += 1;
                            for _ in 0..4 {
                                if !self.peek().is_some_and(|b| b.is_ascii_hexdigit()) {
                                    return Err(self.error("four hex digits after \\u"));
                                }
                                self.pos += 1;
                            }
                        }
                        _ => return Err(self.error("a valid escape after '\\'")),
                    }
                }
                Some(0..=0x1F) => return Err(self.error("no control characters inside a string")),
                Some(_) => self.pos += 1,
            }
        }
    }

    fn digits(&mut self) -> usize {
        let start = self.pos;
        while self.peek().is_some_and(|b| b.is_ascii_digit()) {
            self.pos += 1;
        }
        self.pos - start
    }

    fn number(&mut self) -> Result<(), ConfigError> {
        if self.peek() == Some(b'-') {
            self.pos += 1;
        }
        match self.peek() {
            Some(b'0') => self.pos += 1,
            Some(b'1'..=b'9') => {
                self.digits();
            }
            _ => return Err(self.error("a digit")),
        }
        if self.peek() == Some(b'.') {
            self.pos += 1;
            if self.digits() == 0 {
                return Err(self.error("a digit after '.'"));
            }
        }
        if let Some(b'e' | b'E') = self.peek() {
            self.pos += 1;
            if let Some(b'+' | b'-') = self.peek() {
                self.pos += 1;
            }
            if self.digits() == 0 {
                return Err(self.error("a digit in the exponent"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
