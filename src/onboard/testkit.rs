//! A scripted fake P3-DX for the onboard runtime's tests.
//!
//! It reads the client's command frames on its own (fact sheet 1.1: header FA FB, byte count,
//! ID, int arguments 0x3B/0x1B little-endian, big-endian checksum) and logs them as command
//! number and argument; it answers with the real packets of `crate::wire::arcos` (SYNC
//! replies, CONFIG, status packets), so the session under test decodes what a robot sends.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};
use tokio::time::Instant;

use super::codec::CodecStats;
use crate::wire::arcos::{ConfigPacket, Name, ServerPacket, StatusPacket, SyncReply};

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

/// A server packet's complete frame.
fn packet(p: &ServerPacket) -> Vec<u8> {
    let mut buf = [0u8; crate::wire::arcos::frame::MAX_FRAME_LEN];
    let n = p.emit(&mut buf).expect("a test packet fits a frame");
    buf[..n].to_vec()
}

fn name(s: &str) -> Name {
    Name::try_from(s).expect("a short test name")
}

/// The fake robot's CONFIG packet.
fn config_packet(script: &FakeRobotScript) -> ConfigPacket {
    let mut c = crate::wire::arcos::config::tests::p3dx();
    c.robot_type = name(&script.class);
    c.subtype = name(&script.subclass);
    c.serial = name("TEST");
    c.name = name("fake");
    c.extras.firmware_version = Some(name("T.0"));
    c.rot_vel_top = 300;
    c.trans_vel_top = 1500;
    c.rot_acc_top = 300;
    c.trans_acc_top = 1000;
    c.watchdog_ms = script.watchdog_ms;
    c.rot_vel_max = 100;
    c.trans_vel_max = 750;
    c.sip_cycle_ms = 100;
    c.host_baud = 0;
    c.auto_baud = script.auto_baud;
    c
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
    /// CONFIG requests to ignore before answering (as if their replies were corrupted).
    pub lost_configs: u32,
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
            lost_configs: 0,
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
    let mut configs_to_lose = script.lost_configs;
    let mut open = script.already_open;
    let mut connected = false;
    let mut status = StatusPacket {
        battery_dv: 130,
        ..StatusPacket::default()
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
                            0 => { sync_state = 1; reply = Some(packet(&ServerPacket::Sync(SyncReply::Sync0))); }
                            1 if sync_state == 1 => { sync_state = 2; reply = Some(packet(&ServerPacket::Sync(SyncReply::Sync1))); }
                            2 if open && arg.is_some() => { open = false; }
                            2 if sync_state == 2 => {
                                reply = Some(packet(&ServerPacket::Sync(SyncReply::Sync2 {
                                    name: name("fake"),
                                    class: name(&script.class),
                                    subclass: name(&script.subclass),
                                })));
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
                            18 if configs_to_lose > 0 => configs_to_lose -= 1,
                            18 if script.answers_config => {
                                reply = Some(packet(&ServerPacket::Config(config_packet(&script))));
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
                    if stream.write_all(&packet(&ServerPacket::Status(status.clone()))).await.is_err() {
                        return;
                    }
                }
            }
        }
    }
}
