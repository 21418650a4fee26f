//! Scan matching along a long featureless corridor (issue 18): 43 m long, 2.4 m wide, its end
//! walls beyond the thesis laser's 4 m for most of the way. The robot drives its length with
//! odometry that over-counts distance by 2 % and turns 0.15° left per metre driven; the scans
//! are matched and integrated as a mission does (`papillon::localize::Tracker`). Across the
//! corridor and in heading the walls pin the pose down, so the matcher must hold it (within
//! 10 cm); along it nothing does, so the matcher must keep the odometry there (its error stays
//! within the odometry's own) instead of jumping.
//!
//! Until the likelihood field was made uniform along walls (cells at half their band's height
//! or more all score 1, `papillon::localize::likelihood`), the field sloped along the walls
//! toward where they had been seen most, and the matcher ended 5.6 m behind the truth here.
//!
//! Diagnostics (environment): `CORRIDOR_TRACE=1` prints the error and the last match every 25
//! steps, `CORRIDOR_NORMALS=1` the tilt of the walls' blocks against their normal's standard
//! deviation, `CORRIDOR_TRUTH=1` draws the map at the true pose (docs/experiments.md, sixth
//! measurement).

use papillon::control::odometry::MapFromOdom;
use papillon::geometry::{Pose2, normalize_angle};
use papillon::grid::{GridGeometry, LogOddsBounds, OccupancyGrid};
use papillon::localize::{HitMap, LocalizeConfig, ScanMatcher, Tracker, WINDOW_CELLS};
use papillon::math;
use papillon::mission::MissionConfig;
use papillon::sensor::integrate_scan;
use papillon_sim::laser::LaserSim;
use papillon_sim::world::World;

const CELLS: usize = 440 * 40;

/// Fails (issue 18, docs/experiments.md, sixth measurement): with 5 % range noise the matcher
/// no longer slides along the corridor (it ended 31.6 m off before) but loses the heading in
/// about 40 % of the matches and ends up to 2.4 m across. Run with `--ignored`.
#[test]
#[ignore = "fails: the thesis laser loses the heading in the corridor (docs/experiments.md, sixth measurement)"]
fn along_a_featureless_corridor_with_the_thesis_laser() {
    corridor(0.05, false);
}

#[test]
fn along_a_featureless_corridor_with_a_real_lasers_noise() {
    corridor(0.003, false);
}

/// The same with the odometry's systematic errors estimated online
/// (`papillon::localize::odometry_calibration`): the corridor constrains the heading, so the
/// curvature is learnt from it, and nothing constrains the distance along it.
#[test]
fn along_a_featureless_corridor_with_odometry_calibration() {
    corridor(0.003, true);
}

/// Drives the corridor with the mission's laser at range noise `noise_fraction`, with the
/// tracker's odometry self-calibration on or off.
fn corridor(noise_fraction: f32, calibrate: bool) {
    let geom = GridGeometry::from_extent(44.0, 4.0, 0.1, Default::default()).unwrap();
    let mut world = World::new("corridor", geom);
    world.fill_rect(0.0, 0.0, 44.0, 0.8, true);
    world.fill_rect(0.0, 3.2, 44.0, 4.0, true);
    world.fill_rect(0.0, 0.0, 0.5, 4.0, true);
    world.fill_rect(43.5, 0.0, 44.0, 4.0, true);

    let mission = MissionConfig::default();
    let mut laser_cfg = mission.laser;
    laser_cfg.noise_fraction = noise_fraction;
    let mut laser = LaserSim::new(laser_cfg, 3);
    let mut grid = OccupancyGrid::<CELLS>::new_boxed(geom, LogOddsBounds::default()).unwrap();
    let mut hits = HitMap::<CELLS>::new_boxed(geom);
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    // Every scan matched (no minimum travel): the most matches, the most chances to drift.
    let config = LocalizeConfig {
        enabled: true,
        min_travel_m: 0.0,
        min_turn_rad: 0.0,
        ..LocalizeConfig::default()
    };
    let mut config = config;
    config.calibration.enabled = calibrate;
    let mut tracker = Tracker::new();

    let start = Pose2::new(1.5, 2.0, 0.0);
    let step_m = 0.03;
    let mut odom = Pose2::new(0.0, 0.0, 0.0);
    let mut transform = MapFromOdom::from_start(start, odom);
    let mut worst_across: f32 = 0.0;
    let mut worst_heading: f32 = 0.0;
    let (mut truth, mut estimate) = (start, start);
    let steps = (40.0 / step_m) as usize;
    let mut counts = [0u32; 4];
    let mut along_sum = 0.0f32;
    // The odometry's increments laid along the estimate's own heading: where a matcher that
    // keeps the odometry along the corridor ends (its x), whatever heading it holds.
    let mut odometry_on_estimate_x = start.x;
    for k in 0..=steps {
        truth = Pose2::new(start.x + k as f32 * step_m, start.y, 0.0);
        if k > 0 {
            // Odometry: 2 % long, 0.15° left per metre.
            let d = step_m * 1.02;
            let turn = (0.15f32).to_radians() * step_m;
            odometry_on_estimate_x += d * math::cos(estimate.theta + 0.5 * turn);
            odom = Pose2::new(
                odom.x + d * math::cos(odom.theta),
                odom.y + d * math::sin(odom.theta),
                odom.theta + turn,
            );
        }
        let scan = laser.scan(&world, truth, &[]);
        estimate = tracker
            .on_scan(
                &config,
                &grid,
                &hits,
                &mut matcher,
                &scan,
                &laser_cfg,
                odom,
                &mut transform,
            )
            .unwrap_or_else(|| transform.map_pose(odom));
        if std::env::var("CORRIDOR_TRUTH").is_ok() {
            estimate = truth;
        }
        integrate_scan(
            &mut grid,
            &scan,
            estimate,
            &laser_cfg,
            &mission.sensor,
            &mut (),
        )
        .unwrap();
        hits.add_scan(&scan, &laser_cfg, estimate);
        if let Some(q) = tracker.last() {
            counts[q.constrained as usize] += 1;
            along_sum += q.correction[0];
        }
        if std::env::var("CORRIDOR_TRACE").is_ok()
            && k % 25 == 0
            && let Some(q) = tracker.last()
        {
            eprintln!(
                "k {k} err x {:.3} y {:.3} th {:.4} | c {} eig {:?} corr {:?} dist {:?}",
                estimate.x - truth.x,
                estimate.y - truth.y,
                normalize_angle(estimate.theta - truth.theta),
                q.constrained,
                q.eigenvalues,
                q.correction,
                q.distrust
            );
        }
        worst_across = worst_across.max((estimate.y - truth.y).abs());
        worst_heading = worst_heading.max(normalize_angle(estimate.theta - truth.theta).abs());
    }
    if std::env::var("CORRIDOR_NORMALS").is_ok() {
        for wall_y in [0.8f32, 3.2] {
            let (mut n, mut s2, mut f2) = (0, 0.0f64, 0.0f64);
            let mut x = 2.0f32;
            while x < 40.0 {
                if let Some(sf) =
                    hits.surface_at(papillon::geometry::Point2::new(x, wall_y), 2, 0.1)
                {
                    let tilt = sf.normal.x.atan2(sf.normal.y.abs()) as f64;
                    let phi2 = sf.normal_var_rad2 as f64;
                    n += 1;
                    s2 += tilt * tilt;
                    f2 += phi2;
                    if n % 40 == 0 {
                        eprintln!(
                            "x {x} tilt {:.2} deg, formula {:.2} deg, w {} along {} across {}",
                            tilt.to_degrees(),
                            phi2.sqrt().to_degrees(),
                            sf.weight,
                            sf.along_var_m2,
                            sf.across_var_m2
                        );
                    }
                }
                x += 0.05;
            }
            eprintln!(
                "wall {wall_y}: rms tilt {:.2} deg, rms formula {:.2} deg over {n}",
                (s2 / n as f64).sqrt().to_degrees(),
                (f2 / n as f64).sqrt().to_degrees()
            );
        }
    }
    let odometry_only = MapFromOdom::from_start(start, Pose2::new(0.0, 0.0, 0.0)).map_pose(odom);
    let along_matched = (estimate.x - truth.x).abs();
    // What keeping the odometry along the corridor gives is its increments laid along the
    // heading the walls hold, not the odometry-only pose: that pose ends 0.73 m along
    // instead of the 0.80 m the 2 % over-count makes because its 6° heading drift folds
    // distance across the corridor (it ends 2 m across). A pose that held the true heading
    // exactly and kept the odometry along would end 0.80 m along and fail a bound of
    // 0.725 m + 5 cm, so the odometry-only pose's x error is the wrong reference; the
    // increments on the estimate's own heading are the right one (docs/experiments.md,
    // sixth measurement).
    let along_odometry = (odometry_on_estimate_x - truth.x).abs();
    let along_odometry_only = (odometry_only.x - truth.x).abs();
    eprintln!(
        "noise {noise_fraction}: along: matched {along_matched} m, odometry on the estimate's heading \
         {along_odometry} m (odometry-only pose {along_odometry_only} m); across worst \
         {worst_across} m; heading worst {worst_heading} rad; constrained {counts:?}; \
         corrections along summed {along_sum} m"
    );
    if calibrate {
        // The odometry turns 0.15° left per metre that the robot does not.
        let cal = tracker.calibration();
        eprintln!(
            "calibration: turn gain {} curvature {} rad/m (odometry's error {} rad/m), σ {:?}",
            cal.turn_gain(),
            cal.curvature_rad_per_m(),
            -(0.15f32).to_radians() / 1.02,
            cal.sigmas()
        );
        let err = cal.curvature_rad_per_m() + (0.15f32).to_radians() / 1.02;
        assert!(err.abs() < 1e-3, "curvature {err} rad/m off");
    }
    assert!(tracker.trusted() > steps as u32 / 2, "{tracker:?}");
    assert!(
        worst_across <= 0.10,
        "across the corridor: {worst_across} m (odometry alone ends {} m off)",
        (odometry_only.y - truth.y).abs()
    );
    assert!(worst_heading <= 0.05, "heading: {worst_heading} rad");
    assert!(
        along_matched <= along_odometry + 0.05,
        "along the corridor: {along_matched} m (estimate - truth {} m), odometry on the \
         estimate's heading {along_odometry} m; matches by directions constrained {counts:?}, corrections along \
         summed {along_sum} m",
        estimate.x - truth.x
    );
}
