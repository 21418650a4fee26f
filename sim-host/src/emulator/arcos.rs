//! An emulated P3-DX microcontroller speaking ARCOS, sans-IO: bytes and time in, bytes out.
//!
//! Behaviour follows the protocol fact sheet, section 1 (Pioneer 3 operations manual, ARIA,
//! p2os and AMRISim behaviour): the SYNC0/1/2 handshake answered with name, class `Pioneer`
//! and the emulated [`Subclass`]; bare 0/1/2 packets read as SYNC before the connection and as
//! PULSE/OPEN/CLOSE after it; motors disabled until `ENABLE 1`; a status packet every 100 ms;
//! CONFIG and ENCODER packets on request; and the real firmware watchdog (no command for 2 s,
//! or the period set with [`ArcosEmulator::with_watchdog_ms`], halts the robot at its top
//! deceleration; the next command resumes the last commanded motion).
//!
//! Motion runs on two independent channels, as on the firmware. Translation is either a
//! velocity (VEL) or a position move (MOVE: the commanded distance, at up to SETV, stopping at
//! the deceleration); rotation is either a velocity (RVEL, ROTATE) or a heading held by the
//! heading servo (HEAD absolute, DHEAD relative to the current heading, DCHEAD relative to the
//! current setpoint; at up to SETRV). A later VEL cancels a MOVE, a later RVEL cancels a HEAD,
//! and the other channel keeps going (ARIA drives with VEL and HEAD together). VEL2 puts both
//! channels in velocity mode, STOP and E_STOP set both to zero (E_STOP at once). SETA/SETRA set
//! the ramps the wheels follow; SETO zeroes the reported odometry.
//!
//! Identity ([`Identity`]): by default the emulator is a robot (a robot serial number in
//! CONFIG, the laser on its own link), which makes unmodified ARIA programs connect their
//! TCP/serial laser. As [`Identity::MobileSim`] it reports serial number `SIM`, as MobileSim
//! does, and sends the laser readings over the robot link in the simulator's packets 0x60/0x61
//! once the client asks with SIM_LRF_ENABLE (fact sheet section 5); the caller takes the scan
//! ([`ArcosEmulator::sim_laser_due`]) and the emulator frames it
//! ([`ArcosEmulator::sim_laser_packets`]).
//!
//! Positions are encoded with the subclass's DistConvFactor (`p3dx` 0.485, `p3dx-sh` 1.0): XPOS
//! and YPOS are millimetres divided by it and MOVE's argument is multiplied by it, as the old
//! AROS firmware does; velocities (VelConvFactor 1.0) and angles are the same on both.
//!
//! The emulator drives a [`RobotBody`] but does not step it: the caller advances the body
//! and calls [`ArcosEmulator::tick`] with the same clock.

use papillon::geometry::{Point2, Pose2, normalize_angle};
use papillon::sensor::{LaserConfig, Scan};
use papillon::units::rad_to_arcos_angle;
use papillon::wire::arcos::sip::SonarReading;
use papillon::wire::arcos::{
    Arg, Command, ConfigPacket, EncoderPacket, FrameDecoder, Name, SipExtras, StatusPacket,
    SyncReply, emit_frame,
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
/// Top translational acceleration \[mm/s²\] (CONFIG TransAccTop): the watchdog halts at it.
pub const TRANS_ACC_TOP_MM_S2: i16 = 1000;
/// Top rotational acceleration \[deg/s²\] (CONFIG RotAccTop): the watchdog halts at it.
pub const ROT_ACC_TOP_DEG_S2: i16 = 300;
/// Mm/s per VEL2 unit on a P3-DX (Vel2Divisor).
pub const VEL2_DIVISOR_MM_S: f32 = 20.0;
/// The serial number reported in CONFIG as a robot (anything but `SIM`, which ARIA reads as a
/// simulator).
pub const ROBOT_SERIAL: &str = "DX0000001";
/// The serial number MobileSim reports, by which ARIA recognises a simulator.
pub const SIMULATOR_SERIAL: &str = "SIM";
/// MobileSim's laser commands (fact sheet section 5): enable (0 off, 1 packets 0x60, 2 packets
/// 0x61), field of view start and end \[deg from the centre\], resolution \[deg\].
pub const SIM_LRF_ENABLE: u8 = 230;
/// See [`SIM_LRF_ENABLE`].
pub const SIM_LRF_SET_FOV_START: u8 = 231;
/// See [`SIM_LRF_ENABLE`].
pub const SIM_LRF_SET_FOV_END: u8 = 232;
/// See [`SIM_LRF_ENABLE`].
pub const SIM_LRF_SET_RES: u8 = 233;
/// Simulated laser packet IDs: basic (with pose) and extended (with reflectance).
pub const SIM_LASER_BASIC_ID: u8 = 0x60;
/// See [`SIM_LASER_BASIC_ID`].
pub const SIM_LASER_EXTENDED_ID: u8 = 0x61;
/// Largest range of the laser sent over the robot link \[m\].
pub const SIM_LASER_MAX_RANGE_M: f32 = 30.0;

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

/// What the emulator presents itself as (fact sheet section 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Identity {
    /// A robot: serial number [`ROBOT_SERIAL`]; the laser is on its own link.
    #[default]
    Robot,
    /// MobileSim: serial number `SIM`; the laser also comes over the robot link on request.
    MobileSim,
}

/// The P3-DX subclass named in SYNC2 and CONFIG, with its conversion factors (fact sheet 1.9
/// and section 5, ARIA's parameter files).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Subclass {
    /// `p3dx`: old AROS/P2OS firmware, DistConvFactor 0.485.
    P3dx,
    /// `p3dx-sh`: ARCOS, DistConvFactor 1.0.
    #[default]
    P3dxSh,
}

impl Subclass {
    /// The name sent in SYNC2 and CONFIG.
    pub fn name(self) -> &'static str {
        match self {
            Subclass::P3dx => "p3dx",
            Subclass::P3dxSh => "p3dx-sh",
        }
    }

    /// Millimetres per position unit (XPOS, YPOS, MOVE).
    pub fn dist_conv_factor(self) -> f64 {
        match self {
            Subclass::P3dx => 0.485,
            Subclass::P3dxSh => 1.0,
        }
    }

    /// Millimetres per second per velocity unit (VEL, wheel velocities): 1.0 on both.
    pub fn vel_conv_factor(self) -> f64 {
        1.0
    }
}

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

/// The translation channel.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Translation {
    /// VEL: drive at this speed \[mm/s\].
    Velocity(f32),
    /// MOVE: drive until the odometric path length (mean of the wheels) reaches this \[mm\].
    Move { target_mm: f64 },
}

/// The rotation channel.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rotation {
    /// RVEL/ROTATE: turn at this rate \[deg/s\].
    Velocity(f32),
    /// HEAD/DHEAD/DCHEAD: hold this odometric heading \[rad, raw odometry frame\].
    Heading(f32),
}

/// Distance from a MOVE target under which the move is done \[mm\].
const MOVE_DONE_MM: f64 = 1.0;
/// Heading error under which the heading servo commands no turn \[deg\].
const HEADING_DEADBAND_DEG: f32 = 0.2;

/// The emulated microcontroller's state.
#[derive(Debug)]
pub struct ArcosEmulator {
    decoder: FrameDecoder,
    name: Name,
    identity: Identity,
    subclass: Subclass,
    link: Link,
    last_command_s: f64,
    watchdog_halted: bool,
    next_sip_s: f64,
    encoder_stream: bool,
    encoder_once: bool,
    translation: Translation,
    rotation: Rotation,
    max_speed_mm_s: i16,
    max_turn_deg_s: i16,
    accel_mm_s2: i16,
    decel_mm_s2: i16,
    turn_accel_deg_s2: i16,
    turn_decel_deg_s2: i16,
    /// SETO: the raw odometry pose the reported odometry starts from.
    origin: Pose2,
    sonar_on: bool,
    host_baud: u8,
    commands: u64,
    watchdog_trips: u64,
    watchdog_s: f64,
    sim_laser: SimLaser,
}

/// MobileSim's laser over the robot link.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SimLaser {
    /// 0 off, 1 basic packets, 2 extended packets.
    mode: i16,
    fov_start_deg: i16,
    fov_end_deg: i16,
    res_deg: i16,
    /// A scan was sent in this SIP cycle already.
    due: bool,
}

impl Default for SimLaser {
    fn default() -> Self {
        Self {
            mode: 0,
            fov_start_deg: -90,
            fov_end_deg: 90,
            res_deg: 1,
            due: false,
        }
    }
}

impl ArcosEmulator {
    /// An idle `p3dx-sh` robot that answers SYNC2 with `name` (cut to the name capacity).
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
            identity: Identity::Robot,
            subclass: Subclass::P3dxSh,
            link: Link::Idle,
            last_command_s: 0.0,
            watchdog_halted: false,
            next_sip_s: 0.0,
            encoder_stream: false,
            encoder_once: false,
            translation: Translation::Velocity(0.0),
            rotation: Rotation::Velocity(0.0),
            max_speed_mm_s: TRANS_VEL_TOP_MM_S,
            max_turn_deg_s: ROT_VEL_TOP_DEG_S,
            accel_mm_s2: 300,
            decel_mm_s2: 300,
            turn_accel_deg_s2: 100,
            turn_decel_deg_s2: 100,
            origin: Pose2::default(),
            sonar_on: true,
            host_baud: 0,
            commands: 0,
            watchdog_trips: 0,
            watchdog_s: WATCHDOG_S,
            sim_laser: SimLaser::default(),
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

    /// The same microcontroller presenting itself as `identity`.
    pub fn with_identity(mut self, identity: Identity) -> Self {
        self.identity = identity;
        self
    }

    /// The same microcontroller as subclass `subclass` (its name and conversion factors).
    pub fn with_subclass(mut self, subclass: Subclass) -> Self {
        self.subclass = subclass;
        self
    }

    /// The identity presented.
    pub fn identity(&self) -> Identity {
        self.identity
    }

    /// The subclass emulated.
    pub fn subclass(&self) -> Subclass {
        self.subclass
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

    /// When the next status packet is due \[s\] (for a caller that sleeps until then).
    pub fn next_sip_s(&self) -> f64 {
        self.next_sip_s
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

    /// Advances the emulator's clock to `now_s` \[s\]: runs the position and heading servos,
    /// fires the watchdog, and appends the status (and ENCODER) packets due to `out`. Sonar
    /// ranges are cast in `world` from the body's true pose.
    pub fn tick(&mut self, now_s: f64, world: &World, body: &mut RobotBody, out: &mut Vec<u8>) {
        if self.link != Link::Open {
            return;
        }
        if !self.watchdog_halted && now_s - self.last_command_s >= self.watchdog_s {
            self.watchdog_halted = true;
            self.watchdog_trips += 1;
            // The watchdog halts at the top decelerations, not the client's ramps.
            let (t, r) = (TRANS_ACC_TOP_MM_S2 as f32, ROT_ACC_TOP_DEG_S2 as f32);
            body.set_accelerations(t, t, r, r);
            body.stop();
        }
        self.steer(body);
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
            self.sim_laser.due = self.sim_laser.mode > 0;
        }
    }

    /// As MobileSim, with the laser on the robot link enabled: the beam layout of the scan to
    /// send now (once per status cycle), else `None`. Take the scan from the robot's true pose
    /// and hand it to [`Self::sim_laser_packets`].
    pub fn sim_laser_due(&mut self) -> Option<LaserConfig> {
        if self.identity != Identity::MobileSim || self.link != Link::Open || !self.sim_laser.due {
            return None;
        }
        self.sim_laser.due = false;
        let l = self.sim_laser;
        let res = l.res_deg.max(1) as f32;
        let (start, end) = (
            l.fov_start_deg.min(l.fov_end_deg),
            l.fov_end_deg.max(l.fov_start_deg),
        );
        let count = ((end - start) as f32 / res).floor() as u16 + 1;
        Some(LaserConfig {
            beam_count: count,
            first_angle_rad: (start as f32).to_radians(),
            step_rad: res.to_radians(),
            max_range_m: SIM_LASER_MAX_RANGE_M,
            min_range_m: 0.0,
            noise_fraction: 0.0,
            mount: Pose2::default(),
            rate_hz: (1.0 / SIP_PERIOD_S) as f32,
        })
    }

    /// Appends `scan` as MobileSim's laser packets (0x60 with the reported pose, or 0x61 with
    /// reflectance, as SIM_LRF_ENABLE asked), split over frames with increasing first index.
    /// Beams with no return read the laser's largest range.
    pub fn sim_laser_packets(&self, scan: &Scan, body: &RobotBody, out: &mut Vec<u8>) {
        let max_mm = (SIM_LASER_MAX_RANGE_M * 1000.0) as u16;
        let ranges: Vec<u16> = scan
            .beams()
            .iter()
            .map(|b| {
                b.range_m.map_or(max_mm, |r| {
                    (r * 1000.0).round().clamp(0.0, max_mm as f32) as u16
                })
            })
            .collect();
        let total = ranges.len() as u16;
        let extended = self.sim_laser.mode >= 2;
        let per_packet = if extended { 35 } else { 80 };
        let (x, y, th) = self.reported_position(body);
        for (k, chunk) in ranges.chunks(per_packet).enumerate() {
            let mut payload = Vec::with_capacity(11 + chunk.len() * 5);
            if !extended {
                payload.extend_from_slice(&(x as i16).to_le_bytes());
                payload.extend_from_slice(&(y as i16).to_le_bytes());
                payload.extend_from_slice(&th.to_le_bytes());
            }
            payload.extend_from_slice(&total.to_le_bytes());
            payload.extend_from_slice(&((k * per_packet) as u16).to_le_bytes());
            payload.push(chunk.len() as u8);
            for r in chunk {
                payload.extend_from_slice(&r.to_le_bytes());
                if extended {
                    payload.extend_from_slice(&[0, 0, 0]);
                }
            }
            let id = if extended {
                SIM_LASER_EXTENDED_ID
            } else {
                SIM_LASER_BASIC_ID
            };
            emit_into(out, |b| emit_frame(b, id, &payload).ok());
        }
    }

    /// The status packet describing `body` now.
    pub fn status_packet(&self, world: &World, body: &RobotBody) -> StatusPacket {
        let (left, right) = body.wheel_speeds_mm_s();
        let vel = self.subclass.vel_conv_factor() as f32;
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
        let (x_pos, y_pos, th_pos) = self.reported_position(body);
        let control = match self.rotation {
            Rotation::Heading(raw) => arcos_angle(raw - self.origin.theta),
            Rotation::Velocity(_) => th_pos,
        };
        StatusPacket {
            moving: left.abs() > 0.5 || right.abs() > 0.5,
            x_pos,
            y_pos,
            th_pos,
            left_vel_mm_s: clamp_i16(left / vel),
            right_vel_mm_s: clamp_i16(right / vel),
            battery_dv: battery_dv as u8,
            stall_bumpers: body.arcos_stall_bumpers(),
            control,
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
        let serial = match self.identity {
            Identity::Robot => ROBOT_SERIAL,
            Identity::MobileSim => SIMULATOR_SERIAL,
        };
        let mut p = ConfigPacket {
            robot_type: name("Pioneer"),
            subtype: name(self.subclass.name()),
            serial: name(serial),
            rot_vel_top: ROT_VEL_TOP_DEG_S as u16,
            trans_vel_top: TRANS_VEL_TOP_MM_S as u16,
            rot_acc_top: ROT_ACC_TOP_DEG_S2 as u16,
            trans_acc_top: TRANS_ACC_TOP_MM_S2 as u16,
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

    /// XPOS, YPOS (position units of the subclass, modulo 0x8000) and THPOS (2π/4096) of the
    /// odometry since the last SETO.
    fn reported_position(&self, body: &RobotBody) -> (u16, u16, i16) {
        let rel = relative(self.origin, body.odometry_pose());
        let f = self.subclass.dist_conv_factor();
        let pos = |m: f32| ((f64::from(m) * 1000.0 / f).round() as i64).rem_euclid(0x8000) as u16;
        (pos(rel.x), pos(rel.y), arcos_angle(rel.theta))
    }

    fn feed_watchdog(&mut self, now_s: f64, body: &mut RobotBody) {
        self.last_command_s = now_s;
        if self.watchdog_halted {
            self.watchdog_halted = false;
            self.apply_ramps(body);
            self.steer(body);
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
                    self.halt();
                }
            }
            Command::Vel(v) => {
                self.release_e_stop(body);
                let vel = self.subclass.vel_conv_factor() as f32;
                self.translation = Translation::Velocity(v as f32 * vel);
            }
            Command::RVel(r) | Command::Rotate(r) => {
                self.release_e_stop(body);
                self.rotation = Rotation::Velocity(r as f32);
            }
            Command::Vel2 { left, right } => {
                self.release_e_stop(body);
                let (l, r) = (
                    left as f32 * VEL2_DIVISOR_MM_S,
                    right as f32 * VEL2_DIVISOR_MM_S,
                );
                let track_mm = body.config().track_m * 1000.0;
                self.translation = Translation::Velocity((l + r) / 2.0);
                self.rotation = Rotation::Velocity(((r - l) / track_mm).to_degrees());
            }
            Command::Move(d) => {
                self.release_e_stop(body);
                let mm = f64::from(d) * self.subclass.dist_conv_factor();
                self.translation = Translation::Move {
                    target_mm: path_mm(body) + mm,
                };
            }
            Command::Head(deg) => {
                self.release_e_stop(body);
                self.rotation = Rotation::Heading(self.origin.theta + (deg as f32).to_radians());
            }
            Command::DHead(deg) => {
                self.release_e_stop(body);
                let now = body.odometry_pose().theta;
                self.rotation = Rotation::Heading(now + (deg as f32).to_radians());
            }
            Command::DcHead(deg) => {
                self.release_e_stop(body);
                let setpoint = match self.rotation {
                    Rotation::Heading(h) => h,
                    Rotation::Velocity(_) => body.odometry_pose().theta,
                };
                self.rotation = Rotation::Heading(setpoint + (deg as f32).to_radians());
            }
            Command::Stop => self.halt(),
            Command::EStop => {
                self.halt();
                body.set_e_stop(true);
            }
            Command::SetO => {
                self.origin = body.odometry_pose();
            }
            Command::SetV(v) => self.max_speed_mm_s = v.clamp(0, TRANS_VEL_TOP_MM_S),
            Command::SetRv(v) => self.max_turn_deg_s = v.clamp(0, ROT_VEL_TOP_DEG_S),
            Command::SetA(a) if a != 0 => {
                let m = a.saturating_abs().min(TRANS_ACC_TOP_MM_S2);
                if a > 0 {
                    self.accel_mm_s2 = m;
                } else {
                    self.decel_mm_s2 = m;
                }
                if !self.watchdog_halted {
                    self.apply_ramps(body);
                }
            }
            Command::SetRa(a) if a != 0 => {
                let m = a.saturating_abs().min(ROT_ACC_TOP_DEG_S2);
                if a > 0 {
                    self.turn_accel_deg_s2 = m;
                } else {
                    self.turn_decel_deg_s2 = m;
                }
                if !self.watchdog_halted {
                    self.apply_ramps(body);
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
            Command::Other {
                number,
                arg: Arg::Int(v),
            } if self.identity == Identity::MobileSim => {
                let v = v.clamp(i16::MIN as i32, i16::MAX as i32) as i16;
                match number {
                    SIM_LRF_ENABLE => self.sim_laser.mode = v.clamp(0, 2),
                    SIM_LRF_SET_FOV_START => self.sim_laser.fov_start_deg = v.clamp(-180, 180),
                    SIM_LRF_SET_FOV_END => self.sim_laser.fov_end_deg = v.clamp(-180, 180),
                    SIM_LRF_SET_RES => self.sim_laser.res_deg = v.clamp(1, 90),
                    _ => {}
                }
            }
            // Everything else (SAY, BATTERYINFO, PID values, ...) is accepted and ignored.
            _ => {}
        }
        self.steer(body);
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
                        subclass: name(self.subclass.name()),
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
        self.sim_laser = SimLaser::default();
        body.set_motors_enabled(false);
        body.set_e_stop(false);
        self.apply_ramps(body);
        self.halt();
        self.steer(body);
    }

    fn close(&mut self, body: &mut RobotBody) {
        self.link = Link::Idle;
        self.halt();
        self.watchdog_halted = false;
        body.stop();
        body.set_motors_enabled(false);
        // Runtime settings revert to their defaults after a session.
        let defaults = Self::new("");
        self.max_speed_mm_s = defaults.max_speed_mm_s;
        self.max_turn_deg_s = defaults.max_turn_deg_s;
        self.accel_mm_s2 = defaults.accel_mm_s2;
        self.decel_mm_s2 = defaults.decel_mm_s2;
        self.turn_accel_deg_s2 = defaults.turn_accel_deg_s2;
        self.turn_decel_deg_s2 = defaults.turn_decel_deg_s2;
        self.sim_laser = SimLaser::default();
        self.apply_ramps(body);
    }

    fn release_e_stop(&mut self, body: &mut RobotBody) {
        if body.e_stop() {
            body.set_e_stop(false);
        }
    }

    /// Both channels to zero velocity (STOP).
    fn halt(&mut self) {
        self.translation = Translation::Velocity(0.0);
        self.rotation = Rotation::Velocity(0.0);
    }

    fn apply_ramps(&self, body: &mut RobotBody) {
        body.set_accelerations(
            self.accel_mm_s2 as f32,
            self.decel_mm_s2 as f32,
            self.turn_accel_deg_s2 as f32,
            self.turn_decel_deg_s2 as f32,
        );
    }

    /// Runs the translation and rotation channels and commands the wheels, within the
    /// SETV/SETRV limits (unless the watchdog holds the robot).
    fn steer(&mut self, body: &mut RobotBody) {
        let vmax = self.max_speed_mm_s as f32;
        let rmax = self.max_turn_deg_s as f32;
        let speed = match self.translation {
            Translation::Velocity(v) => v,
            Translation::Move { target_mm } => {
                let remaining = target_mm - path_mm(body);
                if remaining.abs() < MOVE_DONE_MM {
                    self.translation = Translation::Velocity(0.0);
                    0.0
                } else {
                    // The fastest speed that still stops at the target at the deceleration.
                    let decel = f64::from(self.decel_mm_s2.max(1)) * 0.9;
                    let v = (2.0 * decel * remaining.abs()).sqrt() as f32;
                    v.min(vmax).copysign(remaining as f32)
                }
            }
        };
        let turn = match self.rotation {
            Rotation::Velocity(r) => r,
            Rotation::Heading(target) => {
                let err_deg = normalize_angle(target - body.odometry_pose().theta).to_degrees();
                if err_deg.abs() < HEADING_DEADBAND_DEG {
                    0.0
                } else {
                    let decel = self.turn_decel_deg_s2.max(1) as f32 * 0.9;
                    let r = (2.0 * decel * err_deg.abs()).sqrt();
                    r.min(rmax).copysign(err_deg)
                }
            }
        };
        if !self.watchdog_halted {
            body.command(speed.clamp(-vmax, vmax), turn.clamp(-rmax, rmax));
        }
    }
}

/// The odometric path length of `body`: the mean of its wheels' travel \[mm\].
fn path_mm(body: &RobotBody) -> f64 {
    let (l, r) = body.encoder_ticks();
    (f64::from(l) + f64::from(r)) / 2.0 / f64::from(body.config().ticks_per_mm)
}

/// `pose` seen from `origin`.
fn relative(origin: Pose2, pose: Pose2) -> Pose2 {
    let (s, c) = origin.theta.sin_cos();
    let (dx, dy) = (pose.x - origin.x, pose.y - origin.y);
    Pose2::new(c * dx + s * dy, -s * dx + c * dy, pose.theta - origin.theta)
}

/// An angle \[rad\] in ARCOS units (2π/4096), in (-2048, 2048].
fn arcos_angle(a: f32) -> i16 {
    let u = rad_to_arcos_angle(normalize_angle(a)).round() as i32;
    (if u <= -2048 { u + 4096 } else { u }) as i16
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
