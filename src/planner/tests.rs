//! Planner tests: errors, corner cutting, and property tests against a brute-force Dijkstra.

use super::*;
use crate::geometry::Point2;
use crate::grid::{CellClass, GridGeometry, LogOddsBounds, OccupancyGrid};
use crate::random;
use core::f32::consts::FRAC_PI_2;

const CAP: usize = 32 * 24;

/// A plain O(V^2) Dijkstra over an explicit cost function, written apart from the planner's
/// code: the reference for the property tests. Returns the cost \[cells\] or `None`.
fn brute_force(
    w: i32,
    h: i32,
    cost_factor: &dyn Fn(i32, i32) -> Option<f32>,
    start: Cell,
    goal: Cell,
) -> Option<f32> {
    let n = (w * h) as usize;
    let mut dist = [f32::INFINITY; CAP];
    let mut done = [false; CAP];
    let at = |c: i32, r: i32| (r * w + c) as usize;
    cost_factor(start.col, start.row)?;
    cost_factor(goal.col, goal.row)?;
    dist[at(start.col, start.row)] = 0.0;
    loop {
        let mut best = None;
        for i in 0..n {
            if !done[i] && dist[i].is_finite() && best.is_none_or(|b: usize| dist[i] < dist[b]) {
                best = Some(i);
            }
        }
        let b = best?;
        done[b] = true;
        let (c, r) = ((b % w as usize) as i32, (b / w as usize) as i32);
        if c == goal.col && r == goal.row {
            return Some(dist[b]);
        }
        for dr in -1..=1 {
            for dc in -1..=1 {
                if dc == 0 && dr == 0 {
                    continue;
                }
                let (nc, nr) = (c + dc, r + dr);
                if nc < 0 || nr < 0 || nc >= w || nr >= h {
                    continue;
                }
                let Some(f) = cost_factor(nc, nr) else {
                    continue;
                };
                if dc != 0
                    && dr != 0
                    && (cost_factor(c + dc, r).is_none() || cost_factor(c, r + dr).is_none())
                {
                    continue;
                }
                let step = if dc != 0 && dr != 0 {
                    core::f32::consts::SQRT_2
                } else {
                    1.0
                };
                let d = dist[b] + step * f;
                if d < dist[at(nc, nr)] {
                    dist[at(nc, nr)] = d;
                }
            }
        }
    }
}

fn random_grid(
    rng: &mut random::ProjectRng,
    density: f32,
) -> (OccupancyGrid<CAP>, Traversability<CAP>) {
    let g = GridGeometry::new(32, 24, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
    let radius = [0.0, 0.1, 0.15][random::below(rng, 3)];
    let policy = if random::chance(rng, 0.5) {
        UnknownPolicy::Traversable {
            cost_factor: 1.0 + 2.0 * random::unit_f32(rng),
        }
    } else {
        UnknownPolicy::Blocked
    };
    let config = TraversabilityConfig {
        robot_radius_m: radius,
        unknown_policy: policy,
        bands: WallBands::NONE,
    };
    let mut trav = Traversability::<CAP>::new(g, config).unwrap();
    for i in 0..g.cell_count() {
        let u = random::unit_f32(rng);
        let class = if u < density {
            CellClass::Occupied
        } else if u < density + 0.2 {
            CellClass::Unknown
        } else {
            CellClass::Free
        };
        grid.set_class(i, class, &mut trav);
    }
    (grid, trav)
}

fn random_passable(rng: &mut random::ProjectRng, trav: &Traversability<CAP>) -> Option<Cell> {
    let g = trav.geometry();
    for _ in 0..200 {
        let c = g.cell(random::below(rng, g.cell_count()));
        if trav.is_passable(c) {
            return Some(c);
        }
    }
    None
}

fn assert_valid_path(trav: &Traversability<CAP>, cells: &[Cell]) {
    for c in cells {
        assert!(trav.is_passable(*c), "path enters blocked cell {c:?}");
    }
    for w in cells.windows(2) {
        let (dc, dr) = (w[1].col - w[0].col, w[1].row - w[0].row);
        assert!(
            dc.abs() <= 1 && dr.abs() <= 1 && (dc, dr) != (0, 0),
            "bad step {w:?}"
        );
        if dc != 0 && dr != 0 {
            assert!(
                trav.is_passable(Cell::new(w[0].col + dc, w[0].row)),
                "corner cut {w:?}"
            );
            assert!(
                trav.is_passable(Cell::new(w[0].col, w[0].row + dr)),
                "corner cut {w:?}"
            );
        }
    }
}

#[test]
fn astar_distance_field_and_brute_force_agree_on_random_grids() {
    let mut rng = random::seeded(3);
    let mut astar = AStar::<CAP>::new();
    let mut field = DistanceField::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let mut compared = 0;
    let mut unreachable = 0;
    for case in 0..150 {
        let density = [0.1, 0.25, 0.35][case % 3];
        let (_, trav) = random_grid(&mut rng, density);
        let Some(start) = random_passable(&mut rng, &trav) else {
            continue;
        };
        field.compute(&trav, start).unwrap();
        for _ in 0..4 {
            let Some(goal) = random_passable(&mut rng, &trav) else {
                continue;
            };
            let factor = |c: i32, r: i32| trav.cost_factor(Cell::new(c, r));
            let expected = brute_force(32, 24, &factor, start, goal);
            let got = astar.find_path(&trav, start, goal, &mut path);
            match expected {
                None => {
                    unreachable += 1;
                    assert_eq!(got, Err(PlanError::NoPath { start, goal }));
                    assert_eq!(field.distance_to(goal), None);
                }
                Some(cost) => {
                    compared += 1;
                    let cost_m = cost * 0.1;
                    let p = got.unwrap();
                    assert!(
                        (p.cost_m - cost_m).abs() < 1e-4,
                        "case {case}: A* {} vs {cost_m}",
                        p.cost_m
                    );
                    let d = field.distance_to(goal).unwrap();
                    assert!(
                        (d - cost_m).abs() < 1e-4,
                        "case {case}: field {d} vs {cost_m}"
                    );
                    assert_eq!(path[0], start);
                    assert_eq!(path[p.len - 1], goal);
                    assert_valid_path(&trav, &path[..p.len]);
                    let q = field.path_to(goal, &mut path).unwrap();
                    assert!((q.cost_m - cost_m).abs() < 1e-4);
                    assert_valid_path(&trav, &path[..q.len]);
                    assert_eq!(path[0], start);
                    assert_eq!(path[q.len - 1], goal);
                }
            }
        }
    }
    assert!(compared > 300, "only {compared} reachable pairs");
    assert!(unreachable > 10, "only {unreachable} unreachable pairs");
}

#[test]
fn diagonal_moves_never_cut_corners() {
    // 3 x 3 with the east and north neighbours of (0, 0) blocked in turn: the diagonal to
    // (1, 1) is forbidden, the path goes round.
    let mut astar = AStar::<9>::new();
    let mut path = [Cell::default(); 9];
    let t = Traversability::<9>::from_blocked(3, 3, |c| c == Cell::new(1, 0)).unwrap();
    let p = astar
        .find_path(&t, Cell::new(0, 0), Cell::new(1, 1), &mut path)
        .unwrap();
    assert_eq!(
        &path[..p.len],
        &[Cell::new(0, 0), Cell::new(0, 1), Cell::new(1, 1)]
    );
    assert_eq!(p.length_m, 2.0);
    let t = Traversability::<9>::from_blocked(3, 3, |c| c == Cell::new(0, 1)).unwrap();
    let p = astar
        .find_path(&t, Cell::new(0, 0), Cell::new(1, 1), &mut path)
        .unwrap();
    assert_eq!(p.len, 3);
    assert_eq!(p.length_m, 2.0);
    // Both blocked: the diagonal gap is closed.
    let t =
        Traversability::<9>::from_blocked(3, 3, |c| c == Cell::new(0, 1) || c == Cell::new(1, 0))
            .unwrap();
    assert_eq!(
        astar.find_path(&t, Cell::new(0, 0), Cell::new(1, 1), &mut path),
        Err(PlanError::NoPath {
            start: Cell::new(0, 0),
            goal: Cell::new(1, 1)
        })
    );
    // Open: one diagonal step.
    let t = Traversability::<9>::from_blocked(3, 3, |_| false).unwrap();
    let p = astar
        .find_path(&t, Cell::new(0, 0), Cell::new(1, 1), &mut path)
        .unwrap();
    assert_eq!(p.len, 2);
    assert!((p.length_m - core::f32::consts::SQRT_2).abs() < 1e-6);
}

#[test]
fn errors_name_the_problem() {
    let t = Traversability::<16>::from_blocked(4, 4, |c| c == Cell::new(2, 2)).unwrap();
    let mut astar = AStar::<16>::new();
    let mut path = [Cell::default(); 16];
    assert_eq!(
        astar.find_path(&t, Cell::new(2, 2), Cell::new(0, 0), &mut path),
        Err(PlanError::StartBlocked {
            cell: Cell::new(2, 2)
        })
    );
    assert_eq!(
        astar.find_path(&t, Cell::new(0, 0), Cell::new(2, 2), &mut path),
        Err(PlanError::GoalBlocked {
            cell: Cell::new(2, 2)
        })
    );
    assert_eq!(
        astar.find_path(&t, Cell::new(0, 0), Cell::new(4, 0), &mut path),
        Err(PlanError::OutOfBounds {
            cell: Cell::new(4, 0),
            width: 4,
            height: 4
        })
    );
    let mut short = [Cell::default(); 3];
    assert_eq!(
        astar.find_path(&t, Cell::new(0, 0), Cell::new(3, 0), &mut short),
        Err(PlanError::CapacityExceeded {
            needed: 4,
            capacity: 3
        })
    );
    let mut small = AStar::<8>::new();
    assert_eq!(
        small.find_path(&t, Cell::new(0, 0), Cell::new(3, 3), &mut path),
        Err(PlanError::CapacityExceeded {
            needed: 16,
            capacity: 8
        })
    );
    let p = astar
        .find_path(&t, Cell::new(1, 1), Cell::new(1, 1), &mut path)
        .unwrap();
    assert_eq!((p.len, p.length_m), (1, 0.0));
    let msg = std::format!(
        "{}",
        PlanError::GoalBlocked {
            cell: Cell::new(2, 2)
        }
    );
    assert_eq!(msg, "goal cell (2, 2) is blocked");
}

#[test]
fn unknown_cells_cost_their_factor() {
    // A corridor of Unknown cells straight ahead, a Free detour around it.
    let g = GridGeometry::new(7, 3, 1.0, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<21>::new(g, LogOddsBounds::default()).unwrap();
    let config = TraversabilityConfig {
        robot_radius_m: 0.0,
        unknown_policy: UnknownPolicy::Traversable { cost_factor: 3.0 },
        bands: WallBands::NONE,
    };
    let mut t = Traversability::<21>::new(g, config).unwrap();
    for i in 0..21 {
        if g.cell(i).row != 1 || matches!(g.cell(i).col, 0 | 6) {
            grid.set_class(i, CellClass::Free, &mut t);
        }
    }
    let mut astar = AStar::<21>::new();
    let mut path = [Cell::default(); 21];
    let p = astar
        .find_path(&t, Cell::new(0, 1), Cell::new(6, 1), &mut path)
        .unwrap();
    // Straight through five Unknown cells: 5 * 3 + 1 = 16; detour: 2 diagonals + 4 = 6.83.
    assert!((p.cost_m - (4.0 + 2.0 * core::f32::consts::SQRT_2)).abs() < 1e-5);
    assert!((p.length_m - p.cost_m).abs() < 1e-5);
    t.set_config(TraversabilityConfig {
        robot_radius_m: 0.0,
        unknown_policy: UnknownPolicy::Traversable { cost_factor: 1.0 },
        bands: WallBands::NONE,
    })
    .unwrap();
    let p = astar
        .find_path(&t, Cell::new(0, 1), Cell::new(6, 1), &mut path)
        .unwrap();
    assert!((p.cost_m - 6.0).abs() < 1e-5);
}

#[test]
fn memory_is_reused_across_many_queries() {
    let mut rng = random::seeded(8);
    let (_, trav) = random_grid(&mut rng, 0.2);
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let (Some(a), Some(b)) = (
        random_passable(&mut rng, &trav),
        random_passable(&mut rng, &trav),
    ) else {
        panic!("no passable cells");
    };
    let first = astar.find_path(&trav, a, b, &mut path);
    for _ in 0..1000 {
        let c = random_passable(&mut rng, &trav).unwrap();
        let _ = astar.find_path(&trav, c, a, &mut path);
    }
    assert_eq!(astar.find_path(&trav, a, b, &mut path), first);
}

/// Whether the segment `p`-`q` touches the closed square `[x0, x0 + 1] x [y0, y0 + 1]`
/// (Liang–Barsky clipping), an independent check of the supercover traversal.
fn segment_touches_square(p: (f64, f64), q: (f64, f64), x0: f64, y0: f64) -> bool {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (pk, qk) in [
        (-dx, p.0 - x0),
        (dx, x0 + 1.0 - p.0),
        (-dy, p.1 - y0),
        (dy, y0 + 1.0 - p.1),
    ] {
        if pk == 0.0 {
            if qk < 0.0 {
                return false;
            }
        } else {
            let r = qk / pk;
            if pk < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    t0 <= t1
}

#[test]
fn waypoint_segments_never_touch_blocked_cells() {
    let mut rng = random::seeded(21);
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let mut out = [Point2::default(); CAP];
    let mut pruned = 0usize;
    let mut checked = 0usize;
    for case in 0..200 {
        let (_, trav) = random_grid(&mut rng, [0.05, 0.15, 0.3][case % 3]);
        let (Some(a), Some(b)) = (
            random_passable(&mut rng, &trav),
            random_passable(&mut rng, &trav),
        ) else {
            continue;
        };
        let Ok(p) = astar.find_path(&trav, a, b, &mut path) else {
            continue;
        };
        let n = prune_to_waypoints(&trav, &path[..p.len], &mut out).unwrap();
        assert!(n >= 1 && n <= p.len);
        pruned += p.len - n;
        let g = *trav.geometry();
        assert_eq!(g.cell_at(out[0]), Some(a));
        assert_eq!(g.cell_at(out[n - 1]), Some(b));
        for w in out[..n].windows(2) {
            // Segment in cell units.
            let to_cells = |pt: Point2| ((pt.x / 0.1) as f64, (pt.y / 0.1) as f64);
            let (p0, p1) = (to_cells(w[0]), to_cells(w[1]));
            // Round to the exact half-cell centres the waypoints stand for.
            let snap = |v: f64| (v - 0.5).round() + 0.5;
            let (p0, p1) = ((snap(p0.0), snap(p0.1)), (snap(p1.0), snap(p1.1)));
            for i in 0..g.cell_count() {
                let c = g.cell(i);
                if !trav.is_passable(c) {
                    checked += 1;
                    assert!(
                        !segment_touches_square(p0, p1, c.col as f64, c.row as f64),
                        "case {case}: segment {p0:?}-{p1:?} touches blocked {c:?}"
                    );
                }
            }
        }
    }
    assert!(pruned > 500, "pruning removed only {pruned} cells");
    assert!(checked > 10_000);
}

#[test]
fn supercover_includes_both_cells_at_a_corner() {
    let mut seen = [Cell::default(); 8];
    let mut n = 0;
    supercover_all(Cell::new(0, 0), Cell::new(2, 2), &mut seen, &mut n);
    assert_eq!(
        &seen[..n],
        &[
            Cell::new(0, 0),
            Cell::new(1, 0),
            Cell::new(0, 1),
            Cell::new(1, 1),
            Cell::new(2, 1),
            Cell::new(1, 2),
            Cell::new(2, 2)
        ]
    );
    // Straight line along a row: only the row's cells.
    supercover_all(Cell::new(0, 0), Cell::new(3, 0), &mut seen, &mut n);
    assert_eq!(
        &seen[..n],
        &[
            Cell::new(0, 0),
            Cell::new(1, 0),
            Cell::new(2, 0),
            Cell::new(3, 0)
        ]
    );
}

fn supercover_all(a: Cell, b: Cell, seen: &mut [Cell], n: &mut usize) {
    *n = 0;
    waypoints::supercover(a, b, |c| {
        seen[*n] = c;
        *n += 1;
        true
    });
}

#[test]
fn straight_line_double_checks_endpoints() {
    let t = Traversability::<16>::from_blocked(4, 4, |c| c == Cell::new(2, 2)).unwrap();
    let mut planner = StraightLinePlanner;
    let mut path = [Cell::default(); 2];
    let p = planner
        .plan(&t, Cell::new(0, 0), Cell::new(3, 3), &mut path)
        .unwrap();
    assert_eq!(p.len, 2);
    assert!((p.length_m - crate::math::sqrt(18.0)).abs() < 1e-5);
    assert_eq!(
        planner.plan(&t, Cell::new(0, 0), Cell::new(2, 2), &mut path),
        Err(PlanError::GoalBlocked {
            cell: Cell::new(2, 2)
        })
    );
}

#[test]
fn planners_are_interchangeable() {
    fn cost<P: Planner<CAP>>(p: &mut P, t: &Traversability<CAP>, a: Cell, b: Cell) -> f32 {
        let mut path = [Cell::default(); CAP];
        p.plan(t, a, b, &mut path).unwrap().cost_m
    }
    let trav = Traversability::<CAP>::from_blocked(32, 24, |c| c.col == 10 && c.row < 20).unwrap();
    let (a, b) = (Cell::new(1, 1), Cell::new(30, 20));
    let x = cost(&mut AStar::<CAP>::new(), &trav, a, b);
    let y = cost(&mut DistanceField::<CAP>::new(), &trav, a, b);
    assert!((x - y).abs() < 1e-5);
}

/// The distance field's bucket queue settles every cell at the cost the radix heap finds, bit
/// for bit, and closes the same cells; with steps too long for the buckets (a large Unknown
/// cost factor) the sweep keeps the radix heap and still agrees with the reference.
#[test]
fn the_bucket_queue_finds_the_radix_heap_costs_bit_for_bit() {
    use super::search::{DIAGONAL, SearchMemory, StepCosts, Zero};
    let mut rng = random::seeded(17);
    let mut radix = crate::heap::boxed_zeroed::<SearchMemory<CAP>>();
    let mut buckets = crate::heap::boxed_zeroed::<SearchMemory<CAP>>();
    let mut field = DistanceField::<CAP>::new();
    let mut checked_cells = 0;
    for (case, factor) in [1.0f32, 1.0, 1.6, 2.9, 30.0, 43.0, 45.0, 250.0]
        .into_iter()
        .cycle()
        .take(48)
        .enumerate()
    {
        let (mut grid, mut trav) = random_grid(&mut rng, [0.1, 0.25][case % 2]);
        let config = TraversabilityConfig {
            unknown_policy: UnknownPolicy::Traversable {
                cost_factor: factor,
            },
            ..trav.config()
        };
        trav.set_config(config).unwrap();
        grid.set_class(0, CellClass::Unknown, &mut trav);
        let Some(start) = random_passable(&mut rng, &trav) else {
            continue;
        };
        let g = *trav.geometry();
        let s = g.index(start).unwrap();
        let costs = StepCosts::of(&trav);
        radix.start(s, g.width, Zero);
        let (closed_radix, _) = radix.resume(&costs, usize::MAX, Zero);
        buckets.start_sweep(s, g.width, g.cell_count(), DIAGONAL * factor);
        let (closed_buckets, _) = buckets.resume(&costs, usize::MAX, Zero);
        assert_eq!(closed_radix, closed_buckets, "case {case}");
        let (gr, gb) = (radix.generation(), buckets.generation());
        for i in 0..g.cell_count() {
            assert_eq!(radix.is_closed_in(i, gr), buckets.is_closed_in(i, gb));
            if radix.is_closed_in(i, gr) {
                assert_eq!(radix.g(i).to_bits(), buckets.g(i).to_bits(), "case {case}");
                checked_cells += 1;
            }
        }
        // And the field built on it agrees with the reference Dijkstra.
        field.compute(&trav, start).unwrap();
        let factor_of = |c: i32, r: i32| trav.cost_factor(Cell::new(c, r));
        for _ in 0..3 {
            let Some(goal) = random_passable(&mut rng, &trav) else {
                continue;
            };
            let expected = brute_force(32, 24, &factor_of, start, goal).map(|c| c * 0.1);
            match (expected, field.distance_to(goal)) {
                (Some(e), Some(d)) => assert!((e - d).abs() <= 1e-4 * e.max(1.0), "case {case}"),
                (e, d) => assert_eq!(e, d, "case {case}"),
            }
        }
    }
    assert!(
        checked_cells > 10_000,
        "only {checked_cells} cells compared"
    );
}

/// The planning layer of a P3-DX (0.381 m wide, 0.267 m swing radius) with 5 cm of clearance
/// at 0.1 m cells (`mission::footprint`): blocked within 0.29 m of a wall's cell centre, no
/// turning within 0.367 m, near-wall cost within 0.517 m.
fn p3dx_bands() -> TraversabilityConfig {
    TraversabilityConfig {
        robot_radius_m: 0.1905 + 0.05 + 0.05,
        unknown_policy: UnknownPolicy::Traversable { cost_factor: 1.0 },
        bands: WallBands {
            no_turn_radius_m: 0.267 + 0.05 + 0.05,
            no_turn_cost_factor: 2.0,
            near_radius_m: 0.267 + 0.05 + 0.05 + 0.15,
            near_cost_factor: 1.3,
        },
    }
}

/// A 4 m x 3 m room of Free cells at 0.1 m, split by a wall along row 15 with one opening of
/// `door_cells` cells starting at column 18.
fn wall_with_door(door_cells: i32) -> (OccupancyGrid<CAP>, Traversability<CAP>) {
    let g = GridGeometry::new(32, 24, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
    let mut trav = Traversability::<CAP>::new(g, p3dx_bands()).unwrap();
    for i in 0..g.cell_count() {
        let c = g.cell(i);
        let in_wall = c.row == 15 && !(18..18 + door_cells).contains(&c.col);
        let class = if in_wall {
            CellClass::Occupied
        } else {
            CellClass::Free
        };
        grid.set_class(i, class, &mut trav);
    }
    (grid, trav)
}

#[test]
fn a_p3dx_passes_a_half_metre_door_and_never_a_forty_centimetre_one() {
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let (a, b) = (Cell::new(8, 5), Cell::new(24, 21));
    let (_, trav) = wall_with_door(5);
    let p = astar.find_path(&trav, a, b, &mut path).expect("0.5 m door");
    assert_valid_path(&trav, &path[..p.len]);
    // Through the door's middle column, where the robot fits straight but cannot turn.
    let door = Cell::new(20, 15);
    assert!(path[..p.len].contains(&door));
    assert!(trav.is_passable(door) && !trav.can_turn(door));
    assert_eq!(trav.wall_band(Cell::new(8, 5)), Some(0));
    let (_, trav) = wall_with_door(4);
    assert!(matches!(
        astar.find_path(&trav, a, b, &mut path),
        Err(PlanError::NoPath { .. })
    ));
}

#[test]
fn paths_keep_away_from_walls_where_there_is_room() {
    // Along a wall, the cheapest path runs outside the near-wall band.
    let g = GridGeometry::new(32, 24, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
    let mut trav = Traversability::<CAP>::new(g, p3dx_bands()).unwrap();
    for i in 0..g.cell_count() {
        let c = g.cell(i);
        let class = if c.row == 0 {
            CellClass::Occupied
        } else {
            CellClass::Free
        };
        grid.set_class(i, class, &mut trav);
    }
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    // From 0.3 m off the wall to 0.3 m off it, 2.5 m further: the path moves out first.
    let p = astar
        .find_path(&trav, Cell::new(3, 3), Cell::new(28, 3), &mut path)
        .unwrap();
    let far = path[..p.len]
        .iter()
        .filter(|c| trav.wall_band(**c) == Some(0));
    assert!(
        far.count() * 2 > p.len,
        "most of the path is clear of the band"
    );
}

#[test]
fn waypoints_through_a_door_turn_outside_the_no_turn_band() {
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let mut out = [Point2::default(); CAP];
    let (_, trav) = wall_with_door(5);
    let (a, b) = (Cell::new(4, 4), Cell::new(28, 20));
    let p = astar.find_path(&trav, a, b, &mut path).unwrap();
    let n = prune_to_waypoints(&trav, &path[..p.len], &mut out).unwrap();
    let g = *trav.geometry();
    for (k, w) in out[..n].iter().enumerate() {
        let c = g.cell_at(*w).unwrap();
        assert!(
            trav.can_turn(c),
            "waypoint {k} at {c:?} is in the no-turn band"
        );
    }
    // Every leg stays within the bands its stretch of path went through: no leg cuts a
    // corner of the door frame.
    for w in out[..n].windows(2) {
        let (c0, c1) = (g.cell_at(w[0]).unwrap(), g.cell_at(w[1]).unwrap());
        assert!(has_line_of_sight(&trav, c0, c1));
    }
}

/// The pruned waypoints of the A* path from `a` to `b` on `trav`.
fn waypoints_between(trav: &Traversability<CAP>, a: Cell, b: Cell) -> Vec<Point2> {
    let mut astar = AStar::<CAP>::new();
    let mut path = [Cell::default(); CAP];
    let mut out = [Point2::default(); CAP];
    let p = astar.find_path(trav, a, b, &mut path).unwrap();
    let n = prune_to_waypoints(trav, &path[..p.len], &mut out).unwrap();
    out[..n].to_vec()
}

#[test]
fn the_leg_through_a_narrow_door_runs_along_its_axis() {
    // A 0.5 m door in a wall along row 15 (cells 18..22), approached from far to the side on
    // both sides: the leg that crosses the wall runs down the door's middle column, so the
    // robot enters it square, not at a slant.
    let (_, trav) = wall_with_door(5);
    let g = *trav.geometry();
    for (a, b) in [
        (Cell::new(4, 4), Cell::new(28, 20)),
        (Cell::new(30, 3), Cell::new(2, 22)),
        (Cell::new(12, 10), Cell::new(26, 19)),
        // A straight line between these stays in the door's middle column through the
        // channel, at a slant of 6°.
        (Cell::new(19, 2), Cell::new(21, 22)),
        (Cell::new(21, 3), Cell::new(19, 23)),
    ] {
        let crossing = waypoints_between(&trav, a, b)
            .windows(2)
            .map(|w| (g.cell_at(w[0]).unwrap(), g.cell_at(w[1]).unwrap()))
            .find(|(c0, c1)| c0.row < 15 && c1.row > 15)
            .expect("a leg crosses the wall");
        assert_eq!(
            (crossing.0.col, crossing.1.col),
            (20, 20),
            "{a:?} -> {b:?}: leg {crossing:?}"
        );
    }
}

#[test]
fn a_leg_into_a_narrow_door_from_the_side_comes_along_its_axis() {
    // The same 0.5 m door (axis: column 20), the robot to the side of it and close (issue 17:
    // it drove at the last cell before the door at a slant, its front corner towards the
    // jamb, and the safety monitor stopped it there again and again). The waypoint before the
    // leg through the door is reached along the door's axis, from an approach point on that
    // axis where the robot can turn; every leg stays in sight.
    let (_, trav) = wall_with_door(5);
    let g = *trav.geometry();
    for (a, b) in [
        (Cell::new(23, 10), Cell::new(20, 21)),
        (Cell::new(17, 9), Cell::new(20, 21)),
        (Cell::new(24, 21), Cell::new(20, 8)),
        (Cell::new(4, 4), Cell::new(28, 20)),
        (Cell::new(30, 3), Cell::new(2, 22)),
    ] {
        let w = &waypoints_between(&trav, a, b)[..];
        let i = w
            .windows(2)
            .position(|s| (s[0].y - 1.55) * (s[1].y - 1.55) < 0.0)
            .expect("a leg crosses the wall");
        assert!(
            i >= 1,
            "{a:?} -> {b:?}: the first leg crosses the door: {w:?}"
        );
        let (before, at) = (w[i - 1], w[i]);
        let axis = if w[i + 1].y > at.y {
            FRAC_PI_2
        } else {
            -FRAC_PI_2
        };
        let skew = crate::geometry::normalize_angle(before.bearing_to(at) - axis);
        assert!(
            skew.abs() <= 0.1,
            "{a:?} -> {b:?}: the leg into {at:?} comes {skew} rad off the door's axis: {w:?}"
        );
        assert!(
            trav.can_turn(g.cell_at(before).unwrap()),
            "{a:?} -> {b:?}: {w:?}"
        );
        for s in w.windows(2) {
            let (c0, c1) = (g.cell_at(s[0]).unwrap(), g.cell_at(s[1]).unwrap());
            assert!(has_line_of_sight(&trav, c0, c1), "{a:?} -> {b:?}: {w:?}");
        }
    }
}

#[test]
fn banded_layer_updated_incrementally_equals_a_rebuild() {
    let g = GridGeometry::new(32, 24, 0.1, Point2::new(0.0, 0.0)).unwrap();
    let mut rng = random::seeded(5);
    let mut grid = OccupancyGrid::<CAP>::new(g, LogOddsBounds::default()).unwrap();
    let mut t = Traversability::<CAP>::new(g, p3dx_bands()).unwrap();
    for step in 0..6000 {
        let i = random::below(&mut rng, g.cell_count());
        let class = match random::below(&mut rng, 3) {
            0 => CellClass::Occupied,
            1 => CellClass::Free,
            _ => CellClass::Unknown,
        };
        grid.set_class(i, class, &mut t);
        if step % 1000 == 999 {
            let mut fresh = Traversability::<CAP>::new(g, p3dx_bands()).unwrap();
            fresh.rebuild_from(&grid).unwrap();
            assert!(t.same_state(&fresh), "step {step}");
        }
    }
}
