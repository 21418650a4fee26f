//! What the ARCOS client session needs from the ARCOS wire codec.
//!
//! The session ([`super::robot`]) speaks in [`ClientCommand`]s and [`Incoming`] packets; an
//! [`ArcosCodec`] turns commands into frames and a received byte stream into packets. The codec
//! proper (framing, checksums, SIP/CONFIG layouts, resynchronisation) lives in `crate::wire::arcos`
//! on the wire branch; **integration point:** an adapter `impl ArcosCodec for WireArcos` maps
//! `wire::arcos::Command` / `ServerPacket` / `StatusPacket` / `ConfigPacket` /
//! `FrameDecoder` onto these types field for field (the field names below follow that API),
//! and [`super::runtime::arcos_codec`] returns it. Until then the runtime has no codec and says
//! so; the session is tested with a test double (`super::testkit`).
//!
//! The adapter, as the wire API stands on its branch:
//! - `encode`: `Sync(0|1|2)` → `Command::Pulse` / `Open(None)` / `Close(None)` (bare);
//!   `Open` → `Open(Some(1))`, `Close` → `Close(Some(1))`, `Config` → `Config(Some(1))`; every
//!   other variant maps to the `Command` of the same name; then `Command::emit`.
//! - `decode`: loop `FrameDecoder::decode(&mut input)`, then `ServerPacket::parse(&frame)`:
//!   `Sync(Sync0 | Sync1)` → [`Incoming::SyncEcho`], `Sync(Sync2 { .. })` →
//!   [`Incoming::Identity`], `Status(p)` → [`Incoming::Status`] (same field names),
//!   `Config(c)` → [`Incoming::Config`], `Reset { id }` → [`Incoming::Reset`], anything else →
//!   [`Incoming::Other`]; a parse error counts in [`CodecStats::bad_payloads`].
//! - `reset` → `FrameDecoder::reset`; `stats` → `FrameDecoder::stats`.

use std::fmt;

/// A command from the onboard PC to the microcontroller (fact sheet 1.5). Velocities in mm/s
/// or deg/s, accelerations in mm/s² or deg/s², as the firmware takes them.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ClientCommand {
    /// SYNC0, SYNC1 or SYNC2 (bare command 0, 1 or 2, no argument).
    Sync(u8),
    /// 0, no argument: keep-alive.
    Pulse,
    /// 1 with an int argument (ARIA sends 1): start the status stream.
    Open,
    /// 2 with an int argument (ARIA sends 1): close the session.
    Close,
    /// 4: enable (true) or disable the motors.
    Enable(bool),
    /// 5: translational acceleration (+) or deceleration (−) \[mm/s²\].
    SetA(i16),
    /// 6: maximum translational velocity \[mm/s\].
    SetV(i16),
    /// 7: reset odometry to (0, 0, 0).
    SetO,
    /// 10: maximum rotational velocity \[deg/s\].
    SetRv(i16),
    /// 11: translational velocity \[mm/s\].
    Vel(i16),
    /// 18 with int 1: request a CONFIG packet.
    Config,
    /// 21: rotational velocity \[deg/s\], counter-clockwise positive.
    RVel(i16),
    /// 23: rotational acceleration (+) or deceleration (−) \[deg/s²\].
    SetRa(i16),
    /// 29: stop.
    Stop,
    /// 50: host port baud code (0 = 9600 … 4 = 115200).
    HostBaud(i16),
    /// 62: battery packets (0, 1, 2).
    BatteryInfo(i16),
}

impl ClientCommand {
    /// Whether this command sets a velocity (the commands a fault must never let through).
    pub fn is_motion(&self) -> bool {
        matches!(self, ClientCommand::Vel(v) | ClientCommand::RVel(v) if *v != 0)
    }
}

/// The robot's identity from the SYNC2 reply.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RobotIdentity {
    /// Robot name (`AMRISim`, `IIT-madras_3906`).
    pub name: String,
    /// Robot class (`Pioneer`).
    pub class: String,
    /// Robot subclass (`p3dx-sh`).
    pub subclass: String,
}

/// The CONFIG packet fields the onboard program uses or prints (fact sheet 1.7).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ConfigHighlights {
    /// Robot class (`Pioneer`).
    pub class: String,
    /// Robot subclass.
    pub subclass: String,
    /// Serial number.
    pub serial: String,
    /// Robot name.
    pub name: String,
    /// Absolute rotational speed limit \[deg/s\].
    pub rot_vel_top_deg_s: u16,
    /// Absolute translational speed limit \[mm/s\].
    pub trans_vel_top_mm_s: u16,
    /// Absolute rotational acceleration limit \[deg/s²\].
    pub rot_acc_top_deg_s2: u16,
    /// Absolute translational acceleration limit \[mm/s²\].
    pub trans_acc_top_mm_s2: u16,
    /// Status packet period \[ms\].
    pub sip_cycle_ms: u8,
    /// Host port baud code (0 = 9600 … 4 = 115200).
    pub host_baud_code: u8,
    /// Firmware watchdog \[ms\].
    pub watchdog_ms: u16,
    /// Current rotational speed limit \[deg/s\].
    pub rot_vel_max_deg_s: u16,
    /// Current translational speed limit \[mm/s\].
    pub trans_vel_max_mm_s: u16,
    /// 2 when the firmware implements auto-baud (HOSTBAUD switching allowed).
    pub auto_baud: u8,
    /// Firmware version string.
    pub firmware: String,
}

/// The status packet (SIP) fields the onboard program uses (fact sheet 1.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RobotStatus {
    /// Sent with ID 0x33 (moving) rather than 0x32.
    pub moving: bool,
    /// XPOS, 15-bit wrapping counter \[mm\].
    pub x_pos: u16,
    /// YPOS, as `x_pos`.
    pub y_pos: u16,
    /// THPOS \[2π/4096 rad\].
    pub th_pos: i16,
    /// Left wheel velocity \[mm/s\].
    pub left_vel_mm_s: i16,
    /// Right wheel velocity \[mm/s\].
    pub right_vel_mm_s: i16,
    /// Battery \[0.1 V\].
    pub battery_dv: u8,
    /// Stall and bumper bits.
    pub stall_bumpers: u16,
    /// FLAGS: bit 0 motors enabled, bit 5 e-stop.
    pub flags: u16,
}

impl RobotStatus {
    /// FLAGS bit 0.
    pub fn motors_enabled(&self) -> bool {
        self.flags & 0x0001 != 0
    }

    /// FLAGS bit 5: the e-stop is pressed.
    pub fn estop(&self) -> bool {
        self.flags & 0x0020 != 0
    }

    /// A wheel stalled (bit 0 or bit 8 of STALL AND BUMPERS).
    pub fn stalled(&self) -> bool {
        self.stall_bumpers & 0x0101 != 0
    }

    /// Any bumper segment pressed.
    pub fn bumped(&self) -> bool {
        self.stall_bumpers & 0xFEFE != 0
    }

    /// Battery voltage \[V\].
    pub fn battery_v(&self) -> f32 {
        self.battery_dv as f32 * 0.1
    }
}

/// A packet from the microcontroller.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Incoming {
    /// Echo of SYNC0 or SYNC1 (0 or 1).
    SyncEcho(u8),
    /// Reply to SYNC2.
    Identity(RobotIdentity),
    /// A CONFIG packet.
    Config(ConfigHighlights),
    /// A standard status packet.
    Status(RobotStatus),
    /// A microcontroller reset notice (ID 0xFE or 0xFF): the session is lost.
    Reset {
        /// The ID seen.
        id: u8,
    },
    /// Any other packet.
    Other {
        /// The ID seen.
        id: u8,
    },
}

/// Decoder counters, for link statistics in the telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CodecStats {
    /// Well-formed packets decoded.
    pub packets: u64,
    /// Frames dropped for a bad checksum.
    pub bad_checksums: u64,
    /// Bytes skipped while hunting for a frame header.
    pub junk_bytes: u64,
    /// Frames with a good checksum whose payload did not parse.
    pub bad_payloads: u64,
}

impl fmt::Display for CodecStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} packets, {} bad checksums, {} junk bytes, {} bad payloads",
            self.packets, self.bad_checksums, self.junk_bytes, self.bad_payloads
        )
    }
}

/// An ARCOS codec for the client side.
pub trait ArcosCodec: Send {
    /// Appends the complete frame of `command` to `out`.
    fn encode(&mut self, command: &ClientCommand, out: &mut Vec<u8>);

    /// Feeds received bytes (any split, junk, corruption); appends every packet completed by
    /// them to `out`. Never panics.
    fn decode(&mut self, bytes: &[u8], out: &mut Vec<Incoming>);

    /// Forgets any partial frame (after a baud change or a reconnect).
    fn reset(&mut self);

    /// Counters since the codec was made.
    fn stats(&self) -> CodecStats;
}
