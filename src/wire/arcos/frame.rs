//! ARCOS packet framing and checksum.
//!
//! ```text
//! FA FB | count N | id | payload (N-3 bytes) | checksum hi | checksum lo
//! ```
//! `N` counts the bytes after itself: the ID, the payload and the 2-byte checksum. The checksum
//! runs over the ID and the payload taken as big-endian 16-bit words summed modulo 0x10000, an
//! odd last byte XOR-ed into the low byte; it is sent high byte first (fact sheet 1.1).

use core::fmt;

use super::EmitError;
use crate::wire::bytes::Writer;

/// The two header bytes.
pub const HEADER: [u8; 2] = [0xFA, 0xFB];
/// Smallest valid byte count (ID + checksum).
pub const MIN_BYTE_COUNT: usize = 3;
/// Largest byte count accepted and emitted (the operations manual's command limit).
pub const MAX_BYTE_COUNT: usize = 249;
/// Largest frame on the wire \[bytes\].
pub const MAX_FRAME_LEN: usize = 3 + MAX_BYTE_COUNT;
/// Largest payload (bytes between the ID and the checksum).
pub const MAX_PAYLOAD_LEN: usize = MAX_BYTE_COUNT - 3;

/// The ARCOS checksum of `data` (the ID byte and the payload).
pub fn checksum(data: &[u8]) -> u16 {
    let mut sum: u16 = 0;
    let mut pairs = data.chunks_exact(2);
    for p in &mut pairs {
        let word = u16::from_be_bytes([
            p.first().copied().unwrap_or(0),
            p.get(1).copied().unwrap_or(0),
        ]);
        sum = sum.wrapping_add(word);
    }
    if let Some(&odd) = pairs.remainder().first() {
        sum ^= odd as u16;
    }
    sum
}

/// Errors checking a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum FrameError {
    /// Fewer bytes than the header and byte count announce.
    Truncated {
        /// Bytes the frame needs.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// The first two bytes are not FA FB.
    BadHeader {
        /// The bytes seen.
        got: [u8; 2],
    },
    /// A byte count below 3 or above [`MAX_BYTE_COUNT`].
    BadLength {
        /// The byte count seen.
        count: u8,
    },
    /// The checksum does not match.
    BadChecksum {
        /// Checksum carried by the frame.
        got: u16,
        /// Checksum computed over the frame.
        computed: u16,
    },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Truncated { needed, got } => {
                write!(f, "frame needs {needed} bytes, got {got}")
            }
            FrameError::BadHeader { got } => {
                write!(f, "header {:02X} {:02X}, expected FA FB", got[0], got[1])
            }
            FrameError::BadLength { count } => write!(
                f,
                "byte count {count}, expected {MIN_BYTE_COUNT}..={MAX_BYTE_COUNT}"
            ),
            FrameError::BadChecksum { got, computed } => {
                write!(f, "checksum 0x{got:04X}, computed 0x{computed:04X}")
            }
        }
    }
}

impl core::error::Error for FrameError {}

/// A checked view of one ARCOS frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// Wraps `buffer` after checking the header, the byte count and the checksum. Bytes after
    /// the frame's end are ignored.
    pub fn new_checked(buffer: T) -> Result<Self, FrameError> {
        let b = buffer.as_ref();
        let got = b.len();
        let (Some(&h0), Some(&h1)) = (b.first(), b.get(1)) else {
            return Err(FrameError::Truncated { needed: 3, got });
        };
        if [h0, h1] != HEADER {
            return Err(FrameError::BadHeader { got: [h0, h1] });
        }
        let Some(&count) = b.get(2) else {
            return Err(FrameError::Truncated { needed: 3, got });
        };
        let n = count as usize;
        if !(MIN_BYTE_COUNT..=MAX_BYTE_COUNT).contains(&n) {
            return Err(FrameError::BadLength { count });
        }
        let total = 3 + n;
        let Some(body) = b.get(3..total - 2) else {
            return Err(FrameError::Truncated { needed: total, got });
        };
        let (Some(&hi), Some(&lo)) = (b.get(total - 2), b.get(total - 1)) else {
            return Err(FrameError::Truncated { needed: total, got });
        };
        let got_sum = u16::from_be_bytes([hi, lo]);
        let computed = checksum(body);
        if got_sum != computed {
            return Err(FrameError::BadChecksum {
                got: got_sum,
                computed,
            });
        }
        Ok(Self { buffer })
    }

    fn bytes(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// The byte count field.
    pub fn byte_count(&self) -> u8 {
        self.bytes().get(2).copied().unwrap_or(0)
    }

    /// Total frame length on the wire \[bytes\].
    pub fn total_len(&self) -> usize {
        3 + self.byte_count() as usize
    }

    /// The packet ID (server) or command number (client).
    pub fn id(&self) -> u8 {
        self.bytes().get(3).copied().unwrap_or(0)
    }

    /// The bytes between the ID and the checksum.
    pub fn payload(&self) -> &[u8] {
        let end = self.total_len().saturating_sub(2);
        self.bytes().get(4..end).unwrap_or(&[])
    }

    /// The checksum carried by the frame.
    pub fn checksum(&self) -> u16 {
        let t = self.total_len();
        let b = self.bytes();
        u16::from_be_bytes([
            b.get(t.wrapping_sub(2)).copied().unwrap_or(0),
            b.get(t.wrapping_sub(1)).copied().unwrap_or(0),
        ])
    }

    /// The whole frame, header to checksum.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes().get(..self.total_len()).unwrap_or(&[])
    }
}

/// Frame length for a payload of `payload_len` bytes.
pub const fn frame_len(payload_len: usize) -> usize {
    payload_len + 6
}

/// Writes a frame with packet ID `id` whose payload `write` produces (announced as
/// `payload_len` bytes, used to check the buffer first); returns the frame length.
pub fn emit_with(
    buf: &mut [u8],
    id: u8,
    payload_len: usize,
    write: impl FnOnce(&mut Writer<'_>) -> Result<(), crate::wire::bytes::Overflow>,
) -> Result<usize, EmitError> {
    let count = payload_len + 3;
    if count > MAX_BYTE_COUNT {
        return Err(EmitError::TooLong {
            count,
            max: MAX_BYTE_COUNT,
        });
    }
    let needed = frame_len(payload_len);
    let capacity = buf.len();
    if capacity < needed {
        return Err(EmitError::BufferTooSmall { needed, capacity });
    }
    let too_small = EmitError::BufferTooSmall { needed, capacity };
    let mut w = Writer::new(buf);
    w.bytes(&HEADER).map_err(|_| too_small)?;
    w.u8(0).map_err(|_| too_small)?;
    w.u8(id).map_err(|_| too_small)?;
    write(&mut w).map_err(|_| too_small)?;
    let end = w.position();
    let count = end - 3 + 2;
    if count > MAX_BYTE_COUNT {
        return Err(EmitError::TooLong {
            count,
            max: MAX_BYTE_COUNT,
        });
    }
    let sum = checksum(w.written().get(3..).unwrap_or(&[]));
    w.bytes(&sum.to_be_bytes()).map_err(|_| too_small)?;
    w.patch(2, count as u8).map_err(|_| too_small)?;
    Ok(w.position())
}

/// Writes a frame with ID `id` and the given payload; returns the frame length.
pub fn emit_frame(buf: &mut [u8], id: u8, payload: &[u8]) -> Result<usize, EmitError> {
    emit_with(buf, id, payload.len(), |w| w.bytes(payload))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golden_checksums() {
        // Fact sheet 1.1: ENABLE 1 = 0x043B + 0x0100 = 0x053B.
        assert_eq!(checksum(&[0x04, 0x3B, 0x01, 0x00]), 0x053B);
        assert_eq!(checksum(&[0x1D]), 0x001D);
        assert_eq!(checksum(&[0x05, 0x1B, 0x2C, 0x01]), 0x311C);
        assert_eq!(checksum(&[]), 0);
    }

    #[test]
    fn frame_view_reads_fields() {
        let f = Frame::new_checked(&[0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xC8, 0x00, 0xD3, 0x3B][..])
            .unwrap();
        assert_eq!(f.id(), 0x0B);
        assert_eq!(f.payload(), &[0x3B, 0xC8, 0x00]);
        assert_eq!(f.checksum(), 0xD33B);
        assert_eq!(f.total_len(), 9);
    }

    #[test]
    fn frame_errors_say_what_was_seen() {
        assert_eq!(
            Frame::new_checked(&[0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1E][..]),
            Err(FrameError::BadChecksum {
                got: 0x001E,
                computed: 0x001D
            })
        );
        assert_eq!(
            Frame::new_checked(&[0xFA, 0xFC, 0x03][..]),
            Err(FrameError::BadHeader { got: [0xFA, 0xFC] })
        );
        assert_eq!(
            Frame::new_checked(&[0xFA, 0xFB, 0x02, 0, 0][..]),
            Err(FrameError::BadLength { count: 2 })
        );
        assert_eq!(
            Frame::new_checked(&[0xFA, 0xFB, 0x06, 0x0B][..]),
            Err(FrameError::Truncated { needed: 9, got: 4 })
        );
        assert!(matches!(
            Frame::new_checked(&[0xFA][..]),
            Err(FrameError::Truncated { .. })
        ));
    }

    #[test]
    fn emit_refuses_small_buffers() {
        let mut buf = [0u8; 5];
        assert_eq!(
            emit_frame(&mut buf, 0x1D, &[]),
            Err(EmitError::BufferTooSmall {
                needed: 6,
                capacity: 5
            })
        );
        let mut big = [0u8; 300];
        assert!(matches!(
            emit_frame(&mut big, 0x20, &[0u8; 247]),
            Err(EmitError::TooLong { .. })
        ));
    }
}
