//! What the diagnosis fits: a baseline (per axis the temperature models of the K row and
//! offset) plus candidate effects as extra columns, all three axes in one weighted least
//! squares (weights from the error floor), with the chi-square of held-out time chunks.
use crate::data::recording::Recording;
use crate::diagnose::effects::{Extra, Restart};
use crate::diagnose::observations::{window_means, DObs};
use crate::diagnose::params::{Param, Term};
use crate::diagnose::regressors::{self, Events};
use crate::fit::lsq::Normal;
use crate::fit::temperature::Basis;
use nalgebra::{DMatrix, DVector};

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

impl Spec {
    /// The spec without its extra number `e`.
    pub fn without(&self, e: usize) -> Spec {
        let mut s = self.clone();
        s.extras.remove(e);
        s
    }

    /// The spec with `extra` added.
    pub fn with(&self, extra: Extra) -> Spec {
        let mut s = self.clone();
        s.extras.push(extra);
        s
    }

    /// Structural unknowns profiled, over all extras.
    pub fn structural(&self) -> usize {
        self.extras.iter().map(Extra::structural).sum()
    }
}

/// A fitted spec.
#[derive(Debug, Clone)]
pub struct Fit {
    /// What was fitted.
    pub spec: Spec,
    /// Chi-square (weights from the floor).
    pub chi2: f64,
    /// Number of linear parameters.
    pub k: usize,
    /// Parameters.
    pub x: DVector<f64>,
    /// Covariance of the parameters at unit dispersion (None when only profiling).
    pub cov: Option<DMatrix<f64>>,
    /// Heteroscedasticity- and autocorrelation-consistent standard error of every
    /// parameter (Newey-West, Bartlett kernel over neighbouring windows in time; None
    /// when only profiling): it holds residuals correlated in time, which the covariance
    /// does not.
    pub hac: Option<Vec<f64>>,
    /// What each parameter is.
    pub labels: Vec<Param>,
    /// Residual per observation and axis (output units).
    pub resid: Vec<[f64; 3]>,
    /// Model K(T) at each observation (row i at axis i's temperature), bends included.
    pub k_at: Vec<[[f64; 3]; 3]>,
    /// Model U0(T) at each observation, bends included.
    pub u0_at: Vec<[f64; 3]>,
    /// Held-out chi-square: every time chunk predicted by the fit without it.
    pub heldout: f64,
    /// Held-out chi-square per observation row (3 per observation).
    pub heldout_rows: Vec<f64>,
    /// In-sample chi-square per row.
    pub insample_rows: Vec<f64>,
}

impl Fit {
    /// All parameters, linear and structural.
    pub fn params(&self) -> usize {
        self.k + self.spec.structural()
    }
}

/// The data of a diagnosis.
pub struct Data<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Observations.
    pub obs: Vec<DObs>,
    /// Rows left out as spikes (sorted).
    pub spikes: Vec<usize>,
    /// Weight of every residual row (observation x axis): 1 / floor variance.
    pub w: Vec<f64>,
    /// Reference temperature.
    pub t0: f64,
    /// Gaps and handling.
    pub events: Events,
    /// Each observation's temperature rate (the firmware's estimate, 60 s), C/s: where
    /// the temperature moves (for locating and for the static dg).
    pub rate: Vec<f64>,
    /// Each observation's direction of the last change of more than 0.5 C (0 before
    /// the first), for locating.
    pub dir: Vec<f64>,
}

/// One row of the design: `(column, value)` of its nonzero entries.
type Row = Vec<(usize, f64)>;

/// A built design: rows (3 per observation), labels, and each observation's temperature
/// per axis.
struct Design {
    rows: Vec<Row>,
    labels: Vec<Param>,
    temps: Vec<[f64; 3]>,
}

impl Design {
    fn push_column(&mut self, label: Param, entries: impl IntoIterator<Item = (usize, f64)>) {
        let col = self.labels.len();
        self.labels.push(label);
        for (r, v) in entries {
            if v != 0.0 {
                self.rows[r].push((col, v));
            }
        }
    }
}

impl<'a> Data<'a> {
    /// A copy of the data (to fit it with other weights).
    pub fn clone_parts(&self) -> Data<'a> {
        Data {
            rec: self.rec,
            obs: self.obs.clone(),
            spikes: self.spikes.clone(),
            w: self.w.clone(),
            t0: self.t0,
            events: self.events.clone(),
            rate: self.rate.clone(),
            dir: self.dir.clone(),
        }
    }

    /// Residual rows.
    pub fn n_rows(&self) -> usize {
        3 * self.obs.len()
    }

    /// Window means of a per-row series.
    fn means(&self, series: &[f64]) -> Vec<f64> {
        window_means(&self.obs, series, &self.spikes)
    }

    /// Each observation's temperature per axis: the sensor's, or the element's through
    /// the spec's thermal lag.
    fn temps(&self, spec: &Spec) -> Vec<[f64; 3]> {
        let lag = spec.extras.iter().find_map(|e| match e {
            Extra::Lag { taus } => Some(taus),
            _ => None,
        });
        match lag {
            Some(taus) => {
                let per_axis = regressors::lagged(self.rec, taus).map(|s| self.means(&s));
                (0..self.obs.len())
                    .map(|r| std::array::from_fn(|i| per_axis[i][r]))
                    .collect()
            }
            None => self.obs.iter().map(|o| [o.temp_c; 3]).collect(),
        }
    }

    /// The baseline's columns: per axis, K row (or scale only) and offset times the
    /// temperature basis (the offsets' basis is the fine one of a `Curvature` extra).
    fn baseline(&self, spec: &Spec, d: &mut Design) {
        let obasis = offset_basis(spec);
        for i in 0..3 {
            let phis: Vec<Vec<f64>> = d
                .temps
                .iter()
                .map(|t| spec.basis.eval(self.t0, t[i]))
                .collect();
            let ophis: Vec<Vec<f64>> = d.temps.iter().map(|t| obasis.eval(self.t0, t[i])).collect();
            let inputs: Vec<usize> = if spec.cross { vec![0, 1, 2] } else { vec![i] };
            for j in inputs {
                for k in 0..spec.basis.len() {
                    let col = self
                        .obs
                        .iter()
                        .enumerate()
                        .map(|(r, o)| (3 * r + i, o.a[j] * phis[r][k]));
                    d.push_column(Param::K { i, j, k }, col.collect::<Vec<_>>());
                }
            }
            for k in 0..obasis.len() {
                let col = (0..self.obs.len()).map(|r| (3 * r + i, ophis[r][k]));
                d.push_column(Param::U0 { i, k }, col.collect::<Vec<_>>());
            }
        }
    }

    /// A per-axis effect column for every axis: `value(observation, axis)`.
    fn per_axis(
        &self,
        d: &mut Design,
        term: Term,
        extra: usize,
        value: &dyn Fn(usize, usize) -> f64,
    ) {
        for axis in 0..3 {
            let col: Vec<(usize, f64)> = (0..self.obs.len())
                .map(|r| (3 * r + axis, value(r, axis)))
                .collect();
            d.push_column(Param::Effect { term, axis, extra }, col);
        }
    }

    /// The restart rows of a warm-up clock.
    fn restarts(&self, restart: Restart) -> Vec<usize> {
        let mut v = match restart {
            Restart::Start => Vec::new(),
            Restart::Gaps => self.events.gaps.clone(),
            Restart::Handling => [self.events.gaps.clone(), self.events.handling.clone()].concat(),
        };
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The columns of extra number `e`; `base` gives K(T) for fixture columns.
    fn extra(&self, e: usize, extra: &Extra, d: &mut Design, base: Option<&Fit>) {
        let obs = &self.obs;
        match extra {
            Extra::Curvature(_) | Extra::Lag { .. } => {}
            Extra::Bend { knot_c } => {
                let h: Vec<[f64; 3]> = d
                    .temps
                    .iter()
                    .map(|t| t.map(|v| (v - knot_c).max(0.0)))
                    .collect();
                self.per_axis(d, Term::BendOffset, e, &|r, i| h[r][i]);
                self.per_axis(d, Term::BendScale, e, &|r, i| obs[r].a[i] * h[r][i]);
            }
            Extra::Rate { tau_s } => {
                let m = self.means(&regressors::rates(self.rec, *tau_s));
                self.per_axis(d, Term::Rate, e, &|r, _| m[r]);
            }
            Extra::Hysteresis {
                threshold_c,
                initial,
                scale,
            } => {
                let m = self.means(&regressors::directions(self.rec, *threshold_c, *initial));
                self.per_axis(d, Term::Hysteresis, e, &|r, _| m[r] / 2.0);
                if *scale {
                    self.per_axis(d, Term::HysteresisScale, e, &|r, i| {
                        obs[r].a[i] * m[r] / 2.0
                    });
                }
            }
            Extra::K2 => self.per_axis(d, Term::K2, e, &|r, i| obs[r].a[i] * obs[r].a[i]),
            Extra::Asymmetry => self.per_axis(d, Term::Asymmetry, e, &|r, i| obs[r].a[i].abs()),
            Extra::Warmup { tau_s, restart } => {
                let m = self.means(&regressors::warmup(
                    self.rec,
                    *tau_s,
                    &self.restarts(*restart),
                ));
                self.per_axis(d, Term::Warmup, e, &|r, _| m[r]);
            }
            Extra::Fixture(p) => {
                let Some(b) = base else { return };
                for (n, dirv) in fixture_directions(self.rec.positions.vector(*p))
                    .iter()
                    .enumerate()
                {
                    let mut col = Vec::new();
                    for (r, o) in obs.iter().enumerate().filter(|(_, o)| o.position == *p) {
                        let _ = o;
                        for (i, row) in b.k_at[r].iter().enumerate() {
                            col.push((
                                3 * r + i,
                                row[0] * dirv[0] + row[1] * dirv[1] + row[2] * dirv[2],
                            ));
                        }
                    }
                    d.push_column(
                        Param::FixtureAngle {
                            n: n as u8 + 1,
                            extra: e,
                        },
                        col,
                    );
                }
            }
        }
    }

    fn design(&self, spec: &Spec, base: Option<&Fit>) -> Design {
        let mut d = Design {
            rows: vec![Vec::new(); self.n_rows()],
            labels: Vec::new(),
            temps: self.temps(spec),
        };
        self.baseline(spec, &mut d);
        for (e, x) in spec.extras.iter().enumerate() {
            self.extra(e, x, &mut d, base);
        }
        d
    }

    /// Fit a spec; `None` when the data do not determine it. With `full`, also the
    /// covariance and the held-out chi-square (profiling needs neither). A spec with
    /// fixture errors linearises them around `base`'s K(T) (or the spec's own without them).
    pub fn fit(&self, spec: &Spec, base: Option<&Fit>, full: bool) -> Option<Fit> {
        let own_base;
        let base = match base {
            Some(b) => Some(b),
            None if spec.extras.iter().any(|e| matches!(e, Extra::Fixture(_))) => {
                let mut s = spec.clone();
                s.extras.retain(|e| !matches!(e, Extra::Fixture(_)));
                own_base = self.fit(&s, None, false)?;
                Some(&own_base)
            }
            None => None,
        };
        let d = self.design(spec, base);
        let p = d.labels.len();
        let b: Vec<f64> = self.obs.iter().flat_map(|o| o.u).collect();
        let n_chunks = self.obs.iter().map(|o| o.chunk + 1).max().unwrap_or(1);
        let mut chunks: Vec<Normal> = (0..n_chunks).map(|_| Normal::new(p)).collect();
        for (r, row) in d.rows.iter().enumerate() {
            chunks[self.obs[r / 3].chunk].add_sparse(row, b[r], self.w[r]);
        }
        let total = chunks.iter().fold(Normal::new(p), |a, f| a.plus(f));
        let predict =
            |x: &DVector<f64>, r: usize| d.rows[r].iter().map(|(c, v)| v * x[*c]).sum::<f64>();
        let (x, cov) = if full {
            let s = total.solve()?;
            (s.x, Some(s.cov))
        } else {
            (total.solve_x()?, None)
        };
        let resid_rows: Vec<f64> = (0..b.len()).map(|r| b[r] - predict(&x, r)).collect();
        let chi2 = resid_rows.iter().zip(&self.w).map(|(r, w)| w * r * r).sum();
        // each chunk predicted by the fit without it (a chunk the others cannot predict
        // keeps its in-sample residual)
        let mut heldout_rows = vec![0.0; b.len()];
        let mut hac = None;
        if full {
            let sols: Vec<DVector<f64>> = chunks
                .iter()
                .map(|c| total.minus(c).solve_x().unwrap_or_else(|| x.clone()))
                .collect();
            for (r, h) in heldout_rows.iter_mut().enumerate() {
                let e = b[r] - predict(&sols[self.obs[r / 3].chunk], r);
                *h = self.w[r] * e * e;
            }
            if let Some(c) = &cov {
                hac = Some(hac_sigma(&d.rows, c, &resid_rows, &self.w, self.obs.len()));
            }
        }
        let (k_at, u0_at): (Vec<_>, Vec<_>) = d
            .temps
            .iter()
            .map(|t| static_at(spec, &d.labels, &x, self.t0, *t))
            .unzip();
        Some(Fit {
            spec: spec.clone(),
            chi2,
            k: p,
            cov,
            hac,
            labels: d.labels,
            resid: resid_rows.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            k_at,
            u0_at,
            heldout: heldout_rows.iter().sum(),
            heldout_rows,
            insample_rows: resid_rows
                .iter()
                .zip(&self.w)
                .map(|(r, w)| w * r * r)
                .collect(),
            x,
        })
    }

    /// K(T) and U0(T) of a fitted spec at the temperatures `temps` (bends included).
    pub fn coefficients_at(&self, f: &Fit, temps: &[f64]) -> Vec<([[f64; 3]; 3], [f64; 3])> {
        temps
            .iter()
            .map(|&t| static_at(&f.spec, &f.labels, &f.x, self.t0, [t; 3]))
            .collect()
    }
}

/// A chunk is an extrapolation, not a test, when its held-out chi-square is more than
/// this many times its in-sample one (plus one per row): the rest of the data does not
/// determine the model there (the only calibration dwells at an end temperature, say).
pub const EXTRAPOLATION: f64 = 10.0;

impl Data<'_> {
    /// Per chunk: whether both fits predict it from the other chunks (not an
    /// extrapolation for either).
    pub fn predictable(&self, a: &Fit, b: &Fit) -> Vec<bool> {
        let n = self.obs.iter().map(|o| o.chunk + 1).max().unwrap_or(0);
        let mut sums = vec![[0.0f64; 5]; n];
        for (r, o) in self.obs.iter().enumerate() {
            for row in 3 * r..3 * r + 3 {
                let s = &mut sums[o.chunk];
                s[0] += a.heldout_rows.get(row).copied().unwrap_or(0.0);
                s[1] += a.insample_rows.get(row).copied().unwrap_or(0.0);
                s[2] += b.heldout_rows.get(row).copied().unwrap_or(0.0);
                s[3] += b.insample_rows.get(row).copied().unwrap_or(0.0);
                s[4] += 1.0;
            }
        }
        sums.iter()
            .map(|s| s[0] <= EXTRAPOLATION * (s[1] + s[4]) && s[2] <= EXTRAPOLATION * (s[3] + s[4]))
            .collect()
    }

    /// The held-out chi-squares of `a` and `b` over the chunks both predict.
    pub fn heldout_pair(&self, a: &Fit, b: &Fit) -> (f64, f64) {
        let ok = self.predictable(a, b);
        let mut out = (0.0, 0.0);
        for (r, o) in self.obs.iter().enumerate() {
            if ok[o.chunk] {
                for row in 3 * r..3 * r + 3 {
                    out.0 += a.heldout_rows.get(row).copied().unwrap_or(0.0);
                    out.1 += b.heldout_rows.get(row).copied().unwrap_or(0.0);
                }
            }
        }
        out
    }
}

/// Newey-West standard errors: each observation's influence on every parameter
/// (`C x_r w_r e_r`, summed over its three axes), then the influences' sum of squares and
/// of cross products with up to `L` neighbours in time, Bartlett-weighted.
fn hac_sigma(rows: &[Row], cov: &DMatrix<f64>, resid: &[f64], w: &[f64], n_obs: usize) -> Vec<f64> {
    let p = cov.ncols();
    let lags = (4.0 * (n_obs as f64 / 100.0).powf(2.0 / 9.0))
        .floor()
        .max(5.0) as usize;
    let mut infl = vec![vec![0.0; p]; n_obs];
    for (r, row) in rows.iter().enumerate() {
        let we = w[r] * resid[r];
        if we == 0.0 {
            continue;
        }
        let target = &mut infl[r / 3];
        for (j, t) in target.iter_mut().enumerate() {
            *t += row.iter().map(|(c, v)| cov[(j, *c)] * v).sum::<f64>() * we;
        }
    }
    (0..p)
        .map(|j| {
            let mut v: f64 = infl.iter().map(|a| a[j] * a[j]).sum();
            for l in 1..=lags {
                let k = 1.0 - l as f64 / (lags + 1) as f64;
                v += 2.0 * k * (l..n_obs).map(|t| infl[t][j] * infl[t - l][j]).sum::<f64>();
            }
            v.max(0.0).sqrt()
        })
        .collect()
}

/// The offsets' temperature basis: a `Curvature` extra's fine one, else the baseline's.
fn offset_basis(spec: &Spec) -> Basis {
    spec.extras
        .iter()
        .find_map(|e| match e {
            Extra::Curvature(b) => Some(Basis::Pwl {
                breakpoints: b.clone(),
            }),
            _ => None,
        })
        .unwrap_or_else(|| spec.basis.clone())
}

/// K and U0 of a fitted spec (baseline and bends), row i at temperature `temps[i]`.
fn static_at(
    spec: &Spec,
    labels: &[Param],
    x: &DVector<f64>,
    t0: f64,
    temps: [f64; 3],
) -> ([[f64; 3]; 3], [f64; 3]) {
    let obasis = offset_basis(spec);
    let phi = temps.map(|t| spec.basis.eval(t0, t));
    let ophi = temps.map(|t| obasis.eval(t0, t));
    let mut k = [[0.0; 3]; 3];
    let mut u0 = [0.0; 3];
    for (c, l) in labels.iter().enumerate() {
        let v = x[c];
        match *l {
            Param::K { i, j, k: b } => k[i][j] += v * phi[i][b],
            Param::U0 { i, k: b } => u0[i] += v * ophi[i][b],
            Param::Effect { term, axis, extra } => {
                if let Some(Extra::Bend { knot_c }) = spec.extras.get(extra) {
                    let h = (temps[axis] - knot_c).max(0.0);
                    match term {
                        Term::BendOffset => u0[axis] += v * h,
                        Term::BendScale => k[axis][axis] += v * h,
                        _ => {}
                    }
                }
            }
            Param::FixtureAngle { .. } => {}
        }
    }
    (k, u0)
}

/// Two directions perpendicular to `a` (the fixture error's rotation axes, applied to a).
pub fn fixture_directions(a: [f64; 3]) -> [[f64; 3]; 2] {
    let helper = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = normalize(cross(a, helper));
    let e2 = cross(a, e1);
    [e2, e1.map(|v| -v)]
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
