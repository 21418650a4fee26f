//! LMS200 stream decoder plus request/response parsers. Never panics; what parses
//! re-encodes and parses back equal.
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::sensor::Scan;
use papillon::wire::lms200::{Event, Lms200Decoder, Request, Response, Telegram, Variant};

fuzz_target!(|data: &[u8]| {
    let Some((&split, bytes)) = data.split_first() else {
        return;
    };
    let step = (split as usize).max(1);
    let mut dec = Box::new(Lms200Decoder::new());
    let mut out = [0u8; 900];
    let mut scan = Scan::new();
    for chunk in bytes.chunks(step) {
        let mut input = chunk;
        while let Some(ev) = dec.decode(&mut input) {
            let Event::Telegram(t) = ev else { continue };
            if let Ok(r) = Request::parse(&t) {
                let n = r.emit(&mut out).expect("fits");
                let back = Telegram::new_checked(&out[..n]).expect("checks");
                assert_eq!(Request::parse(&back), Ok(r));
            }
            if let Ok(r) = Response::parse(&t) {
                if let Response::MeasuredValues(m) = &r {
                    let v = Variant::DEG180_RES05;
                    let _ = papillon::sensor::telegram::lms200_scan(m, v, 0x1FFF, 8.0, &mut scan);
                }
                let n = r.emit(&mut out).expect("fits");
                let back = Telegram::new_checked(&out[..n]).expect("checks");
                assert_eq!(Response::parse(&back), Ok(r));
            }
        }
    }
});
