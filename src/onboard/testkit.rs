//! Test doubles for the onboard runtime: a minimal ARCOS codec and a scripted fake robot.
//!
//! The framing follows fact sheet 1.1 (header FA FB, byte count, ID, int arguments 0x3B/0x1B
//! little-endian, big-endian checksum). The CONFIG and status payloads are SHORTENED test
//! layouts (only the fields the session reads, in a fixed order), not the firmware's: the real
//! layouts belong to `crate::wire::arcos`, which replaces this double once merged.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};
use tokio::time::Instant;

use super::arcos::{
    ArcosCodec, ClientCommand, CodecStats, ConfigHighlights, Incoming, RobotIdentity, RobotStatus,
};

/// Fact sheet 1.1 checksum.
pub fn checksum(data: &[u8]) -> u16 {
    let mut sum: u16 = 0;
    let mut chunks = data.chunks_exact(2);
    for pair in &mut chunks {
        sum = sum.wrapping_add(u16::from_be_bytes([pair[0], pair[1]]));
    }
    if let [last] = chunks.remainder() {
        sum ^= *last as u16;
    }
    sum
}

/// A complete frame with `id` and `payload`.
pub fn frame(id: u8, payload: &[u8]) -> Vec<u8> {
    let mut body = vec![id];
    body.extend_from_slice(payload);
    let c = checksum(&body);
    let mut out = vec![0xFA, 0xFB, (body.len() + 2) as u8];
    out.extend_from_slice(&body);
    out.extend_from_slice(&c.to_be_bytes());
    out
}

fn int_arg(v: i16) -> Vec<u8> {
    let mut out = vec![if v < 0 { 0x1B } else { 0x3B }];
    out.extend_from_slice(&(v.unsigned_abs()).to_le_bytes());
    out
}

/// Command number and argument of a client command.
pub fn command_parts(c: &ClientCommand) -> (u8, Option<i16>) {
    match *c {
        ClientCommand::Sync(n) => (n, None),
        ClientCommand::Pulse => (0, None),
        ClientCommand::Open => (1, Some(1)),
        ClientCommand::Close => (2, Some(1)),
        ClientCommand::Enable(on) => (4, Some(on as i16)),
        ClientCommand::SetA(v) => (5, Some(v)),
        ClientCommand::SetV(v) => (6, Some(v)),
        ClientCommand::SetO => (7, None),
        ClientCommand::SetRv(v) => (10, Some(v)),
        ClientCommand::Vel(v) => (11, Some(v)),
        ClientCommand::Config => (18, Some(1)),
        ClientCommand::RVel(v) => (21, Some(v)),
        ClientCommand::SetRa(v) => (23, Some(v)),
        ClientCommand::Stop => (29, None),
        ClientCommand::HostBaud(v) => (50, Some(v)),
        ClientCommand::BatteryInfo(v) => (62, Some(v)),
    }
}

/// Splits a byte stream into verified frames (ID, payload), counting junk and bad checksums.
#[derive(Default)]
pub struct Deframer {
    buf: Vec<u8>,
    /// Counters.
    pub stats: CodecStats,
}

impl Deframer {
    /// Feeds bytes; returns completed frames.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        loop {
            let Some(start) = self.buf.windows(2).position(|w| w == [0xFA, 0xFB]) else {
                let keep = usize::from(self.buf.last() == Some(&0xFA));
                let drop = self.buf.len() - keep;
                self.stats.junk_bytes += drop as u64;
                self.buf.drain(..drop);
                return out;
            };
            self.stats.junk_bytes += start as u64;
            self.buf.drain(..start);
            if self.buf.len() < 3 {
                return out;
            }
            let count = self.buf[2] as usize;
            if count < 3 {
                self.buf.drain(..2);
                self.stats.junk_bytes += 2;
                continue;
            }
            if self.buf.len() < 3 + count {
                return out;
            }
            let body = &self.buf[3..3 + count - 2];
            let got = u16::from_be_bytes([self.buf[1 + count], self.buf[2 + count]]);
            if checksum(body) == got {
                out.push((body[0], body[1..].to_vec()));
                self.stats.packets += 1;
                self.buf.drain(..3 + count);
            } else {
                self.stats.bad_checksums += 1;
                self.buf.drain(..2);
            }
        }
    }
}

/// The client-side test codec.
#[derive(Default)]
pub struct MiniArcos {
    deframer: Deframer,
}

fn cstrings(payload: &[u8], n: usize) -> Option<(Vec<String>, &[u8])> {
    let mut rest = payload;
    let mut out = Vec::new();
    for _ in 0..n {
        let end = rest.iter().position(|&b| b == 0)?;
        out.push(String::from_utf8_lossy(&rest[..end]).into_owned());
        rest = &rest[end + 1..];
    }
    Some((out, rest))
}

fn u16_at(p: &[u8], i: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*p.get(i)?, *p.get(i + 1)?]))
}

/// Parses a status payload in the shortened test layout.
pub fn parse_status(id: u8, p: &[u8]) -> Option<RobotStatus> {
    Some(RobotStatus {
        moving: id == 0x33,
        x_pos: u16_at(p, 0)?,
        y_pos: u16_at(p, 2)?,
        th_pos: u16_at(p, 4)? as i16,
        left_vel_mm_s: u16_at(p, 6)? as i16,
        right_vel_mm_s: u16_at(p, 8)? as i16,
        battery_dv: *p.get(10)?,
        stall_bumpers: u16_at(p, 11)?,
        flags: u16_at(p, 13)?,
    })
}

/// Encodes a status payload in the shortened test layout.
pub fn status_payload(s: &RobotStatus) -> Vec<u8> {
    let mut p = Vec::new();
    p.extend_from_slice(&s.x_pos.to_le_bytes());
    p.extend_from_slice(&s.y_pos.to_le_bytes());
    p.extend_from_slice(&s.th_pos.to_le_bytes());
    p.extend_from_slice(&s.left_vel_mm_s.to_le_bytes());
    p.extend_from_slice(&s.right_vel_mm_s.to_le_bytes());
    p.push(s.battery_dv);
    p.extend_from_slice(&s.stall_bumpers.to_le_bytes());
    p.extend_from_slice(&s.flags.to_le_bytes());
    p
}

/// Encodes a CONFIG payload in the shortened test layout.
pub fn config_payload(c: &ConfigHighlights) -> Vec<u8> {
    let mut p = Vec::new();
    for s in [&c.class, &c.subclass, &c.serial, &c.name, &c.firmware] {
        p.extend_from_slice(s.as_bytes());
        p.push(0);
    }
    for v in [
        c.rot_vel_top_deg_s,
        c.trans_vel_top_mm_s,
        c.rot_acc_top_deg_s2,
        c.trans_acc_top_mm_s2,
        c.watchdog_ms,
        c.rot_vel_max_deg_s,
        c.trans_vel_max_mm_s,
    ] {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&[c.sip_cycle_ms, c.host_baud_code, c.auto_baud]);
    p
}

fn parse_config(p: &[u8]) -> Option<ConfigHighlights> {
    let (s, rest) = cstrings(p, 5)?;
    let v = |i: usize| u16_at(rest, 2 * i);
    Some(ConfigHighlights {
        class: s[0].clone(),
        subclass: s[1].clone(),
        serial: s[2].clone(),
        name: s[3].clone(),
        firmware: s[4].clone(),
        rot_vel_top_deg_s: v(0)?,
        trans_vel_top_mm_s: v(1)?,
        rot_acc_top_deg_s2: v(2)?,
        trans_acc_top_mm_s2: v(3)?,
        watchdog_ms: v(4)?,
        rot_vel_max_deg_s: v(5)?,
        trans_vel_max_mm_s: v(6)?,
        sip_cycle_ms: *rest.get(14)?,
        host_baud_code: *rest.get(15)?,
        auto_baud: *rest.get(16)?,
    })
}

impl ArcosCodec for MiniArcos {
    fn encode(&mut self, command: &ClientCommand, out: &mut Vec<u8>) {
        let (number, arg) = command_parts(command);
        out.extend_from_slice(&frame(number, &arg.map(int_arg).unwrap_or_default()));
    }

    fn decode(&mut self, bytes: &[u8], out: &mut Vec<Incoming>) {
        for (id, payload) in self.deframer.feed(bytes) {
            let packet = match id {
                0 | 1 => Some(Incoming::SyncEcho(id)),
                2 => cstrings(&payload, 3).map(|(s, _)| {
                    Incoming::Identity(RobotIdentity {
                        name: s[0].clone(),
                        class: s[1].clone(),
                        subclass: s[2].clone(),
                    })
                }),
                0x20 => parse_config(&payload).map(Incoming::Config),
                0x32 | 0x33 => parse_status(id, &payload).map(Incoming::Status),
                0xFE | 0xFF => Some(Incoming::Reset { id }),
                _ => Some(Incoming::Other { id }),
            };
            match packet {
                Some(p) => out.push(p),
                None => self.deframer.stats.bad_payloads += 1,
            }
        }
    }

    fn reset(&mut self) {
        self.deframer.buf.clear();
    }

    fn stats(&self) -> CodecStats {
        self.deframer.stats
    }
}

/// How the fake robot behaves.
#[derive(Clone, Debug)]
pub struct FakeRobotScript {
    /// SYNC0 packets to ignore before answering.
    pub silent_syncs: u32,
    /// Reported class.
    pub class: String,
    /// Reported subclass.
    pub subclass: String,
    /// CONFIG AutoBaud.
    pub auto_baud: u8,
    /// Whether the robot answers after a HOSTBAUD (false: silent for 1.5 s, as if at the wrong
    /// speed, then back).
    pub baud_switch_works: bool,
    /// Streams status packets before the handshake (an old session still open) until CLOSE.
    pub already_open: bool,
    /// Whether a CONFIG request is answered.
    pub answers_config: bool,
    /// Status packet period.
    pub sip_period: Duration,
    /// Stop sending status packets after this many (None: never stop).
    pub sip_limit: Option<u32>,
    /// CONFIG Watchdog \[ms\].
    pub watchdog_ms: u16,
}

impl Default for FakeRobotScript {
    fn default() -> Self {
        Self {
            silent_syncs: 0,
            class: "Pioneer".into(),
            subclass: "p3dx-sh".into(),
            auto_baud: 2,
            baud_switch_works: true,
            already_open: false,
            answers_config: true,
            sip_period: Duration::from_millis(100),
            sip_limit: None,
            watchdog_ms: 2000,
        }
    }
}

/// What the fake robot received: (arrival time, command number, argument).
pub type CommandLog = Arc<Mutex<Vec<(Instant, u8, Option<i16>)>>>;

/// Parses a command frame's payload into its argument.
fn parse_arg(payload: &[u8]) -> Option<i16> {
    match payload {
        [0x3B, lo, hi, ..] => Some(u16::from_le_bytes([*lo, *hi]) as i16),
        [0x1B, lo, hi, ..] => Some(-(u16::from_le_bytes([*lo, *hi]) as i16)),
        _ => None,
    }
}

/// Runs a fake P3-DX on `stream` until the stream closes or CLOSE arrives after OPEN.
pub async fn run_fake_robot(mut stream: DuplexStream, script: FakeRobotScript, log: CommandLog) {
    let mut deframer = Deframer::default();
    let mut buf = [0u8; 256];
    let mut sync_state = 0u8;
    let mut silent_left = script.silent_syncs;
    let mut open = script.already_open;
    let mut connected = false;
    let mut status = RobotStatus {
        battery_dv: 130,
        ..RobotStatus::default()
    };
    let mut sips_sent = 0u32;
    let mut next_sip = Instant::now() + script.sip_period;
    let mut deaf_until: Option<Instant> = None;
    loop {
        tokio::select! {
            read = stream.read(&mut buf) => {
                let n = match read { Ok(0) | Err(_) => return, Ok(n) => n };
                for (number, payload) in deframer.feed(&buf[..n]) {
                    let now = Instant::now();
                    if deaf_until.is_some_and(|t| now < t) {
                        continue;
                    }
                    let arg = parse_arg(&payload);
                    log.lock().unwrap().push((now, number, arg));
                    let mut reply: Option<Vec<u8>> = None;
                    if !connected {
                        match number {
                            // An old session still open: SYNCs read as PULSE/OPEN.
                            0 | 1 if open => {}
                            2 if open && arg.is_none() => {}
                            0 if silent_left > 0 => silent_left -= 1,
                            0 => { sync_state = 1; reply = Some(frame(0, &[])); }
                            1 if sync_state == 1 => { sync_state = 2; reply = Some(frame(1, &[])); }
                            2 if open && arg.is_some() => { open = false; }
                            2 if sync_state == 2 => {
                                let mut p = Vec::new();
                                for s in ["fake", script.class.as_str(), script.subclass.as_str()] {
                                    p.extend_from_slice(s.as_bytes());
                                    p.push(0);
                                }
                                reply = Some(frame(2, &p));
                                connected = true;
                                sync_state = 3;
                            }
                            _ => { sync_state = 0; }
                        }
                    } else {
                        match number {
                            1 => { open = true; next_sip = now + script.sip_period; }
                            2 => { let _ = stream.shutdown().await; return; }
                            4 => { if arg == Some(1) { status.flags |= 1 } else { status.flags &= !1 } }
                            11 => status.left_vel_mm_s = arg.unwrap_or(0),
                            18 if script.answers_config => {
                                reply = Some(frame(0x20, &config_payload(&ConfigHighlights {
                                    class: script.class.clone(),
                                    subclass: script.subclass.clone(),
                                    serial: "TEST".into(),
                                    name: "fake".into(),
                                    firmware: "T.0".into(),
                                    rot_vel_top_deg_s: 300,
                                    trans_vel_top_mm_s: 1500,
                                    rot_acc_top_deg_s2: 300,
                                    trans_acc_top_mm_s2: 1000,
                                    watchdog_ms: script.watchdog_ms,
                                    rot_vel_max_deg_s: 100,
                                    trans_vel_max_mm_s: 750,
                                    sip_cycle_ms: 100,
                                    host_baud_code: 0,
                                    auto_baud: script.auto_baud,
                                })));
                            }
                            50 if !script.baud_switch_works => {
                                deaf_until = Some(now + Duration::from_millis(1500));
                            }
                            _ => {}
                        }
                    }
                    if let Some(bytes) = reply
                        && stream.write_all(&bytes).await.is_err()
                    {
                        return;
                    }
                }
            }
            _ = tokio::time::sleep_until(next_sip), if open => {
                next_sip += script.sip_period;
                let quiet = deaf_until.is_some_and(|t| Instant::now() < t);
                if !quiet && script.sip_limit.is_none_or(|l| sips_sent < l) {
                    sips_sent += 1;
                    status.x_pos = status.x_pos.wrapping_add(1) & 0x7FFF;
                    if stream.write_all(&frame(0x32, &status_payload(&status))).await.is_err() {
                        return;
                    }
                }
            }
        }
    }
}
