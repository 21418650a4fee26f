//! The generated world set (issue 17): deterministic, connected for a P3-DX footprint through
//! openings of 0.5–0.9 m, within the runner's map capacity.

use papillon::grid::DEFAULT_CELL_CAPACITY;
use papillon_sim::world::World;
use papillon_sim::world::generated::{self, Kind, Opening, Plan, SET_LEN};

/// The free run through the middle of an opening, across it, measured on the plan's bitmap
/// [cells of 0.1 m].
fn measured_width(plan: &Plan, o: &Opening) -> i32 {
    let (w, _) = plan.size_cells();
    let blocked = |x: i32, y: i32| plan.blocked()[(y * w + x) as usize];
    let r = o.rect;
    if o.across_x {
        let y = (r.y0 + r.y1) / 2;
        let (mut a, mut b) = (r.x0, r.x0);
        while !blocked(a - 1, y) {
            a -= 1;
        }
        while !blocked(b, y) {
            b += 1;
        }
        b - a
    } else {
        let x = (r.x0 + r.x1) / 2;
        let (mut a, mut b) = (r.y0, r.y0);
        while !blocked(x, a - 1) {
            a -= 1;
        }
        while !blocked(x, b) {
            b += 1;
        }
        b - a
    }
}

fn set() -> Vec<Plan> {
    (0..SET_LEN).map(|i| Plan::from_set(i).unwrap()).collect()
}

#[test]
fn same_seed_same_plan() {
    for kind in Kind::ALL {
        let a = Plan::generate(kind, 42);
        let b = Plan::generate(kind, 42);
        assert_eq!(a, b, "{kind:?}");
        assert_ne!(a.blocked(), Plan::generate(kind, 43).blocked(), "{kind:?}");
    }
    let w1 = World::load("gen-07", 0.1).unwrap();
    let w2 = World::load("gen-07", 0.1).unwrap();
    assert_eq!(w1, w2);
}

#[test]
fn the_world_is_the_plan() {
    let plan = Plan::from_set(3).unwrap();
    let world = World::load("gen-03", 0.1).unwrap();
    assert_eq!(world.name(), "gen-03");
    assert_eq!(world.blocked(), plan.blocked());
    assert_eq!(world.start(), plan.start_pose());
    assert!(world.start_is_clear(generated::START_CLEAR_M));
    let free = plan.free_area_m2() / 0.01;
    assert_eq!(world.truth().free_count(), free.round() as usize);
    // Other resolutions draw the same design.
    let fine = World::load("gen-03", 0.05).unwrap();
    assert!((fine.occupied_fraction() - world.occupied_fraction()).abs() < 0.01);
    let named = World::load("gen-clutter-1703", 0.1).unwrap();
    assert_eq!(named.blocked(), world.blocked());
}

#[test]
fn every_plan_of_the_set_is_a_connected_building_of_the_right_size() {
    let plans = set();
    for kind in Kind::ALL {
        let n = plans.iter().filter(|p| p.kind() == kind).count();
        assert!(n >= 4, "{kind:?} appears {n} times");
    }
    for plan in &plans {
        let name = plan.name();
        let (w, h) = plan.size_m();
        assert!(
            (12.0..=30.0).contains(&w) && (12.0..=30.0).contains(&h),
            "{name}: {w} x {h} m"
        );
        let world = plan.world(0.1).unwrap();
        assert!(
            world.geometry().cell_count() <= DEFAULT_CELL_CAPACITY,
            "{name}"
        );
        assert!(world.start_is_clear(generated::START_CLEAR_M), "{name}");
        let reach = plan.reach();
        assert!(
            reach.is_connected(),
            "{name}: {} footprint cells stranded",
            reach.stranded_cells()
        );
        assert!(reach.reached_cells() > 5000, "{name}");
        // Every designed opening is as wide as designed, 0.5–1.0 m, and the narrowest is
        // 0.5–0.9 m.
        for o in plan.openings() {
            let m = measured_width(plan, o);
            assert_eq!(m, o.width_dm(), "{name}: opening {o:?}");
            assert!((5..=10).contains(&m), "{name}: opening {o:?}");
        }
        let narrowest = plan.narrowest_opening_m();
        assert!((0.5..=0.9).contains(&narrowest), "{name}: {narrowest}");
    }
    // The set has openings of every width from 0.5 m to 0.9 m.
    for width in 5..=9 {
        assert!(
            plans
                .iter()
                .flat_map(|p| p.openings())
                .any(|o| o.width_dm() == width),
            "no opening of {width} dm"
        );
    }
}

#[test]
fn any_seed_gives_a_connected_plan_within_capacity() {
    for kind in Kind::ALL {
        for seed in 0..6 {
            let plan = Plan::generate(kind, seed);
            assert!(plan.reach().is_connected(), "{kind:?} {seed}");
            let (w, h) = plan.size_cells();
            assert!((w * h) as usize <= DEFAULT_CELL_CAPACITY);
        }
    }
}
