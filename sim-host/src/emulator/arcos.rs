//! An emulated P3-DX microcontroller speaking ARCOS, sans-IO: bytes and time in, bytes out.
//!
//! Behaviour follows the protocol fact sheet, section 1 (Pioneer 3 operations manual, ARIA,
//! p2os and AMRISim behaviour): the SYNC0/1/2 handshake answered with name, class `Pioneer`
//! and subclass `p3dx-sh`; bare 0/1/2 packets read as SYNC before the connection and as
//! PULSE/OPEN/CLOSE after it; motors disabled until `ENABLE 1`; a status packet every 100 ms;
//! CONFIG and ENCODER packets on request; and the real firmware watchdog (no command for 2 s,
//! or the period set with [`ArcosEmulator::with_watchdog_ms`], halts the robot at its
//! deceleration; the next command resumes the last commanded motion).
//!
//! The emulator drives a [`RobotBody`] but does not step it: the caller advances the body
//! and calls [`ArcosEmulator::tick`] with the same clock.

use papillon::geometry::{Point2, Pose2};
use papillon::wire::arcos::sip::SonarReading;
use papillon::wire::arcos::{
    Command, ConfigPacket, EncoderPacket, FrameDecoder, Name, SipExtras, StatusPacket, SyncReply,
};

use crate::laser::cast_ray;
use crate::physics::RobotBody;
use crate::world::World;

/// Status packet period \[s\] (CONFIG SIPcycle 100 ms).
pub const SIP_PERIOD_S: f64 = 0.1;
/// Firmware watchdog period \[s\] (CONFIG Watchdog 2000 ms), the FLASH default.
pub const WATCHDOG_S: f64 = 2.0;
/// Largest sonar range reported \[mm\] (also reported when nothing echoes).
pub const SONAR_MAX_MM: u16 = 5000;
/// Absolute translational speed limit \[mm/s\] (CONFIG TransVelTop).
pub const TRANS_VEL_TOP_MM_S: i16 = 1200;
/// Absolute rotational speed limit \[deg/s\] (CONFIG RotVelTop).
pub const ROT_VEL_TOP_DEG_S: i16 = 300;
/// Mm/s per VEL2 unit on a P3-DX (Vel2Divisor).
pub const VEL2_DIVISOR_MM_S: f32 = 20.0;

/// Front sonar poses on a P3-DX-SH (x mm, y mm, heading deg), AriaCoda p3dx-sh.p (fact sheet
/// 1.9).
pub const FRONT_SONAR: [(f32, f32, f32); 8] = [
    (69.0, 136.0, 90.0),
    (114.0, 119.0, 50.0),
    (148.0, 78.0, 30.0),
    (166.0, 27.0, 10.0),
    (166.0, -27.0, -10.0),
    (148.0, -78.0, -30.0),
    (114.0, -119.0, -50.0),
    (69.0, -136.0, -90.0),
];

/// Where the emulated microcontroller is in its session with a client.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Link {
    /// No session; bare 0/1/2 packets are SYNC packets.
    Idle,
    /// SYNC2 answered; waiting for OPEN.
    Synced,
    /// OPEN received: status packets stream; bare 0/1/2 are PULSE/OPEN/CLOSE.
    Open,
}

/// The emulated microcontroller's state.
#[derive(Debug)]
pub struct ArcosEmulator {
    decoder: FrameDecoder,
    name: Name,
    link: Link,
    last_command_s: f64,
    watchdog_halted: bool,
    next_sip_s: f64,
    encoder_stream: bool,
    encoder_once: bool,
    speed_mm_s: f32,
    turn_deg_s: f32,
    max_speed_mm_s: i16,
    max_turn_deg_s: i16,
    accel_mm_s2: i16,
    decel_mm_s2: i16,
    turn_accel_deg_s2: i16,
    turn_decel_deg_s2: i16,
    sonar_on: bool,
    host_baud: u8,
    commands: u64,
    watchdog_trips: u64,
    watchdog_s: f64,
}

impl ArcosEmulator {
    /// An idle microcontroller that answers SYNC2 with `name` (cut to the name capacity).
    pub fn new(name: &str) -> Self {
        let mut n = Name::new();
        for c in name.chars() {
            if n.push(c).is_err() {
                break;
            }
        }
        Self {
            decoder: FrameDecoder::new(),
            name: n,
            link: Link::Idle,
            last_command_s: 0.0,
            watchdog_halted: false,
            next_sip_s: 0.0,
            encoder_stream: false,
            encoder_once: false,
            speed_mm_s: 0.0,
            turn_deg_s: 0.0,
            max_speed_mm_s: TRANS_VEL_TOP_MM_S,
            max_turn_deg_s: ROT_VEL_TOP_DEG_S,
            accel_mm_s2: 300,
            decel_mm_s2: 300,
            turn_accel_deg_s2: 100,
            turn_decel_deg_s2: 100,
            sonar_on: true,
            host_baud: 0,
            commands: 0,
            watchdog_trips: 0,
            watchdog_s: WATCHDOG_S,
        }
    }

    /// The same microcontroller with its FLASH watchdog set to `ms` milliseconds (the
    /// `Watchdog` parameter, changed with ARCOScf on a real robot; CONFIG reports it). Zero
    /// keeps the default.
    pub fn with_watchdog_ms(mut self, ms: u16) -> Self {
        if ms > 0 {
            self.watchdog_s = f64::from(ms) / 1000.0;
        }
        self
    }

    /// The watchdog period \[s\].
    pub fn watchdog_s(&self) -> f64 {
        self.watchdog_s
    }

    /// The session state.
    pub fn link(&self) -> Link {
        self.link
    }

    /// Whether the watchdog is holding the robot.
    pub fn watchdog_halted(&self) -> bool {
        self.watchdog_halted
    }

    /// How many times the watchdog has fired.
    pub fn watchdog_trips(&self) -> u64 {
        self.watchdog_trips
    }

    /// Valid command packets received.
    pub fn commands(&self) -> u64 {
        self.commands
    }

    /// The last HOSTBAUD code received (0 = 9600 … 4 = 115200); the emulator keeps no baud.
    pub fn host_baud(&self) -> u8 {
        self.host_baud
    }

    /// The current translational speed limit (SETV) \[mm/s\].
    pub fn max_speed_mm_s(&self) -> i16 {
        self.max_speed_mm_s
    }

    /// The current rotational speed limit (SETRV) \[deg/s\].
    pub fn max_turn_deg_s(&self) -> i16 {
        self.max_turn_deg_s
    }

    /// Ends the session as when the link drops: the robot stops and its motors are disabled.
    pub fn disconnect(&mut self, body: &mut RobotBody) {
        self.close(body);
    }

    /// Feeds bytes received from the client at time `now_s` \[s\]; replies are appended to
    /// `out`. Junk before a packet header and packets with bad checksums are skipped.
    pub fn receive(&mut self, now_s: f64, bytes: &[u8], body: &mut RobotBody, out: &mut Vec<u8>) {
        let mut input = bytes;
        while let Some(parsed) = self.decoder.decode(&mut input).map(|f| Command::parse(&f)) {
            // A well-framed packet with an argument the firmware does not accept is ignored,
            // but it still proves the client is alive.
            self.feed_watchdog(now_s, body);
            if let Ok(command) = parsed {
                self.commands += 1;
                self.handle(now_s, command, body, out);
            }
        }
    }

    /// Advances the emulator's clock to `now_s` \[s\]: fires the watchdog, and appends the
    /// status (and ENCODER) packets due to `out`. Sonar ranges are cast in `world` from the
    /// body's true pose.
    pub fn tick(&mut self, now_s: f64, world: &World, body: &mut RobotBody, out: &mut Vec<u8>) {
        if self.link != Link::Open {
            return;
        }
        if !self.watchdog_halted && now_s - self.last_command_s >= self.watchdog_s {
            self.watchdog_halted = true;
            self.watchdog_trips += 1;
            body.stop();
        }
        if now_s + 1e-9 >= self.next_sip_s {
            // Keep a steady cadence; after a long gap, restart it from now.
            self.next_sip_s += SIP_PERIOD_S;
            if self.next_sip_s <= now_s {
                self.next_sip_s = now_s + SIP_PERIOD_S;
            }
            let sip = self.status_packet(world, body);
            emit_into(out, |b| sip.emit(b).ok());
            if self.encoder_stream || self.encoder_once {
                self.encoder_once = false;
                let (left_ticks, right_ticks) = body.encoder_ticks();
                let packet = EncoderPacket {
                    left_ticks,
                    right_ticks,
                };
                emit_into(out, |b| packet.emit(b).ok());
            }
        }
    }

    /// The status packet describing `body` now.
    pub fn status_packet(&self, world: &World, body: &RobotBody) -> StatusPacket {
        let (left, right) = body.wheel_speeds_mm_s();
        let mut flags = 0u16;
        if body.motors_enabled() {
            flags |= 1;
        }
        if self.sonar_on {
            flags |= 1 << 1;
        }
        if body.e_stop() {
            flags |= 1 << 5;
        }
        let battery_dv = (body.battery_v() * 10.0).round().clamp(0.0, 255.0) as u16;
        let mut sonar = StatusPacket::default().sonar;
        if self.sonar_on {
            for (i, range_mm) in sonar_ranges_mm(world, body.true_pose()).iter().enumerate() {
                let _ = sonar.push(SonarReading {
                    number: i as u8,
                    range_mm: *range_mm,
                });
            }
        }
        let rot_ddeg = body.turn_deg_s() * 10.0;
        StatusPacket {
            moving: left.abs() > 0.5 || right.abs() > 0.5,
            x_pos: body.arcos_x(),
            y_pos: body.arcos_y(),
            th_pos: body.arcos_heading(),
            left_vel_mm_s: clamp_i16(left),
            right_vel_mm_s: clamp_i16(right),
            battery_dv: battery_dv as u8,
            stall_bumpers: body.arcos_stall_bumpers(),
            control: body.arcos_heading(),
            flags,
            compass: 0,
            sonar,
            extras: SipExtras {
                grip_state: Some(0),
                anport: Some(0),
                analog: Some(0),
                digin: Some(0xFF),
                digout: Some(0xFF),
                battery_dv_x10: Some(battery_dv),
                charge_state: Some(0),
                rot_vel_ddeg_s: Some(clamp_i16(rot_ddeg)),
                ..SipExtras::default()
            },
        }
    }

    /// The CONFIG packet (reply to CONFIG).
    pub fn config_packet(&self) -> ConfigPacket {
        let mut p = ConfigPacket {
            robot_type: name("Pioneer"),
            subtype: name("p3dx-sh"),
            serial: name("SIM"),
            rot_vel_top: ROT_VEL_TOP_DEG_S as u16,
            trans_vel_top: TRANS_VEL_TOP_MM_S as u16,
            rot_acc_top: 300,
            trans_acc_top: 1000,
            pwm_max: 1000,
            name: self.name.clone(),
            sip_cycle_ms: (SIP_PERIOD_S * 1000.0) as u8,
            host_baud: self.host_baud,
            front_sonar: 1,
            low_battery_dv: 110,
            rev_count: 16570,
            watchdog_ms: (self.watchdog_s * 1000.0).round() as u16,
            normal_mpacs: 1,
            rot_vel_max: self.max_turn_deg_s as u16,
            trans_vel_max: self.max_speed_mm_s as u16,
            rot_acc: self.turn_accel_deg_s2 as u16,
            rot_decel: self.turn_decel_deg_s2 as u16,
            trans_acc: self.accel_mm_s2 as u16,
            trans_decel: self.decel_mm_s2 as u16,
            front_bumps: 5,
            rear_bumps: 5,
            ..ConfigPacket::default()
        };
        p.sonar_cycle_ms = 40;
        p.auto_baud = 0;
        p
    }

    fn feed_watchdog(&mut self, now_s: f64, body: &mut RobotBody) {
        self.last_command_s = now_s;
        if self.watchdog_halted {
            self.watchdog_halted = false;
            body.command(self.speed_mm_s, self.turn_deg_s);
        }
    }

    fn handle(&mut self, now_s: f64, command: Command, body: &mut RobotBody, out: &mut Vec<u8>) {
        if self.link != Link::Open {
            self.handshake(now_s, command, body, out);
            return;
        }
        match command {
            Command::Pulse | Command::Open(_) => {}
            Command::Close(_) => self.close(body),
            Command::Enable(on) => {
                body.set_motors_enabled(on);
                if !on {
                    self.drive(body, 0.0, 0.0);
                }
            }
            Command::Vel(v) => {
                let turn = self.turn_deg_s;
                self.release_e_stop(body);
                self.drive(body, v as f32, turn);
            }
            Command::RVel(r) | Command::Rotate(r) => {
                let speed = self.speed_mm_s;
                self.release_e_stop(body);
                self.drive(body, speed, r as f32);
            }
            Command::Vel2 { left, right } => {
                self.release_e_stop(body);
                let (l, r) = (
                    left as f32 * VEL2_DIVISOR_MM_S,
                    right as f32 * VEL2_DIVISOR_MM_S,
                );
                let track_mm = body.config().track_m * 1000.0;
                let turn = ((r - l) / track_mm).to_degrees();
                self.drive(body, (l + r) / 2.0, turn);
            }
            Command::Stop => self.drive(body, 0.0, 0.0),
            Command::EStop => {
                self.drive(body, 0.0, 0.0);
                body.set_e_stop(true);
            }
            Command::SetV(v) => {
                self.max_speed_mm_s = v.clamp(0, TRANS_VEL_TOP_MM_S);
                let (s, t) = (self.speed_mm_s, self.turn_deg_s);
                self.drive(body, s, t);
            }
            Command::SetRv(v) => {
                self.max_turn_deg_s = v.clamp(0, ROT_VEL_TOP_DEG_S);
                let (s, t) = (self.speed_mm_s, self.turn_deg_s);
                self.drive(body, s, t);
            }
            Command::SetA(a) => {
                if a >= 0 {
                    self.accel_mm_s2 = a;
                } else {
                    self.decel_mm_s2 = a.saturating_neg();
                }
            }
            Command::SetRa(a) => {
                if a >= 0 {
                    self.turn_accel_deg_s2 = a;
                } else {
                    self.turn_decel_deg_s2 = a.saturating_neg();
                }
            }
            Command::HostBaud(code) => self.host_baud = code.clamp(0, 4) as u8,
            Command::Config(_) => {
                let p = self.config_packet();
                emit_into(out, |b| p.emit(b).ok());
            }
            Command::Encoder(mode) => match mode {
                0 => {
                    self.encoder_stream = false;
                    self.encoder_once = false;
                }
                1 => self.encoder_once = true,
                _ => self.encoder_stream = true,
            },
            Command::Sonar(on) => self.sonar_on = on,
            // Everything else (SAY, BATTERYINFO, PID values, ...) is accepted and ignored.
            _ => {}
        }
    }

    fn handshake(&mut self, now_s: f64, command: Command, body: &mut RobotBody, out: &mut Vec<u8>) {
        let sync = command.sync_number();
        match (self.link, sync, &command) {
            // After SYNC2, OPEN (bare as p2os sends it, or with ARIA's int 1) opens.
            (Link::Synced, Some(1), _) | (Link::Synced, None, Command::Open(_)) => {
                self.open(now_s, body);
            }
            // Out-of-sequence SYNC numbers are followed, as AMRISim does.
            (_, Some(n), _) => {
                let reply = match n {
                    0 => SyncReply::Sync0,
                    1 => SyncReply::Sync1,
                    _ => SyncReply::Sync2 {
                        name: self.name.clone(),
                        class: name("Pioneer"),
                        subclass: name("p3dx-sh"),
                    },
                };
                emit_into(out, |b| reply.emit(b).ok());
                self.link = if n == 2 { Link::Synced } else { Link::Idle };
            }
            // Anything else before the session is ignored (ARIA's CLOSE 1 included).
            _ => {}
        }
    }

    fn open(&mut self, now_s: f64, body: &mut RobotBody) {
        self.link = Link::Open;
        self.next_sip_s = now_s;
        self.last_command_s = now_s;
        self.watchdog_halted = false;
        self.encoder_stream = false;
        self.encoder_once = false;
        body.set_motors_enabled(false);
        body.set_e_stop(false);
        self.drive(body, 0.0, 0.0);
    }

    fn close(&mut self, body: &mut RobotBody) {
        self.link = Link::Idle;
        self.drive(body, 0.0, 0.0);
        body.set_motors_enabled(false);
        // Runtime settings revert to their defaults after a session.
        self.max_speed_mm_s = TRANS_VEL_TOP_MM_S;
        self.max_turn_deg_s = ROT_VEL_TOP_DEG_S;
    }

    fn release_e_stop(&mut self, body: &mut RobotBody) {
        if body.e_stop() {
            body.set_e_stop(false);
        }
    }

    /// Stores and applies a motion command, clamped to the SETV/SETRV limits.
    fn drive(&mut self, body: &mut RobotBody, speed_mm_s: f32, turn_deg_s: f32) {
        let vmax = self.max_speed_mm_s as f32;
        let rmax = self.max_turn_deg_s as f32;
        self.speed_mm_s = speed_mm_s.clamp(-vmax, vmax);
        self.turn_deg_s = turn_deg_s.clamp(-rmax, rmax);
        if !self.watchdog_halted {
            body.command(self.speed_mm_s, self.turn_deg_s);
        }
    }
}

/// Ranges \[mm\] of the 8 front sonars of a robot at `pose` in `world`, [`SONAR_MAX_MM`] when
/// nothing echoes.
pub fn sonar_ranges_mm(world: &World, pose: Pose2) -> [u16; 8] {
    let mut out = [SONAR_MAX_MM; 8];
    let max_m = SONAR_MAX_MM as f32 / 1000.0;
    for (o, (x_mm, y_mm, th_deg)) in out.iter_mut().zip(FRONT_SONAR) {
        let p = pose.compose(Pose2::new(
            x_mm / 1000.0,
            y_mm / 1000.0,
            th_deg.to_radians(),
        ));
        let origin = Point2::new(p.x, p.y);
        if let Some(r) = cast_ray(world, origin, p.theta, max_m) {
            *o = (r * 1000.0).round().clamp(0.0, SONAR_MAX_MM as f32) as u16;
        }
    }
    out
}

fn name(s: &str) -> Name {
    Name::try_from(s).unwrap_or_default()
}

fn clamp_i16(v: f32) -> i16 {
    v.round().clamp(i16::MIN as f32, i16::MAX as f32) as i16
}

fn emit_into(out: &mut Vec<u8>, emit: impl FnOnce(&mut [u8]) -> Option<usize>) {
    let mut buf = [0u8; 512];
    if let Some(n) = emit(&mut buf) {
        out.extend_from_slice(&buf[..n]);
    }
}
