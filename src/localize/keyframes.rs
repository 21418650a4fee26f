//! Keyframes: the scans a pose graph keeps, one each time the corrected pose has moved or
//! turned enough since the last (slam_toolbox's `minimum_travel_distance` and
//! `minimum_travel_heading`: Macenski & Jambrecic, *SLAM Toolbox: SLAM for the dynamic world*,
//! JOSS 6(61), 2021), so that the map can be drawn again from them once their poses are
//! corrected (Konolige et al., *Efficient sparse pose adjustment for 2D mapping*, IROS 2010,
//! keep the scans of their graph's nodes for the same purpose).
//!
//! A keyframe holds its ranges as whole millimetres (`u16`, 0 for no return) in the beam order
//! of the laser; the beam geometry is the laser's ([`LaserConfig::beam_angle`]), shared by all.
//! The store has a fixed capacity `K`; a full store is an error, never a panic. No allocation.

use crate::geometry::Pose2;
use crate::sensor::{Beam, LaserConfig, Scan};

/// Beams a keyframe keeps at most (an LMS1xx scan: 541).
pub const KEYFRAME_BEAMS: usize = 541;

/// Why a scan was not kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyframeError {
    /// The store holds `capacity` keyframes already.
    Full {
        /// Keyframes it holds at most.
        capacity: usize,
    },
    /// The scan's beams are not the laser's (count or angles), or more than
    /// [`KEYFRAME_BEAMS`].
    BeamLayout {
        /// Beams in the scan.
        beams: usize,
    },
}

impl core::fmt::Display for KeyframeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Full { capacity } => write!(f, "keyframes: all {capacity} in use"),
            Self::BeamLayout { beams } => write!(
                f,
                "keyframes: a scan of {beams} beams does not follow the laser's layout (at most {KEYFRAME_BEAMS} beams)"
            ),
        }
    }
}

impl core::error::Error for KeyframeError {}

/// One kept scan.
#[derive(Clone, Copy, bytemuck::Zeroable)]
pub struct Keyframe {
    /// Corrected path length driven when it was taken \[m\].
    pub path_m: f32,
    beams: u16,
    ranges_mm: [u16; KEYFRAME_BEAMS],
}

impl core::fmt::Debug for Keyframe {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Keyframe")
            .field("path_m", &self.path_m)
            .field("beams", &self.beams)
            .finish_non_exhaustive()
    }
}

impl Keyframe {
    /// Writes the scan back into `out` (beam angles from `laser`).
    pub fn scan_into(&self, laser: &LaserConfig, out: &mut Scan) {
        out.clear();
        for (i, &mm) in self.ranges_mm[..usize::from(self.beams)].iter().enumerate() {
            let range_m = (mm > 0).then(|| f32::from(mm) * 1e-3);
            // At most KEYFRAME_BEAMS < MAX_BEAMS beams.
            let _ = out.push(Beam {
                angle_rad: laser.beam_angle(i),
                range_m,
            });
        }
    }
}

/// At most `K` keyframes, in the order they were taken.
#[derive(bytemuck::Zeroable)]
pub struct KeyframeStore<const K: usize> {
    frames: [Keyframe; K],
    len: usize,
}

impl<const K: usize> core::fmt::Debug for KeyframeStore<K> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("KeyframeStore")
            .field("len", &self.len)
            .field("capacity", &K)
            .finish()
    }
}

impl<const K: usize> KeyframeStore<K> {
    /// Forgets every keyframe.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Keyframes held.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether none is held.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Keyframe `i`.
    pub fn get(&self, i: usize) -> Option<&Keyframe> {
        self.frames[..self.len].get(i)
    }

    /// Keeps `scan` (taken by `laser`) after `path_m` metres of corrected path; returns its
    /// index. Ranges beyond 65.5 m or not finite are kept as no return.
    pub fn push(
        &mut self,
        scan: &Scan,
        laser: &LaserConfig,
        path_m: f32,
    ) -> Result<usize, KeyframeError> {
        let beams = scan.beams();
        let layout_ok = beams.len() <= KEYFRAME_BEAMS
            && beams
                .iter()
                .enumerate()
                .all(|(i, b)| (b.angle_rad - laser.beam_angle(i)).abs() < 1e-4);
        if !layout_ok {
            return Err(KeyframeError::BeamLayout { beams: beams.len() });
        }
        if self.len >= K {
            return Err(KeyframeError::Full { capacity: K });
        }
        let frame = &mut self.frames[self.len];
        frame.path_m = path_m;
        frame.beams = beams.len() as u16;
        for (slot, b) in frame.ranges_mm.iter_mut().zip(beams) {
            *slot = match b.range_m {
                Some(r) if r.is_finite() && r > 0.0 && r < 65.5 => {
                    ((r * 1000.0 + 0.5) as u16).max(1)
                }
                _ => 0,
            };
        }
        self.len += 1;
        Ok(self.len - 1)
    }
}

/// Whether the corrected pose has moved `travel_m` or turned `turn_rad` since `last`.
pub fn is_keyframe(last: Pose2, now: Pose2, travel_m: f32, turn_rad: f32) -> bool {
    last.position().distance(now.position()) >= travel_m
        || crate::math::abs(crate::geometry::normalize_angle(now.theta - last.theta)) >= turn_rad
}
