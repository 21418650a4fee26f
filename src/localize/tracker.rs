//! Scan matching applied to a robot's odometry: every N-th scan is matched at the pose the
//! odometry predicts, and a trusted match moves the map-from-odometry transform so that the
//! odometry pose of that instant maps to the matched pose. Later odometry then carries the
//! correction forward, and the map, the planner and the controller all see the corrected pose.

use crate::control::odometry::MapFromOdom;
use crate::geometry::Pose2;
use crate::grid::OccupancyGrid;
use crate::sensor::{LaserConfig, Scan};

use super::{MatchConfig, MatchQuality, ScanMatcher, WINDOW_CELLS};

/// When and how a mission matches its scans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalizeConfig {
    /// Match scans at all (off: the map is drawn at the odometry pose).
    pub enabled: bool,
    /// Match every this many scans (1: every scan).
    pub every_n_scans: u32,
    /// The matcher's settings.
    pub matcher: MatchConfig,
}

impl Default for LocalizeConfig {
    /// Off; when on, every scan with the default matcher.
    fn default() -> Self {
        Self {
            enabled: false,
            every_n_scans: 1,
            matcher: MatchConfig::default(),
        }
    }
}

/// A robot's matcher memory and counters.
pub struct Tracker {
    matcher: ScanMatcher<WINDOW_CELLS>,
    scans: u32,
    matches: u32,
    trusted: u32,
    last: Option<MatchQuality>,
}

impl core::fmt::Debug for Tracker {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Tracker")
            .field("scans", &self.scans)
            .field("matches", &self.matches)
            .field("trusted", &self.trusted)
            .field("last", &self.last)
            .finish_non_exhaustive()
    }
}

impl Default for Tracker {
    fn default() -> Self {
        Self::new()
    }
}

impl Tracker {
    /// A tracker that has seen no scan.
    pub const fn new() -> Self {
        Self {
            matcher: ScanMatcher::new(),
            scans: 0,
            matches: 0,
            trusted: 0,
            last: None,
        }
    }

    /// Matches `scan` (taken at odometry pose `pose_odom`) against `grid` when `config` says
    /// so, and corrects `map_from_odom`. Returns the corrected map pose when a match was
    /// trusted, `None` otherwise (the transform is then unchanged).
    pub fn on_scan<const N: usize>(
        &mut self,
        config: &LocalizeConfig,
        grid: &OccupancyGrid<N>,
        scan: &Scan,
        laser: &LaserConfig,
        pose_odom: Pose2,
        map_from_odom: &mut MapFromOdom,
    ) -> Option<Pose2> {
        if !config.enabled {
            return None;
        }
        self.scans += 1;
        if !(self.scans - 1).is_multiple_of(config.every_n_scans.max(1)) {
            return None;
        }
        let predicted = map_from_odom.map_pose(pose_odom);
        let result = self
            .matcher
            .match_scan(grid, scan, laser, predicted, &config.matcher);
        self.matches += 1;
        self.last = Some(result.quality);
        if !result.quality.trusted() {
            return None;
        }
        self.trusted += 1;
        *map_from_odom = MapFromOdom::from_start(result.pose, pose_odom);
        Some(result.pose)
    }

    /// Scans matched so far.
    pub fn matches(&self) -> u32 {
        self.matches
    }

    /// Matches trusted (at least partly applied) so far.
    pub fn trusted(&self) -> u32 {
        self.trusted
    }

    /// The last match's quality.
    pub fn last(&self) -> Option<&MatchQuality> {
        self.last.as_ref()
    }
}
