//! A fitted temperature model described in the paper's terms: the coefficients at T0,
//! then per interval (pwl) the slopes, or per coefficient the polynomial terms; K terms
//! absolute or as the paper's relative beta/gamma, offsets always absolute (alpha).
use crate::fit::temperature::ModelFit;
use crate::model::basis::Basis;
use firmware_core::model::COEFF_NAMES;
use serde::Serialize;
use std::collections::BTreeMap;

/// The temp-fit output (`temp-fit --json`, and `temperature_model` in `fit --json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModelDescription {
    /// `pwl` or `poly`.
    pub model: &'static str,
    /// Polynomial order (poly).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
    /// Reference temperature, C.
    pub t0_c: f64,
    /// K terms relative to their value at T0 (the paper's beta, gamma).
    pub relative: bool,
    /// The 12 coefficients at T0 (V/g, V).
    pub at_t0: BTreeMap<String, f64>,
    /// Per interval (pwl): the slopes, per C.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub intervals: Option<Vec<Interval>>,
    /// Per coefficient (poly): the terms of dT^1..dT^order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coefficients: Option<BTreeMap<String, Vec<f64>>>,
}

/// One interval of a piecewise-linear model.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Interval {
    /// Lower end, C.
    pub from_c: f64,
    /// Upper end, C.
    pub to_c: f64,
    /// Slope of every coefficient, per C (relative ones: 1/C).
    pub coefficients: BTreeMap<String, f64>,
}

/// The paper's name of a relative coefficient: beta_xx, gamma_xy, alpha_x.
pub fn relative_name(c: usize) -> String {
    let n = COEFF_NAMES[c];
    if let Some(ax) = n.strip_prefix("u0") {
        format!("alpha_{ax}")
    } else {
        let ij = &n[1..];
        if ij.as_bytes()[0] == ij.as_bytes()[1] {
            format!("beta_{ij}")
        } else {
            format!("gamma_{ij}")
        }
    }
}

impl ModelDescription {
    /// Describe `fit`; with `relative`, K terms as beta/gamma relative to their value at T0.
    pub fn of(fit: &ModelFit, relative: bool) -> Self {
        let at_t0 = fit.eval(fit.t0_c);
        let name = |c: usize| {
            if relative || c >= 9 {
                relative_name(c)
            } else {
                COEFF_NAMES[c].to_string()
            }
        };
        let rel = |c: usize, v: f64| if relative && c < 9 { v / at_t0[c] } else { v };
        let mut d = ModelDescription {
            model: "pwl",
            order: None,
            t0_c: fit.t0_c,
            relative,
            at_t0: COEFF_NAMES
                .iter()
                .zip(at_t0)
                .map(|(n, v)| (n.to_string(), v))
                .collect(),
            intervals: None,
            coefficients: None,
        };
        match &fit.basis {
            Basis::Pwl { breakpoints } => {
                let interval = |(k, w): (usize, &[f64])| Interval {
                    from_c: w[0],
                    to_c: w[1],
                    coefficients: (0..12)
                        .map(|c| {
                            let slope = (fit.params[c][k + 1] - fit.params[c][k]) / (w[1] - w[0]);
                            (name(c), rel(c, slope))
                        })
                        .collect(),
                };
                d.intervals = Some(breakpoints.windows(2).enumerate().map(interval).collect());
            }
            Basis::Poly { order } => {
                d.model = "poly";
                d.order = Some(*order);
                d.coefficients = Some(
                    (0..12)
                        .map(|c| {
                            let terms = (1..=*order).map(|k| rel(c, fit.params[c][k])).collect();
                            (name(c), terms)
                        })
                        .collect(),
                );
            }
        }
        d
    }

    /// As text: the model, then per interval or per coefficient its terms.
    pub fn text(&self, basis: &Basis) -> String {
        // a name's unit per C (relative K terms are per unit of K; the table's outputs are
        // taken to be in volts, as the paper's)
        let unit = |k: &str, per: &str| {
            if k.starts_with("alpha") || k.starts_with("u0") {
                format!("V/{per}")
            } else if k.starts_with("beta") || k.starts_with("gamma") {
                format!("1/{per}")
            } else {
                format!("V/g/{per}")
            }
        };
        let mut s = format!(
            "model {}  T0 {} C (the table's outputs taken in V: K in V/g, offsets in V)\n",
            basis.describe(),
            self.t0_c
        );
        for i in self.intervals.iter().flatten() {
            s.push_str(&format!(
                "interval {:.2} .. {:.2} C, slopes:\n",
                i.from_c, i.to_c
            ));
            for (k, v) in &i.coefficients {
                s.push_str(&format!("  {k:<10} {v:>14.6e} {}\n", unit(k, "C")));
            }
        }
        for (k, v) in self.coefficients.iter().flatten() {
            let terms: Vec<String> = v
                .iter()
                .enumerate()
                .map(|(p, t)| format!("{t:.6e} {}", unit(k, &format!("C^{}", p + 1))))
                .collect();
            s.push_str(&format!("  {k:<10} dT^1.. : {}\n", terms.join(", ")));
        }
        s.trim_end().to_string()
    }
}
