//! Writes the seed corpora under `fuzz/seeds/<target>/`: the fact sheet's golden frames and
//! frames emitted by the encoders. Run from the repository root:
//! `cargo run --manifest-path fuzz/Cargo.toml --bin seed`.

use std::fs;
use std::path::Path;

use papillon::wire::arcos::{
    Command, ConfigPacket, EncoderPacket, SipExtras, SonarReading, StatusPacket, SyncReply,
};
use papillon::wire::lms1xx::{Reply, Request, ScanConfig, ScanTelegram};
use papillon::wire::lms200::{self, MeasuredValues, Mode, Response, Variant};

fn write(dir: &Path, name: &str, bytes: &[u8]) {
    fs::create_dir_all(dir).unwrap();
    fs::write(dir.join(name), bytes).unwrap();
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds");
    let mut buf = vec![0u8; 32768];

    // ARCOS: golden command frames of the fact sheet plus server packets.
    let golden: &[&[u8]] = &[
        &[0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00],
        &[0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01],
        &[0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02],
        &[0xFA, 0xFB, 0x06, 0x01, 0x3B, 0x01, 0x00, 0x02, 0x3B],
        &[0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B],
        &[0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xC8, 0x00, 0xD3, 0x3B],
        &[0xFA, 0xFB, 0x06, 0x05, 0x1B, 0x2C, 0x01, 0x31, 0x1C],
        &[0xFA, 0xFB, 0x06, 0x15, 0x1B, 0x0A, 0x00, 0x1F, 0x1B],
        &[0xFA, 0xFB, 0x06, 0x32, 0x3B, 0x02, 0x00, 0x34, 0x3B],
        &[0xFA, 0xFB, 0x06, 0x12, 0x3B, 0x01, 0x00, 0x13, 0x3B],
        &[0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D],
    ];
    let mut session = vec![1u8]; // split step for the stream target
    session.extend_from_slice(b"WMS2\r");
    for (i, g) in golden.iter().enumerate() {
        let mut s = vec![(i as u8) + 1];
        s.extend_from_slice(g);
        write(&root.join("arcos_stream"), &format!("golden{i:02}"), &s);
        session.extend_from_slice(g);
    }
    let mut sip = StatusPacket {
        x_pos: 1000,
        th_pos: -1024,
        battery_dv: 130,
        flags: 0x1E,
        ..Default::default()
    };
    for i in 0..16 {
        sip.sonar
            .push(SonarReading {
                number: i,
                range_mm: 5000,
            })
            .unwrap();
    }
    sip.extras = SipExtras {
        grip_state: Some(0),
        anport: Some(0),
        analog: Some(0),
        digin: Some(0xFF),
        digout: Some(0xFF),
        battery_dv_x10: Some(130),
        charge_state: Some(0),
        rot_vel_ddeg_s: Some(0),
        fault_flags: Some(0),
        lat_vel_mm_s: Some(0),
        temperature_c: Some(-127),
        state_of_charge_pct: Some(0),
        uc_time_us: Some(123_456),
        flags3: Some(0),
    };
    let n = sip.emit(&mut buf).unwrap();
    session.extend_from_slice(&buf[..n]);
    let mut s = vec![0x32];
    s.extend_from_slice(&buf[4..n - 2]);
    write(&root.join("sip_parse"), "amrisim_like", &s);
    let mut short = sip.clone();
    short.extras = SipExtras::default();
    let n = short.emit(&mut buf).unwrap();
    let mut s = vec![0x33];
    s.extend_from_slice(&buf[4..n - 2]);
    write(&root.join("sip_parse"), "no_extras", &s);

    let config = ConfigPacket {
        robot_type: "Pioneer".try_into().unwrap(),
        subtype: "p3dx-sh".try_into().unwrap(),
        serial: "SIM".try_into().unwrap(),
        name: "papillon".try_into().unwrap(),
        rot_vel_top: 500,
        trans_vel_top: 2200,
        sip_cycle_ms: 100,
        watchdog_ms: 2000,
        auto_baud: 2,
        ..Default::default()
    };
    let n = config.emit(&mut buf).unwrap();
    session.extend_from_slice(&buf[..n]);
    write(&root.join("config_parse"), "p3dx", &buf[4..n - 2]);
    let sync2 = SyncReply::Sync2 {
        name: "AMRISim".try_into().unwrap(),
        class: "Pioneer".try_into().unwrap(),
        subclass: "p3dx-sh".try_into().unwrap(),
    };
    let n = sync2.emit(&mut buf).unwrap();
    session.extend_from_slice(&buf[..n]);
    let enc = EncoderPacket {
        left_ticks: -5,
        right_ticks: 100_000,
    };
    let n = enc.emit(&mut buf).unwrap();
    session.extend_from_slice(&buf[..n]);
    let n = Command::Vel2 { left: -3, right: 5 }.emit(&mut buf).unwrap();
    session.extend_from_slice(&buf[..n]);
    write(&root.join("arcos_stream"), "session", &session);

    // CoLa-A: both connect sequences, the replies and a 541-beam telegram.
    let mut cola = vec![4u8];
    let cfg = ScanConfig::DEFAULT_50HZ;
    for req in Request::clearpath_connect_sequence(true)
        .iter()
        .chain(Request::aria_connect_sequence().iter())
    {
        let n = req.emit(&mut buf).unwrap();
        cola.extend_from_slice(&buf[..n]);
        if let Some(rep) = Reply::success_for(req, cfg) {
            let n = rep.emit(&mut buf).unwrap();
            cola.extend_from_slice(&buf[..n]);
        }
    }
    write(&root.join("cola_stream"), "connect_sequences", &cola);
    let ranges: Vec<u16> = (0..541u16)
        .map(|i| if i % 50 == 0 { 0 } else { 400 + i * 7 })
        .collect();
    let t = ScanTelegram::with_distances(-450_000, 5000, 5000, &ranges).unwrap();
    let n = t.emit(&mut buf).unwrap();
    let mut s = vec![200u8];
    s.extend_from_slice(&buf[..n]);
    write(&root.join("cola_stream"), "scan541", &s);

    // LMS200: the golden mode telegrams, setup, variant, ACK and measured values.
    let mut l = vec![3u8];
    for r in [
        lms200::Request::SetMode(Mode::Setup {
            password: lms200::DEFAULT_PASSWORD,
        }),
        lms200::Request::SetMode(Mode::ContinuousOutput),
        lms200::Request::SetMode(Mode::Stop),
        lms200::Request::SetMode(Mode::Baud38400),
        lms200::Request::SetVariant(Variant::DEG180_RES05),
    ] {
        let n = r.emit(&mut buf).unwrap();
        l.push(lms200::ACK);
        l.extend_from_slice(&buf[..n]);
    }
    let mut m = MeasuredValues::default();
    for i in 0..361u16 {
        m.values.push(1000 + i).unwrap();
    }
    for r in [
        Response::ModeReply {
            result: 0,
            status: 0x10,
        },
        Response::VariantReply {
            accepted: true,
            variant: Variant::DEG180_RES05,
            status: 0x10,
        },
        Response::MeasuredValues(m),
    ] {
        let n = r.emit(&mut buf).unwrap();
        l.push(lms200::ACK);
        l.extend_from_slice(&buf[..n]);
    }
    l.push(lms200::NACK);
    write(&root.join("lms200_stream"), "session", &l);
    for (i, g) in [
        [0x02u8, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08],
        [0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08],
        [0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08],
    ]
    .iter()
    .enumerate()
    {
        let mut s = vec![1u8];
        s.extend_from_slice(g);
        write(&root.join("lms200_stream"), &format!("golden{i}"), &s);
    }

    // Board files: the shipped boards.
    let boards = Path::new(env!("CARGO_MANIFEST_DIR")).join("../boards");
    for name in ["sim.json", "sim-thesis.json", "p3dx-lms1xx.json", "p3dx-lms200.json"] {
        let text = fs::read(boards.join(name)).unwrap();
        write(&root.join("board_json"), name, &text);
    }

    // Map files: split byte, YAML, image (a P5 and a P2 PGM of 3 x 2 pixels).
    let yaml = b"image: map.pgm\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
    for (name, image) in [
        ("p5", &b"P5\n3 2\n255\n\x00\xfe\xcd\xcd\xfe\x00"[..]),
        ("p2", &b"P2\n# a comment\n3 2\n255\n0 254 205\n205 254 0\n"[..]),
    ] {
        let total = 1 + yaml.len() + image.len();
        // k * (total - 1) / 256 == yaml.len(), rounded up.
        let k = (yaml.len() * 256).div_ceil(total - 1) as u8;
        let mut s = vec![k];
        s.extend_from_slice(yaml);
        s.extend_from_slice(image);
        write(&root.join("map_file"), name, &s);
    }
    println!("seeds written under {}", root.display());
}
