//! Population-based optimizers: xBOA and the nine methods the thesis compares it with.
//!
//! The engine minimises a [`Problem`] (box-bounded, `f32` genes) from a **given** initial
//! [`Population`], one generation per [`Optimizer::step`], without allocating. Every fitness
//! evaluation goes through one counted path, so [`Optimizer::evaluations`] is exact; a method
//! never re-evaluates a point whose fitness it already knows (for instance an unchanged GA child).
//! The exploration layer maximises a gain: it negates the gain in its [`Problem`].
//!
//! Capacities are fixed: [`MAX_POP`] individuals of at most [`MAX_DIM`] genes, and a best-fitness
//! history of [`MAX_HISTORY`] entries (the initial best plus one per generation, so at most
//! `MAX_HISTORY - 1` generations; one more [`Optimizer::step`] returns
//! [`OptimError::HistoryFull`]).
//!
//! A fitness that is NaN is treated as `+inf` (the worst possible value).
//!
//! Typical use, with any method chosen at run time:
//!
//! ```
//! use papillon::optim::{self, functions::{Function, TestFunction}, Method, Optimizer, Population, StopRules};
//! use papillon::random::seeded;
//!
//! let mut problem = TestFunction::new(Function::Sphere, 4).unwrap();
//! let mut rng = seeded(7);
//! let initial = Population::uniform(&problem, 10, &mut rng).unwrap();
//! let rules = StopRules::default(); // 30 generations, stop after 10 without improvement
//! let mut opt = "xboa".parse::<Method>().unwrap().build(initial.len(), rules.max_generations);
//! let summary = optim::run(&mut opt, &mut problem, &initial, &rules, &mut rng).unwrap();
//! assert!(summary.best_fitness <= opt.history()[0]);
//! assert_eq!(opt.best_genome().len(), 4);
//! ```

// Numerical kernels index several parallel arrays (genes, bounds, velocities) by gene number.
#![allow(clippy::needless_range_loop)]

use core::fmt;

use rand_core::Rng;

use crate::random;

pub mod abc;
pub mod aboa;
pub mod boa;
pub mod cmaes;
pub mod functions;
pub mod ga;
pub mod gwo;
pub mod mboa;
mod method;
pub mod pso;
pub mod random_search;
pub mod saboa;
pub mod xboa;

pub use method::{AnyOptimizer, Method, Preset, Tuning, UnknownMethod, UnknownPreset};

/// Largest population any method holds.
pub const MAX_POP: usize = 64;
/// Largest number of genes in a genome.
pub const MAX_DIM: usize = 16;
/// Capacity of the best-fitness history (initial best + one entry per generation).
pub const MAX_HISTORY: usize = 1000;
/// Smallest population a method accepts.
pub const MIN_POP: usize = 2;

/// A genome at full capacity; only the first [`Problem::dim`] genes are used.
pub type Genome = [f32; MAX_DIM];

/// A box-bounded minimisation problem.
pub trait Problem {
    /// Number of genes, 1 to [`MAX_DIM`].
    fn dim(&self) -> usize;
    /// `(lower, upper)` bound of gene `gene` (`lower < upper`).
    fn bounds(&self, gene: usize) -> (f32, f32);
    /// Fitness of `genes` (length [`Problem::dim`]); smaller is better.
    fn evaluate(&mut self, genes: &[f32]) -> f32;
}

impl<P: Problem + ?Sized> Problem for &mut P {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn bounds(&self, gene: usize) -> (f32, f32) {
        (**self).bounds(gene)
    }
    fn evaluate(&mut self, genes: &[f32]) -> f32 {
        (**self).evaluate(genes)
    }
}

/// A [`Problem`] wrapper that counts its evaluations (to audit an optimizer's own count).
#[derive(Debug, Clone)]
pub struct Counting<P> {
    /// The wrapped problem.
    pub inner: P,
    /// Evaluations seen so far.
    pub count: u32,
    /// `true` once a genome outside the bounds was evaluated.
    pub out_of_bounds: bool,
}

impl<P: Problem> Counting<P> {
    /// Wraps `inner` with a zero count.
    pub fn new(inner: P) -> Self {
        Self {
            inner,
            count: 0,
            out_of_bounds: false,
        }
    }
}

impl<P: Problem> Problem for Counting<P> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn bounds(&self, gene: usize) -> (f32, f32) {
        self.inner.bounds(gene)
    }
    fn evaluate(&mut self, genes: &[f32]) -> f32 {
        self.count += 1;
        for (i, &g) in genes.iter().enumerate() {
            let (lo, hi) = self.inner.bounds(i);
            if !(lo..=hi).contains(&g) {
                self.out_of_bounds = true;
            }
        }
        self.inner.evaluate(genes)
    }
}

/// What went wrong when building a population or running an optimizer.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum OptimError {
    /// The problem's dimension is 0 or above [`MAX_DIM`].
    BadDimension {
        /// Dimension seen.
        dim: usize,
    },
    /// A population would hold more than [`MAX_POP`] individuals.
    PopulationFull,
    /// The initial population holds fewer than [`MIN_POP`] individuals.
    PopulationTooSmall {
        /// Size seen.
        len: usize,
    },
    /// A genome's length differs from the population's dimension.
    GenomeLength {
        /// Length seen.
        got: usize,
        /// Dimension expected.
        expected: usize,
    },
    /// The number of fitnesses differs from the number of genomes.
    FitnessCount {
        /// Fitnesses given.
        got: usize,
        /// Genomes given.
        expected: usize,
    },
    /// The problem's dimension differs from the population's or the running optimizer's.
    DimensionMismatch {
        /// Problem dimension.
        problem: usize,
        /// Population/optimizer dimension.
        expected: usize,
    },
    /// A bound pair is not finite or not ordered `lower < upper`.
    BadBounds {
        /// Gene index.
        gene: usize,
        /// Lower bound seen.
        lower: f32,
        /// Upper bound seen.
        upper: f32,
    },
    /// [`Optimizer::step`] was called before [`Optimizer::start`].
    NotStarted,
    /// The best-fitness history is full ([`MAX_HISTORY`] entries).
    HistoryFull,
    /// A test function's optimum would be moved onto or outside its bounds.
    ShiftOutOfBounds {
        /// Shift asked for.
        shift: f32,
        /// Lower bound of every gene.
        lower: f32,
        /// Upper bound of every gene.
        upper: f32,
    },
}

impl fmt::Display for OptimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::BadDimension { dim } => {
                write!(f, "problem dimension {dim} is outside 1..={MAX_DIM}")
            }
            Self::PopulationFull => write!(f, "population would exceed {MAX_POP} individuals"),
            Self::PopulationTooSmall { len } => {
                write!(f, "population of {len} is below the minimum of {MIN_POP}")
            }
            Self::GenomeLength { got, expected } => {
                write!(f, "genome has {got} genes, expected {expected}")
            }
            Self::FitnessCount { got, expected } => {
                write!(f, "{got} fitnesses given for {expected} genomes")
            }
            Self::DimensionMismatch { problem, expected } => {
                write!(f, "problem has {problem} genes, expected {expected}")
            }
            Self::BadBounds { gene, lower, upper } => {
                write!(
                    f,
                    "gene {gene} has bounds [{lower}, {upper}], expected finite lower < upper"
                )
            }
            Self::NotStarted => write!(f, "optimizer stepped before start"),
            Self::HistoryFull => {
                write!(
                    f,
                    "history full: at most {} generations per run",
                    MAX_HISTORY - 1
                )
            }
            Self::ShiftOutOfBounds {
                shift,
                lower,
                upper,
            } => write!(
                f,
                "shift {shift} is outside the open interval ({lower}, {upper}) of the bounds"
            ),
        }
    }
}

impl core::error::Error for OptimError {}

/// Checks a problem's dimension and bounds.
pub(crate) fn check_problem<P: Problem + ?Sized>(problem: &P) -> Result<usize, OptimError> {
    let dim = problem.dim();
    if dim == 0 || dim > MAX_DIM {
        return Err(OptimError::BadDimension { dim });
    }
    for gene in 0..dim {
        let (lower, upper) = problem.bounds(gene);
        if !(lower.is_finite() && upper.is_finite() && lower < upper) {
            return Err(OptimError::BadBounds { gene, lower, upper });
        }
    }
    Ok(dim)
}

/// A fixed-capacity set of genomes with their fitnesses (NaN while unknown).
#[derive(Debug, Clone)]
pub struct Population {
    pub(crate) dim: usize,
    pub(crate) len: usize,
    pub(crate) genes: [Genome; MAX_POP],
    pub(crate) fitness: [f32; MAX_POP],
}

impl Population {
    /// An empty population of `dim`-gene genomes.
    pub fn new(dim: usize) -> Result<Self, OptimError> {
        if dim == 0 || dim > MAX_DIM {
            return Err(OptimError::BadDimension { dim });
        }
        Ok(Self {
            dim,
            len: 0,
            genes: [[0.0; MAX_DIM]; MAX_POP],
            fitness: [f32::NAN; MAX_POP],
        })
    }

    /// `size` genomes drawn uniformly in the problem's bounds (fitness unknown).
    pub fn uniform<P: Problem + ?Sized, R: Rng>(
        problem: &P,
        size: usize,
        rng: &mut R,
    ) -> Result<Self, OptimError> {
        let dim = check_problem(problem)?;
        let mut pop = Self::new(dim)?;
        let mut g = [0.0; MAX_DIM];
        for _ in 0..size {
            for (i, x) in g[..dim].iter_mut().enumerate() {
                let (lo, hi) = problem.bounds(i);
                *x = random::range_f32(rng, lo, hi);
            }
            pop.push(&g[..dim])?;
        }
        Ok(pop)
    }

    /// A population from `genes`, `dim` genes per individual back to back, with their known
    /// fitnesses if `fitness` is given (one per individual).
    pub fn from_flat(
        dim: usize,
        genes: &[f32],
        fitness: Option<&[f32]>,
    ) -> Result<Self, OptimError> {
        let mut pop = Self::new(dim)?;
        if !genes.len().is_multiple_of(dim) {
            return Err(OptimError::GenomeLength {
                got: genes.len() % dim,
                expected: dim,
            });
        }
        let n = genes.len() / dim;
        if let Some(f) = fitness
            && f.len() != n
        {
            return Err(OptimError::FitnessCount {
                got: f.len(),
                expected: n,
            });
        }
        for (i, g) in genes.chunks_exact(dim).enumerate() {
            pop.push_with_fitness(g, fitness.map_or(f32::NAN, |f| f[i]))?;
        }
        Ok(pop)
    }

    /// Appends a genome whose fitness is not known yet ([`Optimizer::start`] evaluates it).
    pub fn push(&mut self, genome: &[f32]) -> Result<(), OptimError> {
        self.push_with_fitness(genome, f32::NAN)
    }

    /// Appends a genome with its known fitness (not re-evaluated by [`Optimizer::start`]).
    pub fn push_with_fitness(&mut self, genome: &[f32], fitness: f32) -> Result<(), OptimError> {
        if genome.len() != self.dim {
            return Err(OptimError::GenomeLength {
                got: genome.len(),
                expected: self.dim,
            });
        }
        if self.len == MAX_POP {
            return Err(OptimError::PopulationFull);
        }
        self.genes[self.len][..self.dim].copy_from_slice(genome);
        self.fitness[self.len] = fitness;
        self.len += 1;
        Ok(())
    }

    /// Number of individuals.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Genes per genome.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Genes of individual `i` (panics if `i >= len`, like slice indexing).
    pub fn genome(&self, i: usize) -> &[f32] {
        &self.genes[..self.len][i][..self.dim]
    }

    /// Fitness of individual `i`, `None` if unknown.
    pub fn fitness(&self, i: usize) -> Option<f32> {
        let f = self.fitness[..self.len][i];
        if f.is_nan() { None } else { Some(f) }
    }

    /// Index and fitness of the best individual with a known fitness.
    pub fn best(&self) -> Option<(usize, f32)> {
        let mut best: Option<(usize, f32)> = None;
        for (i, &f) in self.fitness[..self.len].iter().enumerate() {
            if !f.is_nan() && best.is_none_or(|(_, b)| f < b) {
                best = Some((i, f));
            }
        }
        best
    }

    /// Index of the worst individual (largest fitness).
    pub(crate) fn worst(&self) -> usize {
        let mut w = 0;
        for i in 1..self.len {
            if self.fitness[i] > self.fitness[w] {
                w = i;
            }
        }
        w
    }
}

/// A population-based minimiser driven one generation at a time.
pub trait Optimizer {
    /// Starts a run from `initial` (copied). Individuals without a fitness are evaluated
    /// (counted); the others keep theirs. Resets the evaluation count, the generation count
    /// and the history, whose first entry becomes the initial best fitness.
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError>;

    /// Runs one generation on the same problem as [`Optimizer::start`].
    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError>;

    /// Best genome evaluated so far.
    fn best_genome(&self) -> &[f32];
    /// Fitness of [`Optimizer::best_genome`].
    fn best_fitness(&self) -> f32;
    /// Fitness evaluations since [`Optimizer::start`] (including the initial ones).
    fn evaluations(&self) -> u32;
    /// Generations run since [`Optimizer::start`].
    fn generation(&self) -> u32;
    /// Best fitness so far: entry 0 after start, entry `g` after generation `g`.
    fn history(&self) -> &[f32];
    /// The current population (for PSO the particles' current positions, for CMA-ES the last
    /// sampled generation).
    fn population(&self) -> &Population;
}

/// State every method shares: bounds, population, best, counters and history.
#[derive(Debug, Clone)]
pub(crate) struct Engine {
    pub dim: usize,
    pub lower: Genome,
    pub upper: Genome,
    pub pop: Population,
    pub best: Genome,
    pub best_fitness: f32,
    pub evaluations: u32,
    pub generation: u32,
    /// Horizon `T` of the schedules (the run's maximum generations), at least 1.
    pub horizon: u32,
    history: [f32; MAX_HISTORY],
    history_len: usize,
}

impl Engine {
    pub fn new(horizon: u32) -> Self {
        Self {
            dim: 0,
            lower: [0.0; MAX_DIM],
            upper: [0.0; MAX_DIM],
            pop: Population {
                dim: 0,
                len: 0,
                genes: [[0.0; MAX_DIM]; MAX_POP],
                fitness: [f32::NAN; MAX_POP],
            },
            best: [0.0; MAX_DIM],
            best_fitness: f32::INFINITY,
            evaluations: 0,
            generation: 0,
            horizon: horizon.max(1),
            history: [0.0; MAX_HISTORY],
            history_len: 0,
        }
    }

    /// Copies and evaluates the initial population.
    pub fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        let dim = check_problem(problem)?;
        if dim != initial.dim {
            return Err(OptimError::DimensionMismatch {
                problem: dim,
                expected: initial.dim,
            });
        }
        if initial.len < MIN_POP {
            return Err(OptimError::PopulationTooSmall { len: initial.len });
        }
        self.dim = dim;
        for gene in 0..dim {
            (self.lower[gene], self.upper[gene]) = problem.bounds(gene);
        }
        self.pop = initial.clone();
        self.best_fitness = f32::INFINITY;
        self.best = initial.genes[0];
        self.evaluations = 0;
        self.generation = 0;
        self.history_len = 0;
        for i in 0..self.pop.len {
            let f = self.pop.fitness[i];
            let f = if f.is_nan() {
                let g = self.pop.genes[i];
                self.evaluate(problem, &g)
            } else {
                f
            };
            self.pop.fitness[i] = f;
            if f < self.best_fitness || i == 0 {
                self.best_fitness = f;
                self.best = self.pop.genes[i];
            }
        }
        self.history[0] = self.best_fitness;
        self.history_len = 1;
        Ok(())
    }

    /// Evaluates `x` (counted), NaN becomes `+inf`, and keeps it if it is the best so far.
    pub fn evaluate<P: Problem + ?Sized>(&mut self, problem: &mut P, x: &Genome) -> f32 {
        self.evaluations += 1;
        let f = problem.evaluate(&x[..self.dim]);
        let f = if f.is_nan() { f32::INFINITY } else { f };
        if f < self.best_fitness {
            self.best_fitness = f;
            self.best = *x;
        }
        f
    }

    /// Clamps `x` to the bounds (a NaN gene goes to the lower bound).
    pub fn clamp(&self, x: &mut Genome) {
        for i in 0..self.dim {
            let v = x[i];
            x[i] = if v.is_nan() {
                self.lower[i]
            } else {
                v.max(self.lower[i]).min(self.upper[i])
            };
        }
    }

    /// Uniform genome in bounds.
    pub fn uniform<R: Rng>(&self, rng: &mut R) -> Genome {
        let mut g = [0.0; MAX_DIM];
        for i in 0..self.dim {
            g[i] = random::range_f32(rng, self.lower[i], self.upper[i]);
        }
        g
    }

    /// Checks a step may run on `problem`.
    pub fn begin_step<P: Problem + ?Sized>(&self, problem: &P) -> Result<(), OptimError> {
        if self.history_len == 0 {
            return Err(OptimError::NotStarted);
        }
        if problem.dim() != self.dim {
            return Err(OptimError::DimensionMismatch {
                problem: problem.dim(),
                expected: self.dim,
            });
        }
        if self.history_len >= MAX_HISTORY {
            return Err(OptimError::HistoryFull);
        }
        Ok(())
    }

    /// Closes a generation: counts it and records the best fitness.
    pub fn end_step(&mut self) {
        self.generation += 1;
        self.history[self.history_len] = self.best_fitness;
        self.history_len += 1;
    }

    /// Fraction `t / T` of the horizon elapsed at the start of the current generation.
    pub fn progress(&self) -> f32 {
        self.generation as f32 / self.horizon as f32
    }

    pub fn history(&self) -> &[f32] {
        &self.history[..self.history_len]
    }

    pub fn best_genome(&self) -> &[f32] {
        &self.best[..self.dim]
    }
}

/// Implements the [`Optimizer`] accessors from a field `engine: Engine`.
macro_rules! engine_accessors {
    () => {
        fn best_genome(&self) -> &[f32] {
            self.engine.best_genome()
        }
        fn best_fitness(&self) -> f32 {
            self.engine.best_fitness
        }
        fn evaluations(&self) -> u32 {
            self.engine.evaluations
        }
        fn generation(&self) -> u32 {
            self.engine.generation
        }
        fn history(&self) -> &[f32] {
            self.engine.history()
        }
        fn population(&self) -> &$crate::optim::Population {
            &self.engine.pop
        }
    };
}
pub(crate) use engine_accessors;

/// Fragrance of the butterfly optimizers, `c * I^a`, with the stimulus intensity
/// `I = min(|F|, 1)`.
///
/// Arora and Singh define the fragrance on the stimulus intensity and tune `c` and `a`
/// for intensities of order one; the thesis's objective is scaled to `[-1, 0]`, where
/// `I = |F|` exactly. On a problem whose fitness runs into the hundreds (Rastrigin,
/// Rosenbrock from a uniform start) the raw `|F|^a` gives steps hundreds of box widths
/// long, which all land on the bounds and are rejected, so the run stalls; with the cap a
/// step is at most `c` times the distance the method's equation names.
pub(crate) fn fragrance(c: f32, fitness: f32, a: f32) -> f32 {
    let s = crate::math::abs(fitness);
    // NaN (never stored: it counts as +inf) and +inf both mean "far from good".
    let s = if s.is_nan() { 1.0 } else { s.min(1.0) };
    c * crate::math::powf(s, a)
}

/// When a run stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StopRules {
    /// Maximum generations (default 30).
    pub max_generations: u32,
    /// Stop after this many generations without a strict improvement of the best fitness
    /// (default `Some(10)`; `None` disables).
    pub patience: Option<u32>,
    /// Stop once this many evaluations are used (checked between generations, so the last
    /// generation may overshoot by at most one generation's evaluations; default `None`).
    pub max_evaluations: Option<u32>,
}

impl Default for StopRules {
    fn default() -> Self {
        Self {
            max_generations: 30,
            patience: Some(10),
            max_evaluations: None,
        }
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// [`StopRules::max_generations`] reached.
    MaxGenerations,
    /// [`StopRules::patience`] generations without improvement.
    NoImprovement,
    /// [`StopRules::max_evaluations`] reached.
    MaxEvaluations,
}

/// Outcome of [`run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// Generations run.
    pub generations: u32,
    /// Evaluations used, initial ones included.
    pub evaluations: u32,
    /// Best fitness found.
    pub best_fitness: f32,
    /// Which rule stopped the run.
    pub reason: StopReason,
}

/// Starts `optimizer` from `initial` and steps it until a [`StopRules`] rule fires. The best
/// genome and the history stay readable on `optimizer` afterwards.
pub fn run<O: Optimizer + ?Sized, P: Problem + ?Sized, R: Rng>(
    optimizer: &mut O,
    problem: &mut P,
    initial: &Population,
    rules: &StopRules,
    rng: &mut R,
) -> Result<RunSummary, OptimError> {
    optimizer.start(problem, initial)?;
    let mut last_best = optimizer.best_fitness();
    let mut stale = 0u32;
    let reason = loop {
        if optimizer.generation() >= rules.max_generations {
            break StopReason::MaxGenerations;
        }
        if rules
            .max_evaluations
            .is_some_and(|m| optimizer.evaluations() >= m)
        {
            break StopReason::MaxEvaluations;
        }
        if rules.patience.is_some_and(|p| stale >= p) {
            break StopReason::NoImprovement;
        }
        optimizer.step(problem, rng)?;
        if optimizer.best_fitness() < last_best {
            last_best = optimizer.best_fitness();
            stale = 0;
        } else {
            stale += 1;
        }
    };
    Ok(RunSummary {
        generations: optimizer.generation(),
        evaluations: optimizer.evaluations(),
        best_fitness: optimizer.best_fitness(),
        reason,
    })
}

#[cfg(test)]
mod tests;
