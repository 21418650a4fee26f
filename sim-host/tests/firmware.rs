//! The emulated firmware as an independent client sees it: every frame in these tests is built
//! and checked by hand from the protocol fact sheet (ARCOS section 1, LMS200 section 3), not
//! with the project's codecs, so a shared misreading of the protocol cannot make them pass.
//!
//! Motion commands (MOVE, HEAD, DHEAD, DCHEAD, VEL, RVEL, VEL2, STOP, SETV), how a later
//! velocity cancels a position command, the watchdog's halt, the subclass's DistConvFactor,
//! the identity in CONFIG, MobileSim's laser packets, and the LMS200's configuration sequence.

use papillon_sim::emulator::arcos::{ArcosEmulator, Identity, Subclass};
use papillon_sim::emulator::lms200::Lms200Emulator;
use papillon_sim::physics::{BodyConfig, RobotBody, SlipConfig};
use papillon_sim::serve::MAP_RESOLUTION_M;
use papillon_sim::world::World;

// ---------------------------------------------------------------- ARCOS by hand

/// The ARCOS checksum: big-endian 16-bit words summed, an odd last byte XORed into the low byte.
fn arcos_checksum(data: &[u8]) -> u16 {
    let mut sum: u16 = 0;
    let mut pairs = data.chunks_exact(2);
    for p in &mut pairs {
        sum = sum.wrapping_add(u16::from(p[0]) << 8 | u16::from(p[1]));
    }
    if let [last] = pairs.remainder() {
        sum ^= u16::from(*last);
    }
    sum
}

/// A command frame: FA FB, count, number, [argument], checksum (high byte first).
fn frame(number: u8, arg: Option<i32>) -> Vec<u8> {
    let mut body = vec![number];
    if let Some(v) = arg {
        body.push(if v < 0 { 0x1B } else { 0x3B });
        let m = v.unsigned_abs() as u16;
        body.extend_from_slice(&m.to_le_bytes());
    }
    let sum = arcos_checksum(&body);
    let mut f = vec![0xFA, 0xFB, (body.len() + 2) as u8];
    f.extend_from_slice(&body);
    f.extend_from_slice(&sum.to_be_bytes());
    f
}

/// A server packet: its ID and the bytes after it (checksum checked and removed).
fn packets(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 3 <= bytes.len() {
        assert_eq!(&bytes[i..i + 2], &[0xFA, 0xFB], "header at {i}");
        let n = bytes[i + 2] as usize;
        let body = &bytes[i + 3..i + 3 + n - 2];
        let sum = u16::from_be_bytes([bytes[i + 1 + n], bytes[i + 2 + n]]);
        assert_eq!(
            sum,
            arcos_checksum(body),
            "checksum of packet {:#x}",
            body[0]
        );
        out.push((body[0], body[1..].to_vec()));
        i += 3 + n;
    }
    assert_eq!(i, bytes.len(), "trailing bytes");
    out
}

/// The fields of a status packet this test reads (offsets after the ID, fact sheet 1.6).
#[derive(Clone, Copy, Debug)]
struct Sip {
    x: u16,
    th: i16,
    left_mm_s: i16,
    right_mm_s: i16,
    control: i16,
}

fn sip(payload: &[u8]) -> Sip {
    let u = |o: usize| u16::from_le_bytes([payload[o], payload[o + 1]]);
    Sip {
        x: u(0) & 0x7FFF,
        th: u(4) as i16,
        left_mm_s: u(6) as i16,
        right_mm_s: u(8) as i16,
        control: u(13) as i16,
    }
}

/// The NUL-terminated strings of a SYNC2 reply or a CONFIG's leading fields.
fn strings(payload: &[u8], count: usize) -> Vec<String> {
    payload
        .split(|b| *b == 0)
        .take(count)
        .map(|s| String::from_utf8_lossy(s).into_owned())
        .collect()
}

/// THPOS units (2π/4096) per degree.
const UNITS_PER_DEG: f64 = 4096.0 / 360.0;

/// Emulator, robot and a 10 ms clock; the robot has no slip, so odometry is the truth.
struct Robot {
    world: World,
    body: RobotBody,
    emu: ArcosEmulator,
    now_s: f64,
    last: Option<Sip>,
}

impl Robot {
    fn new(emu: ArcosEmulator) -> Self {
        let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
        let config = BodyConfig {
            slip: SlipConfig::none(),
            ..BodyConfig::default()
        };
        let body = RobotBody::new(config, world.start(), 3);
        Self {
            world,
            body,
            emu,
            now_s: 0.0,
            last: None,
        }
    }

    fn send(&mut self, bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        let mut out = Vec::new();
        self.emu
            .receive(self.now_s, bytes, &mut self.body, &mut out);
        packets(&out)
    }

    /// Runs `dt_s`, sending a PULSE every 0.5 s when `pulse`.
    fn run(&mut self, dt_s: f64, pulse: bool) {
        let end = self.now_s + dt_s;
        let mut next_pulse = self.now_s + 0.5;
        while self.now_s < end - 1e-9 {
            self.now_s += 0.01;
            self.body.advance(0.01, &self.world, &[]);
            if pulse && self.now_s >= next_pulse {
                next_pulse += 0.5;
                self.send(&frame(0, None));
            }
            let mut out = Vec::new();
            self.emu
                .tick(self.now_s, &self.world, &mut self.body, &mut out);
            for (id, payload) in packets(&out) {
                if id == 0x32 || id == 0x33 {
                    self.last = Some(sip(&payload));
                }
            }
        }
    }

    /// SYNC0, SYNC1, SYNC2 (returns SYNC2's strings), OPEN 1, ENABLE 1.
    fn connect(&mut self) -> Vec<String> {
        assert_eq!(self.send(&frame(0, None))[0].0, 0);
        assert_eq!(self.send(&frame(1, None))[0].0, 1);
        let sync2 = self.send(&frame(2, None));
        assert_eq!(sync2[0].0, 2);
        assert!(self.send(&frame(1, Some(1))).is_empty());
        self.send(&frame(4, Some(1)));
        self.run(0.2, true);
        strings(&sync2[0].1, 3)
    }

    fn sip(&self) -> Sip {
        self.last.expect("a status packet")
    }

    fn heading_deg(&self) -> f64 {
        f64::from(self.sip().th) / UNITS_PER_DEG
    }
}

fn angle_diff_deg(a: f64, b: f64) -> f64 {
    (a - b + 540.0).rem_euclid(360.0) - 180.0
}

#[test]
fn move_drives_the_commanded_distance_forward_and_back() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    let x0 = r.body.true_pose().x;
    r.send(&frame(8, Some(1000))); // MOVE 1000 mm
    r.run(1.0, true);
    assert!(r.sip().left_mm_s > 100, "moving: {:?}", r.sip());
    r.run(6.0, true);
    let s = r.sip();
    assert_eq!((s.left_mm_s, s.right_mm_s), (0, 0), "stopped at the end");
    assert!(s.x.abs_diff(1000) <= 10, "XPOS {}", s.x);
    assert!(((r.body.true_pose().x - x0) * 1000.0 - 1000.0).abs() <= 10.0);

    r.send(&frame(8, Some(-400))); // MOVE -400 mm
    r.run(5.0, true);
    assert!(r.sip().x.abs_diff(600) <= 10, "XPOS {}", r.sip().x);
}

#[test]
fn setv_limits_a_move() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    r.send(&frame(6, Some(100))); // SETV 100 mm/s
    r.send(&frame(8, Some(2000)));
    r.run(3.0, true);
    let s = r.sip();
    assert!(s.left_mm_s.abs_diff(100) <= 2, "{s:?}");
}

#[test]
fn head_dhead_and_dchead_reach_their_headings() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    r.send(&frame(12, Some(90))); // HEAD 90
    r.run(4.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), 90.0).abs() < 1.0,
        "{}",
        r.heading_deg()
    );
    // CONTROL is the heading setpoint.
    assert!((f64::from(r.sip().control) / UNITS_PER_DEG - 90.0).abs() < 0.2);
    assert_eq!((r.sip().left_mm_s, r.sip().right_mm_s), (0, 0));

    r.send(&frame(13, Some(-135))); // DHEAD -135: to -45
    r.run(5.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), -45.0).abs() < 1.0,
        "{}",
        r.heading_deg()
    );

    r.send(&frame(22, Some(30))); // DCHEAD +30 from the setpoint: to -15
    r.run(3.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), -15.0).abs() < 1.0,
        "{}",
        r.heading_deg()
    );

    r.send(&frame(12, Some(180))); // HEAD 180: the short way round
    r.run(5.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), 180.0).abs() < 1.0,
        "{}",
        r.heading_deg()
    );
}

#[test]
fn rvel_cancels_a_head_vel_cancels_a_move_and_each_leaves_the_other_channel() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    // VEL with HEAD, as ARIA's actions drive: the robot turns to the heading while driving.
    r.send(&frame(11, Some(200)));
    r.send(&frame(12, Some(90)));
    r.run(4.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), 90.0).abs() < 1.0,
        "{}",
        r.heading_deg()
    );
    assert!(
        r.sip().left_mm_s.abs_diff(200) <= 2,
        "VEL kept: {:?}",
        r.sip()
    );

    // A later RVEL cancels the HEAD: the robot turns on past where HEAD would stop it.
    r.send(&frame(13, Some(90))); // DHEAD +90: to 180
    r.run(0.5, true);
    r.send(&frame(21, Some(0))); // RVEL 0
    r.run(2.0, true);
    let h = r.heading_deg();
    assert!(
        angle_diff_deg(h, 180.0).abs() > 20.0,
        "HEAD not cancelled: {h}"
    );
    r.run(1.0, true);
    assert!(
        angle_diff_deg(r.heading_deg(), h).abs() < 0.5,
        "turning on after RVEL 0"
    );
    assert!(
        r.sip().left_mm_s.abs_diff(200) <= 2,
        "VEL kept: {:?}",
        r.sip()
    );

    // A later VEL cancels a MOVE.
    r.send(&frame(29, None)); // STOP
    r.run(2.0, true);
    assert_eq!((r.sip().left_mm_s, r.sip().right_mm_s), (0, 0));
    let x0 = r.body.odometry_pose();
    r.send(&frame(8, Some(3000)));
    r.run(1.5, true);
    r.send(&frame(11, Some(0))); // VEL 0
    r.run(3.0, true);
    let travelled = (r.body.odometry_pose().position().distance(x0.position()) * 1000.0) as f64;
    assert!((200.0..1500.0).contains(&travelled), "{travelled} mm");
    assert_eq!((r.sip().left_mm_s, r.sip().right_mm_s), (0, 0));

    // And a later MOVE or HEAD cancels a VEL or RVEL.
    r.send(&frame(11, Some(300)));
    r.send(&frame(21, Some(20)));
    r.run(1.0, true);
    r.send(&frame(8, Some(0)));
    r.send(&frame(13, Some(0)));
    r.run(2.0, true);
    assert_eq!((r.sip().left_mm_s, r.sip().right_mm_s), (0, 0));
}

#[test]
fn vel2_drives_the_wheels_and_stop_halts_both_channels() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    // VEL2: right 10 units (200 mm/s) in the low byte, left 5 (100 mm/s) in the high byte.
    r.send(&frame(32, Some(5 << 8 | 10)));
    r.run(2.0, true);
    let s = r.sip();
    assert!(
        s.left_mm_s.abs_diff(100) <= 3 && s.right_mm_s.abs_diff(200) <= 3,
        "{s:?}"
    );
    r.send(&frame(29, None));
    r.run(2.0, true);
    let s = r.sip();
    assert_eq!((s.left_mm_s, s.right_mm_s), (0, 0));
}

#[test]
fn the_watchdog_stops_the_wheels_within_two_and_a_half_seconds_of_silence() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.connect();
    r.send(&frame(11, Some(300)));
    r.run(2.0, true);
    assert!(r.body.speed_mm_s() > 290.0);
    r.send(&frame(11, Some(300))); // the last command
    let silent_from = r.now_s;
    r.run(1.9, false);
    assert!(
        r.body.speed_mm_s() > 290.0,
        "still driving before the watchdog"
    );
    while r.now_s - silent_from < 2.5 {
        r.run(0.01, false);
    }
    assert_eq!(
        r.body.speed_mm_s(),
        0.0,
        "wheels stopped by 2.5 s of silence"
    );
    assert_eq!((r.sip().left_mm_s, r.sip().right_mm_s), (0, 0));
    // The next command resumes the commanded motion.
    r.send(&frame(0, None));
    r.run(2.0, true);
    assert!(r.body.speed_mm_s() > 290.0);
}

#[test]
fn motors_are_disabled_until_enable() {
    let mut r = Robot::new(ArcosEmulator::new("t"));
    r.send(&frame(0, None));
    r.send(&frame(1, None));
    r.send(&frame(2, None));
    r.send(&frame(1, Some(1)));
    r.send(&frame(11, Some(300)));
    r.run(1.0, true);
    assert!(!r.body.motors_enabled());
    assert_eq!(r.body.speed_mm_s(), 0.0);
    r.send(&frame(4, Some(1)));
    r.run(1.5, true);
    assert!(r.body.speed_mm_s() > 290.0);
}

#[test]
fn a_p3dx_reports_positions_in_its_own_units_and_a_p3dx_sh_in_millimetres() {
    for (subclass, factor) in [(Subclass::P3dx, 0.485), (Subclass::P3dxSh, 1.0)] {
        let mut r = Robot::new(ArcosEmulator::new("t").with_subclass(subclass));
        let sync2 = r.connect();
        assert_eq!(sync2[1], "Pioneer");
        assert_eq!(sync2[2], subclass.name());
        let config = r.send(&frame(18, Some(1)));
        assert_eq!(config[0].0, 0x20);
        assert_eq!(strings(&config[0].1, 3)[1], subclass.name());
        let x0 = r.body.true_pose().x;
        // MOVE 600 units: 600 × factor mm.
        r.send(&frame(8, Some(600)));
        r.run(5.0, true);
        let true_mm = f64::from(r.body.true_pose().x - x0) * 1000.0;
        assert!(
            (true_mm - 600.0 * factor).abs() <= 8.0,
            "{subclass:?}: {true_mm} mm"
        );
        // XPOS counts units of the factor.
        let reported_mm = f64::from(r.sip().x) * factor;
        assert!(
            (reported_mm - true_mm).abs() <= 8.0,
            "{subclass:?}: {reported_mm} mm"
        );
        // Velocities are mm/s on both.
        r.send(&frame(11, Some(250)));
        r.run(2.0, true);
        assert!(r.sip().left_mm_s.abs_diff(250) <= 2);
    }
}

#[test]
fn the_identity_decides_the_serial_number_and_the_laser_over_the_robot_link() {
    let serial = |identity| {
        let mut r = Robot::new(ArcosEmulator::new("t").with_identity(identity));
        r.connect();
        let config = r.send(&frame(18, Some(1)));
        strings(&config[0].1, 3)[2].clone()
    };
    let robot = serial(Identity::Robot);
    assert!(
        !robot.eq_ignore_ascii_case("SIM") && !robot.is_empty(),
        "{robot}"
    );
    assert_eq!(serial(Identity::MobileSim), "SIM");

    // As a robot, SIM_LRF_ENABLE does nothing; as MobileSim it starts the laser packets.
    for (identity, wants) in [(Identity::Robot, false), (Identity::MobileSim, true)] {
        let mut r = Robot::new(ArcosEmulator::new("t").with_identity(identity));
        r.connect();
        r.send(&frame(230, Some(1)));
        r.run(0.2, true);
        let due = r.emu.sim_laser_due();
        assert_eq!(due.is_some(), wants, "{identity:?}");
        if let Some(config) = due {
            assert_eq!(config.beam_count, 181, "-90..90 at 1 deg");
            let scan = papillon_sim::laser::LaserSim::new(config, 1).scan(
                &r.world,
                r.body.true_pose(),
                &[],
            );
            let mut out = Vec::new();
            r.emu.sim_laser_packets(&scan, &r.body, &mut out);
            let mut got = vec![None; 181];
            for (id, p) in packets(&out) {
                assert_eq!(id, 0x60);
                let total = u16::from_le_bytes([p[6], p[7]]) as usize;
                let first = u16::from_le_bytes([p[8], p[9]]) as usize;
                let n = p[10] as usize;
                assert_eq!(total, 181);
                assert_eq!(p.len(), 11 + 2 * n);
                for k in 0..n {
                    got[first + k] = Some(u16::from_le_bytes([p[11 + 2 * k], p[12 + 2 * k]]));
                }
            }
            // Every reading came once; beam 0 points south at the wall 0.5 m away.
            let got: Vec<u16> = got.into_iter().map(|g| g.expect("every reading")).collect();
            assert!((450..=550).contains(&got[0]), "{}", got[0]);
        }
    }
}

// ---------------------------------------------------------------- LMS200 by hand

/// The LMS200 CRC (fact sheet section 3).
fn lms_crc(data: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    let mut prev: u8 = 0;
    for &b in data {
        if crc & 0x8000 != 0 {
            crc = (crc << 1) ^ 0x8005;
        } else {
            crc <<= 1;
        }
        crc ^= u16::from(b) | (u16::from(prev) << 8);
        prev = b;
    }
    crc
}

fn telegram(command: u8, data: &[u8]) -> Vec<u8> {
    let mut t = vec![0x02, 0x00];
    t.extend_from_slice(&((data.len() + 1) as u16).to_le_bytes());
    t.push(command);
    t.extend_from_slice(data);
    let crc = lms_crc(&t);
    t.extend_from_slice(&crc.to_le_bytes());
    t
}

/// ACK/NACK bytes as `Err(byte)` and telegrams as `Ok((command, data))`, CRC checked.
fn lms_replies(bytes: &[u8]) -> Vec<Result<(u8, Vec<u8>), u8>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            0x06 | 0x15 => {
                out.push(Err(bytes[i]));
                i += 1;
            }
            0x02 => {
                assert_eq!(bytes[i + 1], 0x80, "laser reply address");
                let len = u16::from_le_bytes([bytes[i + 2], bytes[i + 3]]) as usize;
                let end = i + 4 + len;
                let crc = u16::from_le_bytes([bytes[end], bytes[end + 1]]);
                assert_eq!(crc, lms_crc(&bytes[i..end]), "CRC");
                out.push(Ok((bytes[i + 4], bytes[i + 5..end].to_vec())));
                i = end + 2;
            }
            other => panic!("stray byte {other:#x}"),
        }
    }
    out
}

#[test]
fn the_crc_matches_the_fact_sheet_examples() {
    assert_eq!(telegram(0x20, &[0x25])[6..], [0x35, 0x08]);
    assert_eq!(telegram(0x20, &[0x24])[6..], [0x34, 0x08]);
}

#[test]
fn an_lms200_client_configures_setup_variant_mode_and_continuous_output() {
    let mut emu = Lms200Emulator::new();
    let mut out = Vec::new();
    let mut setup = vec![0x00];
    setup.extend_from_slice(b"SICK_LMS");
    emu.receive(0.0, &telegram(0x20, &setup), &mut out);
    // Variant 180° at 0.5° (0.01° units).
    emu.receive(0.0, &telegram(0x3B, &[180, 0, 50, 0]), &mut out);
    // Configuration: blanking 0, threshold 70, fog 0, measuring mode 5 (one reflector bit,
    // 15 distance bits), unit 1 (mm), then 26 contour/field bytes, as ARIA sends it.
    let mut config = vec![0, 0, 70, 0, 0, 5, 1];
    config.extend_from_slice(&[0; 26]);
    emu.receive(0.0, &telegram(0x77, &config), &mut out);
    emu.receive(0.0, &telegram(0x20, &[0x24]), &mut out);
    let got = lms_replies(&out);
    assert_eq!(got.len(), 8, "{got:?}");
    assert_eq!(got[0], Err(0x06));
    assert_eq!(got[1], Ok((0xA0, vec![0, 0x10])), "setup mode");
    assert_eq!(got[2], Err(0x06));
    assert_eq!(got[3], Ok((0xBB, vec![1, 180, 0, 50, 0, 0x10])), "variant");
    assert_eq!(got[4], Err(0x06));
    let Ok((0xF7, reply)) = &got[5] else {
        panic!("no configuration reply: {:?}", got[5]);
    };
    assert_eq!(reply[0], 1, "configuration accepted");
    assert_eq!(
        &reply[1..1 + config.len()],
        &config[..],
        "configuration echoed"
    );
    assert_eq!(got[6], Err(0x06));
    assert_eq!(got[7], Ok((0xA0, vec![0, 0x10])), "continuous output");

    // The scans stream in millimetres with 15 distance bits: 361 values.
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let mut out = Vec::new();
    emu.tick(
        0.2,
        |c| papillon_sim::laser::LaserSim::new(c, 1).scan(&world, world.start(), &[]),
        &mut out,
    );
    let scans = lms_replies(&out);
    let Ok((0xB0, data)) = &scans[0] else {
        panic!("{scans:?}")
    };
    let word = u16::from_le_bytes([data[0], data[1]]);
    assert_eq!(word & 0x3FF, 361);
    assert_eq!(word >> 14, 1, "mm");
    let first = u16::from_le_bytes([data[2], data[3]]) & 0x7FFF;
    assert!((450..=550).contains(&first), "{first}");

    // A configuration in centimetres: values in cm.
    let mut out = Vec::new();
    config[6] = 0;
    emu.receive(0.3, &telegram(0x77, &config), &mut out);
    emu.tick(
        0.5,
        |c| papillon_sim::laser::LaserSim::new(c, 1).scan(&world, world.start(), &[]),
        &mut out,
    );
    let got = lms_replies(&out);
    assert!(matches!(&got[1], Ok((0xF7, r)) if r[0] == 1));
    let Ok((0xB0, data)) = &got[2] else {
        panic!("{got:?}")
    };
    assert_eq!(u16::from_le_bytes([data[0], data[1]]) >> 14, 0, "cm");
    let first = u16::from_le_bytes([data[2], data[3]]) & 0x7FFF;
    assert!((45..=55).contains(&first), "{first}");

    // An unknown measuring mode is not accepted and changes nothing.
    let mut out = Vec::new();
    config[5] = 0x7F;
    emu.receive(0.6, &telegram(0x77, &config), &mut out);
    let got = lms_replies(&out);
    assert!(matches!(&got[1], Ok((0xF7, r)) if r[0] == 0), "{got:?}");
}
