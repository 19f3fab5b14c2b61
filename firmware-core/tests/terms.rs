//! Discovered terms through the compensator: the first-order correction's error bound,
//! the f32 path against the f64 one (the same code) within its stated bound at 10 Hz,
//! 100 Hz and 1 kHz, the state factors on the unit's clock (dTdt from the rate machine,
//! decay(power_on) restarted by a power-on), and a table without a physics section.
#![cfg(feature = "terms")]
mod common;

use firmware_core::blob::{example_physics, example_terms};
use firmware_core::compensate::{Compensator, ErrorModel, Method, TERMS_F32_BOUND_G};
use firmware_core::model::{invert, Coeffs};
use firmware_core::temperature::Calibration;
use firmware_core::terms::{Axis, Factor, Tau, Term, TermEntry, TermList, UnitState};
use proptest::prelude::*;

/// The f32 path's bound for the tables alone (model.rs, properties.rs), g.
const F32_BOUND_G: f64 = 2e-6;

const METHODS: [Method; 3] = [
    Method::CorrectConstants,
    Method::CorrectResult(ErrorModel::Full),
    Method::CorrectResult(ErrorModel::Simplified),
];

/// A random term: one to three factors of the unit's state, a TAU of 10 s to 1 h when it
/// has a decay.
fn any_term() -> impl Strategy<Value = Term> {
    (
        prop::collection::vec(prop::sample::select(Factor::ALL.to_vec()), 1..=3),
        10.0f32..3600.0,
    )
        .prop_filter_map("two decays", |(f, tau)| {
            let t = f
                .contains(&Factor::DecayPowerOn)
                .then(|| Tau::from_seconds(tau))
                .flatten();
            Term::new(&f, t).ok()
        })
}

/// The largest |value| of a term's state part over the tests' states (|dT| <= 60 C,
/// |dTdt| <= 12 C/min, the decay <= 1), so a coefficient can be sized by it.
fn state_scale(t: &Term) -> f64 {
    t.factors()
        .map(|f| match f {
            Factor::DT => 60.0,
            Factor::DTdt => 12.0,
            _ => 1.0,
        })
        .product()
}

/// A table of up to 8 terms, each contributing at most `size` output units at |a| <= 1 g
/// and the tests' states, no term twice on an axis.
fn any_table(size: f64) -> impl Strategy<Value = TermList<f64>> {
    prop::collection::vec(
        (any_term(), 0u8..3, -1.0f64..1.0),
        1..=firmware_core::terms::MAX_TERMS,
    )
    .prop_map(move |v| {
        let mut out = TermList::new();
        for (term, axis, c) in v {
            let axis = Axis::from_code(axis).unwrap();
            if out
                .iter()
                .any(|e: &TermEntry<f64>| e.axis == axis && e.term == term)
            {
                continue;
            }
            let coefficient = c * size / state_scale(&term);
            out.push(TermEntry {
                axis,
                term,
                coefficient,
            })
            .unwrap();
        }
        out
    })
}

fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The terms' sum on each axis at specific force `a` in state `s` (the forward model).
fn e_of(terms: &[TermEntry<f64>], a: [f64; 3], s: &UnitState<f64>) -> [f64; 3] {
    let mut e = [0.0; 3];
    for t in terms {
        e[t.axis.index()] += t.contribution(a, s);
    }
    e
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// A unit whose outputs carry discovered terms (`U = K a + U0 + e(a)`), compensated
    /// in f64 at one sample after power-on: the first-order correction leaves
    /// `a_rec - a = N (e(a) - e(a_hat))`, so `|a_rec - a| <= |N|^2 L |e(a)|` with `L` the
    /// Lipschitz constant of `e` between `a` and `a_hat` (each term's force part of
    /// degree `d` changes by at most `d M^(d-1)` per g, `M` the largest component).
    #[test]
    fn the_correction_is_exact_to_second_order(cal in common::unit(), a in common::direction(),
            g in 0.0f64..1.5, terms in any_table(2e-3), t in -40.0f64..70.0,
            t_on in 0.0f64..2000.0) {
        let cal: Calibration<f64> = cal.convert();
        let a = a.map(|v| v * g);
        let s = UnitState { dt_c: t - cal.t0_c, dtdt_c_per_min: 0.0, since_power_on_s: t_on };
        let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
        let e = e_of(&terms, a, &s);
        let u = c.forward(a).iter().zip(e).map(|(x, y)| x + y).collect::<Vec<_>>();
        let mut comp = Compensator::with_terms(&cal, &terms, Method::CorrectConstants, 0.01).unwrap();
        // the first sample t_on after power-on: the machines start there
        let out = comp.compensate_dt([u[0], u[1], u[2]], t, t_on);
        prop_assert!(out.status.is_ok());
        let n = invert(&c.k).unwrap();
        let n_f = n.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
        let a_hat: Vec<f64> = (0..3).map(|i| a[i] + (0..3).map(|j| n[i][j] * e[j]).sum::<f64>()).collect();
        let m = a.iter().chain(&a_hat).fold(0.0f64, |m, v| m.max(v.abs()));
        let lip: f64 = terms.iter().map(|t| {
            let d = t.term.factors().filter(|f| f.is_force()).count() as i32;
            (t.coefficient * t.term.state(&s)).abs() * f64::from(d) * m.powi((d - 1).max(0))
        }).sum();
        let err = norm([out.accel[0] - a[0], out.accel[1] - a[1], out.accel[2] - a[2]]);
        prop_assert!(err <= n_f * n_f * lip * norm(e) * 1.000_001 + 1e-13,
            "error {err:e} over the bound {:e}", n_f * n_f * lip * norm(e));
        // and without the correction the terms would be first order
        prop_assert!(err <= n_f * norm(e) + 1e-13);
    }

    /// The f32 path against the f64 path of the same code, on a temperature ramp with
    /// discovered terms (and the physics terms) at 10 Hz, 100 Hz and 1 kHz, every method:
    /// within the tables' bound plus TERMS_F32_BOUND_G, terms of up to 1e-3 output units
    /// (2 mg on a 0.5 V/g unit) each; and the terms' share (the departure with the terms
    /// minus the departure without them, sample by sample) within TERMS_F32_BOUND_G
    /// (5e-7 g the largest seen over 400 cases).
    #[test]
    fn f32_follows_f64_with_terms(cal in common::unit(), terms in any_table(1e-3),
            phys in any::<bool>(), m in 0usize..3, hz in prop::sample::select(vec![10u32, 100, 1000]),
            rate in -6.0f64..6.0, start in -30.0f64..60.0, a in common::direction()) {
        let mut cal: Calibration<f32> = cal;
        if phys {
            cal.physics = Some(example_physics());
        }
        let t32: TermList<f32> = terms.iter().map(TermEntry::convert).collect();
        let cal64: Calibration<f64> = cal.convert();
        let t64: TermList<f64> = t32.iter().map(TermEntry::convert).collect();
        let dt = 1.0 / hz as f32;
        let mut c32 = Compensator::with_terms(&cal, &t32, METHODS[m], dt).unwrap();
        let mut c64 = Compensator::with_terms(&cal64, &t64, METHODS[m], f64::from(dt)).unwrap();
        // the same without the terms: the terms' own share of the departure
        let mut p32 = Compensator::new(&cal, METHODS[m], dt).unwrap();
        let mut p64 = Compensator::new(&cal64, METHODS[m], f64::from(dt)).unwrap();
        let (mut worst, mut terms_share): (f64, f64) = (0.0, 0.0);
        // 60 s of a ramp at `rate` C/min, the unit turning slowly
        for k in 0..(60 * hz) {
            let time = f64::from(k) / f64::from(hz);
            let temp = (start + rate * time / 60.0) as f32;
            let turn = time * 0.05;
            let dir = [a[0] * turn.cos() - a[2] * turn.sin(), a[1], a[0] * turn.sin() + a[2] * turn.cos()];
            let c = Coeffs::from_array(&cal64.model.eval(cal64.t0_c, f64::from(temp)));
            let u = c.forward(dir).map(|v| v as f32);
            let o32 = c32.compensate(u, temp);
            let o64 = c64.compensate(u.map(f64::from), f64::from(temp));
            prop_assert_eq!(o32.status, o64.status);
            let a32 = o32.accel.map(f64::from);
            worst = worst.max(max_abs_diff(a32, o64.accel));
            let (q32, q64) = (p32.compensate(u, temp).accel.map(f64::from),
                              p64.compensate(u.map(f64::from), f64::from(temp)).accel);
            let d32 = [a32[0] - q32[0], a32[1] - q32[1], a32[2] - q32[2]];
            let d64 = [o64.accel[0] - q64[0], o64.accel[1] - q64[1], o64.accel[2] - q64[2]];
            terms_share = terms_share.max(max_abs_diff(d32, d64));
        }
        prop_assert!(worst <= F32_BOUND_G + TERMS_F32_BOUND_G, "f32 departs by {worst:e} g");
        prop_assert!(terms_share <= TERMS_F32_BOUND_G, "the terms' f32 share {terms_share:e} g");
    }
}

/// dTdt is the rate machine's estimate in C/min: on a steady ramp a `dTdt` term on x
/// (no physics section: the rate over each 0.1 s step) removes exactly `c * rate` once
/// the ramp is under way, and a `dT` term `c * (T - T0)` of the sensor's temperature.
#[test]
fn the_state_factors_follow_the_units_clock() {
    let mut cal = firmware_core::blob::example_blob()
        .calibration
        .convert::<f64>();
    cal.update_step_c = 0.0;
    let (c_rate, c_dt) = (1e-3, 2e-5);
    let terms = [
        TermEntry {
            axis: Axis::X,
            term: Term::new(&[Factor::DTdt], None).unwrap(),
            coefficient: c_rate,
        },
        TermEntry {
            axis: Axis::Y,
            term: Term::new(&[Factor::DT], None).unwrap(),
            coefficient: c_dt,
        },
    ];
    let mut with = Compensator::with_terms(&cal, &terms, Method::CorrectConstants, 0.1).unwrap();
    let mut without = Compensator::new(&cal, Method::CorrectConstants, 0.1).unwrap();
    let u = [0.0045, -0.0044, -0.5521];
    let n = invert(&Coeffs::from_array(&cal.at_t0()).k).unwrap();
    let _ = n;
    for k in 0..600 {
        // 3 C/min
        let temp = 10.0 + 0.005 * f64::from(k);
        let (a, b) = (with.compensate(u, temp), without.compensate(u, temp));
        if k > 10 {
            // a = a_plain - N e: e = [c_rate * 3, c_dt * (T - T0), 0] at the last step,
            // which is this sample's (10 Hz: every sample steps)
            let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, temp));
            let n = invert(&c.k).unwrap();
            let e = [c_rate * 3.0, c_dt * (temp - cal.t0_c), 0.0];
            for i in 0..3 {
                let want = b.accel[i] - (0..3).map(|j| n[i][j] * e[j]).sum::<f64>();
                assert!(
                    (a.accel[i] - want).abs() < 1e-9,
                    "{k} {i}: {} vs {want}",
                    a.accel[i]
                );
            }
        }
    }
}

/// decay(power_on,TAU) on the compensator's clock: full weight at the first sample, gone
/// after many time constants, back at full weight after a power-on of the sensor; the
/// same at a fixed sample period and with each sample's own time step.
#[test]
fn a_power_on_brings_the_decay_back() {
    let cal = firmware_core::blob::example_blob().calibration;
    let terms = [TermEntry {
        axis: Axis::Z,
        term: Term::new(&[Factor::DecayPowerOn], Tau::from_seconds(30.0)).unwrap(),
        coefficient: 5e-4f32,
    }];
    let mut c = Compensator::with_terms(&cal, &terms, Method::CorrectConstants, 0.01).unwrap();
    let mut plain = Compensator::new(&cal, Method::CorrectConstants, 0.01).unwrap();
    let u = [0.0045, -0.0044, -0.5521];
    let dz = |a: [f32; 3], b: [f32; 3]| f64::from(a[2] - b[2]).abs();
    let first = dz(
        c.compensate_dt(u, 20.0, 0.0).accel,
        plain.compensate_dt(u, 20.0, 0.0).accel,
    );
    // 5e-4 V on a 0.55 V/g axis: about 0.9 mg
    assert!(first > 8e-4, "{first}");
    for _ in 0..100_000 {
        c.compensate(u, 20.0);
        plain.compensate(u, 20.0);
    }
    let late = dz(c.compensate(u, 20.0).accel, plain.compensate(u, 20.0).accel);
    assert!(late < 1e-7, "after 1000 s: {late}");
    c.power_on(0.0);
    plain.power_on(0.0);
    let again = dz(
        c.compensate_dt(u, 20.0, 0.0).accel,
        plain.compensate_dt(u, 20.0, 0.0).accel,
    );
    assert!((again - first).abs() < 1e-6, "{again} {first}");
    // 30 s later (steps of 0.1 s): exp(-1) of it
    for _ in 0..3000 {
        c.compensate(u, 20.0);
        plain.compensate(u, 20.0);
    }
    let tau = dz(c.compensate(u, 20.0).accel, plain.compensate(u, 20.0).accel);
    assert!(
        (tau / first - (-1.0f64).exp()).abs() < 2e-3,
        "{}",
        tau / first
    );
}

/// The example's full table (8 terms of every kind) at 10 Hz, 100 Hz and 1 kHz in f32
/// against f64 at 10 Hz, compared at every 0.1 s where all have just stepped: within the
/// bound, on a warming from a cold start with the unit turning.
#[test]
fn ten_hundred_and_thousand_hertz_compensate_alike_with_terms() {
    let mut cal = firmware_core::blob::example_blob().calibration;
    cal.physics = Some(example_physics());
    let terms = example_terms();
    let cal64: Calibration<f64> = cal.convert();
    let t64: TermList<f64> = terms.iter().map(TermEntry::convert).collect();
    let temp = |t: f64| (-20.0 + 0.1 * (t - 60.0).max(0.0)) as f32;
    let u_at = |t: f64| {
        let ang = t * 0.01;
        let c = Coeffs::from_array(&cal64.model.eval(cal64.t0_c, f64::from(temp(t))));
        c.forward([ang.sin(), 0.1, -ang.cos()]).map(|v| v as f32)
    };
    let mut c64 = Compensator::with_terms(&cal64, &t64, Method::CorrectConstants, 0.1).unwrap();
    let reference: Vec<[f64; 3]> = (0..6000)
        .map(|k| {
            let t = f64::from(k) * 0.1;
            c64.compensate(u_at(t).map(f64::from), f64::from(temp(t)))
                .accel
        })
        .collect();
    for hz in [10u32, 100, 1000] {
        let per = hz / 10;
        let mut c =
            Compensator::with_terms(&cal, &terms, Method::CorrectConstants, 1.0 / hz as f32)
                .unwrap();
        let mut worst: f64 = 0.0;
        for k in 0..6000 * per {
            let t = f64::from(k) / f64::from(hz);
            let o = c.compensate(u_at(t), temp(t));
            if k % per == 0 {
                let r = reference[(k / per) as usize];
                worst = worst.max(max_abs_diff(o.accel.map(f64::from), r));
            }
        }
        eprintln!("{hz} Hz: f32 within {worst:.2e} g of f64 at 10 Hz");
        assert!(
            worst <= F32_BOUND_G + TERMS_F32_BOUND_G,
            "{hz} Hz: {worst:e} g"
        );
    }
}
