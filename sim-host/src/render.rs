//! Pictures of exploration maps: the drawing is the `papillon` crate's ([`papillon::picture`],
//! feature `picture`), shared with the onboard `map.png`; re-exported here for the simulator's
//! callers.

pub use papillon::picture::*;
