//! The shape of a temperature model of the 12 coefficients (a polynomial of the scaled
//! temperature difference, or piecewise-linear through breakpoints, as the firmware's
//! tables carry them), its basis functions at a temperature, and the distinct
//! temperatures of a set of data: what every fit of the crate, static, dynamic or
//! diagnostic, stands on.
use crate::error::{ErrorKind, HostError, Result};
use firmware_core::temperature::{pwl_segment, MAX_BREAKPOINTS, MAX_POLY_ORDER};

/// Polynomial fits work in `dT / POLY_SCALE_C` for conditioning.
pub const POLY_SCALE_C: f64 = 50.0;

/// The shape of a temperature model.
#[derive(Debug, Clone, PartialEq)]
pub enum Basis {
    /// Polynomial of `dT = T - T0`.
    Poly {
        /// Order 0..=5 (0: one temperature, no temperature dependence; the firmware
        /// table then carries a zero slope).
        order: usize,
    },
    /// Piecewise-linear through strictly increasing breakpoints (C).
    Pwl {
        /// Breakpoints.
        breakpoints: Vec<f64>,
    },
}

impl Basis {
    /// Number of parameters per coefficient.
    pub fn len(&self) -> usize {
        match self {
            Basis::Poly { order } => order + 1,
            Basis::Pwl { breakpoints } => breakpoints.len(),
        }
    }

    /// True for a basis with no functions (never valid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Check the order / breakpoints fit a firmware table.
    pub fn check(&self) -> Result<()> {
        match self {
            Basis::Poly { order } if *order <= MAX_POLY_ORDER => Ok(()),
            Basis::Poly { order } => Err(HostError::new(
                ErrorKind::Invalid,
                format!("polynomial order {order} is outside 0..={MAX_POLY_ORDER}"),
            )),
            Basis::Pwl { breakpoints } => {
                if !(2..=MAX_BREAKPOINTS).contains(&breakpoints.len()) {
                    return Err(HostError::new(
                        ErrorKind::Invalid,
                        format!(
                        "a piecewise-linear model needs 2..={MAX_BREAKPOINTS} breakpoints, got {}",
                        breakpoints.len()
                    ),
                    ));
                }
                if breakpoints.windows(2).any(|w| w[0] >= w[1])
                    || breakpoints.iter().any(|b| !b.is_finite())
                {
                    return Err(HostError::new(
                        ErrorKind::Invalid,
                        format!(
                            "breakpoints must be finite and strictly increasing: {breakpoints:?}"
                        ),
                    ));
                }
                Ok(())
            }
        }
    }

    /// The basis functions at temperature `t` (poly: powers of the scaled dT; pwl: hat
    /// functions, the end segments extrapolated as the firmware does).
    pub fn eval(&self, t0: f64, t: f64) -> Vec<f64> {
        let mut out = Vec::new();
        self.eval_into(t0, t, &mut out);
        out
    }

    /// [`Basis::eval`] written into `out` (cleared first): the same values, and no new
    /// allocation once `out` has room (the diagnosis evaluates the basis at every window
    /// of every fit it tries).
    pub fn eval_into(&self, t0: f64, t: f64, out: &mut Vec<f64>) {
        out.clear();
        match self {
            Basis::Poly { order } => {
                let x = (t - t0) / POLY_SCALE_C;
                out.extend((0..=*order).map(|k| x.powi(k as i32)));
            }
            Basis::Pwl { breakpoints } => {
                // firmware-core's segment rule, so a fit and its table agree everywhere
                out.resize(breakpoints.len(), 0.0);
                if breakpoints.len() >= 2 {
                    let (s, f) = pwl_segment(breakpoints.len(), |j| breakpoints[j], t);
                    out[s] = 1.0 - f;
                    out[s + 1] = f;
                }
            }
        }
    }

    /// Short text, e.g. `poly3` or `pwl[-40,20,70]`.
    pub fn describe(&self) -> String {
        match self {
            Basis::Poly { order } => format!("poly{order}"),
            Basis::Pwl { breakpoints } => format!(
                "pwl[{}]",
                breakpoints
                    .iter()
                    .map(|b| format!("{b}"))
                    .collect::<Vec<_>>()
                    .join(",")
            ),
        }
    }
}

/// Distinct temperatures in `temps`: sorted, a new cluster starts more than 2 C above
/// the first value of the current one (so a ramp counts as many temperatures).
pub fn temperature_clusters(temps: &[f64]) -> Vec<f64> {
    let mut t: Vec<f64> = temps.to_vec();
    t.sort_by(f64::total_cmp);
    let mut out: Vec<Vec<f64>> = Vec::new();
    for v in t {
        match out.last_mut() {
            Some(c) if v - c[0] <= 2.0 => c.push(v),
            _ => out.push(vec![v]),
        }
    }
    out.iter()
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect()
}
