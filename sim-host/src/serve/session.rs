//! The endpoint threads of the server: one ARCOS session or laser stream per client, each a
//! sans-IO emulator ([`crate::emulator`]) driven by a loop that reads what the client sent
//! (waiting at most [`POLL_MS`] ms, and never past the next status packet's deadline, so status
//! packets leave on their cycle however long the work took), hands it to the emulator with the
//! server's clock and its robot's body, passes the reply through the fault injectors
//! ([`crate::faults`]) and writes it back.
//!
//! A robot's microcontroller has one client at a time: a TCP client holds it for its whole
//! connection, the pty from its SYNC to its CLOSE. A second TCP client is refused (its
//! connection closed at once, and the refusal logged on stderr) and the first keeps control;
//! bytes on the pty while a TCP client holds the robot are ignored.

use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread;
use std::time::Duration;

use papillon::random::{self, ProjectRng};

use super::{ROBOT_NAME, Sim};
use crate::emulator::arcos::{ArcosEmulator, Link};
use crate::emulator::lms1xx::Lms1xxEmulator;
use crate::emulator::lms200::Lms200Emulator;
use crate::faults::DelayLine;

/// How long an endpoint thread sleeps when it has nothing to read \[ms\].
pub(super) const POLL_MS: u64 = 2;

/// Accepts clients on `listener` for robot `robot`, each served by `serve` in a thread of its
/// own.
pub(super) fn accept_loop(
    listener: TcpListener,
    sim: Arc<Sim>,
    robot: usize,
    serve: fn(&Sim, usize, TcpStream),
) {
    for stream in listener.incoming().flatten() {
        let sim = Arc::clone(&sim);
        thread::spawn(move || serve(&sim, robot, stream));
    }
}

/// Serves robot `robot`'s microcontroller on a pty master.
pub(super) fn arcos_on_pty(sim: &Sim, robot: usize, master: &mut std::fs::File) {
    serve_arcos(sim, robot, master, false);
}

pub(super) fn serve_arcos_tcp(sim: &Sim, robot: usize, stream: TcpStream) {
    if sim.faults.link_cut(sim.now_s()) {
        return; // the cable is out: the connection drops at once
    }
    let peer = stream
        .peer_addr()
        .map_or_else(|_| "?".to_string(), |a| a.to_string());
    if !sim.claim(robot) {
        eprintln!(
            "papillon-sim serve: robot {robot}: refused ARCOS client {peer}: another client has \
             the robot (one client at a time)"
        );
        return; // dropping the stream closes the connection
    }
    let _ = stream.set_nodelay(true);
    serve_arcos(sim, robot, &mut Tcp(stream), true);
    sim.release(robot);
}

/// A TCP stream whose reads wait until a deadline.
struct Tcp(TcpStream);

impl Read for Tcp {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.0.read(buf)
    }
}

impl Write for Tcp {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()
    }
}

/// A link the session loop can wait on until a deadline.
trait Wait {
    /// Makes the next read wait at most `wait` (a TCP read timeout); returns false if reads
    /// do not wait (a non-blocking pty), so the loop sleeps instead.
    fn wait_at_most(&mut self, wait: Duration) -> bool;
    /// The speed the client set on its end of a serial line \[baud\]; `None` over TCP.
    fn line_baud(&self) -> Option<u32> {
        None
    }
}

impl Wait for Tcp {
    fn wait_at_most(&mut self, wait: Duration) -> bool {
        self.0.set_read_timeout(Some(wait)).is_ok()
    }
}

impl Wait for std::fs::File {
    fn wait_at_most(&mut self, _: Duration) -> bool {
        false
    }

    fn line_baud(&self) -> Option<u32> {
        super::pty::slave_baud(self)
    }
}

/// Runs an ARCOS session for robot `robot` over `io` (reads time out or would block when
/// idle) until EOF; a dropped link stops the robot and disables its motors. A TCP link
/// (`drops_on_cut`) is closed when a `cut` fault begins; a serial line just goes silent.
fn serve_arcos(sim: &Sim, robot: usize, io: &mut (impl Read + Write + Wait), drops_on_cut: bool) {
    let mut emu = ArcosEmulator::new(ROBOT_NAME)
        .with_watchdog_ms(sim.watchdog_ms)
        .with_identity(sim.identity)
        .with_subclass(sim.subclass);
    let link = sim.links.fetch_add(1, Ordering::SeqCst);
    let mut rng = random::seeded(sim.seed ^ (link + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    arcos_session(sim, robot, io, &mut emu, &mut rng, drops_on_cut);
    emu.disconnect(&mut sim.bodies()[robot]);
}

fn arcos_session(
    sim: &Sim,
    robot: usize,
    io: &mut (impl Read + Write + Wait),
    emu: &mut ArcosEmulator,
    rng: &mut ProjectRng,
    drops_on_cut: bool,
) {
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    let mut send = Vec::new();
    let mut line = DelayLine::default();
    // Over TCP the claim is the caller's, for the whole connection; on a pty it is taken at
    // the client's first bytes and given back when its session closes.
    let claims_per_session = !drops_on_cut;
    let mut holding = !claims_per_session;
    let mut refused_logged = false;
    let mut opened = false;
    while !sim.stopped() {
        // Wait for input, but not past the next status packet.
        let wait_s = (emu.next_sip_s() - sim.now_s()).clamp(0.0002, POLL_MS as f64 / 1000.0);
        let waits = io.wait_at_most(Duration::from_secs_f64(wait_s));
        let mut n = match io.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            Err(_) => {
                thread::sleep(Duration::from_millis(POLL_MS * 10));
                0
            }
        };
        // A client at another speed than the microcontroller's sends garbage, and reads
        // garbage: modelled as bytes lost both ways.
        let wrong_speed = sim
            .baud
            .is_some_and(|want| io.line_baud().is_some_and(|have| have != want));
        if wrong_speed {
            n = 0;
        }
        if n > 0 && !holding {
            holding = sim.claim(robot);
            if !holding {
                if !refused_logged {
                    eprintln!(
                        "papillon-sim serve: robot {robot}: ignoring the serial line: another \
                         client has the robot (one client at a time)"
                    );
                    refused_logged = true;
                }
                n = 0;
            }
        }
        let now = sim.now_s();
        let cut = sim.faults.link_cut(now);
        if cut && drops_on_cut {
            return;
        }
        {
            let mut bodies = sim.bodies();
            let body = &mut bodies[robot];
            if !cut {
                emu.receive(now, &buf[..n], body, &mut out);
            }
            emu.tick(now, &sim.world, body, &mut out);
        }
        if let Some(config) = emu.sim_laser_due() {
            let scan = sim.scan(robot, config);
            emu.sim_laser_packets(&scan, &sim.bodies()[robot], &mut out);
        }
        opened |= emu.link() == Link::Open;
        if claims_per_session && holding && opened && emu.link() == Link::Idle {
            sim.release(robot);
            holding = false;
            opened = false;
            refused_logged = false;
        }
        if cut || wrong_speed {
            // The firmware runs on (its watchdog halts the robot), but nothing gets through.
            out.clear();
            line.clear();
        } else {
            sim.faults.damage(rng, &mut out);
            line.push(&sim.faults, rng, now, std::mem::take(&mut out));
            line.due(now, &mut send);
        }
        if !send.is_empty() {
            if write_some(io, &send).is_err() {
                return;
            }
            send.clear();
        }
        if n == 0 && !waits {
            // A non-blocking line: sleep until input may have come or a status packet is due.
            let wait_s = (emu.next_sip_s() - sim.now_s()).clamp(0.0, POLL_MS as f64 / 1000.0);
            thread::sleep(Duration::from_secs_f64(wait_s));
        }
    }
    if claims_per_session && holding {
        sim.release(robot);
    }
}

pub(super) fn serve_laser(sim: &Sim, robot: usize, mut stream: TcpStream) {
    let _ = stream.set_nodelay(true);
    if stream
        .set_read_timeout(Some(Duration::from_millis(POLL_MS)))
        .is_err()
    {
        return;
    }
    let mut emu = Lms1xxEmulator::new();
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    while !sim.stopped() {
        let n = match stream.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            Err(_) => return,
        };
        let now = sim.now_s();
        emu.receive(now, &buf[..n], |c| sim.scan(robot, c), &mut out);
        let replies = out.len();
        emu.tick(now, |c| sim.scan(robot, c), &mut out);
        sim.faults.silence_laser(now, &mut out, replies);
        if !out.is_empty() {
            if stream.write_all(&out).is_err() {
                return;
            }
            out.clear();
        }
    }
}

/// Runs the LMS200 of robot `robot` on a pty master (non-blocking) until shutdown.
pub(super) fn serve_lms200(sim: &Sim, robot: usize, io: &mut (impl Read + Write)) {
    let mut emu = Lms200Emulator::new();
    let mut buf = [0u8; 1024];
    let mut out = Vec::new();
    while !sim.stopped() {
        let n = match io.read(&mut buf) {
            Ok(n) => n,
            Err(e) if is_idle(&e) => 0,
            // No client has the slave open: wait for one.
            Err(_) => 0,
        };
        let now = sim.now_s();
        emu.receive(now, &buf[..n], &mut out);
        let replies = out.len();
        emu.tick(now, |c| sim.scan(robot, c), &mut out);
        sim.faults.silence_laser(now, &mut out, replies);
        if !out.is_empty() {
            let _ = write_some(io, &out);
            out.clear();
        }
        if n == 0 {
            thread::sleep(Duration::from_millis(POLL_MS));
        }
    }
}

fn is_idle(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
    )
}

/// Writes `data`; on a full non-blocking pty (no reader) the rest is dropped, as bytes sent
/// down a serial line nobody listens to are lost.
fn write_some(io: &mut impl Write, mut data: &[u8]) -> io::Result<()> {
    while !data.is_empty() {
        match io.write(data) {
            Ok(0) => return Err(io::ErrorKind::WriteZero.into()),
            Ok(n) => data = &data[n..],
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
