//! The onboard runtime: links, the ARCOS and laser sessions, persistence and telemetry, and
//! the start-up and shutdown sequences of the `papillon` binary.
//!
//! Everything here is std and tokio; the mission logic itself stays in the sans-IO core and is
//! pumped by [`runtime`]. Layers, bottom up:
//! - [`link`]: byte links (serial, TCP, in-memory) and reconnection with back-off;
//! - [`codec`]: the session codecs over `crate::wire` (ARCOS commands and packets, CoLa-A);
//! - [`robot`]: the ARCOS client session (handshake, CONFIG check, HOSTBAUD, keep-alive, safe
//!   stop, velocities only as the core's clamped `Velocity`);
//! - [`laser`]: the LMS1xx client session; [`lms200`]: the LMS200 one;
//! - [`driver`]: the seam between the pump and a mission ([`driver::MissionDriver`]);
//! - [`mission`]: the core mission on its own thread, as the runtime's mission driver;
//! - [`persist`]: atomic saving and loading of the mission state, telemetry;
//! - [`record`]: the mission's MCAP recording (`mission.mcap`, see `crate::record`);
//! - [`pose_history`]: odometry readings with their times, interpolated to a scan's time;
//! - [`sensor_clock`]: status packets and scans placed on the host clock by the devices' own clocks;
//! - [`runtime`]: `papillon run` and `papillon probe`;
//! - [`calibrate`]: `papillon calibrate` (UMBmark).

pub mod calibrate;
pub mod codec;
pub mod driver;
pub mod laser;
pub mod link;
pub mod lms200;
pub mod mission;
pub mod persist;
pub mod pose_history;
pub mod record;
pub mod robot;
pub mod runtime;
pub mod sensor_clock;

#[cfg(test)]
mod testkit;
