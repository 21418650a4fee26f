//! Wire formats: ARCOS (Pioneer P3-DX microcontroller), SICK LMS1xx CoLa-A and SICK LMS200.
//!
//! Each protocol follows the same two layers (after smoltcp's `wire` module): a checked view
//! over a byte buffer (framing, length, checksum) and parsed representations ("Reprs") with
//! `parse`, `emit` and `buffer_len`. A streaming decoder per protocol turns an arbitrary byte
//! stream (split or merged reads, junk, corruption) into frames using a fixed buffer, counts
//! what it had to drop and never panics. The robot-side runtime and the emulators in the
//! simulator use the same types in both directions.
//!
//! Facts (field layouts, byte examples) are written down in the project's protocol notes
//! (`docs/protocols.md`), drawn from public manuals, driver sources read for facts and wire
//! captures.
//! Nothing here is derived from driver code.

pub mod arcos;
pub mod bytes;
pub mod lms1xx;
pub mod lms200;
