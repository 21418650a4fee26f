//! Differential-drive pose tracking in the `odom` frame, and the `map`-from-`odom` transform.
//!
//! Two trackers:
//! - [`ArcosOdometry`] follows the pose the P3-DX integrates itself and reports in every SIP
//!   (docs/protocols.md §1.6): XPOS and YPOS are 15-bit counters of millimetres that wrap modulo
//!   0x8000, THPOS is the heading in 4096 units per turn. Each new reading is unwrapped
//!   against the previous one: the 15-bit difference is read as a signed number in
//!   [-0x4000, 0x4000), so a step larger than half the counter's range is taken for a wrap.
//!   At 100 ms per SIP and at most 2200 mm/s the real step never exceeds 220 mm, far inside
//!   that window. The accumulated position is kept in whole millimetres (`i64`), so a long run
//!   adds no rounding drift.
//! - [`EncoderOdometry`] integrates the accumulated left/right wheel encoder counts of the
//!   ENCODER packet (§1.8) with the standard differential-drive model (midpoint rule; Siegwart,
//!   Nourbakhsh & Scaramuzza, *Introduction to Autonomous Mobile Robots*, 2nd ed., 2011,
//!   §5.2.4). Counts are 32-bit and are differenced with wrapping arithmetic.
//!
//! The first reading after power-on (or SETO) defines the robot's place in `odom`: XPOS and
//! YPOS are read as signed 15-bit values (0x7FFB is -5 mm), so a robot that backed up a
//! little from its reset point starts at a small negative coordinate, not 32 m away.
//!
//! Robots of the `p3dx` subclass (old AROS/P2OS firmware) count XPOS, YPOS and MOVE in units
//! of 0.485 mm, not millimetres (DistConvFactor, docs/protocols.md §1.9 and §5). [`ConversionFactors`]
//! is the one table of the factors per subclass, and [`SipUnitConverter`] turns a robot's
//! status readings into the ARCOS P3-DX-SH units the trackers here expect: each position delta
//! is unwrapped in robot units, the unwrapped total is multiplied by DistConvFactor and wrapped
//! again as a 15-bit millimetre counter, so nothing downstream needs to know the subclass.
//!
//! [`MapFromOdom`] is the rigid transform that places `odom` in `map`; it is fixed when the
//! mission starts, from the known start pose in the map.

use core::f32::consts::TAU;

use crate::geometry::{Point2, Pose2, normalize_angle};
use crate::math;
use crate::units::{ARCOS_ANGLE_UNITS_PER_TURN, arcos_angle_to_rad, rad_to_arcos_angle};

/// Modulus of the XPOS/YPOS counters.
pub const ARCOS_POSITION_MODULUS: i32 = 0x8000;
/// ARCOS heading units per turn as an integer.
const ANGLE_UNITS_PER_TURN_I: i32 = 4096;

/// Signed difference `new - old` of two 15-bit counters, in [-0x4000, 0x4000).
#[inline]
pub fn unwrap_delta_15bit(old: u16, new: u16) -> i32 {
    let d = (i32::from(new) - i32::from(old)) & (ARCOS_POSITION_MODULUS - 1);
    if d >= ARCOS_POSITION_MODULUS / 2 {
        d - ARCOS_POSITION_MODULUS
    } else {
        d
    }
}

/// A 15-bit counter value read as a signed number in [-0x4000, 0x4000).
#[inline]
fn signed_15bit(raw: u16) -> i32 {
    unwrap_delta_15bit(0, raw)
}

/// Signed difference of two ARCOS headings [units], in [-2048, 2048).
#[inline]
fn heading_delta_units(old: i16, new: i16) -> i32 {
    let d = (i32::from(new) - i32::from(old)).rem_euclid(ANGLE_UNITS_PER_TURN_I);
    if d >= ANGLE_UNITS_PER_TURN_I / 2 {
        d - ANGLE_UNITS_PER_TURN_I
    } else {
        d
    }
}

/// Robot subclasses (ARCOS SYNC2/CONFIG subtype) with known conversion factors, compared
/// without regard to case.
pub const KNOWN_SUBCLASSES: [&str; 4] = ["p3dx", "p3dx-sh", "p3dx-sh-lms1xx", "p3dx-sh-lms500"];

/// How a robot's wire units convert to millimetres and radians (the DistConvFactor,
/// VelConvFactor and AngleConvFactor of its subclass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConversionFactors {
    /// Millimetres per position unit (XPOS, YPOS, MOVE): DistConvFactor.
    pub mm_per_distance_unit: f32,
    /// Millimetres per second per velocity unit (VEL, wheel velocities): VelConvFactor.
    pub mm_s_per_velocity_unit: f32,
    /// Radians per heading unit (THPOS, CONTROL): AngleConvFactor.
    pub rad_per_angle_unit: f32,
}

/// Factors of ARCOS on a P3-DX-SH: millimetres, mm/s and 2π/4096 rad (the parameter files'
/// AngleConvFactor 0.001534 is this value rounded).
const ARCOS_SH: ConversionFactors = ConversionFactors {
    mm_per_distance_unit: 1.0,
    mm_s_per_velocity_unit: 1.0,
    rad_per_angle_unit: TAU / ARCOS_ANGLE_UNITS_PER_TURN,
};

/// Factors per subclass, from the vendor's public parameter files (docs/protocols.md §1.9, §5).
const SUBCLASS_FACTORS: [(&str, ConversionFactors); 4] = [
    (
        "p3dx",
        ConversionFactors {
            mm_per_distance_unit: 0.485,
            ..ARCOS_SH
        },
    ),
    ("p3dx-sh", ARCOS_SH),
    ("p3dx-sh-lms1xx", ARCOS_SH),
    ("p3dx-sh-lms500", ARCOS_SH),
];

impl ConversionFactors {
    /// The units the rest of the crate speaks (ARCOS on a P3-DX-SH): converting with them
    /// changes nothing.
    pub const ARCOS_SH: Self = ARCOS_SH;

    /// The factors of `subclass` (case-insensitive), `None` for a subclass not in
    /// [`KNOWN_SUBCLASSES`].
    pub fn for_subclass(subclass: &str) -> Option<Self> {
        SUBCLASS_FACTORS
            .iter()
            .find(|(name, _)| name.eq_ignore_ascii_case(subclass))
            .map(|&(_, f)| f)
    }

    /// The MOVE argument, in robot units, for `distance_mm`; `None` when it does not fit the
    /// command's signed 16-bit argument.
    pub fn move_argument(&self, distance_mm: i32) -> Option<i16> {
        to_i16(distance_mm as f32 / self.mm_per_distance_unit)
    }

    /// The VEL argument, in robot units, for `speed_mm_s`; `None` when it does not fit.
    pub fn vel_argument(&self, speed_mm_s: i16) -> Option<i16> {
        to_i16(f32::from(speed_mm_s) / self.mm_s_per_velocity_unit)
    }

    /// A robot velocity reading \[velocity units\] in mm/s, saturated to `i16`.
    pub fn velocity_mm_s(&self, raw: i16) -> i16 {
        let v = math::round(f32::from(raw) * self.mm_s_per_velocity_unit);
        v.clamp(f32::from(i16::MIN), f32::from(i16::MAX)) as i16
    }

    /// A robot heading \[angle units\] in ARCOS units of 2π/4096, in [-2048, 2048).
    pub fn heading_units(&self, raw: i16) -> i16 {
        let units = math::round(rad_to_arcos_angle(f32::from(raw) * self.rad_per_angle_unit));
        let units = (units as i32).rem_euclid(ANGLE_UNITS_PER_TURN_I);
        let units = if units >= ANGLE_UNITS_PER_TURN_I / 2 {
            units - ANGLE_UNITS_PER_TURN_I
        } else {
            units
        };
        units as i16
    }
}

fn to_i16(v: f32) -> Option<i16> {
    let v = math::round(v);
    (v.is_finite() && v >= f32::from(i16::MIN) && v <= f32::from(i16::MAX)).then_some(v as i16)
}

/// Turns XPOS/YPOS counters in a robot's position units into 15-bit millimetre counters.
///
/// Each reading's delta is unwrapped in robot units (as [`unwrap_delta_15bit`]) and summed;
/// the output is the rounded total × DistConvFactor modulo 0x8000, so rounding never
/// accumulates. With DistConvFactor 1.0 the output is the input.
#[derive(Clone, Debug)]
pub struct SipUnitConverter {
    factors: ConversionFactors,
    last_raw: Option<(u16, u16)>,
    x_units: i64,
    y_units: i64,
}

impl SipUnitConverter {
    /// A converter for a robot with `factors` that has seen no reading yet.
    pub const fn new(factors: ConversionFactors) -> Self {
        Self {
            factors,
            last_raw: None,
            x_units: 0,
            y_units: 0,
        }
    }

    /// The factors applied.
    pub fn factors(&self) -> ConversionFactors {
        self.factors
    }

    /// XPOS and YPOS in robot units to XPOS and YPOS in millimetres (15-bit counters).
    pub fn position_mm(&mut self, x_raw: u16, y_raw: u16) -> (u16, u16) {
        match self.last_raw {
            None => {
                self.x_units = i64::from(signed_15bit(x_raw));
                self.y_units = i64::from(signed_15bit(y_raw));
            }
            Some((x0, y0)) => {
                self.x_units += i64::from(unwrap_delta_15bit(x0, x_raw));
                self.y_units += i64::from(unwrap_delta_15bit(y0, y_raw));
            }
        }
        self.last_raw = Some((x_raw, y_raw));
        let f = f64::from(self.factors.mm_per_distance_unit);
        let mm = |units: i64| {
            (libm::round(units as f64 * f) as i64).rem_euclid(i64::from(ARCOS_POSITION_MODULUS))
                as u16
        };
        (mm(self.x_units), mm(self.y_units))
    }
}

/// The inverse of a rigid transform: `inverse(p) ⊕ p` is the identity.
pub fn pose_inverse(p: Pose2) -> Pose2 {
    let (s, c) = (math::sin(p.theta), math::cos(p.theta));
    Pose2::new(-(c * p.x + s * p.y), s * p.x - c * p.y, -p.theta)
}

/// Tracks the pose the P3-DX reports in its SIPs, in the `odom` frame.
#[derive(Clone, Debug, Default)]
pub struct ArcosOdometry {
    last_raw: Option<(u16, u16, i16)>,
    x_mm: i64,
    y_mm: i64,
    /// Accumulated signed rotation [ARCOS units] since the first reading.
    rotation_units: i64,
    heading_units: i16,
    distance_mm: u64,
}

impl ArcosOdometry {
    /// A tracker that has seen no reading yet.
    pub const fn new() -> Self {
        Self {
            last_raw: None,
            x_mm: 0,
            y_mm: 0,
            rotation_units: 0,
            heading_units: 0,
            distance_mm: 0,
        }
    }

    /// Feeds one SIP's XPOS, YPOS (15-bit mm counters) and THPOS (4096 units per turn) and
    /// returns the new `odom` pose \[m, rad\].
    pub fn update(&mut self, x_raw: u16, y_raw: u16, th_raw: i16) -> Pose2 {
        match self.last_raw {
            None => {
                self.x_mm = i64::from(signed_15bit(x_raw));
                self.y_mm = i64::from(signed_15bit(y_raw));
            }
            Some((x0, y0, th0)) => {
                let dx = unwrap_delta_15bit(x0, x_raw);
                let dy = unwrap_delta_15bit(y0, y_raw);
                self.x_mm += i64::from(dx);
                self.y_mm += i64::from(dy);
                self.rotation_units += i64::from(heading_delta_units(th0, th_raw));
                let step = math::hypot(dx as f32, dy as f32);
                self.distance_mm += math::round(step) as u64;
            }
        }
        self.heading_units = th_raw;
        self.last_raw = Some((x_raw, y_raw, th_raw));
        self.pose_odom()
    }

    /// Whether at least one reading has been fed.
    pub fn has_reading(&self) -> bool {
        self.last_raw.is_some()
    }

    /// The current pose in `odom` \[m, rad\]; the origin until the first reading.
    pub fn pose_odom(&self) -> Pose2 {
        Pose2::new(
            self.x_mm as f32 * 0.001,
            self.y_mm as f32 * 0.001,
            arcos_angle_to_rad(f32::from(self.heading_units)),
        )
    }

    /// The unwrapped position in `odom` \[mm\].
    pub fn position_odom_mm(&self) -> (i64, i64) {
        (self.x_mm, self.y_mm)
    }

    /// Total signed rotation since the first reading \[rad\] (counter-clockwise positive; not
    /// wrapped, so two full turns give 4π).
    pub fn rotation_total_rad(&self) -> f32 {
        self.rotation_units as f32 * (TAU / ARCOS_ANGLE_UNITS_PER_TURN)
    }

    /// Path length driven since the first reading \[m\] (sum of per-SIP straight steps).
    pub fn distance_travelled_m(&self) -> f32 {
        self.distance_mm as f32 * 0.001
    }

    /// Forgets every reading (after a SETO odometry reset on the robot).
    pub fn reset(&mut self) {
        *self = Self::new();
    }
}

/// Errors configuring the encoder tracker.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum OdometryError {
    /// Encoder ticks per millimetre must be finite and positive.
    BadTicksPerMm {
        /// The value given.
        ticks_per_mm: f32,
    },
    /// Track width (distance between the wheel contact points) must be finite and positive.
    BadTrackWidth {
        /// The value given \[mm\].
        track_width_mm: f32,
    },
}

impl core::fmt::Display for OdometryError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            OdometryError::BadTicksPerMm { ticks_per_mm } => {
                write!(
                    f,
                    "encoder ticks per mm must be finite and > 0, got {ticks_per_mm}"
                )
            }
            OdometryError::BadTrackWidth { track_width_mm } => {
                write!(
                    f,
                    "track width must be finite and > 0 mm, got {track_width_mm}"
                )
            }
        }
    }
}

impl core::error::Error for OdometryError {}

/// Encoder geometry of a differential-drive robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderGeometry {
    /// Encoder ticks per millimetre of tyre travel.
    pub ticks_per_mm: f32,
    /// Distance between the left and right wheel contact points \[mm\].
    pub track_width_mm: f32,
}

impl EncoderGeometry {
    /// P3-DX values: 128 ticks/mm (TicksMM a P3-DX user pushed, docs/protocols.md §1.9) and the
    /// 316 mm wheel track of the P3-DX URDF. Calibrate on the real robot.
    pub const fn p3dx() -> Self {
        Self {
            ticks_per_mm: 128.0,
            track_width_mm: 316.0,
        }
    }
}

/// Tracks the pose from accumulated left/right encoder counts, in the `odom` frame.
#[derive(Clone, Debug)]
pub struct EncoderOdometry {
    geometry: EncoderGeometry,
    last_counts: Option<(i32, i32)>,
    x_m: f64,
    y_m: f64,
    theta_rad: f64,
}

impl EncoderOdometry {
    /// A tracker that starts at `start_odom` when it gets its first counts.
    pub fn new(geometry: EncoderGeometry, start_odom: Pose2) -> Result<Self, OdometryError> {
        let EncoderGeometry {
            ticks_per_mm,
            track_width_mm,
        } = geometry;
        if !(ticks_per_mm.is_finite() && ticks_per_mm > 0.0) {
            return Err(OdometryError::BadTicksPerMm { ticks_per_mm });
        }
        if !(track_width_mm.is_finite() && track_width_mm > 0.0) {
            return Err(OdometryError::BadTrackWidth { track_width_mm });
        }
        Ok(Self {
            geometry,
            last_counts: None,
            x_m: f64::from(start_odom.x),
            y_m: f64::from(start_odom.y),
            theta_rad: f64::from(start_odom.theta),
        })
    }

    /// Feeds the accumulated left and right encoder counts and returns the new `odom` pose.
    /// The first call only records the counts.
    pub fn update(&mut self, left_ticks: i32, right_ticks: i32) -> Pose2 {
        if let Some((l0, r0)) = self.last_counts {
            let per_mm = f64::from(self.geometry.ticks_per_mm);
            let dl_m = f64::from(left_ticks.wrapping_sub(l0)) / per_mm * 1e-3;
            let dr_m = f64::from(right_ticks.wrapping_sub(r0)) / per_mm * 1e-3;
            let ds = 0.5 * (dl_m + dr_m);
            let dth = (dr_m - dl_m) / (f64::from(self.geometry.track_width_mm) * 1e-3);
            let mid = self.theta_rad + 0.5 * dth;
            self.x_m += ds * libm::cos(mid);
            self.y_m += ds * libm::sin(mid);
            self.theta_rad = f64::from(normalize_angle((self.theta_rad + dth) as f32));
        }
        self.last_counts = Some((left_ticks, right_ticks));
        self.pose_odom()
    }

    /// The current pose in `odom` \[m, rad\].
    pub fn pose_odom(&self) -> Pose2 {
        Pose2::new(self.x_m as f32, self.y_m as f32, self.theta_rad as f32)
    }
}

/// The rigid transform that maps `odom` poses into the `map` frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MapFromOdom {
    /// The `odom` frame's origin and orientation, expressed in `map` \[m, rad\].
    pub odom_origin_in_map: Pose2,
}

impl MapFromOdom {
    /// The transform that puts the robot, seen at `odom_pose` by its odometry, at the known
    /// map pose `map_pose` (set once at the start of a mission).
    pub fn from_start(map_pose: Pose2, odom_pose: Pose2) -> Self {
        Self {
            odom_origin_in_map: map_pose.compose(pose_inverse(odom_pose)),
        }
    }

    /// An `odom` pose in `map`.
    pub fn map_pose(&self, odom_pose: Pose2) -> Pose2 {
        self.odom_origin_in_map.compose(odom_pose)
    }

    /// An `odom` point in `map`.
    pub fn map_point(&self, odom_point: Point2) -> Point2 {
        self.odom_origin_in_map.transform_point(odom_point)
    }

    /// A `map` pose in `odom`.
    pub fn odom_pose(&self, map_pose: Pose2) -> Pose2 {
        pose_inverse(self.odom_origin_in_map).compose(map_pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    /// What the robot reports for an unwrapped position \[mm\] and heading [units].
    fn raw(x_mm: i64, y_mm: i64, th_units: i64) -> (u16, u16, i16) {
        let th = (th_units + 2048).rem_euclid(4096) - 2048;
        (
            x_mm.rem_euclid(0x8000) as u16,
            y_mm.rem_euclid(0x8000) as u16,
            th as i16,
        )
    }

    #[test]
    fn deltas_unwrap_across_the_15_bit_boundary_both_ways() {
        assert_eq!(unwrap_delta_15bit(0x7FF0, 0x0010), 0x20);
        assert_eq!(unwrap_delta_15bit(0x0010, 0x7FF0), -0x20);
        assert_eq!(unwrap_delta_15bit(100, 300), 200);
        assert_eq!(unwrap_delta_15bit(300, 100), -200);
        // Bit 15 is not part of the counter.
        assert_eq!(unwrap_delta_15bit(0x8005, 0x0007), 2);
    }

    #[test]
    fn forward_and_backward_wraps_keep_the_position_continuous() {
        let mut odo = ArcosOdometry::new();
        odo.update(0x7FF0, 0x0005, 0);
        // Starting value read as signed: 0x7FF0 is -16 mm.
        assert_eq!(odo.position_odom_mm(), (-16, 5));
        odo.update(0x0010, 0x7FFB, 0);
        assert_eq!(odo.position_odom_mm(), (16, -5));
        odo.update(0x7FE0, 0x0001, 0);
        assert_eq!(odo.position_odom_mm(), (-32, 1));
    }

    #[test]
    fn heading_wraps_at_half_a_turn() {
        let mut odo = ArcosOdometry::new();
        let p = odo.update(0, 0, 2040);
        assert!((p.theta - arcos_angle_to_rad(2040.0)).abs() < 1e-5);
        // +16 units across the ±2048 boundary.
        let p = odo.update(0, 0, -2040);
        assert!((p.theta - arcos_angle_to_rad(-2040.0)).abs() < 1e-5);
        assert!((odo.rotation_total_rad() - arcos_angle_to_rad(16.0)).abs() < 1e-5);
        let p = odo.update(0, 0, 2040);
        assert!(p.theta > 3.1);
        assert!(odo.rotation_total_rad().abs() < 1e-6);
    }

    #[test]
    fn spinning_two_turns_accumulates_four_pi() {
        let mut odo = ArcosOdometry::new();
        for k in 0..=(2 * 4096 / 64) {
            let (x, y, th) = raw(0, 0, k * 64);
            odo.update(x, y, th);
        }
        assert!((odo.rotation_total_rad() - 2.0 * TAU).abs() < 1e-4);
    }

    #[test]
    fn long_straight_drive_crosses_several_wraps_without_error() {
        // 120 m diagonal at 37 mm per SIP: x crosses the 32.768 m boundary three times, y
        // goes negative and wraps the other way.
        let mut odo = ArcosOdometry::new();
        let (mut x, mut y) = (0i64, 0i64);
        for _ in 0..3300 {
            x += 37;
            y -= 11;
            let (xr, yr, th) = raw(x, y, -171);
            odo.update(xr, yr, th);
        }
        assert_eq!(odo.position_odom_mm(), (x, y));
        let p = odo.pose_odom();
        assert!((p.x - x as f32 * 0.001).abs() < 1e-3 && (p.y - y as f32 * 0.001).abs() < 1e-3);
        let expected_m = 3300.0 * math::hypot(37.0, 11.0) * 0.001;
        assert!((odo.distance_travelled_m() - expected_m).abs() < 3300.0 * 0.5e-3);
    }

    #[test]
    fn every_known_subclass_has_factors_and_others_have_none() {
        for name in KNOWN_SUBCLASSES {
            assert!(ConversionFactors::for_subclass(name).is_some(), "{name}");
        }
        let p3dx = ConversionFactors::for_subclass("P3DX").unwrap();
        assert_eq!(p3dx.mm_per_distance_unit, 0.485);
        assert_eq!(p3dx.mm_s_per_velocity_unit, 1.0);
        assert!((p3dx.rad_per_angle_unit - 0.001534).abs() < 1e-6);
        for name in ["p3dx-sh", "p3dx-sh-lms1xx", "p3dx-sh-lms500"] {
            assert_eq!(
                ConversionFactors::for_subclass(name),
                Some(ConversionFactors::ARCOS_SH)
            );
        }
        assert_eq!(ConversionFactors::ARCOS_SH.mm_per_distance_unit, 1.0);
        assert_eq!(ConversionFactors::for_subclass("p3at-sh"), None);
        assert_eq!(ConversionFactors::for_subclass(""), None);
    }

    #[test]
    fn move_and_vel_arguments_are_in_robot_units() {
        let p3dx = ConversionFactors::for_subclass("p3dx").unwrap();
        assert_eq!(p3dx.move_argument(485), Some(1000));
        assert_eq!(p3dx.move_argument(-970), Some(-2000));
        // 16 m is 32990 units: beyond the argument's range.
        assert_eq!(p3dx.move_argument(16_000), None);
        assert_eq!(p3dx.vel_argument(300), Some(300));
        let sh = ConversionFactors::ARCOS_SH;
        assert_eq!(sh.move_argument(16_000), Some(16_000));
        assert_eq!(sh.move_argument(40_000), None);
    }

    #[test]
    fn arcos_sh_readings_pass_unchanged() {
        let sh = ConversionFactors::ARCOS_SH;
        let mut conv = SipUnitConverter::new(sh);
        for (x, y) in [(0x7FF0, 5), (0x0010, 0x7FFB), (1234, 0x4000), (0x3FFF, 0)] {
            assert_eq!(conv.position_mm(x, y), (x, y));
        }
        for th in [-2048, -1024, -1, 0, 1, 1024, 2047] {
            assert_eq!(sh.heading_units(th), th);
        }
        assert_eq!(sh.velocity_mm_s(-321), -321);
    }

    #[test]
    fn p3dx_positions_become_millimetres_before_the_odometry() {
        // A 3 m by 20 m drive reported in 0.485 mm units: the robot's counters wrap every
        // 15.9 m, the millimetre counters every 32.8 m; the odometry sees millimetres.
        let p3dx = ConversionFactors::for_subclass("p3dx").unwrap();
        let mut conv = SipUnitConverter::new(p3dx);
        let mut odo = ArcosOdometry::new();
        let (mut x_mm, mut y_mm) = (0.0f64, 0.0f64);
        for _ in 0..1000 {
            x_mm += 3.0;
            y_mm -= 20.0;
            let units = |mm: f64| (libm::round(mm / 0.485) as i64).rem_euclid(0x8000) as u16;
            let (x, y) = conv.position_mm(units(x_mm), units(y_mm));
            odo.update(x, y, 0);
        }
        let (x, y) = odo.position_odom_mm();
        assert!((x - 3000).abs() <= 1 && (y + 20_000).abs() <= 1, "{x} {y}");
        let expected_m = 1000.0 * math::hypot(3.0, 20.0) * 0.001;
        assert!(
            (odo.distance_travelled_m() - expected_m).abs() < 0.5,
            "{}",
            odo.distance_travelled_m()
        );
        // Without the factor the same counters would read as 6.2 m by 41 m.
        let mut raw_odo = ArcosOdometry::new();
        let mut conv = SipUnitConverter::new(ConversionFactors::ARCOS_SH);
        let units = |mm: f64| (libm::round(mm / 0.485) as i64).rem_euclid(0x8000) as u16;
        let (x, y) = conv.position_mm(units(0.0), units(0.0));
        raw_odo.update(x, y, 0);
        let (x, y) = conv.position_mm(units(100.0), units(0.0));
        raw_odo.update(x, y, 0);
        assert_eq!(raw_odo.position_odom_mm().0, 206);
    }

    #[test]
    fn a_first_p3dx_reading_just_below_zero_stays_near_the_origin() {
        let mut conv = SipUnitConverter::new(ConversionFactors::for_subclass("p3dx").unwrap());
        // 0x7FFC is -4 units = -1.94 mm: -2 mm as a 15-bit counter.
        assert_eq!(conv.position_mm(0x7FFC, 200), (0x7FFE, 97));
    }

    #[test]
    fn encoders_integrate_straight_lines_and_spins() {
        let g = EncoderGeometry::p3dx();
        let mut odo = EncoderOdometry::new(g, Pose2::default()).unwrap();
        odo.update(0, 0);
        // 1 m straight ahead in 100 steps.
        for k in 1..=100 {
            let t = (k as f32 * 10.0 * g.ticks_per_mm) as i32;
            odo.update(t, t);
        }
        let p = odo.pose_odom();
        assert!((p.x - 1.0).abs() < 1e-4 && p.y.abs() < 1e-4 && p.theta.abs() < 1e-5);
        // Quarter turn in place, counter-clockwise: right wheel forward.
        let arc_mm = PI / 2.0 * g.track_width_mm / 2.0;
        let base = (1000.0 * g.ticks_per_mm) as i32;
        let d = (arc_mm * g.ticks_per_mm) as i32;
        let p = odo.update(base - d, base + d);
        assert!((p.theta - PI / 2.0).abs() < 1e-3, "{}", p.theta);
        assert!((p.x - 1.0).abs() < 1e-4);
    }

    #[test]
    fn encoder_counts_wrap_at_32_bits() {
        let g = EncoderGeometry::p3dx();
        let mut odo = EncoderOdometry::new(g, Pose2::default()).unwrap();
        odo.update(i32::MAX - 63, i32::MAX - 63);
        // +128 ticks = 1 mm on each wheel, across the i32 wrap.
        let p = odo.update(i32::MIN + 64, i32::MIN + 64);
        assert!((p.x - 0.001).abs() < 1e-6, "{}", p.x);
    }

    #[test]
    fn bad_encoder_geometry_is_an_error() {
        let g = EncoderGeometry {
            ticks_per_mm: 0.0,
            track_width_mm: 316.0,
        };
        assert!(matches!(
            EncoderOdometry::new(g, Pose2::default()),
            Err(OdometryError::BadTicksPerMm { .. })
        ));
        let g = EncoderGeometry {
            ticks_per_mm: 128.0,
            track_width_mm: f32::NAN,
        };
        assert!(matches!(
            EncoderOdometry::new(g, Pose2::default()),
            Err(OdometryError::BadTrackWidth { .. })
        ));
    }

    #[test]
    fn map_from_odom_places_the_start_pose_and_round_trips() {
        let odom_start = Pose2::new(0.3, -0.2, 0.4);
        let map_start = Pose2::new(5.0, 2.0, PI / 2.0);
        let t = MapFromOdom::from_start(map_start, odom_start);
        let m = t.map_pose(odom_start);
        assert!((m.x - 5.0).abs() < 1e-5 && (m.y - 2.0).abs() < 1e-5);
        assert!((m.theta - PI / 2.0).abs() < 1e-5);
        // 1 m forward in odom is 1 m forward in map too.
        let ahead = odom_start.compose(Pose2::new(1.0, 0.0, 0.0));
        let m = t.map_pose(ahead);
        assert!(
            (m.x - 5.0).abs() < 1e-4 && (m.y - 3.0).abs() < 1e-4,
            "{m:?}"
        );
        let back = t.odom_pose(m);
        assert!((back.x - ahead.x).abs() < 1e-4 && (back.y - ahead.y).abs() < 1e-4);
    }
}
