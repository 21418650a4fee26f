//! An emulated SICK LMS200 on a serial line, sans-IO: bytes and time in, bytes out.
//!
//! Behaviour follows the protocol fact sheet, section 3 (the telegrams ARIA's LMS2xx client
//! sends): every host telegram with a good CRC is acknowledged with ACK (0x06), then answered;
//! a telegram with a bad CRC or an unknown command gets NACK (0x15). Mode changes (setup with
//! the password, continuous output, stop, baud rates) answer 0xA0 with result 0 (a wrong
//! password: result 1); a variant (0x3B) of 100° or 180° at 1°, 0.5° or 0.25° is accepted and
//! answered 0xBB; the configuration telegram (0x77) is answered 0xF7 (first byte 1 =
//! accepted, then the configuration as set, then the status byte); reset (0x10) is answered
//! with the power-on telegram 0x90. In continuous mode, measured values (0xB0) stream at
//! [`SCAN_RATE_HZ`] in the configured unit and measuring mode: by default millimetres with 13
//! distance bits (nothing within 8.191 m reads 0). Baud-rate changes are accepted and ignored
//! (a pty has no baud rate).
//!
//! The configuration's layout is ARIA's LMS2xx client's (fact sheet section 3, AC:L2): blanking
//! (2 bytes), peak/stop threshold (2), fog correction (1), measuring mode (1: 5, 3 or 1 = one,
//! two or three reflector bits above 15, 14 or 13 distance bits), unit (1: 0 cm, 1 mm, 2 10 cm),
//! then the contour and field settings, which the emulator keeps and echoes but does not use.

use papillon::sensor::{LaserConfig, Scan};
use papillon::units::m_to_mm;
use papillon::wire::lms200::{
    ACK, DEFAULT_PASSWORD, Event, LASER_REPLY_ADDRESS, Lms200Decoder, MAX_TELEGRAM_LEN,
    MeasuredValues, Mode, NACK, RangeUnit, Request, Response, Variant, cmd, emit_telegram,
};

/// Largest range in millimetre mode (13 distance bits) \[m\].
pub const MAX_RANGE_M: f32 = 8.191;
/// Scans per second streamed in continuous mode (what a 38400-baud line carries at 1°).
pub const SCAN_RATE_HZ: f64 = 10.0;
/// Status byte of the laser's replies (no error).
const STATUS_OK: u8 = 0x10;
/// Bytes of the configuration telegram's data the emulator reads (up to the unit byte).
const CONFIG_MIN_LEN: usize = 7;
/// Offset of the measuring mode in the configuration data.
const CONFIG_MODE: usize = 5;
/// Offset of the unit in the configuration data.
const CONFIG_UNIT: usize = 6;
/// Longest range of an LMS200 in any unit \[m\].
const LMS200_RANGE_LIMIT_M: f32 = 80.0;

/// Distance bits of the measured values in a measuring mode (ARIA's codes), if known.
fn distance_bits(mode: u8) -> Option<u32> {
    match mode {
        5 => Some(15),
        3 => Some(14),
        1 => Some(13),
        _ => None,
    }
}

/// The beam layout of an LMS200 with `variant`, noise-free, at the robot's centre.
pub fn laser_config(variant: Variant) -> LaserConfig {
    LaserConfig {
        beam_count: variant.beam_count() as u16,
        first_angle_rad: papillon::sensor::telegram::lms200_first_angle_rad(variant),
        step_rad: papillon::sensor::telegram::lms200_step_rad(variant),
        max_range_m: MAX_RANGE_M,
        min_range_m: 0.0,
        noise_fraction: 0.0,
        mount: papillon::geometry::Pose2::default(),
        rate_hz: SCAN_RATE_HZ as f32,
    }
}

/// Whether the LMS200 supports `variant`.
fn supported(variant: Variant) -> bool {
    matches!(variant.angle_deg, 100 | 180)
        && matches!(variant.resolution_cdeg, 100 | 50 | 25)
        && variant.beam_count() <= papillon::wire::lms200::MAX_VALUES
}

/// The emulated laser's session state.
#[derive(Debug)]
pub struct Lms200Emulator {
    decoder: Box<Lms200Decoder>,
    variant: Variant,
    continuous: bool,
    next_scan_s: f64,
    requests: u64,
    unit: RangeUnit,
    distance_bits: u32,
    /// The last configuration accepted (0x77 data), echoed in 0xF7.
    configuration: Option<papillon::wire::lms200::Data>,
}

impl Default for Lms200Emulator {
    fn default() -> Self {
        Self::new()
    }
}

impl Lms200Emulator {
    /// A laser at 180° and 1°, in request mode (not streaming).
    pub fn new() -> Self {
        Self {
            decoder: Box::new(Lms200Decoder::new()),
            variant: Variant::DEG180_RES1,
            continuous: false,
            next_scan_s: 0.0,
            requests: 0,
            unit: RangeUnit::Mm,
            distance_bits: 13,
            configuration: None,
        }
    }

    /// The unit of the measured values.
    pub fn unit(&self) -> RangeUnit {
        self.unit
    }

    /// Distance bits of the measured values (13 to 15).
    pub fn distance_bits(&self) -> u32 {
        self.distance_bits
    }

    /// The longest range the measured values can carry \[m\].
    pub fn max_range_m(&self) -> f32 {
        let mask = (1u32 << self.distance_bits) - 1;
        (mask as f32 * self.unit.mm() as f32 / 1000.0).min(LMS200_RANGE_LIMIT_M)
    }

    /// The current angular range and resolution.
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// Whether measured values stream.
    pub fn continuous(&self) -> bool {
        self.continuous
    }

    /// Telegrams understood so far.
    pub fn requests(&self) -> u64 {
        self.requests
    }

    /// Feeds bytes from the host at `now_s` \[s\]; ACK/NACK and replies are appended to `out`.
    pub fn receive(&mut self, now_s: f64, bytes: &[u8], out: &mut Vec<u8>) {
        let mut input = bytes;
        loop {
            let bad_before = self.decoder.stats().bad_crc;
            let event = self.decoder.decode(&mut input).map(|e| match e {
                Event::Telegram(t) => Some(Request::parse(&t)),
                // The host does not acknowledge; stray ACK/NACK bytes are ignored.
                Event::Ack | Event::Nack => None,
            });
            if self.decoder.stats().bad_crc != bad_before {
                out.push(NACK);
            }
            let Some(event) = event else {
                return;
            };
            let Some(request) = event else {
                continue;
            };
            let Ok(request) = request else {
                out.push(NACK);
                continue;
            };
            let reply = match request {
                Request::Reset => {
                    self.continuous = false;
                    Response::Other {
                        command: cmd::POWER_ON,
                        data: papillon::wire::lms200::Data::from_slice(b"LMS200;30106")
                            .unwrap_or_default(),
                    }
                }
                Request::SetMode(mode) => {
                    let result = match mode {
                        Mode::Setup { password } => u8::from(password != DEFAULT_PASSWORD),
                        Mode::ContinuousOutput => {
                            self.continuous = true;
                            self.next_scan_s = now_s + 1.0 / SCAN_RATE_HZ;
                            0
                        }
                        Mode::Stop => {
                            self.continuous = false;
                            0
                        }
                        _ => 0,
                    };
                    Response::ModeReply {
                        result,
                        status: STATUS_OK,
                    }
                }
                Request::SetVariant(v) => {
                    let accepted = supported(v);
                    if accepted {
                        self.variant = v;
                    }
                    Response::VariantReply {
                        accepted,
                        variant: self.variant,
                        status: STATUS_OK,
                    }
                }
                Request::Other {
                    command: cmd::CONFIG,
                    data,
                } if data.len() >= CONFIG_MIN_LEN => {
                    let unit = match data[CONFIG_UNIT] {
                        0 => Some(RangeUnit::Cm),
                        1 => Some(RangeUnit::Mm),
                        2 => Some(RangeUnit::Dm),
                        _ => None,
                    };
                    let bits = distance_bits(data[CONFIG_MODE]);
                    let accepted = unit.is_some() && bits.is_some();
                    if let (Some(unit), Some(bits)) = (unit, bits) {
                        self.unit = unit;
                        self.distance_bits = bits;
                        self.configuration = Some(data.clone());
                    }
                    let mut reply = papillon::wire::lms200::Data::new();
                    let _ = reply.push(u8::from(accepted));
                    let echoed = self.configuration.as_ref().unwrap_or(&data);
                    let _ = reply.extend_from_slice(echoed);
                    let _ = reply.push(STATUS_OK);
                    Response::Other {
                        command: cmd::CONFIG_REPLY,
                        data: reply,
                    }
                }
                _ => {
                    out.push(NACK);
                    continue;
                }
            };
            self.requests += 1;
            out.push(ACK);
            emit(out, &reply);
        }
    }

    /// If a streamed scan is due at `now_s`, takes it with `scan` and appends its telegram.
    pub fn tick(&mut self, now_s: f64, scan: impl FnOnce(LaserConfig) -> Scan, out: &mut Vec<u8>) {
        if !self.continuous || now_s + 1e-9 < self.next_scan_s {
            return;
        }
        let period = 1.0 / SCAN_RATE_HZ;
        self.next_scan_s += period;
        if self.next_scan_s <= now_s {
            self.next_scan_s = now_s + period;
        }
        let mut config = laser_config(self.variant);
        config.max_range_m = self.max_range_m();
        let s = scan(config);
        let mask = ((1u32 << self.distance_bits) - 1) as u16;
        let unit_mm = self.unit.mm() as f32;
        let mut values = MeasuredValues {
            unit: self.unit,
            flags: 0,
            values: Default::default(),
            status: STATUS_OK,
        };
        for beam in s.beams() {
            let v = beam.range_m.map_or(0, |r| {
                (m_to_mm(r) / unit_mm).round().clamp(0.0, f32::from(mask)) as u16
            });
            // The variant was checked against MAX_VALUES, so this cannot overflow.
            let _ = values.values.push(v & mask);
        }
        emit(out, &Response::MeasuredValues(values));
    }
}

/// Appends the telegram of `response` to `out`.
fn emit(out: &mut Vec<u8>, response: &Response) {
    let mut buf = [0u8; MAX_TELEGRAM_LEN];
    match response.emit(&mut buf) {
        Ok(n) => out.extend_from_slice(&buf[..n]),
        // Every response built here fits a telegram; an empty one keeps the line alive.
        Err(_) => {
            if let Ok(n) = emit_telegram(&mut buf, LASER_REPLY_ADDRESS, cmd::POWER_ON, &[]) {
                out.extend_from_slice(&buf[..n]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use papillon::wire::lms200::{HOST_ADDRESS, Telegram};

    fn request(req: &Request) -> Vec<u8> {
        let mut buf = [0u8; MAX_TELEGRAM_LEN];
        let n = req.emit(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    /// ACK/NACK bytes and responses in `bytes`, in order.
    fn replies(bytes: &[u8]) -> Vec<Result<Response, u8>> {
        let mut dec = Lms200Decoder::new();
        let mut input = bytes;
        let mut out = Vec::new();
        while let Some(e) = dec.decode(&mut input) {
            out.push(match e {
                Event::Ack => Err(ACK),
                Event::Nack => Err(NACK),
                Event::Telegram(t) => {
                    assert_eq!(t.address(), LASER_REPLY_ADDRESS);
                    Ok(Response::parse(&t).unwrap())
                }
            });
        }
        out
    }

    #[test]
    fn aria_start_sequence_then_streaming() {
        let mut emu = Lms200Emulator::new();
        let mut out = Vec::new();
        emu.receive(
            0.0,
            &request(&Request::SetMode(Mode::Setup {
                password: DEFAULT_PASSWORD,
            })),
            &mut out,
        );
        emu.receive(
            0.0,
            &request(&Request::SetVariant(Variant::DEG180_RES05)),
            &mut out,
        );
        emu.receive(0.0, &request(&Request::SetMode(Mode::Baud38400)), &mut out);
        emu.receive(
            0.0,
            &request(&Request::SetMode(Mode::ContinuousOutput)),
            &mut out,
        );
        let got = replies(&out);
        assert_eq!(got.len(), 8, "{got:?}");
        assert_eq!(got[0], Err(ACK));
        assert!(matches!(got[1], Ok(Response::ModeReply { result: 0, .. })));
        assert!(matches!(
            got[3],
            Ok(Response::VariantReply { accepted: true, variant, .. }) if variant == Variant::DEG180_RES05
        ));
        assert!(emu.continuous());
        // Nothing before one period; then one scan per period, 361 values in mm.
        let mut out = Vec::new();
        let scan = |c: LaserConfig| {
            let mut s = Scan::new();
            for i in 0..c.beam_count as usize {
                s.push(papillon::sensor::Beam {
                    angle_rad: c.beam_angle(i),
                    range_m: (i % 2 == 0).then_some(1.5),
                })
                .unwrap();
            }
            s
        };
        emu.tick(0.05, scan, &mut out);
        assert!(out.is_empty());
        for k in 1..=5 {
            emu.tick(k as f64 * 0.1, scan, &mut out);
        }
        let scans = replies(&out);
        assert_eq!(scans.len(), 5);
        let Ok(Response::MeasuredValues(m)) = &scans[0] else {
            panic!("{:?}", scans[0]);
        };
        assert_eq!(m.values.len(), 361);
        assert_eq!((m.values[0], m.values[1]), (1500, 0));
        // Stop ends the stream.
        let mut out = Vec::new();
        emu.receive(0.6, &request(&Request::SetMode(Mode::Stop)), &mut out);
        emu.tick(1.0, scan, &mut out);
        assert_eq!(replies(&out).len(), 2, "ACK and mode reply only");
    }

    #[test]
    fn bad_crc_wrong_password_and_unsupported_variant_are_refused() {
        let mut emu = Lms200Emulator::new();
        let mut bytes = request(&Request::SetMode(Mode::ContinuousOutput));
        let last = bytes.len() - 1;
        bytes[last] ^= 0xFF;
        let mut out = Vec::new();
        emu.receive(0.0, &bytes, &mut out);
        assert_eq!(out, vec![NACK]);
        assert!(!emu.continuous());

        let mut out = Vec::new();
        emu.receive(
            0.0,
            &request(&Request::SetMode(Mode::Setup {
                password: *b"WRONGPWD",
            })),
            &mut out,
        );
        emu.receive(
            0.0,
            &request(&Request::SetVariant(Variant {
                angle_deg: 90,
                resolution_cdeg: 100,
            })),
            &mut out,
        );
        let got = replies(&out);
        assert!(matches!(got[1], Ok(Response::ModeReply { result: 1, .. })));
        assert!(matches!(
            got[3],
            Ok(Response::VariantReply { accepted: false, variant, .. }) if variant == Variant::DEG180_RES1
        ));
        // An unknown command gets NACK.
        let mut buf = [0u8; 16];
        let n = emit_telegram(&mut buf, HOST_ADDRESS, 0x31, &[]).unwrap();
        let mut out = Vec::new();
        emu.receive(0.0, &buf[..n], &mut out);
        assert_eq!(out, vec![NACK]);
        let _ = Telegram::new_checked(&buf[..n]).unwrap();
    }
}
