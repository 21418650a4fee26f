//! The ARCOS client session: handshake, start-up, keep-alive, motion commands and a safe stop.
//!
//! Sequence (fact sheet 1.2–1.4): SYNC0, SYNC1, SYNC2 (each must be answered with the same ID
//! within a second, else start again from SYNC0; a status packet means an old session is still
//! open, so CLOSE it first), read the robot's name, class and subclass from the SYNC2 reply,
//! OPEN, request CONFIG and check the class (`Pioneer`) and the subclass against the board,
//! switch the serial speed up with HOSTBAUD when CONFIG's AutoBaud is 2, then ENABLE the motors
//! and apply the board's speed and acceleration limits.
//!
//! Units: the subclass names the robot's conversion factors
//! ([`ConversionFactors::for_subclass`]; a robot whose subclass has none is refused). The
//! session hands on status packets in the units of ARCOS on a P3-DX-SH whatever the robot: XPOS
//! and YPOS as millimetre counters (converted by a [`SipUnitConverter`]), wheel velocities in
//! mm/s, THPOS and CONTROL in 2π/4096 rad; and it writes the millimetres of a MOVE and the
//! mm/s of a VEL in the robot's units. On a `p3dx` (DistConvFactor 0.485) a MOVE of 485 mm
//! leaves as MOVE 1000.
//!
//! Safety rules this session enforces:
//! - keep-alive: PULSE when nothing else was sent for 500 ms (a quarter of the firmware
//!   watchdog if that is shorter), so the firmware watchdog (2 s by default) only fires when
//!   this program or its link is really gone;
//! - the session never repeats a velocity on its own; after [`ArcosClient::halt`] every
//!   motion command is refused until [`ArcosClient::clear_fault`] (the mission calls it after a
//!   fresh re-plan), so a stale velocity can never be re-sent after a fault;
//! - [`ArcosClient::stop_and_close`]: VEL 0, RVEL 0, STOP, ENABLE 0, 100 ms, CLOSE 1.
//!
//! The session speaks the wire's own types: it sends [`Command`]s and reads [`ServerPacket`]s
//! (status packets reach the mission as the wire's [`StatusPacket`]) through
//! [`ArcosCodec`]. The only velocity it sends on its own is zero; a moving one comes in as a
//! [`Velocity`] (made only by `Limits::clamp`, in the core's safety monitor) through
//! [`ArcosClient::drive`], which writes its two halves as VEL and RVEL.

use std::collections::VecDeque;
use std::fmt;
use std::io;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::Instant;

use super::codec::{ArcosCodec, CodecStats};
use super::link::RobotLink;
use crate::config::{ARCOS_BAUD_RATES, BoardConfig, KNOWN_SUBCLASSES};
use crate::control::command::Velocity;
use crate::control::odometry::{ConversionFactors, SipUnitConverter};
use crate::wire::arcos::{
    Command, ConfigPacket, Name, ServerPacket, StatusPacket, SyncReply, config, encoder,
};

/// The robot's identity from the SYNC2 reply.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RobotIdentity {
    /// Robot name (`AMRISim`, `IIT-madras_3906`).
    pub name: Name,
    /// Robot class (`Pioneer`).
    pub class: Name,
    /// Robot subclass (`p3dx-sh`).
    pub subclass: Name,
}

/// Session timing and checks.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionOptions {
    /// Subclass the robot must report (case-insensitive); `None` accepts any known P3-DX
    /// subclass.
    pub expected_subclass: Option<String>,
    /// Serial speed to switch to when the robot allows it \[baud\]; `None` never switches.
    pub switch_to_baud: Option<u32>,
    /// Wait for each SYNC reply.
    pub sync_timeout: Duration,
    /// Handshake attempts (each from SYNC0) before giving up.
    pub sync_attempts: u32,
    /// Wait for the CONFIG packet after each request.
    pub config_timeout: Duration,
    /// CONFIG requests before giving up: a request is sent again when no whole CONFIG packet
    /// came within `config_timeout` (a byte corrupted on the line loses the whole packet: at
    /// 1 % of bytes corrupted, about two CONFIG packets in three).
    pub config_attempts: u32,
    /// Wait for any packet after a HOSTBAUD switch before reverting.
    pub baud_probe_timeout: Duration,
    /// Send PULSE when nothing else was sent for this long.
    pub keepalive: Duration,
    /// Least time between two commands (the firmware loses commands sent faster than one per
    /// 3–5 ms, fact sheet 1.2).
    pub command_spacing: Duration,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            expected_subclass: None,
            switch_to_baud: Some(38400),
            sync_timeout: Duration::from_millis(1000),
            sync_attempts: 6,
            config_timeout: Duration::from_millis(1000),
            config_attempts: 16,
            baud_probe_timeout: Duration::from_millis(900),
            keepalive: Duration::from_millis(500),
            command_spacing: Duration::from_millis(5),
        }
    }
}

impl SessionOptions {
    /// Options for a board: its expected subclass and baud switch.
    pub fn from_board(board: &BoardConfig) -> Self {
        Self {
            expected_subclass: Some(board.robot.subclass.as_str().to_string()),
            switch_to_baud: Some(board.link.switch_to_baud),
            ..Self::default()
        }
    }
}

/// Motion limits sent at start-up (SETV, SETRV, SETA ±, SETRA ±).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotionLimits {
    /// SETV \[mm/s\].
    pub max_speed_mm_s: i16,
    /// SETRV \[deg/s\].
    pub max_turn_rate_deg_s: i16,
    /// SETA \[mm/s²\].
    pub accel_mm_s2: i16,
    /// SETA with a negative argument \[mm/s²\].
    pub decel_mm_s2: i16,
    /// SETRA, both signs \[deg/s²\].
    pub rot_accel_deg_s2: i16,
}

fn to_i16(v: f32) -> i16 {
    if v.is_finite() {
        v.round().clamp(0.0, i16::MAX as f32) as i16
    } else {
        0
    }
}

impl MotionLimits {
    /// The board's limits, rounded to whole units.
    pub fn from_board(board: &BoardConfig) -> Self {
        let r = &board.robot;
        Self {
            max_speed_mm_s: to_i16(r.max_speed_mm_s),
            max_turn_rate_deg_s: to_i16(r.max_turn_rate_deg_s),
            accel_mm_s2: to_i16(r.accel_mm_s2),
            decel_mm_s2: to_i16(r.decel_mm_s2),
            rot_accel_deg_s2: to_i16(r.rot_accel_deg_s2),
        }
    }

    /// The start-up commands, in the order they are sent.
    pub fn commands(&self) -> [Command; 6] {
        [
            Command::SetV(self.max_speed_mm_s),
            Command::SetRv(self.max_turn_rate_deg_s),
            Command::SetA(self.accel_mm_s2),
            Command::SetA(-self.decel_mm_s2),
            Command::SetRa(self.rot_accel_deg_s2),
            Command::SetRa(-self.rot_accel_deg_s2),
        ]
    }
}

/// Why the robot was stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Fault {
    /// No status packet within the stale timeout.
    StaleStatus,
    /// No laser scan within the stale timeout.
    StaleScan,
    /// The e-stop is pressed.
    EStop,
    /// The motors are disabled (FLAGS bit 0 clear) while the mission wants to move.
    MotorsDisabled,
    /// A wheel stalled or a bumper was hit.
    Contact,
    /// The link failed (read or write error, or end of stream).
    Link,
    /// An obstacle closer than the safety distance.
    Obstacle,
    /// Asked to stop by the operator (a signal).
    Operator,
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Fault::StaleStatus => "no status packet within the stale timeout",
            Fault::StaleScan => "no laser scan within the stale timeout",
            Fault::EStop => "e-stop pressed",
            Fault::MotorsDisabled => "motors disabled",
            Fault::Contact => "wheel stall or bumper contact",
            Fault::Link => "link error",
            Fault::Obstacle => "obstacle inside the safety distance",
            Fault::Operator => "stopped by the operator",
        })
    }
}

/// Errors of the ARCOS session.
#[derive(Debug)]
#[non_exhaustive]
pub enum SessionError {
    /// The link failed.
    Io(io::Error),
    /// The link reached its end (the peer closed it).
    Closed,
    /// No complete SYNC0/1/2 exchange.
    HandshakeFailed {
        /// Attempts made.
        attempts: u32,
        /// The last packet ID seen during the handshake, if any.
        last_id: Option<u8>,
    },
    /// The robot is not a Pioneer.
    WrongClass {
        /// The class it reported.
        got: String,
    },
    /// The robot's subclass is not the one the board expects, or (when `expected` is not one
    /// known subclass) not a subclass whose conversion factors are known.
    WrongSubclass {
        /// The subclass it reported.
        got: String,
        /// The board's subclass, or the known subclasses (`p3dx, p3dx-sh, …`) when the robot's
        /// subclass has no known conversion factors.
        expected: String,
    },
    /// A MOVE or VEL argument does not fit the command in the robot's units.
    OutOfRange {
        /// The command (`MOVE`, `VEL`).
        command: &'static str,
        /// The argument asked for \[mm or mm/s\].
        value: i32,
    },
    /// No CONFIG packet arrived.
    NoConfig,
    /// The microcontroller reset (packet 0xFE / 0xFF).
    MicrocontrollerReset {
        /// The ID seen.
        id: u8,
    },
    /// A motion command was refused because of a latched fault.
    Faulted(Fault),
}

impl fmt::Display for SessionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SessionError::Io(e) => write!(f, "robot link error: {e}"),
            SessionError::Closed => write!(f, "the robot closed the link"),
            SessionError::HandshakeFailed { attempts, last_id } => match last_id {
                Some(id) => write!(
                    f,
                    "no ARCOS handshake after {attempts} attempts (last packet ID 0x{id:02X}); is the robot on and the port right?"
                ),
                None => write!(
                    f,
                    "no ARCOS handshake after {attempts} attempts (the robot never answered); is the robot on and the port right?"
                ),
            },
            SessionError::WrongClass { got } => {
                write!(f, "robot class is {got:?}, expected \"Pioneer\"")
            }
            SessionError::WrongSubclass { got, expected } => {
                if ConversionFactors::for_subclass(expected).is_some() {
                    write!(
                        f,
                        "robot subclass is {got:?} but the board expects {expected:?}"
                    )
                } else {
                    write!(
                        f,
                        "robot subclass {got:?} is not a P3-DX subclass whose conversion factors are known (known: {expected})"
                    )
                }
            }
            SessionError::OutOfRange { command, value } => write!(
                f,
                "{command} {value} does not fit the command's 16-bit argument in the robot's units"
            ),
            SessionError::NoConfig => write!(
                f,
                "the robot sent no whole CONFIG packet (asked several times); is the line very noisy?"
            ),
            SessionError::MicrocontrollerReset { id } => {
                write!(f, "the microcontroller reset (packet 0x{id:02X})")
            }
            SessionError::Faulted(fault) => {
                write!(
                    f,
                    "motion refused until a re-plan clears the fault: {fault}"
                )
            }
        }
    }
}

impl std::error::Error for SessionError {}

impl From<io::Error> for SessionError {
    fn from(e: io::Error) -> Self {
        SessionError::Io(e)
    }
}

/// Something the robot reported.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum RobotEvent {
    /// A status packet and when it was read.
    Status {
        /// Arrival time.
        at: Instant,
        /// The packet (boxed: a SIP carries up to 32 sonar readings).
        status: Box<StatusPacket>,
    },
    /// A CONFIG packet (after a CONFIG request).
    Config(Box<ConfigPacket>),
    /// Any other packet ID.
    Other {
        /// The ID.
        id: u8,
    },
}

/// The outcome of the HOSTBAUD step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BaudSwitch {
    /// Not attempted: TCP link, no auto-baud, or no higher speed asked for.
    NotAttempted,
    /// Switched to this speed \[baud\].
    Switched(u32),
    /// Tried this speed \[baud\]; no packet came back, so the link went back to its old speed.
    Reverted(u32),
}

/// Counters of the session, for the telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SessionStats {
    /// Commands written.
    pub commands_sent: u64,
    /// PULSE keep-alives written.
    pub pulses_sent: u64,
    /// Status packets received.
    pub status_packets: u64,
    /// Decoder counters.
    pub codec: CodecStats,
}

/// An open ARCOS session.
pub struct ArcosClient {
    link: Box<dyn RobotLink>,
    codec: ArcosCodec,
    options: SessionOptions,
    identity: RobotIdentity,
    config: Option<ConfigPacket>,
    baud_switch: BaudSwitch,
    pending: VecDeque<ServerPacket>,
    decoded: Vec<ServerPacket>,
    encoded: Vec<u8>,
    read_buf: Box<[u8; 512]>,
    last_sent: Instant,
    /// PULSE keep-alives are on once the session is open (a PULSE during the handshake would
    /// read as SYNC0).
    keepalive_on: bool,
    fault: Option<Fault>,
    stats: SessionStats,
    /// The robot's units to the P3-DX-SH's (identity until CONFIG names the subclass).
    units: SipUnitConverter,
}

impl ArcosClient {
    /// Performs the handshake, OPEN, CONFIG check and (on serial links) the HOSTBAUD switch.
    /// The motors are still disabled afterwards; call [`ArcosClient::start`].
    pub async fn connect(
        link: Box<dyn RobotLink>,
        options: SessionOptions,
    ) -> Result<Self, SessionError> {
        let mut client = Self {
            link,
            codec: ArcosCodec::default(),
            options,
            identity: RobotIdentity::default(),
            config: None,
            baud_switch: BaudSwitch::NotAttempted,
            pending: VecDeque::new(),
            decoded: Vec::new(),
            encoded: Vec::new(),
            read_buf: Box::new([0u8; 512]),
            last_sent: Instant::now(),
            keepalive_on: false,
            fault: None,
            stats: SessionStats::default(),
            units: SipUnitConverter::new(ConversionFactors::ARCOS_SH),
        };
        client.handshake().await?;
        client.check_identity(&client.identity.class, &client.identity.subclass)?;
        client.send(&Command::Open(Some(1))).await?;
        client.keepalive_on = true;
        let config = client.request_config().await?;
        client.check_identity(&config.robot_type, &config.subtype)?;
        // check_identity refused a subclass without factors.
        if let Some(factors) = ConversionFactors::for_subclass(&config.subtype) {
            client.units = SipUnitConverter::new(factors);
        }
        // A robot whose FLASH watchdog is shorter than four keep-alive periods gets PULSEs
        // four times per watchdog period: a short watchdog (so that a cut serial line stops
        // the robot quickly) is never tripped by a live program.
        if config.watchdog_ms > 0 {
            let quarter = Duration::from_millis(u64::from(config.watchdog_ms) / 4);
            client.options.keepalive = client
                .options
                .keepalive
                .min(quarter.max(client.options.command_spacing));
        }
        client.config = Some(config);
        client.baud_switch = client.switch_baud().await?;
        Ok(client)
    }

    async fn handshake(&mut self) -> Result<(), SessionError> {
        let mut last_id = None;
        for _attempt in 0..self.options.sync_attempts {
            // A corrupted length byte leaves the decoder waiting for a frame that never
            // ends, which would swallow the next replies: start each attempt afresh.
            self.codec.reset();
            self.pending.clear();
            let mut step = 0u8;
            while step <= 2 {
                let sync = match step {
                    0 => Command::SYNC0,
                    1 => Command::SYNC1,
                    _ => Command::SYNC2,
                };
                self.send(&sync).await?;
                let deadline = Instant::now() + self.options.sync_timeout;
                let Some(packet) = self.next_packet(deadline).await? else {
                    break; // silent: start again from SYNC0
                };
                match packet {
                    ServerPacket::Sync(SyncReply::Sync0) if step == 0 => step += 1,
                    ServerPacket::Sync(SyncReply::Sync1) if step == 1 => step += 1,
                    ServerPacket::Sync(SyncReply::Sync2 {
                        name,
                        class,
                        subclass,
                    }) if step == 2 => {
                        self.identity = RobotIdentity {
                            name,
                            class,
                            subclass,
                        };
                        return Ok(());
                    }
                    ServerPacket::Status(_) => {
                        // An old session is still open: close it and start over.
                        last_id = Some(0x32);
                        self.send(&Command::Close(Some(1))).await?;
                        self.drain(Duration::from_millis(200)).await?;
                        break;
                    }
                    other => {
                        last_id = Some(packet_id(&other));
                        break;
                    }
                }
            }
        }
        Err(SessionError::HandshakeFailed {
            attempts: self.options.sync_attempts,
            last_id,
        })
    }

    /// Reads and discards whatever arrives for `wait`.
    async fn drain(&mut self, wait: Duration) -> Result<(), SessionError> {
        let deadline = Instant::now() + wait;
        while self.next_packet(deadline).await?.is_some() {}
        Ok(())
    }

    fn check_identity(&self, class: &str, subclass: &str) -> Result<(), SessionError> {
        if !class.eq_ignore_ascii_case("pioneer") {
            return Err(SessionError::WrongClass {
                got: class.to_string(),
            });
        }
        if let Some(expected) = &self.options.expected_subclass
            && !subclass.eq_ignore_ascii_case(expected)
        {
            return Err(SessionError::WrongSubclass {
                got: subclass.to_string(),
                expected: expected.clone(),
            });
        }
        if ConversionFactors::for_subclass(subclass).is_none() {
            return Err(SessionError::WrongSubclass {
                got: subclass.to_string(),
                expected: KNOWN_SUBCLASSES.join(", "),
            });
        }
        Ok(())
    }

    /// Sends the CONFIG request until a CONFIG packet comes back, at most
    /// `config_attempts` times.
    async fn request_config(&mut self) -> Result<ConfigPacket, SessionError> {
        for attempt in 1..=self.options.config_attempts.max(1) {
            self.send(&Command::Config(Some(1))).await?;
            match self.await_config().await {
                Err(SessionError::NoConfig) => {
                    tracing::debug!(attempt, "no whole CONFIG packet; asking again");
                }
                other => return other,
            }
        }
        Err(SessionError::NoConfig)
    }

    async fn await_config(&mut self) -> Result<ConfigPacket, SessionError> {
        let deadline = Instant::now() + self.options.config_timeout;
        loop {
            match self.next_packet(deadline).await? {
                None => return Err(SessionError::NoConfig),
                Some(ServerPacket::Config(c)) => return Ok(c),
                Some(ServerPacket::Reset { id }) => {
                    return Err(SessionError::MicrocontrollerReset { id });
                }
                Some(ServerPacket::Status(_)) => {
                    self.stats.status_packets += 1;
                }
                Some(_) => {}
            }
        }
    }

    /// HOSTBAUD per fact sheet 1.3: only on a serial link, when CONFIG's AutoBaud is 2 and the
    /// board's speed is higher than the current one.
    async fn switch_baud(&mut self) -> Result<BaudSwitch, SessionError> {
        let (Some(current), Some(target), Some(config)) = (
            self.link.baud(),
            self.options.switch_to_baud,
            self.config.as_ref(),
        ) else {
            return Ok(BaudSwitch::NotAttempted);
        };
        if config.auto_baud != 2 || target <= current {
            return Ok(BaudSwitch::NotAttempted);
        }
        let Some(code) = ARCOS_BAUD_RATES.iter().position(|&b| b == target) else {
            return Ok(BaudSwitch::NotAttempted);
        };
        self.send(&Command::HostBaud(code as i16)).await?;
        tokio::time::sleep(Duration::from_millis(10)).await;
        self.link.set_baud(target)?;
        self.codec.reset();
        self.pending.clear();
        self.send(&Command::Pulse).await?;
        let deadline = Instant::now() + self.options.baud_probe_timeout;
        if self.next_packet(deadline).await?.is_some() {
            Ok(BaudSwitch::Switched(target))
        } else {
            self.link.set_baud(current)?;
            self.codec.reset();
            Ok(BaudSwitch::Reverted(target))
        }
    }

    /// Enables the motors and applies the board's limits.
    pub async fn start(&mut self, limits: &MotionLimits) -> Result<(), SessionError> {
        self.send(&Command::Enable(true)).await?;
        for command in limits.commands() {
            self.send(&command).await?;
        }
        Ok(())
    }

    /// The robot's SYNC2 identity.
    pub fn identity(&self) -> &RobotIdentity {
        &self.identity
    }

    /// The conversion factors of the robot's subclass.
    pub fn factors(&self) -> ConversionFactors {
        self.units.factors()
    }

    /// The CONFIG packet read at connection.
    pub fn config(&self) -> Option<&ConfigPacket> {
        self.config.as_ref()
    }

    /// What the HOSTBAUD step did.
    pub fn baud_switch(&self) -> BaudSwitch {
        self.baud_switch
    }

    /// What kind of link the session runs on.
    pub fn link_kind(&self) -> super::link::LinkKind {
        self.link.kind()
    }

    /// The link's description.
    pub fn link_description(&self) -> String {
        self.link.describe()
    }

    /// Session and decoder counters.
    pub fn stats(&self) -> SessionStats {
        SessionStats {
            codec: self.codec.stats(),
            ..self.stats
        }
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<Fault> {
        self.fault
    }

    /// Commands `velocity`: VEL with its speed \[mm/s\], then RVEL with its turn rate \[deg/s,
    /// counter-clockwise\]. A [`Velocity`] is within the limits that made it. Refused while a
    /// fault is latched.
    pub async fn drive(&mut self, velocity: Velocity) -> Result<(), SessionError> {
        if let Some(fault) = self.fault {
            return Err(SessionError::Faulted(fault));
        }
        self.send(&Command::Vel(velocity.speed_mm_s())).await?;
        self.send(&Command::RVel(velocity.turn_rate_deg_s())).await
    }

    /// Latches `fault` and commands zero velocity at once. Motion stays refused until
    /// [`ArcosClient::clear_fault`]. A link error while stopping is returned (the firmware
    /// watchdog then stops the robot).
    pub async fn halt(&mut self, fault: Fault) -> Result<(), SessionError> {
        if self.fault.is_none() {
            self.fault = Some(fault);
        }
        self.send(&Command::Vel(0)).await?;
        self.send(&Command::RVel(0)).await
    }

    /// Clears a latched fault; the caller must have re-planned (no old velocity is kept).
    pub fn clear_fault(&mut self) {
        self.fault = None;
    }

    /// Waits for the next event until `deadline`, sending PULSE whenever nothing was sent for
    /// the keep-alive period. `Ok(None)` at the deadline.
    pub async fn next_event(
        &mut self,
        deadline: Instant,
    ) -> Result<Option<RobotEvent>, SessionError> {
        loop {
            let Some(packet) = self.next_packet(deadline).await? else {
                return Ok(None);
            };
            match packet {
                ServerPacket::Status(mut status) => {
                    self.stats.status_packets += 1;
                    self.convert_to_arcos_sh_units(&mut status);
                    return Ok(Some(RobotEvent::Status {
                        at: Instant::now(),
                        status: Box::new(status),
                    }));
                }
                ServerPacket::Config(c) => return Ok(Some(RobotEvent::Config(Box::new(c)))),
                ServerPacket::Reset { id } => {
                    self.fault.get_or_insert(Fault::Link);
                    return Err(SessionError::MicrocontrollerReset { id });
                }
                ServerPacket::Sync(_) => {}
                other => {
                    return Ok(Some(RobotEvent::Other {
                        id: packet_id(&other),
                    }));
                }
            }
        }
    }

    /// Rewrites a status packet's positions, headings and wheel velocities in P3-DX-SH units.
    fn convert_to_arcos_sh_units(&mut self, status: &mut StatusPacket) {
        let factors = self.units.factors();
        (status.x_pos, status.y_pos) = self.units.position_mm(status.x_pos, status.y_pos);
        status.th_pos = factors.heading_units(status.th_pos);
        status.control = factors.heading_units(status.control);
        status.left_vel_mm_s = factors.velocity_mm_s(status.left_vel_mm_s);
        status.right_vel_mm_s = factors.velocity_mm_s(status.right_vel_mm_s);
    }

    /// A command as the robot reads it: MOVE's millimetres and VEL's mm/s in its units.
    fn in_robot_units(&self, command: &Command) -> Result<Command, SessionError> {
        let factors = self.units.factors();
        Ok(match *command {
            Command::Move(mm) => Command::Move(factors.move_argument(i32::from(mm)).ok_or(
                SessionError::OutOfRange {
                    command: "MOVE",
                    value: i32::from(mm),
                },
            )?),
            Command::Vel(mm_s) => {
                Command::Vel(factors.vel_argument(mm_s).ok_or(SessionError::OutOfRange {
                    command: "VEL",
                    value: i32::from(mm_s),
                })?)
            }
            ref other => other.clone(),
        })
    }

    /// The next decoded packet before `deadline`, keeping the link alive meanwhile.
    async fn next_packet(
        &mut self,
        deadline: Instant,
    ) -> Result<Option<ServerPacket>, SessionError> {
        loop {
            if let Some(p) = self.pending.pop_front() {
                return Ok(Some(p));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let pulse_at = if self.keepalive_on {
                self.last_sent + self.options.keepalive
            } else {
                deadline
            };
            let wake = pulse_at.min(deadline);
            tokio::select! {
                read = self.link.read(&mut self.read_buf[..]) => {
                    let n = read?;
                    if n == 0 {
                        self.fault.get_or_insert(Fault::Link);
                        return Err(SessionError::Closed);
                    }
                    self.decoded.clear();
                    self.codec.decode(&self.read_buf[..n], &mut self.decoded);
                    self.pending.extend(self.decoded.drain(..));
                }
                _ = tokio::time::sleep_until(wake) => {
                    if self.keepalive_on && Instant::now() >= pulse_at {
                        self.send(&Command::Pulse).await?;
                        self.stats.pulses_sent += 1;
                    }
                }
            }
        }
    }

    /// Writes one command, keeping the minimum spacing between commands. A MOVE \[mm\] and a
    /// VEL \[mm/s\] are written in the robot's units (see the module documentation).
    pub async fn send(&mut self, command: &Command) -> Result<(), SessionError> {
        let command = &self.in_robot_units(command)?;
        let earliest = self.last_sent + self.options.command_spacing;
        if Instant::now() < earliest && self.stats.commands_sent > 0 {
            tokio::time::sleep_until(earliest).await;
        }
        self.encoded.clear();
        self.codec.encode(command, &mut self.encoded);
        let result = async {
            self.link.write_all(&self.encoded).await?;
            self.link.flush().await
        }
        .await;
        if let Err(e) = result {
            self.fault.get_or_insert(Fault::Link);
            return Err(e.into());
        }
        self.last_sent = Instant::now();
        self.stats.commands_sent += 1;
        Ok(())
    }

    /// Stops the robot and ends the session: VEL 0, RVEL 0, STOP, ENABLE 0, 100 ms, CLOSE 1.
    /// Every step is attempted even if an earlier write failed; the first error is returned.
    pub async fn stop_and_close(mut self) -> Result<SessionStats, SessionError> {
        self.fault.get_or_insert(Fault::Operator);
        let mut first_err = None;
        for command in [
            Command::Vel(0),
            Command::RVel(0),
            Command::Stop,
            Command::Enable(false),
        ] {
            if let Err(e) = self.send(&command).await {
                first_err.get_or_insert(e);
            }
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
        if let Err(e) = self.send(&Command::Close(Some(1))).await {
            first_err.get_or_insert(e);
        }
        let _ = self.link.shutdown().await;
        match first_err {
            Some(e) => Err(e),
            None => Ok(self.stats()),
        }
    }
}

/// The packet ID a packet came with.
fn packet_id(p: &ServerPacket) -> u8 {
    match p {
        ServerPacket::Sync(SyncReply::Sync0) => 0,
        ServerPacket::Sync(SyncReply::Sync1) => 1,
        ServerPacket::Sync(SyncReply::Sync2 { .. }) => 2,
        ServerPacket::Config(_) => config::ID,
        ServerPacket::Status(s) => s.id(),
        ServerPacket::Encoder(_) => encoder::ID,
        ServerPacket::Reset { id } | ServerPacket::Other { id } => *id,
    }
}

#[cfg(test)]
mod tests;
