//! Exploration decisions never allocate: with the visibility cache, xBOA and the frontier
//! selectors decide on the House fixture under a counting global allocator. Only the test's
//! own thread is counted (the test harness's main thread may allocate meanwhile).
#![cfg(feature = "std")]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, NearestFrontier, Optimized, Outcome,
    TargetSelector, ViewCache,
};
use papillon::frontier::FrontierWorkspace;
use papillon::geometry::Pose2;
use papillon::grid::{LogOddsBounds, OccupancyGrid};
use papillon::mapfile::read_map;
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::LaserConfig;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Whether allocations on this thread are counted.
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.with(Cell::get) {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

// SAFETY: forwards to the system allocator, counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const CELLS: usize = 240 * 240;

#[test]
fn decisions_do_not_allocate() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/house-mid-mission.yaml");
    let map = read_map(&path).unwrap();
    let mut grid =
        OccupancyGrid::<CELLS>::new_boxed(map.geometry, LogOddsBounds::default()).unwrap();
    map.load_into(&mut grid).unwrap();
    let mut trav =
        Traversability::<CELLS>::new_boxed(map.geometry, TraversabilityConfig::default()).unwrap();
    trav.rebuild_from(&grid).unwrap();
    let laser = LaserConfig::thesis();
    let req = DecisionRequest {
        grid: &grid,
        trav: &trav,
        pose: Pose2::new(1.5, 1.5, 0.0),
        battery_steps: 60.0,
        laser: &laser,
    };
    let mut field = DistanceField::<CELLS>::new_boxed();
    let mut astar = AStar::<CELLS>::new_boxed();
    let mut stamps = vec![0u32; CELLS];
    let mut views = ViewCache::new_boxed();
    let mut ws = FrontierWorkspace::<8192, 256>::new_boxed();
    let mut obj =
        ExploreObjective::with_view_cache(&mut field, &mut astar, &mut stamps, &mut views);
    let config = ExploreConfig {
        targets: 2,
        max_generations: 5,
        ..ExploreConfig::default()
    };

    COUNTED.with(|c| c.set(true));
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let a = Optimized::new(Method::Xboa, config, &mut obj)
        .decide(&req, &mut seeded(1))
        .unwrap();
    let b = NearestFrontier::new(config, &mut obj, &mut ws)
        .decide(&req, &mut seeded(1))
        .unwrap();
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    COUNTED.with(|c| c.set(false));
    assert!(matches!(a, Outcome::Go(_)) && matches!(b, Outcome::Go(_)));
    assert_eq!(after - before, 0, "{} allocations", after - before);
}
