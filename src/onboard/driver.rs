//! The seam between the runtime's pump ([`super::runtime`]) and a mission: the
//! [`MissionDriver`] trait, what a step asks of the robot ([`MissionCommand`]) and the
//! telemetry a mission wants written ([`TelemetryRecord`]). The core mission implements it in
//! [`super::mission`]; the pump's tests implement it with scripted doubles.

use super::persist::{MapImage, MissionState};
use super::robot::Fault;
use crate::control::command::Velocity;
use crate::sensor::Scan;
use crate::wire::arcos::StatusPacket;

/// A telemetry line a mission wants written (`{"t_s", "kind", ...fields}`).
#[derive(Clone, Debug, PartialEq)]
pub struct TelemetryRecord {
    /// Mission time \[s\].
    pub t_s: f64,
    /// The record's kind (`decision`, `replan`, `done`, ...).
    pub kind: &'static str,
    /// Its fields (a JSON object).
    pub fields: serde_json::Value,
}

/// What the mission asks the robot to do after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MissionCommand {
    /// Drive at this velocity. A [`Velocity`] is only made by `Limits::clamp` (the core's
    /// safety monitor, or a caller's own limits): it is within the limits it was built with,
    /// all the way to the VEL and RVEL bytes ([`super::robot::ArcosClient::drive`]).
    Drive(Velocity),
    /// Stand still (thinking, or waiting for scans): nothing is sent.
    Hold,
    /// The mission is complete.
    Done,
}

/// The mission state machine as the runtime sees it (sans-IO: it is given times and data).
pub trait MissionDriver: Send {
    /// A status packet arrived at mission time `t_s` \[s\].
    fn on_status(&mut self, t_s: f64, status: &StatusPacket);
    /// A scan arrived at mission time `t_s` \[s\].
    fn on_scan(&mut self, t_s: f64, scan: &Scan);
    /// The runtime stopped the robot for `fault`; the mission must re-plan before moving.
    fn on_fault(&mut self, t_s: f64, fault: Fault);
    /// The runtime lost a link and is connecting again (the saved counters count it).
    fn on_reconnect(&mut self);
    /// Whether the mission has re-planned since its last fault (the runtime then clears the
    /// latch and lets motion through again).
    fn replanned(&self) -> bool;
    /// One control step at mission time `t_s` \[s\].
    fn step(&mut self, t_s: f64) -> MissionCommand;
    /// The state to save.
    fn snapshot(&self) -> (MissionState, Option<MapImage>);
    /// Telemetry lines produced since the last call (decisions with their compute time...).
    fn take_telemetry(&mut self) -> Vec<TelemetryRecord> {
        Vec::new()
    }
}
