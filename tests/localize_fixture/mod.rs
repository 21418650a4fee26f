//! A half-explored House map as a mission draws it, for the scan-matching benchmark and the
//! no-allocation test: the thesis's inverse sensor model integrates noisy SICK LMS1xx scans (and the returns layer collects their returns)
//! taken along a short tour of the house's south-west rooms (true poses), so walls are
//! occupied only on the faces the laser saw and the rest of the house is Unknown.
//!
//! Shared by `benches/localize.rs` and `tests/no_alloc_localize.rs` (included with `#[path]`).
#![allow(dead_code)]

use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::localize::HitMap;
use papillon::sensor::{LaserConfig, Scan, SensorModel, integrate_scan};
use papillon_sim::laser::LaserSim;
use papillon_sim::world::World;

/// Cells of the house at 10 cm.
pub const CELLS: usize = 240 * 240;

/// The tour the map is drawn from (true poses).
pub const TOUR: [Pose2; 6] = [
    Pose2 {
        x: 1.5,
        y: 1.5,
        theta: 0.0,
    },
    Pose2 {
        x: 1.5,
        y: 1.5,
        theta: 1.6,
    },
    Pose2 {
        x: 2.5,
        y: 1.5,
        theta: 3.1,
    },
    Pose2 {
        x: 2.5,
        y: 2.5,
        theta: -1.6,
    },
    Pose2 {
        x: 1.5,
        y: 2.5,
        theta: 0.8,
    },
    Pose2 {
        x: 2.0,
        y: 2.0,
        theta: -0.8,
    },
];

/// The house world, its map after the tour, and the laser.
pub struct HalfExplored {
    pub world: World,
    pub grid: Box<OccupancyGrid<CELLS>>,
    /// Where the tour's returns landed (the map scans are matched to).
    pub hits: Box<HitMap<CELLS>>,
    pub laser: LaserConfig,
    sim: LaserSim,
}

impl HalfExplored {
    pub fn new() -> Self {
        let world = World::load("house", 0.1).expect("the built-in house");
        let laser = LaserConfig::lms1xx();
        let mut grid =
            OccupancyGrid::<CELLS>::new_boxed(*world.geometry(), LogOddsBounds::default())
                .expect("the house fits");
        let mut hits = HitMap::<CELLS>::new_boxed(*world.geometry());
        let mut sim = LaserSim::new(laser, 11);
        for pose in TOUR {
            for _ in 0..3 {
                let scan = sim.scan(&world, pose, &[]);
                integrate_scan(
                    &mut grid,
                    &scan,
                    pose,
                    &laser,
                    &SensorModel::default(),
                    &mut (),
                )
                .expect("valid pose and model");
                hits.add_scan(&scan, &laser, pose);
            }
        }
        Self {
            world,
            grid,
            hits,
            laser,
            sim,
        }
    }

    /// A fresh noisy scan from the true pose `pose`.
    pub fn scan(&mut self, pose: Pose2) -> Scan {
        self.sim.scan(&self.world, pose, &[])
    }
}
