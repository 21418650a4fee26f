//! The CONFIG packet (ID 0x20), the reply to the CONFIG command (fact sheet 1.7).
//!
//! Fields 1-47 (through ShutdownVoltage) are required; fields 48-67 are optional and
//! positional: each is present only if every earlier one is (AMRISim stops after field 57,
//! PowerbotChargeThreshold). Strings are NUL-terminated and held in [`Name`]s; a longer string
//! is a [`ParseError::StringTooLong`].

use super::frame::{self, Frame};
use super::{EmitError, Name, ParseError, read_name};
use crate::wire::bytes::{Overflow, Reader, Writer};

/// CONFIG packet ID.
pub const ID: u8 = 0x20;

/// One CONFIG field type: how it is read, written and sized.
trait Field: Sized {
    fn read(r: &mut Reader<'_>, name: &'static str) -> Result<Self, ParseError>;
    fn write(&self, w: &mut Writer<'_>) -> Result<(), Overflow>;
    fn wire_len(&self) -> usize;
}

macro_rules! int_field {
    ($t:ty, $read:ident, $write:ident, $as:ty, $n:expr) => {
        impl Field for $t {
            fn read(r: &mut Reader<'_>, field: &'static str) -> Result<Self, ParseError> {
                let offset = r.position();
                r.$read().ok_or(ParseError::Truncated { field, offset })
            }
            fn write(&self, w: &mut Writer<'_>) -> Result<(), Overflow> {
                w.$write(*self as $as)
            }
            fn wire_len(&self) -> usize {
                $n
            }
        }
    };
}
int_field!(u8, u8, u8, u8, 1);
int_field!(i8, i8, u8, u8, 1);
int_field!(u16, u16_le, u16_le, u16, 2);
int_field!(i16, i16_le, u16_le, u16, 2);
int_field!(u32, u32_le, u32_le, u32, 4);

impl Field for Name {
    fn read(r: &mut Reader<'_>, field: &'static str) -> Result<Self, ParseError> {
        read_name(r, field)
    }
    fn write(&self, w: &mut Writer<'_>) -> Result<(), Overflow> {
        w.cstr(self.as_bytes())
    }
    fn wire_len(&self) -> usize {
        self.len() + 1
    }
}

macro_rules! config_packet {
    (
        required { $( $(#[$rm:meta])* $r:ident : $rt:ty = $rn:literal, )* }
        optional { $( $(#[$om:meta])* $o:ident : $ot:ty = $on:literal, )* }
    ) => {
        /// A CONFIG packet: the robot's identity, limits and current settings.
        #[derive(Clone, Debug, PartialEq, Eq, Default)]
        pub struct ConfigPacket {
            $( $(#[$rm])* pub $r: $rt, )*
            /// Optional trailing fields 48-67.
            pub extras: ConfigExtras,
        }

        /// Optional CONFIG fields 48-67, in wire order.
        #[derive(Clone, Debug, PartialEq, Eq, Default)]
        pub struct ConfigExtras {
            $( $(#[$om])* pub $o: Option<$ot>, )*
        }

        impl ConfigPacket {
            /// Parses a CONFIG payload (the bytes after the ID). Bytes after the last known
            /// field are ignored.
            pub fn parse(payload: &[u8]) -> Result<Self, ParseError> {
                let mut r = Reader::new(payload);
                let mut p = ConfigPacket {
                    $( $r: <$rt as Field>::read(&mut r, $rn)?, )*
                    extras: ConfigExtras::default(),
                };
                $(
                    if !r.is_empty() {
                        p.extras.$o = Some(<$ot as Field>::read(&mut r, $on)?);
                    }
                )*
                Ok(p)
            }

            fn payload_len(&self) -> Result<usize, EmitError> {
                let mut len = 0;
                $( len += self.$r.wire_len(); )*
                let mut ended = false;
                $(
                    match &self.extras.$o {
                        Some(v) if ended => {
                            let _ = v;
                            return Err(EmitError::FieldAfterAbsent { field: $on });
                        }
                        Some(v) => len += v.wire_len(),
                        None => ended = true,
                    }
                )*
                let _ = ended;
                Ok(len)
            }

            fn write_payload(&self, w: &mut Writer<'_>) -> Result<(), Overflow> {
                $( self.$r.write(w)?; )*
                $(
                    match &self.extras.$o {
                        Some(v) => v.write(w)?,
                        None => return Ok(()),
                    }
                )*
                Ok(())
            }
        }
    };
}

config_packet! {
    required {
        /// Robot class ("Pioneer").
        robot_type: Name = "Type",
        /// Robot subclass ("p3dx-sh").
        subtype: Name = "Subtype",
        /// Serial number.
        serial: Name = "SerialNumber",
        /// 4MOTS (unused).
        four_mots: u8 = "4MOTS",
        /// Absolute maximum rotational velocity \[deg/s\].
        rot_vel_top: u16 = "RotVelTop",
        /// Absolute maximum translational velocity \[mm/s\].
        trans_vel_top: u16 = "TransVelTop",
        /// Absolute maximum rotational acceleration \[deg/s²\].
        rot_acc_top: u16 = "RotAccTop",
        /// Absolute maximum translational acceleration \[mm/s²\].
        trans_acc_top: u16 = "TransAccTop",
        /// Maximum PWM.
        pwm_max: u16 = "PWMMax",
        /// Robot name.
        name: Name = "Name",
        /// Status packet period \[ms\].
        sip_cycle_ms: u8 = "SIPcycle",
        /// Host port baud code (0 = 9600 … 4 = 115200).
        host_baud: u8 = "HostBaud",
        /// AUX1 baud code.
        aux1_baud: u8 = "Aux1Baud",
        /// Gripper present.
        has_gripper: u16 = "HasGripper",
        /// Front sonar present.
        front_sonar: u16 = "FrontSonar",
        /// Rear sonar present (one byte).
        rear_sonar: u8 = "RearSonar",
        /// Low battery alarm \[0.1 V\].
        low_battery_dv: u16 = "LowBattery",
        /// Differential encoder count.
        rev_count: u16 = "RevCount",
        /// Watchdog period \[ms\].
        watchdog_ms: u16 = "Watchdog",
        /// NormalMPacs.
        normal_mpacs: u8 = "P2Mpacs",
        /// Stall PWM limit.
        stall_val: u16 = "StallVal",
        /// Stall recovery time \[ms\].
        stall_count_ms: u16 = "StallCount",
        /// Joystick translational velocity \[mm/s\].
        joy_vel: u16 = "JoyVel",
        /// Joystick rotational velocity \[deg/s\].
        joy_rvel: u16 = "JoyRVel",
        /// Current maximum rotational velocity \[deg/s\].
        rot_vel_max: u16 = "RotVelMax",
        /// Current maximum translational velocity \[mm/s\].
        trans_vel_max: u16 = "TransVelMax",
        /// Rotational acceleration \[deg/s²\].
        rot_acc: u16 = "RotAcc",
        /// Rotational deceleration \[deg/s²\].
        rot_decel: u16 = "RotDecel",
        /// Rotation PID proportional gain.
        rot_kp: u16 = "RotKP",
        /// Rotation PID derivative gain.
        rot_kv: u16 = "RotKV",
        /// Rotation PID integral gain.
        rot_ki: u16 = "RotKI",
        /// Translational acceleration \[mm/s²\].
        trans_acc: u16 = "TransAcc",
        /// Translational deceleration \[mm/s²\].
        trans_decel: u16 = "TransDecel",
        /// Translation PID proportional gain.
        trans_kp: u16 = "TransKP",
        /// Translation PID derivative gain.
        trans_kv: u16 = "TransKV",
        /// Translation PID integral gain.
        trans_ki: u16 = "TransKI",
        /// Front bumper segments.
        front_bumps: u8 = "FrontBumps",
        /// Rear bumper segments.
        rear_bumps: u8 = "RearBumps",
        /// Charger type.
        charger: u8 = "Charger",
        /// Sonar cycle \[ms\].
        sonar_cycle_ms: u8 = "SonarCycle",
        /// 1 = can change baud, 2 = auto-baud (ARIA may switch).
        auto_baud: u8 = "AutoBaud",
        /// Gyro type.
        has_gyro: u8 = "HasGyro",
        /// Drift factor.
        drift_factor: i16 = "DriftFactor",
        /// AUX2 baud code.
        aux2_baud: u8 = "Aux2Baud",
        /// AUX3 baud code.
        aux3_baud: u8 = "Aux3Baud",
        /// Encoder ticks per mm.
        ticks_mm: u16 = "TicksMM",
        /// Shutdown voltage \[0.1 V\].
        shutdown_voltage_dv: u16 = "ShutdownVoltage",
    }
    optional {
        /// Firmware version.
        firmware_version: Name = "FirmwareVersion",
        /// Gyro clockwise scale.
        gyro_cw: u16 = "GyroCW",
        /// Gyro counter-clockwise scale.
        gyro_ccw: u16 = "GyroCCW",
        /// Kinematics delay \[ms\].
        kinematics_delay_ms: u8 = "KinematicsDelay",
        /// Lateral velocity top \[mm/s\].
        lat_vel_top: u16 = "LatVelTop",
        /// Lateral acceleration top \[mm/s²\].
        lat_acc_top: u16 = "LatAccTop",
        /// Lateral velocity max \[mm/s\].
        lat_vel_max: u16 = "LatVelMax",
        /// Lateral acceleration \[mm/s²\].
        lat_acc: u16 = "LatAcc",
        /// Lateral deceleration \[mm/s²\].
        lat_decel: u16 = "LatDecel",
        /// Powerbot charge threshold.
        powerbot_charge_threshold: u16 = "PowerbotChargeThreshold",
        /// PDB port.
        pdb_port: u8 = "PDBPort",
        /// Gyro rate limit.
        gyro_rate_limit: u16 = "GyroRateLimit",
        /// High temperature shutdown \[°C\].
        high_temperature_shutdown_c: i8 = "HighTemperatureShutdown",
        /// Power bits.
        power_bits: u16 = "PowerBits",
        /// Battery type.
        battery_type: u8 = "BatteryType",
        /// State-of-charge warning level \[%\].
        soc_low: u16 = "SoCLow",
        /// State-of-charge shutdown level \[%\].
        soc_shutdown: u16 = "SoCShutdown",
        /// Bootloader version.
        bootloader_version: Name = "BootloaderVersion",
        /// Config flags.
        config_flags: u32 = "ConfigFlags",
        /// Gyro firmware version.
        gyro_fw_version: i16 = "GyroFWVersion",
    }
}

impl ConfigPacket {
    /// Parses a checked frame with ID 0x20.
    pub fn parse_frame<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        if frame.id() != ID {
            return Err(ParseError::UnexpectedId { got: frame.id() });
        }
        Self::parse(frame.payload())
    }

    /// Encoded length \[bytes\].
    pub fn buffer_len(&self) -> Result<usize, EmitError> {
        Ok(frame::frame_len(self.payload_len()?))
    }

    /// Encodes the packet as a complete frame into `buf`; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        let len = self.payload_len()?;
        frame::emit_with(buf, ID, len, |w| self.write_payload(w))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::random::{ProjectRng, below, seeded};
    use rand_core::Rng;

    /// A CONFIG as an emulated P3-DX sends it, ending at field 57 like AMRISim.
    pub(crate) fn p3dx() -> ConfigPacket {
        ConfigPacket {
            robot_type: Name::try_from("Pioneer").unwrap(),
            subtype: Name::try_from("p3dx-sh").unwrap(),
            serial: Name::try_from("SIM").unwrap(),
            rot_vel_top: 500,
            trans_vel_top: 2200,
            name: Name::try_from("papillon").unwrap(),
            sip_cycle_ms: 100,
            watchdog_ms: 2000,
            auto_baud: 2,
            ticks_mm: 128,
            extras: ConfigExtras {
                firmware_version: Some(Name::try_from("S.0").unwrap()),
                gyro_cw: Some(0),
                gyro_ccw: Some(0),
                kinematics_delay_ms: Some(0),
                lat_vel_top: Some(0),
                lat_acc_top: Some(0),
                lat_vel_max: Some(0),
                lat_acc: Some(0),
                lat_decel: Some(0),
                powerbot_charge_threshold: Some(0),
                ..Default::default()
            },
            ..Default::default()
        }
    }

    #[test]
    fn round_trip_and_layout() {
        let c = p3dx();
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        let n = c.emit(&mut buf).unwrap();
        assert_eq!(n, c.buffer_len().unwrap());
        assert_eq!(&buf[3..12], b"\x20Pioneer\0");
        let f = Frame::new_checked(&buf[..n]).unwrap();
        assert_eq!(ConfigPacket::parse_frame(&f).unwrap(), c);
    }

    #[test]
    fn errors_name_the_field() {
        let c = p3dx();
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        let n = c.emit(&mut buf).unwrap();
        // Cut inside the required block: "Pioneer\0p3dx-sh\0SIM\0" + 4MOTS + RotVelTop (half).
        let payload = &buf[4..n - 2];
        assert_eq!(
            ConfigPacket::parse(&payload[..22]),
            Err(ParseError::Truncated {
                field: "RotVelTop",
                offset: 21
            })
        );
        assert_eq!(
            ConfigPacket::parse(b"Pioneer"),
            Err(ParseError::Truncated {
                field: "Type",
                offset: 0
            })
        );
        let long = [b'a'; 40];
        let mut p = heapless::Vec::<u8, 64>::from_slice(&long).unwrap();
        p.push(0).unwrap();
        assert_eq!(
            ConfigPacket::parse(&p),
            Err(ParseError::StringTooLong {
                field: "Type",
                len: 40,
                capacity: 32
            })
        );
        assert_eq!(
            ConfigPacket::parse(b"\xFF\0"),
            Err(ParseError::NotUtf8 { field: "Type" })
        );
        let mut gap = c.clone();
        gap.extras.gyro_fw_version = Some(3);
        assert_eq!(
            gap.emit(&mut buf),
            Err(EmitError::FieldAfterAbsent {
                field: "GyroFWVersion"
            })
        );
    }

    fn name(rng: &mut ProjectRng) -> Name {
        let mut s = Name::new();
        for _ in 0..below(rng, 9) {
            s.push((b'a' + below(rng, 26) as u8) as char).unwrap();
        }
        s
    }

    pub(crate) fn random_config(rng: &mut ProjectRng) -> ConfigPacket {
        let mut c = p3dx();
        c.robot_type = name(rng);
        c.subtype = name(rng);
        c.serial = name(rng);
        c.name = name(rng);
        c.rot_vel_top = rng.next_u32() as u16;
        c.drift_factor = rng.next_u32() as i16;
        c.shutdown_voltage_dv = rng.next_u32() as u16;
        c.rear_sonar = rng.next_u32() as u8;
        let k = below(rng, 21);
        let mut x = ConfigExtras::default();
        let on = |i: usize| i < k;
        x.firmware_version = on(0).then(|| name(rng));
        x.gyro_cw = on(1).then(|| rng.next_u32() as u16);
        x.gyro_ccw = on(2).then(|| rng.next_u32() as u16);
        x.kinematics_delay_ms = on(3).then(|| rng.next_u32() as u8);
        x.lat_vel_top = on(4).then(|| rng.next_u32() as u16);
        x.lat_acc_top = on(5).then(|| rng.next_u32() as u16);
        x.lat_vel_max = on(6).then(|| rng.next_u32() as u16);
        x.lat_acc = on(7).then(|| rng.next_u32() as u16);
        x.lat_decel = on(8).then(|| rng.next_u32() as u16);
        x.powerbot_charge_threshold = on(9).then(|| rng.next_u32() as u16);
        x.pdb_port = on(10).then(|| rng.next_u32() as u8);
        x.gyro_rate_limit = on(11).then(|| rng.next_u32() as u16);
        x.high_temperature_shutdown_c = on(12).then(|| rng.next_u32() as i8);
        x.power_bits = on(13).then(|| rng.next_u32() as u16);
        x.battery_type = on(14).then(|| rng.next_u32() as u8);
        x.soc_low = on(15).then(|| rng.next_u32() as u16);
        x.soc_shutdown = on(16).then(|| rng.next_u32() as u16);
        x.bootloader_version = on(17).then(|| name(rng));
        x.config_flags = on(18).then(|| rng.next_u32());
        x.gyro_fw_version = on(19).then(|| rng.next_u32() as i16);
        c.extras = x;
        c
    }

    #[test]
    fn decode_of_encode_is_identity() {
        let mut rng = seeded(0xC0F);
        let mut buf = [0u8; frame::MAX_FRAME_LEN];
        for _ in 0..5_000 {
            let c = random_config(&mut rng);
            let n = c.emit(&mut buf).unwrap();
            let f = Frame::new_checked(&buf[..n]).unwrap();
            assert_eq!(ConfigPacket::parse_frame(&f).unwrap(), c);
        }
    }
}
