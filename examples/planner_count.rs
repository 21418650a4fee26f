//! Runs one batch of the planner benchmark's queries (`benches/planner.rs`) once, for counting
//! instructions with callgrind, whose counts do not depend on the machine's load:
//!
//! ```text
//! cargo build --release --example planner_count
//! valgrind --tool=callgrind --collect-atstart=no --toggle-collect='planner_count::run*' \
//!     target/release/examples/planner_count house papillon
//! ```
//!
//! Arguments: the set (`arena` or `house`) and what to run (`papillon`, `pathfinding`, or
//! `field`, the distance-field sweep from the first query's start). Only the `run*` functions
//! are counted; building the maps and picking the queries is not. Prints the batch's cost sum
//! and expansions so the runs can be checked against each other.

use std::hint::black_box;

use papillon::grid::Cell;
use papillon::planner::{AStar, DistanceField, Traversability};

#[path = "../benches/common/planner_maps.rs"]
mod planner_maps;

use planner_maps::*;

#[inline(never)]
fn run_papillon<const N: usize>(
    trav: &Traversability<N>,
    astar: &mut AStar<N>,
    queries: &[(Cell, Cell)],
) -> (f64, u64) {
    let mut sum = 0.0f64;
    let mut expansions = 0u64;
    for &(s, t) in queries {
        let (cost, e) = astar.path_cost(trav, s, t).expect("a path");
        sum += cost as f64;
        expansions += e as u64;
    }
    (sum, expansions)
}

#[inline(never)]
fn run_pathfinding(map: &Map, queries: &[(Cell, Cell)]) -> f64 {
    let mut sum = 0u64;
    for &(s, t) in queries {
        sum += pathfinding_cost(map, s, t).expect("a path") as u64;
    }
    sum as f64 / ORTHO as f64
}

#[inline(never)]
fn run_field<const N: usize>(
    trav: &Traversability<N>,
    field: &mut DistanceField<N>,
    source: Cell,
) -> u32 {
    field.compute(trav, source).expect("a sweep")
}

fn batch<const N: usize>(map: &Map, trav: &Traversability<N>, q: &[(Cell, Cell)], what: &str) {
    match what {
        "papillon" => {
            let mut astar = AStar::<N>::new_boxed();
            let (sum, e) = black_box(run_papillon(trav, &mut astar, q));
            println!(
                "papillon: {} queries, cost sum {sum:.3}, {e} expansions",
                q.len()
            );
        }
        "pathfinding" => {
            let sum = black_box(run_pathfinding(map, q));
            println!("pathfinding: {} queries, cost sum {sum:.3}", q.len());
        }
        "field" => {
            let mut field = DistanceField::<N>::new_boxed();
            let reached = black_box(run_field(trav, &mut field, q[0].0));
            println!("field: {reached} cells reached");
        }
        other => panic!("unknown planner {other:?}: papillon, pathfinding or field"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (set, what) = match args.as_slice() {
        [_, set, what] => (set.as_str(), what.as_str()),
        _ => panic!("usage: planner_count arena|house papillon|pathfinding|field"),
    };
    match set {
        "arena" => {
            let (map, q) = arena();
            let trav = map.traversability::<ARENA_CAP>();
            batch(&map, &*trav, &q, what);
        }
        "house" => {
            let map = house();
            let trav = map.traversability::<HOUSE_CAP>();
            let q = house_queries(&map, &trav);
            batch(&map, &*trav, &q, what);
        }
        other => panic!("unknown set {other:?}: arena or house"),
    }
}
