//! The client sessions' codecs over `crate::wire`: [`WireArcos`] (ARCOS, fact sheet section 1)
//! and [`WireLms1xx`] (SICK LMS1xx CoLa-A, fact sheet section 2).
//!
//! These adapters hold no protocol knowledge of their own: framing, checksums, packet layouts
//! and resynchronisation are the wire module's ([`crate::wire::arcos::FrameDecoder`],
//! [`crate::wire::arcos::ServerPacket`], [`crate::wire::arcos::Command`],
//! [`crate::wire::lms1xx::ColaDecoder`], [`crate::wire::lms1xx::Reply`],
//! [`crate::wire::lms1xx::ScanTelegram`]). They only map the wire types onto the session's
//! vocabulary ([`super::arcos`], [`super::laser`]).

use super::arcos::{
    ArcosCodec, ClientCommand, CodecStats, ConfigHighlights, Incoming, RobotIdentity, RobotStatus,
};
use super::laser::{LaserCodec, LaserCodecStats, LaserReply, LaserRequest};
use crate::sensor::telegram::lms1xx_scan;
use crate::sensor::{LaserConfig, Scan};
use crate::wire::arcos::{
    Command, ConfigPacket, FrameDecoder, ServerPacket, StatusPacket, SyncReply,
    command::MAX_COMMAND_LEN,
};
use crate::wire::lms1xx::{
    ColaDecoder, Dialect, Reply, Request, ScanDataConfig, ScanTelegram,
    command::check_reply,
    command::{ACCESS_LEVEL_AUTHORIZED_CLIENT, AUTHORIZED_CLIENT_PASSWORD},
    scandata::is_scan_data,
};

/// The wire command of a session command (ARIA's arguments: OPEN 1, CLOSE 1, CONFIG 1).
pub fn wire_command(command: &ClientCommand) -> Command {
    match *command {
        ClientCommand::Sync(0) => Command::SYNC0,
        ClientCommand::Sync(1) => Command::SYNC1,
        ClientCommand::Sync(_) => Command::SYNC2,
        ClientCommand::Pulse => Command::Pulse,
        ClientCommand::Open => Command::Open(Some(1)),
        ClientCommand::Close => Command::Close(Some(1)),
        ClientCommand::Enable(on) => Command::Enable(on),
        ClientCommand::SetA(v) => Command::SetA(v),
        ClientCommand::SetV(v) => Command::SetV(v),
        ClientCommand::SetO => Command::SetO,
        ClientCommand::SetRv(v) => Command::SetRv(v),
        ClientCommand::Vel(v) => Command::Vel(v),
        ClientCommand::Config => Command::Config(Some(1)),
        ClientCommand::RVel(v) => Command::RVel(v),
        ClientCommand::SetRa(v) => Command::SetRa(v),
        ClientCommand::Stop => Command::Stop,
        ClientCommand::HostBaud(v) => Command::HostBaud(v),
        ClientCommand::BatteryInfo(v) => Command::BatteryInfo(v),
    }
}

/// The session's view of a status packet.
pub fn robot_status(p: &StatusPacket) -> RobotStatus {
    RobotStatus {
        moving: p.moving,
        x_pos: p.x_pos,
        y_pos: p.y_pos,
        th_pos: p.th_pos,
        left_vel_mm_s: p.left_vel_mm_s,
        right_vel_mm_s: p.right_vel_mm_s,
        battery_dv: p.battery_dv,
        stall_bumpers: p.stall_bumpers,
        flags: p.flags,
    }
}

/// The CONFIG fields the session uses or prints.
pub fn config_highlights(c: &ConfigPacket) -> ConfigHighlights {
    ConfigHighlights {
        class: c.robot_type.as_str().into(),
        subclass: c.subtype.as_str().into(),
        serial: c.serial.as_str().into(),
        name: c.name.as_str().into(),
        rot_vel_top_deg_s: c.rot_vel_top,
        trans_vel_top_mm_s: c.trans_vel_top,
        rot_acc_top_deg_s2: c.rot_acc_top,
        trans_acc_top_mm_s2: c.trans_acc_top,
        sip_cycle_ms: c.sip_cycle_ms,
        host_baud_code: c.host_baud,
        watchdog_ms: c.watchdog_ms,
        rot_vel_max_deg_s: c.rot_vel_max,
        trans_vel_max_mm_s: c.trans_vel_max,
        auto_baud: c.auto_baud,
        firmware: c
            .extras
            .firmware_version
            .as_ref()
            .map(|v| v.as_str().to_string())
            .unwrap_or_default(),
    }
}

/// The ARCOS client codec over [`crate::wire::arcos`].
#[derive(Default)]
pub struct WireArcos {
    decoder: FrameDecoder,
    /// Frames with a good checksum whose payload did not parse.
    bad_payloads: u64,
}

impl ArcosCodec for WireArcos {
    fn encode(&mut self, command: &ClientCommand, out: &mut Vec<u8>) {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        // Every session command has an int argument in range: emitting cannot fail.
        if let Ok(n) = wire_command(command).emit(&mut buf) {
            out.extend_from_slice(&buf[..n]);
        }
    }

    fn decode(&mut self, bytes: &[u8], out: &mut Vec<Incoming>) {
        let mut input = bytes;
        while let Some(frame) = self.decoder.decode(&mut input) {
            let packet = match ServerPacket::parse(&frame) {
                Ok(p) => p,
                Err(_) => {
                    self.bad_payloads += 1;
                    continue;
                }
            };
            out.push(match packet {
                ServerPacket::Sync(SyncReply::Sync0) => Incoming::SyncEcho(0),
                ServerPacket::Sync(SyncReply::Sync1) => Incoming::SyncEcho(1),
                ServerPacket::Sync(SyncReply::Sync2 {
                    name,
                    class,
                    subclass,
                }) => Incoming::Identity(RobotIdentity {
                    name: name.as_str().into(),
                    class: class.as_str().into(),
                    subclass: subclass.as_str().into(),
                }),
                ServerPacket::Status(s) => Incoming::Status(robot_status(&s)),
                ServerPacket::Config(c) => Incoming::Config(config_highlights(&c)),
                ServerPacket::Reset { id } => Incoming::Reset { id },
                ServerPacket::Encoder(_) => Incoming::Other {
                    id: crate::wire::arcos::encoder::ID,
                },
                ServerPacket::Other { id } => Incoming::Other { id },
            });
        }
    }

    fn reset(&mut self) {
        self.decoder.reset();
    }

    fn stats(&self) -> CodecStats {
        let s = self.decoder.stats();
        CodecStats {
            packets: s.frames,
            bad_checksums: s.bad_checksum,
            junk_bytes: s.skipped_bytes,
            bad_payloads: self.bad_payloads,
        }
    }
}

/// The wire request of a connect-sequence step (the clearpath LMS1xx driver's bytes).
pub fn wire_request(request: LaserRequest) -> Request {
    match request {
        LaserRequest::SetAccessMode => Request::SetAccessMode {
            level: ACCESS_LEVEL_AUTHORIZED_CLIENT,
            password_hash: AUTHORIZED_CLIENT_PASSWORD,
            dialect: Dialect::Clearpath,
        },
        LaserRequest::ReadScanConfig => Request::ReadScanConfig,
        LaserRequest::ReadOutputRange => Request::ReadOutputRange,
        LaserRequest::WriteScanDataConfig => {
            Request::SetScanDataConfig(ScanDataConfig::clearpath(false))
        }
        LaserRequest::StartMeasurement => Request::StartMeasurement,
        LaserRequest::ReadState => Request::ReadStatus,
        LaserRequest::Run => Request::Run,
        LaserRequest::SubscribeScans(on) => Request::SubscribeScanData(on),
    }
}

/// The session request a reply answers (`None` for `sFA`, which names no request).
fn answered_request(reply: &Reply) -> Option<LaserRequest> {
    Some(match reply {
        Reply::AccessMode { .. } => LaserRequest::SetAccessMode,
        Reply::ScanConfig(_) => LaserRequest::ReadScanConfig,
        Reply::OutputRange(_) => LaserRequest::ReadOutputRange,
        Reply::ScanDataConfigAck => LaserRequest::WriteScanDataConfig,
        Reply::StartMeasurement { .. } => LaserRequest::StartMeasurement,
        Reply::Status { .. } => LaserRequest::ReadState,
        Reply::Run { .. } => LaserRequest::Run,
        Reply::Subscribed { enabled } => LaserRequest::SubscribeScans(*enabled),
        _ => return None,
    })
}

/// The LMS1xx client codec over [`crate::wire::lms1xx`].
#[derive(Default)]
pub struct WireLms1xx {
    decoder: Box<ColaDecoder>,
    /// The last request sent: an `sFA` refusal answers it.
    last_request: Option<LaserRequest>,
    bad_telegrams: u64,
}

impl WireLms1xx {
    fn reply(&mut self, payload: &[u8], laser: &LaserConfig) -> Option<LaserReply> {
        if is_scan_data(payload) {
            let telegram = ScanTelegram::parse(payload).ok()?;
            let mut scan = Box::new(Scan::new());
            lms1xx_scan(&telegram, laser.max_range_m, &mut scan).ok()?;
            return Some(LaserReply::Scan(scan));
        }
        let reply = Reply::parse(payload).ok()?;
        if let Reply::Status { state } = reply {
            return Some(LaserReply::State(state));
        }
        let Some(request) = answered_request(&reply).or(self.last_request) else {
            return Some(LaserReply::Other);
        };
        Some(match check_reply(&wire_request(request), &reply) {
            Ok(()) => LaserReply::Ack(request),
            Err(e) => LaserReply::Refused {
                request,
                detail: e.to_string(),
            },
        })
    }
}

impl LaserCodec for WireLms1xx {
    fn encode(&mut self, request: LaserRequest, out: &mut Vec<u8>) {
        self.last_request = Some(request);
        let mut buf = [0u8; 256];
        if let Ok(n) = wire_request(request).emit(&mut buf) {
            out.extend_from_slice(&buf[..n]);
        }
    }

    fn decode(&mut self, bytes: &[u8], laser: &LaserConfig, out: &mut Vec<LaserReply>) {
        let mut input = bytes;
        while let Some(payload) = self.decoder.decode(&mut input) {
            // Copy out: the decoder's buffer is borrowed until the next call.
            let payload = payload.to_vec();
            match self.reply(&payload, laser) {
                Some(r) => out.push(r),
                None => self.bad_telegrams += 1,
            }
        }
    }

    fn stats(&self) -> LaserCodecStats {
        let s = self.decoder.stats();
        LaserCodecStats {
            telegrams: s.frames,
            junk_bytes: s.skipped_bytes,
            bad_telegrams: self.bad_telegrams + s.oversize + s.truncated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::arcos::{config, sip};

    fn emit_server(p: &ServerPacket) -> Vec<u8> {
        let mut buf = [0u8; crate::wire::arcos::frame::MAX_FRAME_LEN];
        let n = p.emit(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    #[test]
    fn commands_are_the_fact_sheet_bytes() {
        let mut c = WireArcos::default();
        let bytes = |c: &mut WireArcos, cmd| {
            let mut out = Vec::new();
            c.encode(&cmd, &mut out);
            out
        };
        // SYNC0 and STOP, fact sheet 1.1; OPEN with ARIA's int argument 1.
        assert_eq!(
            bytes(&mut c, ClientCommand::Sync(0)),
            [0xFA, 0xFB, 3, 0, 0, 0]
        );
        assert_eq!(
            bytes(&mut c, ClientCommand::Stop),
            [0xFA, 0xFB, 3, 0x1D, 0, 0x1D]
        );
        let open = bytes(&mut c, ClientCommand::Open);
        assert_eq!(&open[..7], [0xFA, 0xFB, 6, 1, 0x3B, 1, 0]);
        // A negative argument uses the 0x1B type byte and the magnitude.
        let vel = bytes(&mut c, ClientCommand::Vel(-300));
        assert_eq!(&vel[3..7], [11, 0x1B, 0x2C, 0x01]);
        // Each frame parses back to the command the session meant.
        let mut dec = FrameDecoder::new();
        let mut input = &vel[..];
        let f = dec.decode(&mut input).unwrap();
        assert_eq!(Command::parse(&f).unwrap(), Command::Vel(-300));
    }

    #[test]
    fn server_packets_decode_field_for_field_from_any_split() {
        let mut stream = b"WMS2\r".to_vec();
        stream.extend(emit_server(&ServerPacket::Sync(SyncReply::Sync0)));
        stream.extend(emit_server(&ServerPacket::Sync(SyncReply::Sync2 {
            name: "AMRISim".try_into().unwrap(),
            class: "Pioneer".try_into().unwrap(),
            subclass: "p3dx-sh".try_into().unwrap(),
        })));
        stream.extend(emit_server(&ServerPacket::Config(config::tests::p3dx())));
        let sip = sip::tests::amrisim_like();
        stream.extend(emit_server(&ServerPacket::Status(sip.clone())));
        stream.extend(emit_server(&ServerPacket::Reset { id: 0xFE }));
        for split in [1, 7, 64, stream.len()] {
            let mut c = WireArcos::default();
            let mut out = Vec::new();
            for chunk in stream.chunks(split) {
                c.decode(chunk, &mut out);
            }
            assert_eq!(out.len(), 5, "split {split}: {out:?}");
            assert_eq!(out[0], Incoming::SyncEcho(0));
            assert_eq!(
                out[1],
                Incoming::Identity(RobotIdentity {
                    name: "AMRISim".into(),
                    class: "Pioneer".into(),
                    subclass: "p3dx-sh".into(),
                })
            );
            let Incoming::Config(cfg) = &out[2] else {
                panic!("{:?}", out[2]);
            };
            assert_eq!(cfg.class, "Pioneer");
            assert_eq!(cfg.subclass, "p3dx-sh");
            assert_eq!(cfg.watchdog_ms, 2000);
            assert_eq!(cfg.auto_baud, 2);
            assert_eq!(cfg.trans_vel_top_mm_s, 2200);
            assert_eq!(cfg.firmware, "S.0");
            let Incoming::Status(s) = &out[3] else {
                panic!("{:?}", out[3]);
            };
            assert_eq!((s.x_pos, s.y_pos, s.th_pos), (1000, 0x7FF0, -1024));
            assert_eq!(s.battery_dv, 130);
            assert_eq!(s.flags, 0x001E);
            assert!(!s.motors_enabled());
            assert_eq!(out[4], Incoming::Reset { id: 0xFE });
            let stats = c.stats();
            assert_eq!(stats.packets, 5);
            assert_eq!(stats.junk_bytes, 5);
            assert_eq!(stats.bad_checksums, 0);
        }
    }

    #[test]
    fn corrupted_bytes_are_counted_never_decoded() {
        let mut frame = emit_server(&ServerPacket::Status(sip::tests::amrisim_like()));
        frame[10] ^= 0x40;
        let mut c = WireArcos::default();
        let mut out = Vec::new();
        c.decode(&frame, &mut out);
        assert!(out.is_empty());
        assert_eq!(c.stats().bad_checksums, 1);
        // Random bytes never panic.
        let junk: Vec<u8> = (0..4000u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        c.decode(&junk, &mut out);
    }

    fn cola(payload: &str) -> Vec<u8> {
        let mut out = vec![0x02];
        out.extend_from_slice(payload.as_bytes());
        out.push(0x03);
        out
    }

    #[test]
    fn connect_requests_are_the_clearpath_bytes() {
        let mut c = WireLms1xx::default();
        let mut out = Vec::new();
        c.encode(LaserRequest::SetAccessMode, &mut out);
        assert_eq!(out, cola("sMN SetAccessMode 03 F4724744"));
        out.clear();
        c.encode(LaserRequest::WriteScanDataConfig, &mut out);
        assert_eq!(out, cola("sWN LMDscandatacfg 01 00 1 1 0 00 00 0 0 0 0 +1"));
        out.clear();
        c.encode(LaserRequest::SubscribeScans(true), &mut out);
        assert_eq!(out, cola("sEN LMDscandata 1"));
    }

    #[test]
    fn replies_map_to_acks_states_refusals_and_scans() {
        let laser = LaserConfig::lms1xx();
        let mut c = WireLms1xx::default();
        let mut stream = cola("sAN SetAccessMode 1");
        stream.extend(cola("sRA STlms 7 0 8 16:36:54 8 17.03.2030 0 0 0"));
        stream.extend(cola("sAN LMCstartmeas 1"));
        stream.extend(b"junk");
        stream.extend(crate::wire::lms1xx::scandata::tests::lms1xx_telegram());
        stream.extend(cola("sEA LMDscandata 1"));
        let mut out = Vec::new();
        for chunk in stream.chunks(100) {
            c.decode(chunk, &laser, &mut out);
        }
        assert_eq!(out.len(), 5, "{out:?}");
        assert_eq!(out[0], LaserReply::Ack(LaserRequest::SetAccessMode));
        assert_eq!(out[1], LaserReply::State(7));
        assert!(matches!(
            &out[2],
            LaserReply::Refused { request: LaserRequest::StartMeasurement, detail } if detail.contains("status 1")
        ));
        let LaserReply::Scan(scan) = &out[3] else {
            panic!("{:?}", out[3]);
        };
        assert_eq!(scan.len(), 541);
        // First beam at -135°, every 100th value is 0 (no return), others 0.5 m + 1 cm/beam.
        assert!((scan.beams()[0].angle_rad + 135f32.to_radians()).abs() < 1e-4);
        assert_eq!(scan.beams()[0].range_m, None);
        assert!((scan.beams()[1].range_m.unwrap() - 0.51).abs() < 1e-4);
        assert_eq!(out[4], LaserReply::Ack(LaserRequest::SubscribeScans(true)));
        assert_eq!(c.stats().telegrams, 5);
        assert_eq!(c.stats().junk_bytes, 4);
    }

    #[test]
    fn a_laser_error_refuses_the_last_request() {
        let laser = LaserConfig::lms1xx();
        let mut c = WireLms1xx::default();
        let mut sent = Vec::new();
        c.encode(LaserRequest::Run, &mut sent);
        let mut out = Vec::new();
        c.decode(&cola("sFA 5"), &laser, &mut out);
        assert!(matches!(
            &out[..],
            [LaserReply::Refused { request: LaserRequest::Run, detail }] if detail.contains("sFA 5")
        ));
        c.decode(&cola("sSN LMDscandata garbage"), &laser, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(c.stats().bad_telegrams, 1);
    }
}
