//! Exploration decisions never allocate: with the visibility cache, xBOA and the frontier
//! selectors decide on the House fixture under a counting global allocator. Only the test's
//! own thread is counted (the test harness's main thread may allocate meanwhile).
#![cfg(feature = "std")]

mod alloc_count;
mod house_fixture;

use alloc_count::allocations_in;
use house_fixture::{DecisionMemory, HouseSnapshot};
use papillon::explore::{ExploreConfig, NearestFrontier, Optimized, Outcome, TargetSelector};
use papillon::frontier::FrontierWorkspace;
use papillon::optim::Method;
use papillon::random::seeded;

#[test]
fn decisions_do_not_allocate() {
    let house = HouseSnapshot::load();
    let req = house.request();
    let mut ws = FrontierWorkspace::<8192, 256>::new_boxed();
    let mut memory = DecisionMemory::new();
    let mut obj = memory.cached();
    let config = ExploreConfig {
        targets: 2,
        max_generations: 5,
        ..ExploreConfig::default()
    };

    let ((a, b), n) = allocations_in(|| {
        let a = Optimized::new(Method::Xboa, config, &mut obj)
            .decide(&req, &mut seeded(1))
            .unwrap();
        let b = NearestFrontier::new(config, &mut obj, &mut ws)
            .decide(&req, &mut seeded(1))
            .unwrap();
        (a, b)
    });
    assert!(matches!(a, Outcome::Go(_)) && matches!(b, Outcome::Go(_)));
    assert_eq!(n, 0, "{n} allocations");
}
