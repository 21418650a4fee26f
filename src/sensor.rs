//! Laser scans and the LIDAR inverse sensor model.
//!
//! A scan is a fixed-capacity list of beams, each an angle in the laser frame (x forward, y
//! left, counter-clockwise positive) and a range, or no return. [`LaserConfig`] describes the
//! beam layout, the usable range, the blind zone, the range noise and the mount offset on the
//! robot; the defaults are the thesis's simulated laser (181 beams over 180° at 1°, 4 m usable
//! range, 0.30 m blind zone, 5 % Gaussian range noise).
//!
//! The inverse sensor model ([`integrate_scan`]) turns a scan taken at a known robot pose into
//! log-odds evidence on the occupancy grid (Thrun, Burgard & Fox, *Probabilistic Robotics*,
//! 2005, §9.2): every beam is traced with the exact grid traversal of [`crate::raycast`]; cells
//! before the return gain Free evidence, the return cell gains Occupied evidence, and a beam
//! with no return within the usable range gives Free evidence up to that range. The return
//! cell is the one holding the point a little past the measured range ([`hit_depth_m`]: the
//! range noise's two standard deviations, at most a quarter cell), so that a wall's face on a
//! cell edge, or a return just short of it, marks the wall and not the free cell in front. As in the
//! thesis (Bendahmane 2023), each piece of evidence is weighted by how close the beam passes to
//! the cell centre, `w = exp(-d² / 2σ²)` with `d` the perpendicular distance \[m\], and the
//! evidence of all beams crossing a cell accumulates. [`integrate_scan_banded`] widens the
//! Occupied evidence past the return by a band for a pose known only to a few centimetres
//! (the scan-matched missions, [`crate::localize::LocalizeConfig::wall_band_floor_m`]).

use core::f32::consts::PI;
use core::ops::ControlFlow;

use crate::geometry::{Point2, Pose2};
use crate::grid::{Cell, CellClass, CellObserver, OccupancyGrid};
use crate::math;
use crate::raycast;
use crate::units::deg_to_rad;

pub mod telegram;

/// Beams a scan can hold: an LMS1xx at 0.25° over 270° (1081 beams).
pub const MAX_BEAMS: usize = 1081;

/// One laser beam.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Direction in the laser frame \[rad\], counter-clockwise from the laser's forward axis.
    pub angle_rad: f32,
    /// Measured range \[m\]; `None` when nothing returned within the laser's range.
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
#[derive(Debug, Default, PartialEq)]
pub struct Scan {
    beams: heapless::Vec<Beam, MAX_BEAMS>,
}

impl Clone for Scan {
    fn clone(&self) -> Self {
        Self {
            beams: self.beams.clone(),
        }
    }

    /// Copies only the beams `source` holds, not the whole capacity (a mission keeps its last
    /// scan this way at every scan).
    fn clone_from(&mut self, source: &Self) {
        self.beams.clear();
        // Both hold at most MAX_BEAMS beams.
        let _ = self.beams.extend_from_slice(&source.beams);
    }
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
    /// Angle of the first beam in the laser frame \[rad\].
    pub first_angle_rad: f32,
    /// Angle between consecutive beams \[rad\].
    pub step_rad: f32,
    /// Usable range \[m\]: returns beyond it are treated as no return.
    pub max_range_m: f32,
    /// Blind zone \[m\]: readings below it are ignored.
    pub min_range_m: f32,
    /// Standard deviation of the range noise as a fraction of the range (0.05 = 5 %).
    pub noise_fraction: f32,
    /// Laser pose on the robot (base frame: x forward, y left) \[m, rad\].
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

    /// Angle of beam `i` in the laser frame \[rad\].
    #[inline]
    pub fn beam_angle(&self, i: usize) -> f32 {
        self.first_angle_rad + i as f32 * self.step_rad
    }

    /// Angle of the last beam \[rad\].
    pub fn last_angle_rad(&self) -> f32 {
        self.beam_angle(self.beam_count.saturating_sub(1) as usize)
    }
}

impl Default for LaserConfig {
    fn default() -> Self {
        Self::thesis()
    }
}

/// Log-odds increments and distance weighting of the inverse sensor model.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
pub struct SensorModel {
    /// Log-odds added to a cell a beam passes through before its return (negative).
    pub free_log_odds: f32,
    /// Log-odds added to the cell holding a beam's return (positive).
    pub occupied_log_odds: f32,
    /// Standard deviation \[m\] of the Gaussian weighting evidence by the perpendicular distance
    /// between the beam and the cell centre.
    pub sigma_m: f32,
    /// Hits before misses within a scan: a cell holding a return of this scan gets no Free
    /// evidence from the scan's other beams (Hess et al. 2016, Cartographer's probability
    /// grid: "hits are inserted first, misses skip cells already updated by a hit"). Off, each
    /// beam's Free and Occupied evidence is added in beam order (the thesis's model).
    #[serde(default)]
    pub hits_before_misses: bool,
    /// A miss through a cell the map holds Occupied with confidence (log-odds at least
    /// [`CONFIDENT_OCCUPIED_LOG_ODDS`]) counts only when the beam passes within this distance
    /// of the cell's centre, in cells; `None` (the thesis's model, the default): every miss
    /// counts.
    ///
    /// Why: a wall's face often lies on a cell boundary (always, in the simulator's worlds),
    /// and a beam that passes along the face, just clear of it, crosses the face's cells
    /// whenever the pose estimate is a centimetre off towards the wall. The map takes 50 scans
    /// a second, nearly all from the same place, so such a beam's misses pile up and wear the
    /// face away in a fraction of a second: the lab's pillar lost its north face to the scans
    /// of a robot driving down its east side with its estimate 1.3 cm south of the truth, and
    /// the inside of the pillar became a frontier the mission drove 5 m back to look into
    /// (docs/experiments.md, "Issue 26: the pillar's worn face"). A beam through the middle
    /// of a cell held Occupied is still evidence the cell is free (a door's noise hit, a person
    /// who walked away), and a cell with one or two hits is cleared by any miss: applied to
    /// every Occupied cell, the rule kept noise hits in doors and shut passages on the
    /// generated plans (same section). Only for a pose good to a centimetre or two: with dead
    /// reckoning's decimetres the misses must clear the walls drawn where the drift put them.
    /// The mission sets it when the scan matcher is on
    /// ([`crate::localize::LocalizeConfig::grazing_miss_offset_cells`]).
    #[serde(default)]
    pub occupied_miss_offset_cells: Option<f32>,
}

impl SensorModel {
    /// The thesis's model (Bendahmane 2023): free `ln(0.4/0.6) ≈ -0.41`, occupied
    /// `ln(0.7/0.3) ≈ 0.85` (the textbook values of Thrun et al.), σ = 0.05 m (half a 10 cm
    /// cell), each beam's evidence added in beam order, every miss counted.
    pub fn thesis() -> Self {
        Self {
            free_log_odds: -0.405,
            occupied_log_odds: 0.847,
            sigma_m: 0.05,
            hits_before_misses: false,
            occupied_miss_offset_cells: None,
        }
    }

    /// This model with misses through a cell held Occupied with confidence counted only within
    /// `cells` of its centre ([`SensorModel::occupied_miss_offset_cells`]).
    pub fn with_occupied_miss_offset(self, cells: f32) -> Self {
        Self {
            occupied_miss_offset_cells: Some(cells),
            ..self
        }
    }

    /// Hits before misses within a scan and misses much weaker than hits (Hess, Kohler, Rapp
    /// & Andor 2016, "Real-Time Loop Closure in 2D LIDAR SLAM", Cartographer's probability
    /// grid: hit probability 0.55, miss 0.49, a log-odds ratio of 5); here occupied +0.85 as
    /// in the thesis and free -0.1. **Not the default** (docs/experiments.md, "The house with
    /// a precise laser, branch `sensor`"): on the house with a precise laser (0.003) and the
    /// thesis's slip it halves the decisions and reaches 99 % in 7 of 10 seeds instead of 1
    /// of 6, but noise hits in a narrow door then outlive the misses and the 0.5 m and 0.6 m
    /// doors of `sim-host/tests/narrow_door.rs` stay shut in some seeds (hits first alone
    /// already shuts the 0.5 m door at 5 % noise).
    pub fn weak_misses() -> Self {
        Self {
            free_log_odds: -0.1,
            hits_before_misses: true,
            ..Self::thesis()
        }
    }
}

/// How far from an Occupied cell's centre a miss may pass and still count, in cells
/// ([`SensorModel::occupied_miss_offset_cells`], with the scan matcher on): a quarter of a
/// cell, half the Gaussian weight's σ at 10 cm cells.
pub const GRAZING_MISS_OFFSET_CELLS: f32 = 0.25;

/// Log-odds from which the map holds a cell Occupied with confidence: three hits net of the
/// thesis's model (3 x 0.847). Below it, [`SensorModel::occupied_miss_offset_cells`] does not
/// apply: a cell one or two noise hits made Occupied (in a door, on a drifted wall) is cleared
/// by every miss, as before.
pub const CONFIDENT_OCCUPIED_LOG_ODDS: f32 = 2.5;

impl Default for SensorModel {
    /// [`SensorModel::thesis`].
    fn default() -> Self {
        Self::thesis()
    }
}

/// Why a scan could not be integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum IntegrationError {
    /// The free increment must be negative and the occupied one positive, both finite.
    BadIncrements {
        /// The free increment seen.
        free_log_odds: f32,
        /// The occupied increment seen.
        occupied_log_odds: f32,
    },
    /// σ must be a positive finite number of metres.
    BadSigma(f32),
    /// The laser's ranges must satisfy `0 <= min_range_m < max_range_m`, both finite.
    BadRanges {
        /// Blind zone seen \[m\].
        min_range_m: f32,
        /// Usable range seen \[m\].
        max_range_m: f32,
    },
    /// The robot pose or the laser mount is not finite.
    BadPose,
    /// The wall band must be a finite number of metres, at least 0.
    BadBand(f32),
    /// The distance a miss may pass from an Occupied cell's centre must be a finite number of
    /// cells, at least 0.
    BadMissOffset(f32),
}

impl core::fmt::Display for IntegrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            IntegrationError::BadIncrements {
                free_log_odds,
                occupied_log_odds,
            } => write!(
                f,
                "sensor model increments must be free < 0 < occupied, got free {free_log_odds}, occupied {occupied_log_odds}"
            ),
            IntegrationError::BadSigma(s) => {
                write!(
                    f,
                    "sensor model sigma must be a positive number of metres, got {s}"
                )
            }
            IntegrationError::BadRanges {
                min_range_m,
                max_range_m,
            } => write!(
                f,
                "laser ranges must satisfy 0 <= blind zone < usable range, got {min_range_m} m and {max_range_m} m"
            ),
            IntegrationError::BadPose => write!(f, "robot pose or laser mount is not finite"),
            IntegrationError::BadBand(b) => write!(
                f,
                "the wall band past a return must be a finite number of metres >= 0, got {b}"
            ),
            IntegrationError::BadMissOffset(c) => write!(
                f,
                "sensor model occupied_miss_offset_cells must be a finite number of cells >= 0, got {c}"
            ),
        }
    }
}

impl core::error::Error for IntegrationError {}

impl SensorModel {
    /// Checks the increments and σ.
    pub fn validate(&self) -> Result<(), IntegrationError> {
        if !(self.free_log_odds < 0.0
            && self.occupied_log_odds > 0.0
            && self.free_log_odds.is_finite()
            && self.occupied_log_odds.is_finite())
        {
            return Err(IntegrationError::BadIncrements {
                free_log_odds: self.free_log_odds,
                occupied_log_odds: self.occupied_log_odds,
            });
        }
        if !(self.sigma_m > 0.0 && self.sigma_m.is_finite()) {
            return Err(IntegrationError::BadSigma(self.sigma_m));
        }
        if let Some(offset) = self.occupied_miss_offset_cells
            && !(offset >= 0.0 && offset.is_finite())
        {
            return Err(IntegrationError::BadMissOffset(offset));
        }
        Ok(())
    }
}

/// What integrating a scan did to the grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScanIntegration {
    /// Cells that went from Unknown to Free or Occupied: the exploration gain \[cells\].
    pub newly_known: usize,
    /// Cells whose class changed in any way \[cells\].
    pub changed: usize,
    /// Evidence updates applied (a cell crossed by several beams counts once per beam).
    pub updates: usize,
    /// Beams traced.
    pub beams_used: usize,
    /// Beams ignored: reading in the blind zone, or not a number.
    pub beams_ignored: usize,
}

/// Integrates a scan taken at `robot_pose_map` (map frame) into the grid with the inverse
/// sensor model. The laser pose is the robot pose composed with `laser.mount`. Per beam:
/// - a reading below `laser.min_range_m` (blind zone) or not a number is ignored;
/// - a return within `laser.max_range_m`: cells from the laser up to the return get Free
///   evidence and the cell holding the return, taken [`hit_depth_m`] past the measured range,
///   gets Occupied evidence (and only that, from this beam);
/// - a return beyond `laser.max_range_m`, or no return: Free evidence up to the usable range.
///
/// Each update is weighted by `exp(-d² / 2σ²)`, `d` the distance \[m\] from the cell centre to
/// the beam's line. Cells outside the grid are skipped. Every class change is reported to
/// `observer`. Allocation-free.
pub fn integrate_scan<const N: usize>(
    grid: &mut OccupancyGrid<N>,
    scan: &Scan,
    robot_pose_map: Pose2,
    laser: &LaserConfig,
    model: &SensorModel,
    observer: &mut impl CellObserver,
) -> Result<ScanIntegration, IntegrationError> {
    integrate_scan_banded(grid, scan, robot_pose_map, 0.0, laser, model, observer)
}

/// [`integrate_scan`] for a scan whose pose is uncertain along each beam by up to `band_m`
/// \[m\] (at most half a cell is used): every cell between the return's point (taken
/// [`hit_depth_m`] past the measured range) and `band_m` further along the beam gets the
/// return's Occupied evidence too, not only the cell holding the point. The cells before the
/// point get Free evidence as in [`integrate_scan`], so a wall is never drawn thicker on the
/// side the laser saw it from; it may be drawn a cell thicker behind its face.
///
/// Why: a scan drawn at a pose a few centimetres short of the truth along a beam puts the
/// return of a wall's face in the free cell in front of it, and the wall's own cell, behind
/// the return, is then never reached by any beam: it stays Unknown for ever
/// (docs/experiments.md, issue 18, branches `stall18` and `wall18`). The surface lies
/// anywhere within the pose's uncertainty of the point, so each cell of that interval may
/// hold it: the inverse sensor model's obstacle region `|r - z| < α/2` (Thrun, Burgard & Fox,
/// *Probabilistic Robotics*, 2005, §9.2, Table 9.2) widened by the uncertainty of where the
/// beam started, as Elfes (*Using occupancy grids for mobile robot perception and
/// navigation*, IEEE Computer 22(6), 1989) widens the occupied region of a sonar return by its
/// range uncertainty. Only the far side is widened: the near side is seen through.
///
/// Errors: as [`integrate_scan`], and [`IntegrationError::BadBand`] for a negative or
/// non-finite `band_m`.
pub fn integrate_scan_banded<const N: usize>(
    grid: &mut OccupancyGrid<N>,
    scan: &Scan,
    robot_pose_map: Pose2,
    band_m: f32,
    laser: &LaserConfig,
    model: &SensorModel,
    observer: &mut impl CellObserver,
) -> Result<ScanIntegration, IntegrationError> {
    model.validate()?;
    if !(band_m >= 0.0 && band_m.is_finite()) {
        return Err(IntegrationError::BadBand(band_m));
    }
    if !(laser.min_range_m >= 0.0
        && laser.max_range_m > laser.min_range_m
        && laser.max_range_m.is_finite())
    {
        return Err(IntegrationError::BadRanges {
            min_range_m: laser.min_range_m,
            max_range_m: laser.max_range_m,
        });
    }
    let pose = robot_pose_map.compose(laser.mount);
    if !(pose.x.is_finite() && pose.y.is_finite() && pose.theta.is_finite()) {
        return Err(IntegrationError::BadPose);
    }
    let origin = pose.position();
    let inv_two_sigma_sq = 1.0 / (2.0 * model.sigma_m * model.sigma_m);
    let bounds = grid.bounds();
    let mut out = ScanIntegration::default();
    let geom = *grid.geometry();
    let miss_offset_m = model
        .occupied_miss_offset_cells
        .map_or(f32::INFINITY, |cells| cells * geom.resolution_m);
    let hit_depth = |range_m: f32| hit_depth_m(range_m, laser.noise_fraction, geom.resolution_m);
    let band = WallBand {
        geom,
        band_m: band_m.min(0.5 * geom.resolution_m),
        origin,
        inv_two_sigma_sq,
        occupied_log_odds: model.occupied_log_odds,
    };

    // Hits before misses: the cells holding this scan's returns get their Occupied evidence
    // first, and are remembered (sorted) so that no beam of the scan clears them.
    let mut hit_cells: heapless::Vec<usize, MAX_BEAMS> = heapless::Vec::new();
    // Each beam's ray, worked out once for both passes (its sine and cosine are most of it).
    let mut rays: heapless::Vec<Option<BeamRay>, MAX_BEAMS> = heapless::Vec::new();
    if model.hits_before_misses {
        for beam in scan.beams() {
            let ray = BeamRay::new(beam, pose, laser, hit_depth);
            // A scan has at most MAX_BEAMS beams, so this never overflows.
            let _ = rays.push(ray);
            let Some(ray) = ray else {
                continue;
            };
            if !ray.hit {
                continue;
            }
            let cell = geom.cell_at_unchecked(ray.end);
            let Some(index) = geom.index(cell) else {
                continue;
            };
            if grid.log_odds_at(index) < bounds.max {
                ray.evidence(origin, inv_two_sigma_sq).add(
                    grid,
                    cell,
                    index,
                    model.occupied_log_odds,
                    observer,
                    &mut out,
                );
            }
            // The band's cells past it are not protected from the scan's other beams (a
            // beam reaching them sees through where this one stopped).
            band.occupy(&ray, index, grid, observer, &mut out);
            // A scan has at most MAX_BEAMS beams, so this never overflows.
            let _ = hit_cells.push(index);
        }
        hit_cells.sort_unstable();
    }

    for (k, beam) in scan.beams().iter().enumerate() {
        let ray = match rays.get(k) {
            Some(&ray) => ray,
            None => BeamRay::new(beam, pose, laser, hit_depth),
        };
        let Some(ray) = ray else {
            out.beams_ignored += 1;
            continue;
        };
        out.beams_used += 1;
        // The flat index of the cell holding the return (none when no return, or outside the
        // grid, where the walk never goes).
        let hit_index = geom
            .index(geom.cell_at_unchecked(ray.end))
            .filter(|_| ray.hit)
            .unwrap_or(usize::MAX);
        let evidence = ray.evidence(origin, inv_two_sigma_sq);
        let mut update = BeamUpdate {
            grid: &mut *grid,
            model,
            evidence,
            hit_index,
            hit_cells: &hit_cells,
            miss_offset_m,
            observer: &mut *observer,
            out: &mut out,
        };
        let walk = raycast::traverse(&geom, origin, ray.end, |cell, index| {
            // Most cells a beam crosses are saturated Free and a miss leaves them so: that test
            // alone stays in the walk's loop; the rest is out of line (`BeamUpdate::visit`).
            if index != hit_index && update.grid.log_odds_at(index) <= bounds.min {
                return ControlFlow::Continue(());
            }
            update.visit(cell, index);
            ControlFlow::Continue(())
        });
        out.updates += walk.visited;
        if ray.hit && !model.hits_before_misses {
            band.occupy(&ray, hit_index, grid, observer, &mut out);
        }
    }
    Ok(out)
}

/// One beam's walk through the grid in [`integrate_scan_banded`]: what a cell it crosses gets.
struct BeamUpdate<'a, const N: usize, O> {
    grid: &'a mut OccupancyGrid<N>,
    model: &'a SensorModel,
    evidence: BeamEvidence,
    /// The flat index of the cell holding the return (`usize::MAX` when none).
    hit_index: usize,
    /// The scan's returns (sorted), when hits come before misses.
    hit_cells: &'a [usize],
    /// How far from a confidently Occupied cell's centre a miss may pass and count \[m\].
    miss_offset_m: f32,
    observer: &'a mut O,
    out: &'a mut ScanIntegration,
}

impl<const N: usize, O: CellObserver> BeamUpdate<'_, N, O> {
    /// The evidence for `cell` (flat index `index`), a cell the walk's loop did not skip: the
    /// loop keeps only the test for a saturated Free cell a miss crosses (most of a beam's
    /// cells, and the weight is not needed there: the sum is clamped back to the bound), the
    /// rest is here, out of line.
    #[inline(never)]
    fn visit(&mut self, cell: Cell, index: usize) {
        let model = self.model;
        let occupied = index == self.hit_index;
        if model.hits_before_misses && occupied {
            // Its Occupied evidence is in already; no Free evidence from this scan.
            return;
        }
        // A return's cell saturated Occupied stays so whatever the weight, as a saturated
        // Free cell under a miss (skipped by the loop).
        let current = self.grid.log_odds_at(index);
        if occupied && current >= self.grid.bounds().max {
            return;
        }
        if model.hits_before_misses && self.hit_cells.binary_search(&index).is_ok() {
            // Another beam's return: no Free evidence from this scan.
            return;
        }
        if !occupied
            && current >= CONFIDENT_OCCUPIED_LOG_ODDS
            && self.evidence.offset_m(self.grid.geometry(), cell).abs() > self.miss_offset_m
        {
            // A miss grazing a cell held Occupied: as likely pose error along its face.
            return;
        }
        let delta = if occupied {
            model.occupied_log_odds
        } else {
            model.free_log_odds
        };
        self.evidence
            .add(self.grid, cell, index, delta, self.observer, self.out);
    }
}

/// One usable beam in the map frame: where its walk ends and whether that end is a return.
#[derive(Clone, Copy)]
struct BeamRay {
    dir_x: f32,
    dir_y: f32,
    /// The walk's end: the return moved [`hit_depth_m`] past the measured range, or the usable
    /// range when nothing returned.
    end: Point2,
    hit: bool,
}

impl BeamRay {
    /// `None` for a beam the model ignores: a reading in the blind zone, not a number, or an
    /// angle that is not finite. `hit_depth` gives the depth for a measured range.
    #[inline]
    fn new(
        beam: &Beam,
        laser_pose: Pose2,
        laser: &LaserConfig,
        hit_depth: impl Fn(f32) -> f32,
    ) -> Option<Self> {
        let (length_m, hit) = match beam.range_m {
            Some(r) if r.is_nan() || r < laser.min_range_m => return None,
            Some(r) if r <= laser.max_range_m => (r, true),
            _ => (laser.max_range_m, false),
        };
        if !beam.angle_rad.is_finite() {
            return None;
        }
        let angle = laser_pose.theta + beam.angle_rad;
        let (dir_y, dir_x) = math::sin_cos(angle);
        // A return is a point on a surface: the cell holding the surface is the one the beam
        // enters there. Taken literally, a return on a cell's edge (a wall's face) or short of
        // it by the range noise lands in the free cell in front of the wall; the hit is moved
        // a little past the measured range (see `hit_depth_m`).
        let length_m = if hit {
            length_m + hit_depth(length_m)
        } else {
            length_m
        };
        Some(Self {
            dir_x,
            dir_y,
            end: Point2::new(
                laser_pose.x + dir_x * length_m,
                laser_pose.y + dir_y * length_m,
            ),
            hit,
        })
    }

    fn evidence(&self, origin: Point2, inv_two_sigma_sq: f32) -> BeamEvidence {
        BeamEvidence {
            origin,
            dir_x: self.dir_x,
            dir_y: self.dir_y,
            inv_two_sigma_sq,
        }
    }
}

/// The wall band of one scan: how far past each return its Occupied evidence reaches, and what
/// weighs it (see [`integrate_scan_banded`]).
struct WallBand {
    geom: crate::grid::GridGeometry,
    band_m: f32,
    origin: Point2,
    inv_two_sigma_sq: f32,
    occupied_log_odds: f32,
}

impl WallBand {
    /// Occupied evidence to the cells from `ray`'s return point to `band_m` past it along the
    /// beam, but the cell holding the point (`hit_index`, which has its evidence). Nothing for
    /// a beam with no return or an empty band.
    fn occupy<const N: usize>(
        &self,
        ray: &BeamRay,
        hit_index: usize,
        grid: &mut OccupancyGrid<N>,
        observer: &mut impl CellObserver,
        out: &mut ScanIntegration,
    ) {
        if !ray.hit || self.band_m <= 0.0 {
            return;
        }
        let far = Point2::new(
            ray.end.x + ray.dir_x * self.band_m,
            ray.end.y + ray.dir_y * self.band_m,
        );
        let evidence = ray.evidence(self.origin, self.inv_two_sigma_sq);
        let max = grid.bounds().max;
        let walk = raycast::traverse(&self.geom, ray.end, far, |cell, index| {
            if index != hit_index && grid.log_odds_at(index) < max {
                evidence.add(grid, cell, index, self.occupied_log_odds, observer, out);
            }
            ControlFlow::Continue(())
        });
        out.updates += walk.visited;
    }
}

/// How far past a measured range \[m\] the Occupied evidence goes: into the surface the beam
/// hit, by twice the range's standard deviation (`noise_fraction · range_m`) plus a twentieth
/// of a cell, at most a quarter of a cell (`resolution_m`). The Occupied cell is the one
/// holding that point; every cell before it gets Free evidence.
///
/// Why: a wall's face lies between cells, and a return is as often short of the face as past
/// it. In the cell holding the return itself, a beam that ends on the face (moving west or
/// south, a face belongs to the free cell in front of it) or a little short of it marks the
/// free cell in front of the wall Occupied, half the time with any noise, and cells in front of
/// a door's jambs and in its frame shut a 0.5 m door that a 0.381 m robot fits through
/// (docs/experiments.md, issue 17). Thrun, Burgard & Fox, *Probabilistic Robotics* (2005),
/// §9.2, Table 9.2: the obstacle region of the inverse range sensor model lies at and beyond
/// the measured range, `|r - z| < α/2`; a quarter of a cell keeps a return in the middle of a
/// cell in that cell (it does not push the wall a cell back), and the depth never reaches
/// through a wall half a cell thick.
#[inline]
pub fn hit_depth_m(range_m: f32, noise_fraction: f32, resolution_m: f32) -> f32 {
    let noise = if noise_fraction.is_finite() {
        noise_fraction.max(0.0)
    } else {
        0.0
    };
    (0.05 * resolution_m + 2.0 * noise * range_m).min(0.25 * resolution_m)
}

/// One beam's line, for weighting its evidence by the distance to a cell's centre.
struct BeamEvidence {
    origin: Point2,
    dir_x: f32,
    dir_y: f32,
    inv_two_sigma_sq: f32,
}

impl BeamEvidence {
    /// The signed perpendicular distance from `cell`'s centre to the beam's line \[m\].
    #[inline]
    fn offset_m(&self, geom: &crate::grid::GridGeometry, cell: Cell) -> f32 {
        let centre = geom.cell_center(cell);
        (centre.x - self.origin.x) * self.dir_y - (centre.y - self.origin.y) * self.dir_x
    }

    /// Adds `delta` weighted by `exp(-d² / 2σ²)` to `cell` (flat index `index`), `d` the
    /// perpendicular distance from the cell centre to the beam's line, and books the class
    /// change. Kept out of line: most cells a beam crosses are already saturated and skip it.
    #[inline(never)]
    fn add<const N: usize>(
        &self,
        grid: &mut OccupancyGrid<N>,
        cell: Cell,
        index: usize,
        delta: f32,
        observer: &mut impl CellObserver,
        out: &mut ScanIntegration,
    ) {
        let d = self.offset_m(grid.geometry(), cell);
        let weight = math::exp(-d * d * self.inv_two_sigma_sq);
        let (old, new) = grid.add_evidence(index, delta * weight, observer);
        if old != new {
            out.changed += 1;
            if old == CellClass::Unknown {
                out.newly_known += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Cell, CellCounts, GridGeometry, LogOddsBounds};

    type Grid = OccupancyGrid<{ 60 * 60 }>;

    /// A 6 m x 6 m grid at 10 cm with the robot in the middle of a walled room (walls on the
    /// lines x = 1.05, x = 4.95, y = 1.05, y = 4.95: through columns and rows 10 and 49).
    fn room_scan(pose: Pose2, laser: &LaserConfig) -> Scan {
        let mut scan = Scan::new();
        for i in 0..laser.beam_count as usize {
            let a = laser.beam_angle(i);
            let world = pose.theta + a;
            let (c, s) = (math::cos(world), math::sin(world));
            let mut r = f32::INFINITY;
            for (t, ok) in [
                ((4.95 - pose.x) / c, c > 0.0),
                ((1.05 - pose.x) / c, c < 0.0),
                ((4.95 - pose.y) / s, s > 0.0),
                ((1.05 - pose.y) / s, s < 0.0),
            ] {
                if ok && t < r {
                    r = t;
                }
            }
            scan.push(Beam {
                angle_rad: a,
                range_m: (r <= laser.max_range_m).then_some(r),
            })
            .unwrap();
        }
        scan
    }

    fn grid() -> Grid {
        let g = GridGeometry::new(60, 60, 0.1, Point2::new(0.0, 0.0)).unwrap();
        Grid::new(g, LogOddsBounds::default()).unwrap()
    }

    #[test]
    fn clone_from_takes_the_sources_beams_only() {
        let beam = |i: usize| Beam {
            angle_rad: i as f32 * 0.01,
            range_m: (!i.is_multiple_of(3)).then_some(i as f32),
        };
        let mut long = Scan::new();
        let mut short = Scan::new();
        for i in 0..10 {
            long.push(beam(i)).unwrap();
        }
        for i in 0..4 {
            short.push(beam(100 + i)).unwrap();
        }
        let mut kept = long.clone();
        assert_eq!(kept, long);
        kept.clone_from(&short);
        assert_eq!(kept, short);
        kept.clone_from(&long);
        assert_eq!(kept, long);
    }

    #[test]
    fn a_walled_room_shows_occupied_walls_and_a_free_interior() {
        let mut g = grid();
        let mut laser = LaserConfig::thesis();
        laser.beam_count = 360;
        laser.first_angle_rad = -PI;
        let mut changes = 0;
        let mut total = ScanIntegration::default();
        for &theta in &[0.0, PI / 2.0, PI, -PI / 2.0] {
            let pose = Pose2::new(3.0, 3.0, theta);
            let scan = room_scan(pose, &laser);
            let r = integrate_scan(
                &mut g,
                &scan,
                pose,
                &laser,
                &SensorModel::default(),
                &mut |_i: usize, _o: CellClass, _n: CellClass| changes += 1,
            )
            .unwrap();
            total.newly_known += r.newly_known;
            total.changed += r.changed;
        }
        assert_eq!(total.changed, changes);
        assert_eq!(total.newly_known, g.counts().known());
        // Wall cells, corners apart (beams graze the corner cells).
        let geom = *g.geometry();
        let mut wall_occupied = 0;
        let mut wall_cells = 0;
        for k in 12..48 {
            for cell in [
                Cell::new(49, k),
                Cell::new(10, k),
                Cell::new(k, 49),
                Cell::new(k, 10),
            ] {
                wall_cells += 1;
                if g.class_of(cell) == Some(CellClass::Occupied) {
                    wall_occupied += 1;
                }
            }
        }
        assert_eq!(wall_occupied, wall_cells, "every wall cell is occupied");
        // Interior: every cell strictly inside the walls is free.
        for row in 11..49 {
            for col in 11..49 {
                let c = Cell::new(col, row);
                assert_eq!(g.class_of(c), Some(CellClass::Free), "{c:?}");
            }
        }
        // Outside the room nothing is known.
        for i in 0..geom.cell_count() {
            let c = geom.cell(i);
            if c.col < 10 || c.col > 49 || c.row < 10 || c.row > 49 {
                assert_eq!(g.class(i), CellClass::Unknown, "{c:?}");
            }
        }
    }

    /// A wall's face on a cell boundary (row 30's north face, y = 3.1 m) and a robot whose
    /// estimate is 1 cm off towards it: the beams passing along the face, just clear of it,
    /// cross its cells 4 cm from their centres. Under the thesis's model fifty scans (one
    /// second) wear the face away; with misses counted only near a confidently Occupied cell's
    /// centre the face stays, a beam crossing the cells through the middle still clears them,
    /// and so do grazing misses a cell with a single hit.
    #[test]
    fn beams_grazing_a_wall_face_do_not_wear_it_away() {
        let laser = LaserConfig::thesis();
        let face: Vec<usize> = (20..30).map(|col| 30 * 60 + col).collect();
        // The face's cells start at `log_odds`; `scans` scans of one beam along y = `y_m`;
        // how many of the cells are still Occupied.
        let occupied_after = |model: &SensorModel, y_m: f32, log_odds: f32, scans: usize| {
            let mut g = grid();
            for &i in &face {
                g.set_log_odds(i, log_odds, &mut ());
            }
            let mut s = Scan::new();
            s.push(Beam {
                angle_rad: 0.0,
                range_m: Some(3.5),
            })
            .unwrap();
            let pose = Pose2::new(1.0, y_m, 0.0);
            for _ in 0..scans {
                integrate_scan(&mut g, &s, pose, &laser, model, &mut ()).unwrap();
            }
            face.iter()
                .filter(|&&i| g.class(i) == CellClass::Occupied)
                .count()
        };
        let wall = grid().bounds().max;
        // 1 cm inside the face's row (y 3.0..3.1), 4 cm from the cells' centres, one second.
        assert_eq!(occupied_after(&SensorModel::thesis(), 3.09, wall, 50), 0);
        let kept = SensorModel::thesis().with_occupied_miss_offset(GRAZING_MISS_OFFSET_CELLS);
        assert_eq!(occupied_after(&kept, 3.09, wall, 50), face.len());
        // Through the cells' centres: the misses count.
        assert_eq!(occupied_after(&kept, 3.05, wall, 50), 0);
        // Cells with one hit (noise returns in a door) are cleared by grazing misses too.
        let one_hit = SensorModel::thesis().occupied_log_odds;
        assert_eq!(occupied_after(&kept, 3.09, one_hit, 10), 0);
    }

    #[test]
    fn blind_zone_and_out_of_range_readings() {
        let laser = LaserConfig::thesis();
        let model = SensorModel::default();
        // Along the centres of row 30 (y = 3.05 m).
        let pose = Pose2::new(1.0, 3.05, 0.0);
        let beam = |r: Option<f32>| {
            let mut s = Scan::new();
            s.push(Beam {
                angle_rad: 0.0,
                range_m: r,
            })
            .unwrap();
            s
        };
        // Blind zone: nothing happens.
        let mut g = grid();
        let r = integrate_scan(&mut g, &beam(Some(0.2)), pose, &laser, &model, &mut ()).unwrap();
        assert_eq!(
            (r.beams_ignored, r.updates, g.counts()),
            (1, 0, CellCounts::default())
        );
        // Beyond the usable range: free up to 4 m, no occupied cell.
        let mut g = grid();
        let r = integrate_scan(&mut g, &beam(Some(4.5)), pose, &laser, &model, &mut ()).unwrap();
        assert_eq!(g.counts().occupied, 0);
        assert_eq!(g.counts().free, r.newly_known);
        assert_eq!(g.class_of(Cell::new(49, 30)), Some(CellClass::Free));
        assert_eq!(g.class_of(Cell::new(51, 30)), Some(CellClass::Unknown));
        // No return behaves the same.
        let mut g2 = grid();
        integrate_scan(&mut g2, &beam(None), pose, &laser, &model, &mut ()).unwrap();
        assert_eq!(g2.log_odds(), g.log_odds());
        // A return at 2.05 m: cells before free, the return cell occupied only.
        let mut g = grid();
        integrate_scan(&mut g, &beam(Some(2.05)), pose, &laser, &model, &mut ()).unwrap();
        assert_eq!(g.class_of(Cell::new(30, 30)), Some(CellClass::Occupied));
        assert_eq!(g.counts().occupied, 1);
        assert_eq!(g.class_of(Cell::new(29, 30)), Some(CellClass::Free));
        assert_eq!(g.class_of(Cell::new(31, 30)), Some(CellClass::Unknown));
        let w = g.log_odds_at(g.geometry().index(Cell::new(30, 30)).unwrap());
        // The beam runs through the cell centre: full weight.
        assert!((w - model.occupied_log_odds).abs() < 1e-3, "{w}");
    }

    #[test]
    fn a_return_on_a_wall_face_marks_the_wall_not_the_cell_in_front() {
        // A wall whose east face is the line x = 1.1 m (column 10 is the wall, 11 free), seen
        // from the east along the centres of row 30: a return on the face, or 1 cm short of it
        // with a precise laser, lies in column 11 itself; the Occupied evidence goes to column
        // 10 and column 11 stays Free. A return in the middle of a cell stays in that cell.
        let model = SensorModel::default();
        let pose = Pose2::new(3.05, 3.05, PI);
        for (noise, range_m) in [(0.0, 1.95), (0.003, 1.95), (0.003, 1.94), (0.05, 1.95)] {
            let mut laser = LaserConfig::thesis();
            laser.noise_fraction = noise;
            let mut g = grid();
            let mut s = Scan::new();
            s.push(Beam {
                angle_rad: 0.0,
                range_m: Some(range_m),
            })
            .unwrap();
            integrate_scan(&mut g, &s, pose, &laser, &model, &mut ()).unwrap();
            let at = |col| g.class_of(Cell::new(col, 30));
            assert_eq!(
                at(10),
                Some(CellClass::Occupied),
                "noise {noise}, {range_m} m"
            );
            assert_eq!(at(11), Some(CellClass::Free), "noise {noise}, {range_m} m");
            assert_eq!(
                at(9),
                Some(CellClass::Unknown),
                "noise {noise}, {range_m} m"
            );
        }
        // Depth: a twentieth of a cell plus two standard deviations, at most a quarter cell.
        assert!((hit_depth_m(2.0, 0.0, 0.1) - 0.005).abs() < 1e-6);
        assert!((hit_depth_m(2.0, 0.003, 0.1) - 0.017).abs() < 1e-6);
        assert!((hit_depth_m(2.0, 0.05, 0.1) - 0.025).abs() < 1e-6);
        assert!((hit_depth_m(2.0, f32::NAN, 0.1) - 0.005).abs() < 1e-6);
    }

    #[test]
    fn a_wall_band_marks_the_wall_cell_behind_a_return_drawn_short() {
        // The wall of the test above (column 10, east face x = 1.1 m), seen from the east with
        // a precise laser, the scan drawn 3 cm short along the beam (the pose 3 cm east of
        // where the robot stood). Without a band the return marks column 11 (free in truth)
        // and column 10 is never reached; with a 5 cm band column 10 is Occupied too. Only the
        // far side is widened: the cells before the return stay Free, and a band longer than
        // half a cell reaches no further than half a cell.
        let model = SensorModel::default();
        let mut laser = LaserConfig::thesis();
        laser.noise_fraction = 0.003;
        let beam = |range_m: f32| {
            let mut s = Scan::new();
            s.push(Beam {
                angle_rad: 0.0,
                range_m: Some(range_m),
            })
            .unwrap();
            s
        };
        let short = Pose2::new(3.05 + 0.03, 3.05, PI);
        let run = |pose: Pose2, range_m: f32, band_m: f32| {
            let mut g = grid();
            for _ in 0..3 {
                integrate_scan_banded(
                    &mut g,
                    &beam(range_m),
                    pose,
                    band_m,
                    &laser,
                    &model,
                    &mut (),
                )
                .unwrap();
            }
            g
        };
        let g = run(short, 1.95, 0.0);
        let at = |g: &Grid, col| g.class_of(Cell::new(col, 30));
        assert_eq!(at(&g, 11), Some(CellClass::Occupied));
        assert_eq!(at(&g, 10), Some(CellClass::Unknown));
        let g = run(short, 1.95, 0.05);
        assert_eq!(at(&g, 10), Some(CellClass::Occupied));
        assert_eq!(at(&g, 11), Some(CellClass::Occupied));
        assert_eq!(at(&g, 12), Some(CellClass::Free));
        assert_eq!(at(&g, 9), Some(CellClass::Unknown));
        // At the true pose the return's point (1.95 m plus the 1.7 cm depth) lies 1.7 cm into
        // column 10, and a 5 cm band ends 6.7 cm into it: the same cells as without a band.
        let g = run(Pose2::new(3.05, 3.05, PI), 1.95, 0.05);
        assert_eq!(at(&g, 10), Some(CellClass::Occupied));
        assert_eq!(at(&g, 11), Some(CellClass::Free));
        assert_eq!(at(&g, 9), Some(CellClass::Unknown));
        // A return in the middle of column 10 (x = 1.05 m) and a band of 1 m: column 9 too,
        // column 8 never (half a cell at most).
        let g = run(Pose2::new(3.05, 3.05, PI), 2.0, 1.0);
        assert_eq!(at(&g, 10), Some(CellClass::Occupied));
        assert_eq!(at(&g, 9), Some(CellClass::Occupied));
        assert_eq!(at(&g, 8), Some(CellClass::Unknown));
        assert_eq!(at(&g, 11), Some(CellClass::Free));
        // A bad band is an error naming it, and leaves the grid untouched.
        let mut g = grid();
        for bad in [-0.01, f32::NAN, f32::INFINITY] {
            let e = integrate_scan_banded(&mut g, &beam(1.95), short, bad, &laser, &model, &mut ());
            assert!(matches!(e, Err(IntegrationError::BadBand(_))), "{e:?}");
        }
        assert_eq!(g.counts(), CellCounts::default());
    }

    #[test]
    fn evidence_is_weighted_by_distance_to_the_cell_centre_and_accumulates() {
        let laser = LaserConfig::thesis();
        let model = SensorModel::default();
        let mut g = grid();
        // Beam along y = 3.02 (2 cm north of the centres of row 30 at y = 3.05 ... centres of
        // row 30 lie at 3.05: distance 3 cm).
        let pose = Pose2::new(1.0, 3.02, 0.0);
        let mut s = Scan::new();
        s.push(Beam {
            angle_rad: 0.0,
            range_m: Some(3.0),
        })
        .unwrap();
        integrate_scan(&mut g, &s, pose, &laser, &model, &mut ()).unwrap();
        let i = g.geometry().index(Cell::new(20, 30)).unwrap();
        let d: f32 = 0.03;
        let want = model.free_log_odds * math::exp(-d * d / (2.0 * 0.05 * 0.05));
        assert!(
            (g.log_odds_at(i) - want).abs() < 1e-4,
            "{} vs {want}",
            g.log_odds_at(i)
        );
        integrate_scan(&mut g, &s, pose, &laser, &model, &mut ()).unwrap();
        assert!((g.log_odds_at(i) - 2.0 * want).abs() < 1e-4);
    }

    /// The model applied literally: every crossed cell gets its weighted evidence, saturated
    /// or not. Returns the updates applied and the class changes seen.
    fn integrate_literally(
        grid: &mut Grid,
        scan: &Scan,
        pose: Pose2,
        laser: &LaserConfig,
        model: &SensorModel,
        changes: &mut usize,
    ) -> usize {
        let origin = pose.position();
        let geom = *grid.geometry();
        let mut updates = 0;
        // Hits before misses, literally: every return's cell first, in beam order, then the
        // misses of every beam, none in a cell any beam of the scan hit.
        let mut hit_cells = [usize::MAX; MAX_BEAMS];
        let mut hits = 0;
        if model.hits_before_misses {
            for beam in scan.beams() {
                let Some(r) = beam.range_m.filter(|r| *r >= laser.min_range_m) else {
                    continue;
                };
                if r > laser.max_range_m {
                    continue;
                }
                let length = r + hit_depth_m(r, laser.noise_fraction, geom.resolution_m);
                let a = pose.theta + beam.angle_rad;
                let (dx, dy) = (math::cos(a), math::sin(a));
                let end = Point2::new(origin.x + dx * length, origin.y + dy * length);
                let cell = geom.cell_at_unchecked(end);
                let Some(index) = geom.index(cell) else {
                    continue;
                };
                let c = geom.cell_center(cell);
                let d = (c.x - origin.x) * dy - (c.y - origin.y) * dx;
                let w = math::exp(-d * d * (1.0 / (2.0 * model.sigma_m * model.sigma_m)));
                grid.add_evidence(index, model.occupied_log_odds * w, &mut |_, _, _| {
                    *changes += 1
                });
                hit_cells[hits] = index;
                hits += 1;
            }
        }
        for beam in scan.beams() {
            let (length, hit) = match beam.range_m {
                Some(r) if r < laser.min_range_m => continue,
                Some(r) if r <= laser.max_range_m => (r, true),
                _ => (laser.max_range_m, false),
            };
            let length = if hit {
                length + hit_depth_m(length, laser.noise_fraction, geom.resolution_m)
            } else {
                length
            };
            let a = pose.theta + beam.angle_rad;
            let (dx, dy) = (math::cos(a), math::sin(a));
            let end = Point2::new(origin.x + dx * length, origin.y + dy * length);
            let hit_cell = geom.cell_at_unchecked(end);
            raycast::traverse(&geom, origin, end, |cell, index| {
                updates += 1;
                if hit_cells[..hits].contains(&index) {
                    return ControlFlow::Continue(());
                }
                let c = geom.cell_center(cell);
                let d = (c.x - origin.x) * dy - (c.y - origin.y) * dx;
                let w = math::exp(-d * d * (1.0 / (2.0 * model.sigma_m * model.sigma_m)));
                let occupied = hit && cell == hit_cell;
                let grazing = model
                    .occupied_miss_offset_cells
                    .is_some_and(|k| d.abs() > k * geom.resolution_m);
                if !occupied && grazing && grid.log_odds_at(index) >= CONFIDENT_OCCUPIED_LOG_ODDS {
                    return ControlFlow::Continue(());
                }
                let delta = if occupied {
                    model.occupied_log_odds
                } else {
                    model.free_log_odds
                };
                grid.add_evidence(index, delta * w, &mut |_, _, _| *changes += 1);
                ControlFlow::Continue(())
            });
        }
        updates
    }

    #[test]
    fn repeated_scans_give_exactly_the_literal_model_including_saturated_cells() {
        literal_model_check(&SensorModel::thesis());
        literal_model_check(&SensorModel::weak_misses());
        literal_model_check(
            &SensorModel::thesis().with_occupied_miss_offset(GRAZING_MISS_OFFSET_CELLS),
        );
    }

    /// Many scans from nearby poses saturate most cells at the bounds; walls seen from both
    /// sides and a return inside the free interior make cells flip both ways.
    fn literal_model_check(model: &SensorModel) {
        let model = *model;
        let mut fast = grid();
        let mut literal = grid();
        let laser = LaserConfig::thesis();
        let mut rng = crate::random::seeded(8);
        let (mut fast_changes, mut literal_changes) = (0usize, 0usize);
        for k in 0..60 {
            let pose = Pose2::new(
                2.5 + crate::random::unit_f32(&mut rng),
                2.5 + crate::random::unit_f32(&mut rng),
                crate::random::unit_f32(&mut rng) * 2.0 * PI,
            );
            let mut scan = room_scan(pose, &laser);
            if k % 7 == 3 {
                // A person in the room: a few short returns.
                for b in scan.beams_mut().iter_mut().skip(80).take(10) {
                    b.range_m = Some(0.9);
                }
            }
            let out = integrate_scan(&mut fast, &scan, pose, &laser, &model, &mut |_, _, _| {
                fast_changes += 1
            })
            .unwrap();
            let updates = integrate_literally(
                &mut literal,
                &scan,
                pose,
                &laser,
                &model,
                &mut literal_changes,
            );
            assert_eq!(out.updates, updates, "scan {k}");
            for (i, (a, b)) in fast.log_odds().iter().zip(literal.log_odds()).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "scan {k}, cell {i}");
            }
            assert_eq!(fast_changes, literal_changes, "scan {k}");
        }
        assert_eq!(fast.counts(), literal.counts());
        // The test did exercise saturation on both sides.
        let b = fast.bounds();
        assert!(fast.log_odds().iter().filter(|&&l| l == b.min).count() > 500);
        assert!(fast.log_odds().contains(&b.max));
    }

    #[test]
    fn hits_before_misses_keep_a_scans_grazing_beams_from_clearing_its_hits() {
        // One beam returns in cell (30, 30) (x 3.0..3.1 m, y 3.0..3.1 m); three more of the
        // same scan pass through that cell at a shallow angle and return 1.5 m further on, as
        // beams grazing a wall one cell thick do.
        let laser = LaserConfig::thesis();
        let pose = Pose2::new(1.05, 3.05, 0.0);
        let mut scan = Scan::new();
        for (angle_rad, range_m) in [(0.0, 2.0), (0.004, 3.5), (0.008, 3.5), (0.012, 3.5)] {
            scan.push(Beam {
                angle_rad,
                range_m: Some(range_m),
            })
            .unwrap();
        }
        let wall = Cell::new(30, 30);
        let class_of_wall = |model: &SensorModel| {
            let mut g = grid();
            integrate_scan(&mut g, &scan, pose, &laser, model, &mut ()).unwrap();
            let i = g.geometry().index(wall).unwrap();
            (g.class(i), g.log_odds_at(i))
        };
        let hits_first = SensorModel {
            hits_before_misses: true,
            ..SensorModel::thesis()
        };
        let (class, log_odds) = class_of_wall(&hits_first);
        assert_eq!(class, CellClass::Occupied);
        // Only the hit's evidence: the beam runs along the cell's centre line (weight 1).
        assert!((log_odds - hits_first.occupied_log_odds).abs() < 1e-6);
        // In beam order with the thesis's misses, the grazing beams clear it.
        assert_eq!(class_of_wall(&SensorModel::thesis()).0, CellClass::Free);
    }

    #[test]
    fn invalid_configuration_is_an_error() {
        let mut g = grid();
        let laser = LaserConfig::thesis();
        let bad = SensorModel {
            sigma_m: 0.0,
            ..SensorModel::default()
        };
        let s = Scan::new();
        assert_eq!(
            integrate_scan(&mut g, &s, Pose2::default(), &laser, &bad, &mut ()),
            Err(IntegrationError::BadSigma(0.0))
        );
        let bad = SensorModel::thesis().with_occupied_miss_offset(-0.25);
        assert_eq!(
            integrate_scan(&mut g, &s, Pose2::default(), &laser, &bad, &mut ()),
            Err(IntegrationError::BadMissOffset(-0.25))
        );
        let pose = Pose2 {
            x: f32::NAN,
            ..Pose2::default()
        };
        assert_eq!(
            integrate_scan(&mut g, &s, pose, &laser, &SensorModel::default(), &mut ()),
            Err(IntegrationError::BadPose)
        );
    }
}
