//! Blind tests of the diagnosis: the simulator conceals physics in a recording and the
//! diagnosis, which never sees the truth, is judged by class: catalogue effects in the
//! catalogue's form must be named (and nothing on clean data) with their parameters
//! within 3 sigma; other physical forms of an effect must still be named, and nothing
//! else; effects outside the catalogue must get no catalogue name, the residual located
//! on the right axis; clean recordings with real-world nuisances must get no physics.
//! Beyond the catalogue ([`beyond`]): forms the term library expresses must be named as
//! their discovered term on their axis, forms it does not must stay unexplained, and
//! nothing may be discovered on clean and catalogue-only units.
pub mod beyond;
#[cfg(test)]
mod beyond_tests;
pub mod cases;
pub mod config;
pub mod designs;
pub mod draw;
pub mod flight;
pub mod forms;
pub mod kinds;
pub mod outcome;
pub mod profiles;
pub mod report;
pub mod terms;

pub use cases::{Case, EFFECTS};
pub use config::configure;
pub use forms::Class;
pub use outcome::{DiscoveredClaim, FixtureClaim, Outcome};
pub use report::report;

use crate::blind::designs::positions_of;
use crate::data::recording::Recording;
use crate::diagnose::findings::Finding;
use crate::diagnose::parameters::Quantity;
use crate::diagnose::{diagnose_with, EffectId, Rules};
use crate::model::metrics::normalized_rms;
use crate::model::params::Term;
use crate::simulate::{simulate, SimConfig};
use std::path::Path;

/// Run one case with the diagnosis's default rules.
pub fn run(case: &Case) -> Outcome {
    run_with(case, Rules::default())
}

/// Run one case with the diagnosis judging by `rules`.
pub fn run_with(case: &Case, rules: Rules) -> Outcome {
    let cfg = configure(case);
    let fail = |note: String| Outcome {
        case: case.clone(),
        found: Vec::new(),
        ambiguous: Vec::new(),
        exact: false,
        params_ok: None,
        final_over_noise: f64::NAN,
        verdict: None,
        unexplained_axis: None,
        quality: Vec::new(),
        fixture_claims: Vec::new(),
        discovered: Vec::new(),
        note,
    };
    let sim = match simulate(&cfg, |_| {}) {
        Ok(s) => s,
        Err(e) => return fail(format!("simulate: {e}")),
    };
    let rec = match Recording::from_reader(
        Path::new("blind.csv"),
        sim.csv.as_bytes(),
        positions_of(&cfg),
    ) {
        Ok(r) => r,
        Err(e) => return fail(format!("read: {e}")),
    };
    let d = match diagnose_with(&rec, rules) {
        Ok(d) => d,
        Err(e) => return fail(format!("diagnose: {e}")),
    };
    // the catalogue's names; a discovered term is judged as a claim of its own
    let found: Vec<EffectId> = d
        .findings
        .iter()
        .map(|f| f.effect)
        .filter(|e| *e != EffectId::Discovered)
        .collect();
    // a set of discovered terms the design cannot tell apart names no catalogue effect
    let ambiguous: Vec<Vec<EffectId>> = d
        .ambiguous
        .iter()
        .filter(|a| a.terms.is_empty())
        .map(|a| a.candidates.clone())
        .collect();
    let mut named: Vec<EffectId> = found.clone();
    for a in &ambiguous {
        named.extend(a.iter().copied());
    }
    named.sort();
    named.dedup();
    let mut want: Vec<EffectId> = case.effects.clone();
    let k2_or_asymmetry = [EffectId::NonlinearityK2, EffectId::ScaleAsymmetry];
    let expect_ambiguity = case.tp_only && case.effects.iter().any(|e| k2_or_asymmetry.contains(e));
    if expect_ambiguity {
        want.extend(k2_or_asymmetry);
    }
    want.sort();
    want.dedup();
    let exact = named == want && (!expect_ambiguity || !ambiguous.is_empty());
    let params_ok = if case.class() == Class::Catalogue {
        params_within_3_sigma(&cfg, &d.findings)
    } else {
        None
    };
    Outcome {
        case: case.clone(),
        found,
        ambiguous,
        exact,
        params_ok,
        final_over_noise: normalized_rms(&d.data, &d.final_fit),
        verdict: Some(d.verdict()),
        unexplained_axis: d.unexplained.first().map(|h| h.axis.clone()),
        quality: d.quality.iter().map(|q| q.kind).collect(),
        fixture_claims: d.findings.iter().filter_map(FixtureClaim::of).collect(),
        discovered: d
            .findings
            .iter()
            .filter(|f| f.effect == EffectId::Discovered)
            .filter_map(|f| {
                Some(DiscoveredClaim {
                    term: f.term.as_ref()?.to_string(),
                    axes: f.axes.clone(),
                    reproduced: f.reproduced,
                })
            })
            .collect(),
        note: String::new(),
    }
}

/// The diagnosis of a case as text (to look into one case).
pub fn diagnosis_text(case: &Case) -> String {
    let cfg = configure(case);
    let run = || -> crate::error::Result<String> {
        let sim = simulate(&cfg, |_| {})?;
        let rec = Recording::from_reader(
            Path::new("blind.csv"),
            sim.csv.as_bytes(),
            positions_of(&cfg),
        )?;
        let truth = serde_json::to_string(&cfg.effects).unwrap_or_default();
        Ok(format!(
            "concealed: {truth}\n{}",
            crate::diagnose::diagnose(&rec)?.contract().text()
        ))
    };
    run().unwrap_or_else(|e| format!("error: {e}"))
}

/// The true values of a finding's parameters, for the per-axis linear effects and the
/// time constants (None for effects whose parameters are not compared).
fn truth_of(cfg: &SimConfig, effect: EffectId) -> Option<Vec<(Quantity, f64)>> {
    let per_axis = |q: &dyn Fn(usize) -> Quantity, v: [f64; 3]| -> Vec<(Quantity, f64)> {
        (0..3).map(|i| (q(i), v[i])).collect()
    };
    let term = |term: Term| move |axis: usize| Quantity::Term { term, axis };
    let tau = Quantity::Tau {
        pole: 1,
        axis: None,
    };
    let e = &cfg.effects;
    match effect {
        EffectId::TempRate => e.temp_rate.map(|p| per_axis(&term(Term::Rate), p.value)),
        EffectId::Hysteresis => e
            .hysteresis
            .map(|p| per_axis(&term(Term::Hysteresis), p.value)),
        EffectId::NonlinearityK2 => e
            .nonlinearity_k2
            .map(|p| per_axis(&term(Term::K2), p.value)),
        EffectId::ScaleAsymmetry => e
            .scale_asymmetry
            .map(|p| per_axis(&|axis| Quantity::Delta { axis }, p.value)),
        EffectId::ThermalLag => e.thermal_lag.map(|p| vec![(tau, p.value[0])]),
        EffectId::WarmupDrift => e.warmup_drift.map(|w| {
            let mut v = per_axis(&term(Term::Warmup), w.d_v);
            v.push((tau, w.tau_s));
            v
        }),
        // a curvature's and a fixture's true parameters are not the diagnosis's (a sine
        // against breakpoints, two angles against the fixture's own frame)
        EffectId::TempCurvature | EffectId::FixtureError => None,
        // a discovered term's truth is the class's own (crate::blind::forms)
        EffectId::Discovered => None,
    }
}

/// Whether every compared parameter of every finding is within 3 sigma of its truth
/// (None when no finding has compared parameters).
fn params_within_3_sigma(cfg: &SimConfig, findings: &[Finding]) -> Option<bool> {
    let mut params_ok = None;
    for f in findings {
        if let Some(t) = truth_of(cfg, f.effect) {
            let ok = t.iter().all(|(q, v)| {
                matches!(f.parameters.get(*q), Some(p) if (p.value - v).abs() <= 3.0 * p.sigma.max(1e-300))
            });
            params_ok = Some(params_ok.unwrap_or(true) && ok);
        }
    }
    params_ok
}

/// The suite: per seed, a clean recording, each catalogue effect at several magnitudes,
/// pairs, the TP-only ambiguity, and one case of every other form, outside effect and
/// nuisance of [`forms`]; then the classes beyond the catalogue ([`cases::discovery_cases`]: one
/// case of each in the short suite). `long` adds seeds and smaller magnitudes.
pub fn suite(long: bool) -> Vec<Case> {
    let seeds: Vec<u64> = if long { (1..=4).collect() } else { vec![1] };
    let scales: Vec<f64> = if long {
        vec![1.0, 0.3, 0.1, 0.03, 0.01]
    } else {
        vec![1.0]
    };
    let mut v = Vec::new();
    for &seed in &seeds {
        v.push(Case::catalogue(vec![], 1.0, seed + 100));
        for e in EFFECTS {
            for &s in &scales {
                v.push(Case::catalogue(vec![e], s, seed));
            }
        }
        v.push(Case::catalogue(
            vec![EffectId::TempRate, EffectId::NonlinearityK2],
            1.0,
            seed,
        ));
        v.push(Case::catalogue(
            vec![EffectId::Hysteresis, EffectId::FixtureError],
            1.0,
            seed,
        ));
        v.push(Case {
            tp_only: true,
            ..Case::catalogue(vec![EffectId::NonlinearityK2], 1.0, seed)
        });
        for f in forms::Form::ALL
            .into_iter()
            .chain(forms::Form::on_own_profiles())
        {
            v.push(Case::of_form(f, seed));
        }
    }
    v.extend(cases::discovery_cases(long));
    v
}
