//! Blind tests of the diagnosis: the simulator conceals physics in a recording and the
//! diagnosis, which never sees the truth, is judged by class: catalogue effects in the
//! catalogue's form must be named (and nothing on clean data) with their parameters
//! within 3 sigma; other physical forms of an effect must still be named, and nothing
//! else; effects outside the catalogue must get no catalogue name, the residual located
//! on the right axis; clean recordings with real-world nuisances must get no physics.
pub mod cases;
pub mod config;
pub mod draw;
pub mod forms;
pub mod kinds;
pub mod outcome;
pub mod profiles;
pub mod report;

pub use cases::{Case, EFFECTS};
pub use config::configure;
pub use forms::Class;
pub use outcome::{FixtureClaim, Outcome};
pub use report::report;

use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::diagnose::findings::Finding;
use crate::diagnose::metrics::normalized_rms;
use crate::diagnose::{diagnose_with, EffectId, Rules};
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
        note,
    };
    let sim = match simulate(&cfg, |_| {}) {
        Ok(s) => s,
        Err(e) => return fail(format!("simulate: {e}")),
    };
    let rec = match Recording::from_reader(
        Path::new("blind.csv"),
        sim.csv.as_bytes(),
        Positions::default(),
    ) {
        Ok(r) => r,
        Err(e) => return fail(format!("read: {e}")),
    };
    let d = match diagnose_with(&rec, rules) {
        Ok(d) => d,
        Err(e) => return fail(format!("diagnose: {e}")),
    };
    let found: Vec<EffectId> = d.findings.iter().map(|f| f.effect).collect();
    let ambiguous: Vec<Vec<EffectId>> = d.ambiguous.iter().map(|a| a.candidates.clone()).collect();
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
            Positions::default(),
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
fn truth_of(cfg: &SimConfig, effect: EffectId) -> Option<Vec<(String, f64)>> {
    let per_axis = |sym: &str, v: [f64; 3]| -> Vec<(String, f64)> {
        (0..3)
            .map(|i| (format!("{sym}_{}", ["x", "y", "z"][i]), v[i]))
            .collect()
    };
    let e = &cfg.effects;
    match effect {
        EffectId::TempRate => e.temp_rate.map(|p| per_axis("r", p.value)),
        EffectId::Hysteresis => e.hysteresis.map(|p| per_axis("h", p.value)),
        EffectId::NonlinearityK2 => e.nonlinearity_k2.map(|p| per_axis("k2", p.value)),
        EffectId::ScaleAsymmetry => e.scale_asymmetry.map(|p| per_axis("delta", p.value)),
        EffectId::ThermalLag => e
            .thermal_lag
            .map(|p| vec![("tau_s".to_string(), p.value[0])]),
        EffectId::WarmupDrift => e.warmup_drift.map(|w| {
            let mut v = per_axis("d", w.d_v);
            v.push(("tau_s".into(), w.tau_s));
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
            let ok = t.iter().all(|(k, v)| {
                let est = f.parameters.get(k).copied();
                let sig = f.uncertainties.get(k).copied();
                matches!((est, sig), (Some(e), Some(s)) if (e - v).abs() <= 3.0 * s.max(1e-300))
            });
            params_ok = Some(params_ok.unwrap_or(true) && ok);
        }
    }
    params_ok
}

/// The suite: per seed, a clean recording, each catalogue effect at several magnitudes,
/// pairs, the TP-only ambiguity, and one case of every other form, outside effect and
/// nuisance of [`forms`]. `long` adds seeds and smaller magnitudes.
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
        for f in forms::Form::ALL.into_iter().chain(forms::Form::issue_18()) {
            v.push(Case::of_form(f, seed));
        }
    }
    v
}
