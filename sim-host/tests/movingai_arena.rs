//! Acceptance: Papillon's A* and distance field reproduce the published optimal lengths of the
//! Moving AI `arena` benchmark, and `papillon-sim plan` reports them.
//!
//! The benchmark files live in the shared data folder (`shared/data/movingai/`, found by
//! [`papillon_sim::shared_data`]); without it each test says so and passes without checking.

use std::path::{Path, PathBuf};
use std::process::Command;

use papillon::grid::Cell;
use papillon::planner::{AStar, DistanceField, Traversability};
use papillon_sim::movingai::solve;
use papillon_sim::movingai::{MovingAiMap, Scenario};
use papillon_sim::shared_data;

const CAP: usize = 49 * 49;

/// The folder with `arena.map` and `arena.map.scen`, or `None` (with a message) without it.
fn data_dir(test: &str) -> Option<PathBuf> {
    shared_data::locate_or_skip(test, "data/movingai/arena.map.scen")
        .and_then(|p| p.parent().map(PathBuf::from))
}

fn arena(dir: &Path) -> (MovingAiMap, Scenario) {
    let map = MovingAiMap::load(dir.join("arena.map")).unwrap();
    let scen = Scenario::load(dir.join("arena.map.scen"), &map).unwrap();
    (map, scen)
}

#[test]
fn astar_matches_all_130_arena_optima() {
    let Some(dir) = data_dir("astar_matches_all_130_arena_optima") else {
        return;
    };
    let (map, scen) = arena(&dir);
    assert_eq!((map.width, map.height), (49, 49));
    assert_eq!(scen.problems.len(), 130);
    let trav =
        Traversability::<CAP>::from_blocked(map.width, map.height, |c| map.is_cell_blocked(c))
            .unwrap();
    let mut astar = AStar::<CAP>::new();
    let mut field = DistanceField::<CAP>::new();
    let mut path = vec![Cell::default(); CAP];
    for p in &scen.problems {
        let start = map.to_cell(p.start_x, p.start_y);
        let goal = map.to_cell(p.goal_x, p.goal_y);
        let r = astar.find_path(&trav, start, goal, &mut path).unwrap();
        assert!(
            (r.length_m as f64 - p.optimal).abs() <= 1e-3,
            "line {}: A* {} vs optimal {}",
            p.line,
            r.length_m,
            p.optimal
        );
        assert!((r.cost_m - r.length_m).abs() <= 1e-3);
        field.compute(&trav, start).unwrap();
        let d = field.distance_to(goal).unwrap() as f64;
        assert!(
            (d - p.optimal).abs() <= 1e-3,
            "line {}: field {d} vs {}",
            p.line,
            p.optimal
        );
    }
}

#[test]
fn plan_report_counts_all_problems_optimal() {
    let Some(dir) = data_dir("plan_report_counts_all_problems_optimal") else {
        return;
    };
    let (map, scen) = arena(&dir);
    let solved = solve::solve_all(&map, &scen).unwrap();
    let report = solve::report(&solved);
    assert_eq!((report.optimal, report.problems), (130, 130));
    assert!(report.mismatches.is_empty());
    assert!(report.mean_expansions >= 1.0);
}

fn sim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_papillon-sim"))
}

#[test]
fn plan_command_exit_codes() {
    let Some(data) = data_dir("plan_command_exit_codes") else {
        return;
    };
    let data = |name: &str| data.join(name);
    let out = sim()
        .args(["plan", "--json", "--map"])
        .arg(data("arena.map"))
        .arg("--scen")
        .arg(data("arena.map.scen"))
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["problems"], 130);
    assert_eq!(v["optimal"], 130);
    assert_eq!(v["mismatches"].as_array().map(Vec::len), Some(0));

    let dir = std::env::temp_dir().join(format!("papillon-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A wrong expected length: exit 1, listed as a mismatch.
    let scen = std::fs::read_to_string(data("arena.map.scen")).unwrap();
    let wrong = scen.replacen("\t3.00000000", "\t3.50000000", 1);
    assert_ne!(wrong, scen);
    std::fs::write(dir.join("wrong.scen"), wrong).unwrap();
    let out = sim()
        .args(["plan", "--map"])
        .arg(data("arena.map"))
        .arg("--scen")
        .arg(dir.join("wrong.scen"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("129/130 optimal"), "{text}");
    assert!(text.contains("MISMATCH"));
    // A malformed map: exit 2, one stderr line naming file and line.
    std::fs::write(
        dir.join("bad.map"),
        "type octile\nheight 2\nwidth 2\nmap\n..\n.x\n",
    )
    .unwrap();
    let out = sim()
        .args(["plan", "--map"])
        .arg(dir.join("bad.map"))
        .arg("--scen")
        .arg(data("arena.map.scen"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("bad.map:6:"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
