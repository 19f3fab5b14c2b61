//! What the diagnosis fits: a baseline (per axis the temperature models of the K row and
//! offset) plus candidate effects as extra columns, all three axes in one weighted least
//! squares, with the chi-square of held-out folds.
use crate::data::recording::Recording;
use crate::diagnose::observations::{lagged_temps, DObs};
use crate::diagnose::params::{Param, Term};
use crate::fit::lsq::Normal;
use crate::fit::noise::Noise;
use crate::fit::temperature::Basis;
use nalgebra::{DMatrix, DVector};

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

/// An effect added to the baseline model.
#[derive(Debug, Clone, PartialEq)]
pub enum Extra {
    /// `temp_curvature`: the offsets' temperature basis replaced by a fine piecewise-linear one.
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

    /// The per-axis term this effect adds, if it adds one column per axis.
    pub fn term(&self) -> Option<Term> {
        match self {
            Extra::Rate => Some(Term::Rate),
            Extra::Hysteresis => Some(Term::Hysteresis),
            Extra::K2 => Some(Term::K2),
            Extra::Asymmetry => Some(Term::Asymmetry),
            Extra::Warmup(_) => Some(Term::Warmup),
            _ => None,
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
    /// Parameters.
    pub x: DVector<f64>,
    /// Covariance of the parameters (unscaled).
    pub cov: DMatrix<f64>,
    /// What each parameter is.
    pub labels: Vec<Param>,
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

/// Sparse columns: (row, value) pairs, rows being observation x axis.
type Columns = Vec<Vec<(usize, f64)>>;
/// A design matrix, the observations and what each column is.
type Design = (DMatrix<f64>, DVector<f64>, Vec<Param>);

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
        match spec.extras.iter().find_map(|e| match e {
            Extra::Lag(t) => Some(*t),
            _ => None,
        }) {
            Some(tau) => lagged_temps(self.rec, &self.obs, tau),
            None => self.obs.iter().map(|o| o.temp_c).collect(),
        }
    }

    /// The baseline's columns: per axis, K row (or scale only) and offset times the
    /// temperature basis.
    fn baseline_columns(&self, spec: &Spec, temps: &[f64]) -> (Columns, Vec<Param>) {
        let nb = spec.basis.len();
        let phis: Vec<Vec<f64>> = temps.iter().map(|t| spec.basis.eval(self.t0, *t)).collect();
        // temp_curvature bends the offsets: their basis becomes a fine piecewise-linear one
        let obasis = offset_basis(spec);
        let ophis: Vec<Vec<f64>> = temps.iter().map(|t| obasis.eval(self.t0, *t)).collect();
        let (mut cols, mut labels) = (Vec::new(), Vec::new());
        for i in 0..3 {
            let inputs: Vec<usize> = if spec.cross {
                vec![0, 1, 2, 3]
            } else {
                vec![i, 3]
            };
            for j in inputs {
                let (count, ph) = if j == 3 {
                    (obasis.len(), &ophis)
                } else {
                    (nb, &phis)
                };
                for k in 0..count {
                    let mut c = Vec::with_capacity(self.obs.len());
                    for (r, o) in self.obs.iter().enumerate() {
                        let g = if j == 3 { 1.0 } else { o.a[j] };
                        if g != 0.0 {
                            c.push((3 * r + i, g * ph[r][k]));
                        }
                    }
                    cols.push(c);
                    labels.push(if j == 3 {
                        Param::U0 { i, k }
                    } else {
                        Param::K { i, j, k }
                    });
                }
            }
        }
        (cols, labels)
    }

    /// The two fixture-error columns of position `p`: K(T) times the two directions
    /// perpendicular to its vector.
    fn fixture_columns(&self, p: usize, base: &Fit) -> Columns {
        let a = self.rec.positions.vector(p);
        let helper = if a[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let e1 = normalize(cross(a, helper));
        let e2 = cross(a, e1);
        [e2, e1.map(|v| -v)]
            .iter()
            .map(|dirv| {
                let mut c = Vec::new();
                for (r, o) in self.obs.iter().enumerate() {
                    if o.position == p {
                        let kk = base.k_at[r];
                        for (i, row) in kk.iter().enumerate() {
                            c.push((
                                3 * r + i,
                                row[0] * dirv[0] + row[1] * dirv[1] + row[2] * dirv[2],
                            ));
                        }
                    }
                }
                c
            })
            .collect()
    }

    /// The value of a per-axis effect term at observation `o`, axis `i`.
    fn term_value(e: &Extra, o: &DObs, i: usize) -> f64 {
        match e {
            Extra::Rate => o.dtdt,
            Extra::Hysteresis => o.dir / 2.0,
            Extra::K2 => o.a[i] * o.a[i],
            Extra::Asymmetry => o.a[i].abs(),
            Extra::Warmup(tau) => (-o.since_event_s / tau).exp(),
            _ => 0.0,
        }
    }

    /// Build the stacked design (rows: obs x axis) for `spec`; `base` provides K(T) for
    /// fixture columns.
    fn design(&self, spec: &Spec, temps: &[f64], base: Option<&Fit>) -> Design {
        let (mut cols, mut labels) = self.baseline_columns(spec, temps);
        for e in &spec.extras {
            match e {
                Extra::Curvature(_) | Extra::Lag(_) => {}
                Extra::Fixture(p) => {
                    let Some(b) = base else { continue };
                    cols.extend(self.fixture_columns(*p, b));
                    labels.extend([Param::FixtureAngle(1), Param::FixtureAngle(2)]);
                }
                _ => {
                    let Some(term) = e.term() else { continue };
                    for axis in 0..3 {
                        let c = self
                            .obs
                            .iter()
                            .enumerate()
                            .map(|(r, o)| (3 * r + axis, Self::term_value(e, o, axis)))
                            .filter(|(_, v)| *v != 0.0)
                            .collect();
                        cols.push(c);
                        labels.push(Param::Effect { term, axis });
                    }
                }
            }
        }
        let mut a = DMatrix::zeros(3 * self.obs.len(), cols.len());
        for (j, c) in cols.iter().enumerate() {
            for (r, v) in c {
                a[(*r, j)] = *v;
            }
        }
        let b = DVector::from_iterator(3 * self.obs.len(), self.obs.iter().flat_map(|o| o.u));
        (a, b, labels)
    }

    /// Fit a spec; `None` when the data do not determine it.
    pub fn fit(&self, spec: &Spec, base: Option<&Fit>) -> Option<Fit> {
        let temps = self.model_temps(spec);
        let (a, b, labels) = self.design(spec, &temps, base);
        let w = self.weights();
        let dbg = std::env::var_os("HOSTFIT_DEBUG").is_some();
        // the normal equations of the two held-out folds; the full fit's are their sum
        let in_fold = |fold: usize| move |r: usize| self.obs[r / 3].fold == fold;
        let folds = [0, 1].map(|fold| Normal::of_rows(&a, &b, &w, in_fold(fold)));
        let Some(s) = folds[0].plus(&folds[1]).solve() else {
            if dbg {
                eprintln!("  rank deficient: {:?}", spec.extras.last());
            }
            return None;
        };
        let r = &b - &a * &s.x;
        let chi2: f64 = r.iter().zip(&w).map(|(r, w)| w * r * r).sum();
        // held out: each fold fitted alone, its chi2 on the other fold
        let mut heldout = 0.0;
        for (fold, eq) in folds.iter().enumerate() {
            let Some(sf) = eq.solve() else {
                if dbg {
                    eprintln!("  fold {fold} rank deficient: {:?}", spec.extras.last());
                }
                return None;
            };
            let rf = &b - &a * &sf.x;
            heldout += (0..rf.len())
                .filter(|&k| !in_fold(fold)(k))
                .map(|k| w[k] * rf[k] * rf[k])
                .sum::<f64>();
        }
        let resid = (0..self.obs.len())
            .map(|o| [r[3 * o], r[3 * o + 1], r[3 * o + 2]])
            .collect();
        let (k_at, u0_at) = self.coefficients_at(spec, &s.x, &labels, &temps);
        Some(Fit {
            spec: spec.clone(),
            chi2,
            k: s.x.len(),
            x: s.x,
            cov: s.cov,
            labels,
            resid,
            k_at,
            u0_at,
            heldout,
        })
    }

    /// K(T) and U0(T) of a fitted spec at the (effective) temperatures `temps`.
    pub fn coefficients_at(
        &self,
        spec: &Spec,
        x: &DVector<f64>,
        labels: &[Param],
        temps: &[f64],
    ) -> (Vec<[[f64; 3]; 3]>, Vec<[f64; 3]>) {
        let obasis = offset_basis(spec);
        let mut ks = Vec::with_capacity(temps.len());
        let mut us = Vec::with_capacity(temps.len());
        for &t in temps {
            let phi = spec.basis.eval(self.t0, t);
            let ophi = obasis.eval(self.t0, t);
            let mut k = [[0.0; 3]; 3];
            let mut u0 = [0.0; 3];
            for (j, l) in labels.iter().enumerate() {
                match *l {
                    Param::K { i, j: c, k: b } => {
                        k[i][c] += x[j] * phi.get(b).copied().unwrap_or(0.0)
                    }
                    Param::U0 { i, k: b } => u0[i] += x[j] * ophi.get(b).copied().unwrap_or(0.0),
                    _ => {}
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
        .find_map(|e| match e {
            Extra::Curvature(b) => Some(Basis::Pwl {
                breakpoints: b.clone(),
            }),
            _ => None,
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
