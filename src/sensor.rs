//! Laser scans and the LIDAR inverse sensor model.
//!
//! A scan is a fixed-capacity list of beams, each an angle in the laser frame (x forward, y
//! left, counter-clockwise positive) and a range, or no return. [`LaserConfig`] describes the
//! beam layout, the usable range, the blind zone, the range noise and the mount offset on the
//! robot; the defaults are the thesis's simulated laser (181 beams over 180° at 1°, 4 m usable
//! range, 0.30 m blind zone, 5 % Gaussian range noise).

use core::f32::consts::PI;

use crate::geometry::Pose2;
use crate::units::deg_to_rad;

/// Beams a scan can hold: an LMS1xx at 0.25° over 270° (1081 beams).
pub const MAX_BEAMS: usize = 1081;

/// One laser beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Direction in the laser frame [rad], counter-clockwise from the laser's forward axis.
    pub angle_rad: f32,
    /// Measured range [m]; `None` when nothing returned within the laser's range.
    pub range_m: Option<f32>,
}

/// Errors building a scan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ScanError {
    /// More beams than [`MAX_BEAMS`].
    TooManyBeams {
        /// The capacity.
        capacity: usize,
    },
}

impl core::fmt::Display for ScanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ScanError::TooManyBeams { capacity } => {
                write!(f, "a scan holds at most {capacity} beams")
            }
        }
    }
}

impl core::error::Error for ScanError {}

/// A laser scan: beams in increasing angle order, as the laser delivered them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scan {
    beams: heapless::Vec<Beam, MAX_BEAMS>,
}

impl Scan {
    /// An empty scan.
    pub const fn new() -> Self {
        Self {
            beams: heapless::Vec::new(),
        }
    }

    /// Appends a beam; a full scan hands back an error and keeps what it had.
    pub fn push(&mut self, beam: Beam) -> Result<(), ScanError> {
        self.beams.push(beam).map_err(|_| ScanError::TooManyBeams {
            capacity: MAX_BEAMS,
        })
    }

    /// Removes every beam.
    pub fn clear(&mut self) {
        self.beams.clear();
    }

    /// The beams.
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }

    /// Mutable access to the beams (for noise injection and tests).
    pub fn beams_mut(&mut self) -> &mut [Beam] {
        &mut self.beams
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// Whether the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }
}

/// Beam layout, range limits, noise and mounting of a laser rangefinder.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
pub struct LaserConfig {
    /// Number of beams per scan.
    pub beam_count: u16,
    /// Angle of the first beam in the laser frame [rad].
    pub first_angle_rad: f32,
    /// Angle between consecutive beams [rad].
    pub step_rad: f32,
    /// Usable range [m]: returns beyond it are treated as no return.
    pub max_range_m: f32,
    /// Blind zone [m]: readings below it are ignored.
    pub min_range_m: f32,
    /// Standard deviation of the range noise as a fraction of the range (0.05 = 5 %).
    pub noise_fraction: f32,
    /// Laser pose on the robot (base frame: x forward, y left) [m, rad].
    pub mount: Pose2,
    /// Scans per second.
    pub rate_hz: f32,
}

impl LaserConfig {
    /// The thesis's simulated laser: 181 beams over 180° at 1°, 4 m, blind below 0.30 m, 5 %.
    pub fn thesis() -> Self {
        Self {
            beam_count: 181,
            first_angle_rad: -PI / 2.0,
            step_rad: deg_to_rad(1.0),
            max_range_m: 4.0,
            min_range_m: 0.30,
            noise_fraction: 0.05,
            mount: Pose2::default(),
            rate_hz: 10.0,
        }
    }

    /// A SICK LMS1xx: 541 beams over 270° at 0.5°, mounted 55 mm ahead of the robot's centre
    /// (AriaCoda p3dx-sh-lms1xx.p), usable range limited to the thesis's 4 m.
    pub fn lms1xx() -> Self {
        Self {
            beam_count: 541,
            first_angle_rad: deg_to_rad(-135.0),
            step_rad: deg_to_rad(0.5),
            max_range_m: 4.0,
            min_range_m: 0.30,
            noise_fraction: 0.05,
            mount: Pose2::new(0.055, 0.0, 0.0),
            rate_hz: 25.0,
        }
    }

    /// Angle of beam `i` in the laser frame [rad].
    #[inline]
    pub fn beam_angle(&self, i: usize) -> f32 {
        self.first_angle_rad + i as f32 * self.step_rad
    }

    /// Angle of the last beam [rad].
    pub fn last_angle_rad(&self) -> f32 {
        self.beam_angle(self.beam_count.saturating_sub(1) as usize)
    }
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self::thesis()
    }
}
