//! The structural unknowns of each effect's form, profiled: every candidate form is fitted
//! and the best kept (time constants on a log grid refined by golden-section search,
//! thresholds and initial states on grids, a bend's place over the data's temperatures).
use crate::diagnose::design::{Data, Fit, Spec};
use crate::diagnose::effects::{Extra, Restart};

/// The best (lowest chi-square) of several fits.
fn best(fits: impl IntoIterator<Item = Option<Fit>>) -> Option<Fit> {
    fits.into_iter()
        .flatten()
        .min_by(|a, b| a.chi2.total_cmp(&b.chi2))
}

/// `spec` with `extra`, fitted for profiling (no covariance, no held-out chunks).
fn try_fit(data: &Data, spec: &Spec, extra: Extra, base: &Fit) -> Option<Fit> {
    data.fit(&spec.with(extra), Some(base), false)
}

/// A time constant profiled: a log grid from 20 s (x1.7), then golden-section search in
/// log tau around the best grid point.
pub fn time_constant(make: &dyn Fn(f64) -> Option<Fit>, lo_s: f64, steps: i32) -> Option<(f64, Fit)> {
    let grid = (0..steps).map(|k| lo_s * 1.7f64.powi(k));
    let (mut tau, mut fit) = grid
        .filter_map(|t| make(t).map(|f| (t, f)))
        .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))?;
    let (mut lo, mut hi) = ((tau / 1.7).ln(), (tau * 1.7).ln());
    let g = 0.618_033_988_75;
    for _ in 0..10 {
        let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        let (f1, f2) = (make(m1.exp()), make(m2.exp()));
        let c = |f: &Option<Fit>| f.as_ref().map(|f| f.chi2).unwrap_or(f64::INFINITY);
        let (m, f) = if c(&f1) < c(&f2) {
            hi = m2;
            (m1, f1)
        } else {
            lo = m1;
            (m2, f2)
        };
        if let Some(f) = f.filter(|f| f.chi2 < fit.chi2) {
            fit = f;
            tau = m.exp();
        }
    }
    Some((tau, fit))
}

/// thermal_lag: one pole for all axes, then two poles, then a time constant per axis;
/// every form returned (the search compares them with their parameter counts).
pub fn lag(data: &Data, spec: &Spec, base: &Fit) -> Vec<Fit> {
    let common = |t1: f64, t2: f64| Extra::Lag { taus: [[t1, t2]; 3] };
    let Some((tau, one)) = time_constant(&|t| try_fit(data, spec, common(t, 0.0), base), 20.0, 14) else {
        return Vec::new();
    };
    let mut out = vec![one.clone()];
    // two poles: the second a fraction of the first (the pair keeps the total lag)
    let two = best((1..=6).map(|k| {
        let f = 0.08 * 1.6f64.powi(k);
        try_fit(data, spec, common(tau * (1.0 - f), tau * f), base)
    }));
    out.extend(two);
    // a time constant per axis, each refined around the common one in turn
    let mut taus = [[tau, 0.0]; 3];
    let mut per_axis = one;
    for axis in 0..3 {
        let cand = best((-4..=4).map(|k| {
            let mut t = taus;
            t[axis][0] = tau * 1.5f64.powi(k);
            try_fit(data, spec, Extra::Lag { taus: t }, base)
        }));
        if let Some(c) = cand.filter(|c| c.chi2 < per_axis.chi2) {
            if let Some(Extra::Lag { taus: t }) = c.spec.extras.last() {
                taus = *t;
            }
            per_axis = c;
        }
    }
    if taus.iter().any(|t| *t != taus[0]) {
        out.push(per_axis);
    }
    out
}

/// temp_rate: the rate estimator's time constant.
pub fn rate(data: &Data, spec: &Spec, base: &Fit) -> Option<Fit> {
    best([5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0, 640.0].map(|t| try_fit(data, spec, Extra::Rate { tau_s: t }, base)))
}

/// hysteresis: the switching threshold, the state before the first change, and whether
/// the scale factors switch too.
pub fn hysteresis(data: &Data, spec: &Spec, base: &Fit) -> Vec<Fit> {
    let form = |scale: bool| {
        best([0.1, 0.25, 0.5, 1.0, 2.0, 4.0].iter().flat_map(|&th| {
            [-1.0, 1.0].map(|initial| {
                try_fit(
                    data,
                    spec,
                    Extra::Hysteresis {
                        threshold_c: th,
                        initial,
                        scale,
                    },
                    base,
                )
            })
        }))
    };
    [form(false), form(true)].into_iter().flatten().collect()
}

/// warmup_drift: the time constant for each way the clock may restart.
pub fn warmup(data: &Data, spec: &Spec, base: &Fit) -> Vec<Fit> {
    let mut restarts = vec![Restart::Start];
    if !data.events.gaps.is_empty() {
        restarts.push(Restart::Gaps);
    }
    if !data.events.handling.is_empty() {
        restarts.push(Restart::Handling);
    }
    restarts
        .into_iter()
        .filter_map(|restart| {
            time_constant(&|t| try_fit(data, spec, Extra::Warmup { tau_s: t, restart }, base), 20.0, 16)
                .map(|(_, f)| f)
        })
        .collect()
}

/// temp_curvature: a fine piecewise-linear offset basis (broad curvature), and one bend
/// placed at the best of the data's temperatures (local).
pub fn curvature(data: &Data, spec: &Spec, base: &Fit, broad: bool) -> Vec<Fit> {
    let mut temps: Vec<f64> = data.obs.iter().map(|o| o.temp_c).collect();
    temps.sort_by(f64::total_cmp);
    let (tmin, tmax) = (temps[0], temps[temps.len() - 1]);
    let mut out = Vec::new();
    if broad {
        let nb = 16usize.min(((tmax - tmin) / 4.0).floor() as usize + 1).max(2);
        let fine: Vec<f64> = (0..nb).map(|k| tmin + (tmax - tmin) * k as f64 / (nb - 1) as f64).collect();
        out.extend(try_fit(data, spec, Extra::Curvature(fine), base));
    }
    // knots at the 5 %..95 % quantiles of the data's temperatures
    let knots = (1..20).map(|q| temps[q * (temps.len() - 1) / 20]);
    out.extend(best(knots.map(|k| try_fit(data, spec, Extra::Bend { knot_c: k }, base))));
    out
}
