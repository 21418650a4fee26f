//! SICK LMS200 serial telegrams, both directions (fact sheet section 3).
//!
//! ```text
//! STX 02 | address | length lo hi | command | data … | CRC lo hi
//! ```
//! `length` counts the command and data bytes. The CRC runs over every byte from STX to the
//! end of the data (polynomial 0x8005, the SICK algorithm in [`crc16`]). Host → laser
//! telegrams use address 0x00, laser → host 0x80 + laser address. Single ACK (0x06) / NACK
//! (0x15) bytes precede the laser's replies; [`Lms200Decoder`] reports them as events.
//!
//! Messages: mode change 0x20 (setup with password, continuous output, stop, baud rates),
//! variant 0x3B (angular range and resolution, reply 0xBB), mode reply 0xA0, measured values
//! 0xB0.

use core::fmt;

use crate::wire::bytes::{Overflow, Reader, Writer};

/// Start byte.
pub const STX: u8 = 0x02;
/// Acknowledge byte.
pub const ACK: u8 = 0x06;
/// Not-acknowledge byte.
pub const NACK: u8 = 0x15;
/// Address of host → laser telegrams.
pub const HOST_ADDRESS: u8 = 0x00;
/// Address of laser → host telegrams (laser address 0).
pub const LASER_REPLY_ADDRESS: u8 = 0x80;
/// Largest command + data length \[bytes\].
pub const MAX_PAYLOAD_LEN: usize = 812;
/// Largest telegram \[bytes\].
pub const MAX_TELEGRAM_LEN: usize = 4 + MAX_PAYLOAD_LEN + 2;
/// Largest data length (payload minus the command byte).
pub const MAX_DATA_LEN: usize = MAX_PAYLOAD_LEN - 1;
/// Most measured values one telegram holds here (180° at 0.5° = 361, 100° at 0.25° = 401).
pub const MAX_VALUES: usize = 401;
/// The default setup-mode password.
pub const DEFAULT_PASSWORD: [u8; 8] = *b"SICK_LMS";

/// Command bytes.
pub mod cmd {
    /// Reset / initialise.
    pub const RESET: u8 = 0x10;
    /// Mode change.
    pub const MODE: u8 = 0x20;
    /// Variant (angular range and resolution).
    pub const VARIANT: u8 = 0x3B;
    /// Configuration.
    pub const CONFIG: u8 = 0x77;
    /// Power-on message (laser → host).
    pub const POWER_ON: u8 = 0x90;
    /// Mode change reply.
    pub const MODE_REPLY: u8 = 0xA0;
    /// Measured values.
    pub const MEASURED_VALUES: u8 = 0xB0;
    /// Variant reply.
    pub const VARIANT_REPLY: u8 = 0xBB;
    /// Configuration reply.
    pub const CONFIG_REPLY: u8 = 0xF7;
}

/// The LMS200 CRC16 of `data` (STX through the last data byte).
///
/// For each byte: shift the register left one bit, XOR-ing 0x8005 in if the top bit fell
/// out, then XOR in the byte with the previous byte above it.
pub fn crc16(data: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    let mut prev: u8 = 0;
    for &b in data {
        if crc & 0x8000 != 0 {
            crc = (crc << 1) ^ 0x8005;
        } else {
            crc <<= 1;
        }
        crc ^= (b as u16) | ((prev as u16) << 8);
        prev = b;
    }
    crc
}

/// Errors checking a telegram's framing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FrameError {
    /// Fewer bytes than the telegram needs.
    Truncated {
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// The first byte is not STX.
    BadStx {
        /// The byte seen.
        got: u8,
    },
    /// A length of 0 or above [`MAX_PAYLOAD_LEN`].
    BadLength {
        /// The length seen.
        len: u16,
    },
    /// The CRC does not match.
    BadCrc {
        /// CRC carried by the telegram.
        got: u16,
        /// CRC computed.
        computed: u16,
    },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Truncated { needed, got } => {
                write!(f, "telegram needs {needed} bytes, got {got}")
            }
            FrameError::BadStx { got } => write!(f, "first byte 0x{got:02X}, expected STX 0x02"),
            FrameError::BadLength { len } => {
                write!(f, "length {len}, expected 1..={MAX_PAYLOAD_LEN}")
            }
            FrameError::BadCrc { got, computed } => {
                write!(f, "CRC 0x{got:04X}, computed 0x{computed:04X}")
            }
        }
    }
}

impl core::error::Error for FrameError {}

/// Errors decoding a telegram's data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ParseError {
    /// The data ended inside a field.
    Truncated {
        /// The field.
        field: &'static str,
    },
    /// A command byte this parser does not handle.
    UnexpectedCommand {
        /// The byte seen.
        got: u8,
    },
    /// A mode byte that is not one of the known modes.
    UnknownMode {
        /// The byte seen.
        got: u8,
    },
    /// Units bits 11 in the measured-values count word.
    BadUnits {
        /// The count word.
        word: u16,
    },
    /// More values than [`MAX_VALUES`].
    TooManyValues {
        /// The count seen.
        count: usize,
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
            ParseError::Truncated { field } => write!(f, "telegram ends inside {field}"),
            ParseError::UnexpectedCommand { got } => write!(f, "unexpected command 0x{got:02X}"),
            ParseError::UnknownMode { got } => write!(f, "unknown mode 0x{got:02X}"),
            ParseError::BadUnits { word } => {
                write!(f, "count word 0x{word:04X} has units bits 11")
            }
            ParseError::TooManyValues { count } => {
                write!(f, "{count} measured values, capacity {MAX_VALUES}")
            }
            ParseError::TrailingBytes { count } => {
                write!(f, "{count} unexpected bytes after the last field")
            }
        }
    }
}

impl core::error::Error for ParseError {}

/// Errors encoding a telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum EmitError {
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes available.
        capacity: usize,
    },
    /// More than [`MAX_VALUES`] values or a count that does not fit 10 bits.
    TooManyValues {
        /// The count.
        count: usize,
    },
}

impl fmt::Display for EmitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EmitError::BufferTooSmall { needed, capacity } => {
                write!(f, "telegram needs {needed} bytes, buffer holds {capacity}")
            }
            EmitError::TooManyValues { count } => write!(f, "{count} values do not fit"),
        }
    }
}

impl core::error::Error for EmitError {}

/// A checked view of one telegram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Telegram<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Telegram<T> {
    /// Wraps `buffer` after checking STX, the length and the CRC. Bytes after the telegram are
    /// ignored.
    pub fn new_checked(buffer: T) -> Result<Self, FrameError> {
        let b = buffer.as_ref();
        let got = b.len();
        let Some(&stx) = b.first() else {
            return Err(FrameError::Truncated { needed: 4, got });
        };
        if stx != STX {
            return Err(FrameError::BadStx { got: stx });
        }
        let (Some(&lo), Some(&hi)) = (b.get(2), b.get(3)) else {
            return Err(FrameError::Truncated { needed: 4, got });
        };
        let len = u16::from_le_bytes([lo, hi]);
        if len == 0 || len as usize > MAX_PAYLOAD_LEN {
            return Err(FrameError::BadLength { len });
        }
        let end = 4 + len as usize;
        let total = end + 2;
        let (Some(body), Some(&c0), Some(&c1)) = (b.get(..end), b.get(end), b.get(end + 1)) else {
            return Err(FrameError::Truncated { needed: total, got });
        };
        let got_crc = u16::from_le_bytes([c0, c1]);
        let computed = crc16(body);
        if got_crc != computed {
            return Err(FrameError::BadCrc {
                got: got_crc,
                computed,
            });
        }
        Ok(Self { buffer })
    }

    fn bytes(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// The address byte.
    pub fn address(&self) -> u8 {
        self.bytes().get(1).copied().unwrap_or(0)
    }

    /// Command and data length.
    pub fn payload_len(&self) -> usize {
        u16::from_le_bytes([
            self.bytes().get(2).copied().unwrap_or(0),
            self.bytes().get(3).copied().unwrap_or(0),
        ]) as usize
    }

    /// Total length on the wire \[bytes\].
    pub fn total_len(&self) -> usize {
        self.payload_len() + 6
    }

    /// The command byte.
    pub fn command(&self) -> u8 {
        self.bytes().get(4).copied().unwrap_or(0)
    }

    /// The data after the command byte.
    pub fn data(&self) -> &[u8] {
        self.bytes().get(5..4 + self.payload_len()).unwrap_or(&[])
    }

    /// The whole telegram.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes().get(..self.total_len()).unwrap_or(&[])
    }
}

fn emit_with(
    buf: &mut [u8],
    address: u8,
    command: u8,
    data_len: usize,
    write: impl FnOnce(&mut Writer<'_>) -> Result<(), Overflow>,
) -> Result<usize, EmitError> {
    let needed = data_len + 7;
    let capacity = buf.len();
    let too_small = EmitError::BufferTooSmall { needed, capacity };
    if data_len > MAX_DATA_LEN || capacity < needed {
        return Err(too_small);
    }
    let mut w = Writer::new(buf);
    w.u8(STX).map_err(|_| too_small)?;
    w.u8(address).map_err(|_| too_small)?;
    w.u16_le(0).map_err(|_| too_small)?;
    w.u8(command).map_err(|_| too_small)?;
    write(&mut w).map_err(|_| too_small)?;
    let len = (w.position() - 4) as u16;
    let [lo, hi] = len.to_le_bytes();
    w.patch(2, lo).map_err(|_| too_small)?;
    w.patch(3, hi).map_err(|_| too_small)?;
    let crc = crc16(w.written());
    w.u16_le(crc).map_err(|_| too_small)?;
    Ok(w.position())
}

/// Writes a telegram with the given address, command and data; returns its length.
pub fn emit_telegram(
    buf: &mut [u8],
    address: u8,
    command: u8,
    data: &[u8],
) -> Result<usize, EmitError> {
    emit_with(buf, address, command, data.len(), |w| w.bytes(data))
}

/// An operating mode selected with command 0x20.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Mode {
    /// 0x00 + password: installation (setup) mode.
    Setup {
        /// The 8-byte password ([`DEFAULT_PASSWORD`]).
        password: [u8; 8],
    },
    /// 0x24: continuous output of measured values.
    ContinuousOutput,
    /// 0x25: stop continuous output (values on request only).
    Stop,
    /// 0x40: 38400 baud.
    Baud38400,
    /// 0x41: 19200 baud.
    Baud19200,
    /// 0x42: 9600 baud.
    Baud9600,
}

/// Units of the measured values (count word bits 14-15).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RangeUnit {
    /// 00: centimetres.
    Cm,
    /// 01: millimetres.
    #[default]
    Mm,
    /// 10: decimetres (10 cm).
    Dm,
}

impl RangeUnit {
    /// Millimetres per unit.
    pub fn mm(self) -> u32 {
        match self {
            RangeUnit::Cm => 10,
            RangeUnit::Mm => 1,
            RangeUnit::Dm => 100,
        }
    }
}

/// A measured-values telegram (0xB0).
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct MeasuredValues {
    /// Units of the values.
    pub unit: RangeUnit,
    /// Count word bits 10-13 (partial scan information), kept as sent.
    pub flags: u8,
    /// Raw values: distance in the low bits, reflector bits above (per configuration).
    pub values: heapless::Vec<u16, MAX_VALUES>,
    /// Trailing status byte.
    pub status: u8,
}

impl MeasuredValues {
    /// The ranges \[mm\] in scan order: each value's distance bits (`distance_mask`: 0x1FFF
    /// for 13-bit mm data, 0xFFFF to keep everything) times the unit. 0 means no return.
    pub fn ranges_mm(&self, distance_mask: u16) -> impl Iterator<Item = u32> + '_ {
        let unit_mm = self.unit.mm();
        self.values
            .iter()
            .map(move |&raw| u32::from(raw & distance_mask) * unit_mm)
    }
}

/// Angular range and resolution (command 0x3B, reply 0xBB).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    /// Angular range \[deg\]: 100 or 180.
    pub angle_deg: u16,
    /// Resolution \[0.01 deg\]: 100, 50 or 25.
    pub resolution_cdeg: u16,
}

impl Variant {
    /// 180° at 1°.
    pub const DEG180_RES1: Variant = Variant {
        angle_deg: 180,
        resolution_cdeg: 100,
    };
    /// 180° at 0.5°.
    pub const DEG180_RES05: Variant = Variant {
        angle_deg: 180,
        resolution_cdeg: 50,
    };

    /// Beams per scan.
    pub fn beam_count(&self) -> usize {
        if self.resolution_cdeg == 0 {
            return 0;
        }
        self.angle_deg as usize * 100 / self.resolution_cdeg as usize + 1
    }

    /// First beam angle in the laser frame \[0.01 deg\]: scans are centred on forward and the
    /// LMS200 sweeps from its right to its left (−9000 for a 180° scan).
    pub fn first_angle_cdeg(&self) -> i32 {
        -i32::from(self.angle_deg) * 50
    }
}

/// Data bytes of a generic telegram.
pub type Data = heapless::Vec<u8, MAX_DATA_LEN>;

/// A telegram from the host to the laser (address 0x00).
// Stored inline: the core has no allocator; a telegram is at most 812 bytes.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Request {
    /// 0x10: reset (the laser answers with a power-on telegram later).
    Reset,
    /// 0x20: change the operating mode.
    SetMode(Mode),
    /// 0x3B: angular range and resolution.
    SetVariant(Variant),
    /// Any other command.
    Other {
        /// The command byte.
        command: u8,
        /// The data.
        data: Data,
    },
}

impl Request {
    /// Decodes a checked telegram.
    pub fn parse<T: AsRef<[u8]>>(t: &Telegram<T>) -> Result<Self, ParseError> {
        Self::parse_parts(t.command(), t.data())
    }

    /// Decodes a command byte and its data.
    pub fn parse_parts(command: u8, data: &[u8]) -> Result<Self, ParseError> {
        let mut r = Reader::new(data);
        let req = match command {
            cmd::RESET => Request::Reset,
            cmd::MODE => {
                let m = r.u8().ok_or(ParseError::Truncated { field: "mode" })?;
                Request::SetMode(match m {
                    0x00 => {
                        let p = r
                            .take(8)
                            .ok_or(ParseError::Truncated { field: "password" })?;
                        let mut password = [0u8; 8];
                        password.copy_from_slice(p);
                        Mode::Setup { password }
                    }
                    0x24 => Mode::ContinuousOutput,
                    0x25 => Mode::Stop,
                    0x40 => Mode::Baud38400,
                    0x41 => Mode::Baud19200,
                    0x42 => Mode::Baud9600,
                    got => return Err(ParseError::UnknownMode { got }),
                })
            }
            cmd::VARIANT => {
                let angle_deg = r.u16_le().ok_or(ParseError::Truncated { field: "angle" })?;
                let resolution_cdeg = r.u16_le().ok_or(ParseError::Truncated {
                    field: "resolution",
                })?;
                Request::SetVariant(Variant {
                    angle_deg,
                    resolution_cdeg,
                })
            }
            _ => Request::Other {
                command,
                data: Data::from_slice(r.rest())
                    .map_err(|_| ParseError::TooManyValues { count: data.len() })?,
            },
        };
        if !r.is_empty() {
            return Err(ParseError::TrailingBytes {
                count: r.remaining(),
            });
        }
        Ok(req)
    }

    /// Encodes the request as a telegram to laser address 0; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        match self {
            Request::Reset => emit_telegram(buf, HOST_ADDRESS, cmd::RESET, &[]),
            Request::SetMode(m) => {
                let mut data = [0u8; 9];
                let n = match m {
                    Mode::Setup { password } => {
                        data[1..9].copy_from_slice(password);
                        9
                    }
                    Mode::ContinuousOutput => {
                        data[0] = 0x24;
                        1
                    }
                    Mode::Stop => {
                        data[0] = 0x25;
                        1
                    }
                    Mode::Baud38400 => {
                        data[0] = 0x40;
                        1
                    }
                    Mode::Baud19200 => {
                        data[0] = 0x41;
                        1
                    }
                    Mode::Baud9600 => {
                        data[0] = 0x42;
                        1
                    }
                };
                emit_telegram(buf, HOST_ADDRESS, cmd::MODE, data.get(..n).unwrap_or(&[]))
            }
            Request::SetVariant(v) => emit_with(buf, HOST_ADDRESS, cmd::VARIANT, 4, |w| {
                w.u16_le(v.angle_deg)?;
                w.u16_le(v.resolution_cdeg)
            }),
            Request::Other { command, data } => emit_telegram(buf, HOST_ADDRESS, *command, data),
        }
    }
}

/// A telegram from the laser to the host.
// Stored inline: the core has no allocator; a telegram is at most 812 bytes.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Response {
    /// 0xA0: mode change reply; `result` 0 = success.
    ModeReply {
        /// 0 success, otherwise refused (e.g. 1 = wrong password).
        result: u8,
        /// Status byte.
        status: u8,
    },
    /// 0xBB: variant reply.
    VariantReply {
        /// Whether the variant was accepted (first byte 1).
        accepted: bool,
        /// The variant now in force.
        variant: Variant,
        /// Status byte.
        status: u8,
    },
    /// 0xB0: measured values.
    MeasuredValues(MeasuredValues),
    /// Any other command.
    Other {
        /// The command byte.
        command: u8,
        /// The data.
        data: Data,
    },
}

impl Response {
    /// Decodes a checked telegram.
    pub fn parse<T: AsRef<[u8]>>(t: &Telegram<T>) -> Result<Self, ParseError> {
        Self::parse_parts(t.command(), t.data())
    }

    /// Decodes a command byte and its data.
    pub fn parse_parts(command: u8, data: &[u8]) -> Result<Self, ParseError> {
        let mut r = Reader::new(data);
        let t = |field| ParseError::Truncated { field };
        let resp = match command {
            cmd::MODE_REPLY => Response::ModeReply {
                result: r.u8().ok_or(t("result"))?,
                status: r.u8().ok_or(t("status"))?,
            },
            cmd::VARIANT_REPLY => Response::VariantReply {
                accepted: r.u8().ok_or(t("result"))? == 1,
                variant: Variant {
                    angle_deg: r.u16_le().ok_or(t("angle"))?,
                    resolution_cdeg: r.u16_le().ok_or(t("resolution"))?,
                },
                status: r.u8().ok_or(t("status"))?,
            },
            cmd::MEASURED_VALUES => {
                let word = r.u16_le().ok_or(t("count word"))?;
                let count = (word & 0x03FF) as usize;
                let unit = match word >> 14 {
                    0 => RangeUnit::Cm,
                    1 => RangeUnit::Mm,
                    2 => RangeUnit::Dm,
                    _ => return Err(ParseError::BadUnits { word }),
                };
                if count > MAX_VALUES {
                    return Err(ParseError::TooManyValues { count });
                }
                let mut values = heapless::Vec::new();
                for _ in 0..count {
                    let v = r.u16_le().ok_or(t("measured value"))?;
                    let _ = values.push(v);
                }
                Response::MeasuredValues(MeasuredValues {
                    unit,
                    flags: ((word >> 10) & 0x0F) as u8,
                    values,
                    status: r.u8().ok_or(t("status"))?,
                })
            }
            _ => Response::Other {
                command,
                data: Data::from_slice(r.rest())
                    .map_err(|_| ParseError::TooManyValues { count: data.len() })?,
            },
        };
        if !r.is_empty() {
            return Err(ParseError::TrailingBytes {
                count: r.remaining(),
            });
        }
        Ok(resp)
    }

    /// Encodes the response as a telegram from laser address 0 (0x80); returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        let a = LASER_REPLY_ADDRESS;
        match self {
            Response::ModeReply { result, status } => {
                emit_telegram(buf, a, cmd::MODE_REPLY, &[*result, *status])
            }
            Response::VariantReply {
                accepted,
                variant,
                status,
            } => emit_with(buf, a, cmd::VARIANT_REPLY, 6, |w| {
                w.u8(*accepted as u8)?;
                w.u16_le(variant.angle_deg)?;
                w.u16_le(variant.resolution_cdeg)?;
                w.u8(*status)
            }),
            Response::MeasuredValues(m) => {
                let count = m.values.len();
                if count > 0x03FF {
                    return Err(EmitError::TooManyValues { count });
                }
                let unit_bits: u16 = match m.unit {
                    RangeUnit::Cm => 0,
                    RangeUnit::Mm => 1,
                    RangeUnit::Dm => 2,
                };
                let word = (unit_bits << 14) | (((m.flags & 0x0F) as u16) << 10) | count as u16;
                emit_with(buf, a, cmd::MEASURED_VALUES, 3 + 2 * count, |w| {
                    w.u16_le(word)?;
                    for &v in &m.values {
                        w.u16_le(v)?;
                    }
                    w.u8(m.status)
                })
            }
            Response::Other { command, data } => emit_telegram(buf, a, *command, data),
        }
    }
}

/// What the LMS200 stream decoder produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    /// A single ACK byte outside a telegram.
    Ack,
    /// A single NACK byte outside a telegram.
    Nack,
    /// A telegram with a valid CRC.
    Telegram(Telegram<&'a [u8]>),
}

/// What the LMS200 decoder has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Lms200Stats {
    /// Valid telegrams returned.
    pub telegrams: u64,
    /// ACK and NACK bytes returned.
    pub acks: u64,
    /// Candidates dropped for a bad CRC.
    pub bad_crc: u64,
    /// Candidates dropped for a bad length.
    pub bad_length: u64,
    /// Bytes skipped while hunting for STX.
    pub skipped_bytes: u64,
}

/// Streaming LMS200 decoder with a fixed buffer of one telegram. It hunts for STX, checks the
/// length and the CRC, and on failure drops one byte and hunts again. ACK/NACK bytes seen
/// while hunting are reported as events (a 0x06 or 0x15 byte inside junk is indistinguishable
/// from a real one).
#[derive(Clone, Debug)]
pub struct Lms200Decoder {
    buf: [u8; MAX_TELEGRAM_LEN],
    len: usize,
    consumed: usize,
    stats: Lms200Stats,
}

impl Default for Lms200Decoder {
    fn default() -> Self {
        Self::new()
    }
}

enum Found {
    Ack,
    Nack,
    Telegram(usize),
}

impl Lms200Decoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_TELEGRAM_LEN],
            len: 0,
            consumed: 0,
            stats: Lms200Stats {
                telegrams: 0,
                acks: 0,
                bad_crc: 0,
                bad_length: 0,
                skipped_bytes: 0,
            },
        }
    }

    /// Counters since creation.
    pub fn stats(&self) -> Lms200Stats {
        self.stats
    }

    /// Drops any partial telegram.
    pub fn reset(&mut self) {
        self.len = 0;
        self.consumed = 0;
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    fn scan(&mut self) -> Option<Found> {
        loop {
            let first = *self.buf.get(..self.len)?.first()?;
            match first {
                STX => {}
                ACK => return Some(Found::Ack),
                NACK => return Some(Found::Nack),
                _ => {
                    self.stats.skipped_bytes += 1;
                    self.drop_front(1);
                    continue;
                }
            }
            if self.len < 4 {
                return None;
            }
            let len = u16::from_le_bytes([*self.buf.get(2)?, *self.buf.get(3)?]) as usize;
            if len == 0 || len > MAX_PAYLOAD_LEN {
                self.stats.bad_length += 1;
                self.stats.skipped_bytes += 1;
                self.drop_front(1);
                continue;
            }
            let total = len + 6;
            if self.len < total {
                return None;
            }
            let computed = crc16(self.buf.get(..total - 2)?);
            let got = u16::from_le_bytes([*self.buf.get(total - 2)?, *self.buf.get(total - 1)?]);
            if got != computed {
                self.stats.bad_crc += 1;
                self.stats.skipped_bytes += 1;
                self.drop_front(1);
                continue;
            }
            return Some(Found::Telegram(total));
        }
    }

    fn bytes_needed(&self) -> usize {
        if self.len >= 4 {
            let len = u16::from_le_bytes([self.buf[2], self.buf[3]]) as usize;
            (len + 6).saturating_sub(self.len)
        } else {
            4 - self.len
        }
    }

    /// Consumes bytes from `input` until an event is complete and returns it; `input` is
    /// advanced past the bytes used. `None` once `input` is exhausted.
    pub fn decode<'a>(&'a mut self, input: &mut &[u8]) -> Option<Event<'a>> {
        if self.consumed > 0 {
            let n = self.consumed;
            self.consumed = 0;
            self.drop_front(n);
        }
        loop {
            match self.scan() {
                Some(Found::Ack) => {
                    self.consumed = 1;
                    self.stats.acks += 1;
                    return Some(Event::Ack);
                }
                Some(Found::Nack) => {
                    self.consumed = 1;
                    self.stats.acks += 1;
                    return Some(Event::Nack);
                }
                Some(Found::Telegram(total)) => {
                    self.consumed = total;
                    self.stats.telegrams += 1;
                    return Telegram::new_checked(self.buf.get(..total)?)
                        .ok()
                        .map(Event::Telegram);
                }
                None => {}
            }
            if input.is_empty() {
                return None;
            }
            let room = MAX_TELEGRAM_LEN - self.len;
            let n = self.bytes_needed().min(room).max(1).min(input.len());
            let (head, tail) = input.split_at(n);
            self.buf
                .get_mut(self.len..self.len + n)?
                .copy_from_slice(head);
            self.len += n;
            *input = tail;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{ProjectRng, below, seeded};
    use rand_core::Rng;
    extern crate std;
    use std::vec::Vec;

    #[test]
    fn golden_crc_examples() {
        // Fact sheet section 3.
        assert_eq!(
            crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x25]).to_le_bytes(),
            [0x35, 0x08]
        );
        assert_eq!(
            crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x24]).to_le_bytes(),
            [0x34, 0x08]
        );
        assert_eq!(
            crc16(&[0x02, 0x00, 0x02, 0x00, 0x20, 0x40]).to_le_bytes(),
            [0x50, 0x08]
        );
    }

    #[test]
    fn golden_mode_telegrams() {
        let cases: [(Mode, [u8; 8]); 3] = [
            (Mode::Stop, [0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08]),
            (
                Mode::ContinuousOutput,
                [0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08],
            ),
            (
                Mode::Baud38400,
                [0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08],
            ),
        ];
        let mut buf = [0u8; 32];
        for (mode, bytes) in cases {
            let n = Request::SetMode(mode).emit(&mut buf).unwrap();
            assert_eq!(&buf[..n], &bytes);
            let t = Telegram::new_checked(&bytes[..]).unwrap();
            assert_eq!(Request::parse(&t), Ok(Request::SetMode(mode)));
        }
        let bad = [0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x36, 0x08];
        assert_eq!(
            Telegram::new_checked(&bad[..]),
            Err(FrameError::BadCrc {
                got: 0x0836,
                computed: 0x0835
            })
        );
    }

    #[test]
    fn setup_mode_carries_the_password() {
        let mut buf = [0u8; 32];
        let r = Request::SetMode(Mode::Setup {
            password: DEFAULT_PASSWORD,
        });
        let n = r.emit(&mut buf).unwrap();
        assert_eq!(&buf[..5], &[0x02, 0x00, 0x0A, 0x00, 0x20]);
        assert_eq!(&buf[5..14], b"\0SICK_LMS");
        assert_eq!(
            Request::parse(&Telegram::new_checked(&buf[..n]).unwrap()),
            Ok(r)
        );
    }

    #[test]
    fn measured_values_to_scan() {
        let mut m = MeasuredValues::default();
        for i in 0..181u16 {
            m.values.push(if i == 90 { 0 } else { 1000 + i }).unwrap();
        }
        let mut buf = [0u8; MAX_TELEGRAM_LEN];
        let n = Response::MeasuredValues(m.clone()).emit(&mut buf).unwrap();
        // Count word: units mm (01) and 181 values.
        assert_eq!(&buf[5..7], &(0x4000u16 | 181).to_le_bytes());
        let t = Telegram::new_checked(&buf[..n]).unwrap();
        let Response::MeasuredValues(back) = Response::parse(&t).unwrap() else {
            panic!("not measured values")
        };
        assert_eq!(back, m);
        let ranges: Vec<u32> = back.ranges_mm(0x1FFF).collect();
        assert_eq!(ranges.len(), 181);
        assert_eq!((ranges[0], ranges[90], ranges[150]), (1000, 0, 1150));
        assert_eq!(Variant::DEG180_RES1.first_angle_cdeg(), -9000);
    }

    fn random_response(rng: &mut ProjectRng) -> Response {
        match below(rng, 4) {
            0 => Response::ModeReply {
                result: rng.next_u32() as u8,
                status: rng.next_u32() as u8,
            },
            1 => Response::VariantReply {
                accepted: rng.next_u32() & 1 == 1,
                variant: Variant {
                    angle_deg: rng.next_u32() as u16,
                    resolution_cdeg: rng.next_u32() as u16,
                },
                status: rng.next_u32() as u8,
            },
            2 => {
                let mut m = MeasuredValues {
                    unit: [RangeUnit::Cm, RangeUnit::Mm, RangeUnit::Dm][below(rng, 3)],
                    flags: below(rng, 16) as u8,
                    status: rng.next_u32() as u8,
                    ..Default::default()
                };
                for _ in 0..below(rng, MAX_VALUES + 1) {
                    m.values.push(rng.next_u32() as u16).unwrap();
                }
                Response::MeasuredValues(m)
            }
            _ => {
                let mut data = Data::new();
                for _ in 0..below(rng, 40) {
                    data.push(rng.next_u32() as u8).unwrap();
                }
                Response::Other {
                    command: 0x90,
                    data,
                }
            }
        }
    }

    fn random_request(rng: &mut ProjectRng) -> Request {
        match below(rng, 9) {
            0 => Request::Reset,
            1 => Request::SetMode(Mode::Setup {
                password: (rng.next_u64()).to_le_bytes(),
            }),
            2 => Request::SetMode(Mode::ContinuousOutput),
            3 => Request::SetMode(Mode::Stop),
            4 => Request::SetMode(Mode::Baud38400),
            5 => Request::SetMode(Mode::Baud19200),
            6 => Request::SetMode(Mode::Baud9600),
            7 => Request::SetVariant(Variant {
                angle_deg: rng.next_u32() as u16,
                resolution_cdeg: rng.next_u32() as u16,
            }),
            _ => Request::Other {
                command: cmd::CONFIG,
                data: Data::from_slice(&rng.next_u64().to_le_bytes()).unwrap(),
            },
        }
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(200);
        let mut buf = [0u8; MAX_TELEGRAM_LEN];
        for _ in 0..5_000 {
            let r = random_request(&mut rng);
            let n = r.emit(&mut buf).unwrap();
            assert_eq!(
                Request::parse(&Telegram::new_checked(&buf[..n]).unwrap()),
                Ok(r)
            );
            let r = random_response(&mut rng);
            let n = r.emit(&mut buf).unwrap();
            assert_eq!(
                Response::parse(&Telegram::new_checked(&buf[..n]).unwrap()),
                Ok(r)
            );
        }
    }

    #[derive(Debug, PartialEq)]
    enum Ev {
        Ack,
        Nack,
        T(Vec<u8>),
    }

    fn decode_all(dec: &mut Lms200Decoder, chunks: &[&[u8]]) -> Vec<Ev> {
        let mut out = Vec::new();
        for c in chunks {
            let mut input = *c;
            while let Some(e) = dec.decode(&mut input) {
                out.push(match e {
                    Event::Ack => Ev::Ack,
                    Event::Nack => Ev::Nack,
                    Event::Telegram(t) => Ev::T(t.as_bytes().to_vec()),
                });
            }
        }
        out
    }

    fn random_stream(rng: &mut ProjectRng, garbage: bool) -> (Vec<u8>, Vec<Ev>) {
        let mut stream = Vec::new();
        let mut events = Vec::new();
        let mut buf = [0u8; MAX_TELEGRAM_LEN];
        for _ in 0..20 {
            if garbage && below(rng, 3) == 0 {
                for _ in 0..below(rng, 30) {
                    let b = rng.next_u32() as u8;
                    // Junk without STX/ACK/NACK so it cannot hide or fake an event.
                    stream.push(if matches!(b, STX | ACK | NACK) {
                        0x55
                    } else {
                        b
                    });
                }
            }
            match below(rng, 4) {
                0 => {
                    stream.push(ACK);
                    events.push(Ev::Ack);
                }
                1 => {
                    stream.push(NACK);
                    events.push(Ev::Nack);
                }
                2 => {
                    let n = random_request(rng).emit(&mut buf).unwrap();
                    stream.extend_from_slice(&buf[..n]);
                    events.push(Ev::T(buf[..n].to_vec()));
                }
                _ => {
                    let n = random_response(rng).emit(&mut buf).unwrap();
                    stream.extend_from_slice(&buf[..n]);
                    events.push(Ev::T(buf[..n].to_vec()));
                }
            }
        }
        (stream, events)
    }

    fn random_split<'a>(rng: &mut ProjectRng, s: &'a [u8]) -> Vec<&'a [u8]> {
        let mut out = Vec::new();
        let mut rest = s;
        while !rest.is_empty() {
            let n = 1 + below(rng, rest.len().min(1000));
            let (a, b) = rest.split_at(n);
            out.push(a);
            rest = b;
        }
        out
    }

    #[test]
    fn any_split_and_junk_give_the_same_events() {
        let mut rng = seeded(0x200);
        for round in 0..200 {
            let (stream, events) = random_stream(&mut rng, round % 2 == 1);
            let chunks = random_split(&mut rng, &stream);
            let mut dec = Lms200Decoder::new();
            assert_eq!(decode_all(&mut dec, &chunks), events);
        }
        // Arbitrary garbage then padding long enough to refute any false STX: the frames
        // after it all come out.
        for _ in 0..100 {
            let mut stream = Vec::new();
            for _ in 0..below(&mut rng, 2000) {
                stream.push(rng.next_u32() as u8);
            }
            stream.extend_from_slice(&[0x55u8; MAX_TELEGRAM_LEN]);
            let (tail, events) = random_stream(&mut rng, false);
            stream.extend_from_slice(&tail);
            let chunks = random_split(&mut rng, &stream);
            let mut dec = Lms200Decoder::new();
            let got = decode_all(&mut dec, &chunks);
            assert!(got.len() >= events.len());
            assert_eq!(got[got.len() - events.len()..], events[..]);
        }
    }

    #[test]
    fn bad_telegrams_are_counted() {
        let mut dec = Lms200Decoder::new();
        let stream = [
            0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x09, // bad CRC
            0x02, 0x00, 0xFF, 0xFF, // bad length
            0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08,
        ];
        let got = decode_all(&mut dec, &[&stream]);
        assert_eq!(got, std::vec![Ev::T(stream[12..].to_vec())]);
        assert_eq!(dec.stats().bad_crc, 1);
        // The length byte 0x02 of the dropped telegram is itself taken as an STX whose
        // length (0x2520) is refuted: two bad lengths.
        assert_eq!(dec.stats().bad_length, 2);
    }
}
