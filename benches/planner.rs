//! Planner benchmarks: Papillon's A* against the `pathfinding` crate's `astar` on the same grids
//! and queries (the Moving AI arena problems; 100 random queries on a 240 x 240 house-like
//! map), and a distance-field sweep of the 240 x 240 map.
//!
//! Run: `cargo bench -p papillon --bench planner`. Each benchmark times a whole batch of
//! queries; divide by the batch size for the time per query.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use papillon::grid::Cell;
use papillon::planner::{AStar, DistanceField, Traversability};
use papillon::random;

const ARENA_CAP: usize = 49 * 49;
const HOUSE_SIDE: usize = 240;
const HOUSE_CAP: usize = HOUSE_SIDE * HOUSE_SIDE;

/// Integer step costs for `pathfinding` (which needs `Ord` costs): 1 and sqrt(2) scaled.
const ORTHO: u32 = 10_000;
const DIAG: u32 = 14_142;

/// A blocked map, row 0 south, index `row * width + col`.
struct Map {
    width: usize,
    height: usize,
    blocked: Vec<bool>,
}

impl Map {
    fn is_blocked(&self, c: Cell) -> bool {
        c.col < 0
            || c.row < 0
            || c.col as usize >= self.width
            || c.row as usize >= self.height
            || self.blocked[c.row as usize * self.width + c.col as usize]
    }

    fn traversability<const N: usize>(&self) -> Box<Traversability<N>> {
        Traversability::<N>::from_blocked_boxed(self.width, self.height, |c| self.is_blocked(c))
            .unwrap()
    }

    /// Successors for `pathfinding`: the same move rules as Papillon's planner.
    fn successors(&self, c: Cell) -> Vec<(Cell, u32)> {
        let mut out = Vec::with_capacity(8);
        let free = |dc: i32, dr: i32| !self.is_blocked(Cell::new(c.col + dc, c.row + dr));
        for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            if free(dc, dr) {
                out.push((Cell::new(c.col + dc, c.row + dr), ORTHO));
            }
        }
        for (dc, dr) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
            if free(dc, dr) && free(dc, 0) && free(0, dr) {
                out.push((Cell::new(c.col + dc, c.row + dr), DIAG));
            }
        }
        out
    }
}

fn octile_int(a: Cell, b: Cell) -> u32 {
    let dc = a.col.abs_diff(b.col);
    let dr = a.row.abs_diff(b.row);
    let (lo, hi) = (dc.min(dr), dc.max(dr));
    (hi - lo) * ORTHO + lo * DIAG
}

fn pathfinding_cost(map: &Map, a: Cell, b: Cell) -> Option<u32> {
    pathfinding::prelude::astar(
        &a,
        |c| map.successors(*c),
        |c| octile_int(*c, b),
        |c| *c == b,
    )
    .map(|(_, cost)| cost)
}

/// The Moving AI arena map and its problems, converted to row 0 south.
fn arena() -> (Map, Vec<(Cell, Cell)>) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/movingai/");
    let text = std::fs::read_to_string(format!("{dir}arena.map")).expect("arena.map");
    let lines: Vec<&str> = text.lines().collect();
    let height: usize = lines[1].split_whitespace().nth(1).unwrap().parse().unwrap();
    let width: usize = lines[2].split_whitespace().nth(1).unwrap().parse().unwrap();
    let mut blocked = vec![false; width * height];
    for y in 0..height {
        for (x, ch) in lines[4 + y].chars().enumerate() {
            blocked[(height - 1 - y) * width + x] = !matches!(ch, '.' | 'G' | 'S');
        }
    }
    let scen = std::fs::read_to_string(format!("{dir}arena.map.scen")).expect("arena.map.scen");
    let flip = |x: &str, y: &str| {
        let (x, y): (i32, i32) = (x.parse().unwrap(), y.parse().unwrap());
        Cell::new(x, height as i32 - 1 - y)
    };
    let problems = scen
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (flip(f[4], f[5]), flip(f[6], f[7]))
        })
        .collect();
    (
        Map {
            width,
            height,
            blocked,
        },
        problems,
    )
}

/// A deterministic 240 x 240 house-like map (24 m x 24 m at 10 cm): outer walls, a grid of
/// rooms 4 to 7 m wide with 2-cell walls, a 9-cell door in every wall segment, and a few
/// furniture blocks per room.
fn house() -> Map {
    let n = HOUSE_SIDE;
    let mut rng = random::seeded(2023);
    let mut blocked = vec![false; n * n];
    let wall = |c0: usize, r0: usize, c1: usize, r1: usize, b: &mut Vec<bool>| {
        for r in r0..r1.min(n) {
            for c in c0..c1.min(n) {
                b[r * n + c] = true;
            }
        }
    };
    wall(0, 0, n, 2, &mut blocked);
    wall(0, n - 2, n, n, &mut blocked);
    wall(0, 0, 2, n, &mut blocked);
    wall(n - 2, 0, n, n, &mut blocked);
    // Room boundaries along each axis.
    let cuts = |rng: &mut random::ProjectRng| {
        let mut v = vec![0usize];
        let mut x = 0usize;
        loop {
            x += 40 + random::below(rng, 31);
            if x + 40 >= n {
                break;
            }
            v.push(x);
        }
        v.push(n - 2);
        v
    };
    let xs = cuts(&mut rng);
    let ys = cuts(&mut rng);
    for &x in &xs[1..xs.len() - 1] {
        wall(x, 0, x + 2, n, &mut blocked);
    }
    for &y in &ys[1..ys.len() - 1] {
        wall(0, y, n, y + 2, &mut blocked);
    }
    // Doors: one per wall segment between two crossings.
    for (k, &x) in xs[1..xs.len() - 1].iter().enumerate() {
        let _ = k;
        for w in ys.windows(2) {
            let span = w[1] - w[0] - 2;
            let r = w[0] + 2 + 5 + random::below(&mut rng, span - 19);
            for rr in r..r + 9 {
                blocked[rr * n + x] = false;
                blocked[rr * n + x + 1] = false;
            }
        }
    }
    for &y in &ys[1..ys.len() - 1] {
        for w in xs.windows(2) {
            let span = w[1] - w[0] - 2;
            let c = w[0] + 2 + 5 + random::below(&mut rng, span - 19);
            for cc in c..c + 9 {
                blocked[y * n + cc] = false;
                blocked[(y + 1) * n + cc] = false;
            }
        }
    }
    // Furniture: small blocks inside rooms, away from the walls.
    for wx in xs.windows(2) {
        for wy in ys.windows(2) {
            for _ in 0..2 {
                let c = wx[0] + 12 + random::below(&mut rng, wx[1] - wx[0] - 30);
                let r = wy[0] + 12 + random::below(&mut rng, wy[1] - wy[0] - 30);
                let (dw, dh) = (
                    4 + random::below(&mut rng, 8),
                    4 + random::below(&mut rng, 8),
                );
                wall(c, r, c + dw, r + dh, &mut blocked);
            }
        }
    }
    Map {
        width: n,
        height: n,
        blocked,
    }
}

/// 100 random start/goal pairs joined by a path.
fn house_queries(map: &Map, trav: &Traversability<HOUSE_CAP>) -> Vec<(Cell, Cell)> {
    let mut rng = random::seeded(7);
    let mut field = DistanceField::<HOUSE_CAP>::new_boxed();
    let mut out = Vec::new();
    let pick = |rng: &mut random::ProjectRng| loop {
        let c = Cell::new(
            random::below(rng, map.width) as i32,
            random::below(rng, map.height) as i32,
        );
        if !map.is_blocked(c) {
            return c;
        }
    };
    while out.len() < 100 {
        let a = pick(&mut rng);
        let b = pick(&mut rng);
        field.compute(trav, a).unwrap();
        if field.is_reachable(b) {
            out.push((a, b));
        }
    }
    out
}

fn check_same_costs<const N: usize>(
    map: &Map,
    trav: &Traversability<N>,
    astar: &mut AStar<N>,
    queries: &[(Cell, Cell)],
) {
    let mut expansions = 0u64;
    for &(a, b) in queries {
        let (ours, e) = astar.path_cost(trav, a, b).unwrap();
        expansions += e as u64;
        let theirs = pathfinding_cost(map, a, b).unwrap() as f32 / ORTHO as f32;
        assert!(
            (ours - theirs).abs() < 1e-2,
            "{a:?}->{b:?}: {ours} vs {theirs}"
        );
    }
    eprintln!(
        "{} queries on {} x {}: mean {:.0} expansions, {} passable cells",
        queries.len(),
        map.width,
        map.height,
        expansions as f64 / queries.len() as f64,
        map.blocked.iter().filter(|b| !**b).count()
    );
}

fn bench_planner(c: &mut Criterion) {
    let (arena_map, arena_queries) = arena();
    let arena_trav = arena_map.traversability::<ARENA_CAP>();
    let mut arena_astar = AStar::<ARENA_CAP>::new_boxed();
    check_same_costs(&arena_map, &arena_trav, &mut arena_astar, &arena_queries);

    let house_map = house();
    let house_trav = house_map.traversability::<HOUSE_CAP>();
    let queries = house_queries(&house_map, &house_trav);
    let mut house_astar = AStar::<HOUSE_CAP>::new_boxed();
    check_same_costs(&house_map, &house_trav, &mut house_astar, &queries);

    let mut g = c.benchmark_group("arena_130_queries");
    g.bench_function("papillon_astar", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(s, t) in &arena_queries {
                sum += arena_astar.path_cost(&arena_trav, s, t).unwrap().0;
            }
            black_box(sum)
        })
    });
    g.bench_function("pathfinding_astar", |b| {
        b.iter(|| {
            let mut sum = 0u64;
            for &(s, t) in &arena_queries {
                sum += pathfinding_cost(&arena_map, s, t).unwrap() as u64;
            }
            black_box(sum)
        })
    });
    g.finish();

    let mut g = c.benchmark_group("house240_100_queries");
    g.bench_function("papillon_astar", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for &(s, t) in &queries {
                sum += house_astar.path_cost(&house_trav, s, t).unwrap().0;
            }
            black_box(sum)
        })
    });
    g.bench_function("pathfinding_astar", |b| {
        b.iter(|| {
            let mut sum = 0u64;
            for &(s, t) in &queries {
                sum += pathfinding_cost(&house_map, s, t).unwrap() as u64;
            }
            black_box(sum)
        })
    });
    g.finish();

    let mut field = DistanceField::<HOUSE_CAP>::new_boxed();
    let source = queries[0].0;
    c.bench_function("house240_distance_field_sweep", |b| {
        b.iter(|| black_box(field.compute(&house_trav, source).unwrap()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = bench_planner
}
criterion_main!(benches);
