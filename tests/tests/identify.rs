//! Identification: least squares = formula (10), recovery within the standard errors,
//! too few positions, and the joint fit against the per-stop route under drift.
use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::data::stops::stops;
use host_fit::fit::identify::{formula_10, identify_stop};
use host_fit::fit::noise::noise;
use host_fit::fit::pipeline::{fit_recording, Identification, ModelChoice, ModelKind};
use std::path::Path;
use tests::{synthetic_csv, PAPER_T0, TP};

fn read(csv: &str) -> Recording {
    Recording::from_reader(
        Path::new("synthetic.csv"),
        csv.as_bytes(),
        Positions::default(),
    )
    .unwrap()
}

fn all(_: usize) -> bool {
    true
}

#[test]
fn least_squares_equals_formula_10_with_six_positions() {
    for seed in 0..20 {
        let csv = synthetic_csv(&[20.0], &|_| PAPER_T0, &TP, 30, 2e-5, 0.0, seed);
        let rec = read(&csv);
        let st = stops(&rec, &all, 3.0);
        assert_eq!(st.len(), 1);
        let got = identify_stop(&rec, &st[0], &noise(&rec)).unwrap();
        let means: [[f64; 3]; 6] = std::array::from_fn(|m| rec.dwells[m].u_mean);
        let want = formula_10(&means);
        for c in 0..12 {
            assert!(
                (got.coeffs[c] - want[c]).abs() < 1e-12,
                "seed {seed} coeff {c}: {} vs {}",
                got.coeffs[c],
                want[c]
            );
        }
        assert!(
            got.k2.iter().all(Option::is_some),
            "the even term is determined by TP1..TP6"
        );
    }
}

#[test]
fn recovers_truth_consistently_with_standard_errors() {
    let mut z2 = 0.0;
    let mut n = 0;
    for seed in 100..160 {
        let csv = synthetic_csv(&[20.0], &|_| PAPER_T0, &TP, 20, 5e-5, 0.0, seed);
        let rec = read(&csv);
        let st = stops(&rec, &all, 3.0);
        let got = identify_stop(&rec, &st[0], &noise(&rec)).unwrap();
        for c in 0..12 {
            let z = (got.coeffs[c] - PAPER_T0[c]) / got.stderr[c];
            assert!(z.abs() < 5.0, "seed {seed} coeff {c}: z = {z}");
            z2 += z * z;
            n += 1;
        }
    }
    let rms = (z2 / n as f64).sqrt();
    assert!(
        (0.85..1.15).contains(&rms),
        "rms z-score {rms}: standard errors are miscalibrated"
    );
}

#[test]
fn four_non_coplanar_positions_suffice_and_coplanar_ones_do_not() {
    let four = [TP[0], TP[1], TP[2], TP[5]];
    let rec = read(&synthetic_csv(
        &[20.0],
        &|_| PAPER_T0,
        &four,
        10,
        0.0,
        0.0,
        1,
    ));
    let st = stops(&rec, &all, 3.0);
    let got = identify_stop(&rec, &st[0], &noise(&rec)).unwrap();
    for c in 0..12 {
        assert!((got.coeffs[c] - PAPER_T0[c]).abs() < 1e-12);
    }
    let plane = [TP[0], TP[1], TP[2], TP[3]];
    let rec = read(&synthetic_csv(
        &[20.0],
        &|_| PAPER_T0,
        &plane,
        10,
        1e-5,
        0.0,
        1,
    ));
    let st = stops(&rec, &all, 3.0);
    let e = identify_stop(&rec, &st[0], &noise(&rec)).unwrap_err();
    assert_eq!(e.kind(), host_fit::error::ErrorKind::Insufficient, "{e}");
    // it names the stop and the positions present
    let e = e.to_string();
    assert!(
        e.contains("20.00 C") && e.contains("TP1, TP2, TP3, TP4"),
        "{e}"
    );
}

/// A unit whose offsets move 0.1 mV/C and scale factors 1e-4 /C, with the case still
/// settling 0.15 C per dwell at every stop: per-stop formula (10) mixes dwells taken at
/// different temperatures, the joint fit uses each at its own.
#[test]
fn joint_fit_beats_per_stop_when_the_temperature_drifts_within_a_stop() {
    let truth = |t: f64| {
        let mut c = PAPER_T0;
        for (i, v) in c.iter_mut().enumerate() {
            if i < 3 {
                *v *= 1.0 + 1e-4 * (t - 20.0);
            } else if i >= 9 {
                *v += 1e-4 * (t - 20.0);
            }
        }
        c
    };
    let temps = [-40.0, 20.0, 70.0];
    let rec = read(&synthetic_csv(&temps, &truth, &TP, 30, 1e-6, 0.15, 7));
    let err_at = |route: Identification| {
        let oc = fit_recording(
            &rec,
            &ModelChoice {
                kind: ModelKind::Poly,
                order: Some(1),
                breakpoints: None,
            },
            route,
        )
        .unwrap();
        let mut worst: f64 = 0.0;
        for t in [-30.0, 0.0, 45.0] {
            let (a, b) = (oc.fit.eval(t), truth(t));
            for c in 0..12 {
                worst = worst.max((a[c] - b[c]).abs());
            }
        }
        worst
    };
    let joint = err_at(Identification::Joint);
    let per_stop = err_at(Identification::PerStop);
    assert!(joint < 1e-6, "joint fit error {joint:e}");
    println!("max coefficient error: joint {joint:e}, per-stop {per_stop:e}");
    assert!(
        per_stop > 5.0 * joint,
        "per-stop {per_stop:e} vs joint {joint:e}"
    );
}
