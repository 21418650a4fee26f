//! The methods by name, their parameter sets ([`Preset`]), and [`AnyOptimizer`]: any of them
//! behind one type, chosen at run time without allocation.

use core::fmt;
use core::str::FromStr;

use rand_core::Rng;

use super::*;

/// The methods, selectable at run time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Butterfly optimization with crossover ([`xboa`]).
    Xboa,
    /// Butterfly optimization ([`boa`]).
    Boa,
    /// Modified butterfly optimization ([`mboa`]).
    Mboa,
    /// Butterfly optimization with a non-linear sensory modality ([`aboa`]).
    Aboa,
    /// Self-adaptive butterfly optimization ([`saboa`]).
    Saboa,
    /// Real-coded genetic algorithm ([`ga`]).
    Ga,
    /// Particle swarm optimization, ring topology ([`pso`]).
    Pso,
    /// Grey wolf optimizer ([`gwo`]).
    Gwo,
    /// Artificial bee colony ([`abc`]).
    Abc,
    /// Covariance matrix adaptation evolution strategy ([`cmaes`]).
    CmaEs,
    /// Uniform random search, the baseline ([`random_search`]); not one of the ten compared
    /// methods, so not in [`Method::ALL`].
    Random,
}

impl Method {
    /// The ten methods the thesis compares.
    pub const ALL: [Method; 10] = [
        Method::Xboa,
        Method::Boa,
        Method::Mboa,
        Method::Aboa,
        Method::Saboa,
        Method::Ga,
        Method::Pso,
        Method::Gwo,
        Method::Abc,
        Method::CmaEs,
    ];

    /// Command-line name: `xboa boa mboa aboa saboa ga pso gwo abc cmaes` (and `random`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Xboa => "xboa",
            Method::Boa => "boa",
            Method::Mboa => "mboa",
            Method::Aboa => "aboa",
            Method::Saboa => "saboa",
            Method::Ga => "ga",
            Method::Pso => "pso",
            Method::Gwo => "gwo",
            Method::Abc => "abc",
            Method::CmaEs => "cmaes",
            Method::Random => "random",
        }
    }

    /// The method with the thesis's hyper-parameters ([`Preset::Thesis`]) for `population`
    /// individuals (xBOA and BOA interpolate between their pop-5 and pop-20 tunings, see their
    /// modules), `max_generations` being the horizon `T` of its schedules.
    pub fn build(self, population: usize, max_generations: u32) -> AnyOptimizer {
        self.build_preset(Preset::Thesis, population, max_generations)
    }

    /// [`Method::build_preset`], except that `tuning`, when it is this method's, replaces the
    /// preset's hyper-parameters (a tuning of another method is ignored: the caller checks
    /// that they match, see [`Tuning::method`]). The exploration layer builds its optimizers
    /// this way, with the preset and tuning of its [`crate::explore::ExploreConfig`].
    pub fn build_tuned(
        self,
        preset: Preset,
        tuning: Option<Tuning>,
        population: usize,
        max_generations: u32,
    ) -> AnyOptimizer {
        let t = max_generations;
        match tuning {
            Some(Tuning::Xboa(p)) if self == Method::Xboa => {
                AnyOptimizer::Xboa(xboa::Xboa::new(p, t))
            }
            Some(Tuning::Boa(p)) if self == Method::Boa => AnyOptimizer::Boa(boa::Boa::new(p, t)),
            Some(Tuning::Mboa(p)) if self == Method::Mboa => {
                AnyOptimizer::Mboa(mboa::Mboa::new(p, t))
            }
            Some(Tuning::Aboa(p)) if self == Method::Aboa => {
                AnyOptimizer::Aboa(aboa::Aboa::new(p, t))
            }
            Some(Tuning::Saboa(p)) if self == Method::Saboa => {
                AnyOptimizer::Saboa(saboa::Saboa::new(p, t))
            }
            Some(Tuning::Ga(p)) if self == Method::Ga => AnyOptimizer::Ga(ga::Ga::new(p, t)),
            Some(Tuning::Pso(p)) if self == Method::Pso => AnyOptimizer::Pso(pso::Pso::new(p, t)),
            _ => self.build_preset(preset, population, max_generations),
        }
    }

    /// The method with the parameter set `preset`; [`Method::build`] is
    /// `build_preset(Preset::Thesis, ..)`. Only GA, PSO, GWO and ABC differ between the presets.
    pub fn build_preset(
        self,
        preset: Preset,
        population: usize,
        max_generations: u32,
    ) -> AnyOptimizer {
        let t = max_generations;
        let (ga, pso, gwo, abc) = match preset {
            Preset::Thesis => (
                ga::GaParams::thesis(),
                pso::PsoParams::thesis(),
                gwo::Schedule::Started,
                abc::AbcParams::karaboga(),
            ),
            Preset::Standard => (
                ga::GaParams::standard(),
                pso::PsoParams::standard(),
                gwo::Schedule::Paper,
                abc::AbcParams::standard(),
            ),
        };
        match self {
            Method::Xboa => AnyOptimizer::Xboa(xboa::Xboa::new(
                xboa::XboaParams::for_population(population),
                t,
            )),
            Method::Boa => {
                AnyOptimizer::Boa(boa::Boa::new(boa::BoaParams::for_population(population), t))
            }
            Method::Mboa => AnyOptimizer::Mboa(mboa::Mboa::new(mboa::MboaParams::default(), t)),
            Method::Aboa => AnyOptimizer::Aboa(aboa::Aboa::new(aboa::AboaParams::default(), t)),
            Method::Saboa => {
                AnyOptimizer::Saboa(saboa::Saboa::new(saboa::SaboaParams::default(), t))
            }
            Method::Ga => AnyOptimizer::Ga(ga::Ga::new(ga, t)),
            Method::Pso => AnyOptimizer::Pso(pso::Pso::new(pso, t)),
            Method::Gwo => AnyOptimizer::Gwo(gwo::Gwo::with_schedule(gwo, t)),
            Method::Abc => AnyOptimizer::Abc(abc::Abc::new(abc, t)),
            Method::CmaEs => AnyOptimizer::CmaEs(cmaes::CmaEs::new(t)),
            Method::Random => AnyOptimizer::Random(random_search::RandomSearch::new(t)),
        }
    }
}

/// Hyper-parameters of one method that replace the thesis's ([`Method::build_tuned`]): what
/// `papillon-sim tune` searches and a sweep's `params` sets. GWO, ABC and CMA-ES have none
/// (the thesis's "auto-tuning").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tuning {
    /// xBOA's.
    Xboa(xboa::XboaParams),
    /// BOA's.
    Boa(boa::BoaParams),
    /// mBOA's.
    Mboa(mboa::MboaParams),
    /// ABOA's.
    Aboa(aboa::AboaParams),
    /// SABOA's.
    Saboa(saboa::SaboaParams),
    /// GA's.
    Ga(ga::GaParams),
    /// PSO's.
    Pso(pso::PsoParams),
}

impl Tuning {
    /// The method these parameters are for.
    pub fn method(&self) -> Method {
        match self {
            Tuning::Xboa(_) => Method::Xboa,
            Tuning::Boa(_) => Method::Boa,
            Tuning::Mboa(_) => Method::Mboa,
            Tuning::Aboa(_) => Method::Aboa,
            Tuning::Saboa(_) => Method::Saboa,
            Tuning::Ga(_) => Method::Ga,
            Tuning::Pso(_) => Method::Pso,
        }
    }
}

/// Which hyper-parameters a method gets ([`Method::build_preset`]).
///
/// CMA-ES, random search and the butterfly methods (whose only parameters are the thesis's
/// own) are the same in both; GWO differs only in its `a` schedule ([`gwo::Schedule`]), ABC
/// only in GABC's global-best term ([`abc::AbcParams`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Preset {
    /// The thesis's Table 4.1, tuned on the exploration problem: GA and PSO as in
    /// [`ga::GaParams::thesis`] and [`pso::PsoParams::thesis`], GWO with
    /// [`gwo::Schedule::Started`], ABC as Karaboga's ([`abc::AbcParams::karaboga`], pygmo's
    /// `bee_colony`). [`Method::build`] uses it; the thesis reproduction experiments run it.
    #[default]
    Thesis,
    /// The literature's defaults: [`ga::GaParams::standard`] (Deb's), [`pso::PsoParams::standard`]
    /// (Clerc and Kennedy's, pygmo's `pso` default), [`gwo::Schedule::Paper`] and GABC
    /// ([`abc::AbcParams::standard`]). Stronger on the standard test functions
    /// (`docs/optimizers.md`), and the exploration's default
    /// ([`crate::explore::DEFAULT_PRESET`]).
    Standard,
}

impl Preset {
    /// Both presets.
    pub const ALL: [Preset; 2] = [Preset::Thesis, Preset::Standard];

    /// Command-line name: `thesis` or `standard`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Thesis => "thesis",
            Preset::Standard => "standard",
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A preset name that is not `thesis` or `standard`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnknownPreset;

impl fmt::Display for UnknownPreset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("unknown preset, expected one of: thesis standard")
    }
}

impl core::error::Error for UnknownPreset {}

impl FromStr for Preset {
    type Err = UnknownPreset;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Preset::ALL
            .iter()
            .copied()
            .find(|p| p.name() == s)
            .ok_or(UnknownPreset)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A method name that is not one of `xboa boa mboa aboa saboa ga pso gwo abc cmaes random`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnknownMethod;

impl fmt::Display for UnknownMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(
            "unknown method, expected one of: xboa boa mboa aboa saboa ga pso gwo abc cmaes random",
        )
    }
}

impl core::error::Error for UnknownMethod {}

impl FromStr for Method {
    type Err = UnknownMethod;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .iter()
            .chain(core::iter::once(&Method::Random))
            .copied()
            .find(|m| m.name() == s)
            .ok_or(UnknownMethod)
    }
}

/// Any method behind one type, chosen at run time without allocation.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
pub enum AnyOptimizer {
    /// xBOA.
    Xboa(xboa::Xboa),
    /// BOA.
    Boa(boa::Boa),
    /// mBOA.
    Mboa(mboa::Mboa),
    /// ABOA.
    Aboa(aboa::Aboa),
    /// SABOA.
    Saboa(saboa::Saboa),
    /// GA.
    Ga(ga::Ga),
    /// PSO.
    Pso(pso::Pso),
    /// GWO.
    Gwo(gwo::Gwo),
    /// ABC.
    Abc(abc::Abc),
    /// CMA-ES.
    CmaEs(cmaes::CmaEs),
    /// Random search.
    Random(random_search::RandomSearch),
}

macro_rules! dispatch {
    ($self:expr, $o:ident => $body:expr) => {
        match $self {
            AnyOptimizer::Xboa($o) => $body,
            AnyOptimizer::Boa($o) => $body,
            AnyOptimizer::Mboa($o) => $body,
            AnyOptimizer::Aboa($o) => $body,
            AnyOptimizer::Saboa($o) => $body,
            AnyOptimizer::Ga($o) => $body,
            AnyOptimizer::Pso($o) => $body,
            AnyOptimizer::Gwo($o) => $body,
            AnyOptimizer::Abc($o) => $body,
            AnyOptimizer::CmaEs($o) => $body,
            AnyOptimizer::Random($o) => $body,
        }
    };
}

impl AnyOptimizer {
    /// Which method this is.
    pub fn method(&self) -> Method {
        match self {
            AnyOptimizer::Xboa(_) => Method::Xboa,
            AnyOptimizer::Boa(_) => Method::Boa,
            AnyOptimizer::Mboa(_) => Method::Mboa,
            AnyOptimizer::Aboa(_) => Method::Aboa,
            AnyOptimizer::Saboa(_) => Method::Saboa,
            AnyOptimizer::Ga(_) => Method::Ga,
            AnyOptimizer::Pso(_) => Method::Pso,
            AnyOptimizer::Gwo(_) => Method::Gwo,
            AnyOptimizer::Abc(_) => Method::Abc,
            AnyOptimizer::CmaEs(_) => Method::CmaEs,
            AnyOptimizer::Random(_) => Method::Random,
        }
    }
}

impl Optimizer for AnyOptimizer {
    fn start<P: Problem + ?Sized>(
        &mut self,
        problem: &mut P,
        initial: &Population,
    ) -> Result<(), OptimError> {
        dispatch!(self, o => o.start(problem, initial))
    }
    fn step<P: Problem + ?Sized, R: Rng>(
        &mut self,
        problem: &mut P,
        rng: &mut R,
    ) -> Result<(), OptimError> {
        dispatch!(self, o => o.step(problem, rng))
    }
    fn best_genome(&self) -> &[f32] {
        dispatch!(self, o => o.best_genome())
    }
    fn best_fitness(&self) -> f32 {
        dispatch!(self, o => o.best_fitness())
    }
    fn evaluations(&self) -> u32 {
        dispatch!(self, o => o.evaluations())
    }
    fn generation(&self) -> u32 {
        dispatch!(self, o => o.generation())
    }
    fn history(&self) -> &[f32] {
        dispatch!(self, o => o.history())
    }
    fn population(&self) -> &Population {
        dispatch!(self, o => o.population())
    }
}
