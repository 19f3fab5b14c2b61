//! Temperature models of the 12 coefficients as fixed tables (model.md section 4).
//!
//! Both kinds store absolute values (relative beta/gamma are fragile when a
//! cross-sensitivity is near zero, model.md section 4):
//! - polynomial: `c(T) = sum_k p_k dT^k`, `dT = T - T0`, order 1..=5;
//! - piecewise-linear: the coefficient values at 2..=16 strictly increasing breakpoints,
//!   linearly interpolated, the end segments extrapolated.
use crate::error::Error;
use crate::model::N_COEFFS;
use crate::real::Real;
use serde::{Deserialize, Serialize};

/// Highest polynomial order a table holds.
pub const MAX_POLY_ORDER: usize = 5;
/// Most breakpoints a piecewise-linear table holds.
pub const MAX_BREAKPOINTS: usize = 16;

/// One value per coefficient, in [`crate::model::COEFF_NAMES`] order.
pub type CoeffRow<R> = [R; N_COEFFS];

/// The temperature model of all 12 coefficients.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TempModel<R> {
    /// Polynomial in `dT = T - T0`: `terms[k]` holds the dT^k coefficient of every
    /// coefficient (so `terms[0]` is the value at T0); `terms.len() = order + 1`.
    Poly {
        /// Coefficients of dT^0, dT^1, ... dT^order.
        terms: heapless::Vec<CoeffRow<R>, { MAX_POLY_ORDER + 1 }>,
    },
    /// Piecewise-linear through breakpoints.
    Pwl {
        /// Strictly increasing temperatures, C.
        breakpoints: heapless::Vec<R, MAX_BREAKPOINTS>,
        /// `values[j]`: the 12 coefficients at `breakpoints[j]`.
        values: heapless::Vec<CoeffRow<R>, MAX_BREAKPOINTS>,
    },
}

/// Everything the compensator needs: the temperature model and how to use it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration<R> {
    /// Reference temperature T0, C: the "passport" constants are `model` at T0.
    pub t0_c: R,
    /// Lowest temperature the model is valid at, C.
    pub t_min_c: R,
    /// Highest temperature the model is valid at, C.
    pub t_max_c: R,
    /// Outside `[t_min_c, t_max_c]`: clamp the temperature (true) or extrapolate (false).
    /// Either way the output is flagged out of range.
    pub clamp: bool,
    /// Method 1/2 recompute their cached matrices only when the temperature moved by
    /// more than this many C since the last update (0 = on every change).
    pub update_step_c: R,
    /// The coefficient tables.
    pub model: TempModel<R>,
    /// Physics beyond the 12 coefficients, found by `host-fit diagnose` (None = off).
    pub physics: Option<Physics<R>>,
}

/// Terms beyond the paper's model (physics-catalogue.md), applied in flight. Per-sample
/// constants are computed on the host for the sample period, so the firmware needs no
/// `exp` (libm's `expf` works in f64 and would pull soft-double code in).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Physics<R> {
    /// The sample period the constants below are for, s.
    pub sample_period_s: R,
    /// `thermal_lag`: one-pole filter on the temperature input,
    /// `T_eff += lag_alpha (T - T_eff)` (`1 - exp(-dt/tau)`; 1 = no lag).
    pub lag_alpha: R,
    /// `temp_rate`: offset per C/s of the temperature rate, per axis (output units).
    pub rate: [R; 3],
    /// Low-pass of the temperature whose difference is the rate (`1 - exp(-dt/tau_r)`).
    pub rate_alpha: R,
    /// `hysteresis`: offsets split `+-h/2` by the direction of the last change, per axis.
    pub hysteresis: [R; 3],
    /// A change of more than this (C) sets the direction.
    pub hysteresis_threshold_c: R,
    /// Direction at power-on (+1 heating, -1 cooling, 0 unknown).
    pub hysteresis_initial: R,
    /// `nonlinearity_k2`: `U_i += k2_i a_i^2`, per axis (output units per g^2).
    pub k2: [R; 3],
    /// `scale_asymmetry`: `U_i += c_i |a_i|` (`c_i = K_ii delta_i`), per axis.
    pub asymmetry: [R; 3],
    /// `warmup_drift`: `U0_i += d_i w`, `w` = 1 at power-on, times `warmup_decay` per sample.
    pub warmup: [R; 3],
    /// `exp(-dt / tau_w)`.
    pub warmup_decay: R,
}

impl<R: Real> Physics<R> {
    /// Check finiteness and ranges.
    pub fn validate(&self) -> Result<(), Error> {
        let scalars = [
            self.sample_period_s,
            self.lag_alpha,
            self.rate_alpha,
            self.hysteresis_threshold_c,
            self.hysteresis_initial,
            self.warmup_decay,
        ];
        let arrays = [
            self.rate,
            self.hysteresis,
            self.k2,
            self.asymmetry,
            self.warmup,
        ];
        if !scalars
            .iter()
            .chain(arrays.iter().flatten())
            .all(|v| v.is_finite())
        {
            return Err(Error::NonFinite);
        }
        let unit = |v: R| v > R::ZERO && v <= R::ONE;
        if self.sample_period_s <= R::ZERO
            || !unit(self.lag_alpha)
            || !unit(self.rate_alpha)
            || self.warmup_decay < R::ZERO
            || self.warmup_decay > R::ONE
            || self.hysteresis_threshold_c < R::ZERO
        {
            return Err(Error::BadRange);
        }
        Ok(())
    }

    /// Convert to another float type.
    pub fn convert<S: Real>(&self) -> Physics<S> {
        let c = |v: R| S::from_f64(v.to_f64());
        let a = |v: [R; 3]| v.map(c);
        Physics {
            sample_period_s: c(self.sample_period_s),
            lag_alpha: c(self.lag_alpha),
            rate: a(self.rate),
            rate_alpha: c(self.rate_alpha),
            hysteresis: a(self.hysteresis),
            hysteresis_threshold_c: c(self.hysteresis_threshold_c),
            hysteresis_initial: c(self.hysteresis_initial),
            k2: a(self.k2),
            asymmetry: a(self.asymmetry),
            warmup: a(self.warmup),
            warmup_decay: c(self.warmup_decay),
        }
    }
}

/// The piecewise-linear segment rule, written once for the firmware's tables and the
/// host's fits: the segment is the last one whose lower breakpoint is <= `t` (the first
/// one when `t` is below the table, or NaN), so the end segments extrapolate. Returns the
/// index of the segment's lower breakpoint and the fraction `(t - b_lo) / (b_hi - b_lo)`
/// (exact to 1.5 ulp: two roundings). Every segment is visited, so the time does not
/// depend on `t`. `None` with fewer than two breakpoints.
pub fn pwl_segment<R: Real>(breakpoints: &[R], t: R) -> Option<(usize, R)> {
    let mut seg = None;
    for (idx, w) in breakpoints.windows(2).enumerate() {
        if let [b0, b1] = w {
            if idx == 0 || t >= *b0 {
                seg = Some((idx, *b0, *b1));
            }
        }
    }
    let (idx, b0, b1) = seg?;
    Some((idx, (t - b0) / (b1 - b0)))
}

fn row_finite<R: Real>(r: &CoeffRow<R>) -> bool {
    r.iter().all(|v| v.is_finite())
}

impl<R: Real> TempModel<R> {
    /// Check sizes, finiteness and breakpoint order.
    pub fn validate(&self) -> Result<(), Error> {
        match self {
            TempModel::Poly { terms } => {
                if terms.len() < 2 {
                    return Err(Error::TableSize);
                }
                if !terms.iter().all(row_finite) {
                    return Err(Error::NonFinite);
                }
            }
            TempModel::Pwl {
                breakpoints,
                values,
            } => {
                if breakpoints.len() < 2 || values.len() != breakpoints.len() {
                    return Err(Error::TableSize);
                }
                if !breakpoints.iter().all(|b| b.is_finite()) || !values.iter().all(row_finite) {
                    return Err(Error::NonFinite);
                }
                if breakpoints.windows(2).any(|w| match w {
                    [a, b] => a >= b,
                    _ => false,
                }) {
                    return Err(Error::BreakpointsNotIncreasing);
                }
            }
        }
        Ok(())
    }

    /// The 12 coefficients at temperature `t` (C), reference `t0` (C).
    ///
    /// Cost is fixed for a given table size (no early exit), so the temperature update
    /// takes the same time wherever `t` is. Outside the breakpoints the end segment is
    /// extrapolated; the caller flags or clamps.
    ///
    /// Error bound (f32, held by tests): Horner's rule gives
    /// `|err| <= 2 n eps sum_k |p_k| |dT|^k` (n = order); the interpolation
    /// `v0 + (v1 - v0) f` gives `|err| <= 4 eps max(|v0|, |v1|)`.
    pub fn eval(&self, t0: R, t: R) -> CoeffRow<R> {
        match self {
            TempModel::Poly { terms } => {
                let dt = t - t0;
                let mut acc = [R::ZERO; N_COEFFS];
                for row in terms.iter().rev() {
                    for (a, p) in acc.iter_mut().zip(row.iter()) {
                        *a = *a * dt + *p;
                    }
                }
                acc
            }
            TempModel::Pwl {
                breakpoints,
                values,
            } => {
                let zero_row = [R::ZERO; N_COEFFS];
                let (seg, f) = pwl_segment(breakpoints, t).unwrap_or((0, R::ZERO));
                let v0 = values.get(seg).unwrap_or(&zero_row);
                let v1 = values.get(seg.wrapping_add(1)).unwrap_or(&zero_row);
                let mut out = [R::ZERO; N_COEFFS];
                for ((o, lo), hi) in out.iter_mut().zip(v0.iter()).zip(v1.iter()) {
                    *o = *lo + (*hi - *lo) * f;
                }
                out
            }
        }
    }

    /// Convert the table to another float type (f64 -> f32 rounds to nearest).
    pub fn convert<S: Real>(&self) -> TempModel<S> {
        let row = |r: &CoeffRow<R>| -> CoeffRow<S> { r.map(|v| S::from_f64(v.to_f64())) };
        match self {
            TempModel::Poly { terms } => TempModel::Poly {
                terms: terms.iter().map(row).collect(),
            },
            TempModel::Pwl {
                breakpoints,
                values,
            } => TempModel::Pwl {
                breakpoints: breakpoints
                    .iter()
                    .map(|b| S::from_f64(b.to_f64()))
                    .collect(),
                values: values.iter().map(row).collect(),
            },
        }
    }
}

impl<R: Real> Calibration<R> {
    /// Check the range, step and tables.
    pub fn validate(&self) -> Result<(), Error> {
        let scalars = [self.t0_c, self.t_min_c, self.t_max_c, self.update_step_c];
        if !scalars.iter().all(|v| v.is_finite()) {
            return Err(Error::NonFinite);
        }
        if self.t_min_c >= self.t_max_c || self.update_step_c < R::ZERO {
            return Err(Error::BadRange);
        }
        if let Some(p) = &self.physics {
            p.validate()?;
        }
        self.model.validate()
    }

    /// The coefficients at the reference temperature (the passport constants).
    pub fn at_t0(&self) -> CoeffRow<R> {
        self.model.eval(self.t0_c, self.t0_c)
    }

    /// Convert to another float type.
    pub fn convert<S: Real>(&self) -> Calibration<S> {
        let c = |v: R| S::from_f64(v.to_f64());
        Calibration {
            t0_c: c(self.t0_c),
            t_min_c: c(self.t_min_c),
            t_max_c: c(self.t_max_c),
            clamp: self.clamp,
            update_step_c: c(self.update_step_c),
            model: self.model.convert(),
            physics: self.physics.as_ref().map(Physics::convert),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(v: f64) -> CoeffRow<f64> {
        core::array::from_fn(|i| v + i as f64)
    }

    #[test]
    fn poly_is_horner_of_dt() {
        let mut terms = heapless::Vec::new();
        terms.push(row(1.0)).unwrap();
        terms.push([0.5; 12]).unwrap();
        terms.push([0.25; 12]).unwrap();
        let m = TempModel::Poly { terms };
        let v = m.eval(20.0, 22.0);
        assert_eq!(v[0], 1.0 + 0.5 * 2.0 + 0.25 * 4.0);
        assert_eq!(v[11], 12.0 + 0.5 * 2.0 + 0.25 * 4.0);
    }

    #[test]
    fn pwl_interpolates_and_extrapolates_end_segments() {
        let m = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[-40.0, 20.0, 70.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0), row(6.0), row(1.0)]).unwrap(),
        };
        assert_eq!(m.eval(20.0, -10.0)[0], 3.0);
        assert_eq!(m.eval(20.0, 20.0)[0], 6.0);
        assert_eq!(m.eval(20.0, 45.0)[0], 3.5);
        assert_eq!(m.eval(20.0, -100.0)[0], -6.0);
        assert_eq!(m.eval(20.0, 120.0)[0], -4.0);
    }

    #[test]
    fn segment_rule_picks_the_last_lower_breakpoint() {
        let b = [-40.0f64, 20.0, 70.0];
        assert_eq!(pwl_segment(&b, -100.0), Some((0, -1.0)));
        assert_eq!(pwl_segment(&b, 20.0), Some((1, 0.0)));
        assert_eq!(pwl_segment(&b, 19.999).map(|s| s.0), Some(0));
        assert_eq!(pwl_segment(&b, 120.0), Some((1, 2.0)));
        assert_eq!(pwl_segment(&b, f64::NAN).map(|s| s.0), Some(0));
        assert_eq!(pwl_segment(&b[..1], 0.0), None);
    }

    #[test]
    fn validate_catches_bad_tables() {
        let bad_order = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[0.0, 0.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0), row(1.0)]).unwrap(),
        };
        assert_eq!(bad_order.validate(), Err(Error::BreakpointsNotIncreasing));
        let bad_len = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[0.0, 1.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0)]).unwrap(),
        };
        assert_eq!(bad_len.validate(), Err(Error::TableSize));
        let mut terms = heapless::Vec::new();
        terms.push(row(0.0)).unwrap();
        assert_eq!(
            TempModel::Poly {
                terms: terms.clone()
            }
            .validate(),
            Err(Error::TableSize)
        );
        terms.push([f64::NAN; 12]).unwrap();
        assert_eq!(TempModel::Poly { terms }.validate(), Err(Error::NonFinite));
    }
}
