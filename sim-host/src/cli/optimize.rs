//! `papillon-sim optimize` (in progress).

use std::process::ExitCode;

/// Arguments of `papillon-sim optimize`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the command.
pub fn run(_args: Args) -> ExitCode {
    eprintln!("papillon-sim optimize: not built yet");
    ExitCode::from(2)
}
