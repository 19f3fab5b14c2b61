//! The columns of a diagnosis fit: what is fitted ([`Spec`]: the baseline's temperature
//! basis, cross terms, the effects added), per axis the baseline's temperature models of
//! the K row and offset, and every effect's columns (through firmware-core's own filters, see
//! [`crate::model::regressors`]), three residual rows per window. What the columns
//! mean at a temperature (K and U0, bends included) is read back by [`static_at`].
use crate::model::basis::Basis;
use crate::model::data::Data;
use crate::model::effects::{Extra, Restart};
use crate::model::library;
use crate::model::orders::Orders;
use crate::model::params::{Param, Term};
use crate::model::regressors;
use nalgebra::DVector;

/// What is fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// Baseline temperature basis.
    pub basis: Basis,
    /// The offsets' polynomial order when it is above the basis's (a polynomial basis
    /// only): chamber ramps logged at rest show the offsets' direction at more
    /// temperatures than the stops show the K rows' (see [`crate::model::orders::Orders`]).
    pub offset_order: Option<usize>,
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

    /// The spec with its polynomial orders set: `k` for the K rows (and the offsets),
    /// `offsets` for the offsets when it is above `k`.
    pub fn with_orders(&self, k: usize, offsets: usize) -> Spec {
        Spec {
            basis: Basis::Poly { order: k },
            offset_order: (offsets > k).then_some(offsets),
            ..self.clone()
        }
    }

    /// The temperature model's text: the basis's (`poly4`), and the offsets' order when
    /// it is above it (`poly4, offsets poly5`).
    pub fn temperature_model(&self) -> String {
        match self.offsets_poly() {
            Some(o) => format!("{}, offsets poly{o}", self.basis.describe()),
            None => self.basis.describe(),
        }
    }

    /// The offsets' own polynomial order when it is the one fitted: a `Curvature`
    /// extra's fine basis replaces it (see [`offset_basis`]).
    fn offsets_poly(&self) -> Option<usize> {
        let fine = self.extras.iter().any(|e| matches!(e, Extra::Curvature(_)));
        self.offset_order.filter(|_| !fine)
    }

    /// The K rows' and the offsets' polynomial orders as fitted; `None` for a
    /// piecewise-linear basis (the offsets' order is the K rows' under a `Curvature`
    /// extra, whose fine basis replaces the polynomial's offsets).
    pub fn poly_orders(&self) -> Option<Orders> {
        match self.basis {
            Basis::Poly { order } => Some(Orders {
                k: order,
                offsets: self.offsets_poly().unwrap_or(order),
            }),
            Basis::Pwl { .. } => None,
        }
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
        // every row holds its axis's baseline columns, and most effects add one or
        // two: room for them up front spares the rows' regrowth (a hot spot)
        let inputs = if spec.cross { 3 } else { 1 };
        let room = inputs * spec.basis.len() + offset_basis(spec).len() + 2 * spec.extras.len();
        let mut d = Design {
            // (not `vec![..; n]`: a clone of an empty Vec drops its capacity)
            rows: (0..self.n_rows())
                .map(|_| Vec::with_capacity(room))
                .collect(),
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
        // every window's basis values in one flat table per basis (row r at r * len):
        // a hot spot, where a vector per window cost more than the values
        let (nb, nob) = (spec.basis.len(), obasis.len());
        let mut phis = Vec::with_capacity(nb * d.temps.len());
        let mut ophis = Vec::with_capacity(nob * d.temps.len());
        let mut scratch = Vec::with_capacity(nb.max(nob));
        for i in 0..3 {
            phis.clear();
            ophis.clear();
            for t in &d.temps {
                spec.basis.eval_into(self.t0, t[i], &mut scratch);
                phis.extend_from_slice(&scratch);
                obasis.eval_into(self.t0, t[i], &mut scratch);
                ophis.extend_from_slice(&scratch);
            }
            let inputs: Vec<usize> = if spec.cross { vec![0, 1, 2] } else { vec![i] };
            for j in inputs {
                for k in 0..nb {
                    let col = self
                        .obs
                        .iter()
                        .enumerate()
                        .map(|(r, o)| (3 * r + i, o.a[j] * phis[r * nb + k]));
                    d.push_column(Param::K { i, j, k }, col);
                }
            }
            for k in 0..nob {
                let col = (0..self.obs.len()).map(|r| (3 * r + i, ophis[r * nob + k]));
                d.push_column(Param::U0 { i, k }, col);
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
            Extra::Rate { tau_s, centred } => {
                let m = self.means(&if *centred {
                    regressors::centred_rates(self.rec, *tau_s)
                } else {
                    regressors::rates(self.rec, *tau_s)
                });
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

/// The offsets' temperature basis: a `Curvature` extra's fine one, else the offsets'
/// own order, else the baseline's.
pub fn offset_basis(spec: &Spec) -> Basis {
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
        .or_else(|| spec.offset_order.map(|order| Basis::Poly { order }))
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
    StaticAt::new(spec, labels, x, t0).at(temps)
}

/// [`static_at`] at many temperatures: the offsets' basis found once and the basis
/// values written into buffers kept between calls (a fit reads K and U0 back at every
/// window: a hot spot when each call allocated its own).
pub struct StaticAt<'a> {
    spec: &'a Spec,
    labels: &'a [Param],
    x: &'a DVector<f64>,
    t0: f64,
    obasis: Basis,
    phi: [Vec<f64>; 3],
    ophi: [Vec<f64>; 3],
}

impl<'a> StaticAt<'a> {
    /// The fitted spec's parameters `x` (columns `labels`) about `t0`.
    pub fn new(spec: &'a Spec, labels: &'a [Param], x: &'a DVector<f64>, t0: f64) -> Self {
        StaticAt {
            spec,
            labels,
            x,
            t0,
            obasis: offset_basis(spec),
            phi: Default::default(),
            ophi: Default::default(),
        }
    }

    /// K and U0, row i at temperature `temps[i]`.
    pub fn at(&mut self, temps: [f64; 3]) -> ([[f64; 3]; 3], [f64; 3]) {
        let (spec, t0) = (self.spec, self.t0);
        for i in 0..3 {
            spec.basis.eval_into(t0, temps[i], &mut self.phi[i]);
            self.obasis.eval_into(t0, temps[i], &mut self.ophi[i]);
        }
        let (phi, ophi) = (&self.phi, &self.ophi);
        let mut k = [[0.0; 3]; 3];
        let mut u0 = [0.0; 3];
        for (c, l) in self.labels.iter().enumerate() {
            let v = self.x[c];
            match *l {
                Param::K { i, j, k: b } => k[i][j] += v * phi[i][b],
                Param::U0 { i, k: b } => u0[i] += v * ophi[i][b],
                Param::Effect { term, axis, extra } => {
                    bend(spec, extra, term, temps[axis], v, axis, &mut k, &mut u0);
                }
                Param::FixtureAngle { .. } => {}
            }
        }
        (k, u0)
    }
}

/// A bend's column (an offset or scale above a knot, `v` its value) added to row `axis`
/// of K and U0 at the element's temperature `t`; nothing for the other effects, which
/// K(T) and U0(T) do not hold.
#[allow(clippy::too_many_arguments)]
fn bend(
    spec: &Spec,
    extra: usize,
    term: Term,
    t: f64,
    v: f64,
    axis: usize,
    k: &mut [[f64; 3]; 3],
    u0: &mut [f64; 3],
) {
    if let Some(Extra::Bend { knot_c }) = spec.extras.get(extra) {
        let h = (t - knot_c).max(0.0);
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
