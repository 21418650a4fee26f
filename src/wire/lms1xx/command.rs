//! CoLa-A requests (client → laser) and replies (laser → client).
//!
//! The two client connect sequences of the fact sheet:
//! - clearpath LMS1xx: `SetAccessMode`, `LMPscancfg`, `LMPoutputRange`, `LMDscandatacfg`,
//!   `LMCstartmeas`, `STlms` (must be 7), `Run`, `sEN LMDscandata 1`
//!   ([`Request::clearpath_connect_sequence`]);
//! - ARIA: `SetAccessMode`, `mLMPsetscancfg` (50 Hz), `LMDscandatacfg`, `Run`,
//!   `sEN LMDscandata 1` ([`Request::aria_connect_sequence`]).
//!
//! The two clients write some numbers differently (`03` vs `3`, hex vs `+5000`); a
//! [`Dialect`] on those requests reproduces each client's bytes exactly, and the parser
//! recognises the dialect from the bytes.

use core::fmt::Write;

use super::framing::emit_with;
use super::{EmitError, ParseError, Tokens, token_text};

/// How a client writes the numbers of a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Dialect {
    /// The clearpath LMS1xx driver: hex, zero-padded where it pads.
    #[default]
    Clearpath,
    /// ARIA: plain or signed-decimal numbers.
    Aria,
}

/// The "authorized client" access level.
pub const ACCESS_LEVEL_AUTHORIZED_CLIENT: u8 = 3;
/// The hashed password of the authorized client level.
pub const AUTHORIZED_CLIENT_PASSWORD: u32 = 0xF472_4744;
/// `STlms` state meaning "ready for measurement".
pub const STATE_READY: u8 = 7;

/// Scan frequency, resolution and angular range (`LMPscancfg`, `mLMPsetscancfg`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanConfig {
    /// Scan frequency \[0.01 Hz\] (5000 = 50 Hz).
    pub frequency_centi_hz: u32,
    /// Number of sectors.
    pub sectors: u32,
    /// Angular resolution \[1/10000 deg\] (5000 = 0.5°).
    pub resolution_deg_e4: u32,
    /// Start angle in SICK's frame \[1/10000 deg\] (−450000 = −45°).
    pub start_deg_e4: i32,
    /// Stop angle in SICK's frame \[1/10000 deg\] (2250000 = 225°).
    pub stop_deg_e4: i32,
}

impl ScanConfig {
    /// 50 Hz, 0.5°, −45° to 225° (the LMS1xx default the fact sheet shows).
    pub const DEFAULT_50HZ: ScanConfig = ScanConfig {
        frequency_centi_hz: 5000,
        sectors: 1,
        resolution_deg_e4: 5000,
        start_deg_e4: -450_000,
        stop_deg_e4: 2_250_000,
    };

    fn parse(t: &mut Tokens<'_>) -> Result<Self, ParseError> {
        Ok(ScanConfig {
            frequency_centi_hz: t.uint("scan frequency", u32::MAX)?,
            sectors: t.uint("sectors", u32::MAX)?,
            resolution_deg_e4: t.uint("resolution", u32::MAX)?,
            start_deg_e4: t.int32("start angle")?,
            stop_deg_e4: t.int32("stop angle")?,
        })
    }

    fn write_hex(&self, w: &mut impl Write) -> core::fmt::Result {
        write!(
            w,
            " {:X} {:X} {:X} {:X} {:X}",
            self.frequency_centi_hz,
            self.sectors,
            self.resolution_deg_e4,
            self.start_deg_e4 as u32,
            self.stop_deg_e4 as u32
        )
    }
}

/// Output range (`LMPoutputRange`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutputRange {
    /// Number of sectors.
    pub sectors: u32,
    /// Angular resolution \[1/10000 deg\].
    pub resolution_deg_e4: u32,
    /// Start angle in SICK's frame \[1/10000 deg\].
    pub start_deg_e4: i32,
    /// Stop angle in SICK's frame \[1/10000 deg\].
    pub stop_deg_e4: i32,
}

/// Scan data content configuration (`LMDscandatacfg`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScanDataConfig {
    /// Output channel (1 = first echo).
    pub output_channel: u8,
    /// Send remission (RSSI) values.
    pub remission: bool,
    /// Remission resolution: 16 bit (true) or 8 bit.
    pub resolution_16bit: bool,
    /// Unit.
    pub unit: u8,
    /// Encoder data.
    pub encoder: u8,
    /// Send position.
    pub position: bool,
    /// Send device name.
    pub device_name: bool,
    /// Send comment.
    pub comment: bool,
    /// Send time stamp.
    pub timestamp: bool,
    /// Output every n-th scan.
    pub output_interval: u16,
    /// How the numbers are written.
    pub dialect: Dialect,
}

impl ScanDataConfig {
    /// What the clearpath driver sends (`01 00 1 1 0 00 00 0 0 0 <ts> +1`).
    pub const fn clearpath(timestamp: bool) -> Self {
        Self {
            output_channel: 1,
            remission: true,
            resolution_16bit: true,
            unit: 0,
            encoder: 0,
            position: false,
            device_name: false,
            comment: false,
            timestamp,
            output_interval: 1,
            dialect: Dialect::Clearpath,
        }
    }

    /// What ARIA sends (`1 0 0 0 0 0 0 0 0 0 0 1`).
    pub const fn aria() -> Self {
        Self {
            output_channel: 1,
            remission: false,
            resolution_16bit: false,
            unit: 0,
            encoder: 0,
            position: false,
            device_name: false,
            comment: false,
            timestamp: false,
            output_interval: 1,
            dialect: Dialect::Aria,
        }
    }
}

/// A client request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Request {
    /// `sMN SetAccessMode <level> <password hash>`.
    SetAccessMode {
        /// Access level (3 = authorized client).
        level: u8,
        /// Hashed password.
        password_hash: u32,
        /// How the level is written (`03` or `3`).
        dialect: Dialect,
    },
    /// `sRN LMPscancfg`.
    ReadScanConfig,
    /// `sMN mLMPsetscancfg …`.
    SetScanConfig {
        /// The configuration.
        config: ScanConfig,
        /// Hex (clearpath) or signed decimal (ARIA).
        dialect: Dialect,
    },
    /// `sRN LMPoutputRange`.
    ReadOutputRange,
    /// `sWN LMDscandatacfg …`.
    SetScanDataConfig(ScanDataConfig),
    /// `sMN LMCstartmeas`.
    StartMeasurement,
    /// `sMN LMCstopmeas`.
    StopMeasurement,
    /// `sRN STlms`.
    ReadStatus,
    /// `sMN Run`.
    Run,
    /// `sEN LMDscandata 1` / `0`.
    SubscribeScanData(bool),
    /// `sRN LMDscandata`: one scan on request.
    PollScanData,
    /// `sMN mEEwriteall`.
    SaveConfig,
}

impl Request {
    /// The clearpath LMS1xx driver's connect sequence.
    pub const fn clearpath_connect_sequence(timestamp: bool) -> [Request; 8] {
        [
            Request::SetAccessMode {
                level: ACCESS_LEVEL_AUTHORIZED_CLIENT,
                password_hash: AUTHORIZED_CLIENT_PASSWORD,
                dialect: Dialect::Clearpath,
            },
            Request::ReadScanConfig,
            Request::ReadOutputRange,
            Request::SetScanDataConfig(ScanDataConfig::clearpath(timestamp)),
            Request::StartMeasurement,
            Request::ReadStatus,
            Request::Run,
            Request::SubscribeScanData(true),
        ]
    }

    /// ARIA's connect sequence.
    pub const fn aria_connect_sequence() -> [Request; 5] {
        [
            Request::SetAccessMode {
                level: ACCESS_LEVEL_AUTHORIZED_CLIENT,
                password_hash: AUTHORIZED_CLIENT_PASSWORD,
                dialect: Dialect::Aria,
            },
            Request::SetScanConfig {
                config: ScanConfig::DEFAULT_50HZ,
                dialect: Dialect::Aria,
            },
            Request::SetScanDataConfig(ScanDataConfig::aria()),
            Request::Run,
            Request::SubscribeScanData(true),
        ]
    }

    /// The command name (second token).
    pub fn name(&self) -> &'static str {
        match self {
            Request::SetAccessMode { .. } => "SetAccessMode",
            Request::ReadScanConfig => "LMPscancfg",
            Request::SetScanConfig { .. } => "mLMPsetscancfg",
            Request::ReadOutputRange => "LMPoutputRange",
            Request::SetScanDataConfig(_) => "LMDscandatacfg",
            Request::StartMeasurement => "LMCstartmeas",
            Request::StopMeasurement => "LMCstopmeas",
            Request::ReadStatus => "STlms",
            Request::Run => "Run",
            Request::SubscribeScanData(_) | Request::PollScanData => "LMDscandata",
            Request::SaveConfig => "mEEwriteall",
        }
    }

    fn write(&self, w: &mut impl Write) -> core::fmt::Result {
        match self {
            Request::SetAccessMode {
                level,
                password_hash,
                dialect,
            } => match dialect {
                Dialect::Clearpath => {
                    write!(w, "sMN SetAccessMode {level:02X} {password_hash:08X}")
                }
                Dialect::Aria => write!(w, "sMN SetAccessMode {level:X} {password_hash:08X}"),
            },
            Request::ReadScanConfig => w.write_str("sRN LMPscancfg"),
            Request::SetScanConfig { config, dialect } => {
                w.write_str("sMN mLMPsetscancfg")?;
                match dialect {
                    Dialect::Clearpath => config.write_hex(w),
                    Dialect::Aria => write!(
                        w,
                        " {:+} {:+} {:+} {:+} {:+}",
                        config.frequency_centi_hz,
                        config.sectors,
                        config.resolution_deg_e4,
                        config.start_deg_e4,
                        config.stop_deg_e4
                    ),
                }
            }
            Request::ReadOutputRange => w.write_str("sRN LMPoutputRange"),
            Request::SetScanDataConfig(c) => {
                let b = |v: bool| v as u8;
                match c.dialect {
                    Dialect::Clearpath => write!(
                        w,
                        "sWN LMDscandatacfg {:02X} 00 {} {} {:X} {:02X} 00 {} {} {} {} {:+}",
                        c.output_channel,
                        b(c.remission),
                        b(c.resolution_16bit),
                        c.unit,
                        c.encoder,
                        b(c.position),
                        b(c.device_name),
                        b(c.comment),
                        b(c.timestamp),
                        c.output_interval
                    ),
                    Dialect::Aria => write!(
                        w,
                        "sWN LMDscandatacfg {:X} 0 {} {} {:X} {:X} 0 {} {} {} {} {:X}",
                        c.output_channel,
                        b(c.remission),
                        b(c.resolution_16bit),
                        c.unit,
                        c.encoder,
                        b(c.position),
                        b(c.device_name),
                        b(c.comment),
                        b(c.timestamp),
                        c.output_interval
                    ),
                }
            }
            Request::StartMeasurement => w.write_str("sMN LMCstartmeas"),
            Request::StopMeasurement => w.write_str("sMN LMCstopmeas"),
            Request::ReadStatus => w.write_str("sRN STlms"),
            Request::Run => w.write_str("sMN Run"),
            Request::SubscribeScanData(on) => write!(w, "sEN LMDscandata {}", *on as u8),
            Request::PollScanData => w.write_str("sRN LMDscandata"),
            Request::SaveConfig => w.write_str("sMN mEEwriteall"),
        }
    }

    /// Encodes the request as a complete telegram (STX … ETX); returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        emit_with(buf, |w| self.write(w))
    }

    /// Parses a telegram payload (between STX and ETX).
    pub fn parse(payload: &[u8]) -> Result<Self, ParseError> {
        let mut t = Tokens::new(payload);
        let kind = t.next_token().ok_or(ParseError::Empty)?;
        let name = t.token("command name")?;
        let unknown = || ParseError::UnknownMessage {
            got: token_text(payload),
        };
        let req = match (kind, name) {
            (b"sMN", b"SetAccessMode") => {
                let lt = t.clone().token("access level")?;
                let level = t.uint("access level", 255)? as u8;
                let password_hash = t.uint("password hash", u32::MAX)?;
                Request::SetAccessMode {
                    level,
                    password_hash,
                    dialect: if lt.len() >= 2 {
                        Dialect::Clearpath
                    } else {
                        Dialect::Aria
                    },
                }
            }
            (b"sRN", b"LMPscancfg") => Request::ReadScanConfig,
            (b"sMN", b"mLMPsetscancfg") => {
                let first = t.clone().token("scan frequency")?;
                let dialect = if matches!(first.first(), Some(b'+' | b'-')) {
                    Dialect::Aria
                } else {
                    Dialect::Clearpath
                };
                Request::SetScanConfig {
                    config: ScanConfig::parse(&mut t)?,
                    dialect,
                }
            }
            (b"sRN", b"LMPoutputRange") => Request::ReadOutputRange,
            (b"sWN", b"LMDscandatacfg") => {
                let output_channel = t.uint("output channel", 255)? as u8;
                t.uint("output channel high byte", 255)?;
                let remission = t.flag("remission")?;
                let resolution_16bit = t.flag("resolution")?;
                let unit = t.uint("unit", 255)? as u8;
                let encoder = t.uint("encoder", 255)? as u8;
                t.uint("encoder high byte", 255)?;
                let position = t.flag("position")?;
                let device_name = t.flag("device name")?;
                let comment = t.flag("comment")?;
                let timestamp = t.flag("time")?;
                let last = t.clone().token("output interval")?;
                let output_interval = t.uint("output interval", u16::MAX as u32)? as u16;
                Request::SetScanDataConfig(ScanDataConfig {
                    output_channel,
                    remission,
                    resolution_16bit,
                    unit,
                    encoder,
                    position,
                    device_name,
                    comment,
                    timestamp,
                    output_interval,
                    dialect: if last.first() == Some(&b'+') {
                        Dialect::Clearpath
                    } else {
                        Dialect::Aria
                    },
                })
            }
            (b"sMN", b"LMCstartmeas") => Request::StartMeasurement,
            (b"sMN", b"LMCstopmeas") => Request::StopMeasurement,
            (b"sRN", b"STlms") => Request::ReadStatus,
            (b"sMN", b"Run") => Request::Run,
            (b"sEN", b"LMDscandata") => Request::SubscribeScanData(t.flag("subscribe flag")?),
            (b"sRN", b"LMDscandata") => Request::PollScanData,
            (b"sMN", b"mEEwriteall") => Request::SaveConfig,
            _ => return Err(unknown()),
        };
        Ok(req)
    }
}

/// A reply from the laser (scan data telegrams are [`super::ScanTelegram`]s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Reply {
    /// `sAN SetAccessMode <0|1>`.
    AccessMode {
        /// 1 = granted.
        granted: bool,
    },
    /// `sRA LMPscancfg …`.
    ScanConfig(ScanConfig),
    /// `sAN mLMPsetscancfg <status> \[config\]`: 0 OK, 1 bad frequency, 2 bad resolution,
    /// 3 both, 4 bad scan area.
    SetScanConfig {
        /// Status code.
        status: u8,
        /// The configuration in force, if sent.
        config: Option<ScanConfig>,
    },
    /// `sRA LMPoutputRange …`.
    OutputRange(OutputRange),
    /// `sWA LMDscandatacfg`.
    ScanDataConfigAck,
    /// `sAN LMCstartmeas <status>` (0 = OK).
    StartMeasurement {
        /// Status code.
        status: u8,
    },
    /// `sAN LMCstopmeas <status>` (0 = OK).
    StopMeasurement {
        /// Status code.
        status: u8,
    },
    /// `sRA STlms <state> …` (7 = ready for measurement); later tokens are ignored.
    Status {
        /// Device state.
        state: u8,
    },
    /// `sAN Run <0|1>`.
    Run {
        /// 1 = success.
        success: bool,
    },
    /// `sEA LMDscandata <0|1>`.
    Subscribed {
        /// Whether scan data events are now on.
        enabled: bool,
    },
    /// `sAN mEEwriteall <0|1>`.
    SaveConfig {
        /// 1 = success.
        success: bool,
    },
    /// `sFA <code>`: the laser refused the request.
    Error {
        /// Error code.
        code: u32,
    },
}

impl Reply {
    /// A short name of the reply, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Reply::AccessMode { .. } => "sAN SetAccessMode",
            Reply::ScanConfig(_) => "sRA LMPscancfg",
            Reply::SetScanConfig { .. } => "sAN mLMPsetscancfg",
            Reply::OutputRange(_) => "sRA LMPoutputRange",
            Reply::ScanDataConfigAck => "sWA LMDscandatacfg",
            Reply::StartMeasurement { .. } => "sAN LMCstartmeas",
            Reply::StopMeasurement { .. } => "sAN LMCstopmeas",
            Reply::Status { .. } => "sRA STlms",
            Reply::Run { .. } => "sAN Run",
            Reply::Subscribed { .. } => "sEA LMDscandata",
            Reply::SaveConfig { .. } => "sAN mEEwriteall",
            Reply::Error { .. } => "sFA",
        }
    }

    /// Parses a telegram payload (between STX and ETX). Extra trailing tokens are ignored.
    pub fn parse(payload: &[u8]) -> Result<Self, ParseError> {
        let mut t = Tokens::new(payload);
        let kind = t.next_token().ok_or(ParseError::Empty)?;
        if kind == b"sFA" {
            return Ok(Reply::Error {
                code: t.uint("error code", u32::MAX)?,
            });
        }
        let name = t.token("command name")?;
        Ok(match (kind, name) {
            (b"sAN", b"SetAccessMode") => Reply::AccessMode {
                granted: t.flag("access result")?,
            },
            (b"sRA", b"LMPscancfg") => Reply::ScanConfig(ScanConfig::parse(&mut t)?),
            (b"sAN", b"mLMPsetscancfg") => {
                let status = t.uint("status", 255)? as u8;
                let config = if t.is_empty() {
                    None
                } else {
                    Some(ScanConfig::parse(&mut t)?)
                };
                Reply::SetScanConfig { status, config }
            }
            (b"sRA", b"LMPoutputRange") => Reply::OutputRange(OutputRange {
                sectors: t.uint("sectors", u32::MAX)?,
                resolution_deg_e4: t.uint("resolution", u32::MAX)?,
                start_deg_e4: t.int32("start angle")?,
                stop_deg_e4: t.int32("stop angle")?,
            }),
            (b"sWA", b"LMDscandatacfg") => Reply::ScanDataConfigAck,
            (b"sAN", b"LMCstartmeas") => Reply::StartMeasurement {
                status: t.uint("status", 255)? as u8,
            },
            (b"sAN", b"LMCstopmeas") => Reply::StopMeasurement {
                status: t.uint("status", 255)? as u8,
            },
            (b"sRA", b"STlms") => Reply::Status {
                state: t.uint("state", 255)? as u8,
            },
            (b"sAN", b"Run") => Reply::Run {
                success: t.flag("run result")?,
            },
            (b"sEA", b"LMDscandata") => Reply::Subscribed {
                enabled: t.flag("subscribe flag")?,
            },
            (b"sAN", b"mEEwriteall") => Reply::SaveConfig {
                success: t.flag("save result")?,
            },
            _ => {
                return Err(ParseError::UnknownMessage {
                    got: token_text(payload),
                });
            }
        })
    }

    fn write(&self, w: &mut impl Write) -> core::fmt::Result {
        match self {
            Reply::AccessMode { granted } => write!(w, "sAN SetAccessMode {}", *granted as u8),
            Reply::ScanConfig(c) => {
                w.write_str("sRA LMPscancfg")?;
                c.write_hex(w)
            }
            Reply::SetScanConfig { status, config } => {
                write!(w, "sAN mLMPsetscancfg {status:X}")?;
                match config {
                    Some(c) => c.write_hex(w),
                    None => Ok(()),
                }
            }
            Reply::OutputRange(r) => write!(
                w,
                "sRA LMPoutputRange {:X} {:X} {:X} {:X}",
                r.sectors, r.resolution_deg_e4, r.start_deg_e4 as u32, r.stop_deg_e4 as u32
            ),
            Reply::ScanDataConfigAck => w.write_str("sWA LMDscandatacfg"),
            Reply::StartMeasurement { status } => write!(w, "sAN LMCstartmeas {status:X}"),
            Reply::StopMeasurement { status } => write!(w, "sAN LMCstopmeas {status:X}"),
            Reply::Status { state } => write!(w, "sRA STlms {state:X}"),
            Reply::Run { success } => write!(w, "sAN Run {}", *success as u8),
            Reply::Subscribed { enabled } => write!(w, "sEA LMDscandata {}", *enabled as u8),
            Reply::SaveConfig { success } => write!(w, "sAN mEEwriteall {}", *success as u8),
            Reply::Error { code } => write!(w, "sFA {code:X}"),
        }
    }

    /// Encodes the reply as a complete telegram (STX … ETX); returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        emit_with(buf, |w| self.write(w))
    }

    /// The reply the laser gives to `request` when all is well (what an emulator sends).
    /// `None` for [`Request::PollScanData`], answered with a scan telegram.
    pub fn success_for(request: &Request, scan_config: ScanConfig) -> Option<Reply> {
        Some(match request {
            Request::SetAccessMode { .. } => Reply::AccessMode { granted: true },
            Request::ReadScanConfig => Reply::ScanConfig(scan_config),
            Request::SetScanConfig { config, .. } => Reply::SetScanConfig {
                status: 0,
                config: Some(*config),
            },
            Request::ReadOutputRange => Reply::OutputRange(OutputRange {
                sectors: scan_config.sectors,
                resolution_deg_e4: scan_config.resolution_deg_e4,
                start_deg_e4: scan_config.start_deg_e4,
                stop_deg_e4: scan_config.stop_deg_e4,
            }),
            Request::SetScanDataConfig(_) => Reply::ScanDataConfigAck,
            Request::StartMeasurement => Reply::StartMeasurement { status: 0 },
            Request::StopMeasurement => Reply::StopMeasurement { status: 0 },
            Request::ReadStatus => Reply::Status { state: STATE_READY },
            Request::Run => Reply::Run { success: true },
            Request::SubscribeScanData(on) => Reply::Subscribed { enabled: *on },
            Request::SaveConfig => Reply::SaveConfig { success: true },
            Request::PollScanData => return None,
        })
    }
}

/// Why a reply does not complete a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReplyError {
    /// The reply answers another request.
    Unexpected {
        /// The reply expected.
        expected: &'static str,
        /// The reply received.
        got: &'static str,
    },
    /// The laser answered with a failure status.
    Refused {
        /// The command.
        command: &'static str,
        /// The status it returned.
        status: u32,
    },
    /// `STlms` is not 7 (ready for measurement).
    NotReady {
        /// The state reported.
        state: u8,
    },
    /// The laser sent `sFA`.
    LaserError {
        /// Its error code.
        code: u32,
    },
}

impl core::fmt::Display for ReplyError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplyError::Unexpected { expected, got } => {
                write!(f, "expected reply '{expected}', got '{got}'")
            }
            ReplyError::Refused { command, status } => {
                write!(f, "laser refused {command} with status {status}")
            }
            ReplyError::NotReady { state } => {
                write!(f, "laser state {state}, expected 7 (ready for measurement)")
            }
            ReplyError::LaserError { code } => write!(f, "laser error sFA {code}"),
        }
    }
}

impl core::error::Error for ReplyError {}

/// Checks that `reply` answers `request` successfully (what a client does after each step of
/// its connect sequence).
pub fn check_reply(request: &Request, reply: &Reply) -> Result<(), ReplyError> {
    if let Reply::Error { code } = reply {
        return Err(ReplyError::LaserError { code: *code });
    }
    let refused = |status: u32| ReplyError::Refused {
        command: request.name(),
        status,
    };
    let expected = match request {
        Request::SetAccessMode { .. } => "sAN SetAccessMode",
        Request::ReadScanConfig => "sRA LMPscancfg",
        Request::SetScanConfig { .. } => "sAN mLMPsetscancfg",
        Request::ReadOutputRange => "sRA LMPoutputRange",
        Request::SetScanDataConfig(_) => "sWA LMDscandatacfg",
        Request::StartMeasurement => "sAN LMCstartmeas",
        Request::StopMeasurement => "sAN LMCstopmeas",
        Request::ReadStatus => "sRA STlms",
        Request::Run => "sAN Run",
        Request::SubscribeScanData(_) => "sEA LMDscandata",
        Request::PollScanData => "sRA LMDscandata",
        Request::SaveConfig => "sAN mEEwriteall",
    };
    match (request, reply) {
        (Request::SetAccessMode { .. }, Reply::AccessMode { granted }) => {
            if *granted {
                Ok(())
            } else {
                Err(refused(0))
            }
        }
        (Request::ReadScanConfig, Reply::ScanConfig(_))
        | (Request::ReadOutputRange, Reply::OutputRange(_))
        | (Request::SetScanDataConfig(_), Reply::ScanDataConfigAck) => Ok(()),
        (Request::SetScanConfig { .. }, Reply::SetScanConfig { status, .. })
        | (Request::StartMeasurement, Reply::StartMeasurement { status })
        | (Request::StopMeasurement, Reply::StopMeasurement { status }) => {
            if *status == 0 {
                Ok(())
            } else {
                Err(refused(*status as u32))
            }
        }
        (Request::ReadStatus, Reply::Status { state }) => {
            if *state == STATE_READY {
                Ok(())
            } else {
                Err(ReplyError::NotReady { state: *state })
            }
        }
        (Request::Run, Reply::Run { success })
        | (Request::SaveConfig, Reply::SaveConfig { success }) => {
            if *success {
                Ok(())
            } else {
                Err(refused(0))
            }
        }
        (Request::SubscribeScanData(on), Reply::Subscribed { enabled }) => {
            if on == enabled {
                Ok(())
            } else {
                Err(refused(*enabled as u32))
            }
        }
        _ => Err(ReplyError::Unexpected {
            expected,
            got: reply.name(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{below, seeded};
    use rand_core::Rng;

    fn enc_req(r: &Request) -> heapless::Vec<u8, 128> {
        let mut buf = [0u8; 128];
        let n = r.emit(&mut buf).unwrap();
        heapless::Vec::from_slice(&buf[..n]).unwrap()
    }

    fn payload(b: &[u8]) -> &[u8] {
        &b[1..b.len() - 1]
    }

    #[test]
    fn golden_requests_of_both_clients() {
        let cases: &[(Request, &[u8])] = &[
            (
                Request::clearpath_connect_sequence(false)[0],
                b"sMN SetAccessMode 03 F4724744",
            ),
            (
                Request::aria_connect_sequence()[0],
                b"sMN SetAccessMode 3 F4724744",
            ),
            (Request::ReadScanConfig, b"sRN LMPscancfg"),
            (
                Request::aria_connect_sequence()[1],
                b"sMN mLMPsetscancfg +5000 +1 +5000 -450000 +2250000",
            ),
            (
                Request::SetScanConfig {
                    config: ScanConfig::DEFAULT_50HZ,
                    dialect: Dialect::Clearpath,
                },
                b"sMN mLMPsetscancfg 1388 1 1388 FFF92230 225510",
            ),
            (Request::ReadOutputRange, b"sRN LMPoutputRange"),
            (
                Request::SetScanDataConfig(ScanDataConfig::clearpath(false)),
                b"sWN LMDscandatacfg 01 00 1 1 0 00 00 0 0 0 0 +1",
            ),
            (
                Request::SetScanDataConfig(ScanDataConfig::clearpath(true)),
                b"sWN LMDscandatacfg 01 00 1 1 0 00 00 0 0 0 1 +1",
            ),
            (
                Request::SetScanDataConfig(ScanDataConfig::aria()),
                b"sWN LMDscandatacfg 1 0 0 0 0 0 0 0 0 0 0 1",
            ),
            (Request::StartMeasurement, b"sMN LMCstartmeas"),
            (Request::ReadStatus, b"sRN STlms"),
            (Request::Run, b"sMN Run"),
            (Request::SubscribeScanData(true), b"sEN LMDscandata 1"),
            (Request::SubscribeScanData(false), b"sEN LMDscandata 0"),
            (Request::PollScanData, b"sRN LMDscandata"),
            (Request::SaveConfig, b"sMN mEEwriteall"),
        ];
        for (req, text) in cases {
            let b = enc_req(req);
            assert_eq!(b[0], 0x02);
            assert_eq!(*b.last().unwrap(), 0x03);
            assert_eq!(payload(&b), *text, "{req:?}");
            assert_eq!(Request::parse(text).as_ref(), Ok(req));
        }
    }

    #[test]
    fn golden_replies() {
        let cases: &[(Reply, &[u8])] = &[
            (Reply::AccessMode { granted: true }, b"sAN SetAccessMode 1"),
            (
                Reply::ScanConfig(ScanConfig::DEFAULT_50HZ),
                b"sRA LMPscancfg 1388 1 1388 FFF92230 225510",
            ),
            (
                Reply::OutputRange(OutputRange {
                    sectors: 1,
                    resolution_deg_e4: 5000,
                    start_deg_e4: -450_000,
                    stop_deg_e4: 2_250_000,
                }),
                b"sRA LMPoutputRange 1 1388 FFF92230 225510",
            ),
            (Reply::ScanDataConfigAck, b"sWA LMDscandatacfg"),
            (Reply::StartMeasurement { status: 0 }, b"sAN LMCstartmeas 0"),
            (Reply::Status { state: 7 }, b"sRA STlms 7"),
            (Reply::Run { success: true }, b"sAN Run 1"),
            (Reply::Subscribed { enabled: true }, b"sEA LMDscandata 1"),
            (Reply::Subscribed { enabled: false }, b"sEA LMDscandata 0"),
            (Reply::SaveConfig { success: true }, b"sAN mEEwriteall 1"),
            (
                Reply::SetScanConfig {
                    status: 0,
                    config: None,
                },
                b"sAN mLMPsetscancfg 0",
            ),
        ];
        let mut buf = [0u8; 128];
        for (rep, text) in cases {
            let n = rep.emit(&mut buf).unwrap();
            assert_eq!(payload(&buf[..n]), *text);
            assert_eq!(Reply::parse(text).as_ref(), Ok(rep));
        }
        // The signed-decimal form parses to the same values.
        assert_eq!(
            Reply::parse(b"sRA LMPscancfg +5000 +1 +5000 -450000 +2250000"),
            Ok(Reply::ScanConfig(ScanConfig::DEFAULT_50HZ))
        );
        // STlms: only the state is read.
        assert_eq!(
            Reply::parse(b"sRA STlms 7 0 8 16:36:54 8 17.03.2030 0 0 0"),
            Ok(Reply::Status { state: 7 })
        );
    }

    #[test]
    fn connect_sequences_accept_success_and_reject_the_rest() {
        let cfg = ScanConfig::DEFAULT_50HZ;
        for req in Request::clearpath_connect_sequence(false)
            .iter()
            .chain(Request::aria_connect_sequence().iter())
        {
            let ok = Reply::success_for(req, cfg).unwrap();
            assert_eq!(check_reply(req, &ok), Ok(()));
        }
        assert_eq!(
            check_reply(&Request::ReadStatus, &Reply::Status { state: 6 }),
            Err(ReplyError::NotReady { state: 6 })
        );
        assert_eq!(
            check_reply(&Request::Run, &Reply::AccessMode { granted: true }),
            Err(ReplyError::Unexpected {
                expected: "sAN Run",
                got: "sAN SetAccessMode"
            })
        );
        assert_eq!(
            check_reply(
                &Request::aria_connect_sequence()[1],
                &Reply::SetScanConfig {
                    status: 2,
                    config: None
                }
            ),
            Err(ReplyError::Refused {
                command: "mLMPsetscancfg",
                status: 2
            })
        );
        assert_eq!(
            check_reply(&Request::Run, &Reply::Error { code: 4 }),
            Err(ReplyError::LaserError { code: 4 })
        );
    }

    #[test]
    fn parse_errors_name_the_token() {
        assert_eq!(Request::parse(b""), Err(ParseError::Empty));
        assert!(matches!(
            Request::parse(b"sMN Fly"),
            Err(ParseError::UnknownMessage { .. })
        ));
        assert_eq!(
            Reply::parse(b"sRA LMPscancfg 1388 1 1388"),
            Err(ParseError::MissingToken {
                field: "start angle",
                index: 5
            })
        );
        assert_eq!(
            Reply::parse(b"sAN Run x"),
            Err(ParseError::BadNumber {
                field: "run result",
                index: 2,
                got: "x".try_into().unwrap()
            })
        );
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(0xC01A);
        let mut buf = [0u8; 256];
        for _ in 0..20_000 {
            let d = if rng.next_u32() & 1 == 0 {
                Dialect::Clearpath
            } else {
                Dialect::Aria
            };
            let config = ScanConfig {
                frequency_centi_hz: rng.next_u32(),
                sectors: rng.next_u32(),
                resolution_deg_e4: rng.next_u32(),
                start_deg_e4: rng.next_u32() as i32,
                stop_deg_e4: rng.next_u32() as i32,
            };
            let mut config_dec = config;
            if d == Dialect::Aria {
                // ARIA's signed decimal carries unsigned values up to i32::MAX exactly.
                config_dec.frequency_centi_hz &= 0x7FFF_FFFF;
                config_dec.sectors &= 0x7FFF_FFFF;
                config_dec.resolution_deg_e4 &= 0x7FFF_FFFF;
            }
            let sdc = ScanDataConfig {
                output_channel: rng.next_u32() as u8,
                remission: rng.next_u32() & 1 == 1,
                resolution_16bit: rng.next_u32() & 1 == 1,
                unit: rng.next_u32() as u8,
                encoder: rng.next_u32() as u8,
                position: rng.next_u32() & 1 == 1,
                device_name: rng.next_u32() & 1 == 1,
                comment: rng.next_u32() & 1 == 1,
                timestamp: rng.next_u32() & 1 == 1,
                output_interval: rng.next_u32() as u16,
                dialect: d,
            };
            let req = match below(&mut rng, 12) {
                0 => Request::SetAccessMode {
                    level: if d == Dialect::Aria {
                        below(&mut rng, 16) as u8
                    } else {
                        rng.next_u32() as u8
                    },
                    password_hash: rng.next_u32(),
                    dialect: d,
                },
                1 => Request::ReadScanConfig,
                2 => Request::SetScanConfig {
                    config: config_dec,
                    dialect: d,
                },
                3 => Request::ReadOutputRange,
                4 => Request::SetScanDataConfig(sdc),
                5 => Request::StartMeasurement,
                6 => Request::StopMeasurement,
                7 => Request::ReadStatus,
                8 => Request::Run,
                9 => Request::SubscribeScanData(rng.next_u32() & 1 == 1),
                10 => Request::PollScanData,
                _ => Request::SaveConfig,
            };
            let n = req.emit(&mut buf).unwrap();
            assert_eq!(Request::parse(payload(&buf[..n])), Ok(req));
            let rep = match Reply::success_for(&req, config) {
                Some(r) => r,
                None => Reply::Error {
                    code: rng.next_u32(),
                },
            };
            let n = rep.emit(&mut buf).unwrap();
            assert_eq!(Reply::parse(payload(&buf[..n])), Ok(rep));
        }
    }
}
