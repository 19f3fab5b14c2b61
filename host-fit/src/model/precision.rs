//! The firmware's f32 path against the f64 model: the firmware evaluates a blob in f32
//! (f32 tables, f32 arithmetic, its in-flight filters in f32), host-fit fits and predicts
//! in f64; every blob built is checked to stay within a documented bound of the f64
//! evaluation of the model it carries.
use crate::error::{HostError, Result};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::model::Coeffs;
use firmware_core::temperature::Calibration;

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
        let mut m64 =
            Compensator::new(&c64, method, 1.0).map_err(|e| HostError::msg(e.to_string()))?;
        let mut m32 =
            Compensator::new(&c32, method, 1.0).map_err(|e| HostError::msg(e.to_string()))?;
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
                "the temperature-rate term ({:.3e} output units per C/s, estimator {:.0} s)",
                p.rate.iter().fold(0.0f64, |m, v| m.max(v.abs())),
                p.rate_tau_s
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
    /// The temperature model's terms cancel: at `temp_c` the polynomial terms of
    /// coefficient `coefficient` (canonical order) add up to `ratio` times their sum, and
    /// f32 keeps about 7 digits of each term.
    Cancellation {
        /// The coefficient (`COEFF_NAMES` order).
        coefficient: usize,
        /// Where, C.
        temp_c: f64,
        /// Sum of the terms' magnitudes over the magnitude of their sum.
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
                "the cause is the temperature model, not K's conditioning: at {temp_c:.1} C the polynomial terms of {} add up to {ratio:.0}x their sum, and f32 keeps about 7 digits of each term (a model this far from its data's range, or of an order the data do not support)",
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
        return Err(HostError::msg(format!(
            "the f32 firmware path departs from the f64 model by {dep:.3e} g, over the bound {F32_BOUND_G:.1e} g: {}",
            cause(cal).text(cal)
        )));
    }
    Ok((dep, beyond))
}

/// Why `cal`'s f32 path departs from its f64 model: an in-flight term, when switching it
/// off alone brings the departure within the bound; else whichever loses more digits,
/// the cancellation of the temperature model's terms or K's condition number, over the
/// valid range.
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
        if let firmware_core::temperature::TempModel::Poly { terms } = &cal.model {
            let dt = t - cal.t0_c;
            for c in 0..12 {
                let (mut sum, mut abs) = (0.0, 0.0);
                for (k, row) in terms.iter().enumerate() {
                    let v = row[c] * dt.powi(k as i32);
                    sum += v;
                    abs += v.abs();
                }
                let r = abs / sum.abs().max(f64::MIN_POSITIVE);
                if r > worst_ratio.0 {
                    (worst_ratio, at_ratio) = ((r, t), c);
                }
            }
        }
        let k = Coeffs::from_array(&cal.model.eval(cal.t0_c, t)).k;
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
