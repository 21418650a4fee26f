//! The client sessions' codecs over `crate::wire`: [`ArcosCodec`] (ARCOS, fact sheet section 1)
//! and [`WireLms1xx`] (SICK LMS1xx CoLa-A, fact sheet section 2).
//!
//! These hold no protocol knowledge of their own: framing, checksums, packet layouts and
//! resynchronisation are the wire module's ([`crate::wire::arcos::FrameDecoder`],
//! [`crate::wire::arcos::ServerPacket`], [`crate::wire::arcos::Command`],
//! [`crate::wire::lms1xx::ColaDecoder`], [`crate::wire::lms1xx::Reply`],
//! [`crate::wire::lms1xx::ScanTelegram`]). [`ArcosCodec`] speaks the wire's own types and adds
//! the link counters of the telemetry; [`WireLms1xx`] maps CoLa-A replies onto the laser
//! session's connect steps ([`super::laser`]) and turns scan telegrams into scans through
//! [`crate::sensor::telegram`].

use std::fmt;

use super::laser::{LaserCodec, LaserCodecStats, LaserReply, LaserRequest};
use crate::sensor::telegram::lms1xx_scan;
use crate::sensor::{LaserConfig, Scan};
use crate::wire::arcos::{Command, FrameDecoder, ServerPacket, command::MAX_COMMAND_LEN};
use crate::wire::lms1xx::{
    ColaDecoder, Dialect, Reply, Request, ScanDataConfig, ScanTelegram,
    command::check_reply,
    command::{ACCESS_LEVEL_AUTHORIZED_CLIENT, AUTHORIZED_CLIENT_PASSWORD},
    scandata::is_scan_data,
};

/// Decoder counters, for link statistics in the telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CodecStats {
    /// Well-formed packets decoded.
    pub packets: u64,
    /// Frames dropped for a bad checksum.
    pub bad_checksums: u64,
    /// Bytes skipped while hunting for a frame header.
    pub junk_bytes: u64,
    /// Frames with a good checksum whose payload did not parse.
    pub bad_payloads: u64,
}

impl fmt::Display for CodecStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} packets, {} bad checksums, {} junk bytes, {} bad payloads",
            self.packets, self.bad_checksums, self.junk_bytes, self.bad_payloads
        )
    }
}

/// The ARCOS client codec: [`Command`]s to frames, received bytes (any split, junk,
/// corruption) to [`ServerPacket`]s, with counters.
#[derive(Default)]
pub struct ArcosCodec {
    decoder: FrameDecoder,
    /// Frames with a good checksum whose payload did not parse.
    bad_payloads: u64,
}

impl ArcosCodec {
    /// Appends the complete frame of `command` to `out`.
    pub fn encode(&mut self, command: &Command, out: &mut Vec<u8>) {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        // The session's commands have int arguments in range: emitting cannot fail.
        if let Ok(n) = command.emit(&mut buf) {
            out.extend_from_slice(&buf[..n]);
        }
    }

    /// Feeds received bytes; appends every packet completed by them to `out`. A frame whose
    /// payload does not parse is counted, never returned. Never panics.
    pub fn decode(&mut self, bytes: &[u8], out: &mut Vec<ServerPacket>) {
        let mut input = bytes;
        while let Some(frame) = self.decoder.decode(&mut input) {
            match ServerPacket::parse(&frame) {
                Ok(p) => out.push(p),
                Err(_) => self.bad_payloads += 1,
            }
        }
    }

    /// Forgets any partial frame (after a baud change or a reconnect).
    pub fn reset(&mut self) {
        self.decoder.reset();
    }

    /// Counters since the codec was made.
    pub fn stats(&self) -> CodecStats {
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
            return Some(LaserReply::Scan(scan, Some(telegram.time_since_startup_us)));
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
    use crate::wire::arcos::{SyncReply, config, sip};

    fn emit_server(p: &ServerPacket) -> Vec<u8> {
        let mut buf = [0u8; crate::wire::arcos::frame::MAX_FRAME_LEN];
        let n = p.emit(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    #[test]
    fn commands_are_the_fact_sheet_bytes() {
        let mut c = ArcosCodec::default();
        let bytes = |c: &mut ArcosCodec, cmd| {
            let mut out = Vec::new();
            c.encode(&cmd, &mut out);
            out
        };
        // SYNC0 and STOP, fact sheet 1.1; OPEN with ARIA's int argument 1.
        assert_eq!(bytes(&mut c, Command::SYNC0), [0xFA, 0xFB, 3, 0, 0, 0]);
        assert_eq!(bytes(&mut c, Command::Stop), [0xFA, 0xFB, 3, 0x1D, 0, 0x1D]);
        let open = bytes(&mut c, Command::Open(Some(1)));
        assert_eq!(&open[..7], [0xFA, 0xFB, 6, 1, 0x3B, 1, 0]);
        // A negative argument uses the 0x1B type byte and the magnitude.
        let vel = bytes(&mut c, Command::Vel(-300));
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
            let mut c = ArcosCodec::default();
            let mut out = Vec::new();
            for chunk in stream.chunks(split) {
                c.decode(chunk, &mut out);
            }
            assert_eq!(out.len(), 5, "split {split}: {out:?}");
            assert_eq!(out[0], ServerPacket::Sync(SyncReply::Sync0));
            let ServerPacket::Sync(SyncReply::Sync2 {
                name,
                class,
                subclass,
            }) = &out[1]
            else {
                panic!("{:?}", out[1]);
            };
            assert_eq!(
                (name.as_str(), class.as_str(), subclass.as_str()),
                ("AMRISim", "Pioneer", "p3dx-sh")
            );
            let ServerPacket::Config(cfg) = &out[2] else {
                panic!("{:?}", out[2]);
            };
            assert_eq!(cfg.robot_type, "Pioneer");
            assert_eq!(cfg.subtype, "p3dx-sh");
            assert_eq!(cfg.watchdog_ms, 2000);
            assert_eq!(cfg.auto_baud, 2);
            assert_eq!(cfg.trans_vel_top, 2200);
            assert_eq!(
                cfg.extras.firmware_version.as_ref().map(|v| v.as_str()),
                Some("S.0")
            );
            let ServerPacket::Status(s) = &out[3] else {
                panic!("{:?}", out[3]);
            };
            assert_eq!((s.x_pos, s.y_pos, s.th_pos), (1000, 0x7FF0, -1024));
            assert_eq!(s.battery_dv, 130);
            assert_eq!(s.flags, 0x001E);
            assert!(!s.motors_enabled());
            assert_eq!(out[4], ServerPacket::Reset { id: 0xFE });
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
        let mut c = ArcosCodec::default();
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
        let LaserReply::Scan(scan, _) = &out[3] else {
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
