//! CONFIG packet parser: never panics; what parses re-encodes and parses back equal.
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::wire::arcos::{ConfigPacket, Frame};

fuzz_target!(|data: &[u8]| {
    if let Ok(c) = ConfigPacket::parse(data) {
        let mut out = [0u8; 300];
        if let Ok(n) = c.emit(&mut out) {
            let f = Frame::new_checked(&out[..n]).expect("emitted frame checks");
            assert_eq!(ConfigPacket::parse_frame(&f), Ok(c));
        }
    }
});
