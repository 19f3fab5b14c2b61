//! Blind tests of the diagnosis: the simulator conceals effects of known size in a
//! recording; the diagnosis, which never sees the truth, must name them (and nothing on
//! clean data), report ambiguity where the data cannot separate, get the parameters
//! within 3 sigma and bring the residual to within 1.5x the noise.
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::diagnose::EFFECT_IDS;
use crate::diagnose::diagnose;
use crate::diagnose::findings::Finding;
use crate::diagnose::metrics::normalized_rms;
use crate::rng::Rng;
use crate::simulate::{simulate, Curvature, Fixture, PerAxis, SimConfig, Stop, Warmup};
use std::path::Path;

/// One blind case.
#[derive(Debug, Clone)]
pub struct Case {
    /// The concealed effects (catalogue ids); empty = clean.
    pub effects: Vec<&'static str>,
    /// Magnitude in units of the effect's nominal size (1 = clearly visible).
    pub scale: f64,
    /// Seed of the simulation and of the random axes/signs.
    pub seed: u64,
    /// Only TP positions (then k2 and asymmetry cannot be told apart).
    pub tp_only: bool,
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
    /// Final residual over noise.
    pub final_over_noise: f64,
    /// Notes for the report.
    pub note: String,
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

fn axes3(rng: &mut Rng, scale: f64, size: f64) -> [f64; 3] {
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
    let params_ok = params_within_3_sigma(&cfg, &d.findings);
    let data = d.data(&rec);
    let final_over_noise = normalized_rms(&data, &d.final_fit);
    Outcome {
        case: case.clone(),
        found,
        ambiguous,
        exact,
        params_ok,
        final_over_noise,
        note: String::new(),
    }
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

/// The suite: clean recordings, each effect at several magnitudes and seeds, pairs, and
/// the TP-only ambiguity. `long` adds seeds and smaller magnitudes.
pub fn suite(long: bool) -> Vec<Case> {
    let seeds: Vec<u64> = if long { (1..=4).collect() } else { vec![1] };
    let scales: Vec<f64> = if long {
        vec![1.0, 0.3, 0.1, 0.03, 0.01]
    } else {
        vec![1.0]
    };
    let mut v = Vec::new();
    for &seed in &seeds {
        v.push(Case {
            effects: vec![],
            scale: 1.0,
            seed: seed + 100,
            tp_only: false,
        });
        for e in EFFECTS {
            for &s in &scales {
                v.push(Case {
                    effects: vec![e],
                    scale: s,
                    seed,
                    tp_only: false,
                });
            }
        }
        v.push(Case {
            effects: vec!["temp_rate", "nonlinearity_k2"],
            scale: 1.0,
            seed,
            tp_only: false,
        });
        v.push(Case {
            effects: vec!["hysteresis", "fixture_error"],
            scale: 1.0,
            seed,
            tp_only: false,
        });
        v.push(Case {
            effects: vec!["nonlinearity_k2"],
            scale: 1.0,
            seed,
            tp_only: true,
        });
    }
    v
}

/// One line per case: what was concealed and what was named.
fn case_lines(outcomes: &[Outcome]) -> String {
    let mut s = String::from("case                                   scale seed  found / ambiguous                         exact  params  final/noise\n");
    for o in outcomes {
        let name = if o.case.effects.is_empty() {
            "clean".to_string()
        } else {
            o.case.effects.join("+")
        } + if o.case.tp_only { " (TP only)" } else { "" };
        let amb = o
            .ambiguous
            .iter()
            .map(|a| format!("{{{}}}", a.join("|")))
            .collect::<Vec<_>>()
            .join(" ");
        s.push_str(&format!(
            "{name:<38} {:>5.2} {:>4}  {:<40} {:<6} {:<7} {:>6.2} {}\n",
            o.case.scale,
            o.case.seed,
            format!(
                "{} {amb}",
                if o.found.is_empty() {
                    "none".to_string()
                } else {
                    o.found.join(",")
                }
            ),
            if o.exact { "yes" } else { "NO" },
            match o.params_ok {
                Some(true) => "ok",
                Some(false) => "off",
                None => "-",
            },
            o.final_over_noise,
            o.note
        ));
    }
    s
}

/// Every effect named by a case, found or ambiguous.
fn named(o: &Outcome) -> Vec<String> {
    let mut named: Vec<String> = o.found.clone();
    named.extend(o.ambiguous.iter().flatten().cloned());
    named
}

/// Concealed single effect (rows) against the effects named (columns).
fn confusion(outcomes: &[Outcome]) -> String {
    let cols: Vec<&str> = std::iter::once("none").chain(EFFECTS).collect();
    let mut s = String::from("\nconfusion (concealed single effect -> effects named, counts):\n");
    s.push_str(&format!("{:<16}", ""));
    for c in &cols {
        s.push_str(&format!("{:>6}", &c[..c.len().min(5)]));
    }
    s.push('\n');
    for row in std::iter::once("clean").chain(EFFECTS) {
        let cases: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| {
                !o.case.tp_only
                    && if row == "clean" {
                        o.case.effects.is_empty()
                    } else {
                        o.case.effects == [row]
                    }
            })
            .collect();
        if cases.is_empty() {
            continue;
        }
        s.push_str(&format!("{row:<16}"));
        for c in &cols {
            let n = cases
                .iter()
                .filter(|o| {
                    let named = named(o);
                    if *c == "none" {
                        named.is_empty()
                    } else {
                        named.iter().any(|x| x == c)
                    }
                })
                .count();
            s.push_str(&format!("{n:>6}"));
        }
        s.push('\n');
    }
    s
}

/// Where detection stops: the concealed effect named, by magnitude.
fn by_magnitude(outcomes: &[Outcome]) -> String {
    let mut scales: Vec<f64> = outcomes
        .iter()
        .filter(|o| !o.case.effects.is_empty())
        .map(|o| o.case.scale)
        .collect();
    scales.sort_by(|a, b| b.total_cmp(a));
    scales.dedup();
    let mut s = String::from(
        "\ndetection by magnitude (1 = the nominal size; effect named / exactly right / cases):\n",
    );
    for sc in &scales {
        let at: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| !o.case.effects.is_empty() && o.case.scale == *sc)
            .collect();
        let hit = at
            .iter()
            .filter(|o| {
                let named = named(o);
                o.case.effects.iter().all(|e| named.iter().any(|f| f == e))
            })
            .count();
        let ex = at.iter().filter(|o| o.exact).count();
        s.push_str(&format!("  {sc:>5.2}: {hit}/{ex}/{}\n", at.len()));
    }
    s
}

/// The scores over the whole suite.
fn scores(outcomes: &[Outcome]) -> String {
    let exact = outcomes.iter().filter(|o| o.exact).count();
    let detectable: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.scale >= 0.1).collect();
    let det_exact = detectable.iter().filter(|o| o.exact).count();
    let mut s = format!(
        "exactly the right set at magnitudes >= 0.1: {det_exact}/{} ({:.0}%)\n",
        detectable.len(),
        100.0 * det_exact as f64 / detectable.len().max(1) as f64
    );
    let clean: Vec<&Outcome> = outcomes
        .iter()
        .filter(|o| o.case.effects.is_empty())
        .collect();
    let false_on_clean = clean
        .iter()
        .filter(|o| !o.found.is_empty() || !o.ambiguous.is_empty())
        .count();
    let p: Vec<bool> = outcomes.iter().filter_map(|o| o.params_ok).collect();
    let resid_ok = outcomes
        .iter()
        .filter(|o| o.exact && o.final_over_noise <= 1.5)
        .count();
    s.push_str(&format!(
        "\nexactly the right set: {exact}/{} ({:.0}%); false findings on clean recordings: {false_on_clean}/{}; parameters within 3 sigma: {}/{}; final residual <= 1.5x noise (exact cases): {resid_ok}/{exact}\n",
        outcomes.len(),
        100.0 * exact as f64 / outcomes.len().max(1) as f64,
        clean.len(),
        p.iter().filter(|b| **b).count(),
        p.len()
    ));
    s
}

/// The confusion matrix and scores as text.
pub fn report(outcomes: &[Outcome]) -> String {
    case_lines(outcomes) + &confusion(outcomes) + &by_magnitude(outcomes) + &scores(outcomes)
}
