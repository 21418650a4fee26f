//! `papillon-sim plan` (in progress).

use std::process::ExitCode;

/// Arguments of `papillon-sim plan`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the command.
pub fn run(_args: Args) -> ExitCode {
    eprintln!("papillon-sim plan: not built yet");
    ExitCode::from(2)
}
