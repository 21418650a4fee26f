//! Matching scans to the map allocates nothing: a counting global allocator watches the thread
//! doing the work (the matcher's memory is allocated once, before).

mod alloc_count;
#[path = "localize_fixture/mod.rs"]
mod localize_fixture;

use alloc_count::allocations_in;
use localize_fixture::HalfExplored;
use papillon::geometry::Pose2;
use papillon::localize::{MatchConfig, ScanMatcher, WINDOW_CELLS};

#[test]
fn matching_scans_allocates_nothing() {
    let mut house = HalfExplored::new();
    let poses = [
        Pose2::new(2.0, 1.8, 0.8),
        Pose2::new(1.8, 2.2, -2.0),
        Pose2::new(2.2, 2.0, 1.6),
    ];
    let scans: Vec<_> = poses.iter().map(|&p| house.scan(p)).collect();
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    let config = MatchConfig::default();
    let (results, n) = allocations_in(|| {
        let mut out = [None; 3];
        for (k, (scan, truth)) in scans.iter().zip(poses).enumerate() {
            let predicted = Pose2::new(truth.x + 0.06, truth.y - 0.04, truth.theta + 0.02);
            out[k] = Some(matcher.match_scan(
                &house.grid,
                &house.hits,
                scan,
                &house.laser,
                predicted,
                &config,
            ));
        }
        out
    });
    assert_eq!(n, 0, "matching allocated {n} times");
    // The work was done: every match was trusted and ended near the truth (a sanity bound:
    // accuracy is measured by the unit tests and the runner, not here).
    for (r, truth) in results.iter().zip(poses) {
        let r = r.unwrap();
        assert!(r.quality.trusted(), "{:?}", r.quality);
        let err = r.pose.position().distance(truth.position());
        assert!(err < 0.12, "{err} m: {r:?} vs {truth:?}");
    }
}

/// The tracker with the odometry self-calibration on (`LocalizeConfig::calibration`): the
/// prediction from the corrected increment and the augmented update allocate nothing either.
#[test]
fn tracking_with_odometry_calibration_allocates_nothing() {
    use papillon::control::odometry::MapFromOdom;
    use papillon::localize::{LocalizeConfig, Tracker};
    let mut house = HalfExplored::new();
    let poses = [
        Pose2::new(2.0, 1.8, 0.8),
        Pose2::new(2.05, 1.85, 0.9),
        Pose2::new(2.1, 1.9, 1.0),
    ];
    let scans: Vec<_> = poses.iter().map(|&p| house.scan(p)).collect();
    let mut matcher = Box::new(ScanMatcher::<WINDOW_CELLS>::new());
    let mut config = LocalizeConfig {
        enabled: true,
        ..LocalizeConfig::default()
    };
    config.calibration.enabled = true;
    let mut tracker = Tracker::new();
    // The odometry frame is the map frame, and the odometry turns 1 % too little.
    let mut transform = MapFromOdom::from_start(poses[0], poses[0]);
    let (trusted, n) = allocations_in(|| {
        let mut trusted = 0;
        for (scan, truth) in scans.iter().zip(poses) {
            let odom = Pose2::new(truth.x, truth.y, 0.8 + (truth.theta - 0.8) * 0.99);
            if tracker
                .on_scan(
                    &config,
                    &house.grid,
                    &house.hits,
                    &mut matcher,
                    scan,
                    &house.laser,
                    odom,
                    &mut transform,
                )
                .is_some()
            {
                trusted += 1;
            }
        }
        trusted
    });
    assert_eq!(n, 0, "tracking allocated {n} times");
    assert!(trusted >= 2, "{tracker:?}");
    assert!(tracker.calibration().turn_gain().is_finite());
}
