//! What the missions of one process share: the map (occupancy grid and its traversability
//! layer, kept in step) and the decision working memory.
//!
//! The thesis's multi-robot exploration coordinates implicitly, through a common map and no
//! messages. Besides the cells, the common map carries one mark per robot: where it is and
//! which waypoints it still means to drive. Robots see each other only as obstacles in their
//! scans; a robot uses the marks only to tell another robot in its way from a wall, and to
//! step out of the path of a robot it yields to.

use crate::control::Time;
use crate::explore::{ExploreObjective, MouthSearch, ViewCache};
use crate::frontier::FrontierWorkspace;
use crate::geometry::{Point2, Pose2};
use crate::grid::{GridGeometry, OccupancyGrid};
use crate::planner::{AStar, DistanceField, Planner, Traversability};

use super::window::{STAMP_WINDOW_CELLS, StampWindow};
use super::{MissionConfig, MissionError};

/// Most robots sharing one map: a hundred, as the thesis's simulator (issue 24). A mark is
/// 160 bytes, so the marks of a hundred robots take 16 KB of every [`SharedMap`], whatever the
/// number of robots; a robot reads only the marks written (`mark_count`), so fewer robots
/// cost nothing more. (The onboard binary runs one robot.)
pub const MAX_ROBOTS: usize = 100;
/// Most remaining waypoints a robot publishes on the shared map.
pub const MAX_SHARED_WAYPOINTS: usize = 16;
/// Most frontiers a frontier-based decision handles.
pub const MAX_FRONTIERS: usize = 256;

/// A robot's mark on the shared map.
#[derive(Clone, Copy, bytemuck::Zeroable)]
pub struct RobotMark {
    /// The robot's mission id.
    pub id: u8,
    /// Its map pose.
    pub pose: Pose2,
    /// When the pose was written.
    pub time: Time,
    path_len: usize,
    path: [Point2; MAX_SHARED_WAYPOINTS],
}

impl RobotMark {
    /// The waypoints it still means to drive, nearest first (at most
    /// [`MAX_SHARED_WAYPOINTS`]); empty while it stands still.
    pub fn path(&self) -> &[Point2] {
        &self.path[..self.path_len]
    }
}

impl PartialEq for RobotMark {
    fn eq(&self, other: &Self) -> bool {
        (self.id, self.pose, self.time) == (other.id, other.pose, other.time)
            && self.path() == other.path()
    }
}

impl core::fmt::Debug for RobotMark {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RobotMark")
            .field("id", &self.id)
            .field("pose", &self.pose)
            .field("time", &self.time)
            .field("path", &self.path())
            .finish()
    }
}

/// The map all robots of one mission share (in process): the occupancy grid and its
/// traversability layer, kept in step (scans integrate into both), and the robots' marks.
#[derive(bytemuck::Zeroable)]
pub struct SharedMap<const N: usize> {
    /// The occupancy grid.
    pub grid: OccupancyGrid<N>,
    /// Its traversability layer (inflated by the robot radius).
    pub trav: Traversability<N>,
    /// One mark per robot, the first `mark_count` of them written.
    marks: [RobotMark; MAX_ROBOTS],
    mark_count: usize,
    /// Scan-matching working memory (robots integrate their scans one after the other, so one
    /// is enough; [`crate::localize`]).
    pub matcher: crate::localize::ScanMatcher<{ crate::localize::WINDOW_CELLS }>,
    /// Where the robots' returns landed, at their corrected poses: the map scans are matched
    /// to (written only with [`MissionConfig::localize`] on; [`crate::localize::hits`]).
    pub hits: crate::localize::HitMap<N>,
    /// Keyframes, pose graph and loop closures (used only with the localisation's graph on,
    /// one robot; [`crate::localize::graph`]).
    pub graph: crate::localize::graph::KeyframeGraph<
        { crate::localize::graph::GRAPH_KEYFRAMES },
        { crate::localize::graph::GRAPH_EDGES },
    >,
    /// Each cell's class before the graph redraws the map, one byte a cell (used only with
    /// the graph on and [`crate::localize::graph::GraphConfig::redraw_keeps_unseen`];
    /// zeroed and untouched otherwise).
    pub known_before_redraw: [i8; N],
}

impl<const N: usize> core::fmt::Debug for SharedMap<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SharedMap")
            .field("grid", &self.grid)
            .field("trav", &self.trav)
            .field("robots", &self.robots())
            .finish()
    }
}

impl<const N: usize> SharedMap<N> {
    /// An all-Unknown map of the given geometry, built on the stack (for small `N`; on a host
    /// prefer [`Self::new_boxed`]).
    pub fn new(geometry: GridGeometry, config: &MissionConfig) -> Result<Self, MissionError> {
        let grid = OccupancyGrid::new(geometry, config.grid_bounds).map_err(MissionError::Grid)?;
        let trav =
            Traversability::new(geometry, config.traversability).map_err(MissionError::Map)?;
        Ok(Self {
            grid,
            trav,
            marks: [bytemuck::Zeroable::zeroed(); MAX_ROBOTS],
            mark_count: 0,
            matcher: crate::localize::ScanMatcher::new(),
            hits: crate::localize::HitMap::new(geometry),
            graph: bytemuck::Zeroable::zeroed(),
            known_before_redraw: [0; N],
        })
    }

    /// An all-Unknown map built on the heap, whatever `N`.
    #[cfg(feature = "std")]
    pub fn new_boxed(
        geometry: GridGeometry,
        config: &MissionConfig,
    ) -> Result<std::boxed::Box<Self>, MissionError> {
        let mut map = crate::heap::boxed_zeroed::<Self>();
        map.grid
            .set_up_zeroed(geometry, config.grid_bounds)
            .map_err(MissionError::Grid)?;
        map.trav
            .set_up_zeroed(geometry, config.traversability)
            .map_err(MissionError::Map)?;
        map.hits.set_up_zeroed(geometry);
        Ok(map)
    }

    /// The robots' marks, in the order they were first written.
    pub fn robots(&self) -> &[RobotMark] {
        &self.marks[..self.mark_count]
    }

    /// Reloads the traversability layer from the grid (after the caller edited the grid
    /// without passing the layer as observer, e.g. a prior map).
    pub fn rebuild_traversability(&mut self) -> Result<(), MissionError> {
        self.trav
            .rebuild_from(&self.grid)
            .map_err(MissionError::Map)
    }

    /// The mark of robot `id`, if it wrote one.
    pub fn robot(&self, id: u8) -> Option<&RobotMark> {
        self.robots().iter().find(|m| m.id == id)
    }

    /// Writes robot `id`'s mark. Errors if more than [`MAX_ROBOTS`] robots share the map.
    pub(crate) fn mark(
        &mut self,
        id: u8,
        pose: Pose2,
        time: Time,
        path: &[Point2],
    ) -> Result<(), MissionError> {
        let slot = match self.robots().iter().position(|m| m.id == id) {
            Some(i) => i,
            None if self.mark_count < MAX_ROBOTS => {
                self.mark_count += 1;
                self.mark_count - 1
            }
            None => {
                return Err(MissionError::TooManyRobots {
                    capacity: MAX_ROBOTS,
                });
            }
        };
        let n = path.len().min(MAX_SHARED_WAYPOINTS);
        let slot = &mut self.marks[slot];
        slot.id = id;
        slot.pose = pose;
        slot.time = time;
        slot.path_len = n;
        slot.path[..n].copy_from_slice(&path[..n]);
        Ok(())
    }
}

/// Decision working memory: distance field, path planner, visited-cell stamps, the visibility
/// cache of the exploration objective (16.7 MB, whatever `N`), frontier search memory and the
/// memory of the search for passages shut on the map ([`MouthSearch`]) and the map window
/// saved while a robot's body is lifted and the others stamped (213 KB). One
/// per process is enough, as robots decide one after the other.
///
/// The planner that joins the targets of a decision (the legs after the first, which the
/// distance field answers) is `P`: A* ([`AStar`]) unless a test double stands in (any
/// [`Planner`]); the mission is generic over it, so the choice costs nothing at run time.
#[derive(bytemuck::Zeroable)]
pub struct Workspace<const N: usize, P = AStar<N>> {
    field: DistanceField<N>,
    planner: P,
    stamps: [u32; N],
    views: ViewCache,
    frontier: FrontierWorkspace<N, MAX_FRONTIERS>,
    mouths: MouthSearch<N>,
    /// The map window saved while a robot's body is lifted and the others stamped.
    stamp: StampWindow<STAMP_WINDOW_CELLS>,
}

impl<const N: usize, P: Planner<N>> core::fmt::Debug for Workspace<N, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Workspace")
            .field("capacity", &N)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> Default for Workspace<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Workspace<N> {
    /// Working memory with A*, built on the stack (or in a `static`); about 90 bytes per
    /// cell plus the 16.7 MB visibility cache.
    pub const fn new() -> Self {
        Self::with_planner(AStar::new())
    }
}

impl<const N: usize, P: Planner<N>> Workspace<N, P> {
    /// Working memory around `planner`, built on the stack (or in a `static`).
    pub const fn with_planner(planner: P) -> Self {
        Self {
            field: DistanceField::new(),
            planner,
            stamps: [0; N],
            views: ViewCache::new(),
            frontier: FrontierWorkspace::new(),
            mouths: MouthSearch::new(),
            stamp: StampWindow::new(),
        }
    }

    /// Working memory built on the heap, whatever `N`, its planner all zero bytes (A*'s
    /// empty memory).
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self>
    where
        P: bytemuck::Zeroable,
    {
        let mut ws = crate::heap::boxed_zeroed::<Self>();
        ws.views
            .set_entry_limit(crate::explore::view_cache::MAX_VIEWS);
        ws
    }

    /// The saved map window (`super::window`).
    pub(crate) fn stamp_window(&mut self) -> &mut StampWindow<STAMP_WINDOW_CELLS> {
        &mut self.stamp
    }

    /// The path planner.
    pub fn planner(&self) -> &P {
        &self.planner
    }

    /// The distance field of the last decision or plan, and the memory of the search for
    /// passages shut on the map.
    pub(crate) fn mouth_parts(&mut self) -> (&DistanceField<N>, &mut MouthSearch<N>) {
        (&self.field, &mut self.mouths)
    }

    /// The exploration objective over this memory, and the frontier search memory.
    pub(crate) fn parts(
        &mut self,
    ) -> (
        ExploreObjective<'_, N, P>,
        &mut FrontierWorkspace<N, MAX_FRONTIERS>,
    ) {
        (
            ExploreObjective::with_view_cache(
                &mut self.field,
                &mut self.planner,
                &mut self.stamps,
                &mut self.views,
            ),
            &mut self.frontier,
        )
    }
}
