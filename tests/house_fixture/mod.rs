//! The mid-mission House snapshot (`fixtures/house-mid-mission.yaml`, see `fixtures/README.md`)
//! and the decision the exploration benchmark, examples and tests make from it: the robot at
//! (1.5 m, 1.5 m) facing east with 60 steps of battery and the thesis's laser.
//!
//! Shared by `benches/explore.rs`, `examples/decision_timing.rs`,
//! `examples/initial_population.rs` and `tests/no_alloc_explore.rs` (included with `mod` or
//! `#[path]`); each uses part of it.
#![allow(dead_code)]

use std::path::Path;

use papillon::explore::{DecisionRequest, ExploreObjective, ViewCache};
use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::mapfile::read_map;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::sensor::LaserConfig;

/// Cells of the snapshot's grid (240 x 240 at 10 cm).
pub const CELLS: usize = 240 * 240;

/// Energy left at the decision \[steps\].
pub const BATTERY_STEPS: f32 = 60.0;

/// The snapshot's map, its traversability layer and the laser that predicts the views.
pub struct HouseSnapshot {
    pub grid: Box<OccupancyGrid<CELLS>>,
    pub trav: Box<Traversability<CELLS>>,
    pub laser: LaserConfig,
}

impl HouseSnapshot {
    /// Reads the fixture; panics with the file's path if it cannot be read (a broken checkout).
    pub fn load() -> Self {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/house-mid-mission.yaml");
        let map = read_map(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut grid = OccupancyGrid::<CELLS>::new_boxed(map.geometry, LogOddsBounds::default())
            .expect("the snapshot fits its grid");
        map.load_into(&mut grid)
            .expect("the snapshot fits its grid");
        let mut trav =
            Traversability::<CELLS>::new_boxed(map.geometry, TraversabilityConfig::default())
                .expect("default traversability settings are valid");
        trav.rebuild_from(&grid).expect("same geometry");
        Self {
            grid,
            trav,
            laser: LaserConfig::thesis(),
        }
    }

    /// The decision made from the snapshot.
    pub fn request(&self) -> DecisionRequest<'_, CELLS> {
        DecisionRequest {
            grid: &self.grid,
            trav: &self.trav,
            pose: Pose2::new(1.5, 1.5, 0.0),
            battery_steps: BATTERY_STEPS,
            laser: &self.laser,
        }
    }
}

/// The working memory an exploration objective borrows, allocated once.
pub struct DecisionMemory {
    field: Box<DistanceField<CELLS>>,
    astar: Box<AStar<CELLS>>,
    stamps: Vec<u32>,
    views: Box<ViewCache>,
}

impl DecisionMemory {
    pub fn new() -> Self {
        Self {
            field: DistanceField::new_boxed(),
            astar: AStar::new_boxed(),
            stamps: vec![0; CELLS],
            views: ViewCache::new_boxed(),
        }
    }

    /// The objective with the visibility cache (what the mission uses).
    pub fn cached(&mut self) -> ExploreObjective<'_, CELLS> {
        ExploreObjective::with_view_cache(
            &mut self.field,
            &mut self.astar,
            &mut self.stamps,
            &mut self.views,
        )
    }

    /// The objective tracing every beam from the exact pose.
    pub fn traced(&mut self) -> ExploreObjective<'_, CELLS> {
        ExploreObjective::new(&mut self.field, &mut self.astar, &mut self.stamps)
    }
}
