//! One exploration decision on a mid-mission snapshot of the thesis's House map: xBOA with
//! population 5 and 20 (30 generations, k = 1) and the two frontier selectors.
//!
//! The snapshot is built from `../shared/data/thesis-maps/map-house.csv` (24 x 24 one-metre
//! blocks at 10 cm: a 240 x 240 grid): cells within 6 m of the robot at (1.5 m, 1.5 m) are known
//! with their true class, the rest Unknown.
//!
//! Run: `cargo bench -p papillon --bench explore -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, criterion_group, criterion_main};
use papillon::explore::{
    DecisionRequest, ExploreConfig, ExploreObjective, FrontierUtility, NearestFrontier, Optimized,
    TargetSelector,
};
use papillon::frontier::FrontierWorkspace;
use papillon::geometry::{Point2, Pose2};
use papillon::grid::{CellClass, GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::optim::Method;
use papillon::planner::{AStar, DistanceField, Traversability, TraversabilityConfig};
use papillon::random::seeded;
use papillon::sensor::LaserConfig;

const SIDE: usize = 240;
const CELLS: usize = SIDE * SIDE;

fn snapshot() -> (Box<OccupancyGrid<CELLS>>, Box<Traversability<CELLS>>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/thesis-maps/map-house.csv"
    );
    let text = std::fs::read_to_string(path).expect("House map (shared data)");
    let rows: Vec<Vec<bool>> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|v| v.trim() == "1").collect())
        .collect();
    let g = GridGeometry::new(SIDE, SIDE, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(g, LogOddsBounds::default()).unwrap();
    let robot = Point2::new(1.5, 1.5);
    for i in 0..g.cell_count() {
        let c = g.cell(i);
        // Row 0 of the file is the north edge; grid row 0 is the south edge.
        let wall = rows[23 - (c.row as usize / 10)][c.col as usize / 10];
        if g.cell_center(c).distance(robot) <= 6.0 {
            let class = if wall {
                CellClass::Occupied
            } else {
                CellClass::Free
            };
            grid.set_class(i, class, &mut ());
        }
    }
    let mut trav = Traversability::<CELLS>::new_boxed(g, TraversabilityConfig::default()).unwrap();
    trav.rebuild_from(&grid).unwrap();
    (grid, trav)
}

fn bench(c: &mut Criterion) {
    let (grid, trav) = snapshot();
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
    let mut obj = ExploreObjective::new(&mut field, &mut astar, &mut stamps);
    let mut ws = FrontierWorkspace::<8192, 256>::new_boxed();
    let mut group = c.benchmark_group("explore_decision");
    for pop in [5usize, 20] {
        let config = ExploreConfig {
            population: pop,
            max_generations: 30,
            ..ExploreConfig::default()
        };
        let mut sel = Optimized::new(Method::Xboa, config, &mut obj);
        group.bench_function(format!("xboa_pop{pop}_gen30"), |b| {
            b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
        });
    }
    {
        let mut sel = NearestFrontier::new(ExploreConfig::default(), &mut obj, &mut ws);
        group.bench_function("nearest_frontier", |b| {
            b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
        });
    }
    {
        let mut sel = FrontierUtility::new(ExploreConfig::default(), &mut obj, &mut ws);
        group.bench_function("frontier_utility", |b| {
            b.iter(|| sel.decide(&req, &mut seeded(1)).unwrap())
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
