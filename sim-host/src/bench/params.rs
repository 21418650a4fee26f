//! Hyper-parameters by name: what a sweep's `params` sets and `papillon-sim tune` searches.
//!
//! Each tunable method has the parameters of the thesis's Table 4.1 (Bendahmane 2023), under
//! the names of its parameter struct in [`papillon::optim`]:
//!
//! | method | parameter | meaning | search range (`tune`) | Table 4.1 (pop 5 / pop 20) |
//! |---|---|---|---|---|
//! | xboa | `a`, `c`, `p_c` | power exponent, initial sensory modality, crossover probability | 0.01–1, 0.01–1, 0–1 | 0.994, 0.518, 0.583 / 0.905, 0.257, 0.593 |
//! | boa | `a`, `c`, `p` | power exponent, sensory modality, switch probability | 0.01–1, 0.01–1, 0–1 | 0.73, 0.577, 0.331 / 0.547, 0.602, 0.395 |
//! | mboa | `a`, `c`, `p` | as BOA | as BOA | 0.61, 0.356, 0.762 |
//! | aboa | `a`, `p`, `mu` | power exponent, switch probability, shape of the `c` schedule | 0.01–1, 0–1, 0.5–3 | 0.992, 0.983, 1.356 |
//! | saboa | `p` | switch probability | 0–1 | 0.237 |
//! | ga | `crossover`, `mutation`, `eta_m` | crossover and per-gene mutation probabilities, polynomial-mutation index | 0–1, 0–1, 1–100 | 0.11, 0.215, 76.026 |
//! | pso | `inertia`, `cognitive`, `social`, `vmax_fraction` | inertia weight, c1, c2, maximum speed (box fraction) | 0–1, 0–4, 0–4, 0.05–1 | 0.449, 3.379, 1.506, 0.329 |
//!
//! GWO, ABC and CMA-ES have none (the thesis: "auto-tuning"). The thesis gives no search
//! ranges (its Hyperopt run's are lost); these are the parameters' natural domains (a
//! probability in 0–1; BOA's `a` and `c` in 0–1 as in Arora & Singh 2019; PSO's coefficients
//! up to 4, twice the usual 2.05; μ around the thesis's 1.356), wide enough to hold every value
//! of Table 4.1.

use std::collections::BTreeMap;

use papillon::optim::{Method, Preset, Tuning, aboa, boa, ga, mboa, pso, saboa, xboa};

/// Named values of a method's hyper-parameters.
pub type ParamMap = BTreeMap<String, f32>;

/// One searched parameter: name and range (uniform).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Name.
    pub name: &'static str,
    /// Lower bound.
    pub low: f32,
    /// Upper bound.
    pub high: f32,
}

const fn r(name: &'static str, low: f32, high: f32) -> Range {
    Range { name, low, high }
}

const XBOA: [Range; 3] = [r("a", 0.01, 1.0), r("c", 0.01, 1.0), r("p_c", 0.0, 1.0)];
const BOA: [Range; 3] = [r("a", 0.01, 1.0), r("c", 0.01, 1.0), r("p", 0.0, 1.0)];
const ABOA: [Range; 3] = [r("a", 0.01, 1.0), r("p", 0.0, 1.0), r("mu", 0.5, 3.0)];
const SABOA: [Range; 1] = [r("p", 0.0, 1.0)];
const GA: [Range; 3] = [
    r("crossover", 0.0, 1.0),
    r("mutation", 0.0, 1.0),
    r("eta_m", 1.0, 100.0),
];
const PSO: [Range; 4] = [
    r("inertia", 0.0, 1.0),
    r("cognitive", 0.0, 4.0),
    r("social", 0.0, 4.0),
    r("vmax_fraction", 0.05, 1.0),
];

/// The search space of `method` (empty for GWO, ABC, CMA-ES and the frontier rules).
pub fn space(method: &str) -> &'static [Range] {
    match method {
        "xboa" => &XBOA,
        "boa" | "mboa" => &BOA,
        "aboa" => &ABOA,
        "saboa" => &SABOA,
        "ga" => &GA,
        "pso" => &PSO,
        _ => &[],
    }
}

/// The thesis's Table 4.1 values of `method` at `population` (as the optimizers build them,
/// [`Method::build`]), by name; empty for a method without parameters.
pub fn thesis_values(method: &str, population: usize) -> ParamMap {
    preset_values(method, population, Preset::Thesis)
}

/// The values of `method` at `population` under `preset` ([`Method::build_preset`]), by name:
/// Table 4.1's, except GA's and PSO's under [`Preset::Standard`]; empty for a method without
/// parameters.
pub fn preset_values(method: &str, population: usize, preset: Preset) -> ParamMap {
    let Ok(m) = method.parse::<Method>() else {
        return ParamMap::new();
    };
    let v: Vec<(&str, f32)> = match m {
        Method::Xboa => {
            let p = xboa::XboaParams::for_population(population);
            vec![("a", p.a), ("c", p.c), ("p_c", p.p_c)]
        }
        Method::Boa => {
            let p = boa::BoaParams::for_population(population);
            vec![("a", p.a), ("c", p.c), ("p", p.p)]
        }
        Method::Mboa => {
            let p = mboa::MboaParams::default();
            vec![("a", p.a), ("c", p.c), ("p", p.p)]
        }
        Method::Aboa => {
            let p = aboa::AboaParams::default();
            vec![("a", p.a), ("p", p.p), ("mu", p.mu)]
        }
        Method::Saboa => vec![("p", saboa::SaboaParams::default().p)],
        Method::Ga => {
            let p = ga_base(preset);
            vec![
                ("crossover", p.crossover),
                ("mutation", p.mutation),
                ("eta_m", p.eta_m),
            ]
        }
        Method::Pso => {
            let p = pso_base(preset);
            vec![
                ("inertia", p.inertia),
                ("cognitive", p.cognitive),
                ("social", p.social),
                ("vmax_fraction", p.vmax_fraction),
            ]
        }
        _ => vec![],
    };
    v.into_iter().map(|(k, x)| (k.to_string(), x)).collect()
}

fn ga_base(preset: Preset) -> ga::GaParams {
    match preset {
        Preset::Thesis => ga::GaParams::thesis(),
        Preset::Standard => ga::GaParams::standard(),
    }
}

fn pso_base(preset: Preset) -> pso::PsoParams {
    match preset {
        Preset::Thesis => pso::PsoParams::thesis(),
        Preset::Standard => pso::PsoParams::standard(),
    }
}

/// The tuning of `method` at `population`: `preset`'s values ([`preset_values`]) with `values`
/// replacing some; an unknown name, a value outside the search range, or a method without
/// parameters is an error naming it.
pub fn tuning(
    method: &str,
    population: usize,
    preset: Preset,
    values: &ParamMap,
) -> Result<Tuning, String> {
    let ranges = space(method);
    if ranges.is_empty() {
        return Err(format!("params: {method} has no hyper-parameters to set"));
    }
    let mut all = preset_values(method, population, preset);
    for (k, &v) in values {
        let Some(range) = ranges.iter().find(|r| r.name == k) else {
            let names: Vec<&str> = ranges.iter().map(|r| r.name).collect();
            return Err(format!(
                "params.{method}.{k}: unknown parameter, expected one of: {}",
                names.join(" ")
            ));
        };
        if !(v.is_finite() && v >= range.low && v <= range.high) {
            return Err(format!(
                "params.{method}.{k}: expected {} to {}, got {v}",
                range.low, range.high
            ));
        }
        all.insert(k.clone(), v);
    }
    let g = |k: &str| all[k];
    Ok(match method {
        "xboa" => Tuning::Xboa(xboa::XboaParams {
            a: g("a"),
            c: g("c"),
            p_c: g("p_c"),
        }),
        "boa" => Tuning::Boa(boa::BoaParams {
            a: g("a"),
            c: g("c"),
            p: g("p"),
        }),
        "mboa" => Tuning::Mboa(mboa::MboaParams {
            a: g("a"),
            c: g("c"),
            p: g("p"),
        }),
        "aboa" => Tuning::Aboa(aboa::AboaParams {
            a: g("a"),
            p: g("p"),
            mu: g("mu"),
        }),
        "saboa" => Tuning::Saboa(saboa::SaboaParams { p: g("p") }),
        "ga" => Tuning::Ga(ga::GaParams {
            crossover: g("crossover"),
            mutation: g("mutation"),
            eta_m: g("eta_m"),
            ..ga_base(preset)
        }),
        "pso" => Tuning::Pso(pso::PsoParams {
            inertia: g("inertia"),
            cognitive: g("cognitive"),
            social: g("social"),
            vmax_fraction: g("vmax_fraction"),
            ..pso_base(preset)
        }),
        _ => unreachable!("space() is empty for other methods"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_1_values_lie_in_the_search_ranges_and_rebuild_the_thesis_tuning() {
        for m in ["xboa", "boa", "mboa", "aboa", "saboa", "ga", "pso"] {
            for pop in [5, 20] {
                let v = thesis_values(m, pop);
                assert_eq!(v.len(), space(m).len(), "{m}");
                let t = tuning(m, pop, Preset::Thesis, &v).unwrap();
                let none = ParamMap::new();
                assert_eq!(t, tuning(m, pop, Preset::Thesis, &none).unwrap(), "{m}");
                assert_eq!(t.method().name(), m);
            }
        }
        assert_eq!(thesis_values("xboa", 5)["a"], 0.994);
        assert_eq!(thesis_values("boa", 20)["p"], 0.395);
    }

    /// A partial set fills the rest from the chosen preset, not always from Table 4.1.
    #[test]
    fn a_partial_set_keeps_the_chosen_presets_other_values() {
        let mut v = ParamMap::new();
        v.insert("mutation".into(), 0.3);
        let Tuning::Ga(standard) = tuning("ga", 20, Preset::Standard, &v).unwrap() else {
            panic!("not a GA tuning");
        };
        assert_eq!(standard.mutation, 0.3);
        assert_eq!(standard.crossover, ga::GaParams::standard().crossover);
        assert_eq!(standard.eta_m, ga::GaParams::standard().eta_m);
        let Tuning::Ga(thesis) = tuning("ga", 20, Preset::Thesis, &v).unwrap() else {
            panic!("not a GA tuning");
        };
        assert_eq!(thesis.crossover, ga::GaParams::thesis().crossover);
        assert_ne!(standard.crossover, thesis.crossover);
        v.clear();
        v.insert("social".into(), 1.0);
        let Tuning::Pso(p) = tuning("pso", 20, Preset::Standard, &v).unwrap() else {
            panic!("not a PSO tuning");
        };
        assert_eq!(p.social, 1.0);
        assert_eq!(p.inertia, pso::PsoParams::standard().inertia);
    }

    #[test]
    fn bad_parameters_are_named() {
        let mut v = ParamMap::new();
        v.insert("q".into(), 0.5);
        let e = tuning("xboa", 5, Preset::Thesis, &v).unwrap_err();
        assert!(e.contains("params.xboa.q") && e.contains("p_c"), "{e}");
        v.clear();
        v.insert("p_c".into(), 1.5);
        let e = tuning("xboa", 5, Preset::Thesis, &v).unwrap_err();
        assert!(e.contains("0 to 1"), "{e}");
        assert!(tuning("gwo", 5, Preset::Thesis, &ParamMap::new()).is_err());
    }
}
