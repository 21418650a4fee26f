//! A whole optimizer run allocates nothing: every method, from building it to its last
//! generation, under a counting global allocator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{self, Method, Optimizer, Population, StopRules};
use papillon::random::seeded;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static WATCHING: Cell<bool> = const { Cell::new(false) };
}

fn watched() -> bool {
    WATCHING.try_with(Cell::get).unwrap_or(false)
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if watched() {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if watched() {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_whole_run_of_every_method_allocates_nothing() {
    let methods = Method::ALL.into_iter().chain([Method::Random]);
    let mut checked = 0;
    for method in methods {
        for function in [Function::Sphere, Function::Rosenbrock] {
            WATCHING.with(|w| w.set(true));
            let before = ALLOCATIONS.load(Ordering::SeqCst);
            let mut problem = TestFunction::new(function, 10).unwrap();
            let mut rng = seeded(11);
            let initial = Population::uniform(&problem, 20, &mut rng).unwrap();
            let rules = StopRules {
                max_generations: 100,
                patience: Some(10),
                max_evaluations: None,
            };
            let mut opt = method.build(initial.len(), rules.max_generations);
            let summary = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap();
            let history_len = opt.history().len();
            let after = ALLOCATIONS.load(Ordering::SeqCst);
            WATCHING.with(|w| w.set(false));
            assert_eq!(after - before, 0, "{method} on {function} allocated");
            assert!(summary.generations > 0 && history_len == summary.generations as usize + 1);
            checked += 1;
        }
    }
    assert_eq!(checked, 22);
    // The counter itself works.
    WATCHING.with(|w| w.set(true));
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let v = std::hint::black_box(vec![1u8; 10]);
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    WATCHING.with(|w| w.set(false));
    drop(v);
    assert_eq!(after - before, 1);
}
