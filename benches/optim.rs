//! Engine overhead of each optimizer: a whole 30-generation run on the sphere function, whose
//! evaluation (a sum of squares) is negligible next to the method's own work, so the time per
//! run divided by 30 is the per-generation overhead. Two shapes: population 20 x 10 genes (the
//! test-function protocol) and population 10 x 16 genes (exploration, 8 targets).
//!
//! `optim_pygmo_protocol`: issue 23's comparison with pygmo, one whole run (build, start from
//! 20 individuals, 100 generations, 10 genes, standard preset) of GA, PSO, GWO, ABC and CMA-ES
//! on the sphere and Rastrigin functions, evaluations included (`docs/optimizers.md`).
//!
//! `cargo bench -p papillon --bench optim -- --warm-up-time 1 --measurement-time 2`

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use papillon::optim::functions::{Function, TestFunction};
use papillon::optim::{self, Method, Population, Preset, StopRules};
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

fn pygmo_protocol(c: &mut Criterion) {
    const GENS: u32 = 100;
    let mut group = c.benchmark_group("optim_pygmo_protocol");
    group.sample_size(20);
    let rules = StopRules {
        max_generations: GENS,
        patience: None,
        max_evaluations: None,
    };
    for function in [Function::Sphere, Function::Rastrigin] {
        let problem = TestFunction::new(function, 10).unwrap();
        let initial = Population::uniform(&problem, 20, &mut seeded(1)).unwrap();
        for method in [
            Method::Ga,
            Method::Pso,
            Method::Gwo,
            Method::Abc,
            Method::CmaEs,
        ] {
            let id = BenchmarkId::new(method.name(), function.name());
            group.bench_function(id, |b| {
                let mut seed = 0;
                b.iter(|| {
                    seed += 1;
                    let mut problem = problem;
                    let mut rng = seeded(seed);
                    let mut opt = method.build_preset(Preset::Standard, 20, GENS);
                    let s = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap();
                    black_box(s.best_fitness)
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, overhead, pygmo_protocol);
criterion_main!(benches);
