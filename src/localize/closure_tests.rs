//! Loop closure ([`super::loop_closure`]) on the synthetic worlds of [`super::tests`]: a match
//! against a local map of old keyframes is accepted with the right pose in a furnished room,
//! and refused in a featureless corridor.

use super::keyframes::KeyframeStore;
use super::loop_closure::{ClosureConfig, LOCAL_CELLS, LocalMap, Refusal, candidate};
use super::tests::{config, corridor, matcher, returns, room, scan_at};
use crate::geometry::{Pose2, normalize_angle};
use crate::grid::LogOddsBounds;
use crate::sensor::{LaserConfig, SensorModel};

type Store = KeyframeStore<8>;

/// Three old keyframes a metre apart along a corridor's middle, heading east.
fn along_the_corridor() -> [Pose2; 3] {
    [18.0, 19.0, 20.0].map(|x| Pose2::new(x, 2.0, 0.0))
}

/// Old keyframes at `poses`, taken `path_step` metres of path apart, scans from `walls`.
fn keep(walls: &[super::tests::Segment], poses: &[Pose2], laser: &LaserConfig) -> Box<Store> {
    let mut store: Box<Store> = bytemuck::zeroed_box();
    for (k, p) in poses.iter().enumerate() {
        let scan = scan_at(walls, *p, laser, 0.003, 100 + k as u64);
        store.push(&scan, laser, k as f32).unwrap();
    }
    store
}

/// Draws the local map of the old keyframes `store` (taken at `old`) around `predicted`, on a
/// 10 cm grid with the default sensor model.
fn render_old(
    local: &mut LocalMap<LOCAL_CELLS>,
    store: &Store,
    old: &[Pose2],
    predicted: Pose2,
    laser: &LaserConfig,
) {
    local
        .render(
            store,
            |i| old.get(i).copied(),
            0..old.len(),
            predicted.position(),
            0.1,
            laser,
            &SensorModel::default(),
            LogOddsBounds::default(),
        )
        .unwrap();
}

/// The keyframes of the first visit, which went round the furnished room.
fn first_visit() -> [Pose2; 6] {
    [
        Pose2::new(2.0, 2.0, 0.0),
        Pose2::new(3.5, 2.5, 0.4),
        Pose2::new(5.0, 3.0, 1.2),
        Pose2::new(6.5, 2.0, 2.5),
        Pose2::new(4.5, 5.0, -2.8),
        Pose2::new(2.0, 4.5, -1.5),
    ]
}

#[test]
fn a_drifted_return_to_a_furnished_room_is_closed_at_the_true_pose() {
    let (walls, _) = room();
    let laser = LaserConfig::lms1xx();
    let old = first_visit();
    let store = keep(&walls, &old, &laser);
    let mut local: Box<LocalMap<LOCAL_CELLS>> = bytemuck::zeroed_box();
    let mut m = matcher();
    let c = ClosureConfig::default();
    // Two drifts at a place the matcher constrains in every direction (many more places and
    // headings: `drifted_returns_are_closed_at_the_truth_or_refused`).
    let cases = [
        (Pose2::new(4.0, 3.0, 0.3), (0.3, -0.2, 0.12)),
        (Pose2::new(4.0, 3.0, 0.3), (-0.25, 0.3, -0.15)),
    ];
    for (k, (truth, (dx, dy, dth))) in cases.into_iter().enumerate() {
        // The drifted estimate of the current pose, beyond the tracker's ±0.3 m / ±0.1 rad.
        let predicted = Pose2::new(truth.x + dx, truth.y + dy, truth.theta + dth);
        render_old(&mut local, &store, &old, predicted, &laser);
        let scan = scan_at(&walls, truth, &laser, 0.003, k as u64);
        let (verdict, q) = local.close(&mut m, &scan, &laser, predicted, &config(), &c);
        let pose = verdict.unwrap_or_else(|why| panic!("case {k}: refused {why:?}, {q:?}"));
        let err = pose.position().distance(truth.position());
        let err_th = normalize_angle(pose.theta - truth.theta).abs();
        // Measured: 1.4 cm and 0.012 rad in case 0 (the matcher's own heading error on a map
        // drawn from noisy scans); the drift put in was 36 cm and 0.12 rad.
        assert!(
            err < 0.03 && err_th < 0.02,
            "case {k}: {err} m, {err_th} rad"
        );
    }
}

#[test]
fn a_featureless_corridor_is_not_closed() {
    let (walls, _) = corridor();
    let laser = LaserConfig::lms1xx();
    let old = along_the_corridor();
    let store = keep(&walls, &old, &laser);
    let mut local: Box<LocalMap<LOCAL_CELLS>> = bytemuck::zeroed_box();
    let mut m = matcher();
    let truth = Pose2::new(19.5, 2.1, 3.1);
    let predicted = Pose2::new(19.8, 2.0, 3.05);
    render_old(&mut local, &store, &old, predicted, &laser);
    let scan = scan_at(&walls, truth, &laser, 0.003, 7);
    let c = ClosureConfig::default();
    let (verdict, q) = local.close(&mut m, &scan, &laser, predicted, &config(), &c);
    assert!(
        matches!(
            verdict,
            Err(Refusal::Unconstrained(_) | Refusal::Distrusted(_))
        ),
        "{verdict:?} {q:?}"
    );
}

#[test]
fn candidates_are_old_and_near() {
    let (walls, _) = room();
    let laser = LaserConfig::lms1xx();
    let poses = [
        Pose2::new(2.0, 2.0, 0.0),
        Pose2::new(6.0, 2.0, 0.0),
        Pose2::new(2.5, 2.0, 0.0),
    ];
    let mut store: Box<Store> = bytemuck::zeroed_box();
    for (k, p) in poses.iter().enumerate() {
        let scan = scan_at(&walls, *p, &laser, 0.0, k as u64);
        // Keyframes at 0 m, 5 m and 12 m of path.
        store.push(&scan, &laser, [0.0, 5.0, 12.0][k]).unwrap();
    }
    let c = ClosureConfig {
        min_path_m: 10.0,
        max_distance_m: 2.5,
        ..ClosureConfig::default()
    };
    let at = |x: f32| Pose2::new(x, 2.0, 0.0);
    let pose_of = |i: usize| poses.get(i).copied();
    // At 20 m of path, near (2.4, 2): keyframe 0 (8 m old keyframe 2 is too recent).
    assert_eq!(candidate(&store, pose_of, at(2.4), 20.0, &c), Some(0));
    // At 16 m: only keyframe 0 and 1 are 10 m old; near (5.5, 2) keyframe 1.
    assert_eq!(candidate(&store, pose_of, at(5.5), 16.0, &c), Some(1));
    // At 9 m nothing is old enough; far from all, nothing.
    assert_eq!(candidate(&store, pose_of, at(2.4), 9.0, &c), None);
    assert_eq!(candidate(&store, pose_of, at(8.6), 30.0, &c), None);
}

/// Many drifted returns to the furnished room: 8 places x 7 headings x the two drifts of the
/// test above, old keyframes from its 6 poses, laser noise 0.3 %. No accepted closure may be
/// more than 0.1 m off the truth, and most returns to the places the old keyframes saw well
/// must be closed. (Before the returns layer's `clear` also forgot the per-cell statistics
/// the point-to-line fit reads, the local map of one attempt kept the surfaces of the
/// attempts before it, drawn on another lattice: 76 of these 112 were accepted, 29 of them
/// 0.14-0.84 m and up to 17° off.)
#[test]
fn drifted_returns_are_closed_at_the_truth_or_refused() {
    let (walls, _) = room();
    let laser = LaserConfig::lms1xx();
    let old = first_visit();
    let store = keep(&walls, &old, &laser);
    let mut local: Box<LocalMap<LOCAL_CELLS>> = bytemuck::zeroed_box();
    let mut m = matcher();
    let c = ClosureConfig::default();
    // The first five places lie among the old keyframes; the last three (the east end, the
    // north wall) are seen by them from afar or not at all, and may be refused.
    let places = [
        (1.5, 1.5),
        (2.2, 3.5),
        (4.0, 1.5),
        (4.5, 4.0),
        (5.5, 2.5),
        (7.3, 1.5),
        (7.5, 5.5),
        (3.5, 5.8),
    ];
    let drifts = [(0.3, -0.2, 0.12), (-0.25, 0.3, -0.15)];
    let (mut accepted, mut accepted_near, mut near, mut worst) = (0, 0, 0, (0.0f32, 0.0f32));
    for (p, &(x, y)) in places.iter().enumerate() {
        for h in 0..7 {
            let truth = Pose2::new(x, y, -3.0 + h as f32 * 6.0 / 7.0);
            for (d, &(dx, dy, dth)) in drifts.iter().enumerate() {
                let predicted = Pose2::new(truth.x + dx, truth.y + dy, truth.theta + dth);
                render_old(&mut local, &store, &old, predicted, &laser);
                let seed = (p * 100 + h * 10 + d) as u64;
                let scan = scan_at(&walls, truth, &laser, 0.003, seed);
                let (verdict, q) = local.close(&mut m, &scan, &laser, predicted, &config(), &c);
                near += usize::from(p < 5);
                if let Ok(pose) = verdict {
                    accepted += 1;
                    accepted_near += usize::from(p < 5);
                    let err = pose.position().distance(truth.position());
                    let err_th = normalize_angle(pose.theta - truth.theta).abs();
                    assert!(
                        err < 0.1,
                        "place {p}, heading {h}, drift {d}: closed {err} m, {err_th} rad off the truth ({q:?})"
                    );
                    worst = (worst.0.max(err), worst.1.max(err_th));
                }
            }
        }
    }
    // Measured: 54 of 112 accepted, all 54 at the first five places (of 70), at most
    // 5.1 cm and 1.75° off.
    assert!(
        accepted_near * 10 >= near * 7,
        "{accepted_near} of {near} returns among the old keyframes closed ({accepted} of 112 in all)"
    );
    assert!(worst.0 < 0.1, "{worst:?}");
}

/// A corridor 2 m wide (the featureless one's walls) whose walls carry a 0.3 m jamb every
/// 0.6 m from x = 12 m to 27 m: every scan there is constrained along the corridor, but a pose
/// 0.6 m further along explains it as well.
fn jambs() -> [super::tests::Segment; 54] {
    let mut walls = [super::tests::seg(1.0, 1.0, 41.0, 1.0); 54];
    walls[1] = super::tests::seg(1.0, 3.0, 41.0, 3.0);
    for k in 0..26 {
        let x = 12.0 + 0.6 * k as f32;
        walls[2 + 2 * k] = super::tests::seg(x, 1.0, x, 1.3);
        walls[3 + 2 * k] = super::tests::seg(x, 3.0, x, 2.7);
    }
    walls
}

/// The closures' ambiguity test: in a corridor of evenly spaced jambs, a match the wide search
/// put one jamb further on (0.6 m) while the prediction lies in the true pose's basin is
/// refused, the refinement from the prediction pairing as many returns elsewhere; the true
/// pose from the same prediction is not ambiguous; with the test off the free-space test
/// refuses the alias, and with both off nothing is refused.
#[test]
fn a_match_the_prediction_explains_as_well_elsewhere_is_ambiguous() {
    let walls = jambs();
    let laser = LaserConfig::lms1xx();
    let old = along_the_corridor();
    let store = keep(&walls, &old, &laser);
    let mut local: Box<LocalMap<LOCAL_CELLS>> = bytemuck::zeroed_box();
    let truth = Pose2::new(19.5, 2.05, 0.02);
    let predicted = Pose2::new(19.56, 2.01, 0.03);
    let alias = Pose2::new(truth.x + 0.6, truth.y, truth.theta);
    render_old(&mut local, &store, &old, predicted, &laser);
    let scan = scan_at(&walls, truth, &laser, 0.003, 11);
    let (points, n) = returns(&scan, &laser);
    let points = &points[..n];
    let c = ClosureConfig::default();
    let verdict = local.second_basin(points, &laser, predicted, alias, &config(), &c);
    assert!(
        matches!(verdict, Some(Refusal::Ambiguous(r)) if r >= c.ambiguity_ratio),
        "{verdict:?}"
    );
    assert_eq!(
        local.second_basin(points, &laser, predicted, truth, &config(), &c),
        None
    );
    // Without the ambiguity test the free-space test still refuses the alias: one jamb on,
    // the beams that met a jamb's side end behind the next one.
    let free_space_only = ClosureConfig {
        ambiguity: false,
        ..c
    };
    let verdict = local.second_basin(
        points,
        &laser,
        predicted,
        alias,
        &config(),
        &free_space_only,
    );
    assert!(
        matches!(verdict, Some(Refusal::SeesThrough(_))),
        "{verdict:?}"
    );
    let off = ClosureConfig {
        see_through: false,
        ..free_space_only
    };
    assert_eq!(
        local.second_basin(points, &laser, predicted, alias, &config(), &off),
        None
    );
}

/// The free-space test between two basins: a scan of the wall's east face matched a wall's
/// thickness west puts its returns on the west face, behind the east one; with the ambiguity
/// test off (it may or may not tell the two apart, by the returns each pairs) that match is
/// refused as seeing through the wall, the true pose from the same prediction is not, and
/// with both tests off nothing is refused.
#[test]
fn a_match_that_puts_the_returns_behind_a_wall_is_refused() {
    let walls = super::tests::thick_wall();
    let laser = LaserConfig::lms1xx();
    let old = [
        Pose2::new(1.5, 1.5, 0.0),
        Pose2::new(1.5, 3.2, 0.0),
        Pose2::new(3.0, 3.3, 0.0),
        Pose2::new(4.5, 3.2, core::f32::consts::PI),
        Pose2::new(4.5, 1.5, core::f32::consts::PI),
    ];
    let store = keep(&walls, &old, &laser);
    let mut local: Box<LocalMap<LOCAL_CELLS>> = bytemuck::zeroed_box();
    let truth = Pose2::new(4.2, 1.2, core::f32::consts::PI);
    let predicted = Pose2::new(4.22, 1.18, core::f32::consts::PI + 0.01);
    let behind = Pose2::new(truth.x - 0.2, truth.y, truth.theta);
    render_old(&mut local, &store, &old, predicted, &laser);
    let scan = scan_at(&walls, truth, &laser, 0.003, 12);
    let (points, n) = returns(&scan, &laser);
    let points = &points[..n];

    let margin_m = 0.15;
    let seen_through =
        |pose| super::free_space::seen_through(local.grid(), points, &laser, pose, margin_m);
    let (at_truth, at_behind) = (seen_through(truth), seen_through(behind));
    assert!(
        at_behind > at_truth + 0.1,
        "behind the wall {at_behind}, at the truth {at_truth}"
    );

    let c = ClosureConfig {
        ambiguity: false,
        ..ClosureConfig::default()
    };
    let verdict = local.second_basin(points, &laser, predicted, behind, &config(), &c);
    assert!(
        matches!(verdict, Some(Refusal::SeesThrough(f)) if f == at_behind),
        "{verdict:?}"
    );
    assert_eq!(
        local.second_basin(points, &laser, predicted, truth, &config(), &c),
        None
    );
    let off = ClosureConfig {
        see_through: false,
        ..c
    };
    assert_eq!(
        local.second_basin(points, &laser, predicted, behind, &config(), &off),
        None
    );
}
