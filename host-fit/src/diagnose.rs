//! Diagnosis: when the model and a recording disagree, locate the mismatch, name the
//! physics left out (physics-catalogue.md), model it, and show the fit improve.
//!
//! All three axes are fitted in one weighted least squares (weights n / sigma^2 from the
//! in-dwell noise): per axis the temperature models of its K row and offset, and the
//! candidate effects as extra columns; effects with a nonlinear parameter (thermal lag
//! and warm-up time constants) are profiled over it. A candidate is accepted when it
//! lowers BIC by more than [`BIC_MARGIN`] and improves the chi-square of dwells it was
//! not fitted on (two folds of alternate dwells); candidates that explain the data
//! equally well are reported as ambiguous, with the measurement that would separate them.
//!
//! `HOSTFIT_DEBUG=1` prints every candidate's BIC change and held-out chi-square to stderr.
use crate::error::{HostError, Result};
use crate::identify::{noise, Noise};
use crate::recording::Recording;
use crate::temperature::{temperature_clusters, Basis};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use serde_json::{json, Map, Value};

/// A candidate must lower BIC by more than this to be accepted ("clearly").
pub const BIC_MARGIN: f64 = 10.0;
/// Two candidates within this much BIC of each other explain the data equally well.
pub const AMBIGUITY_MARGIN: f64 = 6.0;
/// The catalogue's effect ids, in the order candidates are tried.
pub const EFFECT_IDS: [&str; 8] = [
    "temp_curvature",
    "thermal_lag",
    "temp_rate",
    "hysteresis",
    "nonlinearity_k2",
    "scale_asymmetry",
    "fixture_error",
    "warmup_drift",
];
/// A `-` run longer than this (s) is handling (the unit re-mounted, turned by hand).
pub const HANDLING_S: f64 = 120.0;

/// One observation: the mean of a window of a dwell.
#[derive(Debug, Clone)]
pub struct DObs {
    /// Position index and vector.
    pub position: usize,
    /// Specific force, g.
    pub a: [f64; 3],
    /// Samples.
    pub n: usize,
    /// Row range `[start, end)`.
    pub start: usize,
    /// End of the row range.
    pub end: usize,
    /// Dwell index.
    pub dwell: usize,
    /// Held-out fold (0 or 1): alternate windows of short dwells, alternate hours of long ones.
    pub fold: usize,
    /// Mean sensor temperature, C.
    pub temp_c: f64,
    /// Mean time, s.
    pub t_s: f64,
    /// Mean rate of the sensor temperature, C/s.
    pub dtdt: f64,
    /// Direction of the last temperature change (+1 heating, -1 cooling, 0 unknown).
    pub dir: f64,
    /// Mean time since power-on or the last handling, s.
    pub since_event_s: f64,
    /// Mean outputs.
    pub u: [f64; 3],
}

/// Per-row derived series.
struct Series {
    dtdt: Vec<f64>,
    dir: Vec<f64>,
    since: Vec<f64>,
}

fn series(rec: &Recording) -> Series {
    let n = rec.rows.len();
    let t: Vec<f64> = rec.rows.iter().map(|r| r.t_s).collect();
    let temp: Vec<f64> = rec.rows.iter().map(|r| r.temp_c).collect();
    // smoothed temperature derivative: least-squares slope over +-60 s
    let mut dtdt = vec![0.0; n];
    let (mut lo, mut hi) = (0usize, 0usize);
    for k in 0..n {
        while t[k] - t[lo] > 60.0 {
            lo += 1;
        }
        while hi + 1 < n && t[hi + 1] - t[k] <= 60.0 {
            hi += 1;
        }
        let m = (hi - lo + 1) as f64;
        if m >= 3.0 {
            let mt = t[lo..=hi].iter().sum::<f64>() / m;
            let my = temp[lo..=hi].iter().sum::<f64>() / m;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for j in lo..=hi {
                sxy += (t[j] - mt) * (temp[j] - my);
                sxx += (t[j] - mt) * (t[j] - mt);
            }
            dtdt[k] = if sxx > 0.0 { sxy / sxx } else { 0.0 };
        }
    }
    // direction of the last change of more than 0.5 C; before the first change the unit
    // is taken to have come from the other side (its history before the recording is
    // unknown, and a unit cooled first was usually warm before)
    let mut dir = vec![0.0; n];
    let first = temp.first().copied().unwrap_or(0.0);
    let first_change = temp
        .iter()
        .find(|v| (**v - first).abs() > 0.5)
        .map(|v| if *v > first { 1.0 } else { -1.0 })
        .unwrap_or(0.0);
    let (mut d, mut reference) = (-first_change, first);
    for k in 0..n {
        let s = temp[k];
        if s - reference > 0.5 {
            d = 1.0;
            reference = s;
        } else if reference - s > 0.5 {
            d = -1.0;
            reference = s;
        } else if (s - reference) * d > 0.0 {
            reference = s;
        }
        dir[k] = d;
    }
    // time since power-on or handling
    let mut since = vec![0.0; n];
    let mut event = t.first().copied().unwrap_or(0.0);
    let mut k = 0;
    while k < n {
        if rec.rows[k].position.is_none() {
            let s = k;
            while k < n && rec.rows[k].position.is_none() {
                since[k] = t[k] - event;
                k += 1;
            }
            let end_t = if k < n { t[k] } else { t[n - 1] };
            if end_t - t[s] > HANDLING_S {
                event = end_t;
            }
            continue;
        }
        since[k] = t[k] - event;
        k += 1;
    }
    Series { dtdt, dir, since }
}

/// Windows of every dwell of a known position: at most `span_c` of temperature and
/// `max_s` of time each.
pub fn observations(rec: &Recording, span_c: f64, max_s: f64) -> Vec<DObs> {
    let s = series(rec);
    let mut out = Vec::new();
    for (di, d) in rec.dwells.iter().enumerate() {
        let a = rec.positions.vector(d.position);
        let mut windows = crate::identify::windows(rec, d, span_c, max_s);
        // at least two windows per dwell, so each held-out fold sees every dwell
        if windows.len() == 1 && d.len() >= 4 {
            let mid = d.start + d.len() / 2;
            windows = vec![(d.start, mid), (mid, d.end)];
        }
        let short = windows.len() <= 4;
        for (wi, (start, end)) in windows.into_iter().enumerate() {
            let m = (end - start) as f64;
            let mean = |f: &dyn Fn(usize) -> f64| (start..end).map(f).sum::<f64>() / m;
            // held-out folds: alternate windows of short dwells, alternate hours of long ones
            let fold = if short {
                wi % 2
            } else {
                (di + ((rec.rows[start].t_s - rec.rows[d.start].t_s) / 3600.0) as usize) % 2
            };
            out.push(DObs {
                position: d.position,
                a,
                n: end - start,
                start,
                end,
                dwell: di,
                fold,
                temp_c: mean(&|k| rec.rows[k].temp_c),
                t_s: mean(&|k| rec.rows[k].t_s),
                dtdt: mean(&|k| s.dtdt[k]),
                dir: mean(&|k| s.dir[k]),
                since_event_s: mean(&|k| s.since[k]),
                u: [
                    mean(&|k| rec.rows[k].u[0]),
                    mean(&|k| rec.rows[k].u[1]),
                    mean(&|k| rec.rows[k].u[2]),
                ],
            });
        }
    }
    out
}

/// Mean of the first-order low-pass (time constant `tau`) of the sensor temperature
/// over each observation's rows.
fn lagged_temps(rec: &Recording, obs: &[DObs], tau: f64) -> Vec<f64> {
    let mut f = vec![0.0; rec.rows.len()];
    let mut y = rec.rows.first().map(|r| r.temp_c).unwrap_or(0.0);
    let mut prev_t = rec.rows.first().map(|r| r.t_s).unwrap_or(0.0);
    for (k, r) in rec.rows.iter().enumerate() {
        let dt = (r.t_s - prev_t).max(0.0);
        y += (r.temp_c - y) * (1.0 - (-dt / tau).exp());
        prev_t = r.t_s;
        f[k] = y;
    }
    obs.iter()
        .map(|o| f[o.start..o.end].iter().sum::<f64>() / o.n as f64)
        .collect()
}

/// An effect added to the baseline model.
#[derive(Debug, Clone, PartialEq)]
pub enum Extra {
    /// `temp_curvature`: the temperature basis replaced by a fine piecewise-linear one.
    Curvature(Vec<f64>),
    /// `thermal_lag`: the model evaluated at the low-passed temperature.
    Lag(f64),
    /// `temp_rate`: U0_i += r_i dT/dt.
    Rate,
    /// `hysteresis`: U0_i += h_i dir / 2.
    Hysteresis,
    /// `nonlinearity_k2`: U_i += K2_i a_i^2.
    K2,
    /// `scale_asymmetry`: U_i += c_i |a_i| (c_i = K_ii delta_i).
    Asymmetry,
    /// `warmup_drift`: U0_i += d_i exp(-t_since / tau).
    Warmup(f64),
    /// `fixture_error`: position p rotated by two small angles.
    Fixture(usize),
}

impl Extra {
    /// The catalogue id.
    pub fn id(&self) -> &'static str {
        match self {
            Extra::Curvature(_) => "temp_curvature",
            Extra::Lag(_) => "thermal_lag",
            Extra::Rate => "temp_rate",
            Extra::Hysteresis => "hysteresis",
            Extra::K2 => "nonlinearity_k2",
            Extra::Asymmetry => "scale_asymmetry",
            Extra::Warmup(_) => "warmup_drift",
            Extra::Fixture(_) => "fixture_error",
        }
    }
}

/// What is fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// Baseline temperature basis.
    pub basis: Basis,
    /// Whether the cross-sensitivities are fitted (else fixed at 0).
    pub cross: bool,
    /// Effects added.
    pub extras: Vec<Extra>,
}

/// A fitted spec.
#[derive(Debug, Clone)]
pub struct Fit {
    /// What was fitted.
    pub spec: Spec,
    /// Chi-square (weights n / sigma^2).
    pub chi2: f64,
    /// Number of parameters.
    pub k: usize,
    /// Parameters and their covariance.
    pub x: DVector<f64>,
    /// Covariance of the parameters (unscaled).
    pub cov: DMatrix<f64>,
    /// Column labels.
    pub labels: Vec<String>,
    /// Residual per observation and axis (output units).
    pub resid: Vec<[f64; 3]>,
    /// Model K(T) at each observation (for fixture-error columns and dg).
    pub k_at: Vec<[[f64; 3]; 3]>,
    /// Model U0(T) at each observation.
    pub u0_at: Vec<[f64; 3]>,
    /// Chi-square of the held-out halves (each fitted on the other).
    pub heldout: f64,
}

/// The data of a diagnosis.
pub struct Data<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Observations.
    pub obs: Vec<DObs>,
    /// Noise.
    pub noise: Noise,
    /// Reference temperature.
    pub t0: f64,
}

const AX: [&str; 3] = ["x", "y", "z"];

impl Data<'_> {
    fn weights(&self) -> Vec<f64> {
        let mut w = Vec::with_capacity(3 * self.obs.len());
        for o in &self.obs {
            for i in 0..3 {
                w.push(o.n as f64 / (self.noise.sigma[i] * self.noise.sigma[i]));
            }
        }
        w
    }

    /// The temperature each observation's model is evaluated at: the sensor's, or its
    /// low-pass with the thermal-lag time constant of the spec.
    fn model_temps(&self, spec: &Spec) -> Vec<f64> {
        match spec.extras.iter().find_map(|e| {
            if let Extra::Lag(t) = e {
                Some(*t)
            } else {
                None
            }
        }) {
            Some(tau) => lagged_temps(self.rec, &self.obs, tau),
            None => self.obs.iter().map(|o| o.temp_c).collect(),
        }
    }

    /// Build the stacked design (rows: obs x axis) for `spec`; `base` provides K(T) for
    /// fixture columns.
    fn design(&self, spec: &Spec, base: Option<&Fit>) -> (DMatrix<f64>, DVector<f64>, Vec<String>) {
        let n = self.obs.len();
        let temps = self.model_temps(spec);
        let basis = spec.basis.clone();
        let nb = basis.len();
        let phis: Vec<Vec<f64>> = temps.iter().map(|t| basis.eval(self.t0, *t)).collect();
        // temp_curvature bends the offsets: their basis becomes a fine piecewise-linear one
        let obasis = offset_basis(spec);
        let onb = obasis.len();
        let ophis: Vec<Vec<f64>> = temps.iter().map(|t| obasis.eval(self.t0, *t)).collect();
        let mut labels = Vec::new();
        // per axis: g columns x basis
        let gs: Vec<Vec<usize>> = (0..3)
            .map(|i| {
                if spec.cross {
                    vec![0, 1, 2, 3]
                } else {
                    vec![i, 3]
                }
            })
            .collect();
        let mut cols: Vec<Vec<(usize, f64)>> = Vec::new(); // sparse columns: (row, value)
        for i in 0..3 {
            for &j in &gs[i] {
                let (count, ph) = if j == 3 { (onb, &ophis) } else { (nb, &phis) };
                for k in 0..count {
                    let mut c = Vec::with_capacity(n);
                    for (r, o) in self.obs.iter().enumerate() {
                        let g = if j == 3 { 1.0 } else { o.a[j] };
                        if g != 0.0 {
                            c.push((3 * r + i, g * ph[r][k]));
                        }
                    }
                    cols.push(c);
                    let name = if j == 3 {
                        format!("u0{}", AX[i])
                    } else {
                        format!("k{}{}", AX[i], AX[j])
                    };
                    labels.push(format!("{name}#{k}"));
                }
            }
        }
        for e in &spec.extras {
            match e {
                Extra::Curvature(_) | Extra::Lag(_) => {}
                Extra::Fixture(p) => {
                    let Some(b) = base else { continue };
                    let a = self.rec.positions.vector(*p);
                    let helper = if a[0].abs() < 0.9 {
                        [1.0, 0.0, 0.0]
                    } else {
                        [0.0, 1.0, 0.0]
                    };
                    let e1 = normalize(cross(a, helper));
                    let e2 = cross(a, e1);
                    for (name, dirv) in [("angle1_rad", e2), ("angle2_rad", e1.map(|v| -v))] {
                        let mut c = Vec::new();
                        for (r, o) in self.obs.iter().enumerate() {
                            if o.position == *p {
                                let kk = b.k_at[r];
                                for i in 0..3 {
                                    c.push((
                                        3 * r + i,
                                        kk[i][0] * dirv[0]
                                            + kk[i][1] * dirv[1]
                                            + kk[i][2] * dirv[2],
                                    ));
                                }
                            }
                        }
                        cols.push(c);
                        labels.push(name.to_string());
                    }
                }
                _ => {
                    for i in 0..3 {
                        let mut c = Vec::new();
                        for (r, o) in self.obs.iter().enumerate() {
                            let v = match e {
                                Extra::Rate => o.dtdt,
                                Extra::Hysteresis => o.dir / 2.0,
                                Extra::K2 => o.a[i] * o.a[i],
                                Extra::Asymmetry => o.a[i].abs(),
                                Extra::Warmup(tau) => (-o.since_event_s / tau).exp(),
                                _ => 0.0,
                            };
                            if v != 0.0 {
                                c.push((3 * r + i, v));
                            }
                        }
                        cols.push(c);
                        let p = match e {
                            Extra::Rate => "r",
                            Extra::Hysteresis => "h",
                            Extra::K2 => "k2",
                            Extra::Asymmetry => "c",
                            Extra::Warmup(_) => "d",
                            _ => "?",
                        };
                        labels.push(format!("{p}_{}", AX[i]));
                    }
                }
            }
        }
        let mut a = DMatrix::zeros(3 * n, cols.len());
        for (j, c) in cols.iter().enumerate() {
            for (r, v) in c {
                a[(*r, j)] = *v;
            }
        }
        let b = DVector::from_iterator(3 * n, self.obs.iter().flat_map(|o| o.u));
        (a, b, labels)
    }

    /// Fit a spec; `None` when the data do not determine it.
    pub fn fit(&self, spec: &Spec, base: Option<&Fit>) -> Option<Fit> {
        let (a, b, labels) = self.design(spec, base);
        let w = self.weights();
        let dbg = std::env::var_os("HOSTFIT_DEBUG").is_some();
        // the normal equations of the two held-out folds; the full fit's are their sum
        let masks: [Vec<bool>; 2] =
            [0, 1].map(|fold| self.obs.iter().flat_map(|o| [o.fold == fold; 3]).collect());
        let folds = masks.clone().map(|m| normal(&a, &b, &w, &m));
        let (ata, atb) = (&folds[0].0 + &folds[1].0, &folds[0].1 + &folds[1].1);
        let Some((x, cov)) = solve(&ata, &atb) else {
            if dbg {
                eprintln!("  rank deficient: {:?}", spec.extras.last());
            }
            return None;
        };
        let r = &b - &a * &x;
        let chi2: f64 = r.iter().zip(&w).map(|(r, w)| w * r * r).sum();
        // held out: each fold fitted alone, its chi2 on the other fold
        let mut heldout = 0.0;
        for (fold, (mask, (fa, fb))) in masks.iter().zip(&folds).enumerate() {
            let Some((xf, _)) = solve(fa, fb) else {
                if dbg {
                    eprintln!("  fold {fold} rank deficient: {:?}", spec.extras.last());
                }
                return None;
            };
            let rf = &b - &a * &xf;
            heldout += rf
                .iter()
                .zip(&w)
                .zip(mask)
                .filter(|(_, m)| !**m)
                .map(|((r, w), _)| w * r * r)
                .sum::<f64>();
        }
        let resid = (0..self.obs.len())
            .map(|o| [r[3 * o], r[3 * o + 1], r[3 * o + 2]])
            .collect();
        let (k_at, u0_at) = self.coefficients(spec, &x, &labels);
        Some(Fit {
            spec: spec.clone(),
            chi2,
            k: x.len(),
            x,
            cov,
            labels,
            resid,
            k_at,
            u0_at,
            heldout,
        })
    }

    fn coefficients(
        &self,
        spec: &Spec,
        x: &DVector<f64>,
        labels: &[String],
    ) -> (Vec<[[f64; 3]; 3]>, Vec<[f64; 3]>) {
        let temps = self.model_temps(spec);
        self.coefficients_at(spec, x, labels, &temps)
    }

    /// K(T) and U0(T) of a fitted spec at the (effective) temperatures `temps`.
    pub fn coefficients_at(
        &self,
        spec: &Spec,
        x: &DVector<f64>,
        labels: &[String],
        temps: &[f64],
    ) -> (Vec<[[f64; 3]; 3]>, Vec<[f64; 3]>) {
        let basis = spec.basis.clone();
        let obasis = offset_basis(spec);
        let mut ks = Vec::new();
        let mut us = Vec::new();
        for &t in temps {
            let phi = basis.eval(self.t0, t);
            let ophi = obasis.eval(self.t0, t);
            let mut k = [[0.0; 3]; 3];
            let mut u0 = [0.0; 3];
            for (j, l) in labels.iter().enumerate() {
                let Some((name, idx)) = l.split_once('#') else {
                    continue;
                };
                let idx = idx.parse::<usize>().unwrap_or(0);
                let b = name.as_bytes();
                let axis = |c: u8| (c - b'x') as usize;
                if let Some(ax) = name.strip_prefix("u0") {
                    u0[axis(ax.as_bytes()[0])] += x[j] * ophi.get(idx).copied().unwrap_or(0.0);
                } else {
                    k[axis(b[1])][axis(b[2])] += x[j] * phi.get(idx).copied().unwrap_or(0.0);
                }
            }
            ks.push(k);
            us.push(u0);
        }
        (ks, us)
    }
}

/// The offsets' temperature basis: temp_curvature bends them with a fine piecewise-linear
/// one; otherwise the baseline's.
fn offset_basis(spec: &Spec) -> Basis {
    spec.extras
        .iter()
        .find_map(|e| {
            if let Extra::Curvature(b) = e {
                Some(Basis::Pwl {
                    breakpoints: b.clone(),
                })
            } else {
                None
            }
        })
        .unwrap_or_else(|| spec.basis.clone())
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / n)
}

/// Solve the weighted normal equations on column-scaled data (fast enough for the many
/// fits of a diagnosis; the residuals are computed directly, not from the normal
/// equations); `None` when rank deficient.
/// The weighted normal equations `(A^T W A, A^T W b)` of the rows in `fold`.
fn normal(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    w: &[f64],
    fold: &[bool],
) -> (DMatrix<f64>, DVector<f64>) {
    let p = a.ncols();
    let mut ata: DMatrix<f64> = DMatrix::zeros(p, p);
    let mut atb: DVector<f64> = DVector::zeros(p);
    for r in 0..a.nrows() {
        if !fold[r] {
            continue;
        }
        let row = a.row(r);
        let nz: Vec<usize> = (0..p).filter(|&j| row[j] != 0.0).collect();
        for &i in &nz {
            atb[i] += w[r] * row[i] * b[r];
            for &j in &nz {
                ata[(i, j)] += w[r] * row[i] * row[j];
            }
        }
    }
    (ata, atb)
}

fn solve(ata: &DMatrix<f64>, atb: &DVector<f64>) -> Option<(DVector<f64>, DMatrix<f64>)> {
    let p = ata.ncols();
    let d: Vec<f64> = (0..p).map(|j| ata[(j, j)].sqrt()).collect();
    if d.iter().any(|v| *v <= 0.0 || !v.is_finite()) {
        return None;
    }
    let mut s = ata.clone();
    for i in 0..p {
        for j in 0..p {
            s[(i, j)] /= d[i] * d[j];
        }
    }
    let eig = s.clone().symmetric_eigen();
    let (mn, mx) = eig
        .eigenvalues
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
    if mn.is_nan() || mn <= 1e-11 * mx {
        return None;
    }
    let inv = eig.eigenvectors.clone()
        * DMatrix::from_diagonal(&eig.eigenvalues.map(|v| 1.0 / v))
        * eig.eigenvectors.transpose();
    let sb = DVector::from_iterator(p, (0..p).map(|i| atb[i] / d[i]));
    let y = &inv * sb;
    let x = DVector::from_iterator(p, (0..p).map(|i| y[i] / d[i]));
    let mut cov = inv;
    for i in 0..p {
        for j in 0..p {
            cov[(i, j)] /= d[i] * d[j];
        }
    }
    Some((x, cov))
}

fn bic(f: &Fit, n: usize) -> f64 {
    f.chi2 + f.k as f64 * (n as f64).ln()
}

/// One located mismatch: a group of observations whose residual exceeds the noise.
#[derive(Debug, Clone, Serialize)]
pub struct Hotspot {
    /// Grouping (axis, position, temperature, time, dT/dt, direction).
    pub group: String,
    /// The group's value.
    pub value: String,
    /// Axis.
    pub axis: String,
    /// RMS of the normalised residual (1 = noise).
    pub rms_sigma: f64,
    /// Mean residual, output units.
    pub mean: f64,
    /// Observations in the group.
    pub count: usize,
}

fn locate(data: &Data, fit: &Fit) -> Vec<Hotspot> {
    let mut groups: Vec<(String, String, Vec<usize>)> = Vec::new();
    let mut add =
        |g: &str, v: String, idx: usize| match groups.iter_mut().find(|x| x.0 == g && x.1 == v) {
            Some(x) => x.2.push(idx),
            None => groups.push((g.to_string(), v, vec![idx])),
        };
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let clusters = temperature_clusters(&temps);
    let t_end = data.obs.iter().map(|o| o.t_s).fold(0.0, f64::max).max(1.0);
    for (r, o) in data.obs.iter().enumerate() {
        add(
            "position",
            data.rec.positions.name(o.position).to_string(),
            r,
        );
        let c = clusters
            .iter()
            .min_by(|a, b| (*a - o.temp_c).abs().total_cmp(&(*b - o.temp_c).abs()))
            .copied()
            .unwrap_or(0.0);
        add("temperature", format!("{c:.0} C"), r);
        let bin = ((o.t_s / t_end) * 8.0).floor().min(7.0);
        add(
            "time",
            format!(
                "{:.1}-{:.1} h",
                bin * t_end / 8.0 / 3600.0,
                (bin + 1.0) * t_end / 8.0 / 3600.0
            ),
            r,
        );
        add(
            "dT/dt",
            if o.dtdt.abs() > 0.002 {
                if o.dtdt > 0.0 {
                    "heating >0.002 C/s"
                } else {
                    "cooling >0.002 C/s"
                }
            } else {
                "steady"
            }
            .to_string(),
            r,
        );
        add(
            "direction",
            match o.dir {
                d if d > 0.5 => "after heating",
                d if d < -0.5 => "after cooling",
                _ => "unknown",
            }
            .to_string(),
            r,
        );
    }
    let mut out = Vec::new();
    for (g, v, idx) in groups {
        for i in 0..3 {
            let z: Vec<f64> = idx
                .iter()
                .map(|&r| fit.resid[r][i] * (data.obs[r].n as f64).sqrt() / data.noise.sigma[i])
                .collect();
            let rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
            let mean = idx.iter().map(|&r| fit.resid[r][i]).sum::<f64>() / idx.len() as f64;
            if rms > 2.0 {
                out.push(Hotspot {
                    group: g.clone(),
                    value: v.clone(),
                    axis: AX[i].into(),
                    rms_sigma: rms,
                    mean,
                    count: idx.len(),
                });
            }
        }
    }
    out.sort_by(|a, b| b.rms_sigma.total_cmp(&a.rms_sigma));
    out
}

/// A finding of the JSON contract.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// Catalogue id.
    pub effect: String,
    /// Axes where the effect is significant.
    pub axes: Vec<String>,
    /// Parameters.
    pub parameters: Map<String, Value>,
    /// 1-sigma uncertainties.
    pub uncertainties: Map<String, Value>,
    /// BIC change when added.
    pub delta_bic: f64,
    /// Residual RMS after adding it.
    pub residual_rms_after: f64,
    /// max |dg| after adding it, mg.
    pub max_abs_dg_mg_after: f64,
    /// One sentence.
    pub evidence: String,
    /// The position, for fixture_error.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<String>,
}

/// Two or more candidates the data cannot separate.
#[derive(Debug, Clone, Serialize)]
pub struct Ambiguity {
    /// Catalogue ids.
    pub candidates: Vec<String>,
    /// The measurement that separates them.
    pub needed: String,
}

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// In-dwell noise per axis.
    pub noise: Noise,
    /// Baseline.
    pub baseline: Fit,
    /// Final model.
    pub final_fit: Fit,
    /// Accepted findings.
    pub findings: Vec<Finding>,
    /// Ambiguities.
    pub ambiguous: Vec<Ambiguity>,
    /// Where the baseline residual exceeds noise.
    pub hotspots: Vec<Hotspot>,
    /// What cannot be identified from this recording.
    pub not_identifiable: Vec<String>,
    /// The data.
    pub obs: Vec<DObs>,
    /// Expected residual RMS from noise alone (output units, per window).
    pub noise_rms: f64,
    /// The final model's coefficients on a grid over the data's temperatures (for the blob).
    pub table: Vec<(f64, [f64; 12])>,
    /// Median sample period of the recording, s.
    pub sample_period_s: f64,
    /// Direction of the hysteresis state at the start of the recording.
    pub initial_direction: f64,
}

impl Diagnosis {
    /// The extended model as a firmware calibration: the final model's coefficients as a
    /// piecewise-linear table (up to 16 points, which also carries a temp_curvature
    /// finding), and the in-flight physics terms of the findings (fixture_error only
    /// corrects the calibration, which the final fit already does).
    pub fn calibration(&self, t0: f64) -> firmware_core::temperature::Calibration<f64> {
        use firmware_core::temperature::{Calibration, Physics, TempModel};
        let f = &self.final_fit;
        let get = |prefix: &str| -> [f64; 3] {
            std::array::from_fn(|i| {
                f.labels
                    .iter()
                    .position(|l| *l == format!("{prefix}_{}", AX[i]))
                    .map(|j| f.x[j])
                    .unwrap_or(0.0)
            })
        };
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
        for e in &f.spec.extras {
            match e {
                Extra::Lag(tau) => {
                    ph.lag_alpha = 1.0 - (-dt / tau).exp();
                    any = true;
                }
                Extra::Rate => {
                    ph.rate = get("r");
                    any = true;
                }
                Extra::Hysteresis => {
                    ph.hysteresis = get("h");
                    any = true;
                }
                Extra::K2 => {
                    ph.k2 = get("k2");
                    any = true;
                }
                Extra::Asymmetry => {
                    ph.asymmetry = get("c");
                    any = true;
                }
                Extra::Warmup(tau) => {
                    ph.warmup = get("d");
                    ph.warmup_decay = (-dt / tau).exp();
                    any = true;
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

fn residual_rms(f: &Fit) -> f64 {
    let n = f.resid.len() * 3;
    (f.resid.iter().flatten().map(|r| r * r).sum::<f64>() / n.max(1) as f64).sqrt()
}

/// Noise-weighted residual RMS in units of the in-dwell noise (1 = noise only).
pub fn normalized_rms(data: &Data, f: &Fit) -> f64 {
    (f.chi2 / (3 * data.obs.len()) as f64).sqrt()
}

/// max |dg| (mg) over the static windows: the position's |a| from the fitted model.
fn max_dg(data: &Data, f: &Fit) -> f64 {
    let mut worst: f64 = 0.0;
    for (r, o) in data.obs.iter().enumerate() {
        if o.dtdt.abs() > 0.002 {
            continue;
        }
        let k = f.k_at[r];
        let Some(n) = firmware_core::model::invert(&k) else {
            continue;
        };
        // the output without the fitted extras: the prediction minus residual is the
        // model; the model's static part is K a + U0, so a = N (U - extras - U0)
        let extras: Vec<f64> = (0..3)
            .map(|i| {
                o.u[i]
                    - f.resid[r][i]
                    - (k[i][0] * o.a[0] + k[i][1] * o.a[1] + k[i][2] * o.a[2] + f.u0_at[r][i])
            })
            .collect();
        let u: [f64; 3] = std::array::from_fn(|i| o.u[i] - extras[i]);
        let a = firmware_core::model::apply(&n, u, f.u0_at[r]);
        worst = worst.max(firmware_core::model::dg(&a).abs() * 1e3);
    }
    worst
}

fn needed(a: &str, b: &str) -> String {
    let pair = |x: &str, y: &str| (a == x && b == y) || (a == y && b == x);
    if pair("nonlinearity_k2", "scale_asymmetry") {
        "tilted positions (e.g. PP1..PP6) where a_i^2 and |a_i| differ".into()
    } else if pair("thermal_lag", "temp_rate") {
        "a soak after a ramp long enough to watch the error decay (lag) or vanish with dT/dt (rate), or ramps at two rates".into()
    } else if pair("hysteresis", "thermal_lag") || pair("hysteresis", "temp_rate") {
        "a temperature visited from both directions after a long soak".into()
    } else if pair("warmup_drift", "thermal_lag") || pair("warmup_drift", "temp_rate") {
        "a power cycle or handling at a steady temperature, away from any temperature change".into()
    } else {
        format!(
            "data that changes {a} and {b} differently (other positions, temperatures or timing)"
        )
    }
}

/// Run the diagnosis.
pub fn diagnose(rec: &Recording) -> Result<Diagnosis> {
    let nz = noise(rec);
    let obs = observations(rec, 0.25, 300.0);
    if obs.len() < 6 {
        return Err(HostError::in_file(
            &rec.path,
            "too few static observations to diagnose",
        ));
    }
    let data = Data {
        rec,
        obs,
        noise: nz,
        t0: rec.t0_c,
    };
    let n_rows = 3 * data.obs.len();
    let temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    let n_temps = temperature_clusters(&temps).len();
    let mut not_identifiable = Vec::new();
    // baseline: cross-sensitivities if identifiable, the polynomial order by BIC
    let mut baseline: Option<Fit> = None;
    for cross_terms in [true, false] {
        for order in 1..=5usize.min(n_temps.saturating_sub(1)).max(1) {
            let spec = Spec {
                basis: Basis::Poly { order },
                cross: cross_terms,
                extras: Vec::new(),
            };
            if let Some(f) = data.fit(&spec, None) {
                if baseline
                    .as_ref()
                    .is_none_or(|b| bic(&f, n_rows) < bic(b, n_rows))
                {
                    baseline = Some(f);
                }
            }
        }
        if baseline.is_some() {
            if !cross_terms {
                not_identifiable.push(
                    "cross-sensitivities (need >= 4 positions not in one plane): fixed at 0"
                        .to_string(),
                );
            }
            break;
        }
    }
    let baseline = baseline.ok_or_else(|| {
        HostError::in_file(
            &rec.path,
            "the positions present do not determine even the per-axis offset and scale",
        )
    })?;
    let hotspots = locate(&data, &baseline);
    // candidates
    let positions: Vec<usize> = {
        let mut p: Vec<usize> = data.obs.iter().map(|o| o.position).collect();
        p.sort_unstable();
        p.dedup();
        p
    };
    let (tmin, tmax) = temps
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(*t), b.max(*t))
        });
    let fine: Vec<f64> = {
        let nb = 16usize
            .min(((tmax - tmin) / 4.0).floor() as usize + 1)
            .max(2);
        (0..nb)
            .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
            .collect()
    };
    let mut current = baseline.clone();
    let mut findings: Vec<Finding> = Vec::new();
    let mut ambiguous: Vec<Ambiguity> = Vec::new();
    let mut used: Vec<&'static str> = Vec::new();
    loop {
        let mut trials: Vec<(Fit, f64)> = Vec::new();
        let try_spec = |extra: Extra, current: &Fit| -> Option<Fit> {
            let mut s = current.spec.clone();
            s.extras.push(extra);
            data.fit(&s, Some(current))
        };
        let profile = |make: &dyn Fn(f64) -> Extra, current: &Fit| -> Option<Fit> {
            let grid: Vec<f64> = (0..14).map(|k| 20.0 * 1.7f64.powi(k)).collect();
            let mut best: Option<Fit> = None;
            for tau in grid {
                if let Some(f) = try_spec(make(tau), current) {
                    if best.as_ref().is_none_or(|b| f.chi2 < b.chi2) {
                        best = Some(f);
                    }
                }
            }
            // refine in log tau by golden section around the best grid point
            let b = best?;
            let tau0 = b.spec.extras.iter().rev().find_map(|e| match e {
                Extra::Lag(t) | Extra::Warmup(t) => Some(*t),
                _ => None,
            })?;
            let (mut lo, mut hi) = ((tau0 / 1.7).ln(), (tau0 * 1.7).ln());
            let g = 0.618_033_988_75;
            let mut best = b;
            for _ in 0..12 {
                let m1 = hi - g * (hi - lo);
                let m2 = lo + g * (hi - lo);
                let f1 = try_spec(make(m1.exp()), current);
                let f2 = try_spec(make(m2.exp()), current);
                let c1 = f1.as_ref().map(|f| f.chi2).unwrap_or(f64::INFINITY);
                let c2 = f2.as_ref().map(|f| f.chi2).unwrap_or(f64::INFINITY);
                if c1 < c2 {
                    hi = m2;
                    if let Some(f) = f1 {
                        if f.chi2 < best.chi2 {
                            best = f;
                        }
                    }
                } else {
                    lo = m1;
                    if let Some(f) = f2 {
                        if f.chi2 < best.chi2 {
                            best = f;
                        }
                    }
                }
            }
            Some(best)
        };
        let mut cands: Vec<Option<Fit>> = Vec::new();
        if !used.contains(&"temp_curvature") {
            cands.push(try_spec(Extra::Curvature(fine.clone()), &current));
        }
        if !used.contains(&"thermal_lag") {
            cands.push(profile(&Extra::Lag, &current));
        }
        if !used.contains(&"warmup_drift") {
            cands.push(profile(&Extra::Warmup, &current));
        }
        for e in [Extra::Rate, Extra::Hysteresis, Extra::K2, Extra::Asymmetry] {
            if !used.contains(&e.id()) {
                cands.push(try_spec(e, &current));
            }
        }
        if !used.contains(&"fixture_error") {
            for &p in &positions {
                cands.push(try_spec(Extra::Fixture(p), &current));
            }
        }
        for f in cands.into_iter().flatten() {
            let d = bic(&f, n_rows) - bic(&current, n_rows);
            trials.push((f, d));
        }
        // the best per effect id
        let mut per_id: Vec<(Fit, f64)> = Vec::new();
        for (f, d) in trials {
            let id = f.spec.extras.last().map(|e| e.id()).unwrap_or("");
            match per_id
                .iter_mut()
                .find(|(g, _)| g.spec.extras.last().map(|e| e.id()) == Some(id))
            {
                Some(slot) if d < slot.1 => *slot = (f, d),
                Some(_) => {}
                None => per_id.push((f, d)),
            }
        }
        if std::env::var_os("HOSTFIT_DEBUG").is_some() {
            for (f, d) in &per_id {
                eprintln!(
                    "  trial {:?}: dBIC {d:.1}, heldout {:.1} vs {:.1}",
                    f.spec.extras.last(),
                    f.heldout,
                    current.heldout
                );
            }
        }
        per_id.retain(|(f, d)| {
            *d < -BIC_MARGIN && f.heldout < current.heldout - 2.0 * (f.k - current.k) as f64
        });
        per_id.sort_by(|a, b| a.1.total_cmp(&b.1));
        let Some((best, d)) = per_id.first().cloned() else {
            break;
        };
        let id: &'static str = best.spec.extras.last().map(|e| e.id()).unwrap_or("none");
        let rivals: Vec<&'static str> = per_id[1..]
            .iter()
            .filter(|(_, d2)| (d2 - d).abs() < AMBIGUITY_MARGIN)
            .filter_map(|(f, _)| f.spec.extras.last().map(|e| e.id()))
            .collect();
        let evidence = evidence_for(&data, &current, &best, id, d);
        if rivals.is_empty() {
            findings.push(finding(&data, &best, &current, d, evidence));
        } else {
            let mut c = vec![id.to_string()];
            c.extend(rivals.iter().map(|s| s.to_string()));
            let need = needed(id, rivals[0]);
            ambiguous.push(Ambiguity {
                candidates: c,
                needed: need,
            });
            used.extend(rivals.iter().copied());
        }
        used.push(id);
        current = best;
        if used.len() >= EFFECT_IDS.len() {
            break;
        }
    }
    let noise_rms = {
        let mut s = 0.0;
        for o in &data.obs {
            for i in 0..3 {
                s += data.noise.sigma[i] * data.noise.sigma[i] / o.n as f64;
            }
        }
        (s / n_rows as f64).sqrt()
    };
    let obs = data.obs.clone();
    let nb = 16usize
        .min(((tmax - tmin) / 2.0).floor() as usize + 1)
        .max(2);
    let grid: Vec<f64> = (0..nb)
        .map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64)
        .collect();
    let (ks, us) = data.coefficients_at(&current.spec, &current.x, &current.labels, &grid);
    let table = grid
        .iter()
        .zip(ks.iter().zip(&us))
        .map(|(t, (k, u))| {
            (
                *t,
                firmware_core::model::Coeffs { k: *k, u0: *u }.to_array(),
            )
        })
        .collect();
    let mut gaps: Vec<f64> = rec
        .rows
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .filter(|d| *d > 0.0)
        .collect();
    gaps.sort_by(f64::total_cmp);
    let sample_period_s = gaps.get(gaps.len() / 2).copied().unwrap_or(1.0);
    let initial_direction = series(rec).dir.first().copied().unwrap_or(0.0);
    Ok(Diagnosis {
        noise: nz,
        baseline,
        final_fit: current,
        findings,
        ambiguous,
        hotspots,
        not_identifiable,
        obs,
        noise_rms,
        table,
        sample_period_s,
        initial_direction,
    })
}

fn finding(data: &Data, f: &Fit, prev: &Fit, d: f64, evidence: String) -> Finding {
    let e = f.spec.extras.last().cloned().unwrap_or(Extra::Rate);
    let dof = (3 * data.obs.len()).saturating_sub(f.k).max(1) as f64;
    let scale = (f.chi2 / dof).max(1.0).sqrt();
    let mut parameters = Map::new();
    let mut unc = Map::new();
    let mut axes = Vec::new();
    let extra_start = prev.k;
    for j in extra_start..f.k {
        let name = f.labels[j].clone();
        let mut v = f.x[j];
        let mut s = f.cov[(j, j)].max(0.0).sqrt() * scale;
        if let Extra::Asymmetry = e {
            // c_i = K_ii delta_i: report delta_i, relative
            let i = (name.as_bytes()[2] - b'x') as usize;
            let kii = f.k_at.first().map(|k| k[i][i]).unwrap_or(1.0);
            v /= kii;
            s /= kii.abs();
            parameters.insert(format!("delta_{}", AX[i]), json!(v));
            unc.insert(format!("delta_{}", AX[i]), json!(s));
        } else {
            parameters.insert(name.clone(), json!(v));
            unc.insert(name.clone(), json!(s));
        }
        if let Some(ax) = name
            .rsplit('_')
            .next()
            .filter(|a| ["x", "y", "z"].contains(a))
        {
            if v.abs() > 3.0 * s && !axes.contains(&ax.to_string()) {
                axes.push(ax.to_string());
            }
        }
    }
    let mut position = None;
    match &e {
        Extra::Lag(tau) | Extra::Warmup(tau) => {
            let s = tau_sigma(data, f, prev, *tau) * scale;
            parameters.insert("tau_s".into(), json!(tau));
            unc.insert("tau_s".into(), json!(s));
            if matches!(e, Extra::Lag(_)) {
                axes = vec!["x".into(), "y".into(), "z".into()];
            }
        }
        Extra::Curvature(b) => {
            parameters.insert("breakpoints".into(), json!(b.len()));
            unc.insert("breakpoints".into(), json!(0));
            axes = vec!["x".into(), "y".into(), "z".into()];
        }
        Extra::Fixture(p) => {
            position = Some(data.rec.positions.name(*p).to_string());
            axes = vec!["x".into(), "y".into(), "z".into()];
        }
        _ => {}
    }
    Finding {
        effect: e.id().into(),
        axes,
        parameters,
        uncertainties: unc,
        delta_bic: d,
        residual_rms_after: residual_rms(f),
        max_abs_dg_mg_after: max_dg(data, f),
        evidence,
        position,
    }
}

/// 1-sigma of a profiled time constant: where chi2 rises by 1 (parabola in log tau).
fn tau_sigma(data: &Data, f: &Fit, base: &Fit, tau: f64) -> f64 {
    let at = |t: f64| -> f64 {
        let mut s = f.spec.clone();
        if let Some(last) = s.extras.last_mut() {
            *last = match last {
                Extra::Lag(_) => Extra::Lag(t),
                _ => Extra::Warmup(t),
            };
        }
        data.fit(&s, Some(base))
            .map(|g| g.chi2)
            .unwrap_or(f64::INFINITY)
    };
    let h = 0.05;
    let (c0, cp, cm) = (f.chi2, at(tau * (1.0 + h)), at(tau * (1.0 - h)));
    let curv = (cp + cm - 2.0 * c0) / (h * tau).powi(2);
    if curv > 0.0 {
        (2.0 / curv).sqrt()
    } else {
        f64::INFINITY
    }
}

fn evidence_for(data: &Data, before: &Fit, after: &Fit, id: &str, d: f64) -> String {
    let rb = normalized_rms(data, before);
    let ra = normalized_rms(data, after);
    let top = locate(data, before)
        .into_iter()
        .take(2)
        .map(|h| format!("{} axis in {} {}", h.axis, h.group, h.value))
        .collect::<Vec<_>>()
        .join(" and ");
    let why = match id {
        "thermal_lag" => "the residual follows the temperature changes and scales with each coefficient's temperature slope, as a lagging element temperature does",
        "temp_rate" => "the offset residual is proportional to dT/dt, not to any coefficient's temperature slope",
        "hysteresis" => "the same temperature reached by heating and by cooling gives different offsets",
        "nonlinearity_k2" => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as a_i^2 in tilted positions",
        "scale_asymmetry" => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as |a_i| in tilted positions",
        "fixture_error" => "one position disagrees with all others at every temperature",
        "warmup_drift" => "the offset residual decays with time since power-on or handling, independent of temperature",
        "temp_curvature" => "the coefficients bend between the temperatures more than the best polynomial the data support",
        _ => "",
    };
    format!(
        "Baseline residual {rb:.1}x noise, largest on {}; {why}; modelling it lowers BIC by {:.0} and the residual to {ra:.1}x noise.",
        if top.is_empty() { "no group".to_string() } else { top },
        -d
    )
}

impl Diagnosis {
    /// The JSON contract `at-diagnosis/1`.
    pub fn json(&self, rec: &Recording) -> Value {
        let verdict = if self.findings.is_empty() && self.ambiguous.is_empty() {
            "none"
        } else if residual_rms(&self.final_fit) <= 1.5 * self.noise_rms {
            "explained"
        } else {
            "partly_explained"
        };
        let data = Data {
            rec,
            obs: self.obs.clone(),
            noise: self.noise,
            t0: rec.t0_c,
        };
        json!({
            "format": "at-diagnosis/1",
            "noise_rms": self.noise_rms,
            "noise_sigma_per_sample": self.noise.sigma,
            "output_unit": rec.output_unit,
            "baseline": {
                "temperature_model": format!("{}{}", self.baseline.spec.basis.describe(), if self.baseline.spec.cross { "" } else { ", cross-sensitivities fixed at 0" }),
                "residual_rms": residual_rms(&self.baseline),
                "residual_rms_over_noise": normalized_rms(&data, &self.baseline),
                "max_abs_dg_mg": max_dg(&data, &self.baseline),
            },
            "located": self.hotspots.iter().take(12).collect::<Vec<_>>(),
            "findings": self.findings,
            "ambiguous": self.ambiguous,
            "not_identifiable": self.not_identifiable,
            "final": {
                "residual_rms": residual_rms(&self.final_fit),
                "residual_rms_over_noise": normalized_rms(&data, &self.final_fit),
                "max_abs_dg_mg": max_dg(&data, &self.final_fit),
                "heldout_chi2_before": self.baseline.heldout,
                "heldout_chi2_after": self.final_fit.heldout,
            },
            "verdict": verdict,
        })
    }
}

/// The diagnosis as text for a terminal.
pub fn text(j: &Value) -> String {
    let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let mut s = format!(
        "noise (in-dwell, per window): {:.3e}\nbaseline {}: residual {:.3e} ({:.1}x noise), max |dg| {:.3} mg\n",
        f(&j["noise_rms"]),
        j["baseline"]["temperature_model"].as_str().unwrap_or(""),
        f(&j["baseline"]["residual_rms"]),
        f(&j["baseline"]["residual_rms_over_noise"]),
        f(&j["baseline"]["max_abs_dg_mg"])
    );
    if let Some(h) = j["located"].as_array() {
        if !h.is_empty() {
            s.push_str("where the baseline residual exceeds noise (RMS in noise units):\n");
        }
        for x in h.iter().take(8) {
            s.push_str(&format!(
                "  {:<12} {:<22} axis {}  {:.1}x  (mean {:.3e}, {} windows)\n",
                x["group"].as_str().unwrap_or(""),
                x["value"].as_str().unwrap_or(""),
                x["axis"].as_str().unwrap_or(""),
                f(&x["rms_sigma"]),
                f(&x["mean"]),
                x["count"]
            ));
        }
    }
    for n in j["not_identifiable"].as_array().into_iter().flatten() {
        s.push_str(&format!("not identifiable: {}\n", n.as_str().unwrap_or("")));
    }
    for x in j["findings"].as_array().into_iter().flatten() {
        s.push_str(&format!(
            "finding: {} on axes {} (dBIC {:.0})\n",
            x["effect"].as_str().unwrap_or(""),
            x["axes"],
            f(&x["delta_bic"])
        ));
        if let (Some(p), Some(u)) = (x["parameters"].as_object(), x["uncertainties"].as_object()) {
            for (k, v) in p {
                s.push_str(&format!("    {k} = {:.4e} +- {:.1e}\n", f(v), f(&u[k])));
            }
        }
        s.push_str(&format!("    {}\n", x["evidence"].as_str().unwrap_or("")));
    }
    for x in j["ambiguous"].as_array().into_iter().flatten() {
        s.push_str(&format!(
            "ambiguous: {} cannot be told apart; needed: {}\n",
            x["candidates"],
            x["needed"].as_str().unwrap_or("")
        ));
    }
    s.push_str(&format!(
        "final: residual {:.3e} ({:.1}x noise), max |dg| {:.3} mg; held-out chi2 {:.0} -> {:.0}\nverdict: {}",
        f(&j["final"]["residual_rms"]),
        f(&j["final"]["residual_rms_over_noise"]),
        f(&j["final"]["max_abs_dg_mg"]),
        f(&j["final"]["heldout_chi2_before"]),
        f(&j["final"]["heldout_chi2_after"]),
        j["verdict"].as_str().unwrap_or("")
    ));
    s
}
