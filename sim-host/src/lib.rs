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
pub mod mission_run;
pub mod movingai;
pub mod odometry_error;
pub mod optimize;
pub mod physics;
pub mod placement;
pub mod record;
pub mod render;
pub mod runner;
pub mod scenario;
pub mod score;
pub mod serve;
pub mod shared_data;
pub mod tpe;
pub mod world;
