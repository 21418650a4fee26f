//! The standard status packet (SIP, IDs 0x32 stopped / 0x33 moving), every field including
//! the optional trailing ones (fact sheet 1.6). All multi-byte fields little-endian.

use super::frame::{self, Frame};
use super::{EmitError, ParseError};
use crate::wire::bytes::{Overflow, Reader, Writer};

/// SIP ID when the motors are stopped.
pub const ID_STOPPED: u8 = 0x32;
/// SIP ID when the robot is moving.
pub const ID_MOVING: u8 = 0x33;
/// Sonar readings one SIP can carry (sonar numbers 0-31).
pub const MAX_SONAR: usize = 32;

/// One new sonar reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SonarReading {
    /// Sonar number, 0-31.
    pub number: u8,
    /// Range \[mm\] (× RangeConvFactor 1.0).
    pub range_mm: u16,
}

/// The optional fields after SONAR readings, in wire order. A field is sent only if every
/// field before it is; the parser fills them while bytes remain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SipExtras {
    /// Gripper state.
    pub grip_state: Option<u8>,
    /// Selected analog port.
    pub anport: Option<u8>,
    /// Analog reading, 0-255 = 0-5 V.
    pub analog: Option<u8>,
    /// User digital inputs.
    pub digin: Option<u8>,
    /// User digital outputs.
    pub digout: Option<u8>,
    /// Battery voltage \[0.1 V\].
    pub battery_dv_x10: Option<u16>,
    /// Charge state: -1 unknown, 0 not charging, 1 bulk, 2 overcharge, 3 float, 4 balance.
    pub charge_state: Option<i8>,
    /// Rotational velocity \[0.1 deg/s\].
    pub rot_vel_ddeg_s: Option<i16>,
    /// Control fault flags.
    pub fault_flags: Option<u16>,
    /// Lateral velocity \[mm/s\] (Seekur).
    pub lat_vel_mm_s: Option<i16>,
    /// Temperature \[°C\], -127/-128 = none.
    pub temperature_c: Option<i8>,
    /// State of charge \[%\].
    pub state_of_charge_pct: Option<i8>,
    /// Microcontroller time \[µs\].
    pub uc_time_us: Option<u32>,
    /// FLAGS3.
    pub flags3: Option<u32>,
}

/// A standard status packet.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct StatusPacket {
    /// ID 0x33 (moving) rather than 0x32 (stopped).
    pub moving: bool,
    /// XPOS: integrated x, 15 bits used \[mm × DistConvFactor\]; the control layer unwraps it (`control::odometry`).
    pub x_pos: u16,
    /// YPOS, as `x_pos`.
    pub y_pos: u16,
    /// THPOS: heading \[2π/4096 rad\].
    pub th_pos: i16,
    /// Left wheel velocity \[mm/s\].
    pub left_vel_mm_s: i16,
    /// Right wheel velocity \[mm/s\].
    pub right_vel_mm_s: i16,
    /// Battery \[0.1 V\].
    pub battery_dv: u8,
    /// STALL AND BUMPERS: bit 0 left stall, bits 1-7 bumper ring A, bit 8 right stall,
    /// bits 9-15 bumper ring B.
    pub stall_bumpers: u16,
    /// CONTROL: heading setpoint \[2π/4096 rad\].
    pub control: i16,
    /// FLAGS: bit 0 motors enabled, bits 1-4 sonar arrays, bit 5 e-stop, …
    pub flags: u16,
    /// COMPASS \[2 deg\].
    pub compass: u8,
    /// New sonar readings.
    pub sonar: heapless::Vec<SonarReading, MAX_SONAR>,
    /// Optional trailing fields.
    pub extras: SipExtras,
}

/// Bytes of the fixed part (XPOS through SONAR COUNT).
const FIXED_LEN: usize = 19;

impl StatusPacket {
    /// The packet ID this SIP is sent with.
    pub fn id(&self) -> u8 {
        if self.moving { ID_MOVING } else { ID_STOPPED }
    }

    /// Parses a checked frame.
    pub fn parse_frame<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        Self::parse(frame.id(), frame.payload())
    }

    /// Parses the payload of a packet with ID `id` (0x32 or 0x33). Bytes after FLAGS3 are
    /// ignored (later firmware may add fields).
    pub fn parse(id: u8, payload: &[u8]) -> Result<Self, ParseError> {
        let moving = match id {
            ID_STOPPED => false,
            ID_MOVING => true,
            got => return Err(ParseError::UnexpectedId { got }),
        };
        let mut r = Reader::new(payload);
        macro_rules! req {
            ($e:ident, $name:expr) => {{
                let offset = r.position();
                r.$e().ok_or(ParseError::Truncated {
                    field: $name,
                    offset,
                })?
            }};
        }
        let mut p = StatusPacket {
            moving,
            x_pos: req!(u16_le, "XPOS"),
            y_pos: req!(u16_le, "YPOS"),
            th_pos: req!(i16_le, "THPOS"),
            left_vel_mm_s: req!(i16_le, "L VEL"),
            right_vel_mm_s: req!(i16_le, "R VEL"),
            battery_dv: req!(u8, "BATTERY"),
            stall_bumpers: req!(u16_le, "STALL AND BUMPERS"),
            control: req!(i16_le, "CONTROL"),
            flags: req!(u16_le, "FLAGS"),
            compass: req!(u8, "COMPASS"),
            ..Default::default()
        };
        let count = req!(u8, "SONAR COUNT") as usize;
        if count > MAX_SONAR {
            return Err(ParseError::TooManySonar {
                count,
                capacity: MAX_SONAR,
            });
        }
        for _ in 0..count {
            let number = req!(u8, "SONAR NUMBER");
            let range_mm = req!(u16_le, "SONAR RANGE");
            // Capacity checked above.
            let _ = p.sonar.push(SonarReading { number, range_mm });
        }
        macro_rules! opt {
            ($e:ident, $name:expr) => {{
                if r.is_empty() {
                    None
                } else {
                    Some(req!($e, $name))
                }
            }};
        }
        let x = &mut p.extras;
        x.grip_state = opt!(u8, "GRIP_STATE");
        x.anport = opt!(u8, "ANPORT");
        x.analog = opt!(u8, "ANALOG");
        x.digin = opt!(u8, "DIGIN");
        x.digout = opt!(u8, "DIGOUT");
        x.battery_dv_x10 = opt!(u16_le, "BATTERYX10");
        x.charge_state = opt!(i8, "CHARGESTATE");
        x.rot_vel_ddeg_s = opt!(i16_le, "ROTVEL");
        x.fault_flags = opt!(u16_le, "FAULTFLAGS");
        x.lat_vel_mm_s = opt!(i16_le, "LATVEL");
        x.temperature_c = opt!(i8, "TEMPERATURE");
        x.state_of_charge_pct = opt!(i8, "STATEOFCHARGE");
        x.uc_time_us = opt!(u32_le, "uC time");
        x.flags3 = opt!(u32_le, "FLAGS3");
        Ok(p)
    }

    fn extras_len(&self) -> Result<usize, EmitError> {
        let x = &self.extras;
        let fields: [(&'static str, bool, usize); 14] = [
            ("GRIP_STATE", x.grip_state.is_some(), 1),
            ("ANPORT", x.anport.is_some(), 1),
            ("ANALOG", x.analog.is_some(), 1),
            ("DIGIN", x.digin.is_some(), 1),
            ("DIGOUT", x.digout.is_some(), 1),
            ("BATTERYX10", x.battery_dv_x10.is_some(), 2),
            ("CHARGESTATE", x.charge_state.is_some(), 1),
            ("ROTVEL", x.rot_vel_ddeg_s.is_some(), 2),
            ("FAULTFLAGS", x.fault_flags.is_some(), 2),
            ("LATVEL", x.lat_vel_mm_s.is_some(), 2),
            ("TEMPERATURE", x.temperature_c.is_some(), 1),
            ("STATEOFCHARGE", x.state_of_charge_pct.is_some(), 1),
            ("uC time", x.uc_time_us.is_some(), 4),
            ("FLAGS3", x.flags3.is_some(), 4),
        ];
        let mut len = 0;
        let mut ended = false;
        for (field, present, n) in fields {
            if present {
                if ended {
                    return Err(EmitError::FieldAfterAbsent { field });
                }
                len += n;
            } else {
                ended = true;
            }
        }
        Ok(len)
    }

    fn payload_len(&self) -> Result<usize, EmitError> {
        Ok(FIXED_LEN + 3 * self.sonar.len() + self.extras_len()?)
    }

    /// Encoded length \[bytes\].
    pub fn buffer_len(&self) -> Result<usize, EmitError> {
        Ok(frame::frame_len(self.payload_len()?))
    }

    /// Encodes the SIP as a complete frame into `buf`; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        let len = self.payload_len()?;
        frame::emit_with(buf, self.id(), len, |w| self.write_payload(w))
    }

    fn write_payload(&self, w: &mut Writer<'_>) -> Result<(), Overflow> {
        w.u16_le(self.x_pos)?;
        w.u16_le(self.y_pos)?;
        w.u16_le(self.th_pos as u16)?;
        w.u16_le(self.left_vel_mm_s as u16)?;
        w.u16_le(self.right_vel_mm_s as u16)?;
        w.u8(self.battery_dv)?;
        w.u16_le(self.stall_bumpers)?;
        w.u16_le(self.control as u16)?;
        w.u16_le(self.flags)?;
        w.u8(self.compass)?;
        w.u8(self.sonar.len() as u8)?;
        for s in &self.sonar {
            w.u8(s.number)?;
            w.u16_le(s.range_mm)?;
        }
        let x = &self.extras;
        macro_rules! opt {
            ($v:expr, $f:ident) => {
                match $v {
                    Some(v) => w.$f(v)?,
                    None => return Ok(()),
                }
            };
        }
        opt!(x.grip_state, u8);
        opt!(x.anport, u8);
        opt!(x.analog, u8);
        opt!(x.digin, u8);
        opt!(x.digout, u8);
        opt!(x.battery_dv_x10, u16_le);
        opt!(x.charge_state.map(|v| v as u8), u8);
        opt!(x.rot_vel_ddeg_s.map(|v| v as u16), u16_le);
        opt!(x.fault_flags, u16_le);
        opt!(x.lat_vel_mm_s.map(|v| v as u16), u16_le);
        opt!(x.temperature_c.map(|v| v as u8), u8);
        opt!(x.state_of_charge_pct.map(|v| v as u8), u8);
        opt!(x.uc_time_us, u32_le);
        opt!(x.flags3, u32_le);
        Ok(())
    }

    /// Whether the motors are enabled (FLAGS bit 0).
    pub fn motors_enabled(&self) -> bool {
        self.flags & 1 != 0
    }

    /// Whether the e-stop is engaged (FLAGS bit 5).
    pub fn estop(&self) -> bool {
        self.flags & (1 << 5) != 0
    }

    /// Whether either wheel reports a stall (STALL AND BUMPERS bits 0 and 8).
    pub fn stalled(&self) -> bool {
        self.stall_bumpers & 0x0101 != 0
    }

    /// Bumper bits of ring A (low byte, bits 1-7), ARIA's rear bumpers.
    pub fn bumpers_a(&self) -> u8 {
        ((self.stall_bumpers & 0xFE) >> 1) as u8
    }

    /// Bumper bits of ring B (high byte, bits 9-15), ARIA's front bumpers.
    pub fn bumpers_b(&self) -> u8 {
        ((self.stall_bumpers & 0xFE00) >> 9) as u8
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::random::{ProjectRng, below, seeded};
    use rand_core::Rng;

    /// A SIP as AMRISim sends it: 16 sonar readings, through STATEOFCHARGE, FLAGS 0x001E,
    /// DIGIN/DIGOUT 0xFF, BATTERYX10 130, TEMPERATURE -127 (fact sheet 1.6): byte count 86.
    pub(crate) fn amrisim_like() -> StatusPacket {
        let mut p = StatusPacket {
            x_pos: 1000,
            y_pos: 0x7FF0,
            th_pos: -1024,
            battery_dv: 130,
            flags: 0x001E,
            ..Default::default()
        };
        for i in 0..16 {
            p.sonar
                .push(SonarReading {
                    number: i,
                    range_mm: 5000,
                })
                .unwrap();
        }
        p.extras = SipExtras {
            grip_state: Some(0),
            anport: Some(0),
            analog: Some(0),
            digin: Some(0xFF),
            digout: Some(0xFF),
            battery_dv_x10: Some(130),
            charge_state: Some(0),
            rot_vel_ddeg_s: Some(0),
            fault_flags: Some(0),
            lat_vel_mm_s: Some(0),
            temperature_c: Some(-127),
            state_of_charge_pct: Some(0),
            uc_time_us: None,
            flags3: None,
        };
        p
    }

    #[test]
    fn amrisim_sip_has_byte_count_86() {
        let p = amrisim_like();
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        let n = p.emit(&mut buf).unwrap();
        assert_eq!(buf[2], 86);
        assert_eq!(n, 89);
        let f = Frame::new_checked(&buf[..n]).unwrap();
        assert_eq!(f.id(), ID_STOPPED);
        // XPOS 1000 little-endian first.
        assert_eq!(&buf[4..6], &[0xE8, 0x03]);
        assert_eq!(StatusPacket::parse_frame(&f).unwrap(), p);
    }

    #[test]
    fn p2os_style_sip_stops_after_digout() {
        let mut p = amrisim_like();
        p.extras.battery_dv_x10 = None;
        p.extras.charge_state = None;
        p.extras.rot_vel_ddeg_s = None;
        p.extras.fault_flags = None;
        p.extras.lat_vel_mm_s = None;
        p.extras.temperature_c = None;
        p.extras.state_of_charge_pct = None;
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        let n = p.emit(&mut buf).unwrap();
        let f = Frame::new_checked(&buf[..n]).unwrap();
        assert_eq!(StatusPacket::parse_frame(&f).unwrap(), p);
    }

    #[test]
    fn gaps_and_truncation_are_errors() {
        let mut p = StatusPacket::default();
        p.extras.flags3 = Some(1);
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        assert_eq!(
            p.emit(&mut buf),
            Err(EmitError::FieldAfterAbsent { field: "FLAGS3" })
        );
        assert_eq!(
            StatusPacket::parse(0x32, &[0u8; 10]),
            Err(ParseError::Truncated {
                field: "BATTERY",
                offset: 10
            })
        );
        // A half BATTERYX10 field.
        let mut payload = [0u8; FIXED_LEN + 6];
        payload[18] = 0;
        assert_eq!(
            StatusPacket::parse(0x32, &payload),
            Err(ParseError::Truncated {
                field: "BATTERYX10",
                offset: FIXED_LEN + 5
            })
        );
        assert_eq!(
            StatusPacket::parse(0x20, &payload),
            Err(ParseError::UnexpectedId { got: 0x20 })
        );
    }

    /// A random SIP with a random number of trailing fields.
    pub(crate) fn random_sip(rng: &mut ProjectRng) -> StatusPacket {
        let mut p = StatusPacket {
            moving: rng.next_u32() & 1 == 1,
            x_pos: rng.next_u32() as u16 & 0x7FFF,
            y_pos: rng.next_u32() as u16 & 0x7FFF,
            th_pos: rng.next_u32() as i16,
            left_vel_mm_s: rng.next_u32() as i16,
            right_vel_mm_s: rng.next_u32() as i16,
            battery_dv: rng.next_u32() as u8,
            stall_bumpers: rng.next_u32() as u16,
            control: rng.next_u32() as i16,
            flags: rng.next_u32() as u16,
            compass: rng.next_u32() as u8,
            ..Default::default()
        };
        for _ in 0..below(rng, MAX_SONAR + 1) {
            p.sonar
                .push(SonarReading {
                    number: below(rng, 32) as u8,
                    range_mm: rng.next_u32() as u16,
                })
                .unwrap();
        }
        let k = below(rng, 15);
        let mut r = || rng.next_u32();
        let x = &mut p.extras;
        let on = |i: usize| i < k;
        x.grip_state = on(0).then(|| r() as u8);
        x.anport = on(1).then(|| r() as u8);
        x.analog = on(2).then(|| r() as u8);
        x.digin = on(3).then(|| r() as u8);
        x.digout = on(4).then(|| r() as u8);
        x.battery_dv_x10 = on(5).then(|| r() as u16);
        x.charge_state = on(6).then(|| r() as i8);
        x.rot_vel_ddeg_s = on(7).then(|| r() as i16);
        x.fault_flags = on(8).then(|| r() as u16);
        x.lat_vel_mm_s = on(9).then(|| r() as i16);
        x.temperature_c = on(10).then(|| r() as i8);
        x.state_of_charge_pct = on(11).then(|| r() as i8);
        x.uc_time_us = on(12).then(&mut r);
        x.flags3 = on(13).then(&mut r);
        p
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(0x515);
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        for _ in 0..20_000 {
            let p = random_sip(&mut rng);
            let n = p.emit(&mut buf).unwrap();
            assert_eq!(n, p.buffer_len().unwrap());
            let f = Frame::new_checked(&buf[..n]).unwrap();
            assert_eq!(StatusPacket::parse_frame(&f).unwrap(), p);
        }
    }
}
