//! Identification of the 12 coefficients: observation windows, stops, and the per-stop
//! least squares that reduces to the paper's formula (10).
use crate::data::recording::Recording;
use crate::data::stops::{windows, Stop};
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::noise::Noise;
use crate::model::lsq::weighted_lsq;
use firmware_core::model::{K_INDEX, U0_INDEX};
use nalgebra::{DMatrix, DVector};

/// One observation for a static fit: the mean of a window of a dwell.
#[derive(Debug, Clone, PartialEq)]
pub struct Obs {
    /// Position index.
    pub position: usize,
    /// Specific force (unit vector, g).
    pub a: [f64; 3],
    /// Mean sensor temperature of the window, C.
    pub temp_c: f64,
    /// Mean outputs.
    pub u: [f64; 3],
    /// Samples in the window.
    pub n: usize,
    /// Index of the dwell it came from.
    pub dwell: usize,
    /// Mean time, s.
    pub t_s: f64,
    /// Whether the orientation `a` was estimated from the data (then no even-order
    /// term is fitted: it is not separable from the directions).
    pub estimated: bool,
}

/// Split every selected dwell into windows whose temperature spans at most `span_c`, so
/// a dwell through a ramp is used at its own temperatures, never as one mean.
pub fn observations(rec: &Recording, select: &dyn Fn(usize) -> bool, span_c: f64) -> Vec<Obs> {
    let mut out = Vec::new();
    for (di, d) in rec.dwells.iter().enumerate() {
        if !select(d.position) {
            continue;
        }
        let a = rec.positions.vector(d.position);
        for (start, end) in windows(rec, d, span_c, f64::INFINITY) {
            let w = rec.rows.get(start..end).unwrap_or(&[]);
            let n = w.len() as f64;
            let mut u = [0.0; 3];
            let (mut t, mut ts) = (0.0, 0.0);
            for r in w {
                for (s, v) in u.iter_mut().zip(r.u) {
                    *s += v / n;
                }
                t += r.temp_c / n;
                ts += r.t_s / n;
            }
            out.push(Obs {
                position: d.position,
                a,
                temp_c: t,
                u,
                n: w.len(),
                dwell: di,
                t_s: ts,
                estimated: rec.positions.is_estimated(d.position),
            });
        }
    }
    out
}

/// The coefficients identified at one stop.
#[derive(Debug, Clone, PartialEq)]
pub struct StopCoeffs {
    /// Stop temperature, C.
    pub temp_c: f64,
    /// The 12 coefficients (canonical order).
    pub coeffs: [f64; 12],
    /// Their standard errors from the in-dwell noise.
    pub stderr: [f64; 12],
    /// Per axis: the even-order (K2) term when the positions determine it.
    pub k2: [Option<f64>; 3],
    /// Names of the positions used.
    pub positions: Vec<String>,
}

/// One axis's identified row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisFit {
    /// The axis's row of K (its output per g along x, y and z).
    pub k: [f64; 3],
    /// Its offset U0.
    pub u0: f64,
    /// The even-order (K2) term, when the positions determine it.
    pub k2: Option<f64>,
    /// Standard errors of the row of K and of U0, in that order.
    pub stderr: [f64; 4],
}

/// One axis's static least squares over observations `(a, u_i, weight)`: columns
/// `a_x, a_y, a_z, 1` and, when the positions determine it, `a_i^2`. With TP1..TP6 and
/// equal dwell lengths the solution is exactly the paper's formula (10): the even term
/// makes the offset the mean of the four readings where the axis is level, and the
/// scale and cross terms half-differences of opposite positions.
pub fn axis_lsq(axis: usize, rows: &[([f64; 3], f64, f64)]) -> Option<AxisFit> {
    let build = |with_k2: bool| {
        let p = if with_k2 { 5 } else { 4 };
        let mut a = DMatrix::zeros(rows.len(), p);
        let mut b = DVector::zeros(rows.len());
        let mut w = Vec::with_capacity(rows.len());
        for (r, (v, u, wt)) in rows.iter().enumerate() {
            a[(r, 0)] = v[0];
            a[(r, 1)] = v[1];
            a[(r, 2)] = v[2];
            a[(r, 3)] = 1.0;
            if with_k2 {
                a[(r, 4)] = v[axis] * v[axis];
            }
            b[r] = *u;
            w.push(*wt);
        }
        weighted_lsq(&a, &b, &w)
    };
    let (s, with_k2) = if rows.len() > 5 {
        match build(true) {
            Some(s) => (s, true),
            None => (build(false)?, false),
        }
    } else {
        (build(false)?, false)
    };
    let se = |j: usize| s.cov[(j, j)].max(0.0).sqrt();
    Some(AxisFit {
        k: [s.x[0], s.x[1], s.x[2]],
        u0: s.x[3],
        k2: with_k2.then(|| s.x[4]),
        stderr: [se(0), se(1), se(2), se(3)],
    })
}

/// Identify the 12 coefficients at one stop from its dwell means.
pub fn identify_stop(rec: &Recording, stop: &Stop, noise: &Noise) -> Result<StopCoeffs> {
    let dwells: Vec<_> = stop
        .dwells
        .iter()
        .filter_map(|&i| rec.dwells.get(i))
        .collect();
    let mut names: Vec<String> = dwells
        .iter()
        .map(|d| rec.positions.name(d.position).to_string())
        .collect();
    names.dedup();
    let mut coeffs = [0.0; 12];
    let mut stderr = [0.0; 12];
    let mut k2 = [None; 3];
    for axis in 0..3 {
        let var = noise.sigma[axis] * noise.sigma[axis];
        let rows: Vec<_> = dwells
            .iter()
            .map(|d| {
                (
                    rec.positions.vector(d.position),
                    d.u_mean[axis],
                    d.len() as f64 / var,
                )
            })
            .collect();
        let fit = axis_lsq(axis, &rows).ok_or_else(|| {
            HostError::in_file(
                ErrorKind::Insufficient,
                &rec.path,
                format!(
                    "at the stop at {:.2} C the positions present ({}) do not determine the coefficients: need at least 4 positions not in one plane (e.g. TP1..TP6)",
                    stop.temp_c,
                    names.join(", ")
                ),
            )
        })?;
        for j in 0..3 {
            coeffs[K_INDEX[axis][j]] = fit.k[j];
            stderr[K_INDEX[axis][j]] = fit.stderr[j];
        }
        coeffs[U0_INDEX[axis]] = fit.u0;
        stderr[U0_INDEX[axis]] = fit.stderr[3];
        k2[axis] = fit.k2;
    }
    Ok(StopCoeffs {
        temp_c: stop.temp_c,
        coeffs,
        stderr,
        k2,
        positions: names,
    })
}

/// The paper's formula (10) from the six TP readings `u[m]` (m = TP1..TP6), for tests
/// and for comparison with the paper.
pub fn formula_10(u: &[[f64; 3]; 6]) -> [f64; 12] {
    let [u1, u2, u3, u4, u5, u6] = *u;
    let h = 0.5;
    let mut c = [0.0; 12];
    for i in 0..3 {
        c[K_INDEX[i][0]] = h * (u6[i] - u5[i]);
        c[K_INDEX[i][1]] = h * (u4[i] - u2[i]);
        c[K_INDEX[i][2]] = h * (u1[i] - u3[i]);
    }
    c[9] = 0.25 * (u1[0] + u2[0] + u3[0] + u4[0]);
    c[10] = 0.25 * (u1[1] + u3[1] + u5[1] + u6[1]);
    c[11] = 0.25 * (u2[2] + u4[2] + u5[2] + u6[2]);
    c
}
