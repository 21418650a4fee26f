//! Engine overhead of each optimizer: a whole 30-generation run on the sphere function, whose
//! evaluation (a sum of squares) is negligible next to the method's own work, so the time per
//! run divided by 30 is the per-generation overhead. Two shapes: population 20 x 10 genes (the
//! test-function protocol) and population 10 x 16 genes (exploration, 8 targets).
//!
//! `cargo bench -p papillon --bench optim -- --warm-up-time 1 --measurement-time 2`

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{self, Method, Population, StopRules};
use papillon::random::seeded;

const GENERATIONS: u32 = 30;

fn overhead(c: &mut Criterion) {
    let mut group = c.benchmark_group("optim_run30");
    group.sample_size(20);
    for (pop, dim) in [(20usize, 10usize), (10, 16)] {
        let problem = TestFunction::new(Function::Sphere, dim).unwrap();
        let initial = Population::uniform(&problem, pop, &mut seeded(1)).unwrap();
        let rules = StopRules {
            max_generations: GENERATIONS,
            patience: None,
            max_evaluations: None,
        };
        for method in Method::ALL.into_iter().chain([Method::Random]) {
            let id = BenchmarkId::new(method.name(), format!("p{pop}d{dim}"));
            group.bench_function(id, |b| {
                let mut seed = 0;
                b.iter(|| {
                    seed += 1;
                    let mut problem = problem;
                    let mut rng = seeded(seed);
                    let mut opt = method.build(pop, GENERATIONS);
                    let s = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap();
                    black_box(s.best_fitness)
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, overhead);
criterion_main!(benches);
