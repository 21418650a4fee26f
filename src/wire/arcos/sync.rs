//! SYNC replies (server → client, IDs 0, 1, 2): SYNC0 and SYNC1 are echoed empty; SYNC2
//! carries three NUL-terminated strings: robot name, class and subclass (fact sheet 1.2).

use super::frame::{self, Frame};
use super::{EmitError, Name, ParseError, read_name};

/// A reply to SYNC0, SYNC1 or SYNC2.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SyncReply {
    /// Echo of SYNC0.
    Sync0,
    /// Echo of SYNC1.
    Sync1,
    /// Reply to SYNC2: the robot's identity.
    Sync2 {
        /// Robot name, e.g. "AMRISim".
        name: Name,
        /// Robot class, e.g. "Pioneer".
        class: Name,
        /// Robot subclass, e.g. "p3dx-sh".
        subclass: Name,
    },
}

impl SyncReply {
    /// The packet ID (0, 1 or 2).
    pub fn id(&self) -> u8 {
        match self {
            SyncReply::Sync0 => 0,
            SyncReply::Sync1 => 1,
            SyncReply::Sync2 { .. } => 2,
        }
    }

    /// Parses the payload of a packet with ID `id`. SYNC0/1 payloads are ignored; SYNC2
    /// needs three NUL-terminated strings (bytes after them are ignored).
    pub fn parse(id: u8, payload: &[u8]) -> Result<Self, ParseError> {
        match id {
            0 => Ok(SyncReply::Sync0),
            1 => Ok(SyncReply::Sync1),
            2 => {
                let mut r = crate::wire::bytes::Reader::new(payload);
                Ok(SyncReply::Sync2 {
                    name: read_name(&mut r, "robot name")?,
                    class: read_name(&mut r, "robot class")?,
                    subclass: read_name(&mut r, "robot subclass")?,
                })
            }
            got => Err(ParseError::UnexpectedId { got }),
        }
    }

    /// Parses a checked frame.
    pub fn parse_frame<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<Self, ParseError> {
        Self::parse(frame.id(), frame.payload())
    }

    fn payload_len(&self) -> usize {
        match self {
            SyncReply::Sync2 {
                name,
                class,
                subclass,
            } => name.len() + class.len() + subclass.len() + 3,
            _ => 0,
        }
    }

    /// Encoded length \[bytes\].
    pub fn buffer_len(&self) -> usize {
        frame::frame_len(self.payload_len())
    }

    /// Encodes the reply as a complete frame into `buf`; returns its length.
    pub fn emit(&self, buf: &mut [u8]) -> Result<usize, EmitError> {
        frame::emit_with(buf, self.id(), self.payload_len(), |w| match self {
            SyncReply::Sync2 {
                name,
                class,
                subclass,
            } => {
                w.cstr(name.as_bytes())?;
                w.cstr(class.as_bytes())?;
                w.cstr(subclass.as_bytes())
            }
            _ => Ok(()),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amrisim_sync2_reply() {
        let r = SyncReply::Sync2 {
            name: Name::try_from("AMRISim").unwrap(),
            class: Name::try_from("Pioneer").unwrap(),
            subclass: Name::try_from("p3dx-sh").unwrap(),
        };
        let mut buf = [0u8; 64];
        let n = r.emit(&mut buf).unwrap();
        assert_eq!(&buf[3..n - 2], b"\x02AMRISim\0Pioneer\0p3dx-sh\0");
        let f = Frame::new_checked(&buf[..n]).unwrap();
        assert_eq!(SyncReply::parse_frame(&f), Ok(r));
        // The echoes are the command bytes of fact sheet 1.1.
        let n = SyncReply::Sync0.emit(&mut buf).unwrap();
        assert_eq!(&buf[..n], &[0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00]);
        let n = SyncReply::Sync1.emit(&mut buf).unwrap();
        assert_eq!(&buf[..n], &[0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01]);
        assert_eq!(
            SyncReply::parse(2, b"AMRISim\0Pioneer\0p3dx"),
            Err(ParseError::Truncated {
                field: "robot subclass",
                offset: 16
            })
        );
    }
}
