//! The SICK LMS1xx client session (CoLa-A over TCP, fact sheet section 2).
//!
//! Connect sequence (the clearpath LMS1xx driver's order): SetAccessMode, read LMPscancfg,
//! read LMPoutputRange, write LMDscandatacfg, LMCstartmeas, poll STlms until the device reports
//! 7 (ready for measurement), Run, then `sEN LMDscandata 1`; every scan then arrives as an
//! `sSN LMDscandata` telegram and surfaces as a [`Scan`] with its arrival time.
//!
//! The CoLa-A framing and telegram layouts belong to `crate::wire::lms1xx`; the session reads
//! them through a [`LaserCodec`]: [`super::codec::WireLms1xx`] on the robot (its reply check
//! gives [`LaserReply::Refused`], its scans come from `crate::sensor::telegram`), a byte-level
//! double in the tests. The LMS200 (serial) session is [`super::lms200`].

use std::fmt;
use std::io;
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::time::Instant;

use super::link::RobotLink;
use super::sensor_clock::{PassiveClock, WrappingMicros};
use crate::sensor::{LaserConfig, Scan};

/// A request of the connect sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LaserRequest {
    /// `sMN SetAccessMode 03 F4724744` (authorized client).
    SetAccessMode,
    /// `sRN LMPscancfg`.
    ReadScanConfig,
    /// `sRN LMPoutputRange`.
    ReadOutputRange,
    /// `sWN LMDscandatacfg …` (channel 1, distances, no extras).
    WriteScanDataConfig,
    /// `sMN LMCstartmeas`.
    StartMeasurement,
    /// `sRN STlms`.
    ReadState,
    /// `sMN Run`.
    Run,
    /// `sEN LMDscandata 1` / `0`.
    SubscribeScans(bool),
}

/// A telegram from the laser.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum LaserReply {
    /// The expected success reply to `request`.
    Ack(LaserRequest),
    /// The device state from `STlms` (7 = ready for measurement).
    State(u8),
    /// The laser refused `request` (wrong status code).
    Refused {
        /// The request.
        request: LaserRequest,
        /// What the laser said.
        detail: String,
    },
    /// A scan, already converted to the core's type (boxed: a scan is about 9 KB), and the
    /// laser's own time of it (µs since its start-up) when the telegram carries one.
    Scan(Box<Scan>, Option<u32>),
    /// A telegram the session does not use.
    Other,
}

/// Decoder counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaserCodecStats {
    /// Telegrams decoded.
    pub telegrams: u64,
    /// Bytes skipped outside STX…ETX.
    pub junk_bytes: u64,
    /// Telegrams that did not parse.
    pub bad_telegrams: u64,
}

/// A CoLa-A codec for the client side.
pub trait LaserCodec: Send {
    /// Appends the framed request to `out`.
    fn encode(&mut self, request: LaserRequest, out: &mut Vec<u8>);
    /// Feeds received bytes; appends completed telegrams to `out`, converting scans with
    /// `laser`'s layout. Never panics.
    fn decode(&mut self, bytes: &[u8], laser: &LaserConfig, out: &mut Vec<LaserReply>);
    /// Counters.
    fn stats(&self) -> LaserCodecStats;
}

/// Errors of the laser session.
#[derive(Debug)]
#[non_exhaustive]
pub enum LaserError {
    /// The link failed.
    Io(io::Error),
    /// The laser closed the connection.
    Closed,
    /// No reply to a request in time.
    NoReply(LaserRequest),
    /// The laser refused a request.
    Refused {
        /// The request.
        request: LaserRequest,
        /// What it said.
        detail: String,
    },
    /// The laser never became ready (last STlms state).
    NotReady(u8),
    /// The LMS200 start-up failed (what went wrong, or the board field that prevents it).
    Lms200(String),
}

impl fmt::Display for LaserError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LaserError::Io(e) => write!(f, "laser link error: {e}"),
            LaserError::Closed => write!(f, "the laser closed the connection"),
            LaserError::NoReply(r) => write!(f, "no reply from the laser to {r:?}"),
            LaserError::Refused { request, detail } => {
                write!(f, "the laser refused {request:?}: {detail}")
            }
            LaserError::Lms200(what) => write!(f, "LMS200: {what}"),
            LaserError::NotReady(s) => write!(
                f,
                "the laser did not become ready for measurement (state {s}, expected 7)"
            ),
        }
    }
}

impl std::error::Error for LaserError {}

impl From<io::Error> for LaserError {
    fn from(e: io::Error) -> Self {
        LaserError::Io(e)
    }
}

/// An LMS1xx session streaming scans.
pub struct Lms1xxClient {
    link: Box<dyn RobotLink>,
    codec: Box<dyn LaserCodec>,
    laser: LaserConfig,
    replies: std::collections::VecDeque<LaserReply>,
    buf: Vec<u8>,
    reply_timeout: Duration,
    scans: u64,
    /// The laser's clock: each scan is placed by its own time, not by when it was read
    /// ([`super::sensor_clock`]).
    clock: PassiveClock,
    micros: WrappingMicros,
    epoch: Instant,
}

/// How long to wait for each reply of the connect sequence.
pub const REPLY_TIMEOUT: Duration = Duration::from_millis(1000);

/// How many times `STlms` is polled (100 ms apart) before giving up.
pub const READY_POLLS: u32 = 30;

impl Lms1xxClient {
    /// Runs the connect sequence and subscribes to scans.
    pub async fn connect(
        link: Box<dyn RobotLink>,
        codec: Box<dyn LaserCodec>,
        laser: LaserConfig,
    ) -> Result<Self, LaserError> {
        let mut c = Self {
            link,
            codec,
            laser,
            replies: Default::default(),
            buf: vec![0u8; 8192],
            reply_timeout: REPLY_TIMEOUT,
            scans: 0,
            clock: PassiveClock::new(),
            micros: WrappingMicros::default(),
            epoch: Instant::now(),
        };
        for request in [
            LaserRequest::SetAccessMode,
            LaserRequest::ReadScanConfig,
            LaserRequest::ReadOutputRange,
            LaserRequest::WriteScanDataConfig,
            LaserRequest::StartMeasurement,
        ] {
            c.request(request).await?;
        }
        let mut state = 0;
        for _ in 0..READY_POLLS {
            c.send(LaserRequest::ReadState).await?;
            state = match c.reply(LaserRequest::ReadState).await? {
                LaserReply::State(s) => s,
                _ => 0,
            };
            if state == 7 {
                break;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        if state != 7 {
            return Err(LaserError::NotReady(state));
        }
        c.request(LaserRequest::Run).await?;
        c.request(LaserRequest::SubscribeScans(true)).await?;
        Ok(c)
    }

    async fn send(&mut self, request: LaserRequest) -> Result<(), LaserError> {
        let mut out = Vec::new();
        self.codec.encode(request, &mut out);
        self.link.write_all(&out).await?;
        self.link.flush().await?;
        Ok(())
    }

    async fn request(&mut self, request: LaserRequest) -> Result<(), LaserError> {
        self.send(request).await?;
        self.reply(request).await.map(|_| ())
    }

    /// Waits for the reply to `request`, skipping scans and unrelated telegrams.
    async fn reply(&mut self, request: LaserRequest) -> Result<LaserReply, LaserError> {
        let deadline = Instant::now() + self.reply_timeout;
        loop {
            match self.next_reply(deadline).await? {
                None => return Err(LaserError::NoReply(request)),
                Some(LaserReply::Ack(r)) if r == request => return Ok(LaserReply::Ack(r)),
                Some(LaserReply::State(s)) if request == LaserRequest::ReadState => {
                    return Ok(LaserReply::State(s));
                }
                Some(LaserReply::Refused { request: r, detail }) if r == request => {
                    return Err(LaserError::Refused { request, detail });
                }
                Some(_) => {}
            }
        }
    }

    async fn next_reply(&mut self, deadline: Instant) -> Result<Option<LaserReply>, LaserError> {
        let (codec, laser) = (&mut self.codec, &self.laser);
        next_decoded(
            &mut *self.link,
            &mut self.buf,
            &mut self.replies,
            deadline,
            |bytes, replies| {
                let mut out = Vec::new();
                codec.decode(bytes, laser, &mut out);
                replies.extend(out);
            },
        )
        .await
    }

    /// The next scan and its time, or `None` at `deadline` (a dropout when it exceeds the
    /// board's stale timeout): the laser's own time of the scan placed on this computer's
    /// clock ([`super::sensor_clock`]), never later than its arrival, so that a scan read late
    /// is still placed on the odometry of the moment it was taken; its arrival when the
    /// telegram carries no time.
    pub async fn next_scan(
        &mut self,
        deadline: Instant,
    ) -> Result<Option<(Instant, Scan)>, LaserError> {
        loop {
            match self.next_reply(deadline).await? {
                None => return Ok(None),
                Some(LaserReply::Scan(scan, laser_us)) => {
                    self.scans += 1;
                    let arrival = Instant::now();
                    let Some(us) = laser_us else {
                        return Ok(Some((arrival, *scan)));
                    };
                    let arrival_s = arrival.saturating_duration_since(self.epoch).as_secs_f64();
                    let placed_s = self.clock.place(arrival_s, self.micros.seconds(us));
                    let placed = self.epoch + Duration::from_secs_f64(placed_s.max(0.0));
                    return Ok(Some((placed.min(arrival), *scan)));
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
    pub fn codec_stats(&self) -> LaserCodecStats {
        self.codec.stats()
    }

    /// Unsubscribes (`sEN LMDscandata 0`) and closes the connection.
    pub async fn close(mut self) -> Result<(), LaserError> {
        let r = self.send(LaserRequest::SubscribeScans(false)).await;
        let _ = self.link.shutdown().await;
        r
    }
}

/// The next decoded item of a laser link, or `None` at `deadline`: takes the first of
/// `pending`, else reads the link into `buf` and lets `decode` append what the bytes complete.
/// A link closed by the laser is [`LaserError::Closed`].
pub(crate) async fn next_decoded<T>(
    link: &mut dyn RobotLink,
    buf: &mut [u8],
    pending: &mut std::collections::VecDeque<T>,
    deadline: Instant,
    mut decode: impl FnMut(&[u8], &mut std::collections::VecDeque<T>),
) -> Result<Option<T>, LaserError> {
    loop {
        if let Some(item) = pending.pop_front() {
            return Ok(Some(item));
        }
        let n = match tokio::time::timeout_at(deadline, link.read(buf)).await {
            Err(_) => return Ok(None),
            Ok(read) => read?,
        };
        if n == 0 {
            return Err(LaserError::Closed);
        }
        decode(&buf[..n], pending);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::onboard::link::DuplexLink;
    use crate::sensor::Beam;
    use tokio::io::DuplexStream;

    /// A test codec: requests as one ASCII digit (their index), replies as `A<idx>`, `S<state>`,
    /// `R<idx>` (refused) or `N<ranges in cm, one byte each>` (a scan), each framed STX…ETX.
    #[derive(Default)]
    pub(crate) struct ByteCodec {
        pending: Vec<u8>,
        stats: LaserCodecStats,
    }

    const ORDER: [LaserRequest; 9] = [
        LaserRequest::SetAccessMode,
        LaserRequest::ReadScanConfig,
        LaserRequest::ReadOutputRange,
        LaserRequest::WriteScanDataConfig,
        LaserRequest::StartMeasurement,
        LaserRequest::ReadState,
        LaserRequest::Run,
        LaserRequest::SubscribeScans(true),
        LaserRequest::SubscribeScans(false),
    ];

    fn index(r: LaserRequest) -> u8 {
        ORDER.iter().position(|&o| o == r).unwrap() as u8
    }

    impl LaserCodec for ByteCodec {
        fn encode(&mut self, request: LaserRequest, out: &mut Vec<u8>) {
            out.extend_from_slice(&[0x02, b'0' + index(request), 0x03]);
        }
        fn decode(&mut self, bytes: &[u8], laser: &LaserConfig, out: &mut Vec<LaserReply>) {
            self.pending.extend_from_slice(bytes);
            while let Some(end) = self.pending.iter().position(|&b| b == 0x03) {
                let t: Vec<u8> = self.pending.drain(..=end).collect();
                let body = &t[1..t.len() - 1];
                self.stats.telegrams += 1;
                out.push(match body {
                    [b'A', i] => LaserReply::Ack(ORDER[(*i - b'0') as usize]),
                    [b'S', s] => LaserReply::State(*s),
                    [b'R', i] => LaserReply::Refused {
                        request: ORDER[(*i - b'0') as usize],
                        detail: "status 1".into(),
                    },
                    [b'N', ranges @ ..] => {
                        let mut scan = Scan::new();
                        for (i, &cm) in ranges.iter().enumerate() {
                            let _ = scan.push(Beam {
                                angle_rad: laser.beam_angle(i),
                                range_m: Some(cm as f32 * 0.01),
                            });
                        }
                        LaserReply::Scan(Box::new(scan), None)
                    }
                    _ => LaserReply::Other,
                });
            }
        }
        fn stats(&self) -> LaserCodecStats {
            self.stats
        }
    }

    /// A laser that answers the connect sequence (ready at once), then streams a 3-beam scan
    /// every `period` after the subscription, except from `dropout.0` to `dropout.1` after it.
    pub(crate) async fn streaming_laser(
        mut s: DuplexStream,
        period: Duration,
        dropout: (Duration, Duration),
    ) {
        let mut buf = [0u8; 64];
        let mut subscribed_at: Option<Instant> = None;
        let mut next = Instant::now();
        loop {
            tokio::select! {
                read = s.read(&mut buf) => {
                    let n = match read { Ok(0) | Err(_) => return, Ok(n) => n };
                    for t in buf[..n].chunks(3) {
                        let i = t[1] - b'0';
                        let reply: Vec<u8> = if i == 5 {
                            vec![0x02, b'S', 7, 0x03]
                        } else {
                            vec![0x02, b'A', b'0' + i, 0x03]
                        };
                        if s.write_all(&reply).await.is_err() { return; }
                        if i == 7 {
                            subscribed_at = Some(Instant::now());
                            next = Instant::now() + period;
                        }
                        if i == 8 {
                            subscribed_at = None;
                        }
                    }
                }
                _ = tokio::time::sleep_until(next), if subscribed_at.is_some() => {
                    next += period;
                    let since = Instant::now() - subscribed_at.unwrap_or_else(Instant::now);
                    if !(dropout.0..dropout.1).contains(&since)
                        && s.write_all(&[0x02, b'N', 100, 150, 200, 0x03]).await.is_err()
                    {
                        return;
                    }
                }
            }
        }
    }

    async fn fake_laser(
        mut s: DuplexStream,
        ready_after: u32,
        refuse: Option<u8>,
        log: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
    ) {
        let mut polls = 0;
        let mut buf = [0u8; 64];
        loop {
            let n = match s.read(&mut buf).await {
                Ok(0) | Err(_) => return,
                Ok(n) => n,
            };
            for t in buf[..n].chunks(3) {
                let i = t[1] - b'0';
                log.lock().unwrap().push(i);
                let reply: Vec<u8> = if Some(i) == refuse {
                    vec![0x02, b'R', b'0' + i, 0x03]
                } else if i == 5 {
                    polls += 1;
                    vec![0x02, b'S', if polls > ready_after { 7 } else { 6 }, 0x03]
                } else {
                    vec![0x02, b'A', b'0' + i, 0x03]
                };
                s.write_all(&reply).await.unwrap();
                if i == 7 {
                    for k in 0..3u8 {
                        s.write_all(&[0x02, b'N', 100 + k, 150, 200, 0x03])
                            .await
                            .unwrap();
                    }
                }
            }
        }
    }

    #[tokio::test(start_paused = true)]
    async fn connect_sequence_then_scans() {
        let (link, peer) = DuplexLink::pair(4096, None);
        let log = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        tokio::spawn(fake_laser(peer, 2, None, log.clone()));
        let mut laser = LaserConfig::thesis();
        laser.beam_count = 3;
        let mut c = Lms1xxClient::connect(Box::new(link), Box::new(ByteCodec::default()), laser)
            .await
            .unwrap();
        assert_eq!(*log.lock().unwrap(), [0, 1, 2, 3, 4, 5, 5, 5, 6, 7]);
        let mut firsts = Vec::new();
        while let Some((_, scan)) = c
            .next_scan(Instant::now() + Duration::from_millis(300))
            .await
            .unwrap()
        {
            assert_eq!(scan.len(), 3);
            firsts.push(scan.beams()[0].range_m.unwrap());
        }
        assert_eq!(firsts.len(), 3);
        assert!((firsts[2] - 1.02).abs() < 1e-6);
        assert_eq!(c.scans_received(), 3);
        c.close().await.unwrap();
        tokio::time::sleep(Duration::from_millis(10)).await;
        assert_eq!(log.lock().unwrap().last(), Some(&8));
    }

    #[tokio::test(start_paused = true)]
    async fn refusal_and_never_ready_are_errors() {
        let (link, peer) = DuplexLink::pair(4096, None);
        tokio::spawn(fake_laser(peer, 0, Some(0), Default::default()));
        assert!(matches!(
            Lms1xxClient::connect(
                Box::new(link),
                Box::new(ByteCodec::default()),
                LaserConfig::thesis()
            )
            .await,
            Err(LaserError::Refused {
                request: LaserRequest::SetAccessMode,
                ..
            })
        ));
        let (link, peer) = DuplexLink::pair(4096, None);
        tokio::spawn(fake_laser(peer, u32::MAX, None, Default::default()));
        assert!(matches!(
            Lms1xxClient::connect(
                Box::new(link),
                Box::new(ByteCodec::default()),
                LaserConfig::thesis()
            )
            .await,
            Err(LaserError::NotReady(6))
        ));
    }
}
