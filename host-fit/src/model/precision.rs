//! The firmware's f32 path against the f64 model: the firmware evaluates a blob in f32
//! (f32 tables, f32 arithmetic, its in-flight filters in f32), host-fit fits and predicts
//! in f64; every blob built is checked to stay within a documented bound of the f64
//! evaluation of the model it carries.
use crate::error::{ErrorKind, HostError, Result};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::model::Coeffs;
use firmware_core::temperature::Calibration;
use firmware_core::terms::TermEntry;

/// Documented bound: the firmware's f32 path (f32 tables, f32 arithmetic) stays within
/// this many g of the f64 evaluation of the unrounded model, for |a| <= 1 g, inside the
/// valid temperature range. Held by [`crate::blob::build_blob`] on every blob built; the departure in
/// the 10 C beyond the range (extrapolation, where a high-order polynomial loses f32
/// digits) is measured and reported.
pub const F32_BOUND_G: f64 = 2e-6;

/// 26 unit directions: the axes, the face diagonals and the cube's corners, both signs.
pub fn directions26() -> Vec<[f64; 3]> {
    let mut dirs = Vec::new();
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                let v = [f64::from(x), f64::from(y), f64::from(z)];
                let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if n > 0.0 {
                    dirs.push(v.map(|c| c / n));
                }
            }
        }
    }
    dirs
}

/// Largest |a_f32 - a_f64| (g) over a grid of temperatures (0.5 C steps) and 26
/// directions, for method 1 and method 2 (full): inside the valid range, and in the
/// 10 C beyond it.
pub fn f32_departure(cal64: &Calibration<f64>, cal32: &Calibration<f32>) -> Result<(f64, f64)> {
    f32_departure_with_terms(cal64, &[], cal32, &[])
}

/// [`f32_departure`] of a calibration with its discovered terms (each side's own: the
/// f64 table and the f32 one the blob holds).
pub fn f32_departure_with_terms(
    cal64: &Calibration<f64>,
    terms64: &[TermEntry<f64>],
    cal32: &Calibration<f32>,
    terms32: &[TermEntry<f32>],
) -> Result<(f64, f64)> {
    let mut c64 = cal64.clone();
    c64.update_step_c = 0.0;
    let mut c32 = cal32.clone();
    c32.update_step_c = 0.0;
    let dirs = directions26();
    let (mut inside, mut beyond): (f64, f64) = (0.0, 0.0);
    for method in [
        Method::CorrectConstants,
        Method::CorrectResult(ErrorModel::Full),
    ] {
        // one sample a second: the physics terms' machines follow the sweep alike in both
        let mut m64 = Compensator::with_terms(&c64, terms64, method, 1.0)
            .map_err(|e| HostError::new(ErrorKind::Numerical, e.to_string()))?;
        let mut m32 = Compensator::with_terms(&c32, terms32, method, 1.0)
            .map_err(|e| HostError::new(ErrorKind::Numerical, e.to_string()))?;
        let mut t = cal64.t_min_c - 10.0;
        while t <= cal64.t_max_c + 10.0 {
            let t32 = t as f32;
            let coeffs = Coeffs::from_array(&cal64.model.eval(cal64.t0_c, f64::from(t32)));
            for a in &dirs {
                let u = coeffs.forward(*a).map(|v| f64::from(v as f32));
                let r64 = m64.compensate(u, f64::from(t32)).accel;
                let r32 = m32.compensate(u.map(|v| v as f32), t32).accel;
                let in_range = (cal64.t_min_c..=cal64.t_max_c).contains(&f64::from(t32));
                for (x, y) in r64.iter().zip(r32.iter()) {
                    let d = (x - f64::from(*y)).abs();
                    if in_range {
                        inside = inside.max(d);
                    } else {
                        beyond = beyond.max(d);
                    }
                }
            }
            t += 0.5;
        }
    }
    Ok((inside, beyond))
}

/// An in-flight term of a calibration's physics block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhysicsTerm {
    /// The element's temperature through the thermal lag.
    Lag,
    /// The offset per C/s of the temperature's rate.
    Rate,
    /// The offset by the direction of the last temperature change.
    Hysteresis,
    /// The output per g^2.
    K2,
    /// The output per |g|.
    Asymmetry,
    /// The offset settling after power-on.
    Warmup,
}

impl PhysicsTerm {
    /// Every term.
    pub const ALL: [PhysicsTerm; 6] = [
        PhysicsTerm::Lag,
        PhysicsTerm::Rate,
        PhysicsTerm::Hysteresis,
        PhysicsTerm::K2,
        PhysicsTerm::Asymmetry,
        PhysicsTerm::Warmup,
    ];

    /// `cal` with this term switched off.
    fn without(self, cal: &Calibration<f64>) -> Calibration<f64> {
        let mut c = cal.clone();
        if let Some(p) = c.physics.as_mut() {
            match self {
                PhysicsTerm::Lag => p.lag_tau_s = 0.0,
                PhysicsTerm::Rate => p.rate = [0.0; 3],
                PhysicsTerm::Hysteresis => p.hysteresis = [0.0; 3],
                PhysicsTerm::K2 => p.k2 = [0.0; 3],
                PhysicsTerm::Asymmetry => p.asymmetry = [0.0; 3],
                PhysicsTerm::Warmup => p.warmup = [0.0; 3],
            }
        }
        c
    }

    fn describe(self, cal: &Calibration<f64>) -> String {
        let p = cal
            .physics
            .clone()
            .unwrap_or_else(firmware_core::temperature::Physics::neutral);
        let span = cal.t_max_c - cal.t_min_c;
        match self {
            PhysicsTerm::Lag => format!(
                "the thermal lag ({:.0} s): the element's temperature it carries trails the sensor's far outside the {span:.0} C the model was fitted over, where the temperature model is extrapolated",
                p.lag_tau_s
            ),
            PhysicsTerm::Rate => format!(
                "the temperature-rate term ({:.3e} output units per C/s, {})",
                p.rate.iter().fold(0.0f64, |m, v| m.max(v.abs())),
                crate::model::effects::rate_estimator(p.rate_tau_s)
            ),
            PhysicsTerm::Hysteresis => "the hysteresis term".into(),
            PhysicsTerm::K2 => "the K2 term".into(),
            PhysicsTerm::Asymmetry => "the scale-asymmetry term".into(),
            PhysicsTerm::Warmup => format!("the warm-up term ({:.0} s)", p.warmup_tau_s),
        }
    }
}

/// Why the f32 path of a calibration departs from its f64 model.
#[derive(Debug, Clone, PartialEq)]
pub enum F32Cause {
    /// An in-flight term: without it the departure is within the bound.
    Physics(PhysicsTerm),
    /// The temperature model's terms cancel: at `temp_c` the magnitudes of the
    /// polynomial terms of coefficient `coefficient` (canonical order) add up to `ratio`
    /// times the unit's scale factor there, and f32 keeps about 7 digits of each term, so
    /// |a| loses about `ratio` x 6e-8 g.
    Cancellation {
        /// The coefficient (`COEFF_NAMES` order).
        coefficient: usize,
        /// Where, C.
        temp_c: f64,
        /// Sum of the terms' magnitudes over the mean |K_ii| at `temp_c`.
        ratio: f64,
    },
    /// K(T) is ill-conditioned: its condition number (1-norm) reaches `cond` at `temp_c`.
    Conditioning {
        /// The condition number.
        cond: f64,
        /// Where, C.
        temp_c: f64,
    },
}

impl F32Cause {
    /// The cause in words, for the error that names it.
    pub fn text(&self, cal: &Calibration<f64>) -> String {
        match self {
            F32Cause::Physics(t) => format!(
                "the cause is {}; without it the f32 path stays within the bound",
                t.describe(cal)
            ),
            F32Cause::Cancellation {
                coefficient,
                temp_c,
                ratio,
            } => format!(
                "the cause is the temperature model, not K's conditioning: at {temp_c:.1} C the polynomial terms of {} reach {ratio:.0}x the unit's scale factor and cancel, and f32 keeps about 7 digits of each term (a model bent far from the unit's own, or of an order its data do not support)",
                firmware_core::model::COEFF_NAMES[*coefficient]
            ),
            F32Cause::Conditioning { cond, temp_c } => format!(
                "the cause is K itself: its condition number reaches {cond:.0} at {temp_c:.1} C, too ill-conditioned for f32"
            ),
        }
    }
}

/// The departures of `cal`'s f32 path from its f64 model, inside the valid range and in
/// the 10 C beyond it (see [`f32_departure`]).
pub fn departure(cal: &Calibration<f64>) -> Result<(f64, f64)> {
    f32_departure(cal, &cal.convert())
}

/// [`departure`], an error when the departure inside the range is over
/// [`F32_BOUND_G`] (or not a number); the error names the cause ([`cause`]).
pub fn check(cal: &Calibration<f64>) -> Result<(f64, f64)> {
    let (dep, beyond) = departure(cal)?;
    if dep.is_nan() || dep > F32_BOUND_G {
        return Err(HostError::new(ErrorKind::Numerical, format!(
            "the f32 firmware path departs from the f64 model by {dep:.3e} g, over the bound {F32_BOUND_G:.1e} g: {}",
            cause(cal).text(cal)
        )));
    }
    Ok((dep, beyond))
}

/// [`check`] of a calibration with its discovered terms: the f32 blob's tables (`cal32`,
/// `terms32`) against the f64 model (`cal64`, `terms64`). When the calibration alone is
/// within the bound the terms are named as the cause.
pub fn check_with_terms(
    cal64: &Calibration<f64>,
    terms64: &[TermEntry<f64>],
    cal32: &Calibration<f32>,
    terms32: &[TermEntry<f32>],
) -> Result<(f64, f64)> {
    if terms64.is_empty() {
        return check(cal64);
    }
    let (dep, beyond) = f32_departure_with_terms(cal64, terms64, cal32, terms32)?;
    if dep.is_nan() || dep > F32_BOUND_G {
        let why = match departure(cal64) {
            Ok((d, _)) if d.is_finite() && d <= F32_BOUND_G => {
                "the discovered terms (their f32 coefficients or factors)".to_string()
            }
            _ => cause(cal64).text(cal64),
        };
        return Err(HostError::new(ErrorKind::Numerical, format!(
            "the f32 firmware path departs from the f64 model by {dep:.3e} g, over the bound {F32_BOUND_G:.1e} g: {why}"
        )));
    }
    Ok((dep, beyond))
}

/// Why `cal`'s f32 path departs from its f64 model: an in-flight term, when switching it
/// off alone brings the departure within the bound; else whichever loses more digits
/// over the valid range: the temperature model's terms (their magnitudes over the
/// unit's scale factor: f32 rounds each term) or K's condition number (f32 rounds K).
pub fn cause(cal: &Calibration<f64>) -> F32Cause {
    if cal.physics.is_some() {
        let within = |c: &Calibration<f64>| {
            departure(c).is_ok_and(|(d, _)| d.is_finite() && d <= F32_BOUND_G)
        };
        if let Some(t) = PhysicsTerm::ALL
            .into_iter()
            .find(|t| within(&t.without(cal)))
        {
            return F32Cause::Physics(t);
        }
    }
    let temps = grid(cal);
    let (mut worst_ratio, mut at_ratio) = ((1.0, 0.0), 0);
    let (mut worst_cond, mut at_cond) = (1.0, 0.0);
    for &t in &temps {
        let k = Coeffs::from_array(&cal.model.eval(cal.t0_c, t)).k;
        let scale = (k[0][0].abs() + k[1][1].abs() + k[2][2].abs()) / 3.0;
        if let firmware_core::temperature::TempModel::Poly { terms } = &cal.model {
            let dt = t - cal.t0_c;
            for c in 0..12 {
                let abs: f64 = terms
                    .iter()
                    .enumerate()
                    .map(|(k, row)| (row[c] * dt.powi(k as i32)).abs())
                    .sum();
                let r = abs / scale.max(f64::MIN_POSITIVE);
                if r > worst_ratio.0 {
                    (worst_ratio, at_ratio) = ((r, t), c);
                }
            }
        }
        let cond = match firmware_core::model::invert(&k) {
            Some(n) => norm1(&k) * norm1(&n),
            None => f64::INFINITY,
        };
        if cond > worst_cond {
            (worst_cond, at_cond) = (cond, t);
        }
    }
    if worst_ratio.0 > worst_cond {
        F32Cause::Cancellation {
            coefficient: at_ratio,
            temp_c: worst_ratio.1,
            ratio: worst_ratio.0,
        }
    } else {
        F32Cause::Conditioning {
            cond: worst_cond,
            temp_c: at_cond,
        }
    }
}

/// The temperatures [`f32_departure`] judges inside the valid range (0.5 C apart).
fn grid(cal: &Calibration<f64>) -> Vec<f64> {
    let mut v = Vec::new();
    let mut t = cal.t_min_c;
    while t <= cal.t_max_c {
        v.push(t);
        t += 0.5;
    }
    v
}

/// The 1-norm of a 3x3 matrix (largest column sum of magnitudes).
fn norm1(m: &[[f64; 3]; 3]) -> f64 {
    (0..3)
        .map(|j| (0..3).map(|i| m[i][j].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware_core::temperature::{Physics, TempModel};

    /// A calibration at T0 20 C over `lo..hi` of the polynomial `terms` (per C^k).
    fn poly(
        terms: &[[f64; 12]],
        lo: f64,
        hi: f64,
        physics: Option<Physics<f64>>,
    ) -> Calibration<f64> {
        Calibration {
            t0_c: 20.0,
            t_min_c: lo,
            t_max_c: hi,
            clamp: false,
            update_step_c: 0.0,
            model: TempModel::Poly {
                terms: terms.iter().copied().collect(),
            },
            physics,
        }
    }

    /// The model a 2-h sweep of a lag + gradient unit once flashed (its lag profiled
    /// without a limit, 22 243 s): its f32 path departs by far more than the bound, and
    /// the cause named is the temperature model's terms cancelling, not K (whose
    /// condition number is about 1.1 there, the unit's own).
    #[test]
    fn the_cause_of_a_departure_is_the_model_not_k_when_its_terms_cancel() {
        let terms = [
            [
                16.343433957851996,
                21.221871916647075,
                24.11513416573567,
                0.7305328911534122,
                -2.1731420559581713,
                5.385770891694371,
                -6.549996513150176,
                12.084300040631549,
                -2.0156798422943893,
                -107.70070375364377,
                -46.34234517051865,
                -86.0495828630591,
            ],
            [
                1.645408261001015,
                2.098212153621701,
                2.3817037947700825,
                0.0747386200575773,
                -0.20161606647855845,
                0.5083603098275661,
                -0.6386156306125603,
                1.1709288458221276,
                -0.19879216220574134,
                -10.692945464857168,
                -4.699777938078387,
                -8.547526892386001,
            ],
            [
                0.06403436217696525,
                0.08073182497374144,
                0.0918787102443589,
                0.003032559359866978,
                -0.007379971286223231,
                0.01909627981118586,
                -0.02483925621829464,
                0.04520178353291549,
                -0.007837759757816554,
                -0.4235117969439162,
                -0.18979502486214975,
                -0.33886185206090613,
            ],
            [
                0.0012446269625687764,
                0.001550059678937311,
                0.00176987145253006,
                6.106512538236658e-5,
                -0.00013415356490709975,
                0.00035771035444964657,
                -0.00048171764859295435,
                0.0008699911430387424,
                -0.00015437973802894718,
                -0.008366172194126944,
                -0.0038164030549084605,
                -0.006702291187480317,
            ],
            [
                1.2080682942772234e-5,
                1.4849642719388542e-5,
                1.7022231365701507e-5,
                6.105401032794166e-7,
                -1.2102168542227964e-6,
                3.3407653876153184e-6,
                -4.65787708622956e-6,
                8.34791517289059e-6,
                -1.5188080707000495e-6,
                -8.243989889753147e-5,
                -3.822519901705445e-5,
                -6.613842070846672e-5,
            ],
            [
                4.683624528476981e-8,
                5.677761100252134e-8,
                6.538146870513353e-8,
                2.4259569387301816e-9,
                -4.330509131865838e-9,
                1.244143295014582e-8,
                -1.7963996212917355e-8,
                3.194482496750575e-8,
                -5.969136184292815e-9,
                -3.242085279373884e-7,
                -1.5261417254143943e-7,
                -2.6049333005235906e-7,
            ],
        ];
        let physics = Physics {
            lag_tau_s: 22243.1432536013,
            rate: [
                0.11352398388708729,
                0.049471562645066844,
                0.01142736126471562,
            ],
            rate_tau_s: 2.0,
            hysteresis_threshold_c: 0.5,
            ..Physics::neutral()
        };
        let cal = poly(&terms, -40.0, 68.33, Some(physics));
        let e = check(&cal).unwrap_err().to_string();
        let c = cause(&cal);
        println!("{e}\n{c:?}");
        assert!(
            matches!(c, F32Cause::Cancellation { ratio, .. } if ratio > 100.0),
            "{c:?}"
        );
        assert!(
            !e.contains("K is too ill-conditioned") && e.contains("cancel"),
            "{e}"
        );
    }

    /// A K of condition number 4e5 (two axes nearly parallel): the cause named is K
    /// itself.
    #[test]
    fn the_cause_of_a_departure_is_k_when_it_is_ill_conditioned() {
        // K = 0.55 [[1, 1, 0], [1, 1 + 1e-5, 0], [0, 0, 1]]: cond_1 = (2 + d)^2 / d
        let d = 1e-5;
        let mut row = [0.0; 12];
        row[..3].copy_from_slice(&[0.55, 0.55 * (1.0 + d), 0.55]);
        row[3] = 0.55;
        row[5] = 0.55;
        let cal = poly(&[row, [0.0; 12]], -40.0, 70.0, None);
        let e = check(&cal).unwrap_err().to_string();
        match cause(&cal) {
            F32Cause::Conditioning { cond, .. } => {
                assert!(
                    (cond / ((2.0 + d) * (2.0 + d) / d) - 1.0).abs() < 1e-6,
                    "{cond}"
                )
            }
            c => panic!("{c:?}"),
        }
        assert!(e.contains("condition number"), "{e}");
    }

    /// The paper unit's model stays within the bound; its cause, were it asked, would be
    /// K's own conditioning, about 1.
    #[test]
    fn a_well_conditioned_model_passes() {
        let mut row = [0.0; 12];
        row[..3].copy_from_slice(&[0.55, 0.55, 0.55]);
        row[3] = 0.01;
        let mut slope = [0.0; 12];
        slope[..3].copy_from_slice(&[1e-5, -2e-5, 1e-5]);
        let cal = poly(&[row, slope], -40.0, 70.0, None);
        let (dep, _) = check(&cal).unwrap();
        assert!(dep <= F32_BOUND_G, "{dep}");
    }
}
