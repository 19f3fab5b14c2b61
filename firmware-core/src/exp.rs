//! `exp(-u) - 1` in f32 arithmetic only: the MCU derives the filters' per-step constants
//! from the time step with it, without libm's `expf`/`expm1f` (whose soft-double
//! fallbacks must not be linked) and without a table.
//!
//! Error bound (held by the test `expm1_neg_f32_is_within_its_bound` against f64 on a
//! dense grid of `u` in [0, 100], and at its ends): the result is within
//! [`EXPM1_NEG_F32_BOUND`] of the exact value, relative to it. Cost: fixed, about 20
//! floating-point operations, whatever `u`.

/// Documented relative error bound of [`expm1_neg_f32`] (about 1.7 ulp of 1).
pub const EXPM1_NEG_F32_BOUND: f32 = 2.0e-7;

/// Above this `exp(-u)` is below half an ulp of 1: the result is -1.
const LARGE: f32 = 17.0;
const INV_LN2: f32 = core::f32::consts::LOG2_E;
/// ln 2 in two parts (Cody-Waite): `k * LN2_HI` is exact for the k used here (k <= 25).
const LN2_HI: f32 = 0.693_145_75;
const LN2_LO: f32 = 1.428_606_8e-6;

/// `exp(-r) - 1` for |r| <= 0.35 (Taylor to r^7, nested: truncation below 6e-9
/// relative).
#[inline]
fn series(r: f32) -> f32 {
    let mut p = 1.0 - r * (1.0 / 7.0);
    p = 1.0 - r * (1.0 / 6.0) * p;
    p = 1.0 - r * (1.0 / 5.0) * p;
    p = 1.0 - r * (1.0 / 4.0) * p;
    p = 1.0 - r * (1.0 / 3.0) * p;
    p = 1.0 - r * (1.0 / 2.0) * p;
    -r * p
}

/// `exp(-u) - 1` for `u >= 0` (a time step over a time constant): accurate for tiny `u`
/// (no cancellation), -1 for large `u`. NaN gives NaN; a negative `u` is treated as 0.
#[inline]
pub fn expm1_neg_f32(u: f32) -> f32 {
    if u.is_nan() {
        return u;
    }
    if u <= 0.0 {
        return 0.0;
    }
    if u >= LARGE {
        return -1.0;
    }
    // u = k ln2 + r, |r| <= ln2 / 2; exp(-u) = 2^-k exp(-r), k in 0..=25 here. For
    // k = 0 (u below ln2 / 2) the series of u itself: no cancellation against 1.
    let k = (u * INV_LN2 + 0.5) as i32;
    let kf = k as f32;
    let r = (u - kf * LN2_HI) - kf * LN2_LO;
    let p = series(r);
    if k == 0 {
        return p;
    }
    let scale = f32::from_bits(((127 - k) as u32) << 23);
    scale * (1.0 + p) - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(u: f32) -> f64 {
        let exact = libm::expm1(-f64::from(u));
        let got = f64::from(expm1_neg_f32(u));
        if exact == 0.0 {
            got.abs()
        } else {
            ((got - exact) / exact).abs()
        }
    }

    #[test]
    fn expm1_neg_f32_is_within_its_bound() {
        let mut worst: f64 = 0.0;
        // log-spaced from 1e-12 to 100 (every regime and both switch points) ...
        let n = 400_000;
        for i in 0..=n {
            let u = 1e-12f64 * (1e14f64).powf(i as f64 / n as f64);
            worst = worst.max(rel(u as f32));
        }
        // ... and every f32 around the switch points and the range reduction's steps
        for centre in [
            LARGE,
            0.5 * core::f32::consts::LN_2,
            3.0 * 0.5 * core::f32::consts::LN_2,
        ] {
            let mut u = centre;
            for _ in 0..2000 {
                u = f32::from_bits(u.to_bits() - 1);
            }
            for _ in 0..4000 {
                worst = worst.max(rel(u));
                u = f32::from_bits(u.to_bits() + 1);
            }
        }
        eprintln!("expm1_neg_f32: worst relative error {worst:.3e}");
        assert!(
            worst <= f64::from(EXPM1_NEG_F32_BOUND),
            "worst relative error {worst:e}"
        );
        // the bound is not loose by an order of magnitude
        assert!(
            worst > f64::from(EXPM1_NEG_F32_BOUND) / 10.0,
            "worst {worst:e}"
        );
    }

    #[test]
    fn ends_and_non_numbers() {
        assert_eq!(expm1_neg_f32(0.0), 0.0);
        assert_eq!(expm1_neg_f32(-3.0), 0.0);
        assert_eq!(expm1_neg_f32(1e-30), -1e-30);
        assert_eq!(expm1_neg_f32(f32::INFINITY), -1.0);
        assert_eq!(expm1_neg_f32(40.0), -1.0);
        assert!(expm1_neg_f32(f32::NAN).is_nan());
    }
}
