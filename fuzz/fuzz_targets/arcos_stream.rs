//! ARCOS streaming decoder: arbitrary bytes, split where the first byte says, must never
//! panic; every frame it returns parses (or fails cleanly) as a server packet and as a
//! command, and what parses re-encodes to a frame that parses to the same value.
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::wire::arcos::{Command, Frame, FrameDecoder, ServerPacket};

fuzz_target!(|data: &[u8]| {
    let Some((&split, bytes)) = data.split_first() else {
        return;
    };
    let step = (split as usize).max(1);
    let mut dec = FrameDecoder::new();
    let mut out = [0u8; 300];
    let mut frames = 0u64;
    for chunk in bytes.chunks(step) {
        let mut input = chunk;
        while let Some(frame) = dec.decode(&mut input) {
            frames += 1;
            assert!(frame.total_len() <= 252);
            if let Ok(p) = ServerPacket::parse(&frame) {
                if !matches!(p, ServerPacket::Other { .. } | ServerPacket::Reset { .. }) {
                    if let Ok(n) = p.emit(&mut out) {
                        let f = Frame::new_checked(&out[..n]).expect("emitted frame checks");
                        assert_eq!(ServerPacket::parse(&f).as_ref(), Ok(&p));
                    }
                }
            }
            if let Ok(c) = Command::parse(&frame) {
                let n = c.emit(&mut out).expect("a parsed command re-encodes");
                let f = Frame::new_checked(&out[..n]).expect("emitted frame checks");
                assert_eq!(Command::parse(&f).as_ref(), Ok(&c));
            }
        }
    }
    assert_eq!(dec.stats().frames, frames);
});
