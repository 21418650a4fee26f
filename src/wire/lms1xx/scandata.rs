//! The `LMDscandata` telegram: parsing into a [`ScanTelegram`] and emitting it (for the
//! emulator). The telegram keeps its values as the laser sends them (distances in its units
//! with scale and offset, angles in 1/10000°); the sensor layer (`sensor::telegram`) turns one into a scan.
//!
//! Token layout after `sSN LMDscandata` (or `sRA LMDscandata` when polled), fact sheet
//! section 2: version, device number, serial number, device status (2), telegram counter,
//! scan counter, time since startup \[µs\], time of transmission \[µs\], input status (2), output
//! status (2), reserved, scanning frequency \[0.01 Hz\], measurement frequency, encoders (count
//! then position and speed each), 16-bit channels (count then per channel: content name,
//! scale factor and offset as IEEE-754 floats in 8 hex digits, start angle \[1/10000°\], angular
//! step \[1/10000°\], value count, values), 8-bit channels (same layout), then position, device
//! name, comment, time stamp and event blocks, each a 0/1 flag followed by its data when 1.
//!
//! Angles: SICK counts the start angle from the laser's right-hand side (its 0° is the laser
//! frame's −90°), so the laser-frame angle of beam `i` is
//! `start/10000° − 90° + i · step/10000°`: the LMS1xx's −45° start is −135° from forward,
//! as the clearpath driver computes it (ARIA instead centres the readings symmetrically, which
//! gives the same angles for the standard symmetric 270° field).

use core::fmt::{self, Write};

use super::framing::emit_with;
use super::{EmitError, ParseError, Tokens, token_text};

/// Values a channel can carry: an LMS1xx at 0.25° over 270° (1081 beams).
pub const MAX_VALUES: usize = 1081;
/// Channels of each width a telegram can carry (DIST1, DIST2, RSSI1, RSSI2).
pub const MAX_CHANNELS: usize = 4;
/// Encoders a telegram can carry.
pub const MAX_ENCODERS: usize = 4;

/// A channel content name such as `DIST1` or `RSSI1`.
pub type ChannelName = heapless::String<8>;
/// Device name and comment text.
pub type Text = heapless::String<32>;

/// One output channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel<V> {
    /// Content: `DIST1`, `DIST2`, `RSSI1`, `RSSI2`.
    pub content: ChannelName,
    /// Scale factor (1.0 for distances in mm).
    pub scale: f32,
    /// Scale offset.
    pub offset: f32,
    /// First beam angle in SICK's frame \[1/10000 deg\].
    pub start_angle_deg_e4: i32,
    /// Angular step \[1/10000 deg\].
    pub step_deg_e4: u16,
    /// Raw values.
    pub values: heapless::Vec<V, MAX_VALUES>,
}

/// A 16-bit channel (distances in mm at scale 1.0).
pub type Channel16 = Channel<u16>;
/// An 8-bit channel.
pub type Channel8 = Channel<u8>;

/// One encoder block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderData {
    /// Position \[ticks\].
    pub position: u32,
    /// Speed \[ticks/mm\].
    pub speed: u16,
}

/// The position block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PositionData {
    /// X, Y, Z position (floats).
    pub xyz: [f32; 3],
    /// Rotation about X, Y, Z (floats).
    pub rotation: [f32; 3],
    /// Rotation type.
    pub rotation_type: u8,
}

/// The time stamp block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimeStamp {
    /// Year.
    pub year: u16,
    /// Month.
    pub month: u8,
    /// Day.
    pub day: u8,
    /// Hour.
    pub hour: u8,
    /// Minute.
    pub minute: u8,
    /// Second.
    pub second: u8,
    /// Microseconds.
    pub microsecond: u32,
}

/// The event block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EventData {
    /// Event type, e.g. `FDIN`.
    pub kind: ChannelName,
    /// Encoder position at the event.
    pub encoder_position: u32,
    /// Time of the event \[µs\].
    pub time_us: u32,
    /// Angle of the event \[1/10000 deg\].
    pub angle_deg_e4: i32,
}

/// A parsed `LMDscandata` telegram.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ScanTelegram {
    /// Sent as `sRA` (polled) rather than `sSN` (event).
    pub polled: bool,
    /// Version number.
    pub version: u16,
    /// Device number.
    pub device_number: u16,
    /// Serial number.
    pub serial_number: u32,
    /// Device status (two tokens).
    pub device_status: [u8; 2],
    /// Telegram counter.
    pub telegram_counter: u16,
    /// Scan counter.
    pub scan_counter: u16,
    /// Time since startup \[µs\].
    pub time_since_startup_us: u32,
    /// Time of transmission \[µs\].
    pub time_of_transmission_us: u32,
    /// Input status (two tokens).
    pub input_status: [u8; 2],
    /// Output status (two tokens).
    pub output_status: [u8; 2],
    /// Reserved byte A.
    pub reserved_a: u16,
    /// Scanning frequency \[0.01 Hz\].
    pub scan_frequency_centi_hz: u32,
    /// Measurement frequency.
    pub measurement_frequency: u32,
    /// Encoder blocks.
    pub encoders: heapless::Vec<EncoderData, MAX_ENCODERS>,
    /// 16-bit channels.
    pub channels16: heapless::Vec<Channel16, MAX_CHANNELS>,
    /// 8-bit channels.
    pub channels8: heapless::Vec<Channel8, MAX_CHANNELS>,
    /// Position block, if sent.
    pub position: Option<PositionData>,
    /// Device name, if sent.
    pub device_name: Option<Text>,
    /// Comment, if sent.
    pub comment: Option<Text>,
    /// Time stamp, if sent.
    pub time: Option<TimeStamp>,
    /// Event block, if sent.
    pub event: Option<EventData>,
}

/// Whether a telegram payload is scan data (`sSN LMDscandata …` or `sRA LMDscandata …`).
pub fn is_scan_data(payload: &[u8]) -> bool {
    payload.starts_with(b"sSN LMDscandata ") || payload.starts_with(b"sRA LMDscandata ")
}

fn parse_channel<V: Copy>(
    t: &mut Tokens<'_>,
    max: u32,
    conv: impl Fn(u32) -> V,
) -> Result<Channel<V>, ParseError> {
    let content = t.text::<8>("channel content")?;
    let scale = t.float("scale factor")?;
    let offset = t.float("scale offset")?;
    let start_angle_deg_e4 = t.int32("start angle")?;
    let step_deg_e4 = t.uint("angular step", u16::MAX as u32)? as u16;
    let count = t.uint("value count", u32::MAX)?;
    if count as usize > MAX_VALUES {
        return Err(ParseError::TooMany {
            field: "values",
            count,
            capacity: MAX_VALUES,
        });
    }
    let mut values = heapless::Vec::new();
    for _ in 0..count {
        let v = t.uint("value", max)?;
        let _ = values.push(conv(v));
    }
    Ok(Channel {
        content,
        scale,
        offset,
        start_angle_deg_e4,
        step_deg_e4,
        values,
    })
}

fn count(t: &mut Tokens<'_>, field: &'static str, capacity: usize) -> Result<u32, ParseError> {
    let n = t.uint(field, u32::MAX)?;
    if n as usize > capacity {
        return Err(ParseError::TooMany {
            field,
            count: n,
            capacity,
        });
    }
    Ok(n)
}

/// Reads an optional block's flag; a telegram that ends before it means "absent".
fn block_flag(t: &mut Tokens<'_>, field: &'static str) -> Result<bool, ParseError> {
    if t.is_empty() {
        Ok(false)
    } else {
        t.flag(field)
    }
}

impl ScanTelegram {
    /// A telegram with one DIST1 channel of distances \[mm\] at scale 1.0, as an emulated
    /// LMS1xx sends it.
    pub fn with_distances(
        start_angle_deg_e4: i32,
        step_deg_e4: u16,
        scan_frequency_centi_hz: u32,
        ranges_mm: &[u16],
    ) -> Result<Self, EmitError> {
        let mut values = heapless::Vec::new();
        values
            .extend_from_slice(ranges_mm)
            .map_err(|_| EmitError::TooManyValues {
                count: ranges_mm.len(),
                capacity: MAX_VALUES,
            })?;
        let mut t = ScanTelegram {
            version: 1,
            device_number: 1,
            scan_frequency_centi_hz,
            ..Default::default()
        };
        let _ = t.channels16.push(Channel {
            content: ChannelName::try_from("DIST1").unwrap_or_default(),
            scale: 1.0,
            offset: 0.0,
            start_angle_deg_e4,
            step_deg_e4,
            values,
        });
        Ok(t)
    }

    /// Parses a telegram payload (between STX and ETX). Numbers may be hex or signed
    /// decimal. Blocks after the channels that the telegram omits are absent; tokens after the
    /// event block are ignored.
    pub fn parse(payload: &[u8]) -> Result<Self, ParseError> {
        let mut t = Tokens::new(payload);
        let kind = t.next_token().ok_or(ParseError::Empty)?;
        let name = t.token("command name")?;
        let polled = match (kind, name) {
            (b"sSN", b"LMDscandata") => false,
            (b"sRA", b"LMDscandata") => true,
            _ => {
                return Err(ParseError::UnknownMessage {
                    got: token_text(payload),
                });
            }
        };
        let u8f = |t: &mut Tokens<'_>, f| t.uint(f, 255).map(|v| v as u8);
        let u16f = |t: &mut Tokens<'_>, f| t.uint(f, u16::MAX as u32).map(|v| v as u16);
        let mut s = ScanTelegram {
            polled,
            version: u16f(&mut t, "version")?,
            device_number: u16f(&mut t, "device number")?,
            serial_number: t.uint("serial number", u32::MAX)?,
            device_status: [u8f(&mut t, "device status")?, u8f(&mut t, "device status")?],
            telegram_counter: u16f(&mut t, "telegram counter")?,
            scan_counter: u16f(&mut t, "scan counter")?,
            time_since_startup_us: t.uint("time since startup", u32::MAX)?,
            time_of_transmission_us: t.uint("time of transmission", u32::MAX)?,
            input_status: [u8f(&mut t, "input status")?, u8f(&mut t, "input status")?],
            output_status: [u8f(&mut t, "output status")?, u8f(&mut t, "output status")?],
            reserved_a: u16f(&mut t, "reserved byte A")?,
            scan_frequency_centi_hz: t.uint("scanning frequency", u32::MAX)?,
            measurement_frequency: t.uint("measurement frequency", u32::MAX)?,
            ..Default::default()
        };
        for _ in 0..count(&mut t, "encoders", MAX_ENCODERS)? {
            let position = t.uint("encoder position", u32::MAX)?;
            let speed = u16f(&mut t, "encoder speed")?;
            let _ = s.encoders.push(EncoderData { position, speed });
        }
        for _ in 0..count(&mut t, "16-bit channels", MAX_CHANNELS)? {
            let c = parse_channel(&mut t, u16::MAX as u32, |v| v as u16)?;
            let _ = s.channels16.push(c);
        }
        if !t.is_empty() {
            for _ in 0..count(&mut t, "8-bit channels", MAX_CHANNELS)? {
                let c = parse_channel(&mut t, 255, |v| v as u8)?;
                let _ = s.channels8.push(c);
            }
        }
        if block_flag(&mut t, "position flag")? {
            s.position = Some(PositionData {
                xyz: [
                    t.float("position x")?,
                    t.float("position y")?,
                    t.float("position z")?,
                ],
                rotation: [
                    t.float("rotation x")?,
                    t.float("rotation y")?,
                    t.float("rotation z")?,
                ],
                rotation_type: u8f(&mut t, "rotation type")?,
            });
        }
        if block_flag(&mut t, "device name flag")? {
            t.uint("device name length", u32::MAX)?;
            s.device_name = Some(t.text::<32>("device name")?);
        }
        if block_flag(&mut t, "comment flag")? {
            t.uint("comment length", u32::MAX)?;
            s.comment = Some(t.text::<32>("comment")?);
        }
        if block_flag(&mut t, "time flag")? {
            s.time = Some(TimeStamp {
                year: u16f(&mut t, "year")?,
                month: u8f(&mut t, "month")?,
                day: u8f(&mut t, "day")?,
                hour: u8f(&mut t, "hour")?,
                minute: u8f(&mut t, "minute")?,
                second: u8f(&mut t, "second")?,
                microsecond: t.uint("microsecond", u32::MAX)?,
            });
        }
        if block_flag(&mut t, "event flag")? {
            s.event = Some(EventData {
                kind: t.text::<8>("event type")?,
                encoder_position: t.uint("event encoder position", u32::MAX)?,
                time_us: t.uint("event time", u32::MAX)?,
                angle_deg_e4: t.int32("event angle")?,
            });
        }
        Ok(s)
    }

    fn write(&self, w: &mut impl Write) -> fmt::Result {
        w.write_str(if self.polled {
            "sRA LMDscandata"
        } else {
            "sSN LMDscandata"
        })?;
        write!(
            w,
            " {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X} {:X}",
            self.version,
            self.device_number,
            self.serial_number,
            self.device_status[0],
            self.device_status[1],
            self.telegram_counter,
            self.scan_counter,
            self.time_since_startup_us,
            self.time_of_transmission_us,
            self.input_status[0],
            self.input_status[1],
            self.output_status[0],
            self.output_status[1],
            self.reserved_a,
            self.scan_frequency_centi_hz,
            self.measurement_frequency,
            self.encoders.len()
        )?;
        for e in &self.encoders {
            write!(w, " {:X} {:X}", e.position, e.speed)?;
        }
        write!(w, " {:X}", self.channels16.len())?;
        for c in &self.channels16 {
            write_channel(w, c, |v| v as u32)?;
        }
        write!(w, " {:X}", self.channels8.len())?;
        for c in &self.channels8 {
            write_channel(w, c, |v| v as u32)?;
        }
        match &self.position {
            None => w.write_str(" 0")?,
            Some(p) => {
                w.write_str(" 1")?;
                for v in p.xyz.iter().chain(p.rotation.iter()) {
                    write!(w, " {:08X}", v.to_bits())?;
                }
                write!(w, " {:X}", p.rotation_type)?;
            }
        }
        for text in [&self.device_name, &self.comment] {
            match text {
                None => w.write_str(" 0")?,
                Some(s) => write!(w, " 1 {:X} {}", s.len(), s)?,
            }
        }
        match &self.time {
            None => w.write_str(" 0")?,
            Some(t) => write!(
                w,
                " 1 {:X} {:X} {:X} {:X} {:X} {:X} {:X}",
                t.year, t.month, t.day, t.hour, t.minute, t.second, t.microsecond
            )?,
        }
        match &self.event {
            None => w.write_str(" 0"),
            Some(e) => write!(
                w,
                " 1 {} {:X} {:X} {:X}",
                e.kind, e.encoder_position, e.time_us, e.angle_deg_e4 as u32
            ),
        }
    }

    /// Encodes the telegram (STX … ETX) into `buf`; returns its length. Numbers are written
    /// in hex, floats as their 8-hex-digit bit patterns, as the LMS1xx sends them.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        emit_with(buf, |w| self.write(w))
    }

    /// The first distance channel (`DIST1`, else any `DIST…`).
    pub fn distance_channel(&self) -> Option<&Channel16> {
        self.channels16
            .iter()
            .find(|c| c.content.as_str() == "DIST1")
            .or_else(|| {
                self.channels16
                    .iter()
                    .find(|c| c.content.starts_with("DIST"))
            })
    }
}

fn write_channel<V: Copy>(
    w: &mut impl Write,
    c: &Channel<V>,
    conv: impl Fn(V) -> u32,
) -> fmt::Result {
    write!(
        w,
        " {} {:08X} {:08X} {:X} {:X} {:X}",
        c.content,
        c.scale.to_bits(),
        c.offset.to_bits(),
        c.start_angle_deg_e4 as u32,
        c.step_deg_e4,
        c.values.len()
    )?;
    for &v in &c.values {
        write!(w, " {:X}", conv(v))?;
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::random::{ProjectRng, below, seeded};
    use rand_core::Rng;
    extern crate std;
    use std::vec::Vec;

    /// A 541-beam telegram as an LMS1xx sends it (the fact sheet's example values).
    pub(crate) fn lms1xx_telegram() -> Vec<u8> {
        let mut text = std::string::String::from(
            "sSN LMDscandata 1 1 89A27F 0 0 1A2B 1A2E 3C4D5E 3C4F00 0 0 0 0 0 1388 168 0 1 \
             DIST1 3F800000 00000000 FFF92230 1388 21D",
        );
        for i in 0..541u32 {
            let v = if i % 100 == 0 { 0 } else { 500 + i * 10 };
            text.push_str(&std::format!(" {v:X}"));
        }
        text.push_str(" 0 0 0 0 0 0");
        let mut out = std::vec![0x02];
        out.extend_from_slice(text.as_bytes());
        out.push(0x03);
        out
    }

    #[test]
    fn golden_lms1xx_telegram() {
        let frame = lms1xx_telegram();
        let t = ScanTelegram::parse(&frame[1..frame.len() - 1]).unwrap();
        assert_eq!(t.serial_number, 0x89A27F);
        assert_eq!(t.scan_frequency_centi_hz, 5000);
        assert_eq!(t.measurement_frequency, 0x168);
        let c = &t.channels16[0];
        assert_eq!(c.content.as_str(), "DIST1");
        assert_eq!(c.scale, 1.0);
        assert_eq!(c.offset, 0.0);
        assert_eq!(c.start_angle_deg_e4, -450_000);
        assert_eq!(c.step_deg_e4, 5000);
        assert_eq!(c.values.len(), 541);
        assert_eq!(c.values[1], 510);
        assert!(t.channels8.is_empty() && t.position.is_none() && t.event.is_none());
        // Emitting gives the same bytes back.
        let mut buf = std::vec![0u8; 8192];
        let n = t.emit(&mut buf).unwrap();
        assert_eq!(&buf[..n], &frame[..]);
    }

    #[test]
    fn signed_decimal_numbers_are_accepted() {
        let text =
            b"sSN LMDscandata +1 +1 +9018 +0 +0 +1 +1 +0 +0 +0 +0 +0 +0 +0 +5000 +360 +0 +1 \
                     DIST1 3F800000 00000000 -450000 +5000 +3 +100 +0 +65535 +0";
        let t = ScanTelegram::parse(text).unwrap();
        let c = &t.channels16[0];
        assert_eq!(c.start_angle_deg_e4, -450_000);
        assert_eq!(c.values.as_slice(), &[100, 0, 65535]);
        assert_eq!(
            ScanTelegram::parse(b"sSN LMDscandata 1 1 1 0 0 1 1 0 0 0 0 0 0 0 1388 168 0 1 DIST1 3F800000 0 0 1388 3 1 2"),
            Err(ParseError::MissingToken {
                field: "value",
                index: 28
            })
        );
        assert!(matches!(
            ScanTelegram::parse(b"sSN LMDscandata 1 1 1 0 0 1 1 0 0 0 0 0 0 0 1388 168 0 1 DIST1 3F800000 0 0 1388 FFFFF"),
            Err(ParseError::TooMany { .. })
        ));
    }

    pub(crate) fn random_telegram(rng: &mut ProjectRng) -> ScanTelegram {
        let r = |rng: &mut ProjectRng| rng.next_u32();
        let mut t = ScanTelegram {
            polled: r(rng) & 1 == 1,
            version: r(rng) as u16,
            device_number: r(rng) as u16,
            serial_number: r(rng),
            device_status: [r(rng) as u8, r(rng) as u8],
            telegram_counter: r(rng) as u16,
            scan_counter: r(rng) as u16,
            time_since_startup_us: r(rng),
            time_of_transmission_us: r(rng),
            input_status: [r(rng) as u8, r(rng) as u8],
            output_status: [r(rng) as u8, r(rng) as u8],
            reserved_a: r(rng) as u16,
            scan_frequency_centi_hz: r(rng),
            measurement_frequency: r(rng),
            ..Default::default()
        };
        for _ in 0..below(rng, 3) {
            t.encoders
                .push(EncoderData {
                    position: r(rng),
                    speed: r(rng) as u16,
                })
                .unwrap();
        }
        let names = ["DIST1", "DIST2", "RSSI1", "RSSI2"];
        for _ in 0..below(rng, 3) {
            let mut values = heapless::Vec::new();
            for _ in 0..below(rng, 200) {
                values.push(r(rng) as u16).unwrap();
            }
            t.channels16
                .push(Channel {
                    content: names[below(rng, 4)].try_into().unwrap(),
                    scale: f32::from_bits(r(rng) & 0x7F7F_FFFF),
                    offset: f32::from_bits(r(rng) & 0x7F7F_FFFF),
                    start_angle_deg_e4: r(rng) as i32,
                    step_deg_e4: r(rng) as u16,
                    values,
                })
                .unwrap();
        }
        for _ in 0..below(rng, 2) {
            let mut values = heapless::Vec::new();
            for _ in 0..below(rng, 100) {
                values.push(r(rng) as u8).unwrap();
            }
            t.channels8
                .push(Channel {
                    content: "RSSI1".try_into().unwrap(),
                    scale: 1.0,
                    offset: 0.0,
                    start_angle_deg_e4: r(rng) as i32,
                    step_deg_e4: r(rng) as u16,
                    values,
                })
                .unwrap();
        }
        if r(rng) & 1 == 1 {
            t.position = Some(PositionData {
                xyz: [1.5, -2.0, 0.25],
                rotation: [0.0, 0.0, f32::from_bits(r(rng) & 0x3FFF_FFFF)],
                rotation_type: r(rng) as u8,
            });
        }
        if r(rng) & 1 == 1 {
            t.device_name = Some("LMS111".try_into().unwrap());
        }
        if r(rng) & 1 == 1 {
            t.comment = Some("bench".try_into().unwrap());
        }
        if r(rng) & 1 == 1 {
            t.time = Some(TimeStamp {
                year: 2026,
                month: 11,
                day: 23,
                hour: r(rng) as u8 % 24,
                minute: 5,
                second: 59,
                microsecond: r(rng) % 1_000_000,
            });
        }
        if r(rng) & 1 == 1 {
            t.event = Some(EventData {
                kind: "FDIN".try_into().unwrap(),
                encoder_position: r(rng),
                time_us: r(rng),
                angle_deg_e4: r(rng) as i32,
            });
        }
        t
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(0x5CA7);
        let mut buf = std::vec![0u8; 16384];
        for _ in 0..2_000 {
            let t = random_telegram(&mut rng);
            let n = t.emit(&mut buf).unwrap();
            assert_eq!(ScanTelegram::parse(&buf[1..n - 1]), Ok(t));
        }
    }

    #[test]
    fn stream_of_telegrams_survives_any_split_and_garbage() {
        use super::super::ColaDecoder;
        let mut rng = seeded(0xC0);
        let mut buf = std::vec![0u8; 16384];
        for round in 0..100 {
            let mut stream = Vec::new();
            let mut expected = Vec::new();
            for _ in 0..10 {
                if round % 2 == 1 && below(&mut rng, 2) == 0 {
                    for _ in 0..below(&mut rng, 50) {
                        let b = rng.next_u32() as u8;
                        // Junk between telegrams (an ETX-less fragment is refuted by the
                        // next STX).
                        stream.push(if b == 0x02 { 0x41 } else { b });
                    }
                }
                let t = random_telegram(&mut rng);
                let n = t.emit(&mut buf).unwrap();
                stream.extend_from_slice(&buf[..n]);
                expected.push(t);
            }
            let mut dec = Box::new(ColaDecoder::<16384>::new());
            let mut got = Vec::new();
            let mut rest = &stream[..];
            while !rest.is_empty() {
                let n = 1 + below(&mut rng, rest.len().min(3000));
                let (mut chunk, tail) = rest.split_at(n);
                rest = tail;
                while let Some(p) = dec.decode(&mut chunk) {
                    assert!(is_scan_data(p));
                    got.push(ScanTelegram::parse(p).unwrap());
                }
            }
            assert_eq!(got, expected);
        }
    }

    use std::boxed::Box;
}
