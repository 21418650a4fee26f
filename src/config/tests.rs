use super::*;

extern crate std;
use std::string::{String, ToString};
use std::vec::Vec;

const LMS1XX: &str = include_str!("../../boards/p3dx-lms1xx.json");
const LMS200: &str = include_str!("../../boards/p3dx-lms200.json");
/// The simulator's board without a `$.localize` section (the thesis's laser, matcher off).
const SIM: &str = include_str!("../../boards/sim-thesis.json");
/// The project's board for the simulator: an LMS1xx described as it is, the matcher on.
const SIM_MATCHING: &str = include_str!("../../boards/sim.json");

fn problems(c: &BoardConfig) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let n = c.validate(|path, problem| out.push((path.to_string(), problem.to_string())));
    assert_eq!(n, out.len(), "the returned count matches the reports");
    out
}

fn paths(c: &BoardConfig) -> Vec<String> {
    problems(c).into_iter().map(|(p, _)| p).collect()
}

/// Checks that the only problem reported after `change` is at `path`.
fn only_problem_at(path: &str, change: impl FnOnce(&mut BoardConfig)) {
    let mut c = BoardConfig::default();
    change(&mut c);
    assert_eq!(paths(&c), [path], "after the change to {path}");
}

#[test]
fn shipped_boards_parse_and_validate() {
    for (file, text) in [
        ("p3dx-lms1xx", LMS1XX),
        ("p3dx-lms200", LMS200),
        ("sim", SIM),
    ] {
        let c = BoardConfig::from_json(text.as_bytes())
            .unwrap_or_else(|e| panic!("{file}.json does not parse: {e}"));
        assert_eq!(problems(&c), [], "{file}.json has problems");
    }
}

#[test]
fn lms1xx_board_values() {
    let c = BoardConfig::from_json(LMS1XX.as_bytes()).unwrap();
    assert_eq!(c.link.port.as_str(), "/dev/ttyS0");
    assert_eq!(c.link.tcp, None);
    assert_eq!(c.laser_model(), Some(LaserModel::Lms1xx));
    assert_eq!(c.laser.address.as_deref(), Some("192.168.0.1:2111"));
    assert_eq!(c.laser.mount.x_m, 0.055);
    assert_eq!(c.robot.max_speed_mm_s, 400.0);
    assert_eq!(c.strategy(), Some(Strategy::Short));
}

#[test]
fn lms200_board_values() {
    let c = BoardConfig::from_json(LMS200.as_bytes()).unwrap();
    assert_eq!(c.laser_model(), Some(LaserModel::Lms200));
    assert_eq!(c.laser.port.as_deref(), Some("/dev/ttyS2"));
    assert_eq!(c.laser.mount.x_m, 0.021);
    assert_eq!(c.laser.address, None);
}

/// A real robot's odometry drifts, and with a laser as precise as a SICK's the map drawn at
/// the odometry pose doubles its walls (docs/experiments.md, "Issue 17: the generated set
/// under five sensing set-ups"): the real robots' boards match their scans, with the pose
/// graph, as `sim.json` (the lab's robot in the simulator) does.
#[test]
fn the_real_robots_boards_match_scans_with_the_pose_graph() {
    for (file, text) in [
        ("p3dx-lms1xx", LMS1XX),
        ("p3dx-lms200", LMS200),
        ("sim", SIM_MATCHING),
    ] {
        let c = BoardConfig::from_json(text.as_bytes()).unwrap();
        let l = c.localize_config();
        assert!(l.enabled, "{file}.json: the scan matcher is off");
        assert!(l.graph.enabled, "{file}.json: the pose graph is off");
    }
}

#[test]
fn sim_board_values() {
    let c = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(c.link.port.as_str(), "/tmp/papillon-sim/robot0");
    assert_eq!(c.laser.address.as_deref(), Some("127.0.0.1:2111"));
}

#[test]
fn default_is_valid() {
    assert_eq!(problems(&BoardConfig::default()), []);
}

#[test]
fn laser_config_converts_degrees_and_mount() {
    let c = BoardConfig::from_json(LMS1XX.as_bytes()).unwrap();
    let l = c.laser_config();
    let reference = LaserConfig::lms1xx();
    assert_eq!(l.beam_count, 541);
    assert!((l.first_angle_rad - reference.first_angle_rad).abs() < 1e-6);
    assert!((l.step_rad - reference.step_rad).abs() < 1e-7);
    assert!((l.last_angle_rad() - deg_to_rad(135.0)).abs() < 1e-4);
    assert_eq!(l.mount.x, 0.055);
    assert_eq!(l.max_range_m, 4.0);
    assert_eq!(l.min_range_m, 0.30);
}

#[test]
fn syntax_error_reports_line_column_and_offset() {
    let text = "{\n  \"robot\": {\n    \"name\": \"x\",,\n";
    let err = BoardConfig::from_json(text.as_bytes()).unwrap_err();
    match err {
        ConfigError::Syntax {
            offset,
            line,
            column,
            ..
        } => {
            assert_eq!(line, 3);
            assert_eq!(column, 17);
            assert_eq!(&text[offset..offset + 1], ",");
        }
        other => panic!("expected a syntax error, got {other:?}"),
    }
    let shown = BoardConfig::from_json(text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(shown.contains("line 3, column 17"), "{shown}");
}

#[test]
fn syntax_errors_of_several_kinds_are_located() {
    for (text, offset) in [
        ("", 0),
        ("{", 1),
        ("{\"a\" 1}", 5),
        ("{\"a\": 01}", 7),
        ("{\"a\": tru}", 9),
        ("{\"a\": \"x}", 9),
        ("{\"a\": 1} x", 9),
        ("[1, 2", 5),
        ("{\"a\": 1.}", 8),
    ] {
        match BoardConfig::from_json(text.as_bytes()) {
            Err(ConfigError::Syntax { offset: got, .. }) => {
                assert_eq!(got, offset, "for {text:?}")
            }
            other => panic!("{text:?}: expected a syntax error, got {other:?}"),
        }
    }
}

#[test]
fn missing_and_unknown_keys_are_shape_errors_naming_the_key() {
    let missing = LMS1XX.replace("\"population\": 20,", "");
    assert_eq!(
        BoardConfig::from_json(missing.as_bytes()),
        Err(ConfigError::MissingKey {
            path: "$.mission.population"
        })
    );
    let unknown = LMS1XX.replace("\"population\": 20,", "\"populaton\": 20,");
    match BoardConfig::from_json(unknown.as_bytes()) {
        Err(ConfigError::UnknownKey { path, line, column }) => {
            assert_eq!(path.as_str(), "$.mission.populaton");
            let text_line = unknown.lines().nth(line - 1).unwrap();
            assert_eq!(&text_line[column - 1..column + 10], "\"populaton\"");
        }
        other => panic!("expected an unknown key, got {other:?}"),
    }
    let nested = LMS1XX.replace("\"x_m\": 0.055", "\"x\": 0.055");
    match BoardConfig::from_json(nested.as_bytes()) {
        Err(ConfigError::UnknownKey { path, .. }) => assert_eq!(path.as_str(), "$.laser.mount.x"),
        other => panic!("expected an unknown key, got {other:?}"),
    }
    let wrong_type = LMS1XX.replace("\"population\": 20,", "\"population\": \"20\",");
    assert!(matches!(
        BoardConfig::from_json(wrong_type.as_bytes()),
        Err(ConfigError::Value { .. })
    ));
    let negative = LMS1XX.replace("\"population\": 20,", "\"population\": -20,");
    assert!(matches!(
        BoardConfig::from_json(negative.as_bytes()),
        Err(ConfigError::Value { .. })
    ));
}

#[test]
fn too_long_string_is_a_shape_error() {
    let long = "x".repeat(100);
    let text = LMS1XX.replace("/dev/ttyS0", &long);
    assert!(matches!(
        BoardConfig::from_json(text.as_bytes()),
        Err(ConfigError::Value { .. })
    ));
}

#[test]
fn random_bytes_never_panic() {
    use rand_core::Rng;
    let mut rng = crate::random::seeded(7);
    for _ in 0..500 {
        let mut bytes = LMS1XX.as_bytes().to_vec();
        let flips = 1 + (rng.next_u32() % 4) as usize;
        for _ in 0..flips {
            let i = rng.next_u32() as usize % bytes.len();
            bytes[i] = rng.next_u32() as u8;
        }
        if let Ok(c) = BoardConfig::from_json(&bytes) {
            let _ = c.validate(|_, _| {});
            let _ = c.laser_config();
        }
    }
}

#[test]
fn robot_rules() {
    only_problem_at("$.robot.name", |c| c.robot.name = Name::default());
    only_problem_at("$.robot.subclass", |c| c.robot.subclass = name("box"));
    only_problem_at("$.robot.radius_m", |c| c.robot.radius_m = 0.0);
    only_problem_at("$.robot.max_speed_mm_s", |c| {
        c.robot.max_speed_mm_s = 3000.0
    });
    only_problem_at("$.robot.max_turn_rate_deg_s", |c| {
        c.robot.max_turn_rate_deg_s = -1.0
    });
    only_problem_at("$.robot.accel_mm_s2", |c| c.robot.accel_mm_s2 = 0.0);
    only_problem_at("$.robot.decel_mm_s2", |c| c.robot.decel_mm_s2 = 40000.0);
    only_problem_at("$.robot.rot_accel_deg_s2", |c| {
        c.robot.rot_accel_deg_s2 = f32::NAN
    });
}

#[test]
fn subclass_is_case_insensitive() {
    let mut c = BoardConfig::default();
    for s in ["P3DX-SH", "p3dx", "P3DX-sh-LMS1XX", "p3dx-sh-lms500"] {
        c.robot.subclass = name(s);
        assert_eq!(problems(&c), [], "{s}");
    }
}

#[test]
fn link_rules() {
    only_problem_at("$.link.port", |c| c.link.port = Address::default());
    only_problem_at("$.link.baud", |c| c.link.baud = 4800);
    only_problem_at("$.link.switch_to_baud", |c| c.link.switch_to_baud = 0);
    only_problem_at("$.link.tcp", |c| c.link.tcp = Some(address("localhost")));
    only_problem_at("$.link.tcp", |c| c.link.tcp = Some(address("host:70000")));
    // A TCP link needs no serial port.
    let mut c = BoardConfig::default();
    c.link.port = Address::default();
    c.link.tcp = Some(address("127.0.0.1:8101"));
    assert_eq!(problems(&c), []);
}

#[test]
fn laser_rules() {
    only_problem_at("$.laser.model", |c| c.laser.model = name("lms500"));
    only_problem_at("$.laser.address", |c| c.laser.address = None);
    only_problem_at("$.laser.address", |c| c.laser.address = Some(address("x")));
    only_problem_at("$.laser.port", |c| c.laser.model = name("lms200"));
    only_problem_at("$.laser.baud", |c| {
        c.laser.model = name("lms200");
        c.laser.port = Some(address("/dev/ttyS2"));
        c.laser.baud = Some(500000);
    });
    only_problem_at("$.laser.beam_count", |c| c.laser.beam_count = 1);
    only_problem_at("$.laser.beam_count", |c| c.laser.beam_count = 2000);
    only_problem_at("$.laser.first_angle_deg", |c| {
        c.laser.first_angle_deg = 200.0
    });
    only_problem_at("$.laser.step_deg", |c| c.laser.step_deg = 0.0);
    only_problem_at("$.laser.step_deg", |c| c.laser.step_deg = 1.0);
    only_problem_at("$.laser.min_range_m", |c| c.laser.min_range_m = -0.1);
    only_problem_at("$.laser.max_range_m", |c| c.laser.max_range_m = 0.0);
    only_problem_at("$.laser.max_range_m", |c| c.laser.max_range_m = 0.2);
    only_problem_at("$.laser.noise_fraction", |c| c.laser.noise_fraction = 1.0);
    only_problem_at("$.laser.rate_hz", |c| c.laser.rate_hz = 0.0);
    only_problem_at("$.laser.mount.x_m", |c| c.laser.mount.x_m = 2.0);
    only_problem_at("$.laser.mount.y_m", |c| c.laser.mount.y_m = f32::INFINITY);
    only_problem_at("$.laser.mount.theta_deg", |c| {
        c.laser.mount.theta_deg = 270.0
    });
}

#[test]
fn grid_rules() {
    only_problem_at("$.grid.width_m", |c| c.grid.width_m = 0.0);
    only_problem_at("$.grid.height_m", |c| c.grid.height_m = -1.0);
    only_problem_at("$.grid.resolution_m", |c| c.grid.resolution_m = 0.0);
    only_problem_at("$.grid.resolution_m", |c| {
        c.grid.resolution_m = 0.5;
    });
    only_problem_at("$.grid.origin_x_m", |c| c.grid.origin_x_m = f32::NAN);
    // 300 m x 300 m at 10 cm = 9 000 000 cells, beyond the largest capacity; the problem
    // names the limit.
    only_problem_at("$.grid", |c| {
        c.grid.width_m = 300.0;
        c.grid.height_m = 300.0;
        c.grid.origin_x_m = -150.0;
        c.grid.origin_y_m = -150.0;
    });
    let mut c = BoardConfig::default();
    c.grid.width_m = 300.0;
    c.grid.height_m = 300.0;
    c.grid.origin_x_m = -150.0;
    c.grid.origin_y_m = -150.0;
    let limit = crate::capacity::MAX_CELLS.to_string();
    assert!(
        problems(&c).iter().any(|(_, p)| p.contains(&limit)),
        "{:?}",
        problems(&c)
    );
    // The start pose must be inside.
    only_problem_at("$.grid", |c| c.grid.origin_x_m = 1.0);
    // A 100 m x 100 m floor at 10 cm (1 000 000 cells) and 50 m x 50 m at 5 cm fit (issue 24).
    #[cfg(not(feature = "fixed-capacity"))]
    for (size_m, resolution_m) in [(100.0, 0.1), (50.0, 0.05)] {
        let mut c = BoardConfig::default();
        c.grid.width_m = size_m;
        c.grid.height_m = size_m;
        c.grid.resolution_m = resolution_m;
        c.grid.origin_x_m = -size_m / 2.0;
        c.grid.origin_y_m = -size_m / 2.0;
        assert_eq!(problems(&c), [], "{size_m} m at {resolution_m} m");
    }
}

#[test]
fn mission_rules() {
    only_problem_at("$.mission.method", |c| c.mission.method = name("sgd"));
    only_problem_at("$.mission.population", |c| c.mission.population = 1);
    only_problem_at("$.mission.population", |c| {
        c.mission.population = MAX_POPULATION + 1
    });
    only_problem_at("$.mission.generations", |c| c.mission.generations = 0);
    only_problem_at("$.mission.objective", |c| {
        c.mission.objective = Some(name("thesys"))
    });
    only_problem_at("$.mission.preset", |c| {
        c.mission.preset = Some(name("tuned"))
    });
    only_problem_at("$.mission.strategy", |c| {
        c.mission.strategy = name("medium")
    });
    only_problem_at("$.mission.targets", |c| c.mission.targets = 0);
    only_problem_at("$.mission.battery_steps", |c| c.mission.battery_steps = 0.0);
    only_problem_at("$.mission.reserve_steps", |c| {
        c.mission.reserve_steps = -1.0
    });
    only_problem_at("$.mission.reserve_steps", |c| {
        c.mission.reserve_steps = 400.0
    });
    only_problem_at("$.mission.coverage_target", |c| {
        c.mission.coverage_target = 1.5
    });
    only_problem_at("$.mission.coverage_target", |c| {
        c.mission.coverage_target = 0.0
    });
    let mut c = BoardConfig::default();
    for m in KNOWN_METHODS {
        c.mission.method = name(m);
        assert_eq!(problems(&c), [], "{m}");
    }
    c.mission.population = 2;
    assert_eq!(problems(&c), []);
    c.mission.population = MAX_POPULATION;
    assert_eq!(problems(&c), []);
}

#[test]
fn pid_rules() {
    only_problem_at("$.pid.heading_kp", |c| c.pid.heading_kp = 0.0);
    only_problem_at("$.pid.distance_kp", |c| c.pid.distance_kp = -1.0);
    only_problem_at("$.pid.heading_ki", |c| c.pid.heading_ki = -0.1);
    only_problem_at("$.pid.heading_kd", |c| c.pid.heading_kd = f32::NAN);
    only_problem_at("$.pid.distance_ki", |c| c.pid.distance_ki = -0.1);
    only_problem_at("$.pid.distance_kd", |c| c.pid.distance_kd = -0.1);
}

#[test]
fn safety_and_persistence_rules() {
    only_problem_at("$.safety.obstacle_stop_m", |c| {
        c.safety.obstacle_stop_m = 0.0
    });
    only_problem_at("$.safety.obstacle_stop_m", |c| {
        c.laser.min_range_m = 0.5;
        c.safety.obstacle_stop_m = 0.1;
    });
    only_problem_at("$.safety.stale_timeout_s", |c| {
        c.safety.stale_timeout_s = 2.0
    });
    only_problem_at("$.safety.back_off_m", |c| c.safety.back_off_m = -0.1);
    only_problem_at("$.persistence.save_every_s", |c| {
        c.persistence.save_every_s = 0.0
    });
}

#[test]
fn every_problem_is_reported_at_once() {
    let mut c = BoardConfig::default();
    c.mission.population = 0;
    c.mission.method = name("nope");
    c.link.baud = 1;
    let p = paths(&c);
    assert_eq!(p.len(), 3);
    assert!(p.contains(&"$.mission.population".to_string()));
    assert!(p.contains(&"$.mission.method".to_string()));
    assert!(p.contains(&"$.link.baud".to_string()));
}

#[test]
fn host_port() {
    assert!(is_host_port("127.0.0.1:2111"));
    assert!(is_host_port("robot.local:8101"));
    assert!(!is_host_port(":8101"));
    assert!(!is_host_port("host:"));
    assert!(!is_host_port("host:0"));
    assert!(!is_host_port("host:+80"));
}

#[test]
fn the_objective_is_optional_and_named() {
    use crate::explore::ObjectiveKind;
    let c = BoardConfig::from_json(LMS1XX.as_bytes()).unwrap();
    assert_eq!(c.mission.objective, None);
    assert_eq!(c.objective(), Some(ObjectiveKind::Efficient));
    for (text, kind) in [
        ("thesis", ObjectiveKind::Thesis),
        ("efficient", ObjectiveKind::Efficient),
    ] {
        let json = LMS1XX.replace(
            "\"strategy\": \"short\",",
            &std::format!("\"strategy\": \"short\", \"objective\": \"{text}\","),
        );
        let c = BoardConfig::from_json(json.as_bytes()).unwrap();
        assert_eq!(c.objective(), Some(kind));
        assert_eq!(paths(&c), Vec::<String>::new());
    }
}

#[test]
fn the_preset_is_optional_and_named() {
    use crate::optim::Preset;
    let c = BoardConfig::from_json(LMS1XX.as_bytes()).unwrap();
    assert_eq!(c.mission.preset, None);
    assert_eq!(c.preset(), Some(crate::explore::DEFAULT_PRESET));
    for (text, preset) in [("thesis", Preset::Thesis), ("standard", Preset::Standard)] {
        let json = LMS1XX.replace(
            "\"strategy\": \"short\",",
            &std::format!("\"strategy\": \"short\", \"preset\": \"{text}\","),
        );
        let c = BoardConfig::from_json(json.as_bytes()).unwrap();
        assert_eq!(c.preset(), Some(preset));
        assert_eq!(paths(&c), Vec::<String>::new());
    }
}

/// A string that is not UTF-8 is named by its path (before: "a value has the wrong type or is
/// too long for its field (Invalid unicode code point.)", no path).
#[test]
fn a_string_that_is_not_utf8_names_its_path() {
    let mut bytes = SIM.replacen("\"sim-p3dx\"", "\"sim@\"", 1).into_bytes();
    let at = bytes.iter().position(|&b| b == b'@').unwrap();
    bytes[at] = 0xFF;
    match BoardConfig::from_json(&bytes) {
        Err(ConfigError::Value { path, expected, .. }) => {
            assert_eq!(path, "$.robot.name");
            assert!(expected.contains("UTF-8"), "{expected}");
        }
        other => panic!("{other:?}"),
    }
}

/// With the long strategy, more targets than a decision can hold are refused, and so is an
/// absurd gain (before: clamped to 8 and accepted).
#[test]
fn too_many_long_term_targets_and_an_absurd_gain_are_refused() {
    only_problem_at("$.mission.targets", |c| {
        c.mission.strategy = Name::new("long").unwrap();
        c.mission.targets = 1000;
    });
    only_problem_at("$.pid.distance_kp", |c| c.pid.distance_kp = 1e30);
}

/// Half of a UTF-16 pair in a `\u` escape is a syntax error at its place; a whole pair is
/// read (before: `"\ud800"` was accepted as a robot name).
#[test]
fn a_lone_surrogate_escape_is_refused_and_a_pair_read() {
    let lone = SIM.replacen("\"sim-p3dx\"", "\"\\ud800\"", 1);
    match BoardConfig::from_json(lone.as_bytes()) {
        Err(ConfigError::Syntax { line, .. }) => assert_eq!(line, 3),
        other => panic!("{other:?}"),
    }
    let low = SIM.replacen("\"sim-p3dx\"", "\"\\udc00x\"", 1);
    assert!(matches!(
        BoardConfig::from_json(low.as_bytes()),
        Err(ConfigError::Syntax { .. })
    ));
    let pair = SIM.replacen("\"sim-p3dx\"", "\"\\ud83d\\ude00\"", 1);
    assert!(BoardConfig::from_json(pair.as_bytes()).is_ok());
}

/// `boards/sim.json` runs the matcher with its pose graph, and differs from
/// `boards/sim-thesis.json` only there and in its laser's range noise.
#[test]
fn the_simulator_board_runs_the_matcher_and_its_graph() {
    let c = BoardConfig::from_json(SIM_MATCHING.as_bytes()).unwrap();
    assert!(c.localize_config().enabled);
    assert!(c.localize_config().graph.enabled);
    assert_eq!(c.laser.noise_fraction, 0.003);
    let mut thesis = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(thesis.laser.noise_fraction, 0.05);
    thesis.laser.noise_fraction = c.laser.noise_fraction;
    thesis.localize = c.localize;
    assert_eq!(thesis, c);
}

/// `$.localize` is optional: absent, the matcher is off with the core's defaults; present,
/// its keys set the matcher's user-facing knobs (angles in degrees).
#[test]
fn the_localize_section_is_optional_and_sets_the_matcher() {
    use crate::localize::LocalizeConfig;
    // `sim.json` with the `$.localize` section `section`.
    let with = |section: &str| {
        let json = SIM.replacen(
            "\"persistence\"",
            &format!("\"localize\": {section}, \"persistence\""),
            1,
        );
        BoardConfig::from_json(json.as_bytes()).unwrap()
    };
    let c = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(c.localize, LocalizeBoardConfig::default());
    assert_eq!(c.localize_config(), LocalizeConfig::default());
    assert!(!c.localize_config().enabled);
    let c = with(
        "{\"enabled\": true, \"every_n_scans\": 2, \"min_travel_m\": 0.25, \
         \"min_turn_deg\": 10, \"search_xy_m\": 0.4, \"search_theta_deg\": 8}",
    );
    assert_eq!(paths(&c), Vec::<String>::new());
    let l = c.localize_config();
    assert!(l.enabled);
    assert_eq!(l.every_n_scans, 2);
    assert_eq!(l.min_travel_m, 0.25);
    assert!((l.min_turn_rad - 10f32.to_radians()).abs() < 1e-6);
    assert_eq!(l.matcher.search_xy_m, 0.4);
    assert!((l.matcher.search_theta_rad - 8f32.to_radians()).abs() < 1e-6);
    assert!(!l.graph.enabled);
    // What the board does not give stays the core's.
    let d = LocalizeConfig::default();
    assert_eq!(l.information_scale, d.information_scale);
    assert_eq!(l.matcher.sigma_m, d.matcher.sigma_m);
    // Only `enabled`: the defaults, switched on.
    let c = with("{\"enabled\": true}");
    assert_eq!(
        c.localize_config(),
        LocalizeConfig {
            enabled: true,
            ..LocalizeConfig::default()
        }
    );
    // The pose graph behind it.
    let c = with("{\"enabled\": true, \"pose_graph\": true}");
    assert_eq!(paths(&c), Vec::<String>::new());
    let l = c.localize_config();
    assert!(l.enabled && l.graph.enabled);
    assert_eq!(l.matcher, LocalizeConfig::default().matcher);
    // The odometry's self-calibration: on unless the board turns it off.
    assert!(l.calibration.enabled);
    let c = with("{\"enabled\": true, \"self_calibration\": false}");
    assert_eq!(paths(&c), Vec::<String>::new());
    let l = c.localize_config();
    assert!(l.enabled && !l.calibration.enabled);
}

/// Each bad `$.localize` value is one problem naming its key; a misspelt key and a wrong type
/// are named by their path too.
#[test]
fn bad_localize_values_name_their_field() {
    let on = |c: &mut BoardConfig| c.localize.enabled = Some(true);
    only_problem_at("$.localize.every_n_scans", |c| {
        on(c);
        c.localize.every_n_scans = Some(0);
    });
    only_problem_at("$.localize.min_travel_m", |c| {
        c.localize.min_travel_m = Some(-0.1)
    });
    only_problem_at("$.localize.min_travel_m", |c| {
        c.localize.min_travel_m = Some(f32::NAN)
    });
    only_problem_at("$.localize.min_turn_deg", |c| {
        c.localize.min_turn_deg = Some(200.0)
    });
    only_problem_at("$.localize.search_xy_m", |c| {
        c.localize.search_xy_m = Some(0.0)
    });
    only_problem_at("$.localize.search_theta_deg", |c| {
        c.localize.search_theta_deg = Some(90.0)
    });
    // The pose graph without the matcher it sits behind.
    only_problem_at("$.localize.pose_graph", |c| {
        c.localize.pose_graph = Some(true)
    });
    only_problem_at("$.localize.self_calibration", |c| {
        c.localize.self_calibration = Some(true)
    });
    let typo = SIM.replacen(
        "\"persistence\"",
        "\"localize\": {\"enable\": true}, \"persistence\"",
        1,
    );
    match BoardConfig::from_json(typo.as_bytes()) {
        Err(ConfigError::UnknownKey { path, .. }) => assert_eq!(path.as_str(), "$.localize.enable"),
        other => panic!("{other:?}"),
    }
    let wrong = SIM.replacen(
        "\"persistence\"",
        "\"localize\": {\"enabled\": \"yes\"}, \"persistence\"",
        1,
    );
    match BoardConfig::from_json(wrong.as_bytes()) {
        Err(ConfigError::Value { path, .. }) => assert_eq!(path, "$.localize.enabled"),
        other => panic!("{other:?}"),
    }
}

/// A grid so fine that a whole scan and the search no longer fit the matcher's window would
/// have every match refused: the board check names `$.localize.enabled` (only when on).
#[test]
fn a_matcher_window_too_small_for_the_grid_is_refused_when_matching_is_on() {
    let fine = |c: &mut BoardConfig| c.grid.resolution_m = 0.05;
    let mut c = BoardConfig::default();
    fine(&mut c);
    assert_eq!(paths(&c), Vec::<String>::new());
    only_problem_at("$.localize.enabled", |c| {
        fine(c);
        c.localize.enabled = Some(true);
    });
    let mut c = BoardConfig::default();
    c.localize.enabled = Some(true);
    assert_eq!(paths(&c), Vec::<String>::new());
    let problem = {
        let mut c = BoardConfig::default();
        fine(&mut c);
        c.localize.enabled = Some(true);
        problems(&c).remove(0).1
    };
    assert!(problem.contains("resolution_m"), "{problem}");
}

/// `$.mapping` is optional: absent, or without `motion_filter: true`, every scan is mapped;
/// on, its keys set the filter's thresholds (the turn in degrees), the others are standard.
#[test]
fn the_mapping_section_is_optional_and_sets_the_motion_filter() {
    use crate::mission::MotionFilterConfig;
    let c = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(c.motion_filter_config(), MotionFilterConfig::off());
    let with = |section: &str| {
        let json = SIM.replacen(
            "\"persistence\"",
            &std::format!("\"mapping\": {section}, \"persistence\""),
            1,
        );
        let c = BoardConfig::from_json(json.as_bytes()).unwrap();
        assert_eq!(paths(&c), Vec::<String>::new());
        c.motion_filter_config()
    };
    let f = with("{\"motion_filter\": true, \"min_turn_deg\": 5, \"max_interval_s\": 3}");
    let s = MotionFilterConfig::standard();
    assert!(f.enabled);
    assert_eq!(f.min_travel_m, s.min_travel_m);
    assert!((f.min_turn_rad - 5f32.to_radians()).abs() < 1e-6);
    assert_eq!(f.max_interval_s, 3.0);
    assert_eq!(with("{\"motion_filter\": true}"), s);
    assert_eq!(
        with("{\"min_travel_m\": 0.5}"),
        MotionFilterConfig::off(),
        "thresholds alone do not switch it on"
    );
}

#[test]
fn bad_mapping_values_name_their_field() {
    only_problem_at("$.mapping.min_travel_m", |c| {
        c.mapping.min_travel_m = Some(-0.1)
    });
    only_problem_at("$.mapping.min_turn_deg", |c| {
        c.mapping.min_turn_deg = Some(f32::NAN)
    });
    only_problem_at("$.mapping.max_interval_s", |c| {
        c.mapping.max_interval_s = Some(1e9)
    });
    for p in [0.4, 0.99, f32::NAN] {
        only_problem_at("$.mapping.occupied_thresh", |c| {
            c.mapping.occupied_thresh = Some(p)
        });
    }
}

/// `$.mapping.occupied_thresh` sets the probability above which a cell is an obstacle: the
/// thesis's rule (0.5) when absent; the mission the board makes takes it.
#[test]
fn the_occupied_threshold_comes_from_the_board() {
    let c = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(c.grid_bounds().unwrap().occupied_above, 0.0);
    let json = SIM.replacen(
        "\"persistence\"",
        "\"mapping\": {\"occupied_thresh\": 0.65}, \"persistence\"",
        1,
    );
    let noisy = BoardConfig::from_json(json.as_bytes()).unwrap();
    assert_eq!(paths(&noisy), Vec::<String>::new());
    let b = noisy.grid_bounds().unwrap();
    assert!((b.occupied_thresh() - 0.65).abs() < 1e-6);
}

/// `$.robot.footprint` and `$.planning` are optional: absent, the body is the P3-DX's
/// datasheet outline and the clearance the default; present, each key replaces its value.
#[test]
fn the_footprint_and_the_clearance_come_from_the_board() {
    use crate::control::safety::RobotFootprint;
    use crate::mission::footprint::DEFAULT_CLEARANCE_M;
    let c = BoardConfig::from_json(SIM.as_bytes()).unwrap();
    assert_eq!(c.footprint(), RobotFootprint::p3dx());
    assert_eq!(c.clearance_m(), DEFAULT_CLEARANCE_M);
    // A P3-DX with its bumper rings, and more room on each side.
    let json = SIM
        .replacen(
            "\"robot\": {",
            "\"robot\": {\"footprint\": {\"width_m\": 0.425, \"rear_m\": 0.301, \
             \"swing_radius_m\": 0.25},",
            1,
        )
        .replacen(
            "\"persistence\"",
            "\"planning\": {\"clearance_m\": 0.08}, \"persistence\"",
            1,
        );
    let c = BoardConfig::from_json(json.as_bytes()).unwrap();
    assert_eq!(paths(&c), Vec::<String>::new());
    assert_eq!(c.footprint(), RobotFootprint::p3dx_with_bumpers());
    assert_eq!(c.clearance_m(), 0.08);
}

/// Each bad footprint or clearance value is one problem naming its key; so is a body whose
/// planning layer the grid's cells cannot hold.
#[test]
fn bad_footprint_and_clearance_values_name_their_field() {
    only_problem_at("$.robot.footprint.width_m", |c| {
        c.robot.footprint.width_m = Some(0.0)
    });
    only_problem_at("$.robot.footprint.front_m", |c| {
        c.robot.footprint.front_m = Some(f32::NAN)
    });
    only_problem_at("$.robot.footprint.rear_m", |c| {
        c.robot.footprint.rear_m = Some(1.5)
    });
    only_problem_at("$.robot.footprint.swing_radius_m", |c| {
        c.robot.footprint.swing_radius_m = Some(-0.2)
    });
    // Sides outside the swing circle: named at the key the board gave.
    only_problem_at("$.robot.footprint.width_m", |c| {
        c.robot.footprint.width_m = Some(0.6)
    });
    only_problem_at("$.robot.footprint.swing_radius_m", |c| {
        c.robot.footprint.width_m = Some(0.6);
        c.robot.footprint.swing_radius_m = Some(0.28);
    });
    only_problem_at("$.planning.clearance_m", |c| {
        c.planning.clearance_m = Some(-0.01)
    });
    only_problem_at("$.planning.clearance_m", |c| {
        c.planning.clearance_m = Some(0.5)
    });
    // A metre-wide robot on 5 cm cells: its wall bands reach past the layer's stencil.
    only_problem_at("$.robot.footprint", |c| {
        c.grid.resolution_m = 0.05;
        c.robot.footprint.width_m = Some(1.0);
        c.robot.footprint.swing_radius_m = Some(1.0);
    });
    let mut big = BoardConfig::default();
    big.robot.footprint.width_m = Some(1.0);
    big.robot.footprint.swing_radius_m = Some(1.0);
    assert_eq!(paths(&big), Vec::<String>::new(), "10 cm cells hold it");
    let typo = SIM.replacen(
        "\"persistence\"",
        "\"planning\": {\"clearance\": 0.05}, \"persistence\"",
        1,
    );
    match BoardConfig::from_json(typo.as_bytes()) {
        Err(ConfigError::UnknownKey { path, .. }) => {
            assert_eq!(path.as_str(), "$.planning.clearance")
        }
        other => panic!("{other:?}"),
    }
    let wrong = SIM.replacen(
        "\"robot\": {",
        "\"robot\": {\"footprint\": {\"width_m\": \"wide\"},",
        1,
    );
    match BoardConfig::from_json(wrong.as_bytes()) {
        Err(ConfigError::Value { path, .. }) => assert_eq!(path, "$.robot.footprint.width_m"),
        other => panic!("{other:?}"),
    }
}
