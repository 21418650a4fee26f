//! Client commands (robot PC → microcontroller), both directions.
//!
//! A command is a frame whose ID is the command number, optionally followed by one argument:
//! `3B lo hi` (positive integer), `1B lo hi` (negative integer, magnitude follows) or
//! `2B len chars…` (string) (fact sheet 1.1 and 1.5).
//!
//! SYNC0, SYNC1 and SYNC2 are byte-identical to PULSE, OPEN and CLOSE without argument; they
//! decode as [`Command::Pulse`], [`Command::Open`]`(None)` and [`Command::Close`]`(None)` (see
//! [`Command::SYNC0`] and [`Command::sync_number`]). A server tells them apart by its connection
//! state.

use super::frame::{self, Frame};
use super::{EmitError, ParseError};
use crate::wire::bytes::{Overflow, Reader, Writer};

/// Argument type byte: positive integer.
pub const ARG_INT: u8 = 0x3B;
/// Argument type byte: negative integer (magnitude follows).
pub const ARG_NEG_INT: u8 = 0x1B;
/// Argument type byte: counted string.
pub const ARG_STR: u8 = 0x2B;
/// Longest string argument \[bytes\] (ARIA refuses longer ones).
pub const MAX_STR_ARG: usize = 199;
/// Largest encoded command \[bytes\].
pub const MAX_COMMAND_LEN: usize = frame::frame_len(2 + MAX_STR_ARG);

/// Bytes of a string argument (SAY tunes are binary, so these are bytes, not text).
pub type StrArg = heapless::Vec<u8, MAX_STR_ARG>;

/// A command argument.
// Stored inline: the core has no allocator, and a string argument is at most 199 bytes.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum Arg {
    /// No argument.
    #[default]
    None,
    /// An integer, -65535..=65535 on the wire.
    Int(i32),
    /// A counted string.
    Str(StrArg),
}

#[derive(Clone, Copy)]
enum ArgRef<'a> {
    None,
    Int(i32),
    Str(&'a [u8]),
}

impl ArgRef<'_> {
    fn wire_len(&self) -> usize {
        match self {
            ArgRef::None => 0,
            ArgRef::Int(_) => 3,
            ArgRef::Str(s) => 2 + s.len(),
        }
    }

    fn write(&self, w: &mut Writer<'_>) -> Result<(), Overflow> {
        match *self {
            ArgRef::None => Ok(()),
            ArgRef::Int(v) => {
                w.u8(if v < 0 { ARG_NEG_INT } else { ARG_INT })?;
                w.u16_le(v.unsigned_abs() as u16)
            }
            ArgRef::Str(s) => {
                w.u8(ARG_STR)?;
                w.u8(s.len() as u8)?;
                w.bytes(s)
            }
        }
    }
}

/// Command numbers (fact sheet 1.5).
pub mod num {
    #![allow(missing_docs)]
    pub const PULSE: u8 = 0;
    pub const OPEN: u8 = 1;
    pub const CLOSE: u8 = 2;
    pub const POLLING: u8 = 3;
    pub const ENABLE: u8 = 4;
    pub const SETA: u8 = 5;
    pub const SETV: u8 = 6;
    pub const SETO: u8 = 7;
    pub const MOVE: u8 = 8;
    pub const ROTATE: u8 = 9;
    pub const SETRV: u8 = 10;
    pub const VEL: u8 = 11;
    pub const HEAD: u8 = 12;
    pub const DHEAD: u8 = 13;
    pub const SAY: u8 = 15;
    pub const JOYINFO: u8 = 17;
    pub const CONFIG: u8 = 18;
    pub const ENCODER: u8 = 19;
    pub const SETRVDIR: u8 = 20;
    pub const RVEL: u8 = 21;
    pub const DCHEAD: u8 = 22;
    pub const SETRA: u8 = 23;
    pub const SONAR: u8 = 28;
    pub const STOP: u8 = 29;
    pub const DIGOUT: u8 = 30;
    pub const VEL2: u8 = 32;
    pub const GRIPPER: u8 = 33;
    pub const ADSEL: u8 = 35;
    pub const IOREQUEST: u8 = 40;
    pub const BUMPSTALL: u8 = 44;
    pub const JOYDRIVE: u8 = 47;
    pub const HOSTBAUD: u8 = 50;
    pub const AUX1BAUD: u8 = 51;
    pub const AUX2BAUD: u8 = 52;
    pub const E_STOP: u8 = 55;
    pub const GYRO: u8 = 58;
    pub const BATTERYINFO: u8 = 62;
    pub const REVCOUNT: u8 = 88;
    pub const DRIFTFACTOR: u8 = 89;
    pub const TICKSMM: u8 = 93;
    pub const BATTEST: u8 = 250;
    pub const RESET: u8 = 253;
}

/// A client command. Velocities in mm/s or deg/s, accelerations in mm/s² or deg/s², angles in
/// degrees, as the firmware takes them.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Command {
    /// 0, no argument: keep-alive (also SYNC0).
    Pulse,
    /// 1: start the status packet stream; `None` is also SYNC1, ARIA sends `Some(1)`.
    Open(Option<i16>),
    /// 2: close the session; `None` is also SYNC2, ARIA sends `Some(1)`.
    Close(Option<i16>),
    /// 3: sonar polling sequence.
    Polling(StrArg),
    /// 4: enable (true) or disable the motors.
    Enable(bool),
    /// 5: translational acceleration (+) or deceleration (−) \[mm/s²\].
    SetA(i16),
    /// 6: maximum translational velocity \[mm/s\].
    SetV(i16),
    /// 7: reset odometry to (0, 0, 0).
    SetO,
    /// 8: relative translation \[mm\].
    Move(i16),
    /// 9: rotate at \[deg/s\] (as RVEL).
    Rotate(i16),
    /// 10: maximum rotational velocity \[deg/s\].
    SetRv(i16),
    /// 11: translational velocity \[mm/s\].
    Vel(i16),
    /// 12: absolute heading \[deg\].
    Head(i16),
    /// 13: relative heading change \[deg\].
    DHead(i16),
    /// 15: buzzer tune.
    Say(StrArg),
    /// 17: joystick packets (0 stop, 1 once, 2 continuous).
    JoyInfo(i16),
    /// 18: request a CONFIG packet (ARIA sends `Some(1)`).
    Config(Option<i16>),
    /// 19: ENCODER packets (0 stop, 1 once, ≥2 continuous).
    Encoder(i16),
    /// 20: rotational velocity maximum per direction.
    SetRvDir(i16),
    /// 21: rotational velocity \[deg/s\], counter-clockwise positive.
    RVel(i16),
    /// 22: relative heading setpoint \[deg\].
    DcHead(i16),
    /// 23: rotational acceleration (+) or deceleration (−) \[deg/s²\].
    SetRa(i16),
    /// 28: sonar on (true) or off.
    Sonar(bool),
    /// 29: stop.
    Stop,
    /// 30: digital outputs.
    DigOut(i16),
    /// 32: independent wheel velocities in Vel2Divisor units (20 mm/s on a P3-DX).
    Vel2 {
        /// Left wheel (high byte).
        left: i8,
        /// Right wheel (low byte).
        right: i8,
    },
    /// 33: gripper command.
    Gripper(i16),
    /// 35: analog port selection.
    AdSel(i16),
    /// 40: IO packet requests.
    IoRequest(i16),
    /// 44: stall on bumper contact (0 off, 1 front, 2 rear, 3 both).
    BumpStall(i16),
    /// 47: drive from the robot's joystick (true) or not.
    JoyDrive(bool),
    /// 50: host port baud code (0 = 9600, 1 = 19200, 2 = 38400, 3 = 57600, 4 = 115200).
    HostBaud(i16),
    /// 51: AUX1 port baud code.
    Aux1Baud(i16),
    /// 52: AUX2 port baud code.
    Aux2Baud(i16),
    /// 55: emergency stop.
    EStop,
    /// 58: gyro packets.
    Gyro(i16),
    /// 62: battery packets (0, 1, 2).
    BatteryInfo(i16),
    /// 88: working differential encoder count.
    RevCount(i16),
    /// 89: working drift factor.
    DriftFactor(i16),
    /// 93: working encoder ticks per mm.
    TicksMm(i16),
    /// 250: fake battery voltage \[0.1 V\], 0 = real.
    BatTest(i16),
    /// 253: power-on-like reset.
    Reset,
    /// Any other command number with its raw argument.
    Other {
        /// The command number.
        number: u8,
        /// The argument.
        arg: Arg,
    },
}

impl Command {
    /// SYNC0 (same bytes as PULSE).
    pub const SYNC0: Command = Command::Pulse;
    /// SYNC1 (same bytes as OPEN without argument).
    pub const SYNC1: Command = Command::Open(None);
    /// SYNC2 (same bytes as CLOSE without argument).
    pub const SYNC2: Command = Command::Close(None);

    /// 0, 1 or 2 if the command is a bare (argument-less) 0/1/2 packet, i.e. a SYNCn.
    pub fn sync_number(&self) -> Option<u8> {
        match self {
            Command::Pulse => Some(0),
            Command::Open(None) => Some(1),
            Command::Close(None) => Some(2),
            _ => None,
        }
    }

    /// The command number.
    pub fn number(&self) -> u8 {
        use num::*;
        match self {
            Command::Pulse => PULSE,
            Command::Open(_) => OPEN,
            Command::Close(_) => CLOSE,
            Command::Polling(_) => POLLING,
            Command::Enable(_) => ENABLE,
            Command::SetA(_) => SETA,
            Command::SetV(_) => SETV,
            Command::SetO => SETO,
            Command::Move(_) => MOVE,
            Command::Rotate(_) => ROTATE,
            Command::SetRv(_) => SETRV,
            Command::Vel(_) => VEL,
            Command::Head(_) => HEAD,
            Command::DHead(_) => DHEAD,
            Command::Say(_) => SAY,
            Command::JoyInfo(_) => JOYINFO,
            Command::Config(_) => CONFIG,
            Command::Encoder(_) => ENCODER,
            Command::SetRvDir(_) => SETRVDIR,
            Command::RVel(_) => RVEL,
            Command::DcHead(_) => DCHEAD,
            Command::SetRa(_) => SETRA,
            Command::Sonar(_) => SONAR,
            Command::Stop => STOP,
            Command::DigOut(_) => DIGOUT,
            Command::Vel2 { .. } => VEL2,
            Command::Gripper(_) => GRIPPER,
            Command::AdSel(_) => ADSEL,
            Command::IoRequest(_) => IOREQUEST,
            Command::BumpStall(_) => BUMPSTALL,
            Command::JoyDrive(_) => JOYDRIVE,
            Command::HostBaud(_) => HOSTBAUD,
            Command::Aux1Baud(_) => AUX1BAUD,
            Command::Aux2Baud(_) => AUX2BAUD,
            Command::EStop => E_STOP,
            Command::Gyro(_) => GYRO,
            Command::BatteryInfo(_) => BATTERYINFO,
            Command::RevCount(_) => REVCOUNT,
            Command::DriftFactor(_) => DRIFTFACTOR,
            Command::TicksMm(_) => TICKSMM,
            Command::BatTest(_) => BATTEST,
            Command::Reset => RESET,
            Command::Other { number, .. } => *number,
        }
    }

    fn arg_ref(&self) -> ArgRef<'_> {
        match self {
            Command::Pulse | Command::SetO | Command::Stop | Command::EStop | Command::Reset => {
                ArgRef::None
            }
            Command::Open(a) | Command::Close(a) | Command::Config(a) => {
                a.map_or(ArgRef::None, |v| ArgRef::Int(v as i32))
            }
            Command::Polling(s) | Command::Say(s) => ArgRef::Str(s),
            Command::Enable(b) | Command::Sonar(b) | Command::JoyDrive(b) => ArgRef::Int(*b as i32),
            Command::SetA(v)
            | Command::SetV(v)
            | Command::Move(v)
            | Command::Rotate(v)
            | Command::SetRv(v)
            | Command::Vel(v)
            | Command::Head(v)
            | Command::DHead(v)
            | Command::JoyInfo(v)
            | Command::Encoder(v)
            | Command::SetRvDir(v)
            | Command::RVel(v)
            | Command::DcHead(v)
            | Command::SetRa(v)
            | Command::DigOut(v)
            | Command::Gripper(v)
            | Command::AdSel(v)
            | Command::IoRequest(v)
            | Command::BumpStall(v)
            | Command::HostBaud(v)
            | Command::Aux1Baud(v)
            | Command::Aux2Baud(v)
            | Command::Gyro(v)
            | Command::BatteryInfo(v)
            | Command::RevCount(v)
            | Command::DriftFactor(v)
            | Command::TicksMm(v)
            | Command::BatTest(v) => ArgRef::Int(*v as i32),
            Command::Vel2 { left, right } => {
                ArgRef::Int((((*left as i16) << 8) | (*right as u8 as i16)) as i32)
            }
            Command::Other { arg, .. } => match arg {
                Arg::None => ArgRef::None,
                Arg::Int(v) => ArgRef::Int(*v),
                Arg::Str(s) => ArgRef::Str(s),
            },
        }
    }

    /// Encoded length \[bytes\].
    pub fn buffer_len(&self) -> usize {
        frame::frame_len(self.arg_ref().wire_len())
    }

    /// Encodes the command as a complete frame into `buf`; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        let arg = self.arg_ref();
        if let ArgRef::Int(v) = arg
            && !(-65535..=65535).contains(&v)
        {
            return Err(EmitError::ArgOutOfRange { value: v });
        }
        frame::emit_with(buf, self.number(), arg.wire_len(), |w| arg.write(w))
    }

    /// Decodes a checked frame.
    pub fn parse<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        Self::parse_parts(frame.id(), frame.payload())
    }

    /// Decodes a command from its number and the bytes after it (without checksum).
    pub fn parse_parts(number: u8, payload: &[u8]) -> Result<Self, ParseError> {
        let arg = parse_arg(payload)?;
        use num::*;
        let int = |expected: &'static str| -> Result<i16, ParseError> {
            match &arg {
                Arg::Int(v) => i16::try_from(*v).map_err(|_| ParseError::ArgOutOfRange {
                    command: number,
                    value: *v,
                }),
                _ => Err(ParseError::WrongArg {
                    command: number,
                    expected,
                }),
            }
        };
        let opt_int = || -> Result<Option<i16>, ParseError> {
            match &arg {
                Arg::None => Ok(None),
                _ => int("an integer or no argument").map(Some),
            }
        };
        let string = || -> Result<StrArg, ParseError> {
            match &arg {
                Arg::Str(s) => Ok(s.clone()),
                _ => Err(ParseError::WrongArg {
                    command: number,
                    expected: "a string",
                }),
            }
        };
        let i = || int("an integer");
        Ok(match number {
            PULSE => Command::Pulse,
            OPEN => Command::Open(opt_int()?),
            CLOSE => Command::Close(opt_int()?),
            POLLING => Command::Polling(string()?),
            ENABLE => Command::Enable(i()? != 0),
            SETA => Command::SetA(i()?),
            SETV => Command::SetV(i()?),
            SETO => Command::SetO,
            MOVE => Command::Move(i()?),
            ROTATE => Command::Rotate(i()?),
            SETRV => Command::SetRv(i()?),
            VEL => Command::Vel(i()?),
            HEAD => Command::Head(i()?),
            DHEAD => Command::DHead(i()?),
            SAY => Command::Say(string()?),
            JOYINFO => Command::JoyInfo(i()?),
            CONFIG => Command::Config(opt_int()?),
            ENCODER => Command::Encoder(i()?),
            SETRVDIR => Command::SetRvDir(i()?),
            RVEL => Command::RVel(i()?),
            DCHEAD => Command::DcHead(i()?),
            SETRA => Command::SetRa(i()?),
            SONAR => Command::Sonar(i()? != 0),
            STOP => Command::Stop,
            DIGOUT => Command::DigOut(i()?),
            VEL2 => {
                let v = i()?;
                Command::Vel2 {
                    left: (v >> 8) as i8,
                    right: (v & 0xFF) as u8 as i8,
                }
            }
            GRIPPER => Command::Gripper(i()?),
            ADSEL => Command::AdSel(i()?),
            IOREQUEST => Command::IoRequest(i()?),
            BUMPSTALL => Command::BumpStall(i()?),
            JOYDRIVE => Command::JoyDrive(i()? != 0),
            HOSTBAUD => Command::HostBaud(i()?),
            AUX1BAUD => Command::Aux1Baud(i()?),
            AUX2BAUD => Command::Aux2Baud(i()?),
            E_STOP => Command::EStop,
            GYRO => Command::Gyro(i()?),
            BATTERYINFO => Command::BatteryInfo(i()?),
            REVCOUNT => Command::RevCount(i()?),
            DRIFTFACTOR => Command::DriftFactor(i()?),
            TICKSMM => Command::TicksMm(i()?),
            BATTEST => Command::BatTest(i()?),
            RESET => Command::Reset,
            _ => Command::Other { number, arg },
        })
    }
}

/// Decodes the argument bytes after a command number. A string may be followed by one NUL
/// (ARIA appends one); any other trailing byte is an error.
pub fn parse_arg(payload: &[u8]) -> Result<Arg, ParseError> {
    let mut r = Reader::new(payload);
    let Some(kind) = r.u8() else {
        return Ok(Arg::None);
    };
    let trunc = |field, offset| ParseError::Truncated { field, offset };
    let arg = match kind {
        ARG_INT | ARG_NEG_INT => {
            let m = r.u16_le().ok_or(trunc("integer argument", 1))? as i32;
            Arg::Int(if kind == ARG_NEG_INT { -m } else { m })
        }
        ARG_STR => {
            let len = r.u8().ok_or(trunc("string length", 1))? as usize;
            if len > MAX_STR_ARG {
                return Err(ParseError::StringTooLong {
                    field: "string argument",
                    len,
                    capacity: MAX_STR_ARG,
                });
            }
            let s = r.take(len).ok_or(trunc("string argument", 2))?;
            let v = StrArg::from_slice(s).map_err(|_| ParseError::StringTooLong {
                field: "string argument",
                len,
                capacity: MAX_STR_ARG,
            })?;
            if r.remaining() == 1 && r.clone().u8() == Some(0) {
                r.u8();
            }
            Arg::Str(v)
        }
        got => return Err(ParseError::BadArgType { got }),
    };
    if !r.is_empty() {
        return Err(ParseError::TrailingBytes {
            count: r.remaining(),
        });
    }
    Ok(arg)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::random::{below, seeded};

    fn enc(c: &Command) -> heapless::Vec<u8, MAX_COMMAND_LEN> {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let n = c.emit(&mut buf).unwrap();
        assert_eq!(n, c.buffer_len());
        heapless::Vec::from_slice(&buf[..n]).unwrap()
    }

    fn dec(bytes: &[u8]) -> Command {
        Command::parse(&Frame::new_checked(bytes).unwrap()).unwrap()
    }

    /// Every command byte example of fact sheet 1.1.
    const GOLDEN: &[(Command, &[u8])] = &[
        (Command::Pulse, &[0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00]),
        (Command::Open(None), &[0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01]),
        (Command::Close(None), &[0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02]),
        (
            Command::Open(Some(1)),
            &[0xFA, 0xFB, 0x06, 0x01, 0x3B, 0x01, 0x00, 0x02, 0x3B],
        ),
        (
            Command::Enable(true),
            &[0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B],
        ),
        (
            Command::Vel(200),
            &[0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xC8, 0x00, 0xD3, 0x3B],
        ),
        (
            Command::SetA(-300),
            &[0xFA, 0xFB, 0x06, 0x05, 0x1B, 0x2C, 0x01, 0x31, 0x1C],
        ),
        (
            Command::RVel(-10),
            &[0xFA, 0xFB, 0x06, 0x15, 0x1B, 0x0A, 0x00, 0x1F, 0x1B],
        ),
        (
            Command::HostBaud(2),
            &[0xFA, 0xFB, 0x06, 0x32, 0x3B, 0x02, 0x00, 0x34, 0x3B],
        ),
        (
            Command::Config(Some(1)),
            &[0xFA, 0xFB, 0x06, 0x12, 0x3B, 0x01, 0x00, 0x13, 0x3B],
        ),
        (Command::Stop, &[0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D]),
    ];

    #[test]
    fn golden_commands_encode_and_decode_exactly() {
        for (cmd, bytes) in GOLDEN {
            assert_eq!(enc(cmd).as_slice(), *bytes, "{cmd:?}");
            assert_eq!(&dec(bytes), cmd);
        }
        assert_eq!(Command::SYNC0.sync_number(), Some(0));
        assert_eq!(
            dec(&[0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02]).sync_number(),
            Some(2)
        );
        assert_eq!(Command::Open(Some(1)).sync_number(), None);
    }

    #[test]
    fn vel2_packs_left_high_right_low() {
        let c = Command::Vel2 { left: -3, right: 5 };
        let b = enc(&c);
        // (-3 << 8) | 5 = -763 = 0xFD05 as i16, sent as a negative int of magnitude 763.
        assert_eq!(&b[4..7], &[0x1B, 0xFB, 0x02]);
        assert_eq!(dec(&b), c);
    }

    #[test]
    fn wrong_arguments_are_errors() {
        assert_eq!(
            Command::parse_parts(num::VEL, &[]),
            Err(ParseError::WrongArg {
                command: num::VEL,
                expected: "an integer"
            })
        );
        assert_eq!(
            Command::parse_parts(num::VEL, &[0x3B, 0x00, 0x90]),
            Err(ParseError::ArgOutOfRange {
                command: num::VEL,
                value: 0x9000
            })
        );
        assert_eq!(
            Command::parse_parts(num::VEL, &[0x4B, 0, 0]),
            Err(ParseError::BadArgType { got: 0x4B })
        );
        assert_eq!(
            Command::parse_parts(num::VEL, &[0x3B, 1, 0, 7]),
            Err(ParseError::TrailingBytes { count: 1 })
        );
        assert!(matches!(
            Command::parse_parts(num::SAY, &[0x2B, 5, 1, 2]),
            Err(ParseError::Truncated { .. })
        ));
        // ARIA's trailing NUL after a string is accepted.
        assert_eq!(
            Command::parse_parts(num::SAY, &[0x2B, 2, 9, 8, 0]),
            Ok(Command::Say(StrArg::from_slice(&[9, 8]).unwrap()))
        );
    }

    /// A random command of every kind.
    pub(crate) fn random_command(rng: &mut crate::random::ProjectRng) -> Command {
        use rand_core::Rng;
        let v = rng.next_u32() as i16;
        let b = rng.next_u32() & 1 == 1;
        let mut s = StrArg::new();
        for _ in 0..below(rng, MAX_STR_ARG + 1) {
            s.push(rng.next_u32() as u8).unwrap();
        }
        let opt = if b { Some(v) } else { None };
        match below(rng, 45) {
            0 => Command::Pulse,
            1 => Command::Open(opt),
            2 => Command::Close(opt),
            3 => Command::Polling(s),
            4 => Command::Enable(b),
            5 => Command::SetA(v),
            6 => Command::SetV(v),
            7 => Command::SetO,
            8 => Command::Move(v),
            9 => Command::Rotate(v),
            10 => Command::SetRv(v),
            11 => Command::Vel(v),
            12 => Command::Head(v),
            13 => Command::DHead(v),
            14 => Command::Say(s),
            15 => Command::JoyInfo(v),
            16 => Command::Config(opt),
            17 => Command::Encoder(v),
            18 => Command::SetRvDir(v),
            19 => Command::RVel(v),
            20 => Command::DcHead(v),
            21 => Command::SetRa(v),
            22 => Command::Sonar(b),
            23 => Command::Stop,
            24 => Command::DigOut(v),
            25 => Command::Vel2 {
                left: v as i8,
                right: (v >> 8) as i8,
            },
            26 => Command::Gripper(v),
            27 => Command::AdSel(v),
            28 => Command::IoRequest(v),
            29 => Command::BumpStall(v),
            30 => Command::JoyDrive(b),
            31 => Command::HostBaud(v),
            32 => Command::Aux1Baud(v),
            33 => Command::Aux2Baud(v),
            34 => Command::EStop,
            35 => Command::Gyro(v),
            36 => Command::BatteryInfo(v),
            37 => Command::RevCount(v),
            38 => Command::DriftFactor(v),
            39 => Command::TicksMm(v),
            40 => Command::BatTest(v),
            41 => Command::Reset,
            42 => Command::Other {
                number: 100,
                arg: Arg::Int(rng.next_u32() as i32 % 65536),
            },
            43 => Command::Other {
                number: 224,
                arg: Arg::Str(s),
            },
            _ => Command::Other {
                number: 82,
                arg: Arg::None,
            },
        }
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(0xA5C0);
        for _ in 0..20_000 {
            let c = random_command(&mut rng);
            assert_eq!(dec(&enc(&c)), c);
        }
    }
}
