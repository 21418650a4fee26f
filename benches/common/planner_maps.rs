//! Maps and queries shared by the planner benchmark (`benches/planner.rs`) and the
//! instruction-count harness (`examples/planner_count.rs`): the Moving AI arena problems, a
//! deterministic 240 x 240 house-like map with 100 random queries, and the successor function
//! that lets the `pathfinding` crate search the same moves.

#![allow(dead_code)]

use papillon::grid::Cell;
use papillon::planner::{DistanceField, Traversability};
use papillon::random;

pub const ARENA_CAP: usize = 49 * 49;
pub const HOUSE_SIDE: usize = 240;
pub const HOUSE_CAP: usize = HOUSE_SIDE * HOUSE_SIDE;

/// Integer step costs for `pathfinding` (which needs `Ord` costs): 1 and sqrt(2) scaled.
pub const ORTHO: u32 = 10_000;
pub const DIAG: u32 = 14_142;

/// A blocked map, row 0 south, index `row * width + col`.
pub struct Map {
    pub width: usize,
    pub height: usize,
    pub blocked: Vec<bool>,
}

impl Map {
    pub fn is_blocked(&self, c: Cell) -> bool {
        c.col < 0
            || c.row < 0
            || c.col as usize >= self.width
            || c.row as usize >= self.height
            || self.blocked[c.row as usize * self.width + c.col as usize]
    }

    pub fn traversability<const N: usize>(&self) -> Box<Traversability<N>> {
        Traversability::<N>::from_blocked_boxed(self.width, self.height, |c| self.is_blocked(c))
            .unwrap()
    }

    /// Successors for `pathfinding`: the same move rules as Papillon's planner.
    pub fn successors(&self, c: Cell) -> Vec<(Cell, u32)> {
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

pub fn octile_int(a: Cell, b: Cell) -> u32 {
    let dc = a.col.abs_diff(b.col);
    let dr = a.row.abs_diff(b.row);
    let (lo, hi) = (dc.min(dr), dc.max(dr));
    (hi - lo) * ORTHO + lo * DIAG
}

pub fn pathfinding_cost(map: &Map, a: Cell, b: Cell) -> Option<u32> {
    pathfinding::prelude::astar(
        &a,
        |c| map.successors(*c),
        |c| octile_int(*c, b),
        |c| *c == b,
    )
    .map(|(_, cost)| cost)
}

/// The Moving AI arena map and its problems, converted to row 0 south.
pub fn arena() -> (Map, Vec<(Cell, Cell)>) {
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
pub fn house() -> Map {
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
pub fn house_queries(map: &Map, trav: &Traversability<HOUSE_CAP>) -> Vec<(Cell, Cell)> {
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
