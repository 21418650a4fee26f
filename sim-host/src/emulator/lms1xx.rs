//! An emulated SICK LMS1xx speaking CoLa-A, sans-IO: bytes and time in, bytes out.
//!
//! Behaviour follows the protocol fact sheet, section 2 (the clearpath LMS1xx driver and
//! ARIA's LMS1xx client): every request of both connect sequences gets its success reply in a
//! single telegram; `sSN LMDscandata` telegrams stream only after `sEN LMDscandata 1`, at the
//! configured scan frequency, with one DIST1 channel in millimetres at scale 1.0 (0 when
//! nothing echoes within range), 541 beams over 270° at 0.5° by default.

use papillon::sensor::{LaserConfig, Scan};
use papillon::wire::lms1xx::{ColaDecoder, Reply, Request, ScanConfig, ScanTelegram};

/// Usable range of the emulated laser \[m\] (an LMS111 reaches 20 m).
pub const MAX_RANGE_M: f32 = 20.0;

/// The beam layout of an LMS1xx with `scan_config` (angles converted from SICK's frame, where
/// 90° is straight ahead), noise-free, mounted 55 mm ahead of the robot centre.
pub fn laser_config(scan_config: ScanConfig) -> LaserConfig {
    let res_deg = scan_config.resolution_deg_e4.max(1) as f32 / 1e4;
    let start_deg = scan_config.start_deg_e4 as f32 / 1e4 - 90.0;
    let span_deg = (scan_config.stop_deg_e4 - scan_config.start_deg_e4) as f32 / 1e4;
    let beams = (span_deg / res_deg).round() as i64 + 1;
    LaserConfig {
        beam_count: beams.clamp(1, papillon::sensor::MAX_BEAMS as i64) as u16,
        first_angle_rad: start_deg.to_radians(),
        step_rad: res_deg.to_radians(),
        max_range_m: MAX_RANGE_M,
        noise_fraction: 0.0,
        rate_hz: scan_config.frequency_centi_hz as f32 / 100.0,
        ..LaserConfig::lms1xx()
    }
}

/// The emulated laser's session state.
#[derive(Debug)]
pub struct Lms1xxEmulator {
    decoder: Box<ColaDecoder>,
    scan_config: ScanConfig,
    subscribed: bool,
    next_scan_s: f64,
    scan_counter: u16,
    requests: u64,
}

impl Default for Lms1xxEmulator {
    fn default() -> Self {
        Self::new()
    }
}

impl Lms1xxEmulator {
    /// A laser at the LMS1xx default configuration (50 Hz, 0.5°, −45° to 225°), not streaming.
    pub fn new() -> Self {
        Self {
            decoder: Box::new(ColaDecoder::new()),
            scan_config: ScanConfig::DEFAULT_50HZ,
            subscribed: false,
            next_scan_s: 0.0,
            scan_counter: 0,
            requests: 0,
        }
    }

    /// The current scan configuration.
    pub fn scan_config(&self) -> ScanConfig {
        self.scan_config
    }

    /// Whether `sSN LMDscandata` telegrams are streaming.
    pub fn subscribed(&self) -> bool {
        self.subscribed
    }

    /// Requests understood so far.
    pub fn requests(&self) -> u64 {
        self.requests
    }

    /// Feeds bytes from the client at `now_s` \[s\]; replies are appended to `out`. A polled
    /// scan (`sRN LMDscandata`) is answered with the scan `scan()` returns. Unknown telegrams
    /// are answered with `sFA 1`.
    pub fn receive(
        &mut self,
        now_s: f64,
        bytes: &[u8],
        mut scan: impl FnMut(LaserConfig) -> Scan,
        out: &mut Vec<u8>,
    ) {
        let mut input = bytes;
        while let Some(parsed) = self.decoder.decode(&mut input).map(Request::parse) {
            let Ok(request) = parsed else {
                emit_reply(out, &Reply::Error { code: 1 });
                continue;
            };
            self.requests += 1;
            match request {
                Request::SetScanConfig { config, .. } => self.scan_config = config,
                Request::SubscribeScanData(on) => {
                    // The first scan follows one period after the acknowledgement, so the
                    // reply arrives alone (the clearpath driver reads it with one short read).
                    self.subscribed = on;
                    self.next_scan_s = now_s + self.scan_period_s();
                }
                Request::PollScanData => {
                    let s = scan(laser_config(self.scan_config));
                    self.emit_scan(now_s, &s, true, out);
                    continue;
                }
                _ => {}
            }
            if let Some(reply) = Reply::success_for(&request, self.scan_config) {
                emit_reply(out, &reply);
            }
        }
    }

    /// Time between streamed scans \[s\].
    pub fn scan_period_s(&self) -> f64 {
        100.0 / self.scan_config.frequency_centi_hz.max(1) as f64
    }

    /// Whether a streamed scan is due at `now_s` \[s\].
    pub fn scan_due(&self, now_s: f64) -> bool {
        self.subscribed && now_s + 1e-9 >= self.next_scan_s
    }

    /// If a streamed scan is due at `now_s`, takes it with `scan` and appends its telegram.
    pub fn tick(&mut self, now_s: f64, scan: impl FnOnce(LaserConfig) -> Scan, out: &mut Vec<u8>) {
        if !self.scan_due(now_s) {
            return;
        }
        let period = self.scan_period_s();
        self.next_scan_s += period;
        if self.next_scan_s <= now_s {
            self.next_scan_s = now_s + period;
        }
        let s = scan(laser_config(self.scan_config));
        self.emit_scan(now_s, &s, false, out);
    }

    fn emit_scan(&mut self, now_s: f64, scan: &Scan, polled: bool, out: &mut Vec<u8>) {
        let ranges: Vec<u16> = scan
            .beams()
            .iter()
            .map(|b| match b.range_m {
                Some(r) => (r * 1000.0).round().clamp(0.0, u16::MAX as f32) as u16,
                None => 0,
            })
            .collect();
        let step = self.scan_config.resolution_deg_e4.min(u16::MAX as u32) as u16;
        let Ok(mut t) = ScanTelegram::with_distances(
            self.scan_config.start_deg_e4,
            step,
            self.scan_config.frequency_centi_hz,
            &ranges,
        ) else {
            return;
        };
        self.scan_counter = self.scan_counter.wrapping_add(1);
        t.polled = polled;
        t.serial_number = 0x0053_494D;
        t.telegram_counter = self.scan_counter;
        t.scan_counter = self.scan_counter;
        let us = (now_s * 1e6) as u32;
        t.time_since_startup_us = us;
        t.time_of_transmission_us = us;
        t.measurement_frequency = 0x168;
        let mut buf = vec![0u8; 16384];
        if let Ok(n) = t.emit(&mut buf) {
            out.extend_from_slice(&buf[..n]);
        }
    }
}

fn emit_reply(out: &mut Vec<u8>, reply: &Reply) {
    let mut buf = [0u8; 256];
    if let Ok(n) = reply.emit(&mut buf) {
        out.extend_from_slice(&buf[..n]);
    }
}
