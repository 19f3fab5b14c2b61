//! Temperature models of the 12 coefficients: fitted jointly from all dwells, or from
//! per-stop coefficient tables (the paper's route, formulas (11), (12)).
use crate::data::table::TableRow;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::identify::Obs;
use crate::fit::noise::Noise;
use crate::model::basis::{temperature_clusters, Basis, POLY_SCALE_C};
use crate::model::lsq::{weighted_lsq, Lsq};
use firmware_core::model::{K_INDEX, U0_INDEX};
use firmware_core::temperature::{Calibration, TempModel};
use nalgebra::{DMatrix, DVector};
use std::path::Path;

/// The valid range of a fitted model reaches this far (C) beyond its data: a dwell at
/// the last stop, taken while the case still settles, reads a few tenths of a degree
/// past the calibration dwells, and a model is no worse there than at its data's edge.
pub const RANGE_MARGIN_C: f64 = 1.0;

/// The firmware recomputes its cached matrices after the temperature moves by this much
/// (the blob's default, `fit --update-step`): the lag it adds to |dg| stays an order of
/// magnitude below the acceptance limit near T0 (0.03 mg against 0.3 mg on the paper's
/// unit), and the MCU inverts K(T) ten times per degree instead of every sample.
pub const UPDATE_STEP_C: f64 = 0.1;

/// A fitted temperature model of the 12 coefficients, in f64.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelFit {
    /// The basis.
    pub basis: Basis,
    /// Reference temperature, C.
    pub t0_c: f64,
    /// Per coefficient: absolute parameters (poly: coefficient of dT^k; pwl: value at
    /// breakpoint k).
    pub params: [Vec<f64>; 12],
    /// Their standard errors.
    pub stderr: [Vec<f64>; 12],
    /// Per axis: the even-order term, temperature-independent, when determined.
    pub k2: [Option<f64>; 3],
    /// Temperature range of the data, C.
    pub t_range: (f64, f64),
    /// Weighted residual sum of squares (chi-square with 1/variance weights).
    pub chi2: f64,
    /// Observations (per axis, summed over axes).
    pub n_obs: usize,
    /// Parameters fitted (all axes).
    pub n_params: usize,
    /// Per axis (joint fits only): the solver's parameters' covariance, in the order
    /// `a_x phi, a_y phi, a_z phi, phi[, a_i^2]` with `phi` = [`Basis::eval`], from the
    /// weights (1/noise variance) alone; [`ModelFit::axis_scale`] says by how much the
    /// residuals ask to widen it.
    pub axis_cov: Vec<DMatrix<f64>>,
    /// Per axis (joint fits only): weighted residual sum of squares and degrees of freedom.
    pub axis_chi2: Vec<(f64, usize)>,
}

impl ModelFit {
    /// Per axis, the factor on [`ModelFit::axis_cov`]: the reduced chi-square when it
    /// exceeds 1 (scatter beyond the in-dwell noise: the model misfits, or dwells
    /// differ by more than their samples do), else 1. With `noise_known` false the
    /// weights carried no noise level (a dwell-averaged recording) and the reduced
    /// chi-square is the variance itself.
    pub fn axis_scale(&self, axis: usize, noise_known: bool) -> f64 {
        let Some((chi2, dof)) = self.axis_chi2.get(axis) else {
            return 1.0;
        };
        if *dof == 0 {
            return if noise_known { 1.0 } else { f64::NAN };
        }
        let red = chi2 / *dof as f64;
        if noise_known {
            red.max(1.0)
        } else {
            red
        }
    }
}

impl ModelFit {
    /// The coefficients at temperature `t`.
    pub fn eval(&self, t: f64) -> [f64; 12] {
        self.calibration(0.0, false).model.eval(self.t0_c, t)
    }

    /// As a firmware calibration (f64 tables; `convert::<f32>()` for the blob). The
    /// valid range is the data's widened by [`RANGE_MARGIN_C`], and to the breakpoints
    /// of a pwl model.
    pub fn calibration(&self, update_step_c: f64, clamp: bool) -> Calibration<f64> {
        let (mut lo, mut hi) = (
            self.t_range.0 - RANGE_MARGIN_C,
            self.t_range.1 + RANGE_MARGIN_C,
        );
        let model = match &self.basis {
            Basis::Poly { order } => TempModel::Poly {
                // the firmware's table has at least a slope: order 0 stores a zero one
                terms: (0..=(*order).max(1))
                    .map(|k| std::array::from_fn(|c| self.params[c].get(k).copied().unwrap_or(0.0)))
                    .collect(),
            },
            Basis::Pwl { breakpoints } => {
                lo = lo.min(breakpoints[0]);
                hi = hi.max(breakpoints[breakpoints.len() - 1]);
                TempModel::Pwl {
                    breakpoints: breakpoints.iter().copied().collect(),
                    values: (0..breakpoints.len())
                        .map(|k| std::array::from_fn(|c| self.params[c][k]))
                        .collect(),
                }
            }
        };
        if hi <= lo {
            hi = lo + 1.0;
        }
        Calibration {
            t0_c: self.t0_c,
            t_min_c: lo,
            t_max_c: hi,
            clamp,
            update_step_c,
            model,
            physics: None,
        }
    }
}

fn unscale(basis: &Basis, k: usize, v: f64) -> f64 {
    match basis {
        Basis::Poly { .. } => v / POLY_SCALE_C.powi(k as i32),
        Basis::Pwl { .. } => v,
    }
}

/// Whether data at `temps` can determine `basis` at all: a polynomial needs as many
/// distinct temperatures as parameters, a pwl data on both sides of every breakpoint.
pub(crate) fn check_coverage(basis: &Basis, temps: &[f64]) -> Result<()> {
    let clusters = temperature_clusters(temps);
    let list = clusters
        .iter()
        .map(|t| format!("{t:.1}"))
        .collect::<Vec<_>>()
        .join(", ");
    match basis {
        Basis::Poly { order } if clusters.len() < order + 1 => Err(HostError::new(ErrorKind::Insufficient, format!(
            "a polynomial of order {order} needs data at {} or more temperatures; there are {} ({list} C)",
            order + 1,
            clusters.len()
        ))),
        Basis::Pwl { breakpoints } => {
            for (j, b) in breakpoints.iter().enumerate() {
                let lo = if j == 0 { f64::NEG_INFINITY } else { breakpoints[j - 1] };
                let hi = breakpoints.get(j + 1).copied().unwrap_or(f64::INFINITY);
                if !temps.iter().any(|t| *t > lo && *t < hi) {
                    return Err(HostError::new(ErrorKind::Insufficient, format!(
                        "no data between {lo} and {hi} C to determine the breakpoint at {b} C (data at {list} C)"
                    )));
                }
            }
            Ok(())
        }
        Basis::Poly { .. } => Ok(()),
    }
}

/// The frame of the 12 coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// Fixed by the positions' given orientations: K(T) is full.
    Given,
    /// No pose's orientation is given: the convention fixes it, K(T) lower triangular at
    /// every temperature (kxy, kxz, kyz held at 0), which also removes a rotation of the
    /// frame that varies with temperature (each pose is seen over a narrow span of
    /// temperatures, so such a rotation is all but invisible).
    LowerTriangular,
}

/// What every joint fit of one recording shares.
#[derive(Debug, Clone, Copy)]
pub struct Setting<'a> {
    /// The noise the windows are weighted with.
    pub noise: &'a Noise,
    /// Reference temperature T0, C.
    pub t0_c: f64,
    /// The frame.
    pub frame: Frame,
    /// The recording, named in errors.
    pub path: &'a Path,
}

/// Fit all observations jointly, each at its own temperature: for every axis the four
/// temperature models of its K row and offset (and a constant even term where the
/// positions determine it) in one weighted least squares.
pub fn fit_joint(obs: &[Obs], basis: &Basis, setting: &Setting) -> Result<ModelFit> {
    let Setting {
        noise,
        t0_c: t0,
        frame,
        path,
    } = *setting;
    basis.check()?;
    let temps: Vec<f64> = obs.iter().map(|o| o.temp_c).collect();
    check_coverage(basis, &temps).map_err(|e| e.within(path))?;
    let nb = basis.len();
    let phis: Vec<Vec<f64>> = obs.iter().map(|o| basis.eval(t0, o.temp_c)).collect();
    let mut params: [Vec<f64>; 12] = Default::default();
    let mut stderr: [Vec<f64>; 12] = Default::default();
    let mut k2 = [None; 3];
    let (mut chi2, mut n_params) = (0.0, 0);
    let (mut axis_cov, mut axis_chi2) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        let (s, with_k2) =
            fit_axis(obs, &phis, noise, axis, frame).ok_or_else(|| rank_error(obs, path, basis))?;
        let slots = [
            K_INDEX[axis][0],
            K_INDEX[axis][1],
            K_INDEX[axis][2],
            U0_INDEX[axis],
        ];
        for (j, c) in slots.iter().enumerate() {
            params[*c] = (0..nb)
                .map(|k| unscale(basis, k, s.x[j * nb + k]))
                .collect();
            stderr[*c] = (0..nb)
                .map(|k| unscale(basis, k, s.cov[(j * nb + k, j * nb + k)].max(0.0).sqrt()))
                .collect();
        }
        if with_k2 {
            k2[axis] = Some(s.x[4 * nb]);
        }
        let free =
            s.x.iter()
                .zip(s.cov.diagonal().iter())
                .filter(|(_, v)| **v > 0.0)
                .count();
        chi2 += s.wrss;
        n_params += free;
        axis_chi2.push((s.wrss, obs.len().saturating_sub(free)));
        axis_cov.push(s.cov);
    }
    let (lo, hi) = span(&temps);
    Ok(ModelFit {
        basis: basis.clone(),
        t0_c: t0,
        params,
        stderr,
        k2,
        t_range: (lo, hi),
        chi2,
        n_obs: 3 * obs.len(),
        n_params,
        axis_cov,
        axis_chi2,
    })
}

/// One axis of [`fit_joint`]: columns `a_j phi_k(T)` for j = x, y, z, 1 and, when the
/// positions determine it and none was estimated, `a_axis^2`; returns the solution and
/// whether it has that term.
fn fit_axis(
    obs: &[Obs],
    phis: &[Vec<f64>],
    noise: &Noise,
    axis: usize,
    frame: Frame,
) -> Option<(Lsq, bool)> {
    let nb = phis.first().map(Vec::len).unwrap_or(0);
    let var = noise.sigma[axis].powi(2);
    let w: Vec<f64> = obs.iter().map(|o| o.n as f64 / var).collect();
    let b = DVector::from_iterator(obs.len(), obs.iter().map(|o| o.u[axis]));
    let keep = kept_columns(frame, axis);
    let build = |with_k2: bool| {
        let p = keep.len() * nb + usize::from(with_k2);
        let mut a = DMatrix::zeros(obs.len(), p);
        for (r, (o, phi)) in obs.iter().zip(phis).enumerate() {
            for (c, v) in design_row(o, phi, &keep, axis, with_k2)
                .into_iter()
                .enumerate()
            {
                a[(r, c)] = v;
            }
        }
        weighted_lsq(&a, &b, &w).map(|s| expand(s, &keep, nb, with_k2))
    };
    let given = obs.iter().all(|o| !o.estimated);
    match build(given).filter(|_| given) {
        Some(s) => Some((s, true)),
        None => build(false).map(|s| (s, false)),
    }
}

/// The groups of columns (`a_x`, `a_y`, `a_z`, 1) of one axis's design kept in `frame`:
/// lower triangular holds K[axis][j] at 0 for j > axis.
pub fn kept_columns(frame: Frame, axis: usize) -> Vec<usize> {
    let lower = frame == Frame::LowerTriangular;
    (0..4).filter(|j| !lower || *j == 3 || *j <= axis).collect()
}

/// One observation's row of one axis's design (the fit's and the cross-validation's fold
/// design's one source): `a_j phi_k(T)` for the kept groups `keep`, then `a_axis^2` with
/// the even-order term.
pub fn design_row(o: &Obs, phi: &[f64], keep: &[usize], axis: usize, with_k2: bool) -> Vec<f64> {
    let g = [o.a[0], o.a[1], o.a[2], 1.0];
    let mut row: Vec<f64> = keep
        .iter()
        .flat_map(|j| phi.iter().map(move |f| g[*j] * f))
        .collect();
    if with_k2 {
        row.push(o.a[axis] * o.a[axis]);
    }
    row
}

/// A reduced solution laid out in the full order `a_x phi, a_y phi, a_z phi, phi[, k2]`,
/// the columns held at 0 with zero value and covariance.
fn expand(s: Lsq, keep: &[usize], nb: usize, with_k2: bool) -> Lsq {
    if keep.len() == 4 {
        return s;
    }
    let p = 4 * nb + usize::from(with_k2);
    let mut map: Vec<usize> = keep
        .iter()
        .flat_map(|j| (0..nb).map(move |k| j * nb + k))
        .collect();
    if with_k2 {
        map.push(4 * nb);
    }
    let mut x = DVector::zeros(p);
    let mut cov = DMatrix::zeros(p, p);
    for (r, fr) in map.iter().enumerate() {
        x[*fr] = s.x[r];
        for (c, fc) in map.iter().enumerate() {
            cov[(*fr, *fc)] = s.cov[(r, c)];
        }
    }
    Lsq {
        x,
        cov,
        wrss: s.wrss,
        residuals: s.residuals,
    }
}

fn rank_error(obs: &[Obs], path: &Path, basis: &Basis) -> HostError {
    let temps: Vec<f64> = obs.iter().map(|o| o.temp_c).collect();
    let mut parts = Vec::new();
    for c in temperature_clusters(&temps) {
        let mut names: Vec<usize> = obs
            .iter()
            .filter(|o| (o.temp_c - c).abs() <= 2.0)
            .map(|o| o.position)
            .collect();
        names.sort_unstable();
        names.dedup();
        parts.push(format!("{c:.1} C: {} positions", names.len()));
    }
    HostError::in_file(
        ErrorKind::Insufficient,
        path,
        format!(
            "the data do not determine the {} model of the 12 coefficients (need >= 4 positions not in one plane at enough temperatures); have {}",
            basis.describe(),
            parts.join("; ")
        ),
    )
}

/// Fit a temperature model to a coefficient table, coefficient by coefficient. Order n
/// through exactly n+1 temperatures interpolates, which is the paper's Cramer solution
/// (11); with more temperatures it is weighted least squares (weights 1/stderr^2 when
/// known). A pwl through the table's own temperatures reproduces the table.
pub fn fit_table(rows: &[TableRow], basis: &Basis, t0: f64) -> Result<ModelFit> {
    basis.check()?;
    let temps: Vec<f64> = rows.iter().map(|r| r.temp_c).collect();
    if rows.len() < basis.len() {
        return Err(HostError::new(
            ErrorKind::Insufficient,
            format!(
                "the {} model needs coefficients at {} or more temperatures; the table has {}",
                basis.describe(),
                basis.len(),
                rows.len()
            ),
        ));
    }
    check_coverage(basis, &temps)?;
    let nb = basis.len();
    let mut a = DMatrix::zeros(rows.len(), nb);
    for (r, row) in rows.iter().enumerate() {
        for (k, f) in basis.eval(t0, row.temp_c).iter().enumerate() {
            a[(r, k)] = *f;
        }
    }
    let mut params: [Vec<f64>; 12] = Default::default();
    let mut stderr: [Vec<f64>; 12] = Default::default();
    let mut chi2 = 0.0;
    for c in 0..12 {
        let b = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.coeffs[c]));
        let w: Vec<f64> = rows
            .iter()
            .map(|r| match r.stderr {
                Some(se) if se.iter().all(|s| *s > 0.0) => 1.0 / (se[c] * se[c]),
                _ => 1.0,
            })
            .collect();
        let s = weighted_lsq(&a, &b, &w).ok_or_else(|| {
            HostError::new(
                ErrorKind::Insufficient,
                format!(
                    "the table does not determine the {} model",
                    basis.describe()
                ),
            )
        })?;
        params[c] = (0..nb).map(|k| unscale(basis, k, s.x[k])).collect();
        stderr[c] = (0..nb)
            .map(|k| unscale(basis, k, s.cov[(k, k)].max(0.0).sqrt()))
            .collect();
        chi2 += s.wrss;
    }
    let (lo, hi) = span(&temps);
    Ok(ModelFit {
        basis: basis.clone(),
        t0_c: t0,
        params,
        stderr,
        k2: [None; 3],
        t_range: (lo, hi),
        chi2,
        n_obs: 12 * rows.len(),
        n_params: 12 * nb,
        axis_cov: Vec::new(),
        axis_chi2: Vec::new(),
    })
}

/// The smallest and largest of `v` (infinite, reversed, when `v` is empty).
pub fn span(v: &[f64]) -> (f64, f64) {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}
