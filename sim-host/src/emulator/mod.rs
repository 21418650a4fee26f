//! Emulated robot hardware: the P3-DX microcontroller (ARCOS), the SICK LMS1xx (CoLa-A) and
//! the SICK LMS200 (RS-232 telegrams).
//!
//! Both emulators are sans-IO: they take the bytes a client sent and the current time, and
//! append the bytes to send back to a caller's buffer. The caller owns the sockets, the pty
//! and the clock (see [`crate::serve`]).

pub mod arcos;
pub mod lms1xx;
pub mod lms200;
