//! Planner queries never allocate: A*, distance-field sweeps, path extraction, waypoint
//! pruning and incremental traversability updates run under a counting global allocator.
//! Only the test's own thread is counted (the test harness's main thread may allocate
//! meanwhile).

mod alloc_count;

use alloc_count::allocations_in;
use papillon::geometry::Point2;
use papillon::grid::{Cell, CellClass, GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::planner::{
    AStar, DistanceField, Planner, Traversability, TraversabilityConfig, prune_to_waypoints,
};
use papillon::random;

const CAP: usize = 120 * 100;

#[test]
fn queries_and_updates_do_not_allocate() {
    let geometry = GridGeometry::new(120, 100, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CAP>::new_boxed(geometry, LogOddsBounds::default()).unwrap();
    let mut trav =
        Traversability::<CAP>::new_boxed(geometry, TraversabilityConfig::default()).unwrap();
    let mut astar = AStar::<CAP>::new_boxed();
    let mut field = DistanceField::<CAP>::new_boxed();
    let mut path = vec![Cell::default(); CAP];
    let mut waypoints = vec![Point2::default(); CAP];
    let mut rng = random::seeded(4);
    // Mostly free, a few walls.
    for i in 0..geometry.cell_count() {
        let class = if random::chance(&mut rng, 0.03) {
            CellClass::Occupied
        } else {
            CellClass::Free
        };
        grid.set_class(i, class, &mut *trav);
    }
    trav.rebuild_from(&grid).unwrap();

    let mut solved = 0;
    let ((), n) = allocations_in(|| {
        for _ in 0..200 {
            let a = geometry.cell(random::below(&mut rng, geometry.cell_count()));
            let b = geometry.cell(random::below(&mut rng, geometry.cell_count()));
            if let Ok(p) = astar.plan(&trav, a, b, &mut path) {
                solved += 1;
                prune_to_waypoints(&trav, &path[..p.len], &mut waypoints).unwrap();
            }
            if field.compute(&trav, a).is_ok() {
                let _ = field.distance_to(b);
                let _ = field.path_to(b, &mut path);
            }
            let i = random::below(&mut rng, geometry.cell_count());
            grid.add_evidence(i, random::range_f32(&mut rng, -2.0, 2.0), &mut *trav);
        }
    });
    assert!(solved > 50, "only {solved} queries solved");
    assert_eq!(n, 0, "planner allocated {n} times");
}
