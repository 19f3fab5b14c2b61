//! The diagnosis: the blind suite by class, the JSON contract, an effect outside the
//! catalogue, the flashed model in firmware, the input forms users have, and the real
//! recordings of ../shared/real.
use host_fit::blind::forms::{Form, Outside};
use host_fit::blind::{report, run, run_with, suite, Case, Class};
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::diagnose::contract::Verdict;
use host_fit::diagnose::location::Grouping;
use host_fit::diagnose::quality::NoteKind;
use host_fit::diagnose::{diagnose, EffectId, Rules};
use host_fit::simulate::{simulate, SimConfig};
use host_fit::terms::{Event, Factor};
use serde_json::Value;
use tests::{cli, real_diagnosis as real, repo};

mod reports;

fn recording(cfg: &SimConfig) -> Recording {
    let sim = simulate(cfg, |_| {}).unwrap();
    Recording::from_reader(
        std::path::Path::new("twin.csv"),
        sim.csv.as_bytes(),
        Positions::default(),
    )
    .unwrap()
}

/// `cfg` on a logger's uneven clock: 0.1 Hz at rest, rows up to 0.5 s late, 1 % lost.
fn logged_unevenly(cfg: &SimConfig) -> SimConfig {
    let mut c = cfg.clone();
    c.logger.rest_rate_hz = 0.1;
    c.logger.jitter_s = 0.5;
    c.logger.drop_rate = 0.01;
    c
}

/// The short suite, judged per class: the catalogue's own forms exactly (parameters within
/// 3 sigma, residual at the floor), other forms named right, effects outside the
/// catalogue never given a catalogue name, nuisances never called physics.
#[test]
#[ignore = "full tier (cargo xtask test --full): the short blind suite, 5 CPU-minutes"]
fn blind_suite_by_class() {
    use rayon::prelude::*;
    // the cases are independent: on every core (the order of the outcomes is kept)
    let outcomes: Vec<_> = suite(false).par_iter().map(run).collect();
    let text = report(&outcomes);
    println!("{text}");
    let of = |c: Class| outcomes.iter().filter(move |o| o.case.class() == c);
    for o in of(Class::Catalogue) {
        assert!(o.exact, "{}: {:?}\n{text}", o.case.name(), o.named());
        assert_ne!(o.params_ok, Some(false), "{}\n{text}", o.case.name());
        assert!(o.final_over_noise <= 1.5, "{}\n{text}", o.case.name());
    }
    let passed = |c: Class| of(c).filter(|o| o.passed()).count();
    assert!(
        passed(Class::OtherForm) + 1 >= of(Class::OtherForm).count(),
        "{text}"
    );
    assert!(
        passed(Class::Outside) + 1 >= of(Class::Outside).count(),
        "{text}"
    );
    assert_eq!(
        passed(Class::Nuisance),
        of(Class::Nuisance).count(),
        "{text}"
    );
    // the TP-only recording cannot separate K2 from scale asymmetry: reported, not guessed
    let tp = outcomes.iter().find(|o| o.case.tp_only).unwrap();
    assert!(tp.found.is_empty() && !tp.ambiguous.is_empty(), "{text}");
    classes_on_own_profiles(&outcomes, &text);
    discovery_classes(&outcomes, &text);
}

/// Whether the discovery targets are judged by their pass rule (their term named on
/// their axis, reproduced, the residual at 1.5x the floor): the diagnosis searches the
/// term library and `blind::run_with` fills `Outcome::discovered` from its `discovered`
/// findings.
const JUDGE_DISCOVERY_TARGETS: bool = true;

/// The classes beyond the catalogue in the short suite, one case each (a cross-coupling
/// a_i*a_j on 18 positions, a two-level bias beside a power cycle, a fixture error of an
/// edge position): every class there, reported apart, every case diagnosed; the blind
/// spot stays unexplained on its axis with no term and the control gets exactly its
/// catalogue effect and no term (rules that hold with or without the term search); the
/// target is never given a catalogue name, and with [`JUDGE_DISCOVERY_TARGETS`] it must
/// be named as its term.
fn discovery_classes(outcomes: &[host_fit::blind::Outcome], text: &str) {
    for c in [Class::Expressed, Class::Unexpressed, Class::NoDiscovery] {
        let of: Vec<_> = outcomes.iter().filter(|o| o.case.class() == c).collect();
        assert_eq!(of.len(), 1, "{}: one case in the short suite", c.name());
        assert!(
            text.contains(&format!("\n{}: ", c.name())),
            "{}\n{text}",
            c.name()
        );
        for o in of {
            assert!(o.verdict.is_some(), "{}: {}", o.case.name(), o.note);
            let judged = c != Class::Expressed || JUDGE_DISCOVERY_TARGETS;
            assert!(!judged || o.passed(), "{}\n{text}", o.case.name());
            assert!(
                o.named().is_empty() || c == Class::NoDiscovery,
                "{}",
                o.case.name()
            );
        }
    }
}

/// The classes on test profiles of their own in the short suite (one seed, the cold-first
/// profile): every class is there and reported apart; a digital output of a few counts per g is diagnosed like
/// any other; a fixture re-clamped between two stops is named with its position and stop
/// (before the held-out chunks stopped holding a whole stop's positions, none of the
/// three was: every chunk with that position's dwells was an extrapolation); a mixture
/// gets no wrong name (a missed effect is a miss, a wrong name worse); slow disturbances
/// may leave at most one of five cases named (a settling that starts mid-test is still
/// called a warm-up: measured, not hidden, in the long suite's figure; before a trend in
/// time had to be beaten, two were named).
fn classes_on_own_profiles(outcomes: &[host_fit::blind::Outcome], text: &str) {
    let classes = [
        Class::SlowDisturbance,
        Class::Digital,
        Class::FixtureChange,
        Class::Mixture,
    ];
    for c in classes {
        assert!(
            outcomes.iter().any(|o| o.case.class() == c),
            "{}: no case in the short suite",
            c.name()
        );
        assert!(
            text.contains(&format!("\n{}: ", c.name())),
            "{}\n{text}",
            c.name()
        );
    }
    let of = |c: Class| outcomes.iter().filter(move |o| o.case.class() == c);
    let passed = |c: Class| of(c).filter(|o| o.passed()).count();
    assert_eq!(passed(Class::Digital), of(Class::Digital).count(), "{text}");
    for c in [Class::FixtureChange, Class::Mixture] {
        for o in of(c) {
            assert!(o.wrong_names().is_empty(), "{}\n{text}", o.case.name());
        }
    }
    for o in of(Class::FixtureChange) {
        assert!(o.passed() && o.right_stop(), "{}\n{text}", o.case.name());
    }
    assert!(
        passed(Class::SlowDisturbance) + 1 >= of(Class::SlowDisturbance).count(),
        "{text}"
    );
}

/// The rules are the diagnosis's, and the blind suite can vary them: a case found under
/// the default rules is not found when the acceptance margin is out of reach, and the
/// residual it leaves is then called unexplained.
#[test]
fn the_blind_suite_varies_the_rules() {
    let case = Case::catalogue(vec![EffectId::NonlinearityK2], 1.0, 1);
    let found = run_with(&case, Rules::default());
    assert_eq!(found.found, [EffectId::NonlinearityK2], "{}", found.note);
    assert_eq!(found.verdict, Some(Verdict::Explained));
    let strict = Rules {
        q_margin: f64::INFINITY,
        ..Rules::default()
    };
    let missed = run_with(&case, strict);
    assert!(missed.named().is_empty(), "{:?}", missed.named());
    assert_eq!(missed.verdict, Some(Verdict::Unexplained));
}

#[test]
fn json_contract_on_a_clean_and_an_effect_recording() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for (name, effects) in [("clean", vec![]), ("rate", vec![EffectId::TempRate])] {
        let cfg = host_fit::blind::configure(&Case::catalogue(effects, 1.0, 3));
        let sim = simulate(&cfg, |_| {}).unwrap();
        let p = dir.join(format!("{name}.csv"));
        std::fs::write(&p, sim.csv).unwrap();
        let report = dir.join(format!("{name}.html"));
        let _ = std::fs::remove_file(&report);
        let (code, out, err) = cli(&[
            "diagnose",
            p.to_str().unwrap(),
            "--json",
            "--report",
            report.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        let j: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(j["format"], "at-diagnosis/1");
        for k in [
            "noise_rms",
            "floor",
            "dispersion",
            "baseline",
            "findings",
            "ambiguous",
            "coupled",
            "quality",
            "unexplained",
            "final",
            "flashed",
            "verdict",
        ] {
            assert!(j.get(k).is_some(), "{k} missing");
        }
        assert_eq!(j["floor"]["measured"], true);
        for a in j["floor"]["axes"].as_array().unwrap() {
            // the twin's voltmeter: 2e-5 V white noise per sample
            let s = a["sample_sigma"].as_f64().unwrap();
            assert!((1.5e-5..2.7e-5).contains(&s), "{a}");
        }
        let html = std::fs::read_to_string(&report).unwrap();
        let ids: Vec<String> = reports::check_plots(&html)
            .into_iter()
            .map(|f| f.id)
            .collect();
        // before and after the findings, or once when the final model is the baseline
        let pair = ["resid-time-before", "resid-time-after"];
        assert!(
            pair.iter().all(|p| ids.iter().any(|i| i == p))
                || (j["findings"].as_array().unwrap().is_empty()
                    && ids.iter().any(|i| i == "resid-time-model")),
            "{ids:?}"
        );
        if name == "clean" {
            assert_eq!(j["verdict"], "none");
            assert!(j["findings"].as_array().unwrap().is_empty());
            assert!(j["unexplained"].is_null());
        } else {
            let f = &j["findings"][0];
            assert_eq!(f["effect"], "temp_rate");
            for k in [
                "axes",
                "form",
                "parameters",
                "uncertainties",
                "delta_bic",
                "share",
                "heldout_gain",
                "reproduced",
                "evidence",
            ] {
                assert!(f.get(k).is_some(), "finding.{k} missing");
            }
            assert_eq!(f["reproduced"], true);
            assert_eq!(j["verdict"], "explained");
            assert!(
                j["final"]["heldout_chi2_after"].as_f64()
                    < j["final"]["heldout_chi2_before"].as_f64()
            );
        }
    }
}

/// A settling after each stop large enough that the catalogue's search leaves the
/// baseline at a low order (the blind suite's seed 3: quadratic): the term explains the
/// excess there but cannot leave its region at the floor, and is judged again at the
/// order chosen with it (quartic), its time constant profiled again: named on its axis
/// with the truth's time constant, the rest at the floor; on the suite's even 1 Hz clock
/// and on a logger's uneven one (0.1 Hz at rest, rows jittered by up to 0.5 s, 1 % lost).
#[test]
fn a_term_is_judged_at_the_baseline_order_chosen_with_it() {
    use host_fit::blind::beyond::Expressed;
    use host_fit::diagnose::parameters::Quantity;
    let case = Case::of_form(Form::Expressed(Expressed::StopSettle), 3);
    let even = host_fit::blind::configure(&case);
    let truth = even.effects.stop_settle.unwrap();
    let axis = (0..3).find(|&i| truth.d_v[i] != 0.0).unwrap();
    let o = run(&case);
    assert!(o.passed(), "{}", o.note);
    let uneven = logged_unevenly(&even);
    for (clock, cfg) in [("even", &even), ("uneven", &uneven)] {
        let c = diagnose(&recording(cfg)).unwrap().contract();
        let [f] = c.findings.as_slice() else {
            panic!("{clock}: one finding\n{}", c.text())
        };
        assert_eq!(
            (
                f.effect,
                f.reproduced,
                f.term
                    .as_ref()
                    .map(|t| matches!(t.factors(), [Factor::Decay(Event::Stop, _)]))
            ),
            (EffectId::Discovered, true, Some(true)),
            "{clock}: {}",
            c.text()
        );
        assert_eq!(f.axes, [["x", "y", "z"][axis]], "{clock}: {}", c.text());
        let tau = f
            .parameters
            .get(Quantity::Tau {
                pole: 1,
                axis: None,
            })
            .unwrap_or_else(|| panic!("{clock}: a time constant\n{}", c.text()));
        let ratio = tau.value / truth.tau_s;
        assert!(
            (0.9..=1.1).contains(&ratio),
            "{clock}: {:.0} +- {:.0} s, {ratio:.2} of the truth's {:.0} s",
            tau.value,
            tau.sigma,
            truth.tau_s
        );
        println!(
            "{clock}: {} {:.0} +- {:.0} s (truth {:.0} s), {:?}",
            f.term.as_ref().map(ToString::to_string).unwrap_or_default(),
            tau.value,
            tau.sigma,
            truth.tau_s,
            c.verdict
        );
    }
    // at the floor (0.87x measured; the pass rule allows 1.5x, the miss was 10.7x)
    assert!(
        o.final_over_noise <= 1.2,
        "{:.2}x the floor",
        o.final_over_noise
    );
}

/// A sudden bias shift mid-test is not in the catalogue: no catalogue name, the verdict
/// says so, and the residual is located on the shifted axis, after the shift.
#[test]
fn an_effect_outside_the_catalogue_is_unexplained_and_located() {
    let case = Case::of_form(Form::Outside(Outside::BiasStep), 1);
    let cfg = host_fit::blind::configure(&case);
    let step = cfg.effects.bias_step.unwrap();
    let axis = (0..3).find(|&i| step.value[i] != 0.0).unwrap();
    let rec = recording(&cfg);
    let d = diagnose(&rec).unwrap();
    let c = d.contract();
    assert!(
        c.findings.is_empty() && c.ambiguous.is_empty(),
        "{}",
        c.text()
    );
    assert_eq!(c.verdict, Verdict::Unexplained, "{}", c.text());
    // neither phase found anything: the library's ended with nothing passing
    assert_eq!(
        d.search_ended.library,
        host_fit::diagnose::search::Termination::LibraryNothingPassed,
        "{:?}",
        d.search_ended
    );
    let u = c.unexplained.as_ref().unwrap();
    assert_eq!(u.located[0].axis, ["x", "y", "z"][axis], "{}", c.text());
    // the time spans on that axis: the residual steps by the shift's sign between the
    // spans before it and those after (the baseline's offset sits between the levels)
    let ax = ["x", "y", "z"][axis];
    let spans: Vec<(f64, f64, f64)> = d
        .unexplained
        .iter()
        .filter(|h| h.group == Grouping::Time && h.axis == ax)
        .map(|h| {
            let (a, b) = h.value.trim_end_matches(" h").split_once('-').unwrap();
            (
                a.parse::<f64>().unwrap() * 3600.0,
                b.parse::<f64>().unwrap() * 3600.0,
                h.mean,
            )
        })
        .collect();
    let before: Vec<f64> = spans
        .iter()
        .filter(|s| s.1 <= step.at_s)
        .map(|s| s.2)
        .collect();
    let after: Vec<f64> = spans
        .iter()
        .filter(|s| s.0 >= step.at_s)
        .map(|s| s.2)
        .collect();
    assert!(!before.is_empty() && !after.is_empty(), "{spans:?}");
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let jump = mean(&after) - mean(&before);
    assert_eq!(jump.signum(), step.value[axis].signum(), "{spans:?}");
    assert!(jump.abs() > 0.3 * step.value[axis].abs(), "{spans:?}");
}

/// One physics: the blob `diagnose --out` writes is compensated by firmware-core, sample
/// by sample in f32, to the fitted model's own dg in every static window of the
/// recording with the catalogue's in-flight effects.
#[test]
fn the_flashed_model_reaches_the_fits_own_residual_in_firmware() {
    let text = std::fs::read_to_string(repo().join("examples/sim/in-flight-effects.toml")).unwrap();
    let cfg = host_fit::simulate::parse_config(std::path::Path::new("x.toml"), &text).unwrap();
    let rec = recording(&cfg);
    let d = diagnose(&rec).unwrap();
    let (n, rms_fw, rms_fit, worst) = in_firmware(&rec, &d);
    println!("{n} windows: dg rms {rms_fw:.4} mg in firmware, {rms_fit:.4} mg by the fit; largest difference {worst:.4} mg");
    assert!(n > 50);
    assert!(
        rms_fw <= 1.1 * rms_fit + 0.001,
        "firmware {rms_fw} mg vs fit {rms_fit} mg"
    );
    assert!(worst < 0.005, "a window differs by {worst} mg");
}

/// The diagnosis's flashed model compensated by firmware-core sample by sample in f32
/// over the recording `d` diagnosed: the static windows, the rms of their dg in firmware
/// and by the fit (mg), and the largest difference of one window's.
fn in_firmware(rec: &Recording, d: &host_fit::diagnose::Diagnosis<'_>) -> (usize, f64, f64, f64) {
    use firmware_core::compensate::{Compensator, Method};
    let mut cal = d.calibration(rec.t0_c).unwrap().convert::<f32>();
    // the model itself: the cache of N(T) (0.1 C steps, a stated 0.03 mg) aside
    cal.update_step_c = 0.0;
    assert!(cal.physics.is_some());
    let data = &d.data;
    let fit_dg = host_fit::model::metrics::dg_per_window(data, &d.flashed.fit);
    let mut comp = Compensator::new(&cal, Method::CorrectConstants, 1.0).unwrap();
    let accel: Vec<[f64; 3]> = rec
        .rows
        .iter()
        .zip(rec.clock())
        .map(|(r, c)| {
            if let Some(on) = c.power_on_s {
                comp.power_on(on as f32);
            }
            comp.compensate_dt(r.u.map(|v| v as f32), r.temp_c as f32, c.dt_s as f32)
                .accel
                .map(f64::from)
        })
        .collect();
    let (mut worst, mut n, mut ss_fw, mut ss_fit) = (0.0f64, 0, 0.0, 0.0);
    for (o, fit) in data.obs.iter().zip(&fit_dg) {
        let Some(fit) = fit else { continue };
        let rows = (o.start..o.end).filter(|k| data.spikes.binary_search(k).is_err());
        let (mut a, mut m) = ([0.0; 3], 0.0);
        for k in rows {
            for i in 0..3 {
                a[i] += accel[k][i];
            }
            m += 1.0;
        }
        let fw = ((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt() / m - 1.0) * 1e3;
        worst = worst.max((fw - fit).abs());
        ss_fw += fw * fw;
        ss_fit += fit * fit;
        n += 1;
    }
    let (rms_fw, rms_fit) = ((ss_fw / n as f64).sqrt(), (ss_fit / n as f64).sqrt());
    (n, rms_fw, rms_fit, worst)
}

/// A gradual hysteresis (a play operator: the offset moves linearly over 10 C after each
/// reversal) is not a relay: the relay's best threshold left a triangle after each
/// reversal, and on this unit a rate term took it (`temp_rate` named, partly explained).
/// It is named `hysteresis` in its play form, with a width near the truth's, on an even
/// and a logger's uneven clock; its blob flashes the play operator (a negative
/// threshold) and firmware-core compensates the recording to the fit's own dg.
#[test]
fn a_gradual_hysteresis_is_named_and_flashed_as_a_play_operator() {
    use host_fit::blind::forms::OtherForm;
    use host_fit::diagnose::parameters::Quantity;
    let case = Case::of_form(Form::Other(OtherForm::HysteresisPlay), 3);
    let even = host_fit::blind::configure(&case);
    let width = even.effects.hysteresis_play_c.unwrap();
    let uneven = logged_unevenly(&even);
    for (clock, cfg) in [("even", &even), ("uneven", &uneven)] {
        let rec = recording(cfg);
        let d = diagnose(&rec).unwrap();
        let c = d.contract();
        let [f] = c.findings.as_slice() else {
            panic!("{clock}: one finding\n{}", c.text())
        };
        assert_eq!(
            (f.effect, f.reproduced, c.verdict),
            (EffectId::Hysteresis, true, Verdict::Explained),
            "{clock}: {}",
            c.text()
        );
        let w = f
            .parameters
            .get(Quantity::PlayWidth)
            .unwrap_or_else(|| panic!("{clock}: a play width\n{}", c.text()))
            .value;
        // the width is profiled on a grid (6, 8, 16 C): within a factor 2
        assert!(
            (0.5..=2.0).contains(&(w / width)),
            "{clock}: {w} C for {width:.1} C"
        );
        let cal = d.calibration(rec.t0_c).unwrap();
        let th = cal.physics.map(|p| p.hysteresis_threshold_c);
        assert_eq!(th, Some(-w / 2.0), "{clock}: the flashed threshold");
        let (n, rms_fw, rms_fit, worst) = in_firmware(&rec, &d);
        println!(
            "{clock}: play over {w} C (truth {width:.1} C); {n} windows, dg rms {rms_fw:.4} mg in firmware, {rms_fit:.4} mg by the fit, largest difference {worst:.4} mg"
        );
        assert!(n > 50);
        assert!(
            rms_fw <= 1.1 * rms_fit + 0.001,
            "{clock}: firmware {rms_fw} mg vs fit {rms_fit} mg"
        );
        assert!(worst < 0.005, "{clock}: a window differs by {worst} mg");
    }
}

/// Input forms users have: a dwell-averaged recording (one row per dwell) and a
/// single-temperature one are diagnosed, each saying what it cannot judge.
#[test]
fn dwell_means_and_one_temperature_are_diagnosed_within_what_they_tell() {
    let mut k2 = Case::catalogue(vec![EffectId::NonlinearityK2], 1.0, 2);
    k2.seed = 2;
    let mut averaged = host_fit::blind::configure(&k2);
    averaged.schedule.dwell_means = true;
    let mut one = host_fit::blind::configure(&k2);
    one.schedule.stops.truncate(1);
    for (cfg, note) in [
        (averaged, NoteKind::OneSamplePerDwell),
        (one, NoteKind::OneTemperature),
    ] {
        let rec = recording(&cfg);
        let d = diagnose(&rec).unwrap();
        let c = d.contract();
        let found: Vec<EffectId> = c.findings.iter().map(|f| f.effect).collect();
        assert_eq!(found, [EffectId::NonlinearityK2], "{}", c.text());
        assert!(c.quality.iter().any(|q| q.kind == note), "{}", c.text());
        assert!(
            c.not_identifiable.iter().any(|n| n.contains("temp_rate")),
            "{}",
            c.text()
        );
    }
}

/// What makes a diagnosis of real data credible: the worst |dg| is not made worse, the
/// held-out chunks improve (or stay, with nothing found), and every finding reproduces on
/// both halves of the recording.
fn credible(j: &Value) {
    let f = &j["final"];
    assert!(
        f["max_abs_dg_mg"].as_f64() <= j["baseline"]["max_abs_dg_mg"].as_f64(),
        "{j}"
    );
    assert!(
        f["heldout_chi2_after"].as_f64() <= f["heldout_chi2_before"].as_f64(),
        "{j}"
    );
    for x in j["findings"].as_array().unwrap() {
        assert_eq!(x["reproduced"], true, "{x}");
    }
}

#[test]
fn real_tag_recording() {
    let j = real("cats-tag", &["--positions", "{dir}/positions.csv"]);
    credible(&j);
    assert!(j["not_identifiable"]
        .as_array()
        .unwrap()
        .iter()
        .any(|n| n.as_str().unwrap().contains("cross-sensitivities")));
    // the tilted Y_AXIS period: a fixture-like error of that orientation, and more left
    let found: Vec<&str> = j["findings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["effect"].as_str().unwrap())
        .collect();
    assert!(found.contains(&"fixture_error"), "{j}");
    assert_eq!(j["verdict"], "partly_explained");
}

#[test]
fn real_wrist_recording_with_its_orientations_unknown() {
    let j = real(
        "ggir-wrist",
        &[
            "--positions",
            "{dir}/positions.csv",
            "--unknown-orientations",
        ],
    );
    credible(&j);
    assert_ne!(j["verdict"], "explained", "{j}");
}

#[test]
fn real_hand_tumble_at_one_temperature() {
    let j = real("imucal-ferraris", &[]);
    credible(&j);
    assert!(
        j["quality"]
            .as_array()
            .unwrap()
            .iter()
            .any(|q| q["kind"] == "one_temperature"),
        "{j}"
    );
    for x in j["findings"].as_array().unwrap() {
        let e = x["effect"].as_str().unwrap();
        assert!(
            ["nonlinearity_k2", "scale_asymmetry", "fixture_error"].contains(&e),
            "{e}"
        );
    }
}

/// The book's figure on the extended model (docs/diagnosis.md): every dwell within 0.05 mg with the terms.
#[test]
fn extended_model_in_the_blob_compensates_better_in_firmware() {
    let (a, b, line) = tests::figures::physics_blob();
    println!("{line}");
    tests::readme::same("physics-blob", &line);
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    assert!(worst(&a) <= 0.05, "{line}");
    assert!(mean(&b) >= 20.0 * mean(&a), "{line}");
    assert!(worst(&b) > 0.5, "{line}");
}
