//! Standard status packet parser: first byte picks the ID (0x32/0x33 or other), the rest is
//! the payload. Never panics; what parses re-encodes and parses back equal.
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::wire::arcos::{Frame, StatusPacket};

fuzz_target!(|data: &[u8]| {
    let Some((&id, payload)) = data.split_first() else {
        return;
    };
    let id = if id & 0x80 == 0 { 0x32 | (id & 1) } else { id };
    if let Ok(p) = StatusPacket::parse(id, payload) {
        let mut out = [0u8; 300];
        if let Ok(n) = p.emit(&mut out) {
            let f = Frame::new_checked(&out[..n]).expect("emitted frame checks");
            assert_eq!(StatusPacket::parse_frame(&f), Ok(p));
        }
    }
});
