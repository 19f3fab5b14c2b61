//! The flashed model as a firmware calibration, for `diagnose --out`: its coefficients as
//! the polynomial itself or a piecewise-linear table, and its in-flight physics terms.
use crate::blob::Cache;
use crate::diagnose::effects::Extra;
use crate::diagnose::params::{Param, Term};
use crate::diagnose::Diagnosis;
use crate::error::{HostError, Result};
use crate::fit::temperature::{Basis, POLY_SCALE_C};
use firmware_core::model::{K_INDEX, U0_INDEX};
use firmware_core::temperature::{Calibration, Physics, TempModel};

impl Diagnosis {
    /// The final model's values of a per-axis term of extra `e` (0 where not fitted).
    fn term(&self, e: usize, term: Term) -> [f64; 3] {
        let f = &self.flashed;
        std::array::from_fn(|axis| {
            f.labels
                .iter()
                .position(|l| {
                    *l == Param::Effect {
                        term,
                        axis,
                        extra: e,
                    }
                })
                .map(|j| f.x[j])
                .unwrap_or(0.0)
        })
    }

    /// The in-flight terms in the firmware's form, every time constant in seconds (the
    /// firmware derives its per-step constants from its own clock); `None` when there
    /// are none.
    fn physics(&self) -> Result<Option<Physics<f64>>> {
        let mut ph = Physics::<f64>::neutral();
        ph.hysteresis_threshold_c = 0.5;
        let refuse = |what: &str| {
            Err(HostError::msg(format!(
                "the fitted {what} cannot be flashed by this firmware's physics block; the blob would not compensate what was fitted"
            )))
        };
        let mut any = false;
        for (e, x) in self.flashed.spec.extras.iter().enumerate() {
            any |= !matches!(
                x,
                Extra::Curvature(_) | Extra::Bend { .. } | Extra::Fixture(_)
            );
            match x {
                Extra::Lag { taus } => {
                    if taus.iter().any(|t| *t != taus[0] || t[1] > 0.0) {
                        return refuse("thermal lag (per-axis or two-pole)");
                    }
                    ph.lag_tau_s = taus[0][0];
                }
                Extra::Rate { tau_s } => {
                    ph.rate = self.term(e, Term::Rate);
                    ph.rate_tau_s = *tau_s;
                }
                Extra::Hysteresis {
                    threshold_c,
                    initial,
                    scale,
                } => {
                    if *scale {
                        return refuse("hysteresis of the scale factors");
                    }
                    ph.hysteresis = self.term(e, Term::Hysteresis);
                    ph.hysteresis_threshold_c = *threshold_c;
                    ph.hysteresis_initial = *initial;
                }
                Extra::K2 => ph.k2 = self.term(e, Term::K2),
                Extra::Asymmetry => ph.asymmetry = self.term(e, Term::Asymmetry),
                Extra::Warmup { tau_s, .. } => {
                    // in flight the clock restarts at power-on only, as it does here at
                    // the recording's start and its stated power-offs; handling does not
                    // happen
                    if ph.warmup != [0.0; 3] {
                        return refuse("second warm-up time constant");
                    }
                    ph.warmup = self.term(e, Term::Warmup);
                    ph.warmup_tau_s = *tau_s;
                }
                Extra::Curvature(_) | Extra::Bend { .. } | Extra::Fixture(_) => {}
            }
        }
        Ok(any.then_some(ph))
    }

    /// The extended model as a firmware calibration: the final model's coefficients as a
    /// piecewise-linear table (up to 16 points, which also carries a temp_curvature
    /// finding), and the in-flight physics terms (fixture_error only corrects the
    /// calibration, which the final fit already does).
    pub fn calibration(&self, t0: f64) -> Result<Calibration<f64>> {
        let (lo, hi) = (
            self.table.first().map(|r| r.0).unwrap_or(t0 - 1.0),
            self.table.last().map(|r| r.0).unwrap_or(t0 + 1.0),
        );
        let mut cal = Calibration {
            t0_c: t0,
            t_min_c: lo,
            t_max_c: hi.max(lo + 1.0),
            clamp: false,
            update_step_c: 0.0,
            model: self.poly_table().unwrap_or_else(|| TempModel::Pwl {
                breakpoints: self.table.iter().map(|r| r.0).collect(),
                values: self.table.iter().map(|r| r.1).collect(),
            }),
            physics: self.physics()?,
        };
        // the firmware's cache within the floor of a window mean (in g: over the mean
        // scale factor at T0), as `fit` keeps it within a dwell's own noise
        let c0 = cal.at_t0();
        let k = (c0[0].abs() + c0[1].abs() + c0[2].abs()) / 3.0;
        let floor_mg = (k > 0.0).then(|| self.noise_rms / k * 1e3);
        cal.update_step_c = Cache::choose(&cal, floor_mg, None).step_c;
        Ok(cal)
    }

    /// The flashed model's polynomial itself, when its temperature dependence is one (no
    /// bend, no fine offsets): exact, where a table through it would interpolate.
    fn poly_table(&self) -> Option<TempModel<f64>> {
        let f = &self.flashed;
        let Basis::Poly { order } = f.spec.basis else {
            return None;
        };
        if f.spec
            .extras
            .iter()
            .any(|e| matches!(e, Extra::Curvature(_) | Extra::Bend { .. }))
        {
            return None;
        }
        let mut terms = vec![[0.0; 12]; (order + 1).max(2)];
        for (c, l) in f.labels.iter().enumerate() {
            let (slot, k) = match *l {
                Param::K { i, j, k } => (K_INDEX[i][j], k),
                Param::U0 { i, k } => (U0_INDEX[i], k),
                _ => continue,
            };
            // the fit's basis is powers of dT / POLY_SCALE_C
            terms[k][slot] += f.x[c] / POLY_SCALE_C.powi(k as i32);
        }
        Some(TempModel::Poly {
            terms: terms.into_iter().collect(),
        })
    }
}
