//! The project's own worlds, drawn in code with rectangles (deterministic, any resolution).
//!
//! All coordinates are in the map frame \[m\] from the south-west corner; a rectangle blocks
//! every cell whose centre lies inside it. Every world starts at (1 m, 1 m), heading east, with
//! outer walls thin enough (0.5 m or less) that a P3-DX (radius 0.25 m) sits there clear of
//! them.
//!
//! - `empty`: 24 m x 24 m, 0.5 m outer walls only.
//! - `house`: 24 m x 24 m, living room, kitchen, bathroom, hall and bedrooms behind 1 m
//!   walls on a metre lattice (after the style of the thesis's House map, not a copy of it),
//!   doors 1.5 m wide and some furniture; about 27 % of the area is blocked.
//! - `factory`: 30 m x 50 m: storage racks with 1 m aisles (some closed at one end: dead ends),
//!   a machine hall, an office block and a 0.9 m corridor to a dead-end store room.
//! - `lab`: 8 m x 8 m, two rooms joined by a 1 m door, for quick end-to-end tests.

use papillon::geometry::Point2;
use papillon::grid::GridGeometry;

use super::{World, WorldError};

/// Names of the built-in worlds.
pub const NAMES: [&str; 4] = ["empty", "house", "factory", "lab"];

/// The built-in world called `name`, or `None` if there is no such built-in world.
pub fn by_name(name: &str, resolution_m: f32) -> Option<Result<World, WorldError>> {
    let build: fn(f32) -> Result<World, WorldError> = match name {
        "empty" => empty,
        "house" => house,
        "factory" => factory,
        "lab" => lab,
        _ => return None,
    };
    Some(build(resolution_m))
}

fn blank(name: &str, width_m: f32, height_m: f32, resolution_m: f32) -> Result<World, WorldError> {
    let resolution_m = super::check_resolution(resolution_m)?;
    let g = GridGeometry::from_extent(width_m, height_m, resolution_m, Point2::default())?;
    super::check_size(name, &g, super::RESOLUTION_FLAG)?;
    Ok(World::new(name, g))
}

/// Blocks rectangles given as `(x0, y0, x1, y1)` \[m\].
fn draw(w: &mut World, rects: &[(f32, f32, f32, f32)]) {
    for &(x0, y0, x1, y1) in rects {
        w.fill_rect(x0, y0, x1, y1, true);
    }
}

/// Frees rectangles (doors) given as `(x0, y0, x1, y1)` \[m\].
fn open(w: &mut World, rects: &[(f32, f32, f32, f32)]) {
    for &(x0, y0, x1, y1) in rects {
        w.fill_rect(x0, y0, x1, y1, false);
    }
}

fn outer_walls(w: &mut World, thickness_m: f32) {
    let (wm, hm) = (w.geometry().width_m(), w.geometry().height_m());
    let t = thickness_m;
    draw(
        w,
        &[
            (0.0, 0.0, wm, t),
            (0.0, hm - t, wm, hm),
            (0.0, 0.0, t, hm),
            (wm - t, 0.0, wm, hm),
        ],
    );
}

/// 24 m x 24 m, outer walls only.
pub fn empty(resolution_m: f32) -> Result<World, WorldError> {
    let mut w = blank("empty", 24.0, 24.0, resolution_m)?;
    outer_walls(&mut w, 0.5);
    Ok(w)
}

/// The house's doorways `(x0, y0, x1, y1)` \[m\], each 1.5 m wide, for scheduling doors
/// ([`crate::dynamic::Door`]).
pub const HOUSE_DOORS: [(f32, f32, f32, f32); 10] = [
    // Living room <-> kitchen, kitchen <-> bathroom.
    (9.0, 6.0, 10.0, 7.5),
    (17.0, 3.5, 18.0, 5.0),
    // Hall doors to the south rooms.
    (4.0, 8.0, 5.5, 9.0),
    (14.0, 8.0, 15.5, 9.0),
    (20.0, 8.0, 21.5, 9.0),
    // Hall doors to the north rooms.
    (3.0, 12.0, 4.5, 13.0),
    (10.0, 12.0, 11.5, 13.0),
    (19.5, 12.0, 21.0, 13.0),
    // Study <-> north-east bedroom, west bedroom <-> middle bedroom.
    (19.0, 17.5, 20.5, 18.5),
    (7.0, 18.0, 8.0, 19.5),
];

/// The lab's doorway `(x0, y0, x1, y1)` \[m\] (1 m wide, in the wall between the rooms).
pub const LAB_DOOR: (f32, f32, f32, f32) = (3.9, 4.0, 4.1, 5.0);

/// 24 m x 24 m house: rooms, doors and a hall, about 27 % blocked.
pub fn house(resolution_m: f32) -> Result<World, WorldError> {
    let mut w = blank("house", 24.0, 24.0, resolution_m)?;
    outer_walls(&mut w, 0.5);
    draw(
        &mut w,
        &[
            // South rooms: living room (west), kitchen, bathroom (east); walls 1 m thick.
            (9.0, 0.5, 10.0, 8.0),
            (17.0, 0.5, 18.0, 8.0),
            // Hall between y = 9 and y = 12, closed by two long walls.
            (0.5, 8.0, 23.5, 9.0),
            (0.5, 12.0, 23.5, 13.0),
            // North: three bedrooms and a study.
            (7.0, 13.0, 8.0, 23.5),
            (15.0, 13.0, 16.0, 23.5),
            (16.0, 17.5, 23.5, 18.5),
            // Furniture: sofa and table (living room), counter and island (kitchen),
            // bath (bathroom), beds (bedrooms), desk (study), a closet.
            (3.0, 4.0, 6.0, 5.0),
            (0.5, 6.5, 2.5, 8.0),
            (10.0, 0.5, 13.0, 1.5),
            (12.0, 4.0, 14.5, 5.0),
            (21.5, 0.5, 23.5, 2.0),
            (4.0, 14.5, 6.0, 17.0),
            (9.5, 21.0, 12.0, 23.5),
            (21.0, 14.5, 23.5, 16.5),
            (21.5, 21.5, 23.5, 23.5),
            (0.5, 21.5, 2.5, 23.5),
        ],
    );
    open(&mut w, &HOUSE_DOORS);
    Ok(w)
}

/// 30 m x 50 m factory: racks, machines, narrow corridors and dead ends.
pub fn factory(resolution_m: f32) -> Result<World, WorldError> {
    let mut w = blank("factory", 30.0, 50.0, resolution_m)?;
    outer_walls(&mut w, 0.5);
    // Storage (y 3..17): racks 1 m deep, 12 m long, separated by 1 m aisles; every third
    // aisle is closed at its north end (a dead end).
    let mut x = 3.0;
    let mut aisle = 0;
    while x + 1.0 <= 27.5 {
        draw(&mut w, &[(x, 4.0, x + 1.0, 16.0)]);
        if aisle % 3 == 2 && x + 2.0 <= 27.5 {
            draw(&mut w, &[(x + 1.0, 15.0, x + 2.0, 16.0)]);
        }
        aisle += 1;
        x += 2.0;
    }
    // Loading bays along the south wall.
    for i in 0..5 {
        let x0 = 2.0 + i as f32 * 5.5;
        draw(&mut w, &[(x0, 0.5, x0 + 1.5, 1.5)]);
    }
    // Partition between storage and the machine hall, three 2 m openings.
    draw(&mut w, &[(0.5, 19.5, 29.5, 20.0)]);
    open(
        &mut w,
        &[
            (2.0, 19.5, 4.0, 20.0),
            (14.0, 19.5, 16.0, 20.0),
            (25.0, 19.5, 27.0, 20.0),
        ],
    );
    // Machine hall (y 20..36): 2 m x 3 m machines on a lattice, 2 m lanes.
    for row in 0..4 {
        for col in 0..6 {
            let x0 = 2.5 + col as f32 * 4.0 + if row % 2 == 1 { 1.0 } else { 0.0 };
            let y0 = 21.5 + row as f32 * 3.5;
            draw(&mut w, &[(x0, y0, x0 + 2.0, y0 + 2.0)]);
        }
    }
    // Office block (north-west, y 37..49.5): thin walls, 1 m doors.
    draw(
        &mut w,
        &[
            (0.5, 37.0, 14.0, 37.3),
            (13.7, 37.0, 14.0, 49.5),
            (0.5, 43.0, 13.7, 43.3),
            (7.0, 37.3, 7.3, 43.0),
        ],
    );
    open(
        &mut w,
        &[
            (4.0, 37.0, 5.0, 37.3),
            (10.0, 37.0, 11.0, 37.3),
            (13.7, 46.0, 14.0, 47.0),
            (2.0, 43.0, 3.0, 43.3),
        ],
    );
    // Narrow corridor (0.9 m clear) from the machine hall north to a dead-end store room.
    draw(
        &mut w,
        &[
            (16.0, 37.0, 22.0, 38.0),
            (23.0, 37.0, 25.0, 38.0),
            (21.0, 38.0, 22.1, 45.0),
            (23.0, 38.0, 24.0, 45.0),
            (16.0, 45.0, 22.1, 46.0),
            (23.0, 45.0, 29.5, 46.0),
        ],
    );
    // Store room beyond it (y 46..49.5, open to the corridor) with shelving.
    draw(
        &mut w,
        &[(25.0, 47.5, 29.0, 48.5), (16.5, 47.5, 20.5, 48.5)],
    );
    // East of the corridor, open to the hall: two 1 m bays between walls (dead ends).
    draw(
        &mut w,
        &[(26.0, 38.0, 26.5, 44.0), (27.5, 38.0, 28.0, 44.0)],
    );
    Ok(w)
}

/// 8 m x 8 m lab: two rooms joined by a 1 m door.
pub fn lab(resolution_m: f32) -> Result<World, WorldError> {
    let mut w = blank("lab", 8.0, 8.0, resolution_m)?;
    outer_walls(&mut w, 0.3);
    draw(&mut w, &[(3.9, 0.3, 4.1, 7.7), (5.5, 5.5, 6.5, 6.5)]);
    open(&mut w, &[LAB_DOOR]);
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::grid::Cell;
    use std::collections::VecDeque;

    /// Free cells whose centres are at least `clear_m` from every blocked cell, 8-connected to
    /// the start: where a robot of radius `clear_m` can drive.
    fn drivable(w: &World, clear_m: f32) -> (Vec<bool>, Vec<bool>) {
        let g = *w.geometry();
        let ok: Vec<bool> = (0..g.cell_count())
            .map(|i| !w.disc_hits_blocked(g.cell_center(g.cell(i)), clear_m))
            .collect();
        let mut seen = vec![false; ok.len()];
        let start = g.index(w.start_cell().unwrap()).unwrap();
        assert!(ok[start], "{}: start is not clear by {clear_m} m", w.name());
        let mut q = VecDeque::from([start]);
        seen[start] = true;
        while let Some(i) = q.pop_front() {
            let c = g.cell(i);
            for dr in -1..=1 {
                for dc in -1..=1 {
                    if let Some(j) = g.index(Cell::new(c.col + dc, c.row + dr))
                        && ok[j]
                        && !seen[j]
                    {
                        seen[j] = true;
                        q.push_back(j);
                    }
                }
            }
        }
        (ok, seen)
    }

    #[test]
    fn house_is_about_27_percent_blocked() {
        let w = house(0.1).unwrap();
        let f = w.occupied_fraction();
        assert!((0.25..=0.29).contains(&f), "house occupancy {f}");
    }

    #[test]
    fn every_free_cell_is_connected_to_the_start() {
        for name in NAMES {
            let w = by_name(name, 0.1).unwrap().unwrap();
            let truth = w.truth();
            let free = w.blocked().iter().filter(|&&b| !b).count();
            assert_eq!(
                truth.free_count(),
                free,
                "{name}: free space is not connected"
            );
        }
    }

    #[test]
    fn a_p3dx_with_inflation_reaches_all_open_space() {
        // Radius 0.25 m plus 0.1 m margin: every place where such a disc fits is reachable.
        for name in NAMES {
            let w = by_name(name, 0.1).unwrap().unwrap();
            let (ok, seen) = drivable(&w, 0.35);
            let unreachable = ok.iter().zip(&seen).filter(|(o, s)| **o && !**s).count();
            assert_eq!(
                unreachable, 0,
                "{name}: {unreachable} drivable cells unreachable"
            );
            let reached = seen.iter().filter(|&&s| s).count();
            assert!(reached > 0);
        }
    }

    #[test]
    fn house_doors_are_open_doorways_in_walls() {
        let w = house(0.1).unwrap();
        for &(x0, y0, x1, y1) in &HOUSE_DOORS {
            let cells = w.cells_in_rect(x0, y0, x1, y1);
            assert_eq!(cells.len(), 150, "door {x0},{y0}");
            assert!(cells.iter().all(|&c| !w.is_blocked(c)));
            // Closing the doorway leaves no gap: the wall runs on both sides of it.
            let (wide, cx, cy) = (x1 - x0 > y1 - y0, (x0 + x1) / 2.0, (y0 + y1) / 2.0);
            let (a, b) = if wide {
                (Point2::new(x0 - 0.05, cy), Point2::new(x1 + 0.05, cy))
            } else {
                (Point2::new(cx, y0 - 0.05), Point2::new(cx, y1 + 0.05))
            };
            assert!(w.is_blocked_at(a) && w.is_blocked_at(b), "door {x0},{y0}");
        }
        let lab = lab(0.1).unwrap();
        let (x0, y0, x1, y1) = LAB_DOOR;
        assert_eq!(lab.cells_in_rect(x0, y0, x1, y1).len(), 20);
    }

    #[test]
    fn sizes_and_starts() {
        for (name, (w, h)) in NAMES
            .iter()
            .zip([(240, 240), (240, 240), (300, 500), (80, 80)])
        {
            let world = by_name(name, 0.1).unwrap().unwrap();
            assert_eq!((world.geometry().width, world.geometry().height), (w, h));
            assert_eq!(world.name(), *name);
            assert_eq!(world.start(), super::super::DEFAULT_START);
            assert!(world.start_is_clear(0.35));
        }
        assert!(by_name("moon", 0.1).is_none());
    }

    #[test]
    fn designs_do_not_depend_much_on_resolution() {
        let fine = house(0.05).unwrap().occupied_fraction();
        let coarse = house(0.1).unwrap().occupied_fraction();
        assert!((fine - coarse).abs() < 0.01, "{fine} vs {coarse}");
    }

    #[test]
    fn factory_has_narrow_corridors_and_many_obstacles() {
        let w = factory(0.1).unwrap();
        let f = w.occupied_fraction();
        assert!((0.2..0.45).contains(&f), "factory occupancy {f}");
        // The corridor at x 22.1..23 m is 0.9 m clear.
        let g = *w.geometry();
        let row = g.cell_at(Point2::new(22.5, 41.0)).unwrap().row;
        let free_run = (0..g.width as i32)
            .filter(|&c| {
                let x = g.cell_center(Cell::new(c, row)).x;
                (21.0..24.0).contains(&x) && !w.is_blocked(Cell::new(c, row))
            })
            .count();
        assert_eq!(free_run, 9);
    }
}
