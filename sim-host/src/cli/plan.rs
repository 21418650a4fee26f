//! `papillon-sim plan`: solves a Moving AI benchmark with Papillon's A*
//! ([`crate::movingai::solve`]) and compares every length with the published optimum.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::movingai::solve::{report, solve_all};
use crate::movingai::{MovingAiMap, Scenario};

/// Arguments of `papillon-sim plan`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Moving AI `.map` file.
    #[arg(long)]
    pub map: PathBuf,
    /// Moving AI `.scen` file with the problems and their optimal lengths.
    #[arg(long)]
    pub scen: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command: exit 0 if every length matches, 1 if any differs, 2 on bad input.
pub fn run(args: Args) -> ExitCode {
    let loaded = MovingAiMap::load(&args.map)
        .and_then(|map| Scenario::load(&args.scen, &map).map(|scen| (map, scen)));
    let (map, scen) = match loaded {
        Ok(x) => x,
        Err(e) => {
            eprintln!("papillon-sim plan: {e}");
            return ExitCode::from(2);
        }
    };
    let solved = match solve_all(&map, &scen) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("papillon-sim plan: {}: {e}", args.map.display());
            return ExitCode::from(2);
        }
    };
    let report = report(&solved);
    if args.json {
        match serde_json::to_string(&report) {
            Ok(s) => println!("{s}"),
            Err(e) => {
                eprintln!("papillon-sim plan: cannot encode the report: {e}");
                return ExitCode::from(2);
            }
        }
    } else {
        for s in &solved {
            let computed = s
                .computed
                .map_or_else(|| "none".to_string(), |c| format!("{c:.6}"));
            println!(
                "line {:>4}  start ({}, {})  goal ({}, {})  expected {:.6}  computed {}  expansions {}{}",
                s.line,
                s.start.0,
                s.start.1,
                s.goal.0,
                s.goal.1,
                s.expected,
                computed,
                s.expansions,
                if s.is_optimal() { "" } else { "  MISMATCH" }
            );
        }
        println!(
            "{}/{} optimal, mean {:.1} expansions, mean {:.2} us per query",
            report.optimal, report.problems, report.mean_expansions, report.mean_us
        );
    }
    if report.optimal == report.problems {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
