//! GA: a real-coded genetic algorithm.
//!
//! Sources: D. E. Goldberg, "Genetic Algorithms in Search, Optimization and Machine Learning"
//! (1989) for tournament selection and elitism; K. Deb and R. B. Agrawal, "Simulated binary
//! crossover for continuous search space", Complex Systems 9 (1995); K. Deb and M. Goyal,
//! "A combined genetic adaptive search (GeneAS) for engineering design", Computer Science and
//! Informatics 26 (1996) for the bounded polynomial mutation.
//!
//! Each generation builds a full offspring population: two parents by binary tournaments (the
//! fitter of two uniformly drawn individuals), crossed ([`Crossover`]), then polynomial
//! mutation of each gene with the mutation probability (distribution index `eta_m`), children
//! clamped to the bounds. A child identical to its parent (neither crossed nor mutated) keeps
//! the parent's fitness and is not re-evaluated. The offspring then replace the parents
//! ([`Replacement`]).
//!
//! Two parameter sets:
//! - [`GaParams::thesis`] (the [`Default`]), the thesis's Table 4.1 tuning for the exploration
//!   problem: SBX with crossover probability 0.11, mutation probability 0.215 per gene,
//!   `eta_m = 76.026`, generational replacement with one elite. The thesis gives no crossover
//!   distribution index; we use Deb's customary `eta_c = 20`.
//! - [`GaParams::standard`], Deb's real-coded GA defaults (K. Deb, A. Pratap, S. Agarwal and
//!   T. Meyarivan, "A fast and elitist multiobjective genetic algorithm: NSGA-II", IEEE Trans.
//!   Evol. Comput. 6(2) (2002), section V): SBX with crossover probability 0.9 and
//!   `eta_c = 20`, polynomial mutation of `1 / n` genes on average (`n` genes) with
//!   `eta_m = 20`, tournament of 2, and plus replacement: the best `N` of parents and offspring
//!   survive (the `(mu + lambda)` selection of H.-P. Schwefel, "Numerical Optimization of
//!   Computer Models", Wiley (1981), also NSGA-II's elitism and pygmo's `sga` reinsertion).
//!   pygmo's `sga` differs in its crossover and mutation defaults: exponential crossover
//!   ([`Crossover::Exponential`], `CR = 0.9`), mutation probability 0.02 per gene with
//!   `eta_m = 1`; [`GaParams::pygmo`] is that set on this engine. On the 10-gene sphere the
//!   standard set ends about 10 times lower than either (`docs/optimizers.md`).

use rand_core::Rng;

use super::{
    Engine, Genome, MAX_DIM, MAX_POP, OptimError, Optimizer, Population, Problem, engine_accessors,
};
use crate::random;

/// `x^e` for `x >= 0` as `2^(e log2 x)`: libm's `log2f` and `exp2f` are table-driven and
/// several times faster than its general `powf`, which was most of a run's time; the result
/// differs from `powf` by a few units in the last place.
#[inline]
fn pow_pos(x: f32, e: f32) -> f32 {
    libm::exp2f(e * libm::log2f(x))
}

/// How two parents are crossed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Crossover {
    /// Simulated binary crossover (Deb & Agrawal 1995): with probability
    /// [`GaParams::crossover`] the pair is crossed, each gene then swapped-and-spread with
    /// probability 1/2 around the parents' mean (distribution index [`GaParams::eta_c`]).
    Sbx,
    /// Exponential crossover (Storn & Price 1997): from a uniformly drawn gene, a run of
    /// consecutive genes (wrapping around) is exchanged between the parents; the run goes on to
    /// the next gene with probability [`GaParams::crossover`] and holds at least one gene, at
    /// most all. Every pair is crossed.
    Exponential,
}

/// Who survives a generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Replacement {
    /// The offspring replace the parents, except that the best parent replaces the worst child
    /// when it is strictly better than the best child, so the best never gets worse.
    Generational,
    /// The best `N` of the `N` parents and `N` offspring survive (ties: parents first, then by
    /// index).
    Plus,
}

/// GA hyper-parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaParams {
    /// [`Crossover::Sbx`]: probability that a pair of parents is crossed;
    /// [`Crossover::Exponential`]: probability that the exchanged run goes on by one gene.
    pub crossover: f32,
    /// Per-gene mutation probability, or with [`GaParams::mutation_per_genome`] the expected
    /// number of mutated genes per child (per-gene probability `mutation / n`).
    pub mutation: f32,
    /// Whether [`GaParams::mutation`] counts genes per child rather than a per-gene
    /// probability.
    pub mutation_per_genome: bool,
    /// Polynomial-mutation distribution index.
    pub eta_m: f32,
    /// SBX distribution index.
    pub eta_c: f32,
    /// Crossover operator.
    pub crossover_kind: Crossover,
    /// Survivor selection.
    pub replacement: Replacement,
}

impl GaParams {
    /// The thesis's Table 4.1 tuning (see the module doc).
    pub fn thesis() -> Self {
        Self {
            crossover: 0.11,
            mutation: 0.215,
            mutation_per_genome: false,
            eta_m: 76.026,
            eta_c: 20.0,
            crossover_kind: Crossover::Sbx,
            replacement: Replacement::Generational,
        }
    }

    /// Deb's real-coded GA defaults with plus replacement (see the module doc).
    pub fn standard() -> Self {
        Self {
            crossover: 0.9,
            mutation: 1.0,
            mutation_per_genome: true,
            eta_m: 20.0,
            eta_c: 20.0,
            crossover_kind: Crossover::Sbx,
            replacement: Replacement::Plus,
        }
    }

    /// pygmo 2's `sga` defaults on this engine: exponential crossover `CR = 0.9`, mutation
    /// probability 0.02 per gene with `eta_m = 1`, tournament of 2, plus replacement.
    pub fn pygmo() -> Self {
        Self {
            crossover: 0.9,
            mutation: 0.02,
            mutation_per_genome: false,
            eta_m: 1.0,
            eta_c: 1.0,
            crossover_kind: Crossover::Exponential,
            replacement: Replacement::Plus,
        }
    }
}

impl Default for GaParams {
    /// [`GaParams::thesis`].
    fn default() -> Self {
        Self::thesis()
    }
}

/// GA state.
#[derive(Debug, Clone)]
pub struct Ga {
    params: GaParams,
    engine: Engine,
    children: [Genome; MAX_POP],
    child_fitness: [f32; MAX_POP],
    /// The survivors of plus replacement, built here before they replace the population
    /// (kept between steps so that no generation clears a new buffer).
    survivors: [Genome; MAX_POP],
}

/// Simulated binary crossover of `c1` and `c2` in place (see [`Crossover::Sbx`]).
fn sbx<R: Rng>(c1: &mut Genome, c2: &mut Genome, dim: usize, eta_c: f32, rng: &mut R) {
    let ex = 1.0 / (eta_c + 1.0);
    for d in 0..dim {
        if random::chance(rng, 0.5) {
            let u = random::unit_f32(rng);
            let beta = if u <= 0.5 {
                pow_pos(2.0 * u, ex)
            } else {
                pow_pos(1.0 / (2.0 * (1.0 - u)), ex)
            };
            let (p1, p2) = (c1[d], c2[d]);
            c1[d] = 0.5 * ((1.0 + beta) * p1 + (1.0 - beta) * p2);
            c2[d] = 0.5 * ((1.0 - beta) * p1 + (1.0 + beta) * p2);
        }
    }
}

/// Exponential crossover of `c1` and `c2` in place (see [`Crossover::Exponential`]).
fn exponential<R: Rng>(c1: &mut Genome, c2: &mut Genome, dim: usize, cr: f32, rng: &mut R) {
    let mut d = random::below(rng, dim);
    let mut run = 0;
    loop {
        core::mem::swap(&mut c1[d], &mut c2[d]);
        d = (d + 1) % dim;
        run += 1;
        if run == dim || !random::chance(rng, cr) {
            break;
        }
    }
}

impl Ga {
    /// A GA with `params` (`max_generations` is kept for symmetry with the other methods).
    pub fn new(params: GaParams, max_generations: u32) -> Self {
        Self {
            params,
            engine: Engine::new(max_generations),
            children: [[0.0; MAX_DIM]; MAX_POP],
            child_fitness: [f32::NAN; MAX_POP],
            survivors: [[0.0; MAX_DIM]; MAX_POP],
        }
    }
}

fn tournament<R: Rng>(e: &Engine, rng: &mut R) -> usize {
    let a = random::below(rng, e.pop.len);
    let b = random::below(rng, e.pop.len);
    if e.pop.fitness[b] < e.pop.fitness[a] {
        b
    } else {
        a
    }
}

/// Bounded polynomial mutation of one gene.
fn polynomial<R: Rng>(y: f32, lo: f32, hi: f32, eta: f32, rng: &mut R) -> f32 {
    let width = hi - lo;
    let d1 = (y - lo) / width;
    let d2 = (hi - y) / width;
    let r = random::unit_f32(rng);
    let pow = 1.0 / (eta + 1.0);
    let dq = if r < 0.5 {
        let v = 2.0 * r + (1.0 - 2.0 * r) * pow_pos(1.0 - d1, eta + 1.0);
        pow_pos(v, pow) - 1.0
    } else {
        let v = 2.0 * (1.0 - r) + 2.0 * (r - 0.5) * pow_pos(1.0 - d2, eta + 1.0);
        1.0 - pow_pos(v, pow)
    };
    y + dq * width
}

/// Sorts `v` by `cmp` (a total order), fast when `v` is nearly sorted.
fn insertion_sort(v: &mut [usize], cmp: impl Fn(usize, usize) -> core::cmp::Ordering) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && cmp(x, v[j - 1]) == core::cmp::Ordering::Less {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

impl Optimizer for Ga {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        self.engine.start(problem, initial)
    }

    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        self.engine.begin_step(problem)?;
        let e = &mut self.engine;
        let (n, dim) = (e.pop.len, e.dim);
        let mut k = 0;
        while k < n {
            let (i, j) = (tournament(e, rng), tournament(e, rng));
            let (mut c1, mut c2) = (e.pop.genes[i], e.pop.genes[j]);
            let crossed = match self.params.crossover_kind {
                Crossover::Sbx => {
                    let cross = random::chance(rng, self.params.crossover);
                    if cross {
                        sbx(&mut c1, &mut c2, dim, self.params.eta_c, rng);
                    }
                    cross
                }
                Crossover::Exponential => {
                    exponential(&mut c1, &mut c2, dim, self.params.crossover, rng);
                    true
                }
            };
            let mut changed = [crossed; 2];
            let p_m = if self.params.mutation_per_genome {
                self.params.mutation / dim as f32
            } else {
                self.params.mutation
            };
            for (c, ch) in [&mut c1, &mut c2].into_iter().zip(changed.iter_mut()) {
                for d in 0..dim {
                    if random::chance(rng, p_m) {
                        c[d] = polynomial(c[d], e.lower[d], e.upper[d], self.params.eta_m, rng);
                        *ch = true;
                    }
                }
                e.clamp(c);
            }
            for (slot, (c, ch, parent)) in [(c1, changed[0], i), (c2, changed[1], j)]
                .into_iter()
                .enumerate()
            {
                if k + slot >= n {
                    break;
                }
                let unchanged = !ch || c[..dim] == e.pop.genes[parent][..dim];
                self.child_fitness[k + slot] = if unchanged {
                    e.pop.fitness[parent]
                } else {
                    e.evaluate(problem, &c)
                };
                self.children[k + slot] = c;
            }
            k += 2;
        }
        match self.params.replacement {
            Replacement::Generational => {
                let (best_parent, best_parent_f) = e.pop.best().unwrap_or((0, e.pop.fitness[0]));
                let mut best_child = f32::INFINITY;
                let mut worst_child = 0;
                for c in 0..n {
                    best_child = best_child.min(self.child_fitness[c]);
                    if self.child_fitness[c] > self.child_fitness[worst_child] {
                        worst_child = c;
                    }
                }
                if best_parent_f < best_child {
                    self.children[worst_child] = e.pop.genes[best_parent];
                    self.child_fitness[worst_child] = best_parent_f;
                }
                e.pop.genes[..n].copy_from_slice(&self.children[..n]);
                e.pop.fitness[..n].copy_from_slice(&self.child_fitness[..n]);
            }
            Replacement::Plus => {
                // Candidates 0..n are the parents, n..2n the children.
                let fitness = |k: usize| {
                    if k < n {
                        e.pop.fitness[k]
                    } else {
                        self.child_fitness[k - n]
                    }
                };
                // Ordered by (fitness, candidate): parents and children sorted apart by
                // insertion (the parents come sorted from the previous generation), then
                // merged; the same order a full sort gives, in a fraction of the comparisons.
                let before = |a: usize, b: usize| fitness(a).total_cmp(&fitness(b)).then(a.cmp(&b));
                let mut parents = [0usize; MAX_POP];
                let mut kids = [0usize; MAX_POP];
                for k in 0..n {
                    parents[k] = k;
                    kids[k] = n + k;
                }
                insertion_sort(&mut parents[..n], before);
                insertion_sort(&mut kids[..n], before);
                let mut order = [0usize; MAX_POP];
                let (mut a, mut b) = (0, 0);
                for o in order[..n].iter_mut() {
                    let take_parent = b == n
                        || (a < n && before(parents[a], kids[b]) == core::cmp::Ordering::Less);
                    *o = if take_parent {
                        a += 1;
                        parents[a - 1]
                    } else {
                        b += 1;
                        kids[b - 1]
                    };
                }
                let genes = &mut self.survivors;
                let mut fit = [0.0; MAX_POP];
                for (slot, &k) in order[..n].iter().enumerate() {
                    genes[slot] = if k < n {
                        e.pop.genes[k]
                    } else {
                        self.children[k - n]
                    };
                    fit[slot] = fitness(k);
                }
                e.pop.genes[..n].copy_from_slice(&genes[..n]);
                e.pop.fitness[..n].copy_from_slice(&fit[..n]);
            }
        }
        e.end_step();
        Ok(())
    }

    engine_accessors!();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::seeded;

    fn parents() -> (Genome, Genome) {
        let mut p1 = [0.0; MAX_DIM];
        let mut p2 = [0.0; MAX_DIM];
        for d in 0..MAX_DIM {
            p1[d] = d as f32;
            p2[d] = -(d as f32) - 100.0;
        }
        (p1, p2)
    }

    /// Genes of `c1` taken from `p2` (the children swap genes position by position).
    fn swapped(c1: &Genome, c2: &Genome, p1: &Genome, p2: &Genome, dim: usize) -> [bool; MAX_DIM] {
        let mut s = [false; MAX_DIM];
        for d in 0..dim {
            assert!(
                (c1[d] == p1[d] && c2[d] == p2[d]) || (c1[d] == p2[d] && c2[d] == p1[d]),
                "gene {d}"
            );
            s[d] = c1[d] == p2[d];
        }
        s
    }

    #[test]
    fn exponential_crossover_swaps_one_circular_run() {
        let dim = 10;
        let (p1, p2) = parents();
        let mut rng = seeded(3);
        let mut lengths = [0u32; 11];
        for _ in 0..2000 {
            let (mut c1, mut c2) = (p1, p2);
            exponential(&mut c1, &mut c2, dim, 0.7, &mut rng);
            let s = swapped(&c1, &c2, &p1, &p2, dim);
            let len = s[..dim].iter().filter(|&&b| b).count();
            assert!(len >= 1);
            // One run on the ring: exactly one place where a swapped gene follows a kept one
            // (none when all are swapped).
            let starts = (0..dim)
                .filter(|&d| s[d] && !s[(d + dim - 1) % dim])
                .count();
            assert_eq!(starts, usize::from(len < dim), "{s:?}");
            assert_eq!(c1[dim..], p1[dim..]);
            lengths[len] += 1;
        }
        // Run length L: P(L >= k) = 0.7^(k-1); P(L = 1) = 0.3.
        let p1_share = lengths[1] as f32 / 2000.0;
        assert!((p1_share - 0.3).abs() < 0.04, "{lengths:?}");
        // CR = 0 swaps one gene, CR = 1 all of them.
        let (mut c1, mut c2) = (p1, p2);
        exponential(&mut c1, &mut c2, dim, 0.0, &mut rng);
        assert_eq!(
            swapped(&c1, &c2, &p1, &p2, dim)
                .iter()
                .filter(|&&b| b)
                .count(),
            1
        );
        let (mut c1, mut c2) = (p1, p2);
        exponential(&mut c1, &mut c2, dim, 1.0, &mut rng);
        assert_eq!(c1[..dim], p2[..dim]);
        assert_eq!(c2[..dim], p1[..dim]);
    }

    #[test]
    fn per_genome_mutation_rate_scales_with_the_genes() {
        // Crossover off: a child differs from its parent only by mutation; with one gene per
        // child on average, about 1/n of the genes change whatever n is.
        for dim in [4usize, 16] {
            let mut problem = crate::optim::functions::TestFunction::new(
                crate::optim::functions::Function::Sphere,
                dim,
            )
            .unwrap();
            let start = Population::uniform(&problem, 20, &mut seeded(1)).unwrap();
            let params = GaParams {
                crossover: 0.0,
                crossover_kind: Crossover::Sbx,
                ..GaParams::standard()
            };
            let mut changed = 0usize;
            let mut rng = seeded(2);
            for _ in 0..50 {
                let mut ga = Ga::new(params, 1);
                ga.start(&mut problem, &start).unwrap();
                let e = ga.evaluations();
                ga.step(&mut problem, &mut rng).unwrap();
                // Each evaluated child had at least one mutated gene.
                changed += (ga.evaluations() - e) as usize;
            }
            // P(child mutated) = 1 - (1 - 1/n)^n: 0.68 for n = 4, 0.64 for n = 16.
            let share = changed as f32 / (50.0 * 20.0);
            let expected = 1.0 - libm::powf(1.0 - 1.0 / dim as f32, dim as f32);
            assert!(
                (share - expected).abs() < 0.05,
                "n = {dim}: {share} vs {expected}"
            );
        }
    }
}
