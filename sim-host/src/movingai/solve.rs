//! Solving a Moving AI path-finding benchmark (Sturtevant 2012) with Papillon's A* and
//! comparing every length with the published optimum (`papillon-sim plan` and the arena
//! tests).

use std::time::Instant;

use papillon::grid::Cell;
use papillon::planner::{AStar, Traversability};

use super::{MovingAiMap, Scenario};

/// Largest map the solver accepts \[cells\] (1024 x 1024).
pub const PLAN_CAPACITY: usize = 1 << 20;

/// Tolerance on lengths \[cells\].
pub const TOLERANCE: f64 = 1e-3;

/// One solved problem.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Solved {
    /// Line in the `.scen` file.
    pub line: usize,
    /// Start (x, y), Moving AI coordinates.
    pub start: (usize, usize),
    /// Goal (x, y), Moving AI coordinates.
    pub goal: (usize, usize),
    /// Published optimal length \[cells\].
    pub expected: f64,
    /// Length found \[cells\]; `None` if no path was found.
    pub computed: Option<f64>,
    /// Cells expanded.
    pub expansions: u32,
    /// Time of the query \[µs\].
    pub time_us: f64,
}

impl Solved {
    /// Whether the computed length matches the expected one within [`TOLERANCE`].
    pub fn is_optimal(&self) -> bool {
        self.computed
            .is_some_and(|c| (c - self.expected).abs() <= TOLERANCE)
    }
}

/// Summary of a benchmark run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    /// Problems solved.
    pub problems: usize,
    /// Problems whose length matched.
    pub optimal: usize,
    /// Problems whose length did not match (or had no path).
    pub mismatches: Vec<Solved>,
    /// Mean expansions per query.
    pub mean_expansions: f64,
    /// Mean time per query \[µs\].
    pub mean_us: f64,
}

/// Solves every problem of `scen` on `map`.
pub fn solve_all(map: &MovingAiMap, scen: &Scenario) -> Result<Vec<Solved>, String> {
    if map.width * map.height > PLAN_CAPACITY {
        return Err(format!(
            "map of {} x {} cells exceeds the planner's capacity of {PLAN_CAPACITY} cells",
            map.width, map.height
        ));
    }
    let trav = Traversability::<PLAN_CAPACITY>::from_blocked_boxed(map.width, map.height, |c| {
        map.is_cell_blocked(c)
    })
    .map_err(|e| e.to_string())?;
    let mut astar = AStar::<PLAN_CAPACITY>::new_boxed();
    let mut path = vec![Cell::default(); map.width * map.height];
    let mut out = Vec::with_capacity(scen.problems.len());
    for p in &scen.problems {
        let start = map.to_cell(p.start_x, p.start_y);
        let goal = map.to_cell(p.goal_x, p.goal_y);
        let t0 = Instant::now();
        let result = astar.find_path(&trav, start, goal, &mut path);
        let time_us = t0.elapsed().as_secs_f64() * 1e6;
        let (computed, expansions) = match result {
            Ok(r) => (Some(r.length_m as f64), r.expansions),
            Err(_) => (None, 0),
        };
        out.push(Solved {
            line: p.line,
            start: (p.start_x, p.start_y),
            goal: (p.goal_x, p.goal_y),
            expected: p.optimal,
            computed,
            expansions,
            time_us,
        });
    }
    Ok(out)
}

/// Summarises solved problems.
pub fn report(solved: &[Solved]) -> Report {
    let n = solved.len().max(1) as f64;
    Report {
        problems: solved.len(),
        optimal: solved.iter().filter(|s| s.is_optimal()).count(),
        mismatches: solved.iter().filter(|s| !s.is_optimal()).cloned().collect(),
        mean_expansions: solved.iter().map(|s| s.expansions as f64).sum::<f64>() / n,
        mean_us: solved.iter().map(|s| s.time_us).sum::<f64>() / n,
    }
}
