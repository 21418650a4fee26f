//! Behaviour shared by every method.

use super::functions::{Function, TestFunction};
use super::*;
use crate::random::seeded;

const FUNCTIONS: [Function; 3] = [Function::Sphere, Function::Rastrigin, Function::Rosenbrock];

fn long_run() -> StopRules {
    StopRules {
        max_generations: 100,
        patience: None,
        max_evaluations: None,
    }
}

/// Initial population of run `run`, the same for every method.
fn initial(problem: &TestFunction, run: u64) -> Population {
    Population::uniform(problem, 20, &mut seeded(1000 + run)).unwrap()
}

#[test]
fn every_method_improves_on_every_run_within_bounds_with_exact_counts() {
    for method in Method::ALL {
        for function in FUNCTIONS {
            check_every_run(method, Preset::Thesis, function, None);
        }
    }
}

#[test]
fn the_standard_preset_and_shifted_optima_keep_those_guarantees() {
    for method in [Method::Ga, Method::Pso, Method::Gwo, Method::Abc] {
        for function in FUNCTIONS {
            check_every_run(method, Preset::Standard, function, None);
            check_every_run(method, Preset::Standard, function, Some(1.7));
        }
    }
    // Every method keeps its bounds, counts and history with the optimum moved, and improves
    // on its initial best in every run but one: ABOA on the shifted Rastrigin function stalls
    // in one run of the 25 (docs/optimizers.md).
    for method in Method::ALL {
        for function in FUNCTIONS {
            let stall_seen = method == Method::Aboa && function == Function::Rastrigin;
            let stalled = check_runs(method, Preset::Thesis, function, Some(1.7), !stall_seen);
            assert_eq!(stalled, usize::from(stall_seen), "{method} on {function}");
        }
    }
}

/// 25 runs of `method` on `function` (10 genes, optimum moved to `shift`): every run improves
/// on its initial best, evaluates only inside the bounds, counts every evaluation, and its
/// best-fitness history never rises.
fn check_every_run(method: Method, preset: Preset, function: Function, shift: Option<f32>) {
    check_runs(method, preset, function, shift, true);
}

/// [`check_every_run`], improvement asserted only if `must_improve`; returns the number of
/// runs that ended on their initial best.
fn check_runs(
    method: Method,
    preset: Preset,
    function: Function,
    shift: Option<f32>,
    must_improve: bool,
) -> usize {
    let mut stalled = 0;
    for run in 0..25u64 {
        let inner = match shift {
            None => TestFunction::new(function, 10).unwrap(),
            Some(s) => TestFunction::shifted(function, 10, s).unwrap(),
        };
        let mut problem = Counting::new(inner);
        let start = initial(&problem.inner, run);
        let value = |g: &[f32]| inner.clone().evaluate(g);
        let start_best = start.genes[..20]
            .iter()
            .map(|g| value(&g[..10]))
            .fold(f32::INFINITY, f32::min);
        let mut opt = method.build_preset(preset, 20, 100);
        let mut rng = seeded(run);
        let s = run_optimizer(&mut opt, &mut problem, &start, &mut rng);
        let ctx = format!("{method} ({preset}) on {function} shifted by {shift:?}, run {run}");
        assert!(
            s.best_fitness < start_best || !must_improve,
            "{ctx}: {} not below {start_best}",
            s.best_fitness
        );
        stalled += usize::from(s.best_fitness >= start_best);
        assert_eq!(opt.history()[0], start_best, "{ctx}");
        assert_eq!(opt.history().len(), 101, "{ctx}");
        assert!(
            opt.history().windows(2).all(|w| w[1] <= w[0]),
            "{ctx}: history rises"
        );
        assert_eq!(problem.count, opt.evaluations(), "{ctx}: evaluation count");
        assert!(
            !problem.out_of_bounds,
            "{ctx}: evaluated outside the bounds"
        );
        let (lo, hi) = function.bounds();
        assert!(
            opt.best_genome().iter().all(|g| (lo..=hi).contains(g)),
            "{ctx}"
        );
        assert_eq!(value(opt.best_genome()), opt.best_fitness(), "{ctx}");
        for i in 0..opt.population().len() {
            assert!(
                opt.population()
                    .genome(i)
                    .iter()
                    .all(|g| (lo..=hi).contains(g)),
                "{ctx}"
            );
        }
    }
    stalled
}

/// Median best fitness of 25 runs (10 genes, population 20, 100 generations).
fn median_best(method: Method, preset: Preset, function: Function, shift: f32) -> f32 {
    let mut bests = [0.0f32; 25];
    for (run, b) in bests.iter_mut().enumerate() {
        let mut problem = Counting::new(TestFunction::shifted(function, 10, shift).unwrap());
        let start = initial(&problem.inner, run as u64);
        let mut opt = method.build_preset(preset, 20, 100);
        *b = run_optimizer(&mut opt, &mut problem, &start, &mut seeded(50 + run as u64))
            .best_fitness;
    }
    bests.sort_unstable_by(f32::total_cmp);
    bests[12]
}

#[test]
fn standard_ga_and_pso_reach_a_sphere_median_the_thesis_tuning_does_not() {
    // docs/optimizers.md: standard GA ~0.017 and PSO ~0.003 against the thesis tuning's ~0.15
    // and ~0.3, with the optimum at the centre or moved to 1.7.
    for shift in [0.0, 1.7] {
        for (method, bound) in [(Method::Ga, 0.05), (Method::Pso, 0.02)] {
            let standard = median_best(method, Preset::Standard, Function::Sphere, shift);
            let thesis = median_best(method, Preset::Thesis, Function::Sphere, shift);
            assert!(
                standard < bound && thesis > bound,
                "{method}, shift {shift}: standard {standard}, thesis {thesis}, bound {bound}"
            );
        }
    }
}

#[test]
fn gabc_reaches_a_sphere_median_karabogas_abc_does_not() {
    // docs/optimizers.md: GABC (standard preset) ~3e-7 against Karaboga's ABC's ~2e-4.
    for shift in [0.0, 1.7] {
        let standard = median_best(Method::Abc, Preset::Standard, Function::Sphere, shift);
        let thesis = median_best(Method::Abc, Preset::Thesis, Function::Sphere, shift);
        assert!(
            standard < 1e-5 && thesis > 1e-5,
            "shift {shift}: standard {standard}, thesis {thesis}"
        );
    }
}

#[test]
fn plus_replacement_never_worsens_any_rank() {
    // With (mu + lambda) survival the k-th best fitness of the population never rises, for
    // every k; generational replacement keeps only the best.
    let mut problem = TestFunction::new(Function::Rastrigin, 6).unwrap();
    let start = Population::uniform(&problem, 12, &mut seeded(4)).unwrap();
    let mut rng = seeded(5);
    let sorted = |p: &Population| {
        let mut f = [0.0f32; 12];
        f.copy_from_slice(&p.fitness[..12]);
        f.sort_unstable_by(f32::total_cmp);
        f
    };
    for params in [ga::GaParams::standard(), ga::GaParams::pygmo()] {
        let mut opt = ga::Ga::new(params, 40);
        opt.start(&mut problem, &start).unwrap();
        let mut before = sorted(opt.population());
        for g in 0..40 {
            opt.step(&mut problem, &mut rng).unwrap();
            let after = sorted(opt.population());
            assert!(
                after.iter().zip(&before).all(|(a, b)| a <= b),
                "{params:?}, generation {g}: {before:?} -> {after:?}"
            );
            before = after;
        }
    }
    // The thesis's generational GA loses ranks below the best at some generation.
    let mut opt = ga::Ga::new(ga::GaParams::thesis(), 40);
    opt.start(&mut problem, &start).unwrap();
    let mut before = sorted(opt.population());
    let mut worsened = false;
    for _ in 0..40 {
        opt.step(&mut problem, &mut rng).unwrap();
        let after = sorted(opt.population());
        assert!(after[0] <= before[0]);
        worsened |= after.iter().zip(&before).any(|(a, b)| a > b);
        before = after;
    }
    assert!(worsened);
}

#[test]
fn gwo_pack_closes_on_its_leaders_in_the_last_generation() {
    // With the paper's schedule `a` reaches 0 in generation T, so every wolf moves to the mean
    // of the three leaders: the whole pack ends on one point.
    let mut problem = TestFunction::shifted(Function::Rastrigin, 5, 1.7).unwrap();
    let start = Population::uniform(&problem, 10, &mut seeded(2)).unwrap();
    let mut opt = Method::Gwo.build_preset(Preset::Standard, 10, 20);
    let rules = StopRules {
        max_generations: 20,
        patience: None,
        max_evaluations: None,
    };
    run(&mut opt, &mut problem, &start, &rules, &mut seeded(3)).unwrap();
    let pack = opt.population();
    for i in 1..pack.len() {
        assert_eq!(pack.genome(i), pack.genome(0), "wolf {i}");
    }
    // It is still spread one generation before the end of its horizon, and at the end with
    // the earlier schedule (`a = 2 / T` in the last generation).
    for opt in [
        Method::Gwo.build_preset(Preset::Standard, 10, 21),
        Method::Gwo.build(10, 20),
    ] {
        let mut opt = opt;
        run(&mut opt, &mut problem, &start, &rules, &mut seeded(3)).unwrap();
        let pack = opt.population();
        assert!((1..pack.len()).any(|i| pack.genome(i) != pack.genome(0)));
    }
}

fn run_optimizer(
    opt: &mut AnyOptimizer,
    problem: &mut Counting<TestFunction>,
    start: &Population,
    rng: &mut crate::random::ProjectRng,
) -> RunSummary {
    let s = run(opt, problem, start, &long_run(), rng).unwrap();
    assert_eq!(s.reason, StopReason::MaxGenerations);
    assert_eq!(s.generations, 100);
    s
}

#[test]
fn same_seed_same_run() {
    for method in Method::ALL.into_iter().chain([Method::Random]) {
        let mut results = [(0u32, 0u32); 2];
        for r in &mut results {
            let mut problem = TestFunction::new(Function::Rastrigin, 6).unwrap();
            let start = Population::uniform(&problem, 12, &mut seeded(3)).unwrap();
            let mut opt = method.build(12, 40);
            let rules = StopRules {
                max_generations: 40,
                patience: None,
                max_evaluations: None,
            };
            let s = run(&mut opt, &mut problem, &start, &rules, &mut seeded(9)).unwrap();
            *r = (s.best_fitness.to_bits(), s.evaluations);
        }
        assert_eq!(results[0], results[1], "{method}");
    }
}

#[test]
fn cmaes_converges_on_sphere() {
    // 10 genes, lambda 20, 150 generations (3020 evaluations).
    for r in 0..10u64 {
        let mut problem = TestFunction::new(Function::Sphere, 10).unwrap();
        let start = initial(&problem, r);
        let mut opt = Method::CmaEs.build(20, 150);
        let rules = StopRules {
            max_generations: 150,
            patience: None,
            max_evaluations: None,
        };
        let s = run(&mut opt, &mut problem, &start, &rules, &mut seeded(r)).unwrap();
        assert!(s.best_fitness < 1e-6, "run {r}: {}", s.best_fitness);
    }
}

#[test]
fn cmaes_converges_on_sphere_in_two_dimensions() {
    // Mostly padding: 2 of 16 genes used.
    let mut problem = TestFunction::new(Function::Sphere, 2).unwrap();
    let start = Population::uniform(&problem, 6, &mut seeded(4)).unwrap();
    let mut opt = Method::CmaEs.build(6, 150);
    let rules = StopRules {
        max_generations: 150,
        patience: None,
        max_evaluations: None,
    };
    let s = run(&mut opt, &mut problem, &start, &rules, &mut seeded(4)).unwrap();
    assert!(s.best_fitness < 1e-6, "{}", s.best_fitness);
}

/// A problem whose fitness never changes.
struct Flat;
impl Problem for Flat {
    fn dim(&self) -> usize {
        3
    }
    fn bounds(&self, _: usize) -> (f32, f32) {
        (0.0, 1.0)
    }
    fn evaluate(&mut self, _: &[f32]) -> f32 {
        1.0
    }
}

#[test]
fn stop_rules_apply() {
    let start = Population::uniform(&Flat, 5, &mut seeded(1)).unwrap();
    for method in Method::ALL {
        let mut opt = method.build(5, 30);
        let s = run(
            &mut opt,
            &mut Flat,
            &start,
            &StopRules::default(),
            &mut seeded(2),
        )
        .unwrap();
        assert_eq!(
            (s.reason, s.generations),
            (StopReason::NoImprovement, 10),
            "{method}"
        );
        let rules = StopRules {
            max_generations: 30,
            patience: None,
            max_evaluations: Some(40),
        };
        let s = run(&mut opt, &mut Flat, &start, &rules, &mut seeded(2)).unwrap();
        assert_eq!(s.reason, StopReason::MaxEvaluations, "{method}");
        assert!(s.evaluations >= 40 && s.generations < 30, "{method}");
        let mut sphere = TestFunction::new(Function::Sphere, 3).unwrap();
        let start3 = Population::uniform(&sphere, 5, &mut seeded(1)).unwrap();
        let rules = StopRules {
            max_generations: 7,
            patience: None,
            max_evaluations: None,
        };
        let s = run(&mut opt, &mut sphere, &start3, &rules, &mut seeded(2)).unwrap();
        assert_eq!(
            (s.reason, s.generations, opt.history().len()),
            (StopReason::MaxGenerations, 7, 8)
        );
    }
}

#[test]
fn known_fitnesses_are_not_evaluated_again() {
    let mut problem = Counting::new(TestFunction::new(Function::Sphere, 4).unwrap());
    let mut start = Population::new(4).unwrap();
    let mut rng = seeded(5);
    for i in 0..8 {
        let g: [f32; 4] = core::array::from_fn(|_| crate::random::range_f32(&mut rng, -5.0, 5.0));
        if i % 2 == 0 {
            start
                .push_with_fitness(&g, Function::Sphere.value(&g))
                .unwrap();
        } else {
            start.push(&g).unwrap();
        }
    }
    for method in Method::ALL {
        problem.count = 0;
        let mut opt = method.build(8, 30);
        opt.start(&mut problem, &start).unwrap();
        assert_eq!((opt.evaluations(), problem.count), (4, 4), "{method}");
    }
}

#[test]
fn evaluations_per_generation_match_each_method() {
    let mut problem = TestFunction::new(Function::Sphere, 5).unwrap();
    let start = Population::uniform(&problem, 10, &mut seeded(6)).unwrap();
    let mut rng = seeded(7);
    let mut per_gen = |opt: &mut AnyOptimizer| {
        opt.start(&mut problem, &start).unwrap();
        let before = opt.evaluations();
        opt.step(&mut problem, &mut rng).unwrap();
        opt.evaluations() - before
    };
    // xBOA: two children per crossover, one point per local step.
    let mut x = AnyOptimizer::Xboa(xboa::Xboa::new(
        xboa::XboaParams {
            p_c: 1.0,
            ..Default::default()
        },
        30,
    ));
    assert_eq!(per_gen(&mut x), 20);
    let mut x = AnyOptimizer::Xboa(xboa::Xboa::new(
        xboa::XboaParams {
            p_c: 0.0,
            ..Default::default()
        },
        30,
    ));
    assert_eq!(per_gen(&mut x), 10);
    // GA: a child that is neither crossed nor mutated is not re-evaluated.
    let p = ga::GaParams {
        crossover: 0.0,
        mutation: 0.0,
        ..Default::default()
    };
    assert_eq!(per_gen(&mut AnyOptimizer::Ga(ga::Ga::new(p, 30))), 0);
    // ABC: employed + onlookers (+ a scout, none in the first cycle).
    assert_eq!(per_gen(&mut Method::Abc.build(10, 30)), 20);
    for m in [
        Method::Boa,
        Method::Aboa,
        Method::Saboa,
        Method::Pso,
        Method::Gwo,
        Method::CmaEs,
        Method::Random,
    ] {
        assert_eq!(per_gen(&mut m.build(10, 30)), 10, "{m}");
    }
    let e = per_gen(&mut Method::Mboa.build(10, 30));
    assert!(e == 10 || e == 11, "mboa {e}");
}

#[test]
fn xboa_keeps_population_size_and_never_worsens_a_butterfly() {
    let mut problem = TestFunction::new(Function::Rastrigin, 8).unwrap();
    let start = Population::uniform(&problem, 5, &mut seeded(8)).unwrap();
    let mut opt = Method::Xboa.build(5, 30);
    opt.start(&mut problem, &start).unwrap();
    let mut rng = seeded(8);
    for _ in 0..30 {
        let before: [f32; 5] = core::array::from_fn(|i| opt.population().fitness(i).unwrap());
        opt.step(&mut problem, &mut rng).unwrap();
        assert_eq!(opt.population().len(), 5);
        for (i, b) in before.iter().enumerate() {
            assert!(opt.population().fitness(i).unwrap() <= *b);
        }
    }
}

#[test]
fn errors_are_reported_not_panicked() {
    let mut problem = TestFunction::new(Function::Sphere, 4).unwrap();
    let mut opt = Method::Xboa.build(5, 30);
    let mut rng = seeded(1);
    assert_eq!(
        opt.step(&mut problem, &mut rng),
        Err(OptimError::NotStarted)
    );
    let mut small = Population::new(4).unwrap();
    small.push(&[0.0; 4]).unwrap();
    assert_eq!(
        opt.start(&mut problem, &small),
        Err(OptimError::PopulationTooSmall { len: 1 })
    );
    let other = Population::uniform(
        &TestFunction::new(Function::Sphere, 3).unwrap(),
        5,
        &mut rng,
    )
    .unwrap();
    assert_eq!(
        opt.start(&mut problem, &other),
        Err(OptimError::DimensionMismatch {
            problem: 4,
            expected: 3
        })
    );
    assert_eq!(
        small.push(&[0.0; 3]),
        Err(OptimError::GenomeLength {
            got: 3,
            expected: 4
        })
    );
    let mut full = Population::new(2).unwrap();
    for _ in 0..MAX_POP {
        full.push(&[0.0; 2]).unwrap();
    }
    assert_eq!(full.push(&[0.0; 2]), Err(OptimError::PopulationFull));
    assert_eq!(
        Population::new(17).err(),
        Some(OptimError::BadDimension { dim: 17 })
    );
    // History capacity: MAX_HISTORY - 1 generations, then an error.
    let start = Population::uniform(&problem, 3, &mut rng).unwrap();
    let mut opt = Method::Random.build(3, 30);
    let rules = StopRules {
        max_generations: 5000,
        patience: None,
        max_evaluations: None,
    };
    assert_eq!(
        run(&mut opt, &mut problem, &start, &rules, &mut rng),
        Err(OptimError::HistoryFull)
    );
    assert_eq!(opt.generation() as usize, MAX_HISTORY - 1);
}

#[test]
fn population_from_flat_genes() {
    let genes = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    let p = Population::from_flat(2, &genes, Some(&[1.0, 0.5, 2.0])).unwrap();
    assert_eq!(
        (p.len(), p.genome(1), p.fitness(1), p.best()),
        (3, &[2.0, 3.0][..], Some(0.5), Some((1, 0.5)))
    );
    let p = Population::from_flat(3, &genes, None).unwrap();
    assert_eq!((p.len(), p.fitness(0)), (2, None));
    assert_eq!(
        Population::from_flat(2, &genes, Some(&[1.0])).err(),
        Some(OptimError::FitnessCount {
            got: 1,
            expected: 3
        })
    );
    assert!(Population::from_flat(4, &genes, None).is_err());
}

#[test]
fn every_method_runs_at_the_capacity_edges() {
    for method in Method::ALL.into_iter().chain([Method::Random]) {
        for (pop, dim) in [
            (MIN_POP, 1),
            (MIN_POP, 2),
            (3, 2),
            (5, 16),
            (MAX_POP, MAX_DIM),
        ] {
            let mut problem = Counting::new(TestFunction::new(Function::Ackley, dim).unwrap());
            let start = Population::uniform(&problem.inner, pop, &mut seeded(pop as u64)).unwrap();
            let mut opt = method.build(pop, 30);
            let rules = StopRules {
                max_generations: 30,
                patience: None,
                max_evaluations: None,
            };
            let s = run(&mut opt, &mut problem, &start, &rules, &mut seeded(1)).unwrap();
            let ctx = format!("{method}, pop {pop}, dim {dim}");
            assert!(
                s.best_fitness <= opt.history()[0] && s.best_fitness.is_finite(),
                "{ctx}"
            );
            assert_eq!(
                (problem.count, opt.population().len()),
                (opt.evaluations(), pop),
                "{ctx}"
            );
            assert!(!problem.out_of_bounds, "{ctx}");
        }
    }
}

#[test]
fn presets_round_trip_and_build_is_the_thesis_preset() {
    for p in Preset::ALL {
        assert_eq!(p.name().parse::<Preset>(), Ok(p));
    }
    assert_eq!("pygmo".parse::<Preset>(), Err(UnknownPreset));
    assert_eq!(Preset::default(), Preset::Thesis);
    for m in Method::ALL.into_iter().chain([Method::Random]) {
        for p in Preset::ALL {
            assert_eq!(m.build_preset(p, 5, 30).method(), m);
        }
        let a = run_once(m.build(8, 15));
        let b = run_once(m.build_preset(Preset::Thesis, 8, 15));
        assert_eq!(a, b, "{m}");
        let c = run_once(m.build_preset(Preset::Standard, 8, 15));
        assert_eq!(
            a == c,
            !matches!(m, Method::Ga | Method::Pso | Method::Gwo | Method::Abc),
            "{m}"
        );
    }
}

/// Best fitness and evaluations of one seeded 15-generation run on the 4-gene Rastrigin.
fn run_once(mut opt: AnyOptimizer) -> (u32, u32) {
    let mut problem = TestFunction::new(Function::Rastrigin, 4).unwrap();
    let start = Population::uniform(&problem, 8, &mut seeded(1)).unwrap();
    let rules = StopRules {
        max_generations: 15,
        patience: None,
        max_evaluations: None,
    };
    let s = run(&mut opt, &mut problem, &start, &rules, &mut seeded(2)).unwrap();
    (s.best_fitness.to_bits(), s.evaluations)
}

#[test]
fn method_names_round_trip() {
    for m in Method::ALL.into_iter().chain([Method::Random]) {
        assert_eq!(m.name().parse::<Method>(), Ok(m));
        assert_eq!(m.build(5, 30).method(), m);
    }
    assert_eq!("XBOA".parse::<Method>(), Err(UnknownMethod));
}

#[test]
fn defaults_follow_the_thesis_tuning() {
    let p20 = xboa::XboaParams::for_population(20);
    assert_eq!((p20.a, p20.c, p20.p_c), (0.905, 0.257, 0.593));
    let p5 = xboa::XboaParams::for_population(5);
    assert_eq!((p5.a, p5.c, p5.p_c), (0.994, 0.518, 0.583));
    assert_eq!(xboa::XboaParams::for_population(3), p5);
    assert_eq!(xboa::XboaParams::for_population(32), p20);
    assert_eq!(ga::GaParams::default(), ga::GaParams::thesis());
    let g = ga::GaParams::thesis();
    assert_eq!((g.crossover, g.mutation, g.eta_m), (0.11, 0.215, 76.026));
    assert_eq!(pso::PsoParams::default(), pso::PsoParams::thesis());
    let p = pso::PsoParams::thesis();
    assert_eq!(
        (
            p.neighbours,
            p.inertia,
            p.cognitive,
            p.social,
            p.vmax_fraction
        ),
        (4, 0.449, 3.379, 1.506, 0.329)
    );
    let b = boa::BoaParams::for_population(20);
    assert_eq!((b.a, b.c, b.p), (0.547, 0.602, 0.395));
    let mid = boa::BoaParams::for_population(10);
    assert!(mid.a < 0.73 && mid.a > 0.547);
}

#[test]
fn fragrance_intensity_is_capped_at_one() {
    // On the exploration objective's scale, the fragrance is the paper's `c |F|^a`.
    assert!((fragrance(0.5, -0.25, 1.0) - 0.125).abs() < 1e-7);
    assert!((fragrance(0.6, 0.0, 0.5)).abs() < 1e-7);
    // A fitness in the hundreds no longer gives a step hundreds of box widths long.
    assert_eq!(fragrance(0.5, 300.0, 0.9), 0.5);
    assert_eq!(fragrance(0.5, f32::INFINITY, 0.9), 0.5);
    assert_eq!(fragrance(0.5, f32::NAN, 0.9), 0.5);
}

/// A tuning replaces its own method's parameters and no other's: the tuned run differs from
/// the Table 4.1 run on the same start and seed, and a tuning of another method leaves the
/// run exactly as Table 4.1's.
#[test]
fn a_tuning_applies_to_its_own_method_only() {
    let mut problem = TestFunction::new(Function::Rastrigin, 4).unwrap();
    let start = initial(&problem, 0);
    let rules = StopRules {
        max_generations: 20,
        patience: None,
        max_evaluations: None,
    };
    let history = |opt: &mut AnyOptimizer, problem: &mut TestFunction| {
        run(opt, problem, &start, &rules, &mut seeded(7)).unwrap();
        opt.history().to_vec()
    };
    let tuned = Tuning::Xboa(xboa::XboaParams {
        a: 0.3,
        c: 0.9,
        p_c: 0.1,
    });
    let mut table = Method::Xboa.build(20, 20);
    let mut with_own = Method::Xboa.build_tuned(Preset::Thesis, Some(tuned), 20, 20);
    let mut with_other = Method::Boa.build_tuned(Preset::Thesis, Some(tuned), 20, 20);
    let mut boa = Method::Boa.build(20, 20);
    assert_eq!(with_own.method(), Method::Xboa);
    assert_eq!(with_other.method(), Method::Boa);
    assert_eq!(tuned.method(), Method::Xboa);
    assert_ne!(
        history(&mut with_own, &mut problem),
        history(&mut table, &mut problem)
    );
    assert_eq!(
        history(&mut with_other, &mut problem),
        history(&mut boa, &mut problem)
    );
}
