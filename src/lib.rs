//! Papillon: autonomous exploration for the Pioneer P3-DX.
//!
//! The core is sans-IO, `no_std` and allocation-free: it is fed time, bytes, scans and a seeded
//! random number generator, and returns commands. The onboard runtime (feature `onboard`) and
//! the host simulator (`papillon-sim`) are two pumps around it. See `docs/architecture.md`.
//!
//! Layers, bottom up:
//! - [`math`], [`units`], [`geometry`], [`random`]: numbers, units and frames; `heap` (host
//!   only, crate-private): large fixed-capacity structures allocated zero-filled on the heap.
//! - [`grid`], [`raycast`], [`sensor`], [`frontier`]: the occupancy grid and the LIDAR model;
//!   [`capacity`]: the ladder of grid capacities a host program picks from at start-up
//!   ([`with_cell_capacity!`]).
//! - [`planner`]: traversability, A*, distance fields, waypoints.
//! - [`optim`]: xBOA and the methods the thesis compares.
//! - [`explore`]: the exploration objective and target selectors.
//! - [`control`]: odometry, PID, path following, safety.
//! - [`localize`]: scan-to-map matching that corrects the odometry.
//! - [`mission`]: the mission state machine, one or several robots.
//! - [`config`]: the board file (robot, link, laser, grid, mission, PID, safety), parsed
//!   without an allocator; [`mapfile`] (host only): map files read into an occupancy grid;
//!   [`files`] (host only): bounded reads of every input file; [`command_line`] (host only):
//!   one-line command-line errors for both binaries.
//! - [`wire`]: ARCOS, SICK LMS1xx (CoLa-A) and LMS200 wire formats.
//! - `record` (feature `record`, host only): mission recordings as MCAP with Foxglove's
//!   schemas; `live` (feature `live`, host only): the same messages served live to Foxglove
//!   over a WebSocket.
//! - `onboard` (feature `onboard`): the runtime around the core on the robot.
#![cfg_attr(not(feature = "std"), no_std)]
#![warn(missing_docs)]

pub mod capacity;
#[cfg(feature = "std")]
pub mod command_line;
pub mod config;
pub mod control;
pub mod explore;
#[cfg(feature = "std")]
pub mod files;
pub mod frontier;
pub mod geometry;
pub mod grid;
#[cfg(feature = "std")]
mod heap;
#[cfg(feature = "live")]
pub mod live;
pub mod localize;
#[cfg(feature = "std")]
pub mod mapfile;
pub mod math;
pub mod mission;
pub mod optim;
#[cfg(feature = "picture")]
pub mod picture;
pub mod planner;
pub mod random;
pub mod raycast;
#[cfg(feature = "record")]
pub mod record;
pub mod sensor;
pub mod units;
pub mod wire;

#[cfg(feature = "onboard")]
pub mod onboard;
