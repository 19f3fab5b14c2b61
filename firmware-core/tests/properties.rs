//! Invariants of the shared model and the compensator, with their error bounds.
mod common;

use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::model::{invert, mat_mul, mat_sub, mat_vec, norm3, sub3, Coeffs};
use firmware_core::temperature::Calibration;
use proptest::prelude::*;

/// Documented bound (lib.rs): method 1 in f32 recovers `a` within 2e-6 g.
const F32_BOUND_G: f64 = 2e-6;

fn forward_f64(cal: &Calibration<f64>, t: f64, a: [f64; 3]) -> [f64; 3] {
    Coeffs::from_array(&cal.model.eval(cal.t0_c, t)).forward(a)
}

fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn method1_inverts_forward_model(cal in common::unit(), a in common::direction(),
                                     t in -40.0f64..70.0, g in 0.0f64..2.0) {
        let a = a.map(|v| v * g);
        let cal64: Calibration<f64> = cal.convert();
        let u = forward_f64(&cal64, f64::from(t as f32), a);
        // f64 path: exact up to f64 rounding.
        let mut c64 = Compensator::new(&cal64, Method::CorrectConstants, 1.0).unwrap();
        let o64 = c64.compensate(u, f64::from(t as f32));
        prop_assert!(o64.status.is_ok());
        prop_assert!(max_abs_diff(o64.accel, a) < 1e-12);
        // f32 path: the firmware as it runs, within the documented bound of both.
        let mut c32 = Compensator::new(&cal, Method::CorrectConstants, 1.0).unwrap();
        let o32 = c32.compensate(u.map(|v| v as f32), t as f32);
        prop_assert!(o32.status.is_ok());
        let a32 = o32.accel.map(f64::from);
        prop_assert!(max_abs_diff(a32, a) < F32_BOUND_G, "f32 {:?} vs {:?}", a32, a);
        prop_assert!(max_abs_diff(a32, o64.accel) < F32_BOUND_G);
    }

    /// Method 2 = method 1 - (N0 dK) e with e = N0 (dK a + dU0), exactly (derivation in
    /// compensate.rs docs); so |a2 - a1| <= ||N0 dK||_F |e|, second order in the drift.
    #[test]
    fn method2_departs_from_method1_by_second_order_term(cal in common::unit(),
            a in common::direction(), t in -40.0f64..70.0) {
        let cal: Calibration<f64> = cal.convert();
        let u = forward_f64(&cal, t, a);
        let mut m1 = Compensator::new(&cal, Method::CorrectConstants, 1.0).unwrap();
        let mut m2 = Compensator::new(&cal, Method::CorrectResult(ErrorModel::Full), 1.0).unwrap();
        let a1 = m1.compensate(u, t).accel;
        let a2 = m2.compensate(u, t).accel;
        let c0 = Coeffs::from_array(&cal.at_t0());
        let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
        let n0 = invert(&c0.k).unwrap();
        let dk = mat_sub(&c.k, &c0.k);
        let e = mat_vec(&n0, firmware_core::model::add3(mat_vec(&dk, a), sub3(c.u0, c0.u0)));
        let n0dk = mat_mul(&n0, &dk);
        let predicted = mat_vec(&n0dk, e).map(|v| -v);
        let dep = sub3(a2, a1);
        prop_assert!(max_abs_diff(dep, predicted) < 1e-13, "{:?} vs {:?}", dep, predicted);
        let frob = n0dk.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
        prop_assert!(norm3(&dep) <= frob * norm3(&e) + 1e-13);
    }

    /// The simplified model (8) departs from the full one by about (N0 - diag N0) times
    /// the output-side error: bounded by ||N0 - diag N0||_F |dK a + dU0| + the second
    /// order term above.
    #[test]
    fn simplified_error_model_bound(cal in common::unit(), a in common::direction(),
                                    t in -40.0f64..70.0) {
        let cal: Calibration<f64> = cal.convert();
        let u = forward_f64(&cal, t, a);
        let mut full = Compensator::new(&cal, Method::CorrectResult(ErrorModel::Full), 1.0).unwrap();
        let mut simp =
            Compensator::new(&cal, Method::CorrectResult(ErrorModel::Simplified), 1.0).unwrap();
        let af = full.compensate(u, t).accel;
        let asimp = simp.compensate(u, t).accel;
        let c0 = Coeffs::from_array(&cal.at_t0());
        let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
        let n0 = invert(&c0.k).unwrap();
        let dk = mat_sub(&c.k, &c0.k);
        let a_hat = mat_vec(&n0, sub3(u, c0.u0));
        let w = firmware_core::model::add3(mat_vec(&dk, a_hat), sub3(c.u0, c0.u0));
        let off: f64 = (0..3).flat_map(|i| (0..3).map(move |j| (i, j)))
            .filter(|(i, j)| i != j).map(|(i, j)| n0[i][j] * n0[i][j]).sum::<f64>().sqrt();
        prop_assert!(norm3(&sub3(asimp, af)) <= off * norm3(&w) + 1e-13);
    }

    #[test]
    fn inverse_error_bound_in_f32(cal in common::unit(), t in -40.0f32..70.0) {
        let k32 = Coeffs::from_array(&cal.model.eval(cal.t0_c, t)).k;
        let k64 = k32.map(|r| r.map(f64::from));
        let n32 = invert(&k32).unwrap();
        let n64 = invert(&k64).unwrap();
        let max_n = n64.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (r32, r64) in n32.iter().zip(n64.iter()) {
            for (x, y) in r32.iter().zip(r64.iter()) {
                prop_assert!((f64::from(*x) - y).abs() <= 16.0 * f64::from(f32::EPSILON) * max_n);
            }
        }
    }
}
