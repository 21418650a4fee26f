//! Standard test functions for the optimizers, all minimised, each with its global minimum 0.
//!
//! Definitions and bounds follow M. Jamil and X.-S. Yang, "A literature survey of benchmark
//! functions for global optimization problems", Int. J. Mathematical Modelling and Numerical
//! Optimisation 4(2) (2013), and the Virtual Library of Simulation Experiments (Surjanovic &
//! Bingham):
//!
//! | function | bounds per gene | minimum at |
//! |---|---|---|
//! | sphere `sum x^2` | `[-5.12, 5.12]` | 0 |
//! | rastrigin `10 n + sum (x^2 - 10 cos 2 pi x)` | `[-5.12, 5.12]` | 0 |
//! | rosenbrock `sum 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2` | `[-5, 10]` | 1 |
//! | ackley (`a = 20, b = 0.2, c = 2 pi`) | `[-32.768, 32.768]` | 0 |
//! | griewank `1 + sum x^2 / 4000 - prod cos(x_i / sqrt i)` | `[-600, 600]` | 0 |
//!
//! The sums run in `f64` so that values near the optimum keep their precision.

use core::fmt;
use core::str::FromStr;

use super::{MAX_DIM, OptimError, Problem};

/// A standard test function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Function {
    /// Sum of squares.
    Sphere,
    /// Rastrigin's highly multimodal function.
    Rastrigin,
    /// Rosenbrock's valley.
    Rosenbrock,
    /// Ackley's function.
    Ackley,
    /// Griewank's function.
    Griewank,
}

impl Function {
    /// All functions.
    pub const ALL: [Function; 5] = [
        Function::Sphere,
        Function::Rastrigin,
        Function::Rosenbrock,
        Function::Ackley,
        Function::Griewank,
    ];

    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Function::Sphere => "sphere",
            Function::Rastrigin => "rastrigin",
            Function::Rosenbrock => "rosenbrock",
            Function::Ackley => "ackley",
            Function::Griewank => "griewank",
        }
    }

    /// `(lower, upper)` bound of every gene.
    pub fn bounds(self) -> (f32, f32) {
        match self {
            Function::Sphere | Function::Rastrigin => (-5.12, 5.12),
            Function::Rosenbrock => (-5.0, 10.0),
            Function::Ackley => (-32.768, 32.768),
            Function::Griewank => (-600.0, 600.0),
        }
    }

    /// The gene value of the optimum (every gene the same): 1 for Rosenbrock, 0 for the others.
    pub fn optimum(self) -> f32 {
        if self == Function::Rosenbrock {
            1.0
        } else {
            0.0
        }
    }

    /// Value at `x`.
    pub fn value(self, x: &[f32]) -> f32 {
        self.value_shifted(x, 0.0)
    }

    /// Value at `x` of the function moved by `offset` along every axis, `f(x - offset)`: its
    /// optimum lies at `x_i = optimum() + offset`. Computed in `f64`, so `x_i - offset` is
    /// exactly zero when both are the same `f32`.
    pub fn value_shifted(self, x: &[f32], offset: f32) -> f32 {
        use core::f64::consts::TAU;
        let n = x.len() as f64;
        let offset = offset as f64;
        let at = |i: usize| x[i] as f64 - offset;
        let it = (0..x.len()).map(at);
        let v = match self {
            Function::Sphere => it.map(|v| v * v).sum::<f64>(),
            // 10 (1 - cos 2 pi v) = 20 sin^2 (pi v): the same function without the cancellation
            // near the optimum, and without a library cosine per gene (`sin_pi`).
            // The terms first (a loop the compiler vectorises), then their sum in gene order.
            Function::Rastrigin => {
                let term = |v: f64| {
                    let s = sin_pi(v);
                    v * v + 20.0 * s * s
                };
                if x.len() <= MAX_DIM {
                    let mut terms = [0.0f64; MAX_DIM];
                    for (t, v) in terms.iter_mut().zip(it) {
                        *t = term(v);
                    }
                    terms[..x.len()].iter().sum::<f64>()
                } else {
                    it.map(term).sum::<f64>()
                }
            }
            Function::Rosenbrock => (1..x.len())
                .map(|i| {
                    let (a, b) = (at(i - 1), at(i));
                    100.0 * (b - a * a) * (b - a * a) + (1.0 - a) * (1.0 - a)
                })
                .sum::<f64>(),
            Function::Ackley => {
                let sq = (0..x.len()).map(|i| at(i) * at(i)).sum::<f64>() / n;
                let cs = it.map(|v| libm::cos(TAU * v)).sum::<f64>() / n;
                -20.0 * libm::exp(-0.2 * libm::sqrt(sq)) - libm::exp(cs)
                    + 20.0
                    + core::f64::consts::E
            }
            Function::Griewank => {
                let sq = (0..x.len()).map(|i| at(i) * at(i)).sum::<f64>() / 4000.0;
                let prod = it
                    .enumerate()
                    .map(|(i, v)| libm::cos(v / libm::sqrt(i as f64 + 1.0)))
                    .product::<f64>();
                1.0 + sq - prod
            }
        };
        // Rounding can leave a tiny negative value near the optimum.
        v.max(0.0) as f32
    }
}

/// `sin(pi v)` up to its sign, which `sin^2` does not need: `v` reduced to `r = v - round(v)`
/// in `[-1/2, 1/2]` (exact in floating point), then the Taylor series of `sin(pi r)` to the
/// `x^21` term, whose remainder is below `(pi/2)^23 / 23! < 2e-18` on that interval. For
/// `|v| < 2^51`; the test functions' bounds are far inside.
#[inline]
fn sin_pi(v: f64) -> f64 {
    // Adding and removing 1.5 * 2^52 rounds to the nearest integer.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let r = v - ((v + ROUND) - ROUND);
    let x = core::f64::consts::PI * r;
    let x2 = x * x;
    // Horner on 1 - x^2/3! + x^4/5! - ... - x^20/21!: coefficient k is (-1)^k / (2k + 1)!.
    let mut p = 0.0;
    let mut k = 10;
    while k > 0 {
        p = (p + SIN_TAYLOR[k]) * x2;
        k -= 1;
    }
    x * (p + 1.0)
}

/// `(-1)^k / (2k + 1)!` for `k = 0..=10`.
const SIN_TAYLOR: [f64; 11] = {
    let mut c = [0.0; 11];
    let mut fact = 1.0;
    let mut k = 0;
    while k < 11 {
        if k > 0 {
            fact *= (2 * k) as f64 * (2 * k + 1) as f64;
        }
        c[k] = if k % 2 == 0 { 1.0 / fact } else { -1.0 / fact };
        k += 1;
    }
    c
};

impl fmt::Display for Function {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A function name that is not one of `sphere rastrigin rosenbrock ackley griewank`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnknownFunction;

impl fmt::Display for UnknownFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(
            "unknown function, expected one of: sphere rastrigin rosenbrock ackley griewank",
        )
    }
}

impl core::error::Error for UnknownFunction {}

impl FromStr for Function {
    type Err = UnknownFunction;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Function::ALL
            .iter()
            .copied()
            .find(|f| f.name() == s)
            .ok_or(UnknownFunction)
    }
}

/// A test function in `dim` dimensions, as a [`Problem`], optionally shifted so that its
/// optimum lies at `x_i = shift` instead of the function's own optimum.
///
/// Sphere, Rastrigin, Ackley and Griewank have their optimum at the centre of their box; a
/// method that drifts toward the centre looks better there than it is. Moving the optimum
/// (`papillon-sim optimize --shift 1.7`) takes that bias out of a comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TestFunction {
    function: Function,
    dim: usize,
    /// Added to every coordinate of the optimum.
    offset: f32,
}

impl TestFunction {
    /// `function` in `dim` dimensions (1 to [`MAX_DIM`]; Rosenbrock needs 2).
    pub fn new(function: Function, dim: usize) -> Result<Self, OptimError> {
        let min = if function == Function::Rosenbrock {
            2
        } else {
            1
        };
        if dim < min || dim > MAX_DIM {
            return Err(OptimError::BadDimension { dim });
        }
        Ok(Self {
            function,
            dim,
            offset: 0.0,
        })
    }

    /// `function` in `dim` dimensions with its optimum moved to `x_i = shift`, which must lie
    /// strictly inside the bounds ([`OptimError::ShiftOutOfBounds`] otherwise).
    pub fn shifted(function: Function, dim: usize, shift: f32) -> Result<Self, OptimError> {
        let mut f = Self::new(function, dim)?;
        let (lower, upper) = function.bounds();
        if !(shift > lower && shift < upper) {
            return Err(OptimError::ShiftOutOfBounds {
                shift,
                lower,
                upper,
            });
        }
        f.offset = shift - function.optimum();
        Ok(f)
    }

    /// Where the optimum lies (every gene the same value).
    pub fn optimum(&self) -> f32 {
        self.function.optimum() + self.offset
    }

    /// Which function.
    pub fn function(&self) -> Function {
        self.function
    }
}

impl Problem for TestFunction {
    fn dim(&self) -> usize {
        self.dim
    }
    fn bounds(&self, _gene: usize) -> (f32, f32) {
        self.function.bounds()
    }
    fn evaluate(&mut self, genes: &[f32]) -> f32 {
        self.function.value_shifted(genes, self.offset)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minima_are_zero() {
        for f in Function::ALL {
            let at = if f == Function::Rosenbrock { 1.0 } else { 0.0 };
            let x = [at; 10];
            assert!(f.value(&x) < 1e-6, "{f}: {}", f.value(&x));
        }
    }

    #[test]
    fn rastrigin_matches_its_cosine_form() {
        // 10 n + sum (v^2 - 10 cos 2 pi v), with the library cosine, over the whole box.
        let mut rng = crate::random::seeded(3);
        for _ in 0..2000 {
            let x: [f32; 10] =
                core::array::from_fn(|_| crate::random::range_f32(&mut rng, -5.12, 5.12));
            let cosine = 100.0
                + x.iter()
                    .map(|&v| {
                        let v = v as f64;
                        v * v - 10.0 * libm::cos(core::f64::consts::TAU * v)
                    })
                    .sum::<f64>();
            let ours = Function::Rastrigin.value(&x) as f64;
            assert!(
                (ours - cosine).abs() <= 1e-6 * cosine,
                "{x:?}: {ours} vs {cosine}"
            );
        }
        // Near the optimum the sine form keeps the precision the cosine form loses.
        let tiny = Function::Rastrigin.value(&[1e-5; 10]) as f64;
        let s = core::f64::consts::PI * 1e-5;
        let exact = 10.0 * (1e-10 + 20.0 * s * s);
        assert!((tiny - exact).abs() < 1e-6 * exact, "{tiny} vs {exact}");
    }

    #[test]
    fn values_away_from_minimum_are_positive() {
        let x = [0.5f32; 10];
        for f in Function::ALL {
            assert!(f.value(&x) > 1e-3, "{f}");
        }
        assert!((Function::Sphere.value(&x) - 2.5).abs() < 1e-6);
        assert!((Function::Rastrigin.value(&[1.0, 0.0]) - 1.0).abs() < 1e-5);
        assert!((Function::Rosenbrock.value(&[0.0, 0.0]) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn shifted_functions_have_their_optimum_at_the_shift() {
        for f in Function::ALL {
            let mut p = TestFunction::shifted(f, 10, 1.7).unwrap();
            assert_eq!(p.optimum(), 1.7);
            assert!(
                p.evaluate(&[1.7; 10]) < 1e-6,
                "{f}: {}",
                p.evaluate(&[1.7; 10])
            );
            // The unshifted optimum is no longer one.
            let at = f.optimum();
            assert!(p.evaluate(&[at; 10]) > 1e-3, "{f}");
            // A shifted point sees the unshifted value of its offset from the optimum.
            let x = [0.5f32; 10];
            let moved: [f32; 10] = core::array::from_fn(|i| x[i] + 1.7 - at);
            let expected = f.value(&x);
            assert!(
                (p.evaluate(&moved) - expected).abs() <= 1e-4 * expected.max(1.0),
                "{f}"
            );
        }
        // Shift 0 is the function itself, Rosenbrock's optimum included.
        let mut p = TestFunction::shifted(Function::Rosenbrock, 3, 0.0).unwrap();
        assert!(p.evaluate(&[0.0; 3]) < 1e-9);
    }

    #[test]
    fn a_shift_outside_the_bounds_is_an_error() {
        assert_eq!(
            TestFunction::shifted(Function::Sphere, 4, 6.0),
            Err(OptimError::ShiftOutOfBounds {
                shift: 6.0,
                lower: -5.12,
                upper: 5.12
            })
        );
        assert!(TestFunction::shifted(Function::Sphere, 4, f32::NAN).is_err());
        assert!(TestFunction::shifted(Function::Sphere, 4, 5.12).is_err());
    }

    #[test]
    fn names_round_trip() {
        for f in Function::ALL {
            assert_eq!(f.name().parse::<Function>(), Ok(f));
        }
        assert!("bogus".parse::<Function>().is_err());
    }
}
