//! `papillon-sim serve`: the ARCOS emulator in simulated time (handshake, motors, watchdog),
//! and the served endpoints over a real pty and loopback TCP, driven by clients built on the
//! core codecs.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::os::fd::AsRawFd;
use std::path::PathBuf;
use std::process::{Child, Command as Process, Stdio};
use std::time::{Duration, Instant};

use papillon::wire::arcos::{
    Command, ConfigPacket, EncoderPacket, FrameDecoder, StatusPacket, SyncReply, config, encoder,
    sip,
};
use papillon::wire::lms1xx::command::check_reply;
use papillon::wire::lms1xx::{
    ColaDecoder, Dialect, Reply, Request, ScanConfig, ScanDataConfig, ScanTelegram,
};
use papillon_sim::emulator::arcos::{ArcosEmulator, Link, WATCHDOG_S};
use papillon_sim::emulator::lms1xx::laser_config;
use papillon_sim::laser::LaserSim;
use papillon_sim::physics::{BodyConfig, RobotBody};
use papillon_sim::serve::MAP_RESOLUTION_M;
use papillon_sim::world::World;

/// A server packet decoded from the emulator's output.
#[derive(Debug)]
enum Packet {
    Sync(SyncReply),
    Status(StatusPacket),
    Config(Box<ConfigPacket>),
    Encoder(EncoderPacket),
}

fn decode_all(dec: &mut FrameDecoder, bytes: &[u8]) -> Vec<Packet> {
    let mut input = bytes;
    let mut out = Vec::new();
    while let Some(frame) = dec.decode(&mut input) {
        let p = match frame.id() {
            0..=2 => Packet::Sync(SyncReply::parse_frame(&frame).expect("sync reply")),
            sip::ID_STOPPED | sip::ID_MOVING => {
                Packet::Status(StatusPacket::parse_frame(&frame).expect("status packet"))
            }
            config::ID => Packet::Config(Box::new(
                ConfigPacket::parse_frame(&frame).expect("config packet"),
            )),
            encoder::ID => Packet::Encoder(EncoderPacket::parse_frame(&frame).expect("encoder")),
            other => panic!("unexpected packet id {other:#x}"),
        };
        out.push(p);
    }
    out
}

fn bytes_of(cmd: Command) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = cmd.emit(&mut buf).expect("emit command");
    buf[..n].to_vec()
}

/// The emulator, its robot and a clock advanced in 10 ms steps.
struct Bench {
    world: World,
    body: RobotBody,
    emu: ArcosEmulator,
    now_s: f64,
    dec: FrameDecoder,
}

impl Bench {
    fn new() -> Self {
        let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
        let body = RobotBody::new(BodyConfig::default(), world.start(), 7);
        Self {
            world,
            body,
            emu: ArcosEmulator::new("bench"),
            now_s: 0.0,
            dec: FrameDecoder::new(),
        }
    }

    fn send_bytes(&mut self, bytes: &[u8]) -> Vec<Packet> {
        let mut out = Vec::new();
        self.emu
            .receive(self.now_s, bytes, &mut self.body, &mut out);
        decode_all(&mut self.dec, &out)
    }

    fn send(&mut self, cmd: Command) -> Vec<Packet> {
        self.send_bytes(&bytes_of(cmd))
    }

    /// Runs for `dt_s`, re-sending `keep_alive` every 0.5 s if given; returns the packets.
    fn run(&mut self, dt_s: f64, keep_alive: Option<Command>) -> Vec<Packet> {
        let mut packets = Vec::new();
        let end = self.now_s + dt_s;
        let mut next_keep = self.now_s + 0.5;
        while self.now_s < end - 1e-9 {
            self.now_s += 0.01;
            self.body.advance(0.01, &self.world, &[]);
            if let Some(c) = &keep_alive
                && self.now_s >= next_keep
            {
                next_keep += 0.5;
                packets.extend(self.send(c.clone()));
            }
            let mut out = Vec::new();
            self.emu
                .tick(self.now_s, &self.world, &mut self.body, &mut out);
            packets.extend(decode_all(&mut self.dec, &out));
        }
        packets
    }

    fn connect(&mut self) {
        // ARIA's radio-modem junk first, then SYNC0/1/2 as bare packets.
        let mut first = b"WMS2\r".to_vec();
        first.extend(bytes_of(Command::SYNC0));
        let replies = self.send_bytes(&first);
        assert!(matches!(
            replies.as_slice(),
            [Packet::Sync(SyncReply::Sync0)]
        ));
        let replies = self.send(Command::SYNC1);
        assert!(matches!(
            replies.as_slice(),
            [Packet::Sync(SyncReply::Sync1)]
        ));
        let replies = self.send(Command::SYNC2);
        match replies.as_slice() {
            [
                Packet::Sync(SyncReply::Sync2 {
                    name,
                    class,
                    subclass,
                }),
            ] => {
                assert_eq!(name.as_str(), "bench");
                assert_eq!(class.as_str(), "Pioneer");
                assert_eq!(subclass.as_str(), "p3dx-sh");
            }
            other => panic!("expected SYNC2 reply, got {other:?}"),
        }
        assert!(self.send(Command::Open(Some(1))).is_empty());
        assert_eq!(self.emu.link(), Link::Open);
    }
}

fn statuses(packets: &[Packet]) -> Vec<&StatusPacket> {
    packets
        .iter()
        .filter_map(|p| match p {
            Packet::Status(s) => Some(s),
            _ => None,
        })
        .collect()
}

#[test]
fn handshake_then_motors_stay_off_until_enable() {
    let mut b = Bench::new();
    b.connect();
    b.send(Command::Vel(300));
    let packets = b.run(1.0, Some(Command::Vel(300)));
    let sips = statuses(&packets);
    // 100 ms cadence: 10 or 11 status packets in one second.
    assert!((10..=11).contains(&sips.len()), "{} SIPs", sips.len());
    assert!(sips.iter().all(|s| !s.motors_enabled()));
    assert_eq!(b.body.speed_mm_s(), 0.0);
    assert!(sips.iter().all(|s| s.sonar.len() == 8));

    b.send(Command::Enable(true));
    b.send(Command::Vel(300));
    let packets = b.run(2.0, Some(Command::Vel(300)));
    let last = *statuses(&packets).last().unwrap();
    assert!(last.motors_enabled());
    assert!(last.moving);
    assert!((last.left_vel_mm_s - 300).abs() <= 5, "{last:?}");
    assert!(last.x_pos > 300, "x {}", last.x_pos);
}

#[test]
fn watchdog_halts_after_two_silent_seconds_and_releases_on_next_command() {
    let mut b = Bench::new();
    b.connect();
    b.send(Command::Enable(true));
    b.send(Command::Vel(300));
    b.run(2.0, Some(Command::Vel(300)));
    assert!((b.body.speed_mm_s() - 300.0).abs() < 1.0);

    // Silent for just under the watchdog period: still driving.
    b.run(WATCHDOG_S - 0.1, None);
    assert!(!b.emu.watchdog_halted());
    assert!((b.body.speed_mm_s() - 300.0).abs() < 1.0);

    // Past it: the watchdog fires and the robot comes to a stop (300 mm/s² decel: 1 s).
    b.run(0.2, None);
    assert!(b.emu.watchdog_halted());
    assert_eq!(b.emu.watchdog_trips(), 1);
    let packets = b.run(1.5, None);
    assert_eq!(b.body.speed_mm_s(), 0.0);
    let last = *statuses(&packets).last().unwrap();
    assert!(!last.moving);
    let x_halted = b.body.true_pose().x;
    b.run(0.5, None);
    assert_eq!(b.body.true_pose().x, x_halted);

    // Any command (a PULSE here) resumes the last commanded motion.
    b.send(Command::Pulse);
    assert!(!b.emu.watchdog_halted());
    b.run(1.5, Some(Command::Pulse));
    assert!((b.body.speed_mm_s() - 300.0).abs() < 1.0);
    assert!(b.body.true_pose().x > x_halted + 0.2);
}

/// A FLASH watchdog set shorter (as ARCOScf allows) is reported in CONFIG and halts the robot
/// that much sooner; the halt is a stop at the robot's deceleration.
#[test]
fn a_shorter_flash_watchdog_is_reported_and_halts_sooner() {
    let mut b = Bench::new();
    b.emu = ArcosEmulator::new("bench").with_watchdog_ms(250);
    b.connect();
    let config = b
        .send(Command::Config(None))
        .into_iter()
        .find_map(|p| match p {
            Packet::Config(c) => Some(c),
            _ => None,
        })
        .expect("a CONFIG packet");
    assert_eq!(config.watchdog_ms, 250);
    b.send(Command::Enable(true));
    // Commands every 100 ms keep it driving.
    for _ in 0..20 {
        b.send(Command::Vel(300));
        b.run(0.1, None);
    }
    assert!(!b.emu.watchdog_halted());
    assert!((b.body.speed_mm_s() - 300.0).abs() < 1.0);
    // 0.2 s since the last command, then 0.3 s.
    b.run(0.1, None);
    assert!(!b.emu.watchdog_halted());
    b.run(0.1, None);
    assert!(b.emu.watchdog_halted());
    // 300 mm/s at 300 mm/s² takes 1 s more to stop.
    assert!(b.body.speed_mm_s() > 150.0, "{}", b.body.speed_mm_s());
    b.run(1.1, None);
    assert_eq!(b.body.speed_mm_s(), 0.0);
}

#[test]
fn bare_packets_after_open_are_pulse_open_close_and_limits_apply() {
    let mut b = Bench::new();
    b.connect();
    b.send(Command::Enable(true));
    // A bare 0 after OPEN is a PULSE, not a new handshake: no reply.
    assert!(b.send(Command::SYNC0).is_empty());
    assert_eq!(b.emu.link(), Link::Open);
    b.send(Command::SetV(200));
    b.send(Command::Vel(500));
    b.run(3.0, Some(Command::Pulse));
    assert!((b.body.speed_mm_s() - 200.0).abs() < 1.0);
    b.send(Command::HostBaud(2));
    assert_eq!(b.emu.host_baud(), 2);

    let replies = b.send(Command::Config(Some(1)));
    match replies.as_slice() {
        [Packet::Config(c)] => {
            assert_eq!(c.robot_type.as_str(), "Pioneer");
            assert_eq!(c.subtype.as_str(), "p3dx-sh");
            assert_eq!(c.watchdog_ms, 2000);
            assert_eq!(c.trans_vel_max, 200);
        }
        other => panic!("expected CONFIG, got {other:?}"),
    }

    b.send(Command::Encoder(1));
    let packets = b.run(0.35, Some(Command::Pulse));
    let encoders: Vec<_> = packets
        .iter()
        .filter_map(|p| match p {
            Packet::Encoder(e) => Some(*e),
            _ => None,
        })
        .collect();
    assert_eq!(encoders.len(), 1);
    assert!(encoders[0].left_ticks > 0 && encoders[0].right_ticks > 0);

    b.send(Command::EStop);
    let packets = b.run(0.3, Some(Command::Pulse));
    let last = *statuses(&packets).last().unwrap();
    assert!(last.estop());
    assert_eq!(b.body.speed_mm_s(), 0.0);

    // A bare 2 closes: status packets stop.
    assert!(b.send(Command::SYNC2).is_empty());
    assert_eq!(b.emu.link(), Link::Idle);
    assert!(statuses(&b.run(0.5, None)).is_empty());
}

// ---------------------------------------------------------------- the served endpoints

/// A `papillon-sim serve` process, killed (SIGTERM) on drop.
struct Server {
    child: Child,
    lines: Vec<String>,
    _stdout: BufReader<std::process::ChildStdout>,
}

impl Server {
    fn start(extra: &[&str]) -> Self {
        let mut child = Process::new(env!("CARGO_BIN_EXE_papillon-sim"))
            .arg("serve")
            .args(["--map", "empty"])
            .args(if extra.contains(&"--laser") {
                &[][..]
            } else {
                &["--laser", "127.0.0.1:0"][..]
            })
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start papillon-sim serve");
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut lines = Vec::new();
        loop {
            let mut line = String::new();
            assert!(stdout.read_line(&mut line).unwrap() > 0, "server exited");
            let done = line.trim() == "ready";
            lines.push(line.trim().to_string());
            if done {
                break;
            }
        }
        Self {
            child,
            lines,
            _stdout: stdout,
        }
    }

    fn endpoint(&self, prefix: &str) -> String {
        let line = self
            .lines
            .iter()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} line in {:?}", self.lines));
        line[prefix.len()..].trim().to_string()
    }

    fn terminate(&mut self) -> std::process::ExitStatus {
        // SAFETY: sends SIGTERM to our own child process.
        unsafe { libc::kill(self.child.id() as i32, libc::SIGTERM) };
        let deadline = Instant::now() + Duration::from_secs(5);
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return status;
            }
            assert!(Instant::now() < deadline, "server did not stop on SIGTERM");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Reads packets from `io` (reads time out or would block) until `want` accepts them all,
/// or the deadline passes.
fn read_until(
    io: &mut impl Read,
    dec: &mut FrameDecoder,
    timeout: Duration,
    mut want: impl FnMut(&Packet) -> bool,
) -> bool {
    let deadline = Instant::now() + timeout;
    let mut buf = [0u8; 512];
    while Instant::now() < deadline {
        match io.read(&mut buf) {
            Ok(0) => return false,
            Ok(n) => {
                for p in decode_all(dec, &buf[..n]) {
                    if want(&p) {
                        return true;
                    }
                }
            }
            Err(_) => std::thread::sleep(Duration::from_millis(5)),
        }
    }
    false
}

/// Handshake, OPEN, ENABLE, then drive and turn; returns the first and last status packets.
fn drive_session(io: &mut (impl Read + Write)) -> (StatusPacket, StatusPacket) {
    let mut dec = FrameDecoder::new();
    for (n, cmd) in [Command::SYNC0, Command::SYNC1, Command::SYNC2]
        .into_iter()
        .enumerate()
    {
        io.write_all(&bytes_of(cmd)).unwrap();
        let got = read_until(
            io,
            &mut dec,
            Duration::from_secs(2),
            |p| matches!(p, Packet::Sync(s) if s.id() as usize == n),
        );
        assert!(got, "no reply to SYNC{n}");
    }
    io.write_all(&bytes_of(Command::Open(Some(1)))).unwrap();
    let mut first = None;
    assert!(read_until(io, &mut dec, Duration::from_secs(2), |p| {
        if let Packet::Status(s) = p {
            first = Some(s.clone());
            true
        } else {
            false
        }
    }));
    let first = first.unwrap();
    assert!(!first.motors_enabled());
    io.write_all(&bytes_of(Command::Enable(true))).unwrap();
    let mut last = None;
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(1500) {
        io.write_all(&bytes_of(Command::Vel(200))).unwrap();
        io.write_all(&bytes_of(Command::RVel(20))).unwrap();
        read_until(io, &mut dec, Duration::from_millis(200), |p| {
            if let Packet::Status(s) = p {
                last = Some(s.clone());
            }
            false
        });
    }
    io.write_all(&bytes_of(Command::Stop)).unwrap();
    io.write_all(&bytes_of(Command::Close(Some(1)))).unwrap();
    (first, last.expect("status packets while driving"))
}

fn assert_moved(first: &StatusPacket, last: &StatusPacket) {
    assert!(last.motors_enabled());
    assert!(
        last.x_pos.wrapping_sub(first.x_pos) as i16 > 50,
        "{first:?} -> {last:?}"
    );
    assert!(last.th_pos - first.th_pos > 50, "{first:?} -> {last:?}");
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("papillon-serve-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn tcp_client_connects_enables_and_drives() {
    let server = Server::start(&["--tcp", "127.0.0.1:0"]);
    let addr = server.endpoint("arcos tcp");
    let mut stream = TcpStream::connect(&addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let (first, last) = drive_session(&mut stream);
    assert_moved(&first, &last);
}

#[test]
fn pty_client_connects_enables_and_drives_and_shutdown_removes_the_link() {
    let dir = temp_dir("pty");
    let link = dir.join("robot");
    let mut server = Server::start(&["--pty", link.to_str().unwrap()]);
    assert!(
        server
            .endpoint("arcos pty")
            .starts_with(link.to_str().unwrap())
    );
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&link)
        .unwrap();
    // SAFETY: fcntl on a descriptor we own.
    unsafe {
        let fd = port.as_raw_fd();
        let flags = libc::fcntl(fd, libc::F_GETFL);
        libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let (first, last) = drive_session(&mut port);
    assert_moved(&first, &last);
    drop(port);
    let status = server.terminate();
    assert!(status.success(), "{status:?}");
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "symlink left behind"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------- laser

/// Sends `req`, checks the reply, and returns the bytes read after it.
fn send_request(stream: &mut TcpStream, dec: &mut ColaDecoder, req: Request) -> Vec<u8> {
    let mut buf = [0u8; 256];
    let n = req.emit(&mut buf).unwrap();
    stream.write_all(&buf[..n]).unwrap();
    let deadline = Instant::now() + Duration::from_secs(2);
    let mut rx = [0u8; 512];
    while Instant::now() < deadline {
        if let Ok(n) = stream.read(&mut rx) {
            let mut input = &rx[..n];
            if let Some(payload) = dec.decode(&mut input) {
                let reply = Reply::parse(payload).expect("reply parses");
                check_reply(&req, &reply).expect("successful reply");
                return input.to_vec();
            }
        }
    }
    panic!("no reply to {req:?}");
}

/// Opens an LMS1xx session on `addr` with the clearpath driver's sequence, checks that nothing
/// streams before the subscription, subscribes, and collects scans until `count` arrived or
/// `timeout` passed, with the time (since the subscription) each one arrived.
fn laser_session(addr: &str, count: usize, timeout: Duration) -> Vec<(Duration, ScanTelegram)> {
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let mut dec = Box::new(ColaDecoder::<16384>::new());
    for req in [
        Request::SetAccessMode {
            level: 3,
            password_hash: 0xF472_4744,
            dialect: Dialect::Clearpath,
        },
        Request::ReadScanConfig,
        Request::ReadOutputRange,
        Request::SetScanDataConfig(ScanDataConfig::clearpath(false)),
        Request::StartMeasurement,
        Request::ReadStatus,
        Request::Run,
    ] {
        let rest = send_request(&mut stream, &mut dec, req);
        assert!(rest.is_empty(), "bytes after the reply to {req:?}");
    }
    // Nothing streams before the subscription.
    std::thread::sleep(Duration::from_millis(200));
    let mut rx = vec![0u8; 65536];
    match stream.read(&mut rx) {
        Ok(n) => panic!("{n} bytes (or EOF) before sEN LMDscandata 1"),
        Err(e) => assert!(
            matches!(
                e.kind(),
                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
            ),
            "{e}"
        ),
    }
    let mut pending = send_request(&mut stream, &mut dec, Request::SubscribeScanData(true));
    let subscribed = Instant::now();
    let mut scans = Vec::new();
    while scans.len() < count && subscribed.elapsed() < timeout {
        if let Ok(n) = stream.read(&mut rx) {
            pending.extend_from_slice(&rx[..n]);
        }
        {
            let mut input = &pending[..];
            while let Some(payload) = dec.decode(&mut input) {
                let t = ScanTelegram::parse(payload).expect("scan telegram");
                scans.push((subscribed.elapsed(), t));
            }
        }
        pending.clear();
    }
    scans
}

/// The first `count` scans of an LMS1xx session on `addr`.
fn laser_scans(addr: &str, count: usize, timeout: Duration) -> Vec<ScanTelegram> {
    laser_session(addr, count, timeout)
        .into_iter()
        .map(|(_, t)| t)
        .collect()
}

#[test]
fn lms1xx_session_streams_scans_matching_the_world_only_after_subscribing() {
    let server = Server::start(&[]);
    let addr = server.endpoint("laser lms1xx tcp");
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let expected =
        LaserSim::new(laser_config(ScanConfig::DEFAULT_50HZ), 1).scan(&world, world.start(), &[]);
    let scans = laser_scans(&addr, 5, Duration::from_secs(3));
    assert_eq!(scans.len(), 5, "scans received");
    for t in &scans {
        assert!(!t.polled);
        let ch = t.distance_channel().expect("DIST1");
        assert_eq!(ch.values.len(), 541);
        assert_eq!(ch.start_angle_deg_e4, -450_000);
        assert_eq!(ch.step_deg_e4, 5000);
        assert_eq!(t.scan_frequency_centi_hz, 5000);
        let mut compared = 0;
        for (got, beam) in ch.values.iter().zip(expected.beams()) {
            let want = beam.range_m.map_or(0, |r| (r * 1000.0).round() as u16);
            assert!(got.abs_diff(want) <= 1, "got {got} mm, want {want} mm");
            compared += usize::from(want > 0);
        }
        // From (1, 1) facing east, the walls west and south are close; the far ones lie
        // beyond 20 m for some beams.
        assert!(compared > 300, "{compared} beams with a return");
        // Beam 90 points south (-90°) at the wall face 0.5 m away.
        assert!(
            (450..=550).contains(&ch.values[90]),
            "south range {}",
            ch.values[90]
        );
    }
}

/// `--laser-noise F`: each range gets Gaussian noise of F times the range, drawn afresh for
/// every scan (the runner's laser model), around the noise-free range.
#[test]
fn laser_noise_perturbs_each_scan_afresh_around_the_true_ranges() {
    let server = Server::start(&["--laser-noise", "0.05"]);
    let addr = server.endpoint("laser lms1xx tcp");
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let truth =
        LaserSim::new(laser_config(ScanConfig::DEFAULT_50HZ), 1).scan(&world, world.start(), &[]);
    let scans = laser_scans(&addr, 3, Duration::from_secs(3));
    assert_eq!(scans.len(), 3, "scans received");
    let values: Vec<&[u16]> = scans
        .iter()
        .map(|t| &t.distance_channel().expect("DIST1").values[..])
        .collect();
    let mut compared = 0;
    let mut off = 0;
    let mut sum_sq = 0.0f64;
    for (i, beam) in truth.beams().iter().enumerate() {
        let Some(r) = beam.range_m.filter(|&r| r > 0.5 && r < 10.0) else {
            continue;
        };
        for v in &values {
            // 6 standard deviations: a correct draw is never that far out in these scans.
            let err_m = f64::from(v[i]) / 1000.0 - f64::from(r);
            assert!(
                err_m.abs() < 6.0 * 0.05 * f64::from(r),
                "beam {i}: {err_m} m off {r} m"
            );
            sum_sq += (err_m / (0.05 * f64::from(r))).powi(2);
            compared += 1;
        }
        off += usize::from(values[0][i] != values[1][i]);
    }
    assert!(compared > 300, "{compared} ranges compared");
    // Noise drawn afresh: the same beam differs from one scan to the next.
    assert!(
        off * 10 > compared / 3 * 9,
        "{off} of {} beams differ",
        compared / 3
    );
    // Its spread is the one asked for (unit variance after scaling, within sampling error).
    let variance = sum_sq / compared as f64;
    assert!((0.7..1.3).contains(&variance), "scaled variance {variance}");
}

/// `--laser-noise-m S`: each range gets Gaussian noise of S metres whatever the range (a real
/// laser's statistical error), drawn afresh for every scan.
#[test]
fn laser_noise_m_perturbs_near_and_far_ranges_alike() {
    let sigma_m = 0.012;
    let server = Server::start(&["--laser-noise-m", "0.012"]);
    let addr = server.endpoint("laser lms1xx tcp");
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let truth =
        LaserSim::new(laser_config(ScanConfig::DEFAULT_50HZ), 1).scan(&world, world.start(), &[]);
    let scans = laser_scans(&addr, 20, Duration::from_secs(3));
    assert_eq!(scans.len(), 20, "scans received");
    let values: Vec<&[u16]> = scans
        .iter()
        .map(|t| &t.distance_channel().expect("DIST1").values[..])
        .collect();
    // Per range bin: (beams, sum of each beam's sample variance over the scans / σ²), for
    // ranges under 2 m and over 3 m. Each beam's spread around its own mean: what is
    // compared is the noise, not how the test's noise-free scan rounds against serve's.
    let mut near = (0usize, 0.0f64);
    let mut far = (0usize, 0.0f64);
    for (i, beam) in truth.beams().iter().enumerate() {
        let Some(r) = beam.range_m.filter(|&r| r > 0.5 && r < 10.0) else {
            continue;
        };
        let ranges: Vec<f64> = values.iter().map(|v| f64::from(v[i]) / 1000.0).collect();
        for x in &ranges {
            // 6 standard deviations and a centimetre of rounding: never that far out.
            let err_m = x - f64::from(r);
            assert!(
                err_m.abs() < 6.0 * sigma_m + 0.01,
                "beam {i}: {err_m} m off {r} m"
            );
        }
        let mean = ranges.iter().sum::<f64>() / ranges.len() as f64;
        let var =
            ranges.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (ranges.len() - 1) as f64;
        let bin = if r < 2.0 {
            &mut near
        } else if r > 3.0 {
            &mut far
        } else {
            continue;
        };
        bin.0 += 1;
        bin.1 += var / (sigma_m * sigma_m);
    }
    for (name, (n, sum)) in [("under 2 m", near), ("over 3 m", far)] {
        assert!(n > 20, "{name}: {n} beams compared");
        // The millimetre rounding adds (1/12) mm², under 0.1 % of 12 mm squared.
        let variance = sum / n as f64;
        assert!(
            (0.7..1.3).contains(&variance),
            "{name}: scaled variance {variance}"
        );
    }
}

#[test]
fn driving_into_a_wall_sets_the_front_bumper_and_stall_flags() {
    let mut b = Bench::new();
    // Facing south, 0.5 m from the wall face: contact after about 0.25 m.
    b.body.teleport(papillon::geometry::Pose2::new(
        1.0,
        1.0,
        -core::f32::consts::FRAC_PI_2,
    ));
    b.connect();
    b.send(Command::Enable(true));
    let before = statuses(&b.run(0.3, Some(Command::Pulse)))
        .last()
        .map(|s| s.stall_bumpers)
        .unwrap();
    assert_eq!(before, 0);
    b.send(Command::Vel(200));
    let packets = b.run(3.0, Some(Command::Vel(200)));
    let last = *statuses(&packets).last().unwrap();
    assert_ne!(last.bumpers_b(), 0, "front bumper (ring B) {last:?}");
    assert!(last.stalled());
    assert_eq!(last.bumpers_a(), 0, "rear bumper");
}

#[test]
fn with_one_percent_byte_corruption_the_client_keeps_receiving_valid_status_packets() {
    let mut rng = papillon::random::seeded(42);
    let mut b = Bench::new();
    b.connect();
    b.send(Command::Enable(true));
    b.send(Command::Vel(200));
    let mut client = FrameDecoder::new();
    let mut clean = FrameDecoder::new();
    let (mut valid, mut sent) = (0, 0);
    let mut corrupted = 0;
    for step in 0..300 {
        b.now_s += 0.01;
        b.body.advance(0.01, &b.world, &[]);
        let mut out = Vec::new();
        b.emu.tick(b.now_s, &b.world, &mut b.body, &mut out);
        if step % 50 == 0 {
            b.emu
                .receive(b.now_s, &bytes_of(Command::Pulse), &mut b.body, &mut out);
        }
        sent += statuses(&decode_all(&mut clean, &out)).len();
        for byte in out.iter_mut() {
            if papillon::random::chance(&mut rng, 0.01) {
                *byte ^= 1 << papillon::random::below(&mut rng, 8);
                corrupted += 1;
            }
        }
        let mut input = &out[..];
        while let Some(frame) = client.decode(&mut input) {
            if matches!(frame.id(), sip::ID_STOPPED | sip::ID_MOVING) {
                let s =
                    StatusPacket::parse_frame(&frame).expect("a frame with a good checksum parses");
                assert!(s.motors_enabled());
                valid += 1;
            }
        }
    }
    assert!(corrupted > 10, "{corrupted} bytes corrupted");
    // One every 100 ms for 3 s (from the first tick on).
    assert!((30..=31).contains(&sent), "{sent} status packets sent");
    // A SIP is about 60 bytes: about half survive 1 % corruption untouched.
    assert!(valid >= 10, "{valid} of {sent} status packets valid");
    assert!(valid < sent, "corruption had no effect");
    assert!(client.stats().bad_checksum > 0);
}

#[test]
fn fault_specs_parse_and_bad_ones_are_refused() {
    use papillon_sim::faults::{FaultSpecError, Faults};
    let f: Faults = "corrupt=0.01, drop=0.002".parse().unwrap();
    assert_eq!(f.corrupt, 0.01);
    assert_eq!(f.drop, 0.002);
    assert_eq!("".parse::<Faults>().unwrap(), Faults::default());
    assert!(matches!(
        "corrupt=2".parse::<Faults>(),
        Err(FaultSpecError::BadProbability { .. })
    ));
    assert!(matches!(
        "gremlins=5".parse::<Faults>(),
        Err(FaultSpecError::UnknownItem { .. })
    ));
}

#[test]
fn tcp_client_with_one_percent_corruption_connects_and_keeps_receiving_status_packets() {
    let server = Server::start(&["--tcp", "127.0.0.1:0", "--faults", "corrupt=0.01"]);
    let mut stream = TcpStream::connect(server.endpoint("arcos tcp")).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let mut dec = FrameDecoder::new();
    // A client retries the handshake when a reply is lost to corruption.
    let mut synced = false;
    'attempts: for _ in 0..20 {
        for n in 0..3u8 {
            let cmd = [Command::SYNC0, Command::SYNC1, Command::SYNC2][n as usize].clone();
            stream.write_all(&bytes_of(cmd)).unwrap();
            let got = read_until(
                &mut stream,
                &mut dec,
                Duration::from_millis(300),
                |p| matches!(p, Packet::Sync(s) if s.id() == n),
            );
            if !got {
                continue 'attempts;
            }
        }
        synced = true;
        break;
    }
    assert!(synced, "handshake never completed");
    stream.write_all(&bytes_of(Command::Open(Some(1)))).unwrap();
    let mut valid = 0;
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        stream.write_all(&bytes_of(Command::Pulse)).unwrap();
        read_until(&mut stream, &mut dec, Duration::from_millis(250), |p| {
            valid += usize::from(matches!(p, Packet::Status(_)));
            false
        });
    }
    // About 20 sent; a 60-byte SIP survives 1 % corruption about half the time.
    assert!(valid >= 5, "{valid} valid status packets in 2 s");
    assert!(dec.stats().bad_checksum > 0, "no corruption seen");
}

#[test]
fn two_robots_share_the_world_on_consecutive_endpoints_and_see_each_other() {
    let server = Server::start(&["--robots", "2", "--tcp", "127.0.0.1:0"]);
    // Robot 0 (at the start, facing east) sees robot 1, parked 0.8 m east of it, as a disc.
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let starts = papillon_sim::placement::start_poses(&world, world.start(), 2, 0.25).unwrap();
    assert_eq!(starts[0], world.start());
    let config = laser_config(ScanConfig::DEFAULT_50HZ);
    let other = papillon_sim::physics::Disc::new(starts[1].position(), 0.25);
    let expected = LaserSim::new(config, 1).scan(&world, starts[0], &[other]);
    let alone = LaserSim::new(config, 1).scan(&world, starts[0], &[]);
    let scan = &laser_scans(
        &server.endpoint("robot 0: laser lms1xx tcp"),
        1,
        Duration::from_secs(3),
    )[0];
    let ch = scan.distance_channel().expect("DIST1");
    let mut on_robot = 0;
    for ((got, with), without) in ch.values.iter().zip(expected.beams()).zip(alone.beams()) {
        let want = with.range_m.map_or(0, |r| (r * 1000.0).round() as u16);
        assert!(got.abs_diff(want) <= 1, "got {got} mm, want {want} mm");
        on_robot += usize::from(with.range_m != without.range_m);
    }
    assert!(on_robot >= 10, "{on_robot} beams end on the other robot");
    // Each robot has its own microcontroller on its own port.
    for robot in 0..2 {
        let addr = server.endpoint(&format!("robot {robot}: arcos tcp"));
        let mut stream = TcpStream::connect(&addr).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_millis(20)))
            .unwrap();
        let (first, last) = drive_session(&mut stream);
        assert_moved(&first, &last);
    }
}

#[test]
fn a_cut_drops_the_tcp_link_refuses_connections_and_then_lets_the_client_back() {
    let server = Server::start(&["--tcp", "127.0.0.1:0", "--faults", "cut=1.5+1.5"]);
    let addr = server.endpoint("arcos tcp");
    let started = Instant::now();
    let mut stream = TcpStream::connect(&addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let mut dec = FrameDecoder::new();
    stream.write_all(&bytes_of(Command::SYNC0)).unwrap();
    assert!(read_until(
        &mut stream,
        &mut dec,
        Duration::from_secs(1),
        |p| { matches!(p, Packet::Sync(SyncReply::Sync0)) }
    ));
    // The link drops when the cut begins (read returns EOF).
    let mut buf = [0u8; 256];
    let dropped = loop {
        match stream.read(&mut buf) {
            Ok(0) => break started.elapsed(),
            Ok(_) => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => break started.elapsed(),
        }
        assert!(
            started.elapsed() < Duration::from_secs(3),
            "link never dropped"
        );
        let _ = stream.write_all(&bytes_of(Command::Pulse));
    };
    assert!(
        dropped >= Duration::from_millis(1400),
        "dropped at {dropped:?}"
    );
    // During the cut a new connection is closed at once.
    let mut during = TcpStream::connect(&addr).unwrap();
    during
        .set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    let _ = during.write_all(&bytes_of(Command::SYNC0));
    assert!(matches!(during.read(&mut buf), Ok(0) | Err(_)));
    // After it, the client connects and drives again.
    while started.elapsed() < Duration::from_millis(3200) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut after = TcpStream::connect(&addr).unwrap();
    after
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let (first, last) = drive_session(&mut after);
    assert_moved(&first, &last);
}

#[test]
fn a_laser_dropout_stops_the_scans_and_they_resume_after_it() {
    let server = Server::start(&["--faults", "laser-drop=1.2+1.0"]);
    let addr = server.endpoint("laser lms1xx tcp");
    let started = Instant::now();
    let scans = laser_session(&addr, usize::MAX, Duration::from_millis(2800));
    // The session subscribed about 0.2 s after `started`; convert arrival times to server
    // time conservatively with a 0.15 s margin either side of the window.
    let offset = started.elapsed() - Duration::from_millis(2800);
    let at = |d: Duration| (d + offset).as_secs_f64();
    let before = scans.iter().filter(|(d, _)| at(*d) < 1.05).count();
    let inside = scans
        .iter()
        .filter(|(d, _)| (1.35..2.05).contains(&at(*d)))
        .count();
    let after = scans.iter().filter(|(d, _)| at(*d) > 2.35).count();
    assert!(before > 5, "{before} scans before the dropout");
    assert_eq!(inside, 0, "scans during the dropout");
    assert!(after > 5, "{after} scans after it");
}

#[test]
fn lms200_on_a_second_pty_answers_aria_s_sequence_and_streams_matching_scans() {
    use papillon::wire::lms200::{
        DEFAULT_PASSWORD, Event, Lms200Decoder, Mode, Request as Lms200Request, Response, Variant,
    };
    let dir = temp_dir("lms200");
    let link = dir.join("laser");
    let mut server = Server::start(&["--laser-model", "lms200", "--laser", link.to_str().unwrap()]);
    assert!(
        server
            .endpoint("laser lms200 pty")
            .starts_with(link.to_str().unwrap())
    );
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&link)
        .unwrap();
    // SAFETY: fcntl on a descriptor we own.
    unsafe {
        let fd = port.as_raw_fd();
        let flags = libc::fcntl(fd, libc::F_GETFL);
        libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let mut buf = [0u8; 1024];
    for req in [
        Lms200Request::SetMode(Mode::Setup {
            password: DEFAULT_PASSWORD,
        }),
        Lms200Request::SetVariant(Variant::DEG180_RES1),
        Lms200Request::SetMode(Mode::ContinuousOutput),
    ] {
        let n = req.emit(&mut buf).unwrap();
        port.write_all(&buf[..n]).unwrap();
    }
    let mut dec = Lms200Decoder::new();
    let mut events = Vec::new();
    let mut scans = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(3);
    while scans.len() < 3 && Instant::now() < deadline {
        let n = match port.read(&mut buf) {
            Ok(n) => n,
            Err(_) => {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            }
        };
        let mut input = &buf[..n];
        while let Some(e) = dec.decode(&mut input) {
            match e {
                Event::Ack => events.push("ack"),
                Event::Nack => events.push("nack"),
                Event::Telegram(t) => match Response::parse(&t).unwrap() {
                    Response::ModeReply { result: 0, .. } => events.push("mode"),
                    Response::VariantReply { accepted: true, .. } => events.push("variant"),
                    Response::MeasuredValues(m) => scans.push(m),
                    other => panic!("unexpected {other:?}"),
                },
            }
        }
    }
    assert_eq!(
        events,
        ["ack", "mode", "ack", "variant", "ack", "mode"],
        "replies"
    );
    assert_eq!(scans.len(), 3, "scans received");
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    let config = papillon_sim::emulator::lms200::laser_config(Variant::DEG180_RES1);
    let expected = LaserSim::new(config, 1).scan(&world, world.start(), &[]);
    for m in &scans {
        assert_eq!(m.values.len(), 181);
        for (got, beam) in m.values.iter().zip(expected.beams()) {
            let want = beam.range_m.map_or(0, |r| (r * 1000.0).round() as u16);
            assert!(
                (got & 0x1FFF).abs_diff(want) <= 1,
                "got {got} mm, want {want} mm"
            );
        }
        // Beam 0 points south (-90°) at the wall face 0.5 m away.
        assert!((450..=550).contains(&m.values[0]), "south {}", m.values[0]);
    }
    drop(port);
    assert!(server.terminate().success());
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "symlink left behind"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// While client A drives, client B's connection is closed without a reply (its SYNC0 gets
/// nothing) and A keeps control: its robot keeps moving and its status packets keep coming.
/// After A leaves, a new client is served.
#[test]
fn a_second_tcp_client_is_refused_while_the_first_drives() {
    let server = Server::start(&["--tcp", "127.0.0.1:0"]);
    let addr = server.endpoint("arcos tcp");
    let mut a = TcpStream::connect(&addr).unwrap();
    a.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
    let mut dec = FrameDecoder::new();
    for (n, cmd) in [Command::SYNC0, Command::SYNC1, Command::SYNC2]
        .into_iter()
        .enumerate()
    {
        a.write_all(&bytes_of(cmd)).unwrap();
        assert!(read_until(&mut a, &mut dec, Duration::from_secs(2), |p| {
            matches!(p, Packet::Sync(s) if s.id() as usize == n)
        }));
    }
    a.write_all(&bytes_of(Command::Open(Some(1)))).unwrap();
    a.write_all(&bytes_of(Command::Enable(true))).unwrap();
    a.write_all(&bytes_of(Command::Vel(300))).unwrap();
    let mut last = None;
    read_until(&mut a, &mut dec, Duration::from_millis(1500), |p| {
        if let Packet::Status(s) = p {
            last = Some(s.clone());
        }
        false
    });
    let before = last.take().expect("status packets for A");
    assert!(before.left_vel_mm_s > 250, "{before:?}");

    // B connects and tries the handshake and an OPEN: no reply, the connection ends.
    let mut b = TcpStream::connect(&addr).unwrap();
    b.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    let _ = b.write_all(&bytes_of(Command::SYNC0));
    let _ = b.write_all(&bytes_of(Command::Open(Some(1))));
    let mut b_dec = FrameDecoder::new();
    let mut b_packets = 0;
    let b_open = read_until(&mut b, &mut b_dec, Duration::from_millis(800), |_| {
        b_packets += 1;
        false
    });
    assert_eq!(b_packets, 0, "B got packets");
    assert!(!b_open, "B's connection stays usable");

    // A still drives.
    a.write_all(&bytes_of(Command::Vel(300))).unwrap();
    read_until(&mut a, &mut dec, Duration::from_millis(600), |p| {
        if let Packet::Status(s) = p {
            last = Some(s.clone());
        }
        false
    });
    let after = last.take().expect("A still gets status packets");
    assert!(after.motors_enabled());
    assert!(after.left_vel_mm_s > 250, "{after:?}");
    assert!(after.x_pos.wrapping_sub(before.x_pos) as i16 > 100);

    // A leaves; C is served.
    a.write_all(&bytes_of(Command::Close(Some(1)))).unwrap();
    drop(a);
    std::thread::sleep(Duration::from_millis(100));
    let mut c = TcpStream::connect(&addr).unwrap();
    c.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
    let (first, last) = drive_session(&mut c);
    assert_moved(&first, &last);
}

/// `serve --mcap FILE --live ADDR`: a WebSocket client (tungstenite, not Papillon's server
/// code) is advertised the served robot's true pose and receives it live; after the server
/// stops, the recording read back with the `mcap` crate's reader (not Papillon's writer) holds
/// the world's map, the true poses and odometry, and every scan a laser client was sent.
#[test]
fn serve_records_mcap_and_serves_the_live_view() {
    use tungstenite::Message;
    use tungstenite::client::IntoClientRequest;

    let dir = temp_dir("mcap");
    let path = dir.join("serve.mcap");
    let path_arg = path.to_str().unwrap();
    let mut server = Server::start(&[
        "--tcp",
        "127.0.0.1:0",
        "--mcap",
        path_arg,
        "--live",
        "127.0.0.1:0",
    ]);
    let url = server.endpoint("live");
    assert!(url.starts_with("ws://127.0.0.1:"), "{url}");

    let mut request = url.as_str().into_client_request().unwrap();
    request.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        tungstenite::http::HeaderValue::from_static("foxglove.websocket.v1"),
    );
    let (mut ws, _) = tungstenite::connect(request).unwrap();
    if let tungstenite::stream::MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    }
    let mut live_pose = None;
    while live_pose.is_none() {
        match ws.read().unwrap() {
            Message::Text(text) => {
                let m: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
                if m["op"] != "advertise" {
                    continue;
                }
                for c in m["channels"].as_array().unwrap() {
                    if c["topic"] == "/pose/true" {
                        assert_eq!(c["schemaName"], "foxglove.PoseInFrame");
                        ws.send(Message::text(
                            serde_json::json!({"op": "subscribe",
                                "subscriptions": [{"id": 7, "channelId": c["id"]}]})
                            .to_string(),
                        ))
                        .unwrap();
                    }
                }
            }
            Message::Binary(b) => {
                assert_eq!(b[0], 1, "message data");
                assert_eq!(u32::from_le_bytes(b[1..5].try_into().unwrap()), 7);
                let m: serde_json::Value = serde_json::from_slice(&b[13..]).unwrap();
                live_pose = Some(m);
            }
            _ => {}
        }
    }
    let live_pose = live_pose.unwrap();
    assert_eq!(live_pose["frame_id"], "map");
    // The empty world's start, (1, 1).
    let x = live_pose["pose"]["position"]["x"].as_f64().unwrap();
    assert!((x - 1.0).abs() < 0.01, "{live_pose}");
    drop(ws);

    let scans = laser_scans(
        &server.endpoint("laser lms1xx tcp"),
        5,
        Duration::from_secs(3),
    );
    assert_eq!(scans.len(), 5);
    let mut stream = TcpStream::connect(server.endpoint("arcos tcp")).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let (first, last) = drive_session(&mut stream);
    assert_moved(&first, &last);
    drop(stream);
    assert!(server.terminate().success());

    let bytes = std::fs::read(&path).unwrap();
    let mut topics: std::collections::BTreeMap<String, (String, Vec<serde_json::Value>)> =
        Default::default();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let m = message.unwrap();
        let schema = m.channel.schema.as_ref().expect("a schema");
        assert_eq!(schema.encoding, "jsonschema");
        assert_eq!(m.channel.message_encoding, "json");
        topics
            .entry(m.channel.topic.clone())
            .or_insert_with(|| (schema.name.clone(), Vec::new()))
            .1
            .push(serde_json::from_slice(&m.data).unwrap());
    }
    let schemas: Vec<(&str, &str)> = topics
        .iter()
        .map(|(t, (s, _))| (t.as_str(), s.as_str()))
        .collect();
    assert_eq!(
        schemas,
        [
            ("/map", "foxglove.Grid"),
            ("/pose/odometry", "foxglove.PoseInFrame"),
            ("/pose/true", "foxglove.PoseInFrame"),
            ("/scan", "foxglove.LaserScan"),
        ]
    );
    // The world's map once: every cell known, walls and free space.
    let map = &topics["/map"].1;
    assert_eq!(map.len(), 1);
    let world = World::load("empty", MAP_RESOLUTION_M).unwrap();
    assert_eq!(
        map[0]["column_count"].as_u64().unwrap(),
        world.geometry().width as u64
    );
    use base64::Engine as _;
    let cells = base64::engine::general_purpose::STANDARD
        .decode(map[0]["data"].as_str().unwrap())
        .unwrap();
    assert_eq!(cells.len(), world.blocked().len());
    for (c, &b) in cells.iter().zip(world.blocked()) {
        assert_eq!(*c, if b { 100 } else { 0 });
    }
    // At least the scans the client got (the server may have cast one more before it saw the
    // client leave), each with the LMS1xx's 541 beams.
    let recorded = &topics["/scan"].1;
    assert!(recorded.len() >= 5, "{} scans", recorded.len());
    assert_eq!(recorded[0]["ranges"].as_array().unwrap().len(), 541);
    // True poses at 10 Hz, showing the drive.
    let poses = &topics["/pose/true"].1;
    assert!(poses.len() >= 10, "{} poses", poses.len());
    let xs: Vec<f64> = poses
        .iter()
        .map(|p| p["pose"]["position"]["x"].as_f64().unwrap())
        .collect();
    let moved = xs.iter().fold(0.0_f64, |m, x| m.max((x - xs[0]).abs()));
    assert!(moved > 0.01, "the true pose never moved: {xs:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
