//! CoLa-A stream decoder plus every CoLa-A parser (scan data, replies, requests). Never
//! panics; scan telegrams that parse re-encode to bytes that parse and re-encode identically
//! (bytes are compared because a NaN scale factor is not equal to itself).
#![no_main]

use libfuzzer_sys::fuzz_target;
use papillon::sensor::Scan;
use papillon::wire::lms1xx::{ColaDecoder, Reply, Request, ScanTelegram, scandata};

fuzz_target!(|data: &[u8]| {
    let Some((&split, bytes)) = data.split_first() else {
        return;
    };
    let step = (split as usize).max(1) * 8;
    let mut dec = Box::new(ColaDecoder::<16384>::new());
    let mut out = vec![0u8; 32768];
    let mut again = vec![0u8; 32768];
    let mut scan = Scan::new();
    for chunk in bytes.chunks(step) {
        let mut input = chunk;
        while let Some(p) = dec.decode(&mut input) {
            if scandata::is_scan_data(p) {
                if let Ok(t) = ScanTelegram::parse(p) {
                    let _ = papillon::sensor::telegram::lms1xx_scan(&t, 4.0, &mut scan);
                    let n = t.emit(&mut out).expect("fits");
                    let t2 = ScanTelegram::parse(&out[1..n - 1]).expect("re-parses");
                    let m = t2.emit(&mut again).expect("fits");
                    assert_eq!(&out[..n], &again[..m]);
                }
            }
            if let Ok(r) = Reply::parse(p) {
                let n = r.emit(&mut out).expect("fits");
                assert_eq!(Reply::parse(&out[1..n - 1]), Ok(r));
            }
            if let Ok(r) = Request::parse(p) {
                let n = r.emit(&mut out).expect("fits");
                // Requests keep their values; the dialect guess may differ for odd inputs.
                let _ = Request::parse(&out[1..n - 1]).expect("re-parses");
            }
        }
    }
});
