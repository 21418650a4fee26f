//! Why a mission ended short of full coverage: runs one `papillon-sim mission` (same options)
//! and sorts the observable cells its map does not know by the first reason that explains them:
//!
//! - `unseen`: no pose the planning layer reaches on the *true* map (fully known, same body and
//!   clearance) sees the cell (line of sight within the laser's 4 m): the observable set counts
//!   cells the body cannot observe;
//! - `left`: a cell seen from a pose the robot could still reach on its *final* map: the mission
//!   ended with reachable unknown space (battery, or gave up);
//! - `noise`: seen only from poses that the final map's Occupied cells that are free in truth
//!   (laser noise) cut off; with those cells cleared the robot reaches a pose that sees it;
//! - `shut`: anything else (the final map's planning layer shuts the way for another reason).
//!
//! Usage: `coverage_gaps [mission options...]`, e.g.
//! `coverage_gaps --map gen-03 --seed 25 --battery 488`. Prints one tab-separated line:
//! `map method seed coverage reason missing unseen left noise shut spurious_occupied steps
//! contacts replans_by_cause`. With `GAPS_EVENTS=1` it also prints the last 40 events (`GAPS_EVENTS=N`: N), the map
//! around the robot (or around `GAPS_AT=X,Y`) and the planning layer there (`GAPS_TRUTH=1`:
//! the map against the truth instead: `#` Occupied and a wall, `X` Occupied but free, `w`
//! Free but a wall, `.` Free and free, `:` an unknown wall, ` ` unknown free ground); with
//! `GAPS_GATES=1` the spurious Occupied cells next to where the final map's reach stops; with
//! `GAPS_FRONTIER=1` the final map's frontier cells in clusters, each with how many of its cells
//! the robot reaches (`reached`), could stand next to but not get to (`cut`: a door shut on the
//! map) or only touch from the wall band (`band`), a `frontier_summary` line, and checks that
//! the mission's own traversability layer and distance field agree with a rebuild from the
//! final map (a mission that ended "nothing reachable" with `reached` frontier cells was cut
//! off by something not in its final map); with `GAPS_LOGODDS=X,Y` the log-odds of the cells
//! around a point (a door's cells, say); with `GAPS_SPAN=ROWS,COLS` larger map prints; with `GAPS_TRACK=T0,T1` the robot's true and estimated
//! pose, the planning layer at its cell and the mission's state every 0.5 s from T0 to T1 \[s\];
//! with `GAPS_KIND=1` a `missing_kind` line: the missing cells that are walls in truth, those
//! free in truth, and the wall cells next to a free-in-truth cell the map holds Occupied (the
//! wall's face drawn a cell in front of where it is).
//! Results are in docs/experiments.md ("Generated world set after the obstacle-mark change").

use clap::Parser;
use papillon::geometry::Point2;
use papillon::grid::{Cell, CellClass, OccupancyGrid};
use papillon::planner::Traversability;
use papillon_sim::cli::mission::{Args, setup_from_args};
use papillon_sim::dynamic::Dynamics;
use papillon_sim::runner::{FIXED_CAPACITY, Runner};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: Args,
}

/// Cells the layer lets a robot's centre reach from `from` (4-connected over passable cells).
fn reach(trav: &Traversability<FIXED_CAPACITY>, from: Cell) -> Vec<bool> {
    let g = *trav.geometry();
    let mut seen = vec![false; g.cell_count()];
    // Start from the nearest passable cell within 3 cells (the robot may sit in a band).
    let mut stack = Vec::new();
    for dr in -3..=3 {
        for dc in -3..=3 {
            let c = Cell::new(from.col + dc, from.row + dr);
            if let Some(i) = g.index(c)
                && trav.is_passable(c)
                && !seen[i]
            {
                seen[i] = true;
                stack.push(c);
            }
        }
    }
    while let Some(c) = stack.pop() {
        for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let n = Cell::new(c.col + dc, c.row + dr);
            if let Some(j) = g.index(n)
                && !seen[j]
                && trav.is_passable(n)
            {
                seen[j] = true;
                stack.push(n);
            }
        }
    }
    seen
}

/// Cells seen (line of sight through free truth cells, up to `range_m`) from the reached cells,
/// sampled every `step` cells, 720 rays each.
fn seen_from(
    world: &papillon_sim::world::World,
    reached: &[bool],
    step: i32,
    range_m: f32,
) -> Vec<bool> {
    let g = *world.geometry();
    let mut seen = vec![false; g.cell_count()];
    for (i, _) in reached.iter().enumerate().filter(|(_, r)| **r) {
        let c = g.cell(i);
        if c.col % step != 0 || c.row % step != 0 {
            continue;
        }
        let o = g.cell_center(c);
        for k in 0..720 {
            let a = k as f32 * std::f32::consts::PI / 360.0;
            let n = (range_m / (0.5 * g.resolution_m)) as usize;
            for s in 0..=n {
                let d = s as f32 * 0.5 * g.resolution_m;
                let p = Point2::new(o.x + d * a.cos(), o.y + d * a.sin());
                let Some(cell) = g.cell_at(p) else { break };
                let j = g.index(cell).unwrap();
                seen[j] = true;
                if world.is_blocked_index(j) {
                    break;
                }
            }
        }
    }
    seen
}

/// Prints the final map's frontier cells (Unknown with a Free 4-neighbour) in 8-connected
/// clusters, each with its size, centre, and how many of its cells have a Free neighbour the
/// robot reaches (`reached`), one that is passable but cut off (`cut`), or only Free neighbours
/// in the planning layer's blocked band (`band`); `wall`: cells blocked in truth.
fn frontier_report(
    world: &papillon_sim::world::World,
    map: &OccupancyGrid<FIXED_CAPACITY>,
    trav: &Traversability<FIXED_CAPACITY>,
    reached: &[bool],
) {
    let g = *world.geometry();
    let n4 = [(1, 0), (-1, 0), (0, 1), (0, -1)];
    let mut kind = vec![0u8; g.cell_count()];
    for (i, k) in kind.iter_mut().enumerate() {
        if !papillon::frontier::is_frontier_cell(map, i) {
            continue;
        }
        let c = g.cell(i);
        let mut best = 3;
        for (dc, dr) in n4 {
            let n = Cell::new(c.col + dc, c.row + dr);
            let Some(j) = g.index(n) else { continue };
            if map.class(j) != CellClass::Free {
                continue;
            }
            let v = if reached[j] {
                1
            } else if trav.is_passable(n) {
                2
            } else {
                3
            };
            best = best.min(v);
        }
        *k = best;
    }
    let mut done = vec![false; g.cell_count()];
    let mut totals = [0u32; 4];
    let mut big = [0u32; 4];
    for i in 0..g.cell_count() {
        if kind[i] == 0 || done[i] {
            continue;
        }
        let (mut counts, mut wall, mut sx, mut sy, mut size) = ([0u32; 4], 0, 0.0, 0.0, 0);
        let mut stack = vec![i];
        done[i] = true;
        while let Some(j) = stack.pop() {
            counts[kind[j] as usize] += 1;
            wall += u32::from(world.is_blocked_index(j));
            let p = g.cell_center(g.cell(j));
            sx += p.x;
            sy += p.y;
            size += 1;
            let c = g.cell(j);
            for dr in -1..=1 {
                for dc in -1..=1 {
                    if let Some(k) = g.index(Cell::new(c.col + dc, c.row + dr))
                        && kind[k] != 0
                        && !done[k]
                    {
                        done[k] = true;
                        stack.push(k);
                    }
                }
            }
        }
        for k in 1..4 {
            totals[k] += counts[k];
            big[k] += u32::from(counts[k] >= 5 && wall * 2 < size);
        }
        eprintln!(
            "frontier at ({:.2}, {:.2}) cells {size} reached {} cut {} band {} wall {wall}",
            sx / size as f32,
            sy / size as f32,
            counts[1],
            counts[2],
            counts[3]
        );
    }
    // Totals, and clusters mostly free in truth with at least 5 cells of each kind.
    eprintln!(
        "frontier_summary reached {} cut {} band {} big_reached {} big_cut {} big_band {}",
        totals[1], totals[2], totals[3], big[1], big[2], big[3]
    );
}

/// `GAPS_SPAN=ROWS,COLS`: half the height and width of the map prints \[cells\] (default
/// `None`: 15 x 25 for the map, 6 x 6 for the planning layer).
fn span() -> Option<(i32, i32)> {
    let v = std::env::var("GAPS_SPAN").ok()?;
    let (r, c) = v.split_once(',')?;
    Some((r.parse().ok()?, c.parse().ok()?))
}

fn main() {
    let cli = Cli::parse();
    let mut setup = setup_from_args(&cli.args).unwrap_or_else(|e| panic!("{e}"));
    // `--max-time` as the `mission` command reads it: the map at that moment.
    if let Some(limit_s) = cli.args.max_time {
        setup.run.max_sim_time_s = limit_s;
    }
    let world = setup.world.clone();
    let mut runner = Runner::new(world.clone(), Dynamics::new(), setup.run.clone()).unwrap();
    // GAPS_TRACE=FROM,TO: every control period between those simulated times [s], the true
    // pose, the body's speed and turn rate, the mission's phase, the safety monitor's state,
    // the next waypoints and the mission's events.
    let trace = std::env::var("GAPS_TRACE").ok().and_then(|v| {
        let (a, b) = v.split_once(',')?;
        Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?))
    });
    // GAPS_TRACK=T0,T1: the true and estimated pose, the mission's state and the planning
    // layer at the estimated cell every 0.5 s of simulated time between T0 and T1.
    let track = std::env::var("GAPS_TRACK").ok().and_then(|v| {
        let (a, b) = v.split_once(',')?;
        Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?))
    });
    let mut next_track = 0.0;
    let mut logged = 0;
    let report = runner
        .run_with(|r, progress| {
            let t = r.sim_time_s();
            if let Some((t0, t1)) = track
                && t >= t0
                && t <= t1
                && t >= next_track
            {
                next_track = t + 0.5;
                let m = r.mission(0);
                let (p, e) = (r.body(0).true_pose(), m.pose_map());
                let trav = &r.map().trav;
                let cell = trav.geometry().cell_at(e.position());
                let (pass, turn) =
                    cell.map_or((false, false), |c| (trav.is_passable(c), trav.can_turn(c)));
                eprintln!(
                    "{t:8.1} true ({:.2}, {:.2}, {:.2}) est ({:.2}, {:.2}, {:.2}) passable {pass} turn {turn} {:?}",
                    p.x, p.y, p.theta, e.x, e.y, e.theta, m.state()
                );
            }
            let Some((from, to)) = trace else { return };
            if !matches!(progress, papillon_sim::runner::Progress::Controlled) || t < from || t > to
            {
                logged = r.events().len();
                return;
            }
            let (b, m) = (r.body(0), r.mission(0));
            let p = b.true_pose();
            let path: Vec<String> = m
                .path()
                .iter()
                .take(3)
                .map(|w| format!("({:.2},{:.2})", w.x, w.y))
                .collect();
            eprintln!(
                "{t:7.1} true ({:.2},{:.2},{:.2}) v {:4.0} w {:4.0} {:?} {:?} path {}",
                p.x,
                p.y,
                p.theta,
                b.speed_mm_s(),
                b.turn_deg_s(),
                m.state(),
                m.monitor().state(),
                path.join(" ")
            );
            for e in &r.events()[logged..] {
                eprintln!("        {:?}", e.event);
            }
            logged = r.events().len();
        })
        .unwrap();
    if let Some(v) = std::env::var_os("GAPS_EVENTS") {
        // GAPS_EVENTS=N prints the last N events (40 for any other value).
        let n = v.to_str().and_then(|v| v.parse().ok()).unwrap_or(40);
        let ev = runner.events();
        for e in &ev[ev.len().saturating_sub(n)..] {
            eprintln!("{:8.1} {:?}", e.time_s, e.event);
        }
        eprintln!("stats {:?}", runner.mission(0).stats());
        eprintln!("mission at the end {:?}", runner.mission(0));
    }
    let g = *world.geometry();
    let truth = world.truth();
    let map = &runner.map().grid;
    if std::env::var_os("GAPS_EVENTS").is_some() {
        let p = runner.body(0).true_pose();
        eprintln!(
            "end pose {p:?}, estimated {:?}",
            runner.mission(0).pose_map()
        );
        // Map around the robot: '#' Occupied and blocked, '!' Occupied but free in truth,
        // '.' Free, ',' Free but blocked in truth, ' ' Unknown (truth free), '%' Unknown (truth
        // blocked), 'R' the robot's cell.
        let at = std::env::var("GAPS_AT").ok().and_then(|v| {
            let (x, y) = v.split_once(',')?;
            Some(Point2::new(x.parse().ok()?, y.parse().ok()?))
        });
        let c = g.cell_at(at.unwrap_or(Point2::new(p.x, p.y))).unwrap();
        let (hr, hc) = span().unwrap_or((15, 25));
        for dr in (-hr..=hr).rev() {
            let mut line = String::new();
            for dc in -hc..=hc {
                let cell = Cell::new(c.col + dc, c.row + dr);
                let Some(i) = g.index(cell) else {
                    line.push('~');
                    continue;
                };
                let b = world.is_blocked_index(i);
                line.push(if dc == 0 && dr == 0 {
                    'R'
                } else {
                    match (map.class(i), b) {
                        (CellClass::Occupied, true) => '#',
                        (CellClass::Occupied, false) => '!',
                        (CellClass::Free, false) => '.',
                        (CellClass::Free, true) => ',',
                        (CellClass::Unknown, false) => ' ',
                        (CellClass::Unknown, true) => '%',
                    }
                });
            }
            eprintln!("{line}");
        }
    }
    let config = setup.run.mission.traversability;

    // The true map's reachable poses and what they see.
    let true_grid = world.to_occupancy_grid::<FIXED_CAPACITY>().unwrap();
    let mut trav = Traversability::<FIXED_CAPACITY>::new_boxed(g, config).unwrap();
    trav.rebuild_from(&true_grid).unwrap();
    let start = world.start_cell().unwrap();
    let step = 2;
    let seen_true = seen_from(&world, &reach(&trav, start), step, 4.0);

    // The final map's reachable poses, from where the robot ended.
    let end = report.robots[0]
        .trajectory
        .last()
        .map(|p| g.cell_at(Point2::new(p.x, p.y)).unwrap())
        .unwrap_or(start);
    trav.rebuild_from(map).unwrap();
    let reach_final = reach(&trav, end);
    if std::env::var_os("GAPS_FRONTIER").is_some() {
        // From where the robot believes it is (the mission decides from there).
        let est = runner.mission(0).pose_map();
        let est = g.cell_at(Point2::new(est.x, est.y)).unwrap_or(end);
        let from_est = reach(&trav, est);
        eprintln!(
            "reached from the estimated pose {} (from the true pose {})",
            from_est.iter().filter(|&&r| r).count(),
            reach_final.iter().filter(|&&r| r).count()
        );
        let live = &runner.map().trav;
        let differ: Vec<usize> = (0..g.cell_count())
            .filter(|&i| live.is_passable(g.cell(i)) != trav.is_passable(g.cell(i)))
            .collect();
        eprintln!(
            "mission layer differs from a rebuild in {} cells",
            differ.len()
        );
        for &i in differ.iter().take(8) {
            let c = g.cell(i);
            eprintln!(
                "  {c:?} live {} rebuilt {} class {:?} log-odds {:.2}",
                live.is_passable(c),
                trav.is_passable(c),
                map.class(i),
                map.log_odds_at(i)
            );
        }
        let mut field = papillon::planner::DistanceField::<FIXED_CAPACITY>::new_boxed();
        eprintln!(
            "distance field on the mission's own layer: {:?}",
            field.compute(live, est)
        );
        match field.compute(&*trav, est) {
            Ok(n) => {
                let missed: Vec<usize> = (0..g.cell_count())
                    .filter(|&i| from_est[i] && !field.is_reachable(g.cell(i)))
                    .collect();
                eprintln!(
                    "distance field from {est:?}: {n} cells, {} of the 4-connected reach missed",
                    missed.len()
                );
                for &i in missed.iter().take(5) {
                    eprintln!("  missed {:?}", g.cell(i));
                }
            }
            Err(e) => eprintln!("distance field from {est:?}: {e:?}"),
        }
    }
    if std::env::var_os("GAPS_EVENTS").is_some() {
        eprintln!(
            "end cell passable {} reached from it {}",
            trav.is_passable(end),
            reach_final.iter().filter(|&&r| r).count()
        );
        // Around GAPS_AT if given, else the end cell.
        let centre = std::env::var("GAPS_AT")
            .ok()
            .and_then(|v| {
                let (x, y) = v.split_once(',')?;
                g.cell_at(Point2::new(x.parse().ok()?, y.parse().ok()?))
            })
            .unwrap_or(end);
        // 'o' passable and turnable, '-' passable only straight, 'x' blocked, ' ' Unknown;
        // passable cells the robot does not reach on the final map print 'c' and '='.
        let (hr, hc) = span().unwrap_or((6, 6));
        let truth_print = std::env::var_os("GAPS_TRUTH").is_some();
        for dr in (-hr..=hr).rev() {
            let line: String = (-hc..=hc)
                .map(|dc| {
                    let c = Cell::new(centre.col + dc, centre.row + dr);
                    let index = g.index(c);
                    let reached = index.is_some_and(|i| reach_final[i]);
                    let wall = index.is_some_and(|i| world.is_blocked_index(i));
                    if dc == 0 && dr == 0 {
                        'R'
                    } else if truth_print {
                        match (map.class_of(c), wall) {
                            (Some(CellClass::Occupied), true) => '#',
                            (Some(CellClass::Occupied), false) => 'X',
                            (Some(CellClass::Free), true) => 'w',
                            (Some(CellClass::Free), false) => '.',
                            (_, true) => ':',
                            _ => ' ',
                        }
                    } else if map.class_of(c) == Some(CellClass::Unknown) {
                        ' '
                    } else if trav.is_passable(c) {
                        match (trav.can_turn(c), reached) {
                            (true, true) => 'o',
                            (false, true) => '-',
                            (true, false) => 'c',
                            (false, false) => '=',
                        }
                    } else {
                        'x'
                    }
                })
                .collect();
            eprintln!("{line}");
        }
    }
    let seen_final = seen_from(&world, &reach_final, step, 4.0);
    if let Some(at) = std::env::var("GAPS_LOGODDS").ok().and_then(|v| {
        let (x, y) = v.split_once(',')?;
        g.cell_at(Point2::new(x.parse().ok()?, y.parse().ok()?))
    }) {
        // Log-odds of the 11 x 7 cells around the point (rows north first; '*' blocked in
        // truth).
        for dr in (-3..=3).rev() {
            let mut line = String::new();
            for dc in -5..=5 {
                let c = Cell::new(at.col + dc, at.row + dr);
                if let Some(i) = g.index(c) {
                    let b = if world.is_blocked_index(i) { '*' } else { ' ' };
                    line.push_str(&format!("{:6.2}{b}", map.log_odds_at(i)));
                }
            }
            eprintln!("{line}");
        }
    }
    if std::env::var_os("GAPS_FRONTIER").is_some() {
        frontier_report(&world, map, &trav, &reach_final);
    }

    // The final map without its spurious Occupied cells.
    let mut clean: Box<OccupancyGrid<FIXED_CAPACITY>> =
        OccupancyGrid::new_boxed(g, map.bounds()).unwrap();
    let mut spurious = 0;
    for i in 0..g.cell_count() {
        let mut class = map.class(i);
        if class == CellClass::Occupied && !world.is_blocked_index(i) {
            spurious += usize::from(truth.mask()[i]);
            class = CellClass::Free;
        }
        if class != CellClass::Unknown {
            clean.set_class(i, class, &mut ());
        }
    }
    trav.rebuild_from(&*clean).unwrap();
    let reach_clean = reach(&trav, end);
    let seen_clean = seen_from(&world, &reach_clean, step, 4.0);
    if std::env::var_os("GAPS_GATES").is_some() {
        // Spurious Occupied cells within 0.3 m of a cell the clean map reaches and the final
        // map does not, next to one the final map reaches: what shuts the way.
        let mut blockers = std::collections::BTreeMap::new();
        for i in 0..g.cell_count() {
            if !reach_clean[i] || reach_final[i] {
                continue;
            }
            let c = g.cell(i);
            let gate = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dc, dr)| {
                g.index(Cell::new(c.col + dc, c.row + dr))
                    .is_some_and(|j| reach_final[j])
            });
            if !gate {
                continue;
            }
            for dr in -3..=3 {
                for dc in -3..=3 {
                    if let Some(j) = g.index(Cell::new(c.col + dc, c.row + dr))
                        && map.class(j) == CellClass::Occupied
                        && !world.is_blocked_index(j)
                    {
                        blockers.insert(j, map.log_odds_at(j));
                    }
                }
            }
        }
        for (j, l) in &blockers {
            let p = g.cell_center(g.cell(*j));
            eprintln!("blocker ({:.2}, {:.2}) l={l:.2}", p.x, p.y);
        }
    }

    let (mut missing, mut unseen, mut left, mut noise, mut shut) = (0, 0, 0, 0, 0);
    for &i in truth.cells() {
        if map.class(i).is_known() {
            continue;
        }
        missing += 1;
        if !seen_true[i] {
            unseen += 1;
        } else if seen_final[i] {
            left += 1;
        } else if seen_clean[i] {
            noise += 1;
        } else {
            shut += 1;
        }
    }
    if std::env::var_os("GAPS_KIND").is_some() {
        // The missing cells by what they are in truth: wall cells (blocked) and free cells,
        // and of the wall cells those next to a free-in-truth cell the map holds Occupied (the
        // wall drawn a cell in front of where it is).
        let (mut wall, mut free, mut wall_behind_drawn) = (0, 0, 0);
        for &i in truth.cells() {
            if map.class(i).is_known() {
                continue;
            }
            if world.is_blocked_index(i) {
                wall += 1;
                let c = g.cell(i);
                let drawn_in_front = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dc, dr)| {
                    g.index(Cell::new(c.col + dc, c.row + dr)).is_some_and(|j| {
                        !world.is_blocked_index(j) && map.class(j) == CellClass::Occupied
                    })
                });
                wall_behind_drawn += usize::from(drawn_in_front);
            } else {
                free += 1;
            }
        }
        eprintln!("missing_kind wall {wall} free {free} wall_behind_drawn {wall_behind_drawn}");
    }
    if std::env::var_os("GAPS_MAP").is_some() {
        // The whole map, one character per 2 x 2 cells: 'M' holds an observable cell the map
        // does not know, '#' a wall in truth, '.' free in truth.
        let missing_at: std::collections::HashSet<usize> = truth
            .cells()
            .iter()
            .copied()
            .filter(|&i| !map.class(i).is_known())
            .collect();
        for r in (0..g.height as i32 / 2).rev() {
            let line: String = (0..g.width as i32 / 2)
                .map(|c| {
                    let cells = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .map(|(dc, dr)| g.index(Cell::new(2 * c + dc, 2 * r + dr)).unwrap());
                    if cells.iter().any(|i| missing_at.contains(i)) {
                        'M'
                    } else if cells.iter().any(|&i| world.is_blocked_index(i)) {
                        '#'
                    } else {
                        '.'
                    }
                })
                .collect();
            eprintln!("{line}");
        }
    }
    let mut causes = std::collections::BTreeMap::new();
    for e in runner.events() {
        if let papillon::mission::MissionEvent::Replanned { cause } = e.event {
            *causes.entry(format!("{cause:?}")).or_insert(0) += 1;
        }
    }
    let causes: Vec<String> = causes.iter().map(|(k, v)| format!("{k}={v}")).collect();
    println!(
        "{}\t{}\t{}\t{:.3}\t{}\t{missing}\t{unseen}\t{left}\t{noise}\t{shut}\t{spurious}\t{}\t{}\t{}",
        world.name(),
        setup.method(),
        setup.run.seed,
        report.coverage,
        report.reason.map_or("-", |r| r.name()),
        report.steps(),
        report.collisions(),
        causes.join(","),
    );
}
