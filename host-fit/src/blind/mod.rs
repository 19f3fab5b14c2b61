//! Blind tests of the diagnosis: the simulator conceals physics in a recording and the
//! diagnosis, which never sees the truth, is judged by class: catalogue effects in the
//! catalogue's form must be named (and nothing on clean data) with their parameters
//! within 3 sigma; other physical forms of an effect must still be named, and nothing
//! else; effects outside the catalogue must get no catalogue name, the residual located
//! on the right axis; clean recordings with real-world nuisances must get no physics.
pub mod forms;
pub mod report;

use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::diagnose::diagnose;
use crate::diagnose::findings::Finding;
use crate::diagnose::metrics::normalized_rms;
use crate::diagnose::EFFECT_IDS;
use crate::rng::Rng;
use crate::simulate::{simulate, Curvature, Fixture, PerAxis, SimConfig, Stop, Warmup};
pub use report::report;
use std::path::Path;

/// What a case tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Catalogue effects in the catalogue's own form (and clean recordings).
    Catalogue,
    /// A catalogue effect in another physically plausible form.
    OtherForm,
    /// An effect outside the catalogue.
    Outside,
    /// A clean recording with a real-world nuisance.
    Nuisance,
}

impl Class {
    /// The class's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Class::Catalogue => "catalogue effects, catalogue form",
            Class::OtherForm => "catalogue effects, other forms",
            Class::Outside => "effects outside the catalogue",
            Class::Nuisance => "clean recordings with nuisances",
        }
    }
}

/// One blind case.
#[derive(Debug, Clone)]
pub struct Case {
    /// What it tests.
    pub class: Class,
    /// The form concealed (classes other than the catalogue's), a [`forms`] name.
    pub form: &'static str,
    /// The effects expected to be named (catalogue ids); empty = none.
    pub effects: Vec<&'static str>,
    /// Magnitude in units of the effect's nominal size (1 = clearly visible).
    pub scale: f64,
    /// Seed of the simulation and of the random axes/signs.
    pub seed: u64,
    /// Only TP positions (then k2 and asymmetry cannot be told apart).
    pub tp_only: bool,
}

impl Case {
    /// A catalogue case: `effects` in the catalogue's form.
    pub fn catalogue(effects: Vec<&'static str>, scale: f64, seed: u64) -> Case {
        Case {
            class: Class::Catalogue,
            form: "",
            effects,
            scale,
            seed,
            tp_only: false,
        }
    }

    /// The case's name in reports.
    pub fn name(&self) -> String {
        let base = if !self.form.is_empty() {
            self.form.to_string()
        } else if self.effects.is_empty() {
            "clean".to_string()
        } else {
            self.effects.join("+")
        };
        base + if self.tp_only { " (TP only)" } else { "" }
    }
}

/// The outcome of a case.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The case.
    pub case: Case,
    /// Effects found.
    pub found: Vec<String>,
    /// Ambiguous groups.
    pub ambiguous: Vec<Vec<String>>,
    /// Found exactly the concealed set (ambiguity counts when expected).
    pub exact: bool,
    /// Parameters within 3 sigma (None when not checked).
    pub params_ok: Option<bool>,
    /// Final residual over the floor.
    pub final_over_noise: f64,
    /// The verdict.
    pub verdict: String,
    /// The axis where the final residual is largest, when unexplained.
    pub unexplained_axis: Option<String>,
    /// Data-quality note kinds.
    pub quality: Vec<String>,
    /// Notes for the report.
    pub note: String,
}

impl Outcome {
    /// Every effect named, found or ambiguous.
    pub fn named(&self) -> Vec<String> {
        let mut named: Vec<String> = self.found.clone();
        named.extend(self.ambiguous.iter().flatten().cloned());
        named
    }

    /// The case passed, by its class's rule (see the module doc).
    pub fn passed(&self) -> bool {
        match self.case.class {
            Class::Catalogue | Class::OtherForm => self.exact,
            Class::Outside => self.named().is_empty() && self.located(),
            Class::Nuisance => self.named().is_empty() && self.noted(),
        }
    }

    /// Outside the catalogue: the unexplained residual sits on an axis the effect is on
    /// (or nothing was seen at all).
    pub fn located(&self) -> bool {
        let axes = forms::axes(&self.case);
        match &self.unexplained_axis {
            Some(a) => axes.iter().any(|i| ["x", "y", "z"][*i] == a),
            None => self.verdict == "none",
        }
    }

    /// A nuisance: the data-quality note it should raise is there.
    pub fn noted(&self) -> bool {
        forms::note(&self.case).is_none_or(|k| self.quality.iter().any(|q| q == k))
    }
}

/// The short test profile: 20 -> -20 -> 10 -> 40 -> 10 C (the last stop reached by
/// cooling), TP1..TP6 and PP1..PP6 at each, 1 C/min ramps, 20 min soaks.
pub fn profile(tp_only: bool) -> SimConfig {
    let mut c = SimConfig::default();
    c.unit.serial = "BLIND".into();
    let pos: Vec<String> = if tp_only {
        (1..=6).map(|i| format!("TP{i}")).collect()
    } else {
        c.schedule.positions.clone()
    };
    c.schedule.positions = pos.clone();
    c.schedule.stops = [20.0, -20.0, 10.0, 40.0, 10.0]
        .iter()
        .map(|t| Stop {
            temp_c: *t,
            soak_s: 1200.0,
            ramp_c_per_min: 1.0,
            positions: Some(pos.clone()),
        })
        .collect();
    c
}

pub(crate) fn axes3(rng: &mut Rng, scale: f64, size: f64) -> [f64; 3] {
    // one or two axes, random signs, 0.7..1.3 of the size
    let main = (rng.next_u64() % 3) as usize;
    let mut v = [0.0; 3];
    for (i, x) in v.iter_mut().enumerate() {
        if i == main || rng.uniform() < 0.3 {
            let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            *x = s * size * scale * rng.range(0.7, 1.3);
        }
    }
    v
}

/// Conceal the effects of `case` in the profile; returns the config.
pub fn configure(case: &Case) -> SimConfig {
    let mut c = profile(case.tp_only);
    c.seed = case.seed;
    let mut rng = Rng::new(case.seed ^ 0xB11D);
    if case.class != Class::Catalogue {
        forms::apply(case, &mut c, &mut rng);
        return c;
    }
    for e in &case.effects {
        let s = case.scale;
        match *e {
            "thermal_lag" => {
                c.effects.thermal_lag = Some(PerAxis {
                    value: [rng.range(300.0, 900.0); 3],
                })
            }
            "temp_rate" => {
                c.effects.temp_rate = Some(PerAxis {
                    value: axes3(&mut rng, s, 0.02),
                })
            }
            "hysteresis" => {
                c.effects.hysteresis = Some(PerAxis {
                    value: axes3(&mut rng, s, 1e-4),
                })
            }
            "nonlinearity_k2" => {
                c.effects.nonlinearity_k2 = Some(PerAxis {
                    value: axes3(&mut rng, s, 1e-4),
                })
            }
            "scale_asymmetry" => {
                c.effects.scale_asymmetry = Some(PerAxis {
                    value: axes3(&mut rng, s, 2e-4),
                })
            }
            "fixture_error" => {
                let p = ["TP2", "TP3", "TP5", "PP1", "PP4"][(rng.next_u64() % 5) as usize];
                c.effects.fixture_error = Some(Fixture {
                    position: p.into(),
                    angles_rad: [
                        rng.range(-2e-4, 2e-4) * s + 2e-4 * s,
                        rng.range(-2e-4, 2e-4) * s,
                    ],
                });
            }
            "warmup_drift" => {
                c.effects.warmup_drift = Some(Warmup {
                    d_v: axes3(&mut rng, s, 2e-4),
                    tau_s: rng.range(600.0, 2400.0),
                })
            }
            "temp_curvature" => {
                c.effects.temp_curvature = Some(Curvature {
                    u0_v: axes3(&mut rng, s, 1e-4),
                    k_rel: [0.0; 3],
                    period_c: 25.0,
                })
            }
            _ => {}
        }
    }
    c
}

/// Run one case.
pub fn run(case: &Case) -> Outcome {
    let cfg = configure(case);
    let fail = |note: String| Outcome {
        case: case.clone(),
        found: Vec::new(),
        ambiguous: Vec::new(),
        exact: false,
        params_ok: None,
        final_over_noise: f64::NAN,
        verdict: String::new(),
        unexplained_axis: None,
        quality: Vec::new(),
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
    let d = match diagnose(&rec) {
        Ok(d) => d,
        Err(e) => return fail(format!("diagnose: {e}")),
    };
    let found: Vec<String> = d.findings.iter().map(|f| f.effect.clone()).collect();
    let ambiguous: Vec<Vec<String>> = d.ambiguous.iter().map(|a| a.candidates.clone()).collect();
    let mut named: Vec<String> = found.clone();
    for a in &ambiguous {
        named.extend(a.iter().cloned());
    }
    named.sort();
    named.dedup();
    let mut want: Vec<String> = case.effects.iter().map(|s| s.to_string()).collect();
    let expect_ambiguity = case.tp_only
        && case
            .effects
            .iter()
            .any(|e| *e == "nonlinearity_k2" || *e == "scale_asymmetry");
    if expect_ambiguity {
        want.push("nonlinearity_k2".into());
        want.push("scale_asymmetry".into());
    }
    want.sort();
    want.dedup();
    let exact = named == want && (!expect_ambiguity || !ambiguous.is_empty());
    let params_ok = if case.class == Class::Catalogue {
        params_within_3_sigma(&cfg, &d.findings)
    } else {
        None
    };
    let data = d.data(&rec);
    let final_over_noise = normalized_rms(&data, &d.final_fit);
    let contract = d.contract(&rec);
    Outcome {
        case: case.clone(),
        found,
        ambiguous,
        exact,
        params_ok,
        final_over_noise,
        verdict: contract.verdict.to_string(),
        unexplained_axis: d.unexplained.first().map(|h| h.axis.clone()),
        quality: d.quality.iter().map(|q| q.kind.to_string()).collect(),
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
            diagnose(&rec)?.contract(&rec).text()
        ))
    };
    run().unwrap_or_else(|e| format!("error: {e}"))
}

/// The true values of a finding's parameters, for the per-axis linear effects and the
/// time constants (None for effects whose parameters are not compared).
fn truth_of(cfg: &SimConfig, effect: &str) -> Option<Vec<(String, f64)>> {
    let per_axis = |sym: &str, v: [f64; 3]| -> Vec<(String, f64)> {
        (0..3)
            .map(|i| (format!("{sym}_{}", ["x", "y", "z"][i]), v[i]))
            .collect()
    };
    let e = &cfg.effects;
    match effect {
        "temp_rate" => e.temp_rate.map(|p| per_axis("r", p.value)),
        "hysteresis" => e.hysteresis.map(|p| per_axis("h", p.value)),
        "nonlinearity_k2" => e.nonlinearity_k2.map(|p| per_axis("k2", p.value)),
        "scale_asymmetry" => e.scale_asymmetry.map(|p| per_axis("delta", p.value)),
        "thermal_lag" => e
            .thermal_lag
            .map(|p| vec![("tau_s".to_string(), p.value[0])]),
        "warmup_drift" => e.warmup_drift.map(|w| {
            let mut v = per_axis("d", w.d_v);
            v.push(("tau_s".into(), w.tau_s));
            v
        }),
        _ => None,
    }
}

/// Whether every compared parameter of every finding is within 3 sigma of its truth
/// (None when no finding has compared parameters).
fn params_within_3_sigma(cfg: &SimConfig, findings: &[Finding]) -> Option<bool> {
    let mut params_ok = None;
    for f in findings {
        if let Some(t) = truth_of(cfg, &f.effect) {
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

/// Every catalogue effect the simulator conceals.
pub const EFFECTS: [&str; 8] = EFFECT_IDS;

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
            vec!["temp_rate", "nonlinearity_k2"],
            1.0,
            seed,
        ));
        v.push(Case::catalogue(
            vec!["hysteresis", "fixture_error"],
            1.0,
            seed,
        ));
        v.push(Case {
            tp_only: true,
            ..Case::catalogue(vec!["nonlinearity_k2"], 1.0, seed)
        });
        for f in forms::FORMS {
            v.push(Case {
                class: f.class,
                form: f.name,
                effects: f.expect.to_vec(),
                scale: 1.0,
                seed,
                tp_only: false,
            });
        }
    }
    v
}
