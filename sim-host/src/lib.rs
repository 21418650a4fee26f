//! The host simulator: worlds, physics, laser simulation, emulated hardware, experiments.
#![warn(missing_docs)]

pub mod cli;
pub mod movingai;
