//! The columns of a diagnosis fit: what is fitted ([`Spec`]: the baseline's temperature
//! basis, cross terms, the effects added), per axis the baseline's temperature models of
//! the K row and offset, and every effect's columns (through firmware-core's own filters, see
//! [`crate::model::regressors`]), three residual rows per window. What the columns
//! mean at a temperature (K and U0, bends included) is read back by [`static_at`].
use crate::model::basis::Basis;
use crate::model::data::Data;
use crate::model::effects::{Extra, Restart};
use crate::model::library;
use crate::model::params::{Param, Term};
use crate::model::regressors;
use nalgebra::DVector;

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

    /// The spec with its extra number `e` replaced by `extra`.
    pub fn replaced(&self, e: usize, extra: Extra) -> Spec {
        let mut s = self.clone();
        s.extras[e] = extra;
        s
    }

    /// Structural unknowns profiled, over all extras.
    pub fn structural(&self) -> usize {
        self.extras.iter().map(Extra::structural).sum()
    }
}

/// One row of the design: `(column, value)` of its nonzero entries.
pub type Row = Vec<(usize, f64)>;

/// A built design: rows (3 per observation), labels, and each observation's temperature
/// per axis.
pub struct Design {
    /// The rows, 3 per observation (axes x, y, z).
    pub rows: Vec<Row>,
    /// What every column is.
    pub labels: Vec<Param>,
    /// Each observation's temperature per axis (the element's, through a lag).
    pub temps: Vec<[f64; 3]>,
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

    /// The prediction of row `r` by parameters `x`.
    pub fn predict(&self, x: &DVector<f64>, r: usize) -> f64 {
        self.rows[r].iter().map(|(c, v)| v * x[*c]).sum::<f64>()
    }
}

impl Data<'_> {
    /// The design of `spec`; `base_k` gives K(T) at every observation for fixture
    /// columns (without it they are left out).
    pub fn design(&self, spec: &Spec, base_k: Option<&[[[f64; 3]; 3]]>) -> Design {
        let mut d = Design {
            rows: vec![Vec::new(); self.n_rows()],
            labels: Vec::new(),
            temps: self.temps(spec),
        };
        self.baseline_columns(spec, &mut d);
        for (e, x) in spec.extras.iter().enumerate() {
            self.extra_columns(e, x, &mut d, base_k);
        }
        d
    }

    /// Each observation's temperature per axis: the sensor's, or the element's through
    /// the spec's thermal lag.
    fn temps(&self, spec: &Spec) -> Vec<[f64; 3]> {
        let lag = spec.extras.iter().find_map(|e| {
            if let Extra::Lag { taus } = e {
                Some(taus)
            } else {
                None
            }
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
    fn baseline_columns(&self, spec: &Spec, d: &mut Design) {
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

    /// A linear drift in time of the offsets (and, with `scale`, of the scale factors),
    /// over the recording's span: the rival of [`crate::diagnose::search`], outside the
    /// catalogue (its columns name no extra of the spec).
    pub fn drift_columns(&self, d: &mut Design, scale: bool) {
        let (t0, t1) = self
            .obs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), o| {
                (a.min(o.t_s), b.max(o.t_s))
            });
        let span = (t1 - t0).max(f64::MIN_POSITIVE);
        let s: Vec<f64> = self
            .obs
            .iter()
            .map(|o| (o.t_s - 0.5 * (t0 + t1)) / span)
            .collect();
        let none = usize::MAX;
        self.per_axis(d, Term::Drift, none, &|r, _| s[r]);
        if scale {
            let obs = &self.obs;
            self.per_axis(d, Term::DriftScale, none, &|r, i| obs[r].a[i] * s[r]);
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

    /// The columns of extra number `e`; `base_k` gives K(T) for fixture columns.
    fn extra_columns(
        &self,
        e: usize,
        extra: &Extra,
        d: &mut Design,
        base_k: Option<&[[[f64; 3]; 3]]>,
    ) {
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
            Extra::Fixture(p, from) => {
                if let Some(k) = base_k {
                    self.fixture_columns(e, *p, *from, k, d);
                }
            }
            Extra::Discovered { term, axis } => {
                let c = library::column(self, &library::Series::new(self), term);
                let col = c.iter().enumerate().map(|(r, v)| (3 * r + axis, *v));
                d.push_column(
                    Param::Effect {
                        term: Term::Discovered,
                        axis: *axis,
                        extra: e,
                    },
                    col.collect::<Vec<_>>(),
                );
            }
        }
    }

    /// A fixture error of position `p` (from stop `from` on, else throughout): its two
    /// rotation angles, linearised around the K(T) `base_k` of every observation.
    fn fixture_columns(
        &self,
        e: usize,
        p: usize,
        from: Option<usize>,
        base_k: &[[[f64; 3]; 3]],
        d: &mut Design,
    ) {
        let since = from.map_or(f64::NEG_INFINITY, |n| self.stop_start_s(n));
        for (n, dirv) in fixture_directions(self.rec.positions.vector(p))
            .iter()
            .enumerate()
        {
            let mut col = Vec::new();
            for (r, _) in self
                .obs
                .iter()
                .enumerate()
                .filter(|(_, o)| o.position == p && o.t_s >= since)
            {
                for (i, row) in base_k[r].iter().enumerate() {
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

/// The offsets' temperature basis: a `Curvature` extra's fine one, else the baseline's.
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

/// K and U0 of a fitted spec (baseline and bends), row i at temperature `temps[i]`.
pub fn static_at(
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
                        Term::Rate
                        | Term::Hysteresis
                        | Term::HysteresisScale
                        | Term::K2
                        | Term::Asymmetry
                        | Term::Warmup
                        | Term::Drift
                        | Term::DriftScale
                        | Term::Discovered => {}
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
