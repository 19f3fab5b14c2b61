//! A diagnosis fit: a [`Spec`]'s columns solved as one weighted least squares over all
//! three axes (weights from the floor), with every held-out time chunk predicted by the
//! fit without it, and Newey-West (HAC) standard errors that hold residuals correlated
//! in time.
use crate::model::data::Data;
use crate::model::design::{offset_basis, Design, Row, Spec, StaticAt};
use crate::model::effects::Extra;
use crate::model::lsq::Normal;
use crate::model::normal_cache::{Blocks, Key};
use crate::model::params::{Param, Term};
use nalgebra::{DMatrix, DVector};

/// How much of a fit to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Parameters and chi-square only: enough to profile a structure.
    Profile,
    /// Also the covariance, the HAC errors and the held-out chunks: enough to judge.
    Full,
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

    /// The values of a per-axis term of extra `e`, x y z (0 on an axis where it is not
    /// fitted).
    pub fn term(&self, e: usize, term: Term) -> [f64; 3] {
        std::array::from_fn(|axis| {
            self.labels
                .iter()
                .position(|l| {
                    *l == Param::Effect {
                        term,
                        axis,
                        extra: e,
                    }
                })
                .map(|j| self.x[j])
                .unwrap_or(0.0)
        })
    }
}

impl Data<'_> {
    /// Fit a spec; `None` when the data do not determine it. A spec with fixture errors
    /// linearises them around `base`'s K(T) (or the spec's own without them).
    pub fn fit(&self, spec: &Spec, base: Option<&Fit>, depth: Depth) -> Option<Fit> {
        self.fit_with(spec, base, depth, None)
    }

    /// `spec` with a linear drift in time of the offsets (and, with `scale`, of the scale
    /// factors) beside it, for the chi-square only: the rival an effect that acts
    /// through time must beat ([`crate::diagnose::search`]).
    pub fn fit_drift(&self, spec: &Spec, base: Option<&Fit>, scale: bool) -> Option<Fit> {
        self.fit_with(spec, base, Depth::Profile, Some(scale))
    }

    /// `spec` at the parameters `x` of a fit of the same columns (`x` in its labels'
    /// order), not refitted: its residuals, chi-square and coefficients on these data
    /// (no covariance, no held-out chunks). `base_k` as for the design (fixture columns).
    /// `None` when `spec`'s columns are not `x`'s.
    pub fn evaluate(
        &self,
        spec: &Spec,
        base_k: Option<&[[[f64; 3]; 3]]>,
        x: &DVector<f64>,
    ) -> Option<Fit> {
        let d = self.design(spec, base_k);
        let p = d.labels.len();
        if p != x.len() {
            return None;
        }
        let b: Vec<f64> = self.obs.iter().flat_map(|o| o.u).collect();
        let resid_rows: Vec<f64> = (0..b.len()).map(|r| b[r] - d.predict(x, r)).collect();
        let insample_rows: Vec<f64> = resid_rows
            .iter()
            .zip(&self.w)
            .map(|(r, w)| w * r * r)
            .collect();
        let mut at = StaticAt::new(spec, &d.labels, x, self.t0);
        let (k_at, u0_at): (Vec<_>, Vec<_>) = d.temps.iter().map(|t| at.at(*t)).unzip();
        Some(Fit {
            spec: spec.clone(),
            chi2: insample_rows.iter().sum(),
            k: p,
            cov: None,
            hac: None,
            labels: d.labels,
            resid: resid_rows.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            k_at,
            u0_at,
            heldout: 0.0,
            heldout_rows: vec![0.0; b.len()],
            insample_rows,
            x: x.clone(),
        })
    }

    /// `spec` refitted with the parameters `held` (label indices into `x`, a fit of the
    /// same columns) kept at their values in `x`: every other linear parameter solved
    /// with those columns' part taken off the data, then evaluated as
    /// [`Data::evaluate`]. `None` when the columns differ or the rest is not determined.
    pub fn fit_holding(
        &self,
        spec: &Spec,
        base_k: Option<&[[[f64; 3]; 3]]>,
        x: &DVector<f64>,
        held: &[usize],
    ) -> Option<Fit> {
        let d = self.design(spec, base_k);
        let p = d.labels.len();
        if p != x.len() {
            return None;
        }
        // the free columns, renumbered
        let mut free = vec![None; p];
        let mut n = 0;
        for (j, slot) in free.iter_mut().enumerate() {
            if !held.contains(&j) {
                *slot = Some(n);
                n += 1;
            }
        }
        let mut normal = Normal::new(n);
        let mut row_free: Vec<(usize, f64)> = Vec::new();
        for (r, row) in d.rows.iter().enumerate() {
            let o = &self.obs[r / 3];
            let mut b = o.u[r % 3];
            row_free.clear();
            for &(j, v) in row {
                match free[j] {
                    Some(k) => row_free.push((k, v)),
                    None => b -= v * x[j],
                }
            }
            normal.add_sparse(&row_free, b, self.w[r]);
        }
        let solved = normal.solve_x()?;
        let mut all = x.clone();
        for (j, slot) in free.iter().enumerate() {
            if let Some(k) = slot {
                all[j] = solved[*k];
            }
        }
        self.evaluate(spec, base_k, &all)
    }

    fn fit_with(
        &self,
        spec: &Spec,
        base: Option<&Fit>,
        depth: Depth,
        drift: Option<bool>,
    ) -> Option<Fit> {
        let own_base;
        let base = match base {
            Some(b) => Some(b),
            None if spec.extras.iter().any(|e| matches!(e, Extra::Fixture(..))) => {
                let mut s = spec.clone();
                s.extras.retain(|e| !matches!(e, Extra::Fixture(..)));
                own_base = self.fit(&s, None, Depth::Profile)?;
                Some(&own_base)
            }
            None => None,
        };
        let mut d = self.design(spec, base.map(|b| b.k_at.as_slice()));
        if let Some(scale) = drift {
            self.drift_columns(&mut d, scale);
        }
        let p = d.labels.len();
        let b: Vec<f64> = self.obs.iter().flat_map(|o| o.u).collect();
        let chunks = self.chunk_normals(spec, &d, &b);
        let total = chunks.iter().fold(Normal::new(p), |a, f| a.plus(f));
        let (x, cov) = match depth {
            Depth::Full => {
                let s = total.solve()?;
                (s.x, Some(s.cov))
            }
            Depth::Profile => (total.solve_x()?, None),
        };
        let resid_rows: Vec<f64> = (0..b.len()).map(|r| b[r] - d.predict(&x, r)).collect();
        let chi2 = resid_rows.iter().zip(&self.w).map(|(r, w)| w * r * r).sum();
        let mut heldout_rows = vec![0.0; b.len()];
        let mut hac = None;
        if let Some(c) = &cov {
            heldout_rows = self.heldout_rows(&d.rows, &b, &chunks, &total, &x);
            hac = Some(hac_sigma(&d.rows, c, &resid_rows, &self.w, self.obs.len()));
        }
        let mut at = StaticAt::new(spec, &d.labels, &x, self.t0);
        let (k_at, u0_at): (Vec<_>, Vec<_>) = d.temps.iter().map(|t| at.at(*t)).unzip();
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

    /// The normal equations of every chunk of held-out time. The baseline's block (its
    /// leading columns) is taken from [`crate::model::normal_cache`] when the baseline
    /// reads the windows' own temperatures (no thermal lag moves them) and the rows
    /// list their columns in ascending order, as the design builds them; either way the
    /// equations are bit for bit those of every row added whole.
    fn chunk_normals(&self, spec: &Spec, d: &Design, b: &[f64]) -> Vec<Normal> {
        let p = d.labels.len();
        let chunk = |r: usize| self.obs[r / 3].chunk;
        let baseline = |l: &Param| matches!(l, Param::K { .. } | Param::U0 { .. });
        let lead = d.labels.iter().take_while(|l| baseline(l)).count();
        let lagged = spec.extras.iter().any(|e| matches!(e, Extra::Lag { .. }));
        let cacheable = !lagged
            && lead > 0
            && !d.labels[lead..].iter().any(baseline)
            && d.rows.iter().all(|r| r.windows(2).all(|e| e[0].0 < e[1].0));
        if !cacheable {
            let mut chunks: Vec<Normal> = (0..self.n_chunks()).map(|_| Normal::new(p)).collect();
            for (r, row) in d.rows.iter().enumerate() {
                chunks[chunk(r)].add_sparse(row, b[r], self.w[r]);
            }
            return chunks;
        }
        let offsets = offset_basis(spec);
        let key = Key::of(
            spec.cross,
            &spec.basis,
            &offsets,
            self.t0,
            &self.obs,
            &self.w,
        );
        let blocks = self.normal_cache.get_or(key, || {
            Blocks::accumulate(&d.rows, lead, self.n_chunks(), chunk, b, &self.w)
        });
        let mut chunks: Vec<Normal> = blocks.chunks.iter().map(|c| c.embedded(p)).collect();
        for (r, row) in d.rows.iter().enumerate() {
            chunks[chunk(r)].add_sparse_beyond(row, b[r], self.w[r], lead);
        }
        chunks
    }

    /// Every row's chi-square when its chunk is predicted by the fit without it (a chunk
    /// the others cannot predict keeps the full fit's prediction).
    fn heldout_rows(
        &self,
        rows: &[Row],
        b: &[f64],
        chunks: &[Normal],
        total: &Normal,
        x: &DVector<f64>,
    ) -> Vec<f64> {
        let sols: Vec<DVector<f64>> = chunks
            .iter()
            .map(|c| total.minus(c).solve_x().unwrap_or_else(|| x.clone()))
            .collect();
        (0..b.len())
            .map(|r| {
                let sol = &sols[self.obs[r / 3].chunk];
                let e = b[r] - rows[r].iter().map(|(c, v)| v * sol[*c]).sum::<f64>();
                self.w[r] * e * e
            })
            .collect()
    }

    /// K(T) and U0(T) of a fitted spec at the temperatures `temps` (bends included).
    pub fn coefficients_at(&self, f: &Fit, temps: &[f64]) -> Vec<([[f64; 3]; 3], [f64; 3])> {
        let mut at = StaticAt::new(&f.spec, &f.labels, &f.x, self.t0);
        temps.iter().map(|&t| at.at([t; 3])).collect()
    }

    /// Per chunk: whether both fits predict it from the other chunks (not an
    /// extrapolation for either, see [`crate::model::rules::Rules::extrapolation`]).
    pub fn predictable(&self, a: &Fit, b: &Fit) -> Vec<bool> {
        let mut sums = vec![[0.0f64; 5]; self.n_chunks()];
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
        let x = self.rules.extrapolation;
        sums.iter()
            .map(|s| s[0] <= x * (s[1] + s[4]) && s[2] <= x * (s[3] + s[4]))
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
