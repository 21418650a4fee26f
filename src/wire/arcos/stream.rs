//! Streaming ARCOS frame decoder.
//!
//! Bytes arrive in arbitrary pieces (split or merged reads), possibly with junk before the
//! first header (ARIA writes `WMS2\r` on opening a serial port) or corruption anywhere. The
//! decoder keeps at most one frame's worth of bytes ([`MAX_FRAME_LEN`]) in a fixed buffer. It
//! hunts for `FA FB`, checks the byte count and the checksum, and on any failure drops the
//! first byte of the candidate and hunts again from the next byte, so a valid frame hidden
//! behind a false header is still found. Dropped bytes and frames are counted in
//! [`DecoderStats`].

use super::frame::{Frame, HEADER, MAX_BYTE_COUNT, MAX_FRAME_LEN, MIN_BYTE_COUNT, checksum};

/// What the decoder has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Valid frames returned.
    pub frames: u64,
    /// Candidate frames dropped for a bad checksum.
    pub bad_checksum: u64,
    /// Candidate frames dropped for a byte count outside 3..=249.
    pub bad_length: u64,
    /// Bytes skipped while hunting for a header (junk and the first bytes of dropped frames).
    pub skipped_bytes: u64,
}

/// A streaming ARCOS frame decoder with a fixed buffer.
#[derive(Clone, Debug)]
pub struct FrameDecoder {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    /// Bytes of a frame returned by the previous call, to drop on the next call.
    consumed: usize,
    stats: DecoderStats,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            consumed: 0,
            stats: DecoderStats {
                frames: 0,
                bad_checksum: 0,
                bad_length: 0,
                skipped_bytes: 0,
            },
        }
    }

    /// Counters since creation.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes held waiting for the rest of a frame.
    pub fn buffered(&self) -> usize {
        self.len - self.consumed
    }

    /// Drops any partial frame (e.g. after a gap in the byte stream longer than a frame
    /// time); the counters are kept.
    pub fn reset(&mut self) {
        self.len = 0;
        self.consumed = 0;
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    /// Looks for a complete valid frame at the start of the buffer, dropping what cannot
    /// start one. Returns the frame's length.
    fn scan(&mut self) -> Option<usize> {
        loop {
            // Hunt for FA FB.
            let start = self
                .buf
                .get(..self.len)?
                .iter()
                .position(|&b| b == HEADER[0]);
            let skip = start.unwrap_or(self.len);
            if skip > 0 {
                self.stats.skipped_bytes += skip as u64;
                self.drop_front(skip);
            }
            if self.len < 2 {
                return None;
            }
            if self.buf.get(1) != Some(&HEADER[1]) {
                self.stats.skipped_bytes += 1;
                self.drop_front(1);
                continue;
            }
            if self.len < 3 {
                return None;
            }
            let count = *self.buf.get(2)? as usize;
            if !(MIN_BYTE_COUNT..=MAX_BYTE_COUNT).contains(&count) {
                self.stats.bad_length += 1;
                self.stats.skipped_bytes += 1;
                self.drop_front(1);
                continue;
            }
            let total = 3 + count;
            if self.len < total {
                return None;
            }
            let body = self.buf.get(3..total - 2)?;
            let computed = checksum(body);
            let got = u16::from_be_bytes([*self.buf.get(total - 2)?, *self.buf.get(total - 1)?]);
            if got != computed {
                self.stats.bad_checksum += 1;
                self.stats.skipped_bytes += 1;
                self.drop_front(1);
                continue;
            }
            return Some(total);
        }
    }

    /// Consumes bytes from the front of `input` until a valid frame is complete and returns
    /// it; `input` is advanced past the bytes used. Returns `None` once `input` is exhausted
    /// without completing a frame (the partial frame is kept for the next call).
    ///
    /// ```
    /// use papillon::wire::arcos::{Command, FrameDecoder};
    /// let mut dec = FrameDecoder::new();
    /// let mut input: &[u8] = b"WMS2\r\xFA\xFB\x03\x1D\x00\x1D";
    /// let mut got = None;
    /// while let Some(frame) = dec.decode(&mut input) {
    ///     got = Some(Command::parse(&frame).unwrap());
    /// }
    /// assert_eq!(got, Some(Command::Stop));
    /// assert_eq!(dec.stats().skipped_bytes, 5);
    /// ```
    pub fn decode<'a>(&'a mut self, input: &mut &[u8]) -> Option<Frame<&'a [u8]>> {
        if self.consumed > 0 {
            let n = self.consumed;
            self.consumed = 0;
            self.drop_front(n);
        }
        loop {
            if let Some(total) = self.scan() {
                self.consumed = total;
                self.stats.frames += 1;
                let bytes = self.buf.get(..total)?;
                return Frame::new_checked(bytes).ok();
            }
            // Copy as many input bytes as fit, then scan again.
            let room = MAX_FRAME_LEN - self.len;
            if input.is_empty() {
                return None;
            }
            // Feed at most what the pending candidate still needs, so that at most one frame
            // completes per scan and buffer space is never exceeded.
            let need = self.bytes_needed().min(room).max(1);
            let n = need.min(input.len());
            let (head, tail) = input.split_at(n);
            self.buf
                .get_mut(self.len..self.len + n)?
                .copy_from_slice(head);
            self.len += n;
            *input = tail;
        }
    }

    /// Bytes still needed to complete the candidate at the front of the buffer.
    fn bytes_needed(&self) -> usize {
        match self.buf.get(2) {
            Some(&c) if self.len >= 3 => (3 + c as usize).saturating_sub(self.len),
            _ => 3usize.saturating_sub(self.len),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::command::tests::random_command;
    use super::super::command::{Command, MAX_COMMAND_LEN};
    use super::super::sip::tests::random_sip;
    use super::super::{ServerPacket, StatusPacket};
    use super::*;
    use crate::random::{below, seeded};
    use rand_core::Rng;

    extern crate std;
    use std::vec::Vec;

    fn decode_all(dec: &mut FrameDecoder, chunks: &[&[u8]]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        for c in chunks {
            let mut input = *c;
            while let Some(f) = dec.decode(&mut input) {
                out.push(f.as_bytes().to_vec());
            }
        }
        out
    }

    #[test]
    fn skips_aria_junk_and_counts_bad_frames() {
        let mut dec = FrameDecoder::new();
        let stream: &[u8] = &[
            b'W', b'M', b'S', b'2', b'\r', // ARIA's modem junk
            0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00, // SYNC0
            0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1E, // STOP with a bad checksum
            0xFA, 0xFB, 0x01, // bad byte count
            0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D, // STOP
        ];
        let got = decode_all(&mut dec, &[stream]);
        assert_eq!(got.len(), 2);
        assert_eq!(got[1], [0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D]);
        let s = dec.stats();
        assert_eq!(s.frames, 2);
        assert_eq!(s.bad_checksum, 1);
        assert_eq!(s.bad_length, 1);
        assert_eq!(dec.buffered(), 0);
    }

    #[test]
    fn false_header_does_not_swallow_a_frame() {
        // A header announcing 249 bytes, then a real frame inside its span.
        let mut stream = std::vec![0xFA, 0xFB, 249];
        stream.extend_from_slice(&[0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D]);
        let mut dec = FrameDecoder::new();
        let mut got = decode_all(&mut dec, &[&stream]);
        // The real frame comes out once enough bytes arrive to refute the false one.
        got.extend(decode_all(&mut dec, &[&[0u8; 250]]));
        assert_eq!(
            got,
            std::vec![std::vec![0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D]]
        );
        assert_eq!(dec.stats().bad_checksum, 1);
    }

    fn random_stream(
        rng: &mut crate::random::ProjectRng,
        garbage: bool,
    ) -> (Vec<u8>, Vec<Vec<u8>>) {
        let mut stream = Vec::new();
        let mut frames = Vec::new();
        let mut buf = [0u8; MAX_COMMAND_LEN];
        for _ in 0..40 {
            if garbage && below(rng, 3) == 0 {
                // Garbage that never contains FA, so it cannot hide the next frame.
                for _ in 0..below(rng, 30) {
                    let b = rng.next_u32() as u8;
                    stream.push(if b == 0xFA { 0x00 } else { b });
                }
            }
            let n = if below(rng, 2) == 0 {
                random_command(rng).emit(&mut buf).unwrap()
            } else {
                random_sip(rng).emit(&mut buf).unwrap()
            };
            stream.extend_from_slice(&buf[..n]);
            frames.push(buf[..n].to_vec());
        }
        (stream, frames)
    }

    fn random_split<'a>(rng: &mut crate::random::ProjectRng, s: &'a [u8]) -> Vec<&'a [u8]> {
        let mut out = Vec::new();
        let mut rest = s;
        while !rest.is_empty() {
            let n = 1 + below(rng, rest.len().min(300));
            let (a, b) = rest.split_at(n);
            out.push(a);
            rest = b;
        }
        out
    }

    #[test]
    fn any_split_gives_the_same_frames() {
        let mut rng = seeded(0x5717);
        for _ in 0..300 {
            let (stream, frames) = random_stream(&mut rng, false);
            let chunks = random_split(&mut rng, &stream);
            let mut dec = FrameDecoder::new();
            assert_eq!(decode_all(&mut dec, &chunks), frames);
            let mut dec = FrameDecoder::new();
            assert_eq!(decode_all(&mut dec, &[&stream]), frames);
        }
    }

    #[test]
    fn recovers_after_garbage() {
        let mut rng = seeded(0x6A4B);
        for _ in 0..300 {
            let (stream, frames) = random_stream(&mut rng, true);
            let chunks = random_split(&mut rng, &stream);
            let mut dec = FrameDecoder::new();
            let got = decode_all(&mut dec, &chunks);
            assert_eq!(got, frames);
        }
        // Arbitrary garbage (FA included): every frame after a clean run of frames is found
        // once the garbage is refuted, and nothing panics.
        for _ in 0..300 {
            let mut stream = Vec::new();
            for _ in 0..below(&mut rng, 600) {
                stream.push(if below(&mut rng, 8) == 0 {
                    0xFA
                } else {
                    rng.next_u32() as u8
                });
            }
            // Enough padding to refute any false header in the garbage.
            stream.extend_from_slice(&[0u8; MAX_FRAME_LEN]);
            let (tail, frames) = random_stream(&mut rng, false);
            stream.extend_from_slice(&tail);
            let chunks = random_split(&mut rng, &stream);
            let mut dec = FrameDecoder::new();
            let got = decode_all(&mut dec, &chunks);
            assert!(got.len() >= frames.len());
            assert_eq!(got[got.len() - frames.len()..], frames[..]);
        }
    }

    #[test]
    fn decoded_frames_parse_back() {
        let mut rng = seeded(77);
        let mut buf = [0u8; 256];
        let sip = random_sip(&mut rng);
        let n = sip.emit(&mut buf).unwrap();
        let mut dec = FrameDecoder::new();
        let mut input = &buf[..n];
        let f = dec.decode(&mut input).unwrap();
        assert_eq!(
            ServerPacket::parse(&f),
            Ok(ServerPacket::Status(sip.clone()))
        );
        assert_eq!(StatusPacket::parse_frame(&f), Ok(sip));
        let _ = Command::Stop;
    }
}
