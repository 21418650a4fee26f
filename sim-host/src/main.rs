//! `papillon-sim`: the host simulator's command line.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use papillon_sim::cli;

/// Papillon's host simulator: missions, experiments, emulated hardware and benchmarks.
#[derive(Parser)]
#[command(name = "papillon-sim", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run an experiment (a sweep of missions) in parallel, or merge its shards.
    Bench(cli::bench::Args),
    /// Run a whole exploration mission in simulated time (one or several robots).
    Mission(Box<cli::mission::Args>),
    /// Run the optimizers on standard test functions.
    Optimize(cli::optimize::Args),
    /// Solve a Moving AI path-finding benchmark with Papillon's A*.
    Plan(cli::plan::Args),
    /// Serve an emulated P3-DX microcontroller and LMS1xx laser over a simulated world.
    Serve(cli::serve::Args),
    /// Score a saved robot map (ROS map_server YAML + PGM) against a world's ground truth.
    Score(cli::score::Args),
    /// Tune one method's hyper-parameters on exploration missions (TPE, like the thesis's
    /// Hyperopt run).
    Tune(cli::tune::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            eprintln!("papillon-sim: {}", clap_error_line(&e));
            return ExitCode::from(2);
        }
        Err(e) => {
            // --help and --version.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
    };
    match cli.command {
        Command::Bench(args) => cli::bench::run(args),
        Command::Mission(args) => cli::mission::run(*args),
        Command::Optimize(args) => cli::optimize::run(args),
        Command::Plan(args) => cli::plan::run(args),
        Command::Serve(args) => cli::serve::run(args),
        Command::Score(args) => cli::score::run(args),
        Command::Tune(args) => cli::tune::run(args),
    }
}

/// One line for a bad command line: clap's first paragraph (the error and, for a missing
/// argument, the flags it names), without its `error: ` prefix.
fn clap_error_line(e: &clap::Error) -> String {
    if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        return "a subcommand is missing: bench, mission, optimize, plan, serve, score or tune (see \
                papillon-sim --help)"
            .into();
    }
    papillon::command_line::error_line(&e.to_string())
}
