//! Decoding throughput of the wire codecs [MB/s]: a stream of ARCOS standard status packets
//! (framing, checksum and SIP parsing) and a stream of LMS1xx `LMDscandata` telegrams (CoLa-A
//! framing and full telegram parsing, 541 beams each), plus the LMS1xx telegram converted to a
//! `Scan`.
//!
//! Run: `cargo bench -p papillon --bench wire -- --warm-up-time 1 --measurement-time 3`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use papillon::sensor::Scan;
use papillon::wire::arcos::{FrameDecoder, SipExtras, SonarReading, StatusPacket};
use papillon::wire::lms1xx::{ColaDecoder, ScanTelegram};

/// 1000 AMRISim-like SIPs (16 sonar readings, trailing fields through STATEOFCHARGE).
fn sip_stream() -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; 256];
    for k in 0..1000u16 {
        let mut p = StatusPacket {
            x_pos: k.wrapping_mul(7) & 0x7FFF,
            y_pos: k,
            th_pos: (k % 4096) as i16 - 2048,
            left_vel_mm_s: 200,
            right_vel_mm_s: 210,
            battery_dv: 130,
            flags: 0x1F,
            ..Default::default()
        };
        for i in 0..16 {
            p.sonar
                .push(SonarReading {
                    number: i,
                    range_mm: 1000 + k + i as u16,
                })
                .unwrap();
        }
        p.extras = SipExtras {
            grip_state: Some(0),
            anport: Some(0),
            analog: Some(0),
            digin: Some(0xFF),
            digout: Some(0xFF),
            battery_dv_x10: Some(130),
            charge_state: Some(0),
            rot_vel_ddeg_s: Some(5),
            fault_flags: Some(0),
            lat_vel_mm_s: Some(0),
            temperature_c: Some(-127),
            state_of_charge_pct: Some(0),
            uc_time_us: None,
            flags3: None,
        };
        let n = p.emit(&mut buf).unwrap();
        out.extend_from_slice(&buf[..n]);
    }
    out
}

/// 50 LMS1xx telegrams, 541 beams at 0.5° each.
fn lms1xx_stream() -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = vec![0u8; 16384];
    for k in 0..50u16 {
        let ranges: Vec<u16> = (0..541u16).map(|i| 300 + (i * 13 + k * 7) % 8000).collect();
        let mut t = ScanTelegram::with_distances(-450_000, 5000, 5000, &ranges).unwrap();
        t.scan_counter = k;
        t.telegram_counter = k;
        let n = t.emit(&mut buf).unwrap();
        out.extend_from_slice(&buf[..n]);
    }
    out
}

fn bench(c: &mut Criterion) {
    let sips = sip_stream();
    let mut g = c.benchmark_group("wire");
    g.throughput(Throughput::Bytes(sips.len() as u64));
    g.bench_function("arcos_sip_stream", |b| {
        b.iter(|| {
            let mut dec = FrameDecoder::new();
            let mut input = black_box(&sips[..]);
            let mut sum = 0i64;
            while let Some(f) = dec.decode(&mut input) {
                let p = StatusPacket::parse_frame(&f).unwrap();
                sum += p.x_pos as i64;
            }
            sum
        })
    });

    let lms = lms1xx_stream();
    g.throughput(Throughput::Bytes(lms.len() as u64));
    g.bench_function("lms1xx_scandata_stream", |b| {
        let mut dec = Box::new(ColaDecoder::<16384>::new());
        b.iter(|| {
            let mut input = black_box(&lms[..]);
            let mut n = 0usize;
            while let Some(p) = dec.decode(&mut input) {
                let t = ScanTelegram::parse(p).unwrap();
                n += t.channels16[0].values.len();
            }
            n
        })
    });
    g.bench_function("lms1xx_scandata_stream_to_scan", |b| {
        let mut dec = Box::new(ColaDecoder::<16384>::new());
        let mut scan = Box::new(Scan::new());
        b.iter(|| {
            let mut input = black_box(&lms[..]);
            let mut n = 0usize;
            while let Some(p) = dec.decode(&mut input) {
                let t = ScanTelegram::parse(p).unwrap();
                papillon::sensor::telegram::lms1xx_scan(&t, 4.0, &mut scan).unwrap();
                n += scan.len();
            }
            n
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
