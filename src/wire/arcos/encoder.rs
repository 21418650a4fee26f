//! The ENCODER packet (ID 0x90): accumulated left and right encoder counts, each a 4-byte
//! little-endian signed integer as ARIA reads them (fact sheet 1.8).

use super::frame::{self, Frame};
use super::{EmitError, ParseError};
use crate::wire::bytes::Reader;

/// ENCODER packet ID.
pub const ID: u8 = 0x90;

/// Accumulated wheel encoder counts \[ticks\].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct EncoderPacket {
    /// Left wheel.
    pub left_ticks: i32,
    /// Right wheel.
    pub right_ticks: i32,
}

impl EncoderPacket {
    /// Parses the payload (8 bytes; more are ignored).
    pub fn parse(payload: &[u8]) -> Result<Self, ParseError> {
        let mut r = Reader::new(payload);
        let left_ticks = r.i32_le().ok_or(ParseError::Truncated {
            field: "left encoder",
            offset: 0,
        })?;
        let right_ticks = r.i32_le().ok_or(ParseError::Truncated {
            field: "right encoder",
            offset: 4,
        })?;
        Ok(Self {
            left_ticks,
            right_ticks,
        })
    }

    /// Parses a checked frame with ID 0x90.
    pub fn parse_frame<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        if frame.id() != ID {
            return Err(ParseError::UnexpectedId { got: frame.id() });
        }
        Self::parse(frame.payload())
    }

    /// Encoded length \[bytes\].
    pub const fn buffer_len(&self) -> usize {
        frame::frame_len(8)
    }

    /// Encodes the packet as a complete frame into `buf`; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        frame::emit_with(buf, ID, 8, |w| {
            w.u32_le(self.left_ticks as u32)?;
            w.u32_le(self.right_ticks as u32)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::seeded;
    use rand_core::Rng;

    #[test]
    fn layout_and_round_trip() {
        let e = EncoderPacket {
            left_ticks: -2,
            right_ticks: 0x0102_0304,
        };
        let mut buf = [0u8; 14];
        assert_eq!(e.emit(&mut buf), Ok(14));
        assert_eq!(
            &buf[..12],
            &[0xFA, 0xFB, 11, 0x90, 0xFE, 0xFF, 0xFF, 0xFF, 4, 3, 2, 1]
        );
        let f = Frame::new_checked(&buf[..]).unwrap();
        assert_eq!(EncoderPacket::parse_frame(&f), Ok(e));
        assert_eq!(
            EncoderPacket::parse(&[0; 6]),
            Err(ParseError::Truncated {
                field: "right encoder",
                offset: 4
            })
        );
        let mut rng = seeded(0x90);
        for _ in 0..1000 {
            let e = EncoderPacket {
                left_ticks: rng.next_u32() as i32,
                right_ticks: rng.next_u32() as i32,
            };
            e.emit(&mut buf).unwrap();
            assert_eq!(
                EncoderPacket::parse_frame(&Frame::new_checked(&buf[..]).unwrap()),
                Ok(e)
            );
        }
    }
}
