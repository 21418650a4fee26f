//! What the missions of one process share: the map (occupancy grid and its traversability
//! layer, kept in step) and the decision working memory.
//!
//! The thesis's multi-robot exploration coordinates implicitly, through a common map and no
//! messages. Besides the cells, the common map carries one mark per robot: where it is and
//! which waypoints it still means to drive. Robots see each other only as obstacles in their
//! scans; a robot uses the marks only to tell another robot in its way from a wall, and to
//! step out of the path of a robot it yields to.

use crate::control::Time;
use crate::explore::{ExploreObjective, ViewCache};
use crate::frontier::FrontierWorkspace;
use crate::geometry::{Point2, Pose2};
use crate::grid::{GridGeometry, OccupancyGrid};
use crate::planner::{AStar, DistanceField, Traversability};

use super::{MissionConfig, MissionError};

/// Most robots sharing one map.
pub const MAX_ROBOTS: usize = 8;
/// Most remaining waypoints a robot publishes on the shared map.
pub const MAX_SHARED_WAYPOINTS: usize = 16;
/// Most frontiers a frontier-based decision handles.
pub const MAX_FRONTIERS: usize = 256;

/// A robot's mark on the shared map.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotMark {
    /// The robot's mission id.
    pub id: u8,
    /// Its map pose.
    pub pose: Pose2,
    /// When the pose was written.
    pub time: Time,
    /// The waypoints it still means to drive, nearest first (at most
    /// [`MAX_SHARED_WAYPOINTS`]); empty while it stands still.
    pub path: heapless::Vec<Point2, MAX_SHARED_WAYPOINTS>,
}

/// The map all robots of one mission share (in process): the occupancy grid and its
/// traversability layer, kept in step (scans integrate into both), and the robots' marks.
pub struct SharedMap<const N: usize> {
    /// The occupancy grid.
    pub grid: OccupancyGrid<N>,
    /// Its traversability layer (inflated by the robot radius).
    pub trav: Traversability<N>,
    /// One mark per robot.
    pub robots: heapless::Vec<RobotMark, MAX_ROBOTS>,
    /// Scan-matching working memory (robots integrate their scans one after the other, so one
    /// is enough; [`crate::localize`]).
    pub matcher: crate::localize::ScanMatcher<{ crate::localize::WINDOW_CELLS }>,
}

impl<const N: usize> core::fmt::Debug for SharedMap<N> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SharedMap")
            .field("grid", &self.grid)
            .field("trav", &self.trav)
            .field("robots", &self.robots)
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
            robots: heapless::Vec::new(),
            matcher: crate::localize::ScanMatcher::new(),
        })
    }

    /// An all-Unknown map built on the heap, whatever `N`.
    #[cfg(feature = "std")]
    pub fn new_boxed(
        geometry: GridGeometry,
        config: &MissionConfig,
    ) -> Result<std::boxed::Box<Self>, MissionError> {
        let grid = OccupancyGrid::<N>::new_boxed(geometry, config.grid_bounds)
            .map_err(MissionError::Grid)?;
        let trav = Traversability::<N>::new_boxed(geometry, config.traversability)
            .map_err(MissionError::Map)?;
        let layout = std::alloc::Layout::new::<Self>();
        // SAFETY: the layout is non-zero (it holds two arrays of N > 0 cells... or at least the
        // geometry). Each field is written below before the box is formed: the grid and the
        // layer are copied bit for bit from their own heap boxes (plain data without drop glue,
        // whose boxes are then freed without dropping their contents twice, as they have no
        // drop glue), and the robot list and the matcher are written empty.
        unsafe {
            let raw = std::alloc::alloc(layout) as *mut Self;
            if raw.is_null() {
                std::alloc::handle_alloc_error(layout);
            }
            core::ptr::copy_nonoverlapping(&*grid, core::ptr::addr_of_mut!((*raw).grid), 1);
            core::ptr::copy_nonoverlapping(&*trav, core::ptr::addr_of_mut!((*raw).trav), 1);
            core::ptr::addr_of_mut!((*raw).robots).write(heapless::Vec::new());
            core::ptr::addr_of_mut!((*raw).matcher).write(crate::localize::ScanMatcher::new());
            Ok(std::boxed::Box::from_raw(raw))
        }
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
        self.robots.iter().find(|m| m.id == id)
    }

    /// Writes robot `id`'s mark. Errors if more than [`MAX_ROBOTS`] robots share the map.
    pub(crate) fn mark(
        &mut self,
        id: u8,
        pose: Pose2,
        time: Time,
        path: &[Point2],
    ) -> Result<(), MissionError> {
        let slot = match self.robots.iter().position(|m| m.id == id) {
            Some(i) => &mut self.robots[i],
            None => {
                self.robots
                    .push(RobotMark {
                        id,
                        pose,
                        time,
                        path: heapless::Vec::new(),
                    })
                    .map_err(|_| MissionError::TooManyRobots {
                        capacity: MAX_ROBOTS,
                    })?;
                let last = self.robots.len() - 1;
                &mut self.robots[last]
            }
        };
        slot.pose = pose;
        slot.time = time;
        slot.path.clear();
        let n = path.len().min(MAX_SHARED_WAYPOINTS);
        // Capacity checked.
        let _ = slot.path.extend_from_slice(&path[..n]);
        Ok(())
    }
}

/// Decision working memory: distance field, A*, visited-cell stamps, the visibility cache of
/// the exploration objective (16.0 MB, whatever `N`) and frontier search memory. One per
/// process is enough, as robots decide one after the other.
pub struct Workspace<const N: usize> {
    field: DistanceField<N>,
    astar: AStar<N>,
    stamps: [u32; N],
    views: ViewCache,
    frontier: FrontierWorkspace<N, MAX_FRONTIERS>,
}

impl<const N: usize> core::fmt::Debug for Workspace<N> {
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
    /// Working memory built on the stack (or in a `static`); about 90 bytes per cell plus
    /// the 16.0 MB visibility cache.
    pub const fn new() -> Self {
        Self {
            field: DistanceField::new(),
            astar: AStar::new(),
            stamps: [0; N],
            views: ViewCache::new(),
            frontier: FrontierWorkspace::new(),
        }
    }

    /// Working memory built on the heap, whatever `N`.
    #[cfg(feature = "std")]
    pub fn new_boxed() -> std::boxed::Box<Self> {
        let field = DistanceField::<N>::new_boxed();
        let astar = AStar::<N>::new_boxed();
        let frontier = FrontierWorkspace::<N, MAX_FRONTIERS>::new_boxed();
        let views = ViewCache::new_boxed();
        let layout = std::alloc::Layout::new::<Self>();
        // SAFETY: zeroed memory is a valid `[u32; N]`; the four other fields are copied bit
        // for bit from their own heap boxes (plain data without drop glue, so freeing those
        // boxes afterwards drops nothing twice).
        unsafe {
            let raw = std::alloc::alloc_zeroed(layout) as *mut Self;
            if raw.is_null() {
                std::alloc::handle_alloc_error(layout);
            }
            core::ptr::copy_nonoverlapping(&*field, core::ptr::addr_of_mut!((*raw).field), 1);
            core::ptr::copy_nonoverlapping(&*astar, core::ptr::addr_of_mut!((*raw).astar), 1);
            core::ptr::copy_nonoverlapping(&*frontier, core::ptr::addr_of_mut!((*raw).frontier), 1);
            core::ptr::copy_nonoverlapping(&*views, core::ptr::addr_of_mut!((*raw).views), 1);
            std::boxed::Box::from_raw(raw)
        }
    }

    /// The exploration objective over this memory, and the frontier search memory.
    pub(crate) fn parts(
        &mut self,
    ) -> (
        ExploreObjective<'_, N>,
        &mut FrontierWorkspace<N, MAX_FRONTIERS>,
    ) {
        (
            ExploreObjective::with_view_cache(
                &mut self.field,
                &mut self.astar,
                &mut self.stamps,
                &mut self.views,
            ),
            &mut self.frontier,
        )
    }
}
