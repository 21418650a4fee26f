//! Byte links to the robot's microcontroller and to the laser.
//!
//! A [`RobotLink`] is an async byte stream (tokio's `AsyncRead + AsyncWrite`) that may also be
//! able to change its serial speed. Three implementations:
//! - [`SerialLink`]: a serial port through `tokio-serial` (the P3-DX's host port, an LMS200);
//! - [`TcpLink`]: a TCP connection (MobileSim / AMRISim, `papillon-sim serve`, serial-to-ethernet
//!   bridges, an LMS1xx). It has no speed to change, and — as ARIA does over TCP — nothing is
//!   written before the handshake (no `WMS2` radio-modem preamble) (fact sheet 1.3);
//! - [`DuplexLink`]: an in-memory pair for tests.
//!
//! [`connect_with_backoff`] retries opening a link with a bounded exponential back-off.

use std::io;
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, DuplexStream};
use tokio::net::TcpStream;
use tokio_serial::{SerialPort, SerialPortBuilderExt, SerialStream};

/// What kind of byte link this is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum LinkKind {
    /// A serial port (real or pseudo-terminal).
    Serial,
    /// A TCP connection.
    Tcp,
    /// An in-memory test link.
    Memory,
}

/// An async byte link to a device.
pub trait RobotLink: AsyncRead + AsyncWrite + Unpin + Send {
    /// What kind of link this is.
    fn kind(&self) -> LinkKind;

    /// The current serial speed \[baud\], `None` when the link has none (TCP, memory).
    fn baud(&self) -> Option<u32>;

    /// Changes the serial speed \[baud\]. Links without a speed return an
    /// [`io::ErrorKind::Unsupported`] error.
    fn set_baud(&mut self, baud: u32) -> io::Result<()>;

    /// A human-readable description for logs (`/dev/ttyS0 @ 9600`, `tcp 127.0.0.1:8101`).
    fn describe(&self) -> String;
}

/// Why a serial port could not be opened, as an [`io::Error`] whose kind tells a permanent
/// error from a passing one ([`permanent_at_start`], [`permanent_always`]): `NotFound` (no
/// such device), `InvalidInput` (not a serial port: `/dev/null`, a plain file),
/// `PermissionDenied`, or another kind.
fn open_error(path: &str, e: tokio_serial::Error) -> io::Error {
    use io::ErrorKind as K;
    let flag = "check --port (or the board's $.link.port)";
    let kind = match e.kind() {
        tokio_serial::ErrorKind::Io(kind) => kind,
        _ => K::Other,
    };
    match std::fs::symlink_metadata(path).and_then(|_| std::fs::metadata(path)) {
        Err(m) if m.kind() == K::NotFound => {
            return io::Error::new(
                K::NotFound,
                format!(
                    "serial port {path}: no such device; {flag}; `papillon ports` lists this machine's"
                ),
            );
        }
        Ok(_) if !is_terminal_device(path) => {
            return io::Error::new(
                K::InvalidInput,
                format!("{path} is not a serial port (not a terminal device); {flag}"),
            );
        }
        _ => {}
    }
    if kind == K::PermissionDenied {
        return io::Error::new(
            K::PermissionDenied,
            format!("serial port {path}: permission denied (is this user in the `dialout` group?)"),
        );
    }
    io::Error::new(kind, format!("cannot open serial port {path}: {e}"))
}

/// Whether `path` opens (without waiting for a carrier and without becoming this process's
/// controlling terminal) as a terminal device, which a serial port is.
#[cfg(unix)]
fn is_terminal_device(path: &str) -> bool {
    use std::io::IsTerminal;
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .is_ok_and(|f| f.is_terminal())
}

#[cfg(not(unix))]
fn is_terminal_device(_path: &str) -> bool {
    true
}

/// Whether a link that failed to open with `e` at start-up should be given up at once: the
/// device does not exist, is not a serial port, or may not be opened. Only a refused or
/// timed-out connection (a robot still booting, a bridge not yet up) is worth the back-off.
pub fn permanent_at_start(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::NotFound | io::ErrorKind::InvalidInput | io::ErrorKind::PermissionDenied
    )
}

/// Whether a link that failed to reopen with `e` after a loss should be given up: as
/// [`permanent_at_start`], except that a missing device is waited for (a USB serial adapter
/// disappears while it re-enumerates).
pub fn permanent_always(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::InvalidInput | io::ErrorKind::PermissionDenied
    )
}

/// A serial port.
pub struct SerialLink {
    stream: SerialStream,
    path: String,
}

impl SerialLink {
    /// Opens `path` at `baud`, 8 data bits, no parity, 1 stop bit, no flow control (the ARCOS
    /// host port settings), in exclusive mode where the platform supports it.
    pub fn open(path: &str, baud: u32) -> io::Result<Self> {
        let stream = tokio_serial::new(path, baud)
            .data_bits(tokio_serial::DataBits::Eight)
            .parity(tokio_serial::Parity::None)
            .stop_bits(tokio_serial::StopBits::One)
            .flow_control(tokio_serial::FlowControl::None)
            .open_native_async()
            .map_err(|e| open_error(path, e))?;
        Ok(Self {
            stream,
            path: path.to_string(),
        })
    }

    /// Wraps an already open stream (a pseudo-terminal pair in tests).
    pub fn from_stream(stream: SerialStream, path: &str) -> Self {
        Self {
            stream,
            path: path.to_string(),
        }
    }
}

impl AsyncRead for SerialLink {
    fn poll_read(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &mut tokio::io::ReadBuf<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for SerialLink {
    fn poll_write(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &[u8],
    ) -> std::task::Poll<io::Result<usize>> {
        std::pin::Pin::new(&mut self.stream).poll_write(cx, buf)
    }
    fn poll_flush(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_flush(cx)
    }
    fn poll_shutdown(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_shutdown(cx)
    }
}

impl RobotLink for SerialLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Serial
    }
    fn baud(&self) -> Option<u32> {
        self.stream.baud_rate().ok()
    }
    fn set_baud(&mut self, baud: u32) -> io::Result<()> {
        self.stream
            .set_baud_rate(baud)
            .map_err(|e| io::Error::other(format!("cannot set {} to {baud} baud: {e}", self.path)))
    }
    fn describe(&self) -> String {
        match self.baud() {
            Some(b) => format!("{} @ {b} baud", self.path),
            None => self.path.clone(),
        }
    }
}

/// A TCP connection.
pub struct TcpLink {
    stream: TcpStream,
    peer: String,
}

impl TcpLink {
    /// Connects to `addr` (`host:port`) with Nagle's algorithm off (commands are small and
    /// time-critical).
    pub async fn connect(addr: &str) -> io::Result<Self> {
        let stream = TcpStream::connect(addr)
            .await
            .map_err(|e| io::Error::new(e.kind(), format!("cannot connect to {addr}: {e}")))?;
        stream.set_nodelay(true)?;
        Ok(Self {
            stream,
            peer: addr.to_string(),
        })
    }
}

impl AsyncRead for TcpLink {
    fn poll_read(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &mut tokio::io::ReadBuf<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for TcpLink {
    fn poll_write(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &[u8],
    ) -> std::task::Poll<io::Result<usize>> {
        std::pin::Pin::new(&mut self.stream).poll_write(cx, buf)
    }
    fn poll_flush(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_flush(cx)
    }
    fn poll_shutdown(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_shutdown(cx)
    }
}

impl RobotLink for TcpLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Tcp
    }
    fn baud(&self) -> Option<u32> {
        None
    }
    fn set_baud(&mut self, _baud: u32) -> io::Result<()> {
        Err(io::Error::new(
            io::ErrorKind::Unsupported,
            "a TCP link has no baud rate",
        ))
    }
    fn describe(&self) -> String {
        format!("tcp {}", self.peer)
    }
}

/// One end of an in-memory link, for tests. It records the baud rates it was set to, so a
/// test can check a HOSTBAUD switch.
pub struct DuplexLink {
    stream: DuplexStream,
    baud: Option<u32>,
    /// Every speed the link was set to, in order \[baud\].
    pub baud_history: Vec<u32>,
}

impl DuplexLink {
    /// A connected pair of links with `capacity` bytes of buffering each way; the first end
    /// behaves like a serial port at `baud` (or has no speed when `None`).
    pub fn pair(capacity: usize, baud: Option<u32>) -> (DuplexLink, DuplexStream) {
        let (a, b) = tokio::io::duplex(capacity);
        (
            DuplexLink {
                stream: a,
                baud,
                baud_history: Vec::new(),
            },
            b,
        )
    }
}

impl AsyncRead for DuplexLink {
    fn poll_read(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &mut tokio::io::ReadBuf<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for DuplexLink {
    fn poll_write(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &[u8],
    ) -> std::task::Poll<io::Result<usize>> {
        std::pin::Pin::new(&mut self.stream).poll_write(cx, buf)
    }
    fn poll_flush(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_flush(cx)
    }
    fn poll_shutdown(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<io::Result<()>> {
        std::pin::Pin::new(&mut self.stream).poll_shutdown(cx)
    }
}

impl RobotLink for DuplexLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Memory
    }
    fn baud(&self) -> Option<u32> {
        self.baud
    }
    fn set_baud(&mut self, baud: u32) -> io::Result<()> {
        match self.baud {
            Some(_) => {
                self.baud = Some(baud);
                self.baud_history.push(baud);
                Ok(())
            }
            None => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "this memory link has no baud rate",
            )),
        }
    }
    fn describe(&self) -> String {
        "memory link".to_string()
    }
}

/// A bounded exponential back-off for reconnecting a lost link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Backoff {
    /// Wait before the second attempt.
    pub initial: Duration,
    /// Longest wait between attempts.
    pub max: Duration,
    /// Attempts before giving up (at least 1).
    pub max_attempts: u32,
}

impl Default for Backoff {
    /// 100 ms, doubling up to 5 s, 12 attempts (about 35 s in all).
    fn default() -> Self {
        Self {
            initial: Duration::from_millis(100),
            max: Duration::from_secs(5),
            max_attempts: 12,
        }
    }
}

impl Backoff {
    /// The wait after failed attempt number `attempt` (1-based): `initial · 2^(attempt-1)`,
    /// capped at `max`.
    pub fn delay(&self, attempt: u32) -> Duration {
        let factor = 1u32 << attempt.saturating_sub(1).min(20);
        self.initial.saturating_mul(factor).min(self.max)
    }
}

/// Calls `open` until it succeeds, waiting [`Backoff::delay`] between attempts; returns the
/// last error after `policy.max_attempts` failures, or at once for an error `permanent` says
/// will not pass. `on_failure(attempt, error)` is called for each other failure (for logs).
pub async fn connect_with_backoff<T, F, Fut>(
    policy: Backoff,
    mut open: F,
    permanent: fn(&io::Error) -> bool,
    mut on_failure: impl FnMut(u32, &io::Error),
) -> io::Result<T>
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = io::Result<T>>,
{
    let attempts = policy.max_attempts.max(1);
    let mut attempt = 1;
    loop {
        match open().await {
            Ok(link) => return Ok(link),
            Err(e) => {
                if permanent(&e) {
                    return Err(e);
                }
                on_failure(attempt, &e);
                if attempt >= attempts {
                    return Err(e);
                }
                tokio::time::sleep(policy.delay(attempt)).await;
                attempt += 1;
            }
        }
    }
}

/// Opens the robot link a board and the command line ask for: TCP when `tcp` is given,
/// otherwise the serial port at `baud`.
pub async fn open_robot_link(
    tcp: Option<&str>,
    port: &str,
    baud: u32,
) -> io::Result<Box<dyn RobotLink>> {
    match tcp {
        Some(addr) => Ok(Box::new(TcpLink::connect(addr).await?)),
        None => Ok(Box::new(SerialLink::open(port, baud)?)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    #[tokio::test]
    async fn duplex_carries_bytes_both_ways_and_records_bauds() {
        let (mut link, mut peer) = DuplexLink::pair(64, Some(9600));
        link.write_all(b"\xFA\xFB\x03\x00\x00\x00").await.unwrap();
        let mut got = [0u8; 6];
        peer.read_exact(&mut got).await.unwrap();
        assert_eq!(got, *b"\xFA\xFB\x03\x00\x00\x00");
        peer.write_all(b"abc").await.unwrap();
        let mut back = [0u8; 3];
        link.read_exact(&mut back).await.unwrap();
        assert_eq!(&back, b"abc");
        link.set_baud(38400).unwrap();
        assert_eq!(link.baud(), Some(38400));
        assert_eq!(link.baud_history, [38400]);
    }

    #[tokio::test]
    async fn duplex_without_speed_refuses_baud_change() {
        let (mut link, _peer) = DuplexLink::pair(64, None);
        let err = link.set_baud(38400).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::Unsupported);
    }

    #[test]
    fn backoff_doubles_and_caps() {
        let b = Backoff {
            initial: Duration::from_millis(100),
            max: Duration::from_millis(1000),
            max_attempts: 10,
        };
        let delays: Vec<u128> = (1..=6).map(|a| b.delay(a).as_millis()).collect();
        assert_eq!(delays, [100, 200, 400, 800, 1000, 1000]);
        assert_eq!(b.delay(1000), Duration::from_millis(1000));
    }

    #[tokio::test(start_paused = true)]
    async fn connect_with_backoff_retries_then_succeeds() {
        let mut calls = 0;
        let mut failures = Vec::new();
        let got = connect_with_backoff(
            Backoff {
                initial: Duration::from_millis(10),
                max: Duration::from_millis(40),
                max_attempts: 5,
            },
            || {
                calls += 1;
                let n = calls;
                async move {
                    if n < 3 {
                        Err(io::Error::other("refused"))
                    } else {
                        Ok(n)
                    }
                }
            },
            |_| false,
            |attempt, _| failures.push(attempt),
        )
        .await
        .unwrap();
        assert_eq!(got, 3);
        assert_eq!(failures, [1, 2]);
    }

    #[tokio::test(start_paused = true)]
    async fn connect_with_backoff_gives_up_after_max_attempts() {
        let mut calls = 0u32;
        let err = connect_with_backoff(
            Backoff {
                initial: Duration::from_millis(10),
                max: Duration::from_millis(40),
                max_attempts: 4,
            },
            || {
                calls += 1;
                async { Err::<(), _>(io::Error::other("refused")) }
            },
            |_| false,
            |_, _| {},
        )
        .await
        .unwrap_err();
        assert_eq!(calls, 4);
        assert_eq!(err.to_string(), "refused");
    }

    #[tokio::test(start_paused = true)]
    async fn connect_with_backoff_gives_up_at_once_on_a_permanent_error() {
        let mut calls = 0u32;
        let mut logged = 0u32;
        let err = connect_with_backoff(
            Backoff::default(),
            || {
                calls += 1;
                async { Err::<(), _>(io::Error::new(io::ErrorKind::NotFound, "gone")) }
            },
            permanent_at_start,
            |_, _| logged += 1,
        )
        .await
        .unwrap_err();
        assert_eq!((calls, logged), (1, 0));
        assert_eq!(err.kind(), io::ErrorKind::NotFound);
    }

    #[cfg(unix)]
    #[test]
    fn a_missing_device_and_a_device_that_is_no_serial_port_are_told_apart() {
        let missing = match SerialLink::open("/dev/papillon-no-such-port", 9600) {
            Err(e) => e,
            Ok(_) => panic!("opened a missing device"),
        };
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
        assert!(missing.to_string().contains("no such device"), "{missing}");
        assert!(permanent_at_start(&missing) && !permanent_always(&missing));
        let null = match SerialLink::open("/dev/null", 9600) {
            Err(e) => e,
            Ok(_) => panic!("opened /dev/null as a serial port"),
        };
        assert_eq!(null.kind(), io::ErrorKind::InvalidInput);
        assert!(null.to_string().contains("not a serial port"), "{null}");
        assert!(permanent_at_start(&null) && permanent_always(&null));
    }

    #[tokio::test]
    async fn tcp_link_talks_to_a_loopback_listener() {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let server = tokio::spawn(async move {
            let (mut s, _) = listener.accept().await.unwrap();
            let mut b = [0u8; 4];
            s.read_exact(&mut b).await.unwrap();
            s.write_all(&b).await.unwrap();
        });
        let mut link = TcpLink::connect(&addr).await.unwrap();
        assert_eq!(link.kind(), LinkKind::Tcp);
        assert_eq!(link.baud(), None);
        assert!(link.set_baud(9600).is_err());
        link.write_all(b"ping").await.unwrap();
        let mut b = [0u8; 4];
        link.read_exact(&mut b).await.unwrap();
        assert_eq!(&b, b"ping");
        server.await.unwrap();
    }

    #[tokio::test]
    async fn serial_link_over_a_pseudo_terminal() {
        let (a, mut b) = SerialStream::pair().expect("a pseudo-terminal pair");
        let mut link = SerialLink::from_stream(a, "pty");
        assert_eq!(link.kind(), LinkKind::Serial);
        // termios speed changes on a pty succeed and are ignored (fact sheet 1.3).
        link.set_baud(38400).unwrap();
        link.write_all(b"\xFA\xFB").await.unwrap();
        let mut got = [0u8; 2];
        b.read_exact(&mut got).await.unwrap();
        assert_eq!(got, [0xFA, 0xFB]);
    }
}
