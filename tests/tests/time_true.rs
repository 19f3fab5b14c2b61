//! The diagnosed physics on the unit's own clock (issue 22): a blob from `diagnose --out`
//! compensates, through firmware-core on each recording's own clock, as the diagnosis
//! fitted it, on an uneven logger clock, at any MCU rate, and in flight.
//!
//! The twin here logs unevenly (1 Hz in the dwells, 0.1 Hz while the unit rests through
//! ramps and soaks, rows up to 0.3 s late, 1% of rows lost, a stated power-off), and
//! writes a flight-like recording of the same unit (a cold power-on, fast warming and
//! cooling both ways, a second power cycle, 24 attitudes over the sphere held 40 s, at
//! an MCU rate).
use host_fit::model::effects::EffectId;
use host_fit::simulate::{PerAxis, SimConfig, Warmup};
use tests::time_true::{
    diagnosed_in_flight, found, noiseless_flight, on_plan_sweep, production, s, table, verify,
    write,
};
use tests::{cli, cli_json};

/// The stated bounds (mg): a diagnosed blob through firmware-core on its own recording
/// reaches the diagnosis's own final max |dg| within [`OWN_BOUND_MG`]; in flight it
/// compensates within [`FLIGHT_BOUND_MG`] (the aim: 0.05 mg) and no worse than the plain
/// `fit` blob; a clean unit's default `fit` reaches the plain least-squares reference
/// (the quartic, no cache) within [`REFERENCE_BOUND_MG`].
const OWN_BOUND_MG: f64 = 0.01;
/// See [`OWN_BOUND_MG`].
const FLIGHT_BOUND_MG: f64 = 0.06;
/// See [`OWN_BOUND_MG`].
const REFERENCE_BOUND_MG: f64 = 0.002;
/// In flight, a unit with two coupled effects (a pair of the table: `thermal_lag` +
/// `temp_rate`, `hysteresis` + `temp_rate`) within this (mg), the aim, and no worse than
/// the plain `fit` blob. The hysteresis + rate unit reaches it since the flight's rate
/// estimator keeps the diagnosed `r` (it was 0.139 mg with `r` refitted beside the
/// hysteresis); the lag + rate unit since that estimator is the zero-lag one (0.059 mg
/// with a 2-s low-pass, which trails the rate by 2 s where the case turns a ramp; 0.084
/// before the host crossed the production test's power-off along the sensor's bend,
/// `model::regressors::Cubic`).
const PAIR_FLIGHT_BOUND_MG: f64 = 0.05;
/// "No worse than the `fit` blob" up to this (mg): where `fit` itself takes the dynamic
/// route (a lagging unit's dwells still settle) both blobs carry the same lag and tie.
const TIE_MG: f64 = 0.001;

#[test]
fn diagnosed_blobs_compensate_as_fitted_on_an_uneven_clock_and_in_flight() {
    let (rows, text) = table();
    println!("{text}");
    tests::readme::same("time-true", &text);
    let mut failed = Vec::new();
    for (effect, [own, fw, fd, fp]) in rows {
        if fw > own + OWN_BOUND_MG {
            failed.push(format!(
                "{effect}: the blob {fw:.4} mg on its recording, the diagnosis {own:.4} mg"
            ));
        }
        let bound = if effect.contains('+') {
            PAIR_FLIGHT_BOUND_MG
        } else {
            FLIGHT_BOUND_MG
        };
        if fd > bound || fd > fp + TIE_MG {
            failed.push(format!(
                "{effect}: in flight {fd:.4} mg, the plain fit blob {fp:.4} mg"
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// A clean unit on the uneven clock: `fit` with its default options (the cache step
/// chosen from the unit's slopes) reaches the plain least-squares reference, the quartic
/// the unit is, evaluated at every temperature (no cache).
#[test]
fn a_clean_unit_reaches_the_plain_least_squares_reference_with_default_options() {
    let dir = tempfile::tempdir().unwrap();
    let mut worst = Vec::new();
    for seed in [11, 12, 13] {
        let (rec, _) = write(
            dir.path(),
            &format!("clean{seed}"),
            &production("clean", seed),
        );
        let b = dir.path().join("b.blob");
        let one = |args: &[&str]| {
            let mut all = vec!["fit", s(&rec), "--out", s(&b), "--force", "--json"];
            all.extend(args);
            cli_json(&all);
            verify(&rec, None, &b).0
        };
        let default = one(&[]);
        let reference = one(&["--model", "poly", "--order", "4", "--update-step", "0"]);
        let cached_01 = one(&["--update-step", "0.1"]);
        println!("seed {seed}: default {default:.4} mg, reference {reference:.4} mg, with a 0.1 C cache step {cached_01:.4} mg");
        worst.push((default, reference));
    }
    for (d, r) in worst {
        assert!(
            d <= r + REFERENCE_BOUND_MG,
            "default {d} mg vs reference {r} mg"
        );
    }
}

/// A unit with three in-flight effects at once (lag, rate, warm-up), its production test
/// on the uneven clock.
fn dynamic_unit() -> SimConfig {
    let mut c = production("dynamic", 21);
    c.effects.thermal_lag = Some(PerAxis { value: [500.0; 3] });
    c.effects.temp_rate = Some(PerAxis {
        value: [0.02, 0.0, -0.012],
    });
    c.effects.warmup_drift = Some(Warmup {
        d_v: [2e-4, 0.0, -1.5e-4],
        tau_s: 900.0,
    });
    c
}

/// A short flight of [`dynamic_unit`] (a cold start, a power cycle of the sensor, a
/// warming at 8 C/min; 12 attitudes held 20 s) at an MCU rate, the voltmeter and the
/// temperature sensor noiseless so that only the clock differs.
fn short_flight(rate_hz: f64) -> SimConfig {
    let legs = [(-30.0, 1.0, 120.0), (10.0, 8.0, 120.0)];
    noiseless_flight(dynamic_unit(), rate_hz, &legs, vec![[60.0, 30.0]])
}

/// The same blob compensates the same flight alike sampled at 10 Hz, 100 Hz and 1 kHz:
/// every held attitude's |dg| within [`RATES_BOUND_MG`] of the 10 Hz one (the machines
/// step on about 0.1 s at every rate; between steps the 1 kHz outputs hold). The blob is
/// the one `diagnose --out` writes for the unit (its tables and the lag it finds: with
/// three effects at once the diagnosis names the lag only), its rate and warm-up terms
/// set to the unit's true ones, so that every machine runs.
const RATES_BOUND_MG: f64 = 0.002;

#[test]
fn ten_hundred_and_thousand_hertz_compensate_alike() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, _) = write(dir.path(), "dynamic", &dynamic_unit());
    let blob = dir.path().join("dynamic.blob");
    let d = cli_json(&["diagnose", s(&rec), "--out", s(&blob), "--json", "--force"]);
    assert_eq!(d["blob"]["physics"], true, "{d}");
    let mut b = firmware_core::blob::Blob::decode(&std::fs::read(&blob).unwrap()).unwrap();
    let p = b.calibration.physics.as_mut().unwrap();
    assert!(p.lag_tau_s > 400.0 && p.lag_tau_s < 600.0, "{p:?}");
    p.rate = [0.02, 0.0, -0.012];
    // the flight's estimator (zero-lag over 4 s), what `diagnose --out` flashes
    p.rate_tau_s = -4.0;
    p.warmup = [2e-4, 0.0, -1.5e-4];
    p.warmup_tau_s = 900.0;
    let mut buf = [0u8; firmware_core::blob::MAX_BLOB_LEN];
    let n = b.encode(&mut buf).unwrap();
    std::fs::write(&blob, &buf[..n]).unwrap();
    let runs: Vec<Vec<f64>> = [10.0, 100.0, 1000.0]
        .iter()
        .map(|hz| {
            let (f, pos) = write(dir.path(), &format!("flight-{hz}"), &short_flight(*hz));
            let (worst, dg) = verify(&f, pos.as_deref(), &blob);
            println!(
                "{hz} Hz: {} held attitudes, worst |dg| {worst:.4} mg",
                dg.len()
            );
            dg
        })
        .collect();
    let mut diff: f64 = 0.0;
    for r in &runs[1..] {
        assert_eq!(r.len(), runs[0].len());
        for (a, b) in r.iter().zip(&runs[0]) {
            diff = diff.max((a - b).abs());
        }
    }
    println!("largest difference from 10 Hz: {diff:.5} mg");
    assert!(diff <= RATES_BOUND_MG, "{diff} mg");
}

/// A blob of format 3 (the committed bytes of the paper unit) is refused by every
/// command that reads blobs, its version named.
#[test]
fn a_format_3_blob_is_refused_by_version() {
    let dir = tempfile::tempdir().unwrap();
    let hex =
        std::fs::read_to_string(tests::repo().join("firmware-core/tests/data/example_blob_v3.hex"))
            .unwrap();
    let digits: Vec<u8> = hex.bytes().filter(u8::is_ascii_hexdigit).collect();
    let bytes: Vec<u8> = digits
        .chunks(2)
        .map(|p| u8::from_str_radix(std::str::from_utf8(p).unwrap(), 16).unwrap())
        .collect();
    let b = dir.path().join("old.blob");
    std::fs::write(&b, bytes).unwrap();
    let (rec, _) = write(dir.path(), "clean", &production("clean", 5));
    for args in [
        vec!["inspect", s(&b)],
        vec!["verify", s(&rec), "--blob", s(&b)],
    ] {
        let (code, _, err) = cli(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.contains("unsupported blob format version 3 (this firmware reads versions 4 to 5)"),
            "{err}"
        );
    }
}

/// The blob records the recording's output unit (format 4, byte 15): `fit` and
/// `diagnose --out` write it, `inspect` prints it.
#[test]
fn blobs_record_the_output_unit() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, _) = write(dir.path(), "unit", &production("clean", 3));
    let text = std::fs::read_to_string(&rec).unwrap();
    // the outputs in mV, as the label says (a V recording labelled mV is refused at the
    // door: its outputs change by 0.55 per g, not 550)
    let mv: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.starts_with("t_s") {
                return l.to_string();
            }
            let mut f: Vec<String> = l.split(',').map(String::from).collect();
            let n = f.len();
            for x in &mut f[n - 3..] {
                *x = format!("{}", 1000.0 * x.parse::<f64>().unwrap());
            }
            f.join(",")
        })
        .collect();
    let labelled = dir.path().join("labelled.csv");
    std::fs::write(&labelled, format!("# output_unit=mV\n{}\n", mv.join("\n"))).unwrap();
    for (cmd, blob) in [("fit", "fit.blob"), ("diagnose", "diag.blob")] {
        let b = dir.path().join(blob);
        cli_json(&[cmd, s(&labelled), "--out", s(&b), "--json", "--force"]);
        let j = cli_json(&["inspect", s(&b), "--json"]);
        assert_eq!(j["output_unit"], "mV", "{cmd}: {j}");
        assert_eq!(j["format_version"], 4);
        let (_, out, _) = cli(&["inspect", s(&b)]);
        assert!(out.contains("K in mV per g, U0 in mV"), "{out}");
    }
}

/// The rate units over seeds 1-7 of the production twin (noise only differs), each
/// diagnosed blob in flight: the rate alone and the lag + rate unit within the aim of
/// 0.05 mg on every seed (the lag + rate unit's seed 4 flew at 0.073 mg while a quintic of
/// all twelve coefficients was the only order above the stops' count, see
/// docs/diagnosis.md), and the hysteresis + rate unit too (it flew at 0.036-0.059 mg, 2 of
/// 7, while the diagnosis described the rate through a causal low-pass, which trails the
/// case where it turns a ramp: the fit took the trail into the hysteresis and `r_x` came
/// out 0.9888 +- 0.0025 of the unit's; the centred slope, `regressors::centred_rates`,
/// does not trail). On every unit the mean `r_x` over the seeds is within 3 sigma of the
/// unit's.
#[test]
#[ignore = "full tier (cargo xtask test --full): 21 diagnoses and flights, 3 CPU-minutes"]
fn rate_units_fly_within_the_aim_over_seeds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut failed = Vec::new();
    for effect in ["temp_rate", "thermal_lag+temp_rate", "hysteresis+temp_rate"] {
        let (mut line, mut rates) = (Vec::new(), Vec::new());
        for seed in 1..=7u64 {
            let unit = production(effect, seed);
            let (flown, j) = diagnosed_in_flight(d, &unit, unit.clone());
            line.push(flown);
            rates.extend(rate_x_over_truth(&j, &unit));
            // the diagnosis says where the split rests on the ramps (the hysteresis's)
            let coupled = j["coupled"].as_array().map_or(0, Vec::len);
            if coupled != usize::from(effect.starts_with("hysteresis")) {
                failed.push(format!("{effect} seed {seed}: coupled {}", j["coupled"]));
            }
        }
        let (within, text) = within_aim(&line);
        println!("{effect}: {text} mg, {within} of 7 within 0.05 mg");
        // the split (docs/diagnosis.md), held below
        let (mean, sigma) = mean_and_sigma(&rates);
        println!(
            "{effect}: r_x / truth over {} seeds {mean:.4} +- {sigma:.4}",
            rates.len()
        );
        if within < 7 {
            failed.push(format!("{effect}: {within} of 7 within 0.05 mg ({text})"));
        }
        if (mean - 1.0).abs() > 3.0 * sigma {
            failed.push(format!("{effect}: r_x / truth {mean:.4} +- {sigma:.4}"));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// What separates a hysteresis from a rate term (issue 27): on the production schedule
/// every stop is reached from below, so after the first ramp the hysteresis is one
/// constant, told from the temperature polynomial by the cold start alone and from the
/// rate by the ramps (2 of 7 seeds fly within the aim, above). A return from the hot end
/// to a stop already visited (20 C, soaked as the stops are, every position again) shows
/// that temperature from both directions after a soak, where the rate's share is gone:
/// the diagnosed blob then flies within 0.05 mg on at least 6 of the 7 seeds (7 of 7
/// when measured, 0.017-0.034 mg).
#[test]
#[ignore = "full tier (cargo xtask test --full): 7 diagnoses and flights, 1 CPU-minute"]
fn a_return_to_a_visited_stop_separates_hysteresis_from_rate() {
    use host_fit::simulate::config::Stop;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let effect = "hysteresis+temp_rate";
    let (mut line, mut rates) = (Vec::new(), Vec::new());
    for seed in 1..=7u64 {
        let mut c = production(effect, seed);
        let hot = c.schedule.stops.last().map(|s| s.temp_c);
        assert_eq!(hot, Some(70.0), "the schedule ends at its hot end");
        let back = c.schedule.stops[2].clone();
        assert_eq!(back.temp_c, 20.0);
        c.schedule.stops.push(Stop {
            positions: None,
            ..back
        });
        let (flown, j) = diagnosed_in_flight(d, &c, production(effect, seed));
        let rate = rate_x_over_truth(&j, &c);
        rates.push(rate.unwrap_or_else(|| panic!("seed {seed}: no temp_rate r_x in {j}")));
        // 20 C seen at rest from both directions: no longer reported coupled
        assert_eq!(j["coupled"], serde_json::json!([]), "seed {seed}");
        let found: Vec<&str> = j["findings"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|f| f["effect"].as_str())
            .collect();
        assert!(
            found.contains(&"hysteresis"),
            "seed {seed}: found {found:?}"
        );
        line.push(flown);
    }
    let (within, text) = within_aim(&line);
    println!("{effect} with a return to 20 C: {text} mg, {within} of 7 within 0.05 mg");
    assert!(within >= 6, "{within} of 7 within 0.05 mg ({text})");
    // the split itself: the diagnosed rate is the unit's within what its own stated
    // uncertainty allows for the mean of seven seeds (on the production test alone it is
    // not: printed by `rate_units_fly_within_the_aim_over_seeds`)
    let (mean, sigma) = mean_and_sigma(&rates);
    println!("{effect} with a return to 20 C: r_x / truth over the seeds {mean:.4} +- {sigma:.4}");
    assert!(
        (mean - 1.0).abs() <= 3.0 * sigma,
        "r_x / truth {mean:.4} +- {sigma:.4} over the seeds"
    );
}

/// A power cycle in the middle of a ramp does not hide a hysteresis beside a rate. On
/// `plan`'s 1.5 C/min sweep (10-min holds) the unit's power-off (8400-9000 s) falls in the
/// cooling ramp; the diagnosis's rate regressor once stayed at 0 for 20 s after the
/// power-on, as the firmware's flight estimator does, though the unit feels the ramp at
/// once: the rate's whole effect left there (80x the floor) made the hysteresis look
/// inadequate where it acts, and the diagnosis named the rate alone (3 of 3 seeds; the
/// blob then flew 0.33 mg). Held by one seed here; the flights by the full tier below.
#[test]
fn a_power_on_in_a_ramp_leaves_the_hysteresis_beside_the_rate() {
    let dir = tempfile::tempdir().unwrap();
    let unit = production("hysteresis+temp_rate", 1);
    let c = on_plan_sweep(&unit, 1.5, 10.0);
    let off = c.schedule.power_offs[0][0];
    let at = |t: f64| {
        let k = c
            .schedule
            .program
            .iter()
            .rposition(|p| p.time_s <= t)
            .unwrap();
        c.schedule.program[k].setpoint_c
    };
    assert!(
        at(off + 300.0) < at(off) - 5.0,
        "the power-off falls in a ramp"
    );
    let (rec, _) = write(dir.path(), "sweep", &c);
    let j = cli_json(&["diagnose", s(&rec), "--json"]);
    let names = found(&j);
    assert!(
        names.contains(&EffectId::Hysteresis) && names.contains(&EffectId::TempRate),
        "found {names:?}"
    );
    // the sweep's dwells at rest see temperatures on both branches: not coupled
    assert_eq!(j["coupled"], serde_json::json!([]));
}

/// The blobs diagnosed from `plan`'s 1.5 C/min sweep, the power cycled in its cooling
/// ramp, name the hysteresis on every seed and fly within 0.05 mg on at least 2 of 3
/// (3 of 3 when measured: 0.028, 0.034, 0.030 mg; 0.33 mg each, the rate alone named,
/// before the rate regressor felt the ramp at a power-on).
#[test]
#[ignore = "full tier (cargo xtask test --full): 3 diagnoses and flights, 1 CPU-minute"]
fn a_sweep_with_a_power_cycle_in_its_ramp_flies_within_the_aim() {
    let dir = tempfile::tempdir().unwrap();
    let effect = "hysteresis+temp_rate";
    let mut line = Vec::new();
    for seed in 1..=3u64 {
        let unit = production(effect, seed);
        let (flown, j) = diagnosed_in_flight(dir.path(), &on_plan_sweep(&unit, 1.5, 10.0), unit);
        assert!(
            found(&j).contains(&EffectId::Hysteresis),
            "seed {seed}: found {:?}",
            found(&j)
        );
        line.push(flown);
    }
    let (within, text) = within_aim(&line);
    println!("{effect} on a 1.5 C/min sweep, a power cycle in its ramp: {text} mg");
    assert!(within >= 2, "{within} of 3 within 0.05 mg ({text})");
}

/// A hysteresis beside a lag on the production test (every stop from below) is reported
/// `coupled` like the hysteresis beside a rate, now with the correlation of the
/// hysteresis with the lag's time constants (through the lag's profile; it was null):
/// large (-0.74 on x, -0.62 on y, seed 1), yet the split holds, since the lag acts on all
/// 12 coefficients through their slopes and is pinned by them (the rate, by contrast,
/// moves the offsets alone). Over seeds 1-7: both named; the correlation on x and y
/// (where the hysteresis acts) negative, from 0.5 to 0.85 in size (measured -0.73 to
/// -0.74 on x, -0.59 to -0.62 on y), none on z; tau and h_x, h_y within 3 sigma of the
/// unit's (tau measured within 0.2 %); the blob within 0.05 mg in flight on every seed
/// and no worse than the `fit` blob (which has no hysteresis).
#[test]
#[ignore = "full tier (cargo xtask test --full): 7 diagnoses and fits, 14 flights judged, 15 s"]
fn a_hysteresis_beside_a_lag_is_coupled_yet_split_as_the_unit_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let effect = "hysteresis+thermal_lag";
    let mut failed = Vec::new();
    let (mut line, mut plain_line) = (Vec::new(), Vec::new());
    for seed in 1..=7u64 {
        let unit = production(effect, seed);
        let (flown, j) = diagnosed_in_flight(d, &unit, unit.clone());
        let mut names = found(&j);
        names.sort_by_key(|e| e.as_str());
        if names != [EffectId::Hysteresis, EffectId::ThermalLag] {
            failed.push(format!("seed {seed}: found {names:?}"));
            continue;
        }
        let c = &j["coupled"];
        let r: Vec<Option<f64>> = (0..3).map(|a| c[0]["correlation"][a].as_f64()).collect();
        let pair_ok = c.as_array().map(Vec::len) == Some(1)
            && c[0]["effects"] == serde_json::json!(["hysteresis", "thermal_lag"])
            && r[0]
                .zip(r[1])
                .is_some_and(|(x, y)| [x, y].iter().all(|r| (-0.85..=-0.5).contains(r)))
            && r[2].is_none();
        if !pair_ok {
            failed.push(format!("seed {seed}: coupled {c}"));
        }
        let finding = |e: &str| {
            j["findings"]
                .as_array()
                .and_then(|a| a.iter().find(|f| f["effect"] == e))
                .cloned()
                .unwrap_or_default()
        };
        let truth_h = unit.effects.hysteresis.map(|h| h.value).unwrap();
        let truth_tau = unit.effects.thermal_lag.map(|t| t.value[0]).unwrap();
        let within = |f: &serde_json::Value, k: &str, truth: f64| {
            let (v, s) = (f["parameters"][k].as_f64(), f["uncertainties"][k].as_f64());
            v.zip(s).is_some_and(|(v, s)| (v - truth).abs() <= 3.0 * s)
        };
        let (h, lag) = (finding("hysteresis"), finding("thermal_lag"));
        for (f, k, truth) in [
            (&h, "h_x", truth_h[0]),
            (&h, "h_y", truth_h[1]),
            (&lag, "tau_s", truth_tau),
        ] {
            if !within(f, k, truth) {
                failed.push(format!(
                    "seed {seed}: {k} {} +- {} for {truth}",
                    f["parameters"][k], f["uncertainties"][k]
                ));
            }
        }
        println!(
            "seed {seed}: correlation {r:?}, tau {} s",
            lag["parameters"]["tau_s"]
        );
        // the production and flight recordings `diagnosed_in_flight` wrote
        let (rec, plain) = (d.join("p.csv"), d.join("plain.blob"));
        cli_json(&["fit", s(&rec), "--out", s(&plain), "--json", "--force"]);
        let pos = d.join("f-positions.csv");
        let (by_fit, _) = verify(&d.join("f.csv"), Some(&pos), &plain);
        if flown > PAIR_FLIGHT_BOUND_MG || flown > by_fit + TIE_MG {
            failed.push(format!(
                "seed {seed}: {flown} mg in flight, fit's {by_fit} mg"
            ));
        }
        line.push(flown);
        plain_line.push(by_fit);
    }
    println!(
        "{effect} in flight: {} mg (fit: {} mg)",
        within_aim(&line).1,
        within_aim(&plain_line).1
    );
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The diagnosed rate coefficient on x (`r_x` of the `temp_rate` finding) over the
/// unit's truth, and its stated 1-sigma over the truth; `None` without such a finding.
fn rate_x_over_truth(j: &serde_json::Value, unit: &SimConfig) -> Option<(f64, f64)> {
    let truth = unit.effects.temp_rate.map(|r| r.value[0])?;
    let f = j["findings"]
        .as_array()?
        .iter()
        .find(|f| f["effect"] == "temp_rate")?;
    let v = f["parameters"]["r_x"].as_f64()?;
    let s = f["uncertainties"]["r_x"].as_f64()?;
    Some((v / truth, s / truth.abs()))
}

/// The mean of `ratios` (value, sigma) and the sigma of that mean (independent seeds).
fn mean_and_sigma(ratios: &[(f64, f64)]) -> (f64, f64) {
    let n = ratios.len() as f64;
    let mean = ratios.iter().map(|r| r.0).sum::<f64>() / n;
    let var = ratios.iter().map(|r| r.1 * r.1).sum::<f64>() / (n * n);
    (mean, var.sqrt())
}

/// How many of `line`'s flights (mg) are within the aim of 0.05 mg, and the line printed.
fn within_aim(line: &[f64]) -> (usize, String) {
    let within = line.iter().filter(|w| **w <= 0.05).count();
    let text: Vec<String> = line.iter().map(|w| format!("{w:.3}")).collect();
    (within, text.join(" "))
}

/// `unit`'s test replaced by the program `plan --from-diagnosis` writes from the
/// diagnosis of its production recording (files in `d`), and the plan's JSON: the twin
/// starts soaked at the program's cold start after cooling there (hysteresis branch -1).
fn on_its_plan(d: &std::path::Path, unit: &SimConfig) -> (SimConfig, serde_json::Value) {
    let (rec, _) = write(d, "first", unit);
    let dj = d.join("d.json");
    std::fs::write(&dj, cli_json(&["diagnose", s(&rec), "--json"]).to_string()).unwrap();
    let prog = d.join("program.csv");
    let pj = cli_json(&[
        "plan",
        "--from-diagnosis",
        s(&dj),
        "--tau-s",
        "0",
        "--hours",
        "100",
        "--out",
        s(&prog),
        "--force",
        "--json",
    ]);
    let text = std::fs::read_to_string(&prog).unwrap();
    let steps = host_fit::simulate::program::parse_program(&prog, &text).unwrap();
    let mut c = unit.clone();
    c.chamber.start_c = steps[0].setpoint_c;
    c.schedule.program = steps;
    c.effects.hysteresis_initial = Some(-1.0);
    (c, pj)
}

/// `plan --from-diagnosis` for a hysteresis + rate unit (issue 27): the program it writes
/// (a stop-and-soak one ending with its return; a sweep is not chosen), run on the unit's
/// twin, diagnosed with `--out`: the blob flies within 0.05 mg on at least 6 of the 7
/// seeds (7 of 7 when measured, 0.018-0.036 mg). The twin starts soaked at the program's
/// cold start after cooling there (as the production test, which cools from the room,
/// and the flight start): a unit that had warmed to it would show no branch change until
/// the return.
#[test]
#[ignore = "full tier (cargo xtask test --full): 7 diagnoses, plans and flights, 2 CPU-minutes"]
fn the_plan_for_a_hysteresis_and_rate_unit_flies_within_the_aim() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let effect = "hysteresis+temp_rate";
    let mut line = Vec::new();
    for seed in 1..=7u64 {
        let unit = production(effect, seed);
        let (c, pj) = on_its_plan(d, &unit);
        assert_eq!(pj["chosen"]["kind"]["kind"], "stop_soak", "seed {seed}");
        let (flown, j) = diagnosed_in_flight(d, &c, unit);
        // its return shows a temperature from both sides: the split no longer coupled
        assert_eq!(j["coupled"], serde_json::json!([]), "seed {seed}");
        line.push(flown);
    }
    let (within, text) = within_aim(&line);
    println!("{effect} on its plan: {text} mg, {within} of 7 within 0.05 mg");
    assert!(within >= 6, "{within} of 7 within 0.05 mg ({text})");
}

/// A gradual hysteresis in flight (issue 27): a play operator over 10 C (the offsets move
/// linearly over 10 C of travel after each reversal) on three designs: the default
/// production test (cooled from the room to its coldest stop, then every stop from
/// below), the same with a return from the hot end to 20 C, and the program `plan
/// --from-diagnosis` writes from the first's diagnosis (a hysteresis alone asks for no
/// return; the twin starts soaked at the program's cold start after cooling there). Each
/// design shows the play's turn (after the cold end, and after the return): the diagnosis
/// names the hysteresis alone, in its play form; the blob flashes the play operator, and
/// in flight (a cold start, warming and cooling both ways at 5-8 C/min) it compensates
/// within the aim and better than the plain `fit` blob, which carries no hysteresis.
/// Measured: 0.030, 0.033 and 0.034 mg (the plan is a 1.5 C/min sweep, 37-min holds);
/// the `fit` blob 0.228, 0.186 and 0.329 mg. With the relay alone (the profile's grid
/// without the play, a throwaway edit) the diagnosis named a relay at 4 C and its blob
/// flew at 0.051 mg (with the return): a triangle after each reversal.
#[test]
fn a_play_hysteresis_flies_with_its_blob() {
    use host_fit::simulate::config::Stop;
    /// The bench's designs the play is run on.
    #[derive(Debug)]
    enum Design {
        /// The default production test.
        Production,
        /// The same with a return from the hot end to 20 C.
        WithReturn,
        /// The program `plan --from-diagnosis` writes.
        Plan,
    }
    for design in [Design::Production, Design::WithReturn, Design::Plan] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let unit = {
            let mut c = production("hysteresis", 11);
            c.effects.hysteresis_play_c = Some(10.0);
            c
        };
        let c = match design {
            Design::Production => unit.clone(),
            Design::WithReturn => {
                let mut c = unit.clone();
                let back = c.schedule.stops[2].clone();
                assert_eq!(back.temp_c, 20.0);
                c.schedule.stops.push(Stop {
                    positions: None,
                    ..back
                });
                c
            }
            Design::Plan => {
                let (c, pj) = on_its_plan(d, &unit);
                println!("the plan: {}", pj["chosen"]["kind"]);
                c
            }
        };
        // both blobs fly the unit's own flight (the design is the bench's, not the unit's)
        let (flown, j) = diagnosed_in_flight(d, &c, unit.clone());
        assert_eq!(found(&j), [EffectId::Hysteresis], "{design:?}: {j}");
        let params = &j["findings"][0]["parameters"];
        let width = params["play_width_c"].as_f64();
        let (rec, _) = write(d, "p", &c);
        let plain = d.join("plain.blob");
        cli_json(&["fit", s(&rec), "--out", s(&plain), "--json", "--force"]);
        let (f, pos) = write(d, "f", &tests::time_true::in_flight(unit));
        let (fit_flown, _) = verify(&f, pos.as_deref(), &plain);
        println!(
            "play over 10 C on {design:?}, found {width:?} C: the diagnosed blob in flight {flown:.4} mg, the fit blob {fit_flown:.4} mg"
        );
        assert!(
            width.is_some_and(|w| (5.0..=20.0).contains(&w)),
            "{design:?}: the play's width: {params}"
        );
        assert!(
            flown <= PAIR_FLIGHT_BOUND_MG,
            "{design:?}: {flown} mg in flight"
        );
        assert!(
            flown < fit_flown,
            "{design:?}: {flown} mg, the fit blob {fit_flown} mg"
        );
    }
}

/// The hysteresis's stated 1-sigma beside a lag holds its scatter over repeated tests
/// (issue 27): every linear fit holds the lag's time constants at the values found, and
/// the hysteresis's estimate moves with them (their correlation -0.74 on x), so the
/// sigma at a fixed lag said 1.06e-6 where 120 noise seeds of the production test
/// scattered h_x by 1.61e-6; the profile's share is now added. Over 40 seeds of the same
/// unit (only the noise differs): the scatter of h_x and of h_y over the mean stated
/// sigma within 0.75-1.3 (1 +- 2.5 of the ratio's own spread at 40 seeds; the fixed-lag
/// sigma gave 1.5 on x), and the mean of the seeds within 3 standard errors of the
/// truth (the mean stated sigma over sqrt(40)).
#[test]
#[ignore = "full tier (cargo xtask test --full): 40 diagnoses on two threads, 50 s"]
fn the_hysteresis_sigma_beside_a_lag_holds_its_scatter_over_seeds() {
    const SEEDS: u64 = 40;
    let effect = "hysteresis+thermal_lag";
    let run = |seeds: Vec<u64>| {
        let dir = tempfile::tempdir().unwrap();
        seeds
            .into_iter()
            .map(|seed| {
                let (rec, _) = write(dir.path(), "p", &production(effect, seed));
                let j = cli_json(&["diagnose", s(&rec), "--json"]);
                let h = j["findings"]
                    .as_array()
                    .and_then(|a| a.iter().find(|f| f["effect"] == "hysteresis"))
                    .cloned()
                    .unwrap_or_else(|| panic!("seed {seed}: no hysteresis in {j}"));
                ["h_x", "h_y"].map(|k| {
                    (
                        h["parameters"][k].as_f64().unwrap(),
                        h["uncertainties"][k].as_f64().unwrap(),
                    )
                })
            })
            .collect::<Vec<_>>()
    };
    let (odd, even): (Vec<u64>, Vec<u64>) = (1..=SEEDS).partition(|s| s % 2 == 1);
    let other = std::thread::spawn(move || run(even));
    let mut all = run(odd);
    all.extend(other.join().unwrap());
    let truth = production(effect, 1).effects.hysteresis.unwrap().value;
    let n = all.len() as f64;
    let mut failed = Vec::new();
    for (axis, name) in ["h_x", "h_y"].iter().enumerate() {
        let mean = all.iter().map(|a| a[axis].0).sum::<f64>() / n;
        let scatter =
            (all.iter().map(|a| (a[axis].0 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let stated = all.iter().map(|a| a[axis].1).sum::<f64>() / n;
        let ratio = scatter / stated;
        println!("{name}: mean {mean:.4e} (truth {:.4e}), scatter {scatter:.3e}, stated {stated:.3e}, ratio {ratio:.3}", truth[axis]);
        if !(0.75..=1.3).contains(&ratio) {
            failed.push(format!("{name}: scatter over stated sigma {ratio:.3}"));
        }
        if (mean - truth[axis]).abs() > 3.0 * stated / n.sqrt() {
            failed.push(format!("{name}: mean {mean:e} for {:e}", truth[axis]));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}
