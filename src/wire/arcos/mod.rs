//! ARCOS / P2OS: the serial protocol between the robot PC (client) and the P3-DX
//! microcontroller (server).
//!
//! Layers:
//! - [`frame`]: `FA FB count id … checksum` framing and the checksum ([`Frame`], [`emit_frame`]).
//! - [`command`]: client commands ([`Command`]), encoded by the robot PC and decoded by the
//!   emulated microcontroller.
//! - [`sip`], [`config`], [`encoder`], [`sync`]: server packets (standard status packet,
//!   CONFIG, ENCODER, SYNC replies), encoded by the emulator and decoded by the robot PC;
//!   [`ServerPacket`] dispatches on the packet ID.
//! - [`stream`]: [`FrameDecoder`], the streaming frame decoder.
//!
//! Source: the protocol fact sheet, section 1 (Pioneer 3 operations manual, ARIA and p2os
//! behaviour, wire captures).

pub mod command;
pub mod config;
pub mod encoder;
pub mod frame;
pub mod sip;
pub mod stream;
pub mod sync;

pub use command::{Arg, Command};
pub use config::ConfigPacket;
pub use encoder::EncoderPacket;
pub use frame::{Frame, emit_frame};
pub use sip::{SipExtras, SonarReading, StatusPacket};
pub use stream::{DecoderStats, FrameDecoder};
pub use sync::SyncReply;

use core::fmt;

/// Capacity of robot name, class, subclass, serial number and version strings.
pub const NAME_CAPACITY: usize = 32;

/// A name string as carried in SYNC2 and CONFIG packets.
pub type Name = heapless::String<NAME_CAPACITY>;

/// Errors decoding the payload of a well-framed ARCOS packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ParseError {
    /// The packet ended inside a field.
    Truncated {
        /// The field being read.
        field: &'static str,
        /// Byte offset of the field within the payload (after the ID).
        offset: usize,
    },
    /// The packet ID is not the one this parser handles.
    UnexpectedId {
        /// The ID seen.
        got: u8,
    },
    /// An argument type byte other than 0x3B, 0x1B or 0x2B.
    BadArgType {
        /// The byte seen.
        got: u8,
    },
    /// The command needs an argument of another kind.
    WrongArg {
        /// The command number.
        command: u8,
        /// What it needs.
        expected: &'static str,
    },
    /// An integer argument outside the range the command accepts.
    ArgOutOfRange {
        /// The command number.
        command: u8,
        /// The value seen.
        value: i32,
    },
    /// A string longer than its capacity.
    StringTooLong {
        /// The field.
        field: &'static str,
        /// Its length in bytes.
        len: usize,
        /// The capacity.
        capacity: usize,
    },
    /// A string that is not UTF-8.
    NotUtf8 {
        /// The field.
        field: &'static str,
    },
    /// More sonar readings than the packet type can hold.
    TooManySonar {
        /// The count seen.
        count: usize,
        /// The capacity.
        capacity: usize,
    },
    /// Bytes left after the last field.
    TrailingBytes {
        /// How many.
        count: usize,
    },
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseError::Truncated { field, offset } => {
                write!(
                    f,
                    "packet ends inside field {field} at payload byte {offset}"
                )
            }
            ParseError::UnexpectedId { got } => write!(f, "unexpected packet ID 0x{got:02X}"),
            ParseError::BadArgType { got } => write!(
                f,
                "argument type byte 0x{got:02X}, expected 0x3B, 0x1B or 0x2B"
            ),
            ParseError::WrongArg { command, expected } => {
                write!(f, "command {command} needs {expected}")
            }
            ParseError::ArgOutOfRange { command, value } => {
                write!(f, "command {command}: argument {value} out of range")
            }
            ParseError::StringTooLong {
                field,
                len,
                capacity,
            } => write!(f, "{field}: {len} bytes, capacity {capacity}"),
            ParseError::NotUtf8 { field } => write!(f, "{field} is not UTF-8"),
            ParseError::TooManySonar { count, capacity } => {
                write!(f, "{count} sonar readings, capacity {capacity}")
            }
            ParseError::TrailingBytes { count } => {
                write!(f, "{count} unexpected bytes after the last field")
            }
        }
    }
}

impl core::error::Error for ParseError {}

/// Errors encoding an ARCOS packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum EmitError {
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes the packet needs.
        needed: usize,
        /// Bytes available.
        capacity: usize,
    },
    /// The packet would exceed the protocol's byte count limit.
    TooLong {
        /// The byte count it would have.
        count: usize,
        /// The limit ([`frame::MAX_BYTE_COUNT`]).
        max: usize,
    },
    /// An optional trailing field is set while an earlier one is absent (trailing fields are
    /// positional: a field can only be present if every field before it is).
    FieldAfterAbsent {
        /// The field that is set.
        field: &'static str,
    },
    /// An integer argument outside -65535..=65535 or outside what the command carries.
    ArgOutOfRange {
        /// The value.
        value: i32,
    },
}

impl fmt::Display for EmitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EmitError::BufferTooSmall { needed, capacity } => {
                write!(f, "packet needs {needed} bytes, buffer holds {capacity}")
            }
            EmitError::TooLong { count, max } => {
                write!(f, "byte count {count} exceeds the limit {max}")
            }
            EmitError::FieldAfterAbsent { field } => write!(
                f,
                "optional field {field} is set but an earlier optional field is absent"
            ),
            EmitError::ArgOutOfRange { value } => {
                write!(f, "integer argument {value} out of range")
            }
        }
    }
}

impl core::error::Error for EmitError {}

/// Copies `s` into a [`Name`], failing if it is too long or not UTF-8.
pub(crate) fn name_from(s: &[u8], field: &'static str) -> Result<Name, ParseError> {
    let text = core::str::from_utf8(s).map_err(|_| ParseError::NotUtf8 { field })?;
    let mut out = Name::new();
    out.push_str(text).map_err(|_| ParseError::StringTooLong {
        field,
        len: s.len(),
        capacity: NAME_CAPACITY,
    })?;
    Ok(out)
}

/// Reads a NUL-terminated name.
pub(crate) fn read_name(
    r: &mut crate::wire::bytes::Reader<'_>,
    field: &'static str,
) -> Result<Name, ParseError> {
    let offset = r.position();
    let s = r.cstr().ok_or(ParseError::Truncated { field, offset })?;
    name_from(s, field)
}

/// A server (microcontroller → PC) packet, dispatched on its ID.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ServerPacket {
    /// A SYNC0/1/2 reply (IDs 0, 1, 2).
    Sync(SyncReply),
    /// A standard status packet (IDs 0x32, 0x33).
    Status(StatusPacket),
    /// A CONFIG packet (ID 0x20).
    Config(ConfigPacket),
    /// An ENCODER packet (ID 0x90).
    Encoder(EncoderPacket),
    /// A microcontroller reset notice (IDs 0xFE, 0xFF): the connection is lost.
    Reset {
        /// The ID seen.
        id: u8,
    },
    /// Any other packet, kept as its ID (the payload is left in the frame).
    Other {
        /// The ID seen.
        id: u8,
    },
}

impl ServerPacket {
    /// Parses a checked frame's payload according to its ID.
    pub fn parse<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        let id = frame.id();
        let payload = frame.payload();
        Ok(match id {
            0..=2 => ServerPacket::Sync(SyncReply::parse(id, payload)?),
            sip::ID_STOPPED | sip::ID_MOVING => {
                ServerPacket::Status(StatusPacket::parse(id, payload)?)
            }
            config::ID => ServerPacket::Config(ConfigPacket::parse(payload)?),
            encoder::ID => ServerPacket::Encoder(EncoderPacket::parse(payload)?),
            0xFE | 0xFF => ServerPacket::Reset { id },
            _ => ServerPacket::Other { id },
        })
    }

    /// Encodes the packet into `buf` as a complete frame; returns its length.
    /// [`ServerPacket::Other`] is encoded with an empty payload.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        match self {
            ServerPacket::Sync(s) => s.emit(buf),
            ServerPacket::Status(s) => s.emit(buf),
            ServerPacket::Config(c) => c.emit(buf),
            ServerPacket::Encoder(e) => e.emit(buf),
            ServerPacket::Reset { id } | ServerPacket::Other { id } => emit_frame(buf, *id, &[]),
        }
    }
}
