//! Calibration from a continuous sweep (issue 19): on the twin, a unit recorded as a
//! sweep of at most 2 h is fitted jointly with its thermal lag (the blob carries it) and
//! passes acceptance on an equilibrium verification block through firmware-core, within
//! 1.5x of the 6-h stop-and-soak test's worst |dg| on the same unit (the better of its
//! static and default fits); the 6-h test of a lagging unit passes too with `fit`'s
//! defaults (its dwells still settle, so the data choose the dynamic route); a unit
//! without lag is given none.
use tests::sweep::three_ways;

/// The sweep's worst verification |dg| within this factor of the 6-h test's.
const HOURS_FACTOR: f64 = 1.5;
/// The fitted lag within this share of the truth.
const LAG_REL: f64 = 0.05;

fn lag_text(t: Option<f64>) -> String {
    t.map_or("none".to_string(), |t| format!("{t:.1}"))
}

#[test]
fn a_two_hour_sweep_calibrates_lagging_units_as_well_as_the_six_hour_test() {
    let dir = tempfile::tempdir().unwrap();
    let mut failed = Vec::new();
    let mut text = String::from(
        "worst verification |dg|, mg      sweep  lag fitted, s   6-h static   6-h default  lag fitted, s\n",
    );
    for (lag_s, seed) in [(0.0, 31), (300.0, 32), (1200.0, 33)] {
        let ([sw, long, long_dyn], hours) = three_ways(dir.path(), lag_s, seed);
        let verdict = |j: &tests::sweep::Judged| if j.pass { "" } else { " (fail)" };
        text.push_str(&format!(
            "element lag {:>2.0} min, sweep {hours:.2} h  {:>7.4}  {:>13}  {:>11}  {:>12}  {:>13}\n",
            lag_s / 60.0,
            sw.worst_mg,
            lag_text(sw.lag_s),
            format!("{:.4}{}", long.worst_mg, verdict(&long)),
            format!("{:.4}{}", long_dyn.worst_mg, verdict(&long_dyn)),
            lag_text(long_dyn.lag_s),
        ));
        println!(
            "lag {:.0} min: sweep ({hours:.2} h) {:.4} mg (pass {}, lag {:?} s); 6-h static {:.4} mg (pass {}); 6-h default {:.4} mg (pass {}, lag {:?} s)",
            lag_s / 60.0,
            sw.worst_mg,
            sw.pass,
            sw.lag_s,
            long.worst_mg,
            long.pass,
            long_dyn.worst_mg,
            long_dyn.pass,
            long_dyn.lag_s
        );
        let best_long = long.worst_mg.min(long_dyn.worst_mg);
        if hours > 2.0 || !sw.pass || sw.worst_mg > HOURS_FACTOR * best_long {
            failed.push(format!(
                "lag {lag_s} s: the sweep ({hours:.2} h) {:.4} mg (pass {}), the 6-h test {best_long:.4} mg",
                sw.worst_mg, sw.pass
            ));
        }
        if !long_dyn.pass {
            failed.push(format!(
                "lag {lag_s} s: the 6-h test with fit's defaults fails ({:.4} mg)",
                long_dyn.worst_mg
            ));
        }
        for (what, j) in [("sweep", sw), ("6-h default", long_dyn)] {
            match (lag_s > 0.0, j.lag_s) {
                (false, Some(t)) => {
                    failed.push(format!("no lag, but the {what} blob carries {t} s"))
                }
                (true, None) => {
                    failed.push(format!("lag {lag_s} s, but the {what} blob carries none"))
                }
                (true, Some(t)) if (t / lag_s - 1.0).abs() > LAG_REL => {
                    failed.push(format!("lag {lag_s} s, the {what} blob carries {t:.1} s"))
                }
                _ => {}
            }
        }
    }
    println!("{text}");
    tests::readme::same("sweep", &text);
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// A 2-h sweep of a unit whose element lags its sensor (528 s) and whose offsets follow
/// the temperature's rate, here as a thermal gradient inside the case (a form beside the
/// route's own rate term), is calibrated: `fit` by default and with `--route dynamic`
/// writes a blob carrying the lag within 1 % of the truth, within the f32 bound, that
/// passes acceptance on the equilibrium block. The route used to profile the lag without
/// a limit: it took 22 000 s on this 2-h recording (the element held near where the sweep
/// started), the temperature model bent to the time instead, into coefficients of 30x
/// their size, and `fit` stopped with "the f32 firmware path departs from the f64 model
/// by 2.594e-1 g ... the unit's K is too ill-conditioned for f32".
#[test]
fn a_two_hour_sweep_of_a_lag_and_rate_unit_is_calibrated() {
    use host_fit::simulate::Gradient;
    use tests::sweep::{judge, sweep, unit};
    use tests::time_true::{s, verify, write};
    const LAG_S: f64 = 528.0;
    let dir = tempfile::tempdir().unwrap();
    let mut u = unit(LAG_S, 41);
    u.effects.temp_gradient = Some(Gradient {
        value: [1e-4, 0.0, -1e-4],
        tau_s: 400.0,
    });
    let (sw, _) = write(dir.path(), "sweep", &sweep(u.clone()));
    let (jd, _) = write(dir.path(), "judge", &judge(u));
    let b = dir.path().join("b.blob");
    for route in ["auto", "dynamic"] {
        let (code, out, err) = tests::cli(&[
            "fit",
            s(&sw),
            "--route",
            route,
            "--out",
            s(&b),
            "--force",
            "--json",
        ]);
        assert_eq!(code, 0, "--route {route}: {err}");
        let j: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(j["route"], "dynamic", "{j}");
        let lag = j["thermal_lag_tau_s"].as_f64().unwrap_or(0.0);
        assert!(
            (lag / LAG_S - 1.0).abs() < 0.01,
            "--route {route}: lag {lag} s: {j}"
        );
        assert!(j["f32_departure_g"].as_f64().unwrap() <= 2e-6, "{j}");
        let (worst, _) = verify(&jd, None, &b);
        let (code, _, _) = tests::cli(&["verify", s(&jd), "--blob", s(&b)]);
        println!(
            "--route {route}: {} lag {lag:.1} s, verified worst {worst:.4} mg",
            j["model"]
        );
        assert_eq!(
            code, 0,
            "--route {route}: fails acceptance, worst {worst:.4} mg"
        );
    }
}
