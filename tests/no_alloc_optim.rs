//! A whole optimizer run allocates nothing: every method, from building it to its last
//! generation, under a counting global allocator.

mod alloc_count;

use alloc_count::allocations_in;
use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{self, Method, Optimizer, Population, Preset, StopRules};
use papillon::random::seeded;

#[test]
fn a_whole_run_of_every_method_allocates_nothing() {
    let methods = Method::ALL.into_iter().chain([Method::Random]);
    let mut checked = 0;
    for method in methods {
        for function in [Function::Sphere, Function::Rosenbrock] {
            let ((summary, history_len), n) = allocations_in(|| {
                let mut problem = TestFunction::new(function, 10).unwrap();
                let mut rng = seeded(11);
                let initial = Population::uniform(&problem, 20, &mut rng).unwrap();
                let rules = StopRules {
                    max_generations: 100,
                    patience: Some(10),
                    max_evaluations: None,
                };
                let mut opt = method.build(initial.len(), rules.max_generations);
                let summary =
                    optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap();
                (summary, opt.history().len())
            });
            assert_eq!(n, 0, "{method} on {function} allocated");
            assert!(summary.generations > 0 && history_len == summary.generations as usize + 1);
            checked += 1;
        }
    }
    assert_eq!(checked, 22);
}

#[test]
fn the_standard_preset_on_a_shifted_function_allocates_nothing() {
    for method in [Method::Ga, Method::Pso, Method::Gwo] {
        let (summary, n) = allocations_in(|| {
            let mut problem = TestFunction::shifted(Function::Rastrigin, 10, 1.7).unwrap();
            let mut rng = seeded(12);
            let initial = Population::uniform(&problem, 20, &mut rng).unwrap();
            let rules = StopRules {
                max_generations: 100,
                patience: None,
                max_evaluations: None,
            };
            let mut opt = method.build_preset(Preset::Standard, initial.len(), 100);
            optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap()
        });
        assert_eq!(n, 0, "{method} (standard) allocated");
        assert_eq!(summary.generations, 100);
    }
}
