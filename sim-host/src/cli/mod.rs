//! Subcommands of `papillon-sim`, one module each.

pub mod bench;
pub mod mission;
pub mod optimize;
pub mod plan;
pub mod score;
pub mod serve;
