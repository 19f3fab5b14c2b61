//! The host's fits and the firmware's tables are one model: what a fit optimises (the
//! host's basis functions times its parameters, f64) and what the firmware evaluates
//! from the blob's f32 table agree within the error the f32 rounding explains, for
//! random piecewise-linear and polynomial models, inside the table and beyond it.
use firmware_core::model::N_COEFFS;
use host_fit::fit::temperature::ModelFit;
use host_fit::model::basis::Basis;
use proptest::prelude::*;

/// A fit with `basis` and random parameters (values near a real unit's scale).
fn model(basis: Basis, seeds: &[f64], t0: f64) -> ModelFit {
    let nb = basis.len();
    let params: [Vec<f64>; N_COEFFS] = std::array::from_fn(|c| {
        (0..nb)
            .map(|k| {
                let s = seeds[(c * 7 + k * 3) % seeds.len()];
                match (&basis, c) {
                    (Basis::Pwl { .. }, 0..=2) => -0.55 + 0.01 * s,
                    (Basis::Pwl { .. }, _) => 0.02 * s,
                    (Basis::Poly { .. }, _) if k == 0 && c < 3 => -0.55,
                    // per C^k, so each term stays below ~1e-3 V at 50 C
                    (Basis::Poly { .. }, _) => 1e-3 * s / 50f64.powi(k as i32),
                }
            })
            .collect()
    });
    ModelFit {
        basis,
        t0_c: t0,
        params,
        stderr: Default::default(),
        k2: [None; 3],
        t_range: (-40.0, 70.0),
        chi2: 0.0,
        n_obs: 0,
        n_params: 0,
        axis_cov: Vec::new(),
        axis_chi2: Vec::new(),
    }
}

/// What the fit optimises: the host's basis functions (scaled powers of dT for a
/// polynomial) times the parameters in the same scaling.
fn host_value(m: &ModelFit, t: f64) -> [f64; N_COEFFS] {
    let phi = m.basis.eval(m.t0_c, t);
    std::array::from_fn(|c| {
        phi.iter()
            .enumerate()
            .map(|(k, f)| {
                let scale = match m.basis {
                    Basis::Poly { .. } => 50f64.powi(k as i32),
                    Basis::Pwl { .. } => 1.0,
                };
                f * m.params[c][k] * scale
            })
            .sum()
    })
}

/// The firmware's value from the f32 table the blob carries.
fn firmware_value(m: &ModelFit, t: f64) -> [f32; N_COEFFS] {
    let cal = m.calibration(0.1, false).convert::<f32>();
    cal.model.eval(cal.t0_c, t as f32)
}

const EPS: f64 = f32::EPSILON as f64;

/// The f32 error bound of a piecewise-linear coefficient at `t` (documented on
/// `TempModel::eval`: `4 eps max|v|` for the interpolation, plus the rounding of the
/// values, of `t` and of the breakpoints, each amplified by the fraction beyond the
/// segment when extrapolating).
fn pwl_bound(b: &[f64], v: &[f64], t: f64) -> f64 {
    let s = b[1..b.len() - 1].iter().filter(|x| t >= **x).count();
    let (b0, b1, v0, v1) = (b[s], b[s + 1], v[s], v[s + 1]);
    let f = ((t - b0) / (b1 - b0)).abs();
    let vmax = v0.abs().max(v1.abs());
    let slope = (v1 - v0).abs() / (b1 - b0);
    (6.0 * (1.0 + f) * vmax + 2.0 * slope * (t.abs() + b0.abs() + b1.abs()) * (1.0 + f)) * EPS
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn piecewise_linear_host_and_firmware_agree(
        gaps in prop::collection::vec(1.0f64..40.0, 1..15),
        start in -60.0f64..0.0,
        seeds in prop::collection::vec(-1.0f64..1.0, 16),
        t in -80.0f64..120.0,
    ) {
        let mut b = vec![start];
        for g in &gaps {
            b.push(b.last().unwrap() + g);
        }
        let m = model(Basis::Pwl { breakpoints: b.clone() }, &seeds, 20.0);
        let (h, f) = (host_value(&m, t), firmware_value(&m, t));
        for c in 0..N_COEFFS {
            let err = (h[c] - f64::from(f[c])).abs();
            let bound = pwl_bound(&b, &m.params[c], t);
            prop_assert!(err <= bound, "coefficient {c} at {t} C: host {} firmware {} (err {err:e} > {bound:e})", h[c], f[c]);
        }
    }

    #[test]
    fn polynomial_host_and_firmware_agree(
        order in 1usize..=5,
        seeds in prop::collection::vec(-1.0f64..1.0, 16),
        t0 in -10.0f64..40.0,
        t in -80.0f64..120.0,
    ) {
        let m = model(Basis::Poly { order }, &seeds, t0);
        let (h, f) = (host_value(&m, t), firmware_value(&m, t));
        let dt = (t - t0).abs();
        for c in 0..N_COEFFS {
            // Horner in f32: 2 n eps sum |p_k| |dT|^k; the rounding of the terms (eps/2
            // each) and of dT (ulps of t and t0 times the slope)
            let p = &m.params[c];
            let terms: f64 = p.iter().enumerate().map(|(k, v)| v.abs() * dt.powi(k as i32)).sum();
            let slope: f64 = p.iter().enumerate().skip(1).map(|(k, v)| k as f64 * v.abs() * dt.powi(k as i32 - 1)).sum();
            let bound = (2.0 * order as f64 + 1.0) * EPS * terms + slope * (t.abs() + t0.abs()) * EPS;
            let err = (h[c] - f64::from(f[c])).abs();
            prop_assert!(err <= bound, "coefficient {c} at {t} C: host {} firmware {} (err {err:e} > {bound:e})", h[c], f[c]);
        }
    }
}

/// The bound is tight enough to catch a different segment rule, run in firmware-core: a
/// firmware that took the segment ABOVE a breakpoint left of it (here evaluated by the
/// firmware's own code on a table of that segment alone) would disagree with the host by
/// far more than the bound, where the firmware's real rule agrees within it; below the
/// table (extrapolated) and just left of an interior breakpoint.
#[test]
fn a_wrong_segment_rule_would_be_caught() {
    let b = [-40.0, 20.0, 70.0];
    let m = model(
        Basis::Pwl {
            breakpoints: b.to_vec(),
        },
        &[0.3, -0.8, 0.5, 0.9],
        20.0,
    );
    // the segment above the first interior breakpoint, alone: its line, extended
    let above = ModelFit {
        basis: Basis::Pwl {
            breakpoints: b[1..].to_vec(),
        },
        params: std::array::from_fn(|c| m.params[c][1..].to_vec()),
        ..m.clone()
    };
    for t in [-60.0, 19.0] {
        let h = host_value(&m, t);
        let (right, wrong) = (firmware_value(&m, t), firmware_value(&above, t));
        let (mut agree, mut gap) = (0.0f64, 0.0f64);
        for c in 0..N_COEFFS {
            let bound = pwl_bound(&b, &m.params[c], t);
            agree = agree.max((h[c] - f64::from(right[c])).abs() / bound);
            gap = gap.max((h[c] - f64::from(wrong[c])).abs() / bound);
        }
        assert!(
            agree <= 1.0,
            "at {t} C the firmware is {agree}x the bound away"
        );
        assert!(
            gap > 1e3,
            "at {t} C the wrong rule is only {gap}x the bound away"
        );
    }
}
