//! The SICK LMS200 client session over RS-232 (fact sheet section 3), on the telegrams of
//! [`crate::wire::lms200`].
//!
//! Start-up, as ARIA does it: the laser powers up at 9600 baud. Stop any continuous output
//! (0x20 0x25, the reply may be lost in the stream of a laser still sending), enter setup mode
//! with the password (0x20 0x00 `SICK_LMS`), set the angular range and resolution the board
//! describes (0x3B, reply 0xBB), switch to the board's speed (0x20 0x40/0x41, then the port
//! follows), and start continuous output (0x20 0x24). Each request is acknowledged by a single
//! ACK byte (a NACK is a refusal) before its reply telegram. Every measured-values telegram
//! (0xB0) then becomes a [`Scan`] (through [`lms200_scan`]) with its arrival time. Closing stops the continuous output.

use std::time::Duration;

use tokio::io::AsyncWriteExt;
use tokio::time::Instant;

use super::laser::{LaserError, next_decoded};
use super::link::RobotLink;
use crate::sensor::telegram::lms200_scan;
use crate::sensor::{LaserConfig, Scan};
use crate::wire::lms200::{
    DEFAULT_PASSWORD, Event, Lms200Decoder, Lms200Stats, MAX_TELEGRAM_LEN, Mode, Request, Response,
    Variant,
};

/// The LMS200's speed after power-up \[baud\].
pub const POWER_UP_BAUD: u32 = 9600;
/// How long to wait for each reply of the start-up.
pub const REPLY_TIMEOUT: Duration = Duration::from_millis(1500);
/// Distance bits of a measured value in the default (mm, 8 m) configuration.
pub const DISTANCE_MASK: u16 = 0x1FFF;

/// The angular range and resolution a board's laser layout asks for, if the LMS200 has it
/// (180° or 100° at 1°, 0.5° or 0.25°, centred on forward).
pub fn variant_for(laser: &LaserConfig) -> Option<Variant> {
    let step_cdeg = (laser.step_rad.to_degrees() * 100.0).round() as u16;
    let span_deg = (laser.step_rad.to_degrees() * (laser.beam_count.max(1) - 1) as f32).round();
    let v = Variant {
        angle_deg: span_deg as u16,
        resolution_cdeg: step_cdeg,
    };
    let centred =
        (laser.first_angle_rad + v.angle_deg as f32 / 2.0 * core::f32::consts::PI / 180.0).abs()
            < 1e-3;
    let known = matches!(v.angle_deg, 100 | 180) && matches!(v.resolution_cdeg, 100 | 50 | 25);
    (known && centred && v.beam_count() == usize::from(laser.beam_count)).then_some(v)
}

/// The mode that switches the laser to `baud`.
fn baud_mode(baud: u32) -> Option<Mode> {
    match baud {
        9600 => Some(Mode::Baud9600),
        19200 => Some(Mode::Baud19200),
        38400 => Some(Mode::Baud38400),
        _ => None,
    }
}

/// An LMS200 session streaming scans.
pub struct Lms200Client {
    link: Box<dyn RobotLink>,
    decoder: Box<Lms200Decoder>,
    laser: LaserConfig,
    variant: Variant,
    events: std::collections::VecDeque<Reply>,
    buf: Vec<u8>,
    scans: u64,
}

/// What the session takes from the decoder.
enum Reply {
    Ack,
    Nack,
    Telegram(Box<Response>),
    Bad,
}

impl Lms200Client {
    /// Runs the start-up on `link` (at [`POWER_UP_BAUD`]) and starts continuous output at
    /// `baud`.
    pub async fn connect(
        link: Box<dyn RobotLink>,
        laser: LaserConfig,
        baud: u32,
    ) -> Result<Self, LaserError> {
        let refused = |what: &str| LaserError::Lms200(what.to_string());
        let variant = variant_for(&laser).ok_or_else(|| {
            refused("$.laser: an LMS200 scans 180° or 100° at 1°, 0.5° or 0.25°, centred on forward; beam_count, first_angle_deg and step_deg describe no such layout")
        })?;
        let to_baud = baud_mode(baud)
            .ok_or_else(|| refused("$.laser.baud: an LMS200 runs at 9600, 19200 or 38400 baud"))?;
        let mut c = Self {
            link,
            decoder: Box::default(),
            laser,
            variant,
            events: Default::default(),
            buf: vec![0u8; 2048],
            scans: 0,
        };
        // A laser left streaming may drown the reply: send and move on.
        c.send(&Request::SetMode(Mode::Stop)).await?;
        c.drain(Duration::from_millis(200)).await?;
        c.mode(Mode::Setup {
            password: DEFAULT_PASSWORD,
        })
        .await?;
        c.send(&Request::SetVariant(variant)).await?;
        match c.reply().await? {
            Response::VariantReply { accepted: true, .. } => {}
            _ => {
                return Err(refused(
                    "the LMS200 refused the angular range and resolution",
                ));
            }
        }
        if baud != POWER_UP_BAUD {
            c.mode(to_baud).await?;
            c.link.set_baud(baud)?;
            c.decoder.reset();
        }
        c.mode(Mode::ContinuousOutput).await?;
        Ok(c)
    }

    async fn send(&mut self, request: &Request) -> Result<(), LaserError> {
        let mut out = [0u8; MAX_TELEGRAM_LEN];
        let n = request
            .emit(&mut out)
            .map_err(|e| LaserError::Lms200(e.to_string()))?;
        self.link.write_all(&out[..n]).await?;
        self.link.flush().await?;
        Ok(())
    }

    /// Sends a mode change and checks its reply.
    async fn mode(&mut self, mode: Mode) -> Result<(), LaserError> {
        self.send(&Request::SetMode(mode)).await?;
        match self.reply().await? {
            Response::ModeReply { result: 0, .. } => Ok(()),
            Response::ModeReply { result, .. } => Err(LaserError::Lms200(format!(
                "the LMS200 refused mode {mode:?} (result {result})"
            ))),
            other => Err(LaserError::Lms200(format!(
                "unexpected reply {other:?} to mode {mode:?}"
            ))),
        }
    }

    /// The reply telegram to the last request (after its ACK), skipping measured values.
    async fn reply(&mut self) -> Result<Response, LaserError> {
        let deadline = Instant::now() + REPLY_TIMEOUT;
        loop {
            match self.next(deadline).await? {
                None => return Err(LaserError::Lms200("no reply from the LMS200".into())),
                Some(Reply::Nack) => {
                    return Err(LaserError::Lms200("the LMS200 answered NACK".into()));
                }
                Some(Reply::Ack) | Some(Reply::Bad) => {}
                Some(Reply::Telegram(r)) => {
                    if !matches!(*r, Response::MeasuredValues(_)) {
                        return Ok(*r);
                    }
                }
            }
        }
    }

    async fn drain(&mut self, wait: Duration) -> Result<(), LaserError> {
        let deadline = Instant::now() + wait;
        while self.next(deadline).await?.is_some() {}
        Ok(())
    }

    async fn next(&mut self, deadline: Instant) -> Result<Option<Reply>, LaserError> {
        let decoder = &mut self.decoder;
        next_decoded(
            &mut *self.link,
            &mut self.buf,
            &mut self.events,
            deadline,
            |mut input, events| {
                while let Some(event) = decoder.decode(&mut input) {
                    events.push_back(match event {
                        Event::Ack => Reply::Ack,
                        Event::Nack => Reply::Nack,
                        Event::Telegram(t) => match Response::parse(&t) {
                            Ok(r) => Reply::Telegram(Box::new(r)),
                            Err(_) => Reply::Bad,
                        },
                    });
                }
            },
        )
        .await
    }

    /// The next scan and its arrival time, or `None` at `deadline`.
    pub async fn next_scan(
        &mut self,
        deadline: Instant,
    ) -> Result<Option<(Instant, Scan)>, LaserError> {
        loop {
            match self.next(deadline).await? {
                None => return Ok(None),
                Some(Reply::Telegram(r)) => {
                    let Response::MeasuredValues(m) = *r else {
                        continue;
                    };
                    let mut scan = Scan::new();
                    if lms200_scan(
                        &m,
                        self.variant,
                        DISTANCE_MASK,
                        self.laser.max_range_m,
                        &mut scan,
                    )
                    .is_ok()
                    {
                        self.scans += 1;
                        return Ok(Some((Instant::now(), scan)));
                    }
                }
                Some(_) => {}
            }
        }
    }

    /// Scans received so far.
    pub fn scans_received(&self) -> u64 {
        self.scans
    }

    /// Decoder counters.
    pub fn stats(&self) -> Lms200Stats {
        self.decoder.stats()
    }

    /// Stops the continuous output and closes the port.
    pub async fn close(mut self) -> Result<(), LaserError> {
        let r = self.send(&Request::SetMode(Mode::Stop)).await;
        let _ = self.link.shutdown().await;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::onboard::link::DuplexLink;
    use crate::wire::lms200::{MeasuredValues, RangeUnit, Telegram};
    use tokio::io::{AsyncReadExt, DuplexStream};

    fn telegram(r: &Response) -> Vec<u8> {
        let mut buf = [0u8; MAX_TELEGRAM_LEN];
        let n = r.emit(&mut buf).unwrap();
        buf[..n].to_vec()
    }

    /// An LMS200 built on the wire codec: ACK then the reply to every request, measured
    /// values every 50 ms in continuous mode. Logs the requests it parsed.
    async fn fake_lms200(
        mut s: DuplexStream,
        refuse_password: bool,
        log: std::sync::Arc<std::sync::Mutex<Vec<Request>>>,
    ) {
        let mut dec = Lms200Decoder::new();
        let mut buf = [0u8; 256];
        let mut streaming = false;
        loop {
            let read = tokio::time::timeout(Duration::from_millis(50), s.read(&mut buf)).await;
            let n = match read {
                Ok(Ok(0)) | Ok(Err(_)) => return,
                Ok(Ok(n)) => n,
                Err(_) => 0,
            };
            let mut input = &buf[..n];
            let mut out = Vec::new();
            while let Some(Event::Telegram(t)) = dec.decode(&mut input) {
                let t: Telegram<&[u8]> = t;
                assert_eq!(t.address(), 0);
                let req = Request::parse(&t).unwrap();
                log.lock().unwrap().push(req.clone());
                out.push(0x06);
                let reply = match req {
                    Request::SetMode(Mode::Setup { .. }) if refuse_password => {
                        Response::ModeReply {
                            result: 1,
                            status: 0,
                        }
                    }
                    Request::SetMode(m) => {
                        streaming = m == Mode::ContinuousOutput;
                        Response::ModeReply {
                            result: 0,
                            status: 0,
                        }
                    }
                    Request::SetVariant(v) => Response::VariantReply {
                        accepted: true,
                        variant: v,
                        status: 0,
                    },
                    _ => continue,
                };
                out.extend(telegram(&reply));
            }
            if streaming {
                let mut values = heapless::Vec::new();
                for i in 0..181u16 {
                    // 2 m everywhere, no return straight ahead; reflector bits above.
                    let v = if i == 90 { 0 } else { 2000 | 0x2000 };
                    values.push(v).unwrap();
                }
                out.extend(telegram(&Response::MeasuredValues(MeasuredValues {
                    unit: RangeUnit::Mm,
                    flags: 0,
                    values,
                    status: 0,
                })));
            }
            if s.write_all(&out).await.is_err() {
                return;
            }
        }
    }

    fn laser() -> LaserConfig {
        crate::config::BoardConfig {
            laser: crate::config::LaserBoardConfig {
                model: crate::config::Name::new("lms200").unwrap(),
                beam_count: 181,
                first_angle_deg: -90.0,
                step_deg: 1.0,
                ..crate::config::BoardConfig::default().laser
            },
            ..crate::config::BoardConfig::default()
        }
        .laser_config()
    }

    #[tokio::test]
    async fn start_up_switches_speed_then_streams_scans() {
        let (link, peer) = DuplexLink::pair(8192, Some(9600));
        let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        tokio::spawn(fake_lms200(peer, false, log.clone()));
        let mut c = Lms200Client::connect(Box::new(link), laser(), 38400)
            .await
            .unwrap();
        assert_eq!(
            *log.lock().unwrap(),
            [
                Request::SetMode(Mode::Stop),
                Request::SetMode(Mode::Setup {
                    password: DEFAULT_PASSWORD
                }),
                Request::SetVariant(Variant::DEG180_RES1),
                Request::SetMode(Mode::Baud38400),
                Request::SetMode(Mode::ContinuousOutput),
            ]
        );
        let (_, scan) = c
            .next_scan(Instant::now() + Duration::from_secs(1))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(scan.len(), 181);
        let b = scan.beams();
        assert!((b[0].angle_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-5);
        assert!((b[180].angle_rad - core::f32::consts::FRAC_PI_2).abs() < 1e-4);
        // The reflector bit is masked off; no return straight ahead.
        assert_eq!(b[0].range_m, Some(2.0));
        assert_eq!(b[90].range_m, None);
        c.close().await.unwrap();
        tokio::time::sleep(Duration::from_millis(120)).await;
        assert_eq!(
            log.lock().unwrap().last(),
            Some(&Request::SetMode(Mode::Stop))
        );
    }

    #[tokio::test]
    async fn a_refused_password_and_a_bad_layout_are_errors_naming_the_cause() {
        let (link, peer) = DuplexLink::pair(8192, Some(9600));
        tokio::spawn(fake_lms200(peer, true, Default::default()));
        let err = Lms200Client::connect(Box::new(link), laser(), 9600)
            .await
            .err()
            .unwrap();
        assert!(err.to_string().contains("refused mode Setup"), "{err}");
        let mut odd = laser();
        odd.beam_count = 541;
        let (link, _peer) = DuplexLink::pair(64, Some(9600));
        let err = Lms200Client::connect(Box::new(link), odd, 9600)
            .await
            .err()
            .unwrap();
        assert!(err.to_string().contains("$.laser"), "{err}");
    }
}
