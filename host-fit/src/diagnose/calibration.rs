//! The extended model as a firmware calibration, for `diagnose --out`: the final model's
//! coefficients as a piecewise-linear table and the in-flight physics terms it found.
use crate::diagnose::design::Extra;
use crate::diagnose::params::{Param, Term};
use crate::diagnose::Diagnosis;
use firmware_core::temperature::{Calibration, Physics, TempModel};

impl Diagnosis {
    /// The final model's value of a per-axis term (0 where it was not fitted).
    fn term(&self, term: Term) -> [f64; 3] {
        let f = &self.final_fit;
        std::array::from_fn(|axis| {
            f.labels
                .iter()
                .position(|l| *l == Param::Effect { term, axis })
                .map(|j| f.x[j])
                .unwrap_or(0.0)
        })
    }

    /// The extended model as a firmware calibration: the final model's coefficients as a
    /// piecewise-linear table (up to 16 points, which also carries a temp_curvature
    /// finding), and the in-flight physics terms of the findings (fixture_error only
    /// corrects the calibration, which the final fit already does).
    pub fn calibration(&self, t0: f64) -> Calibration<f64> {
        let dt = self.sample_period_s;
        let mut ph = Physics {
            sample_period_s: dt,
            lag_alpha: 1.0,
            rate: [0.0; 3],
            rate_alpha: 1.0 - (-dt / 30.0f64).exp(),
            hysteresis: [0.0; 3],
            hysteresis_threshold_c: 0.5,
            hysteresis_initial: self.initial_direction,
            k2: [0.0; 3],
            asymmetry: [0.0; 3],
            warmup: [0.0; 3],
            warmup_decay: 1.0,
        };
        let mut any = false;
        for e in &self.final_fit.spec.extras {
            any |= !matches!(e, Extra::Curvature(_) | Extra::Fixture(_));
            match e {
                Extra::Lag(tau) => ph.lag_alpha = 1.0 - (-dt / tau).exp(),
                Extra::Rate => ph.rate = self.term(Term::Rate),
                Extra::Hysteresis => ph.hysteresis = self.term(Term::Hysteresis),
                Extra::K2 => ph.k2 = self.term(Term::K2),
                Extra::Asymmetry => ph.asymmetry = self.term(Term::Asymmetry),
                Extra::Warmup(tau) => {
                    ph.warmup = self.term(Term::Warmup);
                    ph.warmup_decay = (-dt / tau).exp();
                }
                Extra::Curvature(_) | Extra::Fixture(_) => {}
            }
        }
        let (lo, hi) = (
            self.table.first().map(|r| r.0).unwrap_or(t0 - 1.0),
            self.table.last().map(|r| r.0).unwrap_or(t0 + 1.0),
        );
        Calibration {
            t0_c: t0,
            t_min_c: lo,
            t_max_c: hi.max(lo + 1.0),
            clamp: false,
            update_step_c: 0.1,
            model: TempModel::Pwl {
                breakpoints: self.table.iter().map(|r| r.0).collect(),
                values: self.table.iter().map(|r| r.1).collect(),
            },
            physics: any.then_some(ph),
        }
    }
}
