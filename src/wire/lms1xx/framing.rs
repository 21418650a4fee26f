//! CoLa-A STX/ETX framing and the streaming decoder.

use super::{ETX, EmitError, STX};
use crate::wire::bytes::Writer;

/// What the CoLa-A decoder has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ColaStats {
    /// Complete telegrams returned.
    pub frames: u64,
    /// Telegrams dropped for exceeding the buffer.
    pub oversize: u64,
    /// Telegrams dropped because a new STX arrived before their ETX.
    pub truncated: u64,
    /// Bytes skipped outside telegrams.
    pub skipped_bytes: u64,
}

/// Streaming CoLa-A decoder holding at most `N` payload bytes.
///
/// It skips bytes until STX, collects until ETX and returns the payload between them. An STX
/// inside a telegram restarts collection (the partial telegram is counted as truncated); a
/// telegram longer than `N` is dropped whole and counted as oversize. A 1081-beam telegram with
/// one 16-bit channel is about 6 kB; [`ColaDecoder::DEFAULT_CAPACITY`] leaves room for two.
#[derive(Clone, Debug)]
pub struct ColaDecoder<const N: usize = 16384> {
    buf: [u8; N],
    len: usize,
    in_frame: bool,
    overflow: bool,
    stats: ColaStats,
}

impl<const N: usize> Default for ColaDecoder<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ColaDecoder<N> {
    /// The default capacity \[bytes\].
    pub const DEFAULT_CAPACITY: usize = 16384;

    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            in_frame: false,
            overflow: false,
            stats: ColaStats {
                frames: 0,
                oversize: 0,
                truncated: 0,
                skipped_bytes: 0,
            },
        }
    }

    /// Counters since creation.
    pub fn stats(&self) -> ColaStats {
        self.stats
    }

    /// Drops any partial telegram.
    pub fn reset(&mut self) {
        self.len = 0;
        self.in_frame = false;
        self.overflow = false;
    }

    /// Consumes bytes from `input` until a telegram is complete and returns its payload
    /// (between STX and ETX); `input` is advanced past the ETX. `None` once `input` is
    /// exhausted (a partial telegram is kept).
    pub fn decode<'a>(&'a mut self, input: &mut &[u8]) -> Option<&'a [u8]> {
        loop {
            if !self.in_frame {
                match input.iter().position(|&b| b == STX) {
                    Some(i) => {
                        self.stats.skipped_bytes += i as u64;
                        *input = input.get(i + 1..).unwrap_or(&[]);
                        self.in_frame = true;
                        self.overflow = false;
                        self.len = 0;
                    }
                    None => {
                        self.stats.skipped_bytes += input.len() as u64;
                        *input = &[];
                        return None;
                    }
                }
            }
            let stop = input.iter().position(|&b| b == STX || b == ETX);
            let body_len = stop.unwrap_or(input.len());
            let body = input.get(..body_len).unwrap_or(&[]);
            if !self.overflow {
                match self.buf.get_mut(self.len..self.len + body_len) {
                    Some(dst) => {
                        dst.copy_from_slice(body);
                        self.len += body_len;
                    }
                    None => self.overflow = true,
                }
            }
            let Some(i) = stop else {
                *input = &[];
                return None;
            };
            let delim = input.get(i).copied();
            *input = input.get(i + 1..).unwrap_or(&[]);
            if delim == Some(STX) {
                self.stats.truncated += 1;
                self.len = 0;
                self.overflow = false;
                continue;
            }
            self.in_frame = false;
            if self.overflow {
                self.stats.oversize += 1;
                continue;
            }
            self.stats.frames += 1;
            return self.buf.get(..self.len);
        }
    }
}

/// Writes `STX payload ETX` into `buf`; returns the length.
pub fn emit_frame(buf: &mut [u8], payload: &[u8]) -> Result<usize, EmitError> {
    emit_with(buf, |w| w.bytes(payload).map_err(|_| core::fmt::Error))
}

/// Writes STX, whatever `write` produces, and ETX; returns the length.
pub(crate) fn emit_with(
    buf: &mut [u8],
    write: impl FnOnce(&mut Writer<'_>) -> core::fmt::Result,
) -> Result<usize, EmitError> {
    let err = EmitError::BufferTooSmall {
        capacity: buf.len(),
    };
    let mut w = Writer::new(buf);
    w.u8(STX).map_err(|_| err)?;
    write(&mut w).map_err(|_| err)?;
    w.u8(ETX).map_err(|_| err)?;
    Ok(w.position())
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec::Vec;

    #[test]
    fn frames_junk_restart_and_oversize() {
        let mut dec = ColaDecoder::<20>::new();
        let mut input: &[u8] =
            b"junk\x02sAN Run 1\x03\x02partial\x02sEA LMDscandata 1\x03\x02this one is far too long\x03\x02sRA STlms 7\x03";
        let mut got: Vec<Vec<u8>> = Vec::new();
        while let Some(p) = dec.decode(&mut input) {
            got.push(p.to_vec());
        }
        assert_eq!(
            got,
            std::vec![
                b"sAN Run 1".to_vec(),
                b"sEA LMDscandata 1".to_vec(),
                b"sRA STlms 7".to_vec()
            ]
        );
        let s = dec.stats();
        assert_eq!(
            (s.frames, s.truncated, s.oversize, s.skipped_bytes),
            (3, 1, 1, 4)
        );
    }
}
