use super::*;
use crate::onboard::link::DuplexLink;
use crate::onboard::testkit::{CommandLog, FakeRobotScript, run_fake_robot};

fn spawn_robot(script: FakeRobotScript, baud: Option<u32>) -> (Box<dyn RobotLink>, CommandLog) {
    let (link, peer) = DuplexLink::pair(4096, baud);
    let log = CommandLog::default();
    tokio::spawn(run_fake_robot(peer, script, log.clone()));
    (Box::new(link), log)
}

fn numbers(log: &CommandLog) -> Vec<(u8, Option<i16>)> {
    log.lock()
        .unwrap()
        .iter()
        .map(|&(_, n, a)| (n, a))
        .collect()
}

/// A velocity within the default exploration limits (400 mm/s, 60 deg/s).
fn velocity(speed_mm_s: i16, turn_rate_deg_s: i16) -> Velocity {
    crate::control::command::Limits::default().clamp(crate::control::command::MotionCommand {
        speed_mm_s,
        turn_rate_deg_s,
    })
}

fn options(subclass: &str) -> SessionOptions {
    SessionOptions {
        expected_subclass: Some(subclass.to_string()),
        ..SessionOptions::default()
    }
}

#[tokio::test(start_paused = true)]
async fn handshake_open_config_then_start_sends_the_board_limits() {
    let (link, log) = spawn_robot(FakeRobotScript::default(), None);
    let mut client = ArcosClient::connect(link, options("P3DX-SH"))
        .await
        .unwrap();
    assert_eq!(client.identity().name, "fake");
    assert_eq!(client.identity().class, "Pioneer");
    assert_eq!(client.identity().subclass, "p3dx-sh");
    assert_eq!(client.config().unwrap().watchdog_ms, 2000);
    assert_eq!(client.baud_switch(), BaudSwitch::NotAttempted);
    let limits = MotionLimits::from_board(&BoardConfig::default());
    client.start(&limits).await.unwrap();
    // Let the fake robot read everything.
    let _ = client
        .next_event(Instant::now() + Duration::from_millis(150))
        .await
        .unwrap();
    assert_eq!(
        numbers(&log),
        [
            (0, None),
            (1, None),
            (2, None),
            (1, Some(1)),
            (18, Some(1)),
            (4, Some(1)),
            (6, Some(400)),
            (10, Some(60)),
            (5, Some(300)),
            (5, Some(-300)),
            (23, Some(100)),
            (23, Some(-100)),
        ]
    );
}

#[tokio::test(start_paused = true)]
async fn handshake_retries_after_silence() {
    let script = FakeRobotScript {
        silent_syncs: 2,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    assert_eq!(client.identity().subclass, "p3dx-sh");
    let sent = numbers(&log);
    assert_eq!(
        &sent[..5],
        [(0, None), (0, None), (0, None), (1, None), (2, None)]
    );
}

#[tokio::test(start_paused = true)]
async fn handshake_gives_up_when_the_robot_never_answers() {
    let script = FakeRobotScript {
        silent_syncs: u32::MAX,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let opts = SessionOptions {
        sync_attempts: 3,
        ..options("p3dx-sh")
    };
    match ArcosClient::connect(link, opts).await {
        Err(SessionError::HandshakeFailed {
            attempts: 3,
            last_id: None,
        }) => {}
        Err(other) => panic!("unexpected error {other}"),
        Ok(_) => panic!("connected to a silent robot"),
    }
    assert_eq!(numbers(&log), [(0, None), (0, None), (0, None)]);
}

#[tokio::test(start_paused = true)]
async fn an_old_open_session_is_closed_first() {
    let script = FakeRobotScript {
        already_open: true,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    let sent = numbers(&log);
    let close = sent.iter().position(|&c| c == (2, Some(1))).unwrap();
    let sync2 = sent.iter().position(|&c| c == (2, None)).unwrap();
    assert!(close < sync2, "CLOSE before the final SYNC2: {sent:?}");
}

#[tokio::test(start_paused = true)]
async fn wrong_subclass_and_class_are_refused() {
    let (link, _) = spawn_robot(FakeRobotScript::default(), None);
    match ArcosClient::connect(link, options("p3dx-sh-lms1xx")).await {
        Err(SessionError::WrongSubclass { got, expected }) => {
            assert_eq!(got, "p3dx-sh");
            assert_eq!(expected, "p3dx-sh-lms1xx");
        }
        _ => panic!("expected a subclass error"),
    }
    let script = FakeRobotScript {
        class: "PeopleBot".into(),
        ..FakeRobotScript::default()
    };
    let (link, _) = spawn_robot(script, None);
    assert!(matches!(
        ArcosClient::connect(link, options("p3dx-sh")).await,
        Err(SessionError::WrongClass { .. })
    ));
    let script = FakeRobotScript {
        subclass: "box".into(),
        ..FakeRobotScript::default()
    };
    let (link, _) = spawn_robot(script, None);
    let opts = SessionOptions {
        expected_subclass: None,
        ..SessionOptions::default()
    };
    assert!(matches!(
        ArcosClient::connect(link, opts).await,
        Err(SessionError::WrongSubclass { .. })
    ));
}

#[tokio::test(start_paused = true)]
async fn missing_config_is_an_error() {
    let script = FakeRobotScript {
        answers_config: false,
        ..FakeRobotScript::default()
    };
    let (link, _) = spawn_robot(script, None);
    assert!(matches!(
        ArcosClient::connect(link, options("p3dx-sh")).await,
        Err(SessionError::NoConfig)
    ));
}

#[tokio::test(start_paused = true)]
async fn a_lost_config_packet_is_asked_for_again() {
    let script = FakeRobotScript {
        lost_configs: 3,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    assert!(client.config().is_some());
    let requests = numbers(&log).iter().filter(|c| c.0 == 18).count();
    assert_eq!(requests, 4, "three lost CONFIG packets, then one answered");
}

#[tokio::test(start_paused = true)]
async fn config_requests_stop_after_config_attempts() {
    let script = FakeRobotScript {
        answers_config: false,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let opts = SessionOptions {
        config_attempts: 5,
        ..options("p3dx-sh")
    };
    assert!(matches!(
        ArcosClient::connect(link, opts).await,
        Err(SessionError::NoConfig)
    ));
    assert_eq!(numbers(&log).iter().filter(|c| c.0 == 18).count(), 5);
}

#[tokio::test(start_paused = true)]
async fn hostbaud_switch_on_a_serial_link() {
    let (link, peer) = DuplexLink::pair(4096, Some(9600));
    let log = CommandLog::default();
    tokio::spawn(run_fake_robot(
        peer,
        FakeRobotScript::default(),
        log.clone(),
    ));
    let client = ArcosClient::connect(Box::new(link), options("p3dx-sh"))
        .await
        .unwrap();
    assert_eq!(client.baud_switch(), BaudSwitch::Switched(38400));
    let sent = numbers(&log);
    let hb = sent.iter().position(|&c| c == (50, Some(2))).unwrap();
    assert_eq!(sent[hb + 1], (0, None), "PULSE right after HOSTBAUD");
}

#[tokio::test(start_paused = true)]
async fn hostbaud_reverts_when_nothing_comes_back() {
    let script = FakeRobotScript {
        baud_switch_works: false,
        ..FakeRobotScript::default()
    };
    let (link, _) = spawn_robot(script, Some(9600));
    let client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    assert_eq!(client.baud_switch(), BaudSwitch::Reverted(38400));
}

#[tokio::test(start_paused = true)]
async fn no_hostbaud_without_autobaud_or_on_tcp() {
    let script = FakeRobotScript {
        auto_baud: 1,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, Some(9600));
    let client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    assert_eq!(client.baud_switch(), BaudSwitch::NotAttempted);
    assert!(!numbers(&log).iter().any(|&(n, _)| n == 50));
}

#[tokio::test(start_paused = true)]
async fn status_events_arrive_and_pulses_keep_the_link_alive() {
    let (link, log) = spawn_robot(FakeRobotScript::default(), None);
    let mut client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    let start = Instant::now();
    let mut statuses = 0;
    while let Some(ev) = client
        .next_event(start + Duration::from_millis(2000))
        .await
        .unwrap()
    {
        if let RobotEvent::Status { at, status } = ev {
            assert!(at >= start);
            assert_eq!(status.battery_dv, 130);
            statuses += 1;
        }
    }
    assert!(statuses >= 15, "{statuses} status packets in 2 s at 10 Hz");
    let entries = log.lock().unwrap().clone();
    let after: Vec<_> = entries.iter().filter(|e| e.0 > start).collect();
    assert!(after.iter().all(|e| e.1 == 0), "only PULSE while idle");
    assert!(
        (3..=5).contains(&after.len()),
        "{} pulses in 2 s",
        after.len()
    );
    for w in after.windows(2) {
        assert!(w[1].0 - w[0].0 >= Duration::from_millis(500));
    }
    assert!(client.stats().pulses_sent >= 3);
}

#[tokio::test(start_paused = true)]
async fn a_short_firmware_watchdog_gets_pulses_four_times_per_period() {
    let script = FakeRobotScript {
        watchdog_ms: 400,
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let mut client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    let start = Instant::now();
    while client
        .next_event(start + Duration::from_millis(1000))
        .await
        .unwrap()
        .is_some()
    {}
    let entries = log.lock().unwrap().clone();
    let after: Vec<_> = entries.iter().filter(|e| e.0 > start).collect();
    assert!(after.iter().all(|e| e.1 == 0), "only PULSE while idle");
    assert!(
        (9..=11).contains(&after.len()),
        "{} pulses in 1 s",
        after.len()
    );
    for w in after.windows(2) {
        assert!(w[1].0 - w[0].0 <= Duration::from_millis(100) + Duration::from_millis(5));
    }
}

#[tokio::test(start_paused = true)]
async fn after_a_fault_motion_is_refused_and_never_resent() {
    let (link, log) = spawn_robot(FakeRobotScript::default(), None);
    let mut client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    client.drive(velocity(200, 10)).await.unwrap();
    client.halt(Fault::StaleScan).await.unwrap();
    assert!(matches!(
        client.drive(velocity(200, 10)).await,
        Err(SessionError::Faulted(Fault::StaleScan))
    ));
    let t = Instant::now();
    while client
        .next_event(t + Duration::from_millis(1600))
        .await
        .unwrap()
        .is_some()
    {}
    let sent = numbers(&log);
    let halt = sent.iter().rposition(|&c| c == (11, Some(0))).unwrap();
    assert!(
        sent[halt..]
            .iter()
            .all(|&(n, a)| !(n == 11 || n == 21) || a == Some(0)),
        "no non-zero velocity after the halt: {sent:?}"
    );
    client.clear_fault();
    client.drive(velocity(100, 0)).await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn stop_and_close_disables_motors_and_closes() {
    let (link, log) = spawn_robot(FakeRobotScript::default(), None);
    let mut client = ArcosClient::connect(link, options("p3dx-sh"))
        .await
        .unwrap();
    client
        .start(&MotionLimits::from_board(&BoardConfig::default()))
        .await
        .unwrap();
    client.drive(velocity(150, 0)).await.unwrap();
    client.stop_and_close().await.unwrap();
    tokio::time::sleep(Duration::from_millis(50)).await;
    let sent = numbers(&log);
    let n = sent.len();
    assert_eq!(
        &sent[n - 5..],
        [
            (11, Some(0)),
            (21, Some(0)),
            (29, None),
            (4, Some(0)),
            (2, Some(1))
        ]
    );
}

#[tokio::test(start_paused = true)]
async fn closed_link_is_reported_and_latches_a_fault() {
    let (link, peer) = DuplexLink::pair(4096, None);
    let log = CommandLog::default();
    let robot = tokio::spawn(run_fake_robot(peer, FakeRobotScript::default(), log));
    let mut client = ArcosClient::connect(Box::new(link), options("p3dx-sh"))
        .await
        .unwrap();
    robot.abort();
    let _ = robot.await;
    let r = client
        .next_event(Instant::now() + Duration::from_secs(1))
        .await;
    assert!(matches!(
        r,
        Err(SessionError::Closed) | Err(SessionError::Io(_))
    ));
    assert_eq!(client.fault(), Some(Fault::Link));
}

#[test]
fn garbage_never_panics_the_session_codec() {
    use rand_core::Rng;
    let mut rng = crate::random::seeded(3);
    let mut codec = ArcosCodec::default();
    let mut out = Vec::new();
    for _ in 0..2000 {
        let n = (rng.next_u32() % 64) as usize;
        let bytes: Vec<u8> = (0..n).map(|_| rng.next_u32() as u8).collect();
        codec.decode(&bytes, &mut out);
    }
}

#[tokio::test(start_paused = true)]
async fn an_unknown_subclass_is_refused_naming_it_and_the_known_ones() {
    let script = FakeRobotScript {
        subclass: "p3at-sh".into(),
        ..FakeRobotScript::default()
    };
    let (link, _) = spawn_robot(script, None);
    let opts = SessionOptions {
        expected_subclass: None,
        ..SessionOptions::default()
    };
    let err = match ArcosClient::connect(link, opts).await {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a p3at-sh was accepted"),
    };
    assert!(err.contains("\"p3at-sh\""), "{err}");
    for known in crate::config::KNOWN_SUBCLASSES {
        assert!(err.contains(known), "{err}");
    }
}

#[tokio::test(start_paused = true)]
async fn a_p3dx_reports_millimetres_and_gets_moves_in_its_units() {
    let script = FakeRobotScript {
        subclass: "p3dx".into(),
        ..FakeRobotScript::default()
    };
    let (link, log) = spawn_robot(script, None);
    let mut client = ArcosClient::connect(link, options("p3dx")).await.unwrap();
    assert_eq!(client.factors().mm_per_distance_unit, 0.485);
    // The fake robot's XPOS grows by one unit (0.485 mm) per status packet.
    let mut xs = Vec::new();
    while xs.len() < 41 {
        let deadline = Instant::now() + Duration::from_secs(1);
        if let Some(RobotEvent::Status { status, .. }) = client.next_event(deadline).await.unwrap()
        {
            xs.push(i32::from(status.x_pos));
        }
    }
    let advanced_mm = xs[40] - xs[0];
    assert!((advanced_mm - 19).abs() <= 1, "{xs:?}");
    client.send(&Command::Move(485)).await.unwrap();
    client.send(&Command::Vel(300)).await.unwrap();
    assert!(matches!(
        client.send(&Command::Move(20_000)).await,
        Err(SessionError::OutOfRange {
            command: "MOVE",
            value: 20_000
        })
    ));
    let _ = client
        .next_event(Instant::now() + Duration::from_millis(50))
        .await
        .unwrap();
    let sent = numbers(&log);
    assert!(
        sent.ends_with(&[(8, Some(1000)), (11, Some(300))]),
        "{sent:?}"
    );
}
