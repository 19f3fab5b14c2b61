//! The temperature model chosen by the data: every candidate family and order (poly
//! 0..5, pwl through the stops and pwl with one interior stop dropped) is scored by
//! k-fold cross-validation over the calibration dwells, by what the blob would deliver
//! on dwells it was not fitted on (rms of formula (13), |a| - 1, after compensation), and
//! the simplest candidate within one standard error of the best is chosen (the usual
//! one-standard-error rule: a richer model must earn its parameters on held-out data).
//! Verification positions are never used here, so they stay an independent check.
use crate::error::{HostError, Result};
use crate::fit::identify::Obs;
use crate::fit::temperature::{fit_joint, temperature_clusters, Basis, Setting};
use firmware_core::model::{apply, dg, invert, Coeffs};
use firmware_core::temperature::{MAX_BREAKPOINTS, MAX_POLY_ORDER};
use serde::Serialize;
use std::path::Path;

/// Folds of the cross-validation (fewer when there are fewer dwells).
pub const FOLDS: usize = 5;

/// One candidate model and its held-out score.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Candidate {
    /// `polyN` or `pwl[...]`.
    pub model: String,
    /// Parameters per coefficient.
    pub params_per_coefficient: usize,
    /// rms |dg| over the held-out dwells, mg (None: a fold does not determine it).
    pub held_out_rms_dg_mg: Option<f64>,
    /// Its standard error, mg.
    pub standard_error_mg: Option<f64>,
}

/// What the data chose, and why.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Selection {
    /// The chosen model, as [`Basis::describe`].
    pub chosen: String,
    /// How it was chosen.
    pub method: String,
    /// Why, in one sentence.
    pub reason: String,
    /// Every candidate, simplest first.
    pub candidates: Vec<Candidate>,
    /// The chosen basis.
    #[serde(skip)]
    pub basis: Basis,
}

/// The candidates for data at `temps` (C), simplest first: polynomials up to one order
/// below the number of distinct temperatures, the pwl through them (at most 16, evenly
/// picked) and the pwls with one interior breakpoint dropped.
pub fn candidates(temps: &[f64]) -> Vec<Basis> {
    let clusters: Vec<f64> = temperature_clusters(temps)
        .iter()
        .map(|t| (t * 100.0).round() / 100.0)
        .collect();
    let m = clusters.len();
    let mut out: Vec<Basis> = (0..m.min(MAX_POLY_ORDER + 1))
        .map(|order| Basis::Poly { order })
        .collect();
    if m >= 3 {
        let bps: Vec<f64> = if m <= MAX_BREAKPOINTS {
            clusters.clone()
        } else {
            (0..MAX_BREAKPOINTS)
                .map(|k| clusters[k * (m - 1) / (MAX_BREAKPOINTS - 1)])
                .collect()
        };
        if bps.len() >= 4 {
            for drop in 1..bps.len() - 1 {
                let mut b = bps.clone();
                b.remove(drop);
                out.push(Basis::Pwl { breakpoints: b });
            }
        }
        out.push(Basis::Pwl { breakpoints: bps });
    }
    // simplest first; a polynomial before a pwl of as many parameters (smooth between
    // the stops, where no data says otherwise)
    out.sort_by_key(|b| (b.len(), matches!(b, Basis::Pwl { .. })));
    out
}

/// Formula (13) for observation `o` compensated by `cal` (the tables the blob carries;
/// an even-order term is not in the blob), in g; None when K is singular there.
fn dg_with(cal: &firmware_core::temperature::Calibration<f64>, o: &Obs) -> Option<f64> {
    let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, o.temp_c));
    let n = invert(&c.k)?;
    Some(dg(&apply(&n, o.u, c.u0)))
}

/// The fold of every observation: its dwell's rank among the dwells, modulo `k`.
fn folds(obs: &[Obs], k: usize) -> Vec<usize> {
    let mut dwells: Vec<usize> = obs.iter().map(|o| o.dwell).collect();
    dwells.sort_unstable();
    dwells.dedup();
    obs.iter()
        .map(|o| dwells.binary_search(&o.dwell).unwrap_or(0) % k.max(1))
        .collect()
}

/// A candidate's held-out score: rms |dg| over the held-out dwells and its standard
/// error, g.
#[derive(Debug, Clone, Copy)]
struct Score {
    rms: f64,
    se: f64,
}

/// Per held-out dwell, the mean squared dg (g^2) of `basis` under `k`-fold
/// cross-validation; None when a training fold does not determine the model.
fn held_out(obs: &[Obs], basis: &Basis, setting: &Setting, k: usize) -> Option<Vec<f64>> {
    let fold = folds(obs, k);
    let mut per_dwell: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    let quiet = Setting {
        path: Path::new(""),
        ..*setting
    };
    for f in 0..k {
        let train: Vec<Obs> = obs
            .iter()
            .zip(&fold)
            .filter(|(_, g)| **g != f)
            .map(|(o, _)| o.clone())
            .collect();
        let fit = fit_joint(&train, basis, &quiet).ok()?;
        let cal = fit.calibration(0.0, false);
        for (o, _) in obs.iter().zip(&fold).filter(|(_, g)| **g == f) {
            let d = dg_with(&cal, o)?;
            let e = per_dwell.entry(o.dwell).or_insert((0.0, 0));
            e.0 += d * d;
            e.1 += 1;
        }
    }
    Some(per_dwell.values().map(|(s, n)| s / *n as f64).collect())
}

/// rms and its standard error from per-dwell mean squares.
fn rms_se(e: &[f64]) -> Score {
    let n = e.len().max(1) as f64;
    let mean = e.iter().sum::<f64>() / n;
    let var = e.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let rms = mean.sqrt();
    let se = if rms > 0.0 {
        (var / n).sqrt() / (2.0 * rms)
    } else {
        0.0
    };
    Score { rms, se }
}

/// The selection when all calibration data are at one temperature: the coefficients
/// there, no temperature model.
fn one_temperature(temps: &[f64]) -> Selection {
    let t = temps.iter().sum::<f64>() / temps.len().max(1) as f64;
    Selection {
        chosen: Basis::Poly { order: 0 }.describe(),
        method: "none: one temperature".into(),
        reason: format!(
            "all calibration data are at one temperature ({t:.1} C): the 12 coefficients are identified there, and no temperature model can be fitted (the blob holds them constant)"
        ),
        candidates: Vec::new(),
        basis: Basis::Poly { order: 0 },
    }
}

/// Choose the temperature model of the static observations `obs` (see the module doc)
/// among the candidates `keep` accepts (one family, when the user named it), every fit
/// in `setting` (its frame: lower triangular K(T) for the convention of estimated
/// poses).
pub fn choose_among(
    obs: &[Obs],
    setting: &Setting,
    keep: &dyn Fn(&Basis) -> bool,
) -> Result<Selection> {
    let path = setting.path;
    let temps: Vec<f64> = obs.iter().map(|o| o.temp_c).collect();
    let all = candidates(&temps);
    let n_all = all.len();
    let cands: Vec<Basis> = all.into_iter().filter(|b| keep(b)).collect();
    if cands.is_empty() {
        return Err(HostError::in_file(
            path,
            format!(
                "no model of that family can be fitted to calibration data at {} temperature(s)",
                temperature_clusters(&temps).len()
            ),
        ));
    }
    let mut dwells: Vec<usize> = obs.iter().map(|o| o.dwell).collect();
    dwells.sort_unstable();
    dwells.dedup();
    if n_all <= 1 {
        return Ok(one_temperature(&temps));
    }
    // when all the data do not determine even the simplest candidate, say why (which
    // positions at which temperatures), not that cross-validation failed
    if let Some(simplest) = cands.first() {
        fit_joint(obs, simplest, setting)?;
    }
    let k = FOLDS.min(dwells.len());
    let scored: Vec<(Basis, Option<Score>)> = cands
        .into_iter()
        .map(|b| {
            let s = held_out(obs, &b, setting, k).map(|e| rms_se(&e));
            (b, s)
        })
        .collect();
    let (best, bs) = scored
        .iter()
        .filter_map(|(b, s)| s.map(|s| (b, s)))
        .min_by(|x, y| x.1.rms.total_cmp(&y.1.rms))
        .map(|(b, s)| (b.clone(), s))
        .ok_or_else(|| {
            HostError::in_file(
                path,
                format!(
                    "no temperature model is determined when a fifth of the {} calibration dwells is held out: too few positions or temperatures for cross-validation (give --model)",
                    dwells.len()
                ),
            )
        })?;
    let limit = bs.rms + bs.se;
    let (chosen, cs) = scored
        .iter()
        .find_map(|(b, s)| s.filter(|s| s.rms <= limit).map(|s| (b.clone(), s)))
        .unwrap_or((best.clone(), bs));
    let mg = 1e3;
    let reason = if chosen == best {
        format!(
            "{} predicts held-out dwells best: rms |dg| {:.4} mg (+- {:.4})",
            chosen.describe(),
            cs.rms * mg,
            cs.se * mg
        )
    } else {
        format!(
            "{} is the simplest model within one standard error of the best ({} {:.4} +- {:.4} mg): rms |dg| {:.4} mg on held-out dwells",
            chosen.describe(),
            best.describe(),
            bs.rms * mg,
            bs.se * mg,
            cs.rms * mg
        )
    };
    Ok(Selection {
        chosen: chosen.describe(),
        method: format!(
            "{k}-fold cross-validation over {} static calibration dwells (every {k}th dwell held out in turn)",
            dwells.len()
        ),
        reason,
        candidates: scored
            .iter()
            .map(|(b, s)| Candidate {
                model: b.describe(),
                params_per_coefficient: b.len(),
                held_out_rms_dg_mg: s.map(|s| s.rms * mg),
                standard_error_mg: s.map(|s| s.se * mg),
            })
            .collect(),
        basis: chosen,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_are_simplest_first_and_fit_the_temperatures() {
        let temps = [-40.0, -39.8, -10.0, 20.1, 45.0, 70.0];
        let c = candidates(&temps);
        let names: Vec<String> = c.iter().map(Basis::describe).collect();
        // five temperatures: poly0..poly4, the pwl through them and three with an
        // interior breakpoint dropped
        assert_eq!(c.len(), 5 + 1 + 3, "{names:?}");
        assert!(c.windows(2).all(|w| w[0].len() <= w[1].len()), "{names:?}");
        assert_eq!(names.first().map(String::as_str), Some("poly0"));
        assert!(
            names.contains(&"pwl[-39.9,-10,20.1,45,70]".to_string()),
            "{names:?}"
        );
        assert_eq!(candidates(&[20.0, 20.3]), vec![Basis::Poly { order: 0 }]);
    }
}
