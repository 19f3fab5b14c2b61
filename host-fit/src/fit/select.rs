//! The temperature model chosen by the data: every candidate family and order (poly
//! 0..5, pwl through the stops and pwl with one interior stop dropped) is scored by
//! k-fold cross-validation over the calibration dwells, by what the blob would deliver
//! on dwells it was not fitted on (rms of formula (13), |a| - 1, after compensation), and
//! the simplest candidate within one standard error of the best is chosen (the usual
//! one-standard-error rule: a richer model must earn its parameters on held-out data).
//! Verification positions are never used here, so they stay an independent check. The
//! folds keep every training fold's design determined as the full data have it
//! ([`crate::fit::folds`]): every candidate is scored on the same held-out dwells, and
//! none is lost to the fold design.
use crate::data::positions::Positions;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::folds::{design, FoldDesign};
use crate::fit::identify::Obs;
use crate::fit::temperature::{fit_joint, ModelFit, Setting};
use crate::model::basis::{temperature_clusters, Basis};
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
    /// Why it has no score (the full data do not determine it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_scored: Option<String>,
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
    /// Calibration dwells held out in some fold (every candidate scored on these).
    pub held_out_dwells: usize,
    /// The dwells never held out, `POSITION at T C`: without any one of them a training
    /// fold would not determine a candidate, or a temperature's coefficients, that the
    /// full data determine.
    pub never_held_out: Vec<String>,
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

/// A candidate's held-out score: rms |dg| over the held-out dwells and its standard
/// error, g.
#[derive(Debug, Clone, Copy)]
struct Score {
    rms: f64,
    se: f64,
}

/// Per held-out dwell, the mean squared dg (g^2) of `basis` under the folds of `folds`;
/// None when a training fold does not determine the model (the fold design keeps what
/// the full data determine, so only a model the full data do not determine).
fn held_out(obs: &[Obs], basis: &Basis, setting: &Setting, folds: &FoldDesign) -> Option<Vec<f64>> {
    let fold: Vec<Option<usize>> = obs.iter().map(|o| folds.fold_of(o.dwell)).collect();
    let mut per_dwell: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    let quiet = Setting {
        path: Path::new(""),
        ..*setting
    };
    for f in 0..folds.k {
        let train: Vec<Obs> = obs
            .iter()
            .zip(&fold)
            .filter(|(_, g)| **g != Some(f))
            .map(|(o, _)| o.clone())
            .collect();
        if train.len() == obs.len() {
            continue;
        }
        let fit = fit_joint(&train, basis, &quiet).ok()?;
        let cal = fit.calibration(0.0, false);
        for (o, _) in obs.iter().zip(&fold).filter(|(_, g)| **g == Some(f)) {
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
        held_out_dwells: 0,
        never_held_out: Vec::new(),
        basis: Basis::Poly { order: 0 },
    }
}

/// One candidate of the selection.
struct Scored {
    /// Its basis.
    basis: Basis,
    /// Its held-out score, or why it has none.
    score: std::result::Result<Score, String>,
}

/// Score the candidates `keep` accepts among `all`, every one on the same held-out dwells
/// of a fold design that keeps every candidate the full data determine (whatever `keep`
/// says: the folds are the data's, not the family's) determined in every training fold.
fn score(
    obs: &[Obs],
    all: Vec<Basis>,
    setting: &Setting,
    keep: &dyn Fn(&Basis) -> bool,
    k: usize,
) -> (Vec<Scored>, FoldDesign) {
    let quiet = Setting {
        path: Path::new(""),
        ..*setting
    };
    let fitted: Vec<(Basis, Option<ModelFit>)> = all
        .into_iter()
        .map(|b| {
            let f = fit_joint(obs, &b, &quiet).ok();
            (b, f)
        })
        .collect();
    let determined: Vec<(Basis, ModelFit)> = fitted
        .iter()
        .filter_map(|(b, f)| f.clone().map(|f| (b.clone(), f)))
        .collect();
    let folds = design(obs, &determined, setting, k);
    let scored = fitted
        .into_iter()
        .filter(|(b, _)| keep(b))
        .map(|(b, f)| {
            let s = match f {
                None => Err("the data do not determine it".to_string()),
                Some(_) => held_out(obs, &b, setting, &folds)
                    .map(|e| rms_se(&e))
                    .ok_or_else(|| "a training fold does not determine it".to_string()),
            };
            Scored { basis: b, score: s }
        })
        .collect();
    (scored, folds)
}

/// `POSITION at T C` of every dwell `folds` never holds out.
fn never_held_out(obs: &[Obs], folds: &FoldDesign, positions: &Positions) -> Vec<String> {
    folds
        .never_held_out()
        .into_iter()
        .filter_map(|d| {
            let w: Vec<&Obs> = obs.iter().filter(|o| o.dwell == d).collect();
            let first = w.first()?;
            let t = w.iter().map(|o| o.temp_c).sum::<f64>() / w.len() as f64;
            Some(format!("{} at {t:.1} C", positions.name(first.position)))
        })
        .collect()
}

/// Choose the temperature model of the static observations `obs` (see the module doc)
/// among the candidates `keep` accepts (one family, when the user named it), every fit
/// in `setting` (its frame: lower triangular K(T) for the convention of estimated
/// poses); `positions` names the dwells.
pub fn choose_among(
    obs: &[Obs],
    setting: &Setting,
    keep: &dyn Fn(&Basis) -> bool,
    positions: &Positions,
) -> Result<Selection> {
    let path = setting.path;
    let temps: Vec<f64> = obs.iter().map(|o| o.temp_c).collect();
    let all = candidates(&temps);
    if !all.iter().any(keep) {
        return Err(HostError::in_file(
            ErrorKind::Insufficient,
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
    if all.len() <= 1 {
        return Ok(one_temperature(&temps));
    }
    // when all the data do not determine even the simplest candidate, say why (which
    // positions at which temperatures), not that cross-validation failed
    if let Some(simplest) = all.iter().find(|b| keep(b)) {
        fit_joint(obs, simplest, setting)?;
    }
    let k = FOLDS.min(dwells.len());
    let (scored, folds) = score(obs, all, setting, keep, k);
    let (best, bs) = scored
        .iter()
        .filter_map(|c| c.score.as_ref().ok().map(|s| (&c.basis, *s)))
        .min_by(|x, y| x.1.rms.total_cmp(&y.1.rms))
        .map(|(b, s)| (b.clone(), s))
        .ok_or_else(|| {
            HostError::in_file(
                ErrorKind::Insufficient,
                path,
                format!(
                    "no dwell of the {} calibration dwells can be held out without leaving the model undetermined: too few positions or temperatures for cross-validation (give --model)",
                    dwells.len()
                ),
            )
        })?;
    let limit = bs.rms + bs.se;
    let (chosen, cs) = scored
        .iter()
        .find_map(|c| {
            c.score
                .as_ref()
                .ok()
                .filter(|s| s.rms <= limit)
                .map(|s| (c.basis.clone(), *s))
        })
        .unwrap_or((best.clone(), bs));
    let never = never_held_out(obs, &folds, positions);
    Ok(Selection {
        chosen: chosen.describe(),
        method: method_text(k, dwells.len(), &folds, &never),
        reason: reason_text((&chosen, cs), (&best, bs)),
        candidates: scored
            .iter()
            .map(|c| Candidate {
                model: c.basis.describe(),
                params_per_coefficient: c.basis.len(),
                held_out_rms_dg_mg: c.score.as_ref().ok().map(|s| s.rms * 1e3),
                standard_error_mg: c.score.as_ref().ok().map(|s| s.se * 1e3),
                not_scored: c.score.as_ref().err().cloned(),
            })
            .collect(),
        held_out_dwells: folds.held_out(),
        never_held_out: never,
        basis: chosen,
    })
}

/// How the model was chosen, in words: the folds and the dwells never held out.
fn method_text(k: usize, dwells: usize, folds: &FoldDesign, never: &[String]) -> String {
    let mut s = format!(
        "{k}-fold cross-validation over {dwells} static calibration dwells (every {k}th dwell held out in turn"
    );
    if never.is_empty() {
        s.push(')');
    } else {
        s.push_str(&format!(
            "; {} never held out, since a training fold without it would not determine a candidate or a temperature's coefficients that the full data determine: {}; every candidate scored on the same {} held-out dwells)",
            never.len(),
            never.join(", "),
            folds.held_out()
        ));
    }
    s
}

/// Why `chosen` (with its score), against the `best`.
fn reason_text(chosen: (&Basis, Score), best: (&Basis, Score)) -> String {
    let ((c, cs), (b, bs)) = (chosen, best);
    let mg = 1e3;
    if c == b {
        format!(
            "{} predicts held-out dwells best: rms |dg| {:.4} mg (+- {:.4})",
            c.describe(),
            cs.rms * mg,
            cs.se * mg
        )
    } else {
        format!(
            "{} is the simplest model within one standard error of the best ({} {:.4} +- {:.4} mg): rms |dg| {:.4} mg on held-out dwells",
            c.describe(),
            b.describe(),
            bs.rms * mg,
            bs.se * mg,
            cs.rms * mg
        )
    }
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
