//! The host simulator: worlds, physics, laser simulation, emulated hardware, experiments.
#![warn(missing_docs)]

pub mod bench;
pub mod cli;
pub mod dynamic;
pub mod emulator;
pub mod faults;
pub mod laser;
pub mod localization_report;
pub mod map_accuracy;
pub mod movingai;
pub mod odometry_error;
pub mod physics;
pub mod render;
pub mod runner;
pub mod world;
