//! The discovered terms in flight (issue 27, "Done when": the diagnosed blob compensating
//! the unit terms through firmware-core within 2x the noise-limited reference): every
//! form of the blind suite's discovery targets, seeds 1-4, on its own design; the blob
//! `diagnose --out` writes from the unit's production recording, flown through
//! firmware-core (`verify`) in the unit's flight-like recording
//! (`host_fit::blind::flight::flight_config`: a cold power-on at -30 C, 6 C/min warming,
//! 5 C/min cooling, a power cycle, 24 attitudes at 20 Hz; the unit's own state flies, the
//! rig's and the session's terms stay on the bench, so their blobs must have corrected
//! the calibration for them).
//!
//! The noise-limited reference is the same design and seed without the concealed term
//! (the same noise, the same chamber and tilter), diagnosed and flown the same way: what
//! the recording's noise alone leaves in that flight. The figures are the worst |dg| of
//! the flight's dwells within the blob's calibrated range, those near T0 included (the
//! designs span -20..40 C; the flight's first minutes at -30 C and its hold at +45 C
//! are an extrapolation of every blob alike, printed apart and not judged).
use firmware_core::terms::Axis;
use host_fit::blind::beyond::Expressed;
use host_fit::blind::cases::Case;
use host_fit::blind::config::configure;
use host_fit::blind::flight::flight_config;
use host_fit::blind::forms::Form;
use host_fit::diagnose::EffectId;
use host_fit::simulate::{Effects, SimConfig};
use host_fit::terms::{Factor, Term};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;
use tests::time_true::{found, s, write};
use tests::{cli, cli_json};

/// The seeds of each form, as the blind suite runs them.
const SEEDS: [u64; 4] = [1, 2, 3, 4];
/// A case flies when its worst dwell in range is within this many times the reference's.
const WITHIN: f64 = 2.0;
/// A form holds when this many of its cases fly (the blind suite's "3 of 4").
const HOLDS: usize = 3;

/// The worst |dg| of `rec`'s dwells compensated with `blob` through firmware-core, mg:
/// within the blob's calibrated range, and outside it (NaN when no dwell is).
fn flown(rec: &Path, pos: Option<&Path>, blob: &Path) -> (f64, f64) {
    let mut args = vec!["verify", s(rec), "--blob", s(blob), "--json"];
    if let Some(p) = pos {
        args.extend(["--positions", s(p)]);
    }
    let (code, out, err) = cli(&args);
    // the verdict is not measured here, the figures are (exit 3: a dwell failed the spec)
    assert!(matches!(code, 0 | 3 | 4), "verify exit {code}: {err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mg = |k: &str| j[k].as_f64().unwrap_or(f64::NAN);
    // `verify` splits the range's dwells: those within the spec's band of T0 are judged
    // on the tighter limit and reported apart; both are in the calibrated range
    let (t0, over) = (mg("worst_at_t0_mg"), mg("worst_over_range_mg"));
    let in_range = if t0.is_nan() {
        over
    } else if over.is_nan() {
        t0
    } else {
        t0.max(over)
    };
    (in_range, mg("worst_outside_range_mg"))
}

/// What one unit's blobs do in its flight.
struct Flown {
    /// The diagnosed blob: in range, outside (mg).
    diagnosed: (f64, f64),
    /// The plain `fit` blob, in range (mg); `None` when not asked for.
    fit: Option<f64>,
    /// The discovered terms named, each with its axes.
    terms: Vec<(Term, Vec<Axis>)>,
    /// The effects of every finding (`discovered` for the terms).
    effects: Vec<EffectId>,
}

/// Diagnose `prod` (and `fit` it, with `plain`), fly the blobs in `flight`; files in `dir`.
fn fly(dir: &Path, prod: &SimConfig, flight: &SimConfig, plain: bool) -> Flown {
    let (rec, pos) = write(dir, "production", prod);
    let with_positions = |cmd: &'static str, blob: &Path| {
        let mut a = vec![cmd, s(&rec)];
        if let Some(p) = &pos {
            a.extend(["--positions", s(p)]);
        }
        a.extend(["--out", s(blob), "--json", "--force"]);
        cli_json(&a)
    };
    let diagnosed = dir.join("diagnosed.blob");
    let j = with_positions("diagnose", &diagnosed);
    // each finding's term read back into the vocabulary's types: a term the contract
    // writes that the vocabulary does not parse fails here, not in a string match
    let terms = j["findings"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|f| {
            let term = f["term"].as_str()?;
            let parsed: Term = term
                .parse()
                .unwrap_or_else(|e| panic!("the finding's term `{term}`: {e}"));
            let axes = f["axes"]
                .as_array()
                .unwrap_or_else(|| panic!("the finding of `{term}` names no axes: {f}"));
            let axes = axes.iter().map(|a| {
                let a = a.as_str().unwrap_or("");
                *Axis::ALL
                    .iter()
                    .find(|x| x.name() == a)
                    .unwrap_or_else(|| panic!("the finding's axis `{a}`"))
            });
            Some((parsed, axes.collect()))
        })
        .collect();
    let effects = found(&j);
    let (fl, fpos) = write(dir, "flight", flight);
    let fit = plain.then(|| {
        let b = dir.join("fit.blob");
        with_positions("fit", &b);
        flown(&fl, fpos.as_deref(), &b).0
    });
    Flown {
        diagnosed: flown(&fl, fpos.as_deref(), &diagnosed),
        fit,
        terms,
        effects,
    }
}

/// The unit of `case` without its concealed term: the same design, seed and noise.
fn clean(mut c: SimConfig) -> SimConfig {
    c.effects = Effects::default();
    c
}

/// The default tier's case: a scale with the temperature's rate (`a_z*dTdt`, seed 1).
/// Its blob carries the flight's rate estimator and nothing else of the catalogue's
/// physics (without it the firmware differenced the quantised sensor per step: 4.3x the
/// reference), and flies within 2x the clean unit.
#[test]
fn a_rate_term_flies_with_the_flights_estimator() {
    let c = Case::of_form(Form::Expressed(Expressed::ScaleOfRate), 1);
    let dir = tempfile::tempdir().unwrap();
    let (unit, twin) = (dir.path().join("unit"), dir.path().join("clean"));
    std::fs::create_dir_all(&unit).unwrap();
    std::fs::create_dir_all(&twin).unwrap();
    let r = fly(&unit, &configure(&c), &flight_config(&c), false);
    let want = Term::new([Factor::Az, Factor::DTdt]).unwrap();
    assert!(
        r.terms
            .iter()
            .any(|(t, axes)| t == &want && axes == &[Axis::Z]),
        "the term found: {:?}",
        r.terms
    );
    // the term, not the catalogue's rate effect, carries the rate
    assert!(
        r.effects.iter().all(|&e| e != EffectId::TempRate),
        "the findings: {:?}",
        r.effects
    );
    let blob = cli_json(&["inspect", s(&unit.join("diagnosed.blob")), "--json"]);
    let ph = &blob["physics"];
    assert_eq!(
        ph["rate_tau_s"].as_f64(),
        Some(-4.0),
        "the blob's physics section: {ph}"
    );
    // the estimator and no effect of the catalogue's physics
    for k in ["lag_tau_s", "warmup_tau_s"] {
        assert_eq!(ph[k].as_f64(), Some(0.0), "{k} in {ph}");
    }
    for k in ["rate", "hysteresis", "k2", "asymmetry", "warmup"] {
        let v: Vec<f64> = ph[k]
            .as_array()
            .unwrap_or_else(|| panic!("no {k} in {ph}"))
            .iter()
            .map(|v| v.as_f64().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(v, [0.0; 3], "{k} in {ph}");
    }
    let re = fly(
        &twin,
        &clean(configure(&c)),
        &clean(flight_config(&c)),
        false,
    );
    let ratio = r.diagnosed.0 / re.diagnosed.0;
    assert!(
        ratio <= WITHIN,
        "diagnosed {:.4} mg, the clean unit {:.4} mg: {ratio:.2}x",
        r.diagnosed.0,
        re.diagnosed.0
    );
}

#[test]
#[ignore = "full tier (cargo xtask test --full): 40 units and their clean twins diagnosed and flown, 2.5 min on 2 cores"]
fn the_discovered_terms_fly_within_twice_the_noise_limited_reference() {
    let cases: Vec<(Expressed, u64)> = Expressed::ALL
        .iter()
        .flat_map(|&f| SEEDS.map(|s| (f, s)))
        .collect();
    let case = |f: Expressed, seed: u64| Case::of_form(Form::Expressed(f), seed);
    // the references: each clean unit once (forms on one design and seed share it; the
    // key is the whole configuration, so a form that draws anything else has its own)
    let twin = |f: Expressed, seed: u64| {
        let c = case(f, seed);
        let pair = (clean(configure(&c)), clean(flight_config(&c)));
        (format!("{pair:?}"), pair)
    };
    let twins: BTreeMap<String, (SimConfig, SimConfig)> =
        cases.iter().map(|&(f, seed)| twin(f, seed)).collect();
    let reference: BTreeMap<String, f64> = twins
        .into_par_iter()
        .map(|(key, (prod, flight))| {
            let dir = tempfile::tempdir().unwrap();
            (key, fly(dir.path(), &prod, &flight, false).diagnosed.0)
        })
        .collect();
    let flown: Vec<Flown> = cases
        .par_iter()
        .map(|&(f, seed)| {
            let dir = tempfile::tempdir().unwrap();
            let c = case(f, seed);
            fly(dir.path(), &configure(&c), &flight_config(&c), true)
        })
        .collect();
    let mut held = Vec::new();
    let mut worse_than_fit = Vec::new();
    // the figure: per form, each seed's diagnosed flight over its reference, the cases
    // within 2x, the worst diagnosed flight and the plain fit blob's range
    let mut table = vec![format!(
        "{:<40} {:<23} {:>5} {:>10}  {}",
        "form (seeds 1-4)", "diagnosed / reference", "held", "worst, mg", "fit blob, mg"
    )];
    for form in Expressed::ALL {
        let (mut flies, mut ratios, mut worst) = (0, Vec::new(), 0.0_f64);
        let (mut fit_lo, mut fit_hi) = (f64::INFINITY, 0.0_f64);
        for (&(f, seed), r) in cases.iter().zip(&flown) {
            if f != form {
                continue;
            }
            let re = reference[&twin(f, seed).0];
            let fit = r.fit.unwrap_or(f64::NAN);
            let ratio = r.diagnosed.0 / re;
            flies += usize::from(ratio <= WITHIN);
            ratios.push(format!("{ratio:.2}"));
            worst = worst.max(r.diagnosed.0);
            (fit_lo, fit_hi) = (fit_lo.min(fit), fit_hi.max(fit));
            println!(
                "{:<44} seed {seed}: diagnosed {:.4} mg, reference {re:.4} mg ({ratio:.2}x), fit {fit:.4} mg; outside the range {:.4} mg; terms {}",
                f.name(),
                r.diagnosed.0,
                r.diagnosed.1,
                r.terms
                    .iter()
                    .map(|(t, axes)| {
                        let a: Vec<&str> = axes.iter().map(|a| a.name()).collect();
                        format!("{t}@{}", a.join(""))
                    })
                    .collect::<Vec<_>>()
                    .join(" "),
            );
            // no figure (NaN) is worse too
            let no_worse = matches!(
                r.diagnosed.0.partial_cmp(&fit),
                Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
            );
            if !no_worse {
                worse_than_fit.push(format!("{} seed {seed}", f.name()));
            }
        }
        table.push(format!(
            "{:<40} {:<23} {:>5} {worst:>10.4}  {fit_lo:.2}-{fit_hi:.2}",
            form.name().trim_start_matches("term: "),
            ratios.join(" "),
            format!("{flies}/{}", SEEDS.len()),
        ));
        held.push((form, flies));
    }
    tests::readme::same("discovered-flight", &table.join("\n"));
    assert!(
        worse_than_fit.is_empty(),
        "the diagnosed blob flew worse than the plain fit blob: {worse_than_fit:?}"
    );
    let short: Vec<_> = held.iter().filter(|(_, n)| *n < HOLDS).collect();
    assert!(
        short.is_empty(),
        "forms whose blobs fly within {WITHIN}x the reference in fewer than {HOLDS} of 4: {:?}",
        short
            .iter()
            .map(|(f, n)| format!("{} {n}/4", f.name()))
            .collect::<Vec<_>>()
    );
}
