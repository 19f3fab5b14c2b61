//! A finding of the diagnosis, taken from the final joint model: the effect and its form,
//! the axes where it matters, its parameters with uncertainties scaled by the dispersion,
//! where it shows, and how much it improves held-out data; and the candidates the data
//! cannot tell apart, with the measurement that would.
use crate::diagnose::location::{locate, Grouping};
use crate::diagnose::parameters::{Parameter, Parameters, Quantity};
use crate::model::data::Data;
use crate::model::design::Spec;
use crate::model::effects::{EffectId, Extra};
use crate::model::metrics::{contribution, dispersion, judge, max_dg, residual_rms, sigma};
use crate::model::params::{Param, Term};
use crate::model::solve::{Depth, Fit};
use firmware_core::model::AXES;
use serde::{Deserialize, Serialize};

/// A finding of the JSON contract.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Finding {
    /// Catalogue id.
    pub effect: EffectId,
    /// The form found (time constants, switching, restarts, where a bend sits).
    pub form: String,
    /// Axes where the effect matters (removing it worsens that axis significantly).
    pub axes: Vec<String>,
    /// Parameters from the final joint fit, with their 1-sigma scaled by the final
    /// dispersion and their units (the contract's `parameters`, `uncertainties` and
    /// `units`).
    #[serde(flatten)]
    pub parameters: Parameters,
    /// Quasi-BIC change of the final model against the final model without it.
    pub delta_bic: f64,
    /// Share of the chi-square above the floor (of the model without it) it explains.
    pub share: f64,
    /// Held-out chi-square drop per parameter, in floor units.
    pub heldout_gain: f64,
    /// The effect reproduces on both halves of the recording (alternate time chunks,
    /// each fitted alone): it lowers each half's quasi-BIC by more than the margin.
    pub reproduced: bool,
    /// Residual RMS of the final model (output units).
    pub residual_rms_after: f64,
    /// max |dg| of the final model, mg.
    pub max_abs_dg_mg_after: f64,
    /// Where it shows, in one sentence.
    pub evidence: String,
    /// The position, for fixture_error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<String>,
    /// The term in the catalogue's vocabulary, for a discovered term (`a_x*a_y`); a
    /// decay's time constant as its text rounds it (the fitted one is the `tau_s`
    /// parameter).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub term: Option<crate::terms::Term>,
    /// What a discovered term corrects: the unit in flight (the blob compensates it), or
    /// only the calibration (a term of the rig or of the test's time).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corrects: Option<Corrects>,
    /// For a discovered term: the library terms this design cannot tell from it (`term
    /// on axis`); it is named as the simplest of them (fewest factors, then fewest
    /// structural unknowns such as a decay's time constant).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub equivalent: Vec<String>,
}

/// What a discovered term corrects.
#[derive(
    Debug,
    Clone,
    Copy,
    Serialize,
    Deserialize,
    PartialEq,
    Eq,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Corrects {
    /// A state of the unit (force, temperature, its rate, time since power-on): the
    /// blob carries it and the firmware compensates it in flight.
    Unit,
    /// The rig or the test (time, a tilter's moves, a stop, turn-on to turn-on): the
    /// coefficients are fitted with it, referred to the recording's start, and it is
    /// reported, not flashed.
    Calibration,
}

/// Two or more candidates the data cannot separate.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Ambiguity {
    /// Catalogue ids (`discovered` for a set of discovered terms).
    pub candidates: Vec<EffectId>,
    /// For a set of discovered terms: each as `term on axis`, the one in the model first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub terms: Vec<String>,
    /// The measurement that separates them.
    pub needed: String,
}

/// The per-axis held-out chi-square increase (floor units / dispersion) when extra `e`
/// is removed: an axis counts where the effect improves data it was not fitted on.
fn axis_gains(data: &Data, full: &Fit, reduced: &Fit, phi: f64) -> [f64; 3] {
    let ok = data.predictable(full, reduced);
    std::array::from_fn(|i| {
        (0..data.obs.len())
            .filter(|&r| ok[data.obs[r].chunk])
            .map(|r| reduced.heldout_rows[3 * r + i] - full.heldout_rows[3 * r + i])
            .sum::<f64>()
            / phi
    })
}

/// Relative step of a time constant's profile (a lag's, all its poles scaled together;
/// a warm-up's; a discovered decay's).
const PROFILE_STEP: f64 = 0.02;

/// The final fit profiled in the scale `s` of one extra's time constants, which every
/// linear fit holds fixed: the variance of `s` from the chi-square's curvature, and the
/// slope `d x_j / d s` of every linear parameter; the variance at unit dispersion
/// (a Gaussian's, exact for a model linear in `s` near the fit; the lag's profile is a
/// parabola to well under the 2 % step).
pub(crate) struct Scaled {
    /// The variance of the scale.
    pub var_s: f64,
    /// Each linear parameter's slope in the scale (the fit's columns).
    pub slope: Vec<f64>,
}

/// Extra `x` with its time constants scaled by `s` (a lag's on `axis` alone where given,
/// both poles together; on every axis otherwise); `None` for an extra without one, or
/// whose structural value is not a time constant (a knot, a threshold) or is not fitted
/// (the rate estimator's low-pass).
fn time_scaled(x: &Extra, s: f64, axis: Option<usize>) -> Option<Extra> {
    match x {
        Extra::Lag { taus } => {
            let mut taus = *taus;
            for (i, pair) in taus.iter_mut().enumerate() {
                if axis.is_none_or(|a| a == i) {
                    *pair = pair.map(|t| t * s);
                }
            }
            Some(Extra::Lag { taus })
        }
        Extra::Warmup { tau_s, restart } => Some(Extra::Warmup {
            tau_s: tau_s * s,
            restart: *restart,
        }),
        Extra::Discovered { term, axis } => term.tau_s().map(|t| Extra::Discovered {
            term: term.with_tau(t * s),
            axis: *axis,
        }),
        Extra::Curvature(_)
        | Extra::Bend { .. }
        | Extra::Rate { .. }
        | Extra::Hysteresis { .. }
        | Extra::K2
        | Extra::Asymmetry
        | Extra::Fixture(..) => None,
    }
}

/// [`Scaled`] for extra `e` of `f`, its time constants scaled together (a lag's on
/// `axis` alone where given): `None` where it has no time constant, where a refit fails
/// or changes the columns, where the profile is flat, bent down or not finite, or where
/// a slope is not finite.
pub(crate) fn scaled_profile(
    data: &Data,
    f: &Fit,
    e: usize,
    axis: Option<usize>,
) -> Option<Scaled> {
    let extra = f.spec.extras.get(e)?;
    let at = |s: f64| {
        data.fit(
            &f.spec.replaced(e, time_scaled(extra, s, axis)?),
            None,
            Depth::Profile,
        )
    };
    let (up, down) = (at(1.0 + PROFILE_STEP)?, at(1.0 - PROFILE_STEP)?);
    if up.labels != f.labels || down.labels != f.labels {
        return None;
    }
    let curv = (up.chi2 + down.chi2 - 2.0 * f.chi2) / (PROFILE_STEP * PROFILE_STEP);
    // a flat or bent-down profile (or NaN, or infinite) gives no variance
    if !curv.is_finite() || curv <= 0.0 {
        return None;
    }
    let slope: Vec<f64> = (0..f.x.len())
        .map(|j| (up.x[j] - down.x[j]) / (2.0 * PROFILE_STEP))
        .collect();
    slope.iter().all(|b| b.is_finite()).then_some(Scaled {
        var_s: 2.0 / curv,
        slope,
    })
}

/// What the profiled time constants of `f` add to each linear parameter's variance, at
/// unit dispersion: `sum b_j^2 var(s)` over the extras with a time constant (each
/// profiled alone; their own covariance left out; a lag whose time constants differ by
/// axis profiled per axis, since a coefficient on x leans on x's time constant and a
/// common scale's curvature sums all three axes'; two poles of one axis scaled
/// together). Computed once per final fit. A linear parameter's covariance is
/// the one at the time constants found; its estimate moves with them, so its spread
/// over repeated tests is the sum (the hysteresis beside a lag of the production test,
/// 120 noise seeds: h_x scattered 1.6e-6, where the fixed-lag sigma said 1.06e-6 and
/// the correlation -0.74 accounts for the factor 1.5).
pub(crate) fn profiled_variance(data: &Data, f: &Fit) -> Vec<f64> {
    let mut add = vec![0.0; f.x.len()];
    for (e, extra) in f.spec.extras.iter().enumerate() {
        let per_axis = matches!(extra, Extra::Lag { taus } if taus.iter().any(|t| *t != taus[0]));
        let directions: Vec<Option<usize>> = if per_axis {
            (0..3).map(Some).collect()
        } else {
            vec![None]
        };
        for axis in directions {
            if let Some(p) = scaled_profile(data, f, e, axis) {
                for (a, b) in add.iter_mut().zip(&p.slope) {
                    *a += b * b * p.var_s;
                }
            }
        }
    }
    add
}

/// The linear parameters of extra `e` and their scaled 1-sigma, widened by `added` (each
/// column's variance from the profiled time constants, [`profiled_variance`]) in the
/// ratio it has to the column's own formal variance: `sigma sqrt(1 + added / C_jj)`.
fn linear_parameters(full: &Fit, e: usize, phi: f64, added: &[f64]) -> Vec<Parameter> {
    full.labels
        .iter()
        .enumerate()
        .filter(|(_, l)| l.extra() == Some(e))
        .filter_map(|(j, l)| {
            let widen = match (&full.cov, added.get(j)) {
                (Some(c), Some(a)) if c[(j, j)] > 0.0 && a.is_finite() => {
                    (1.0 + a / c[(j, j)]).sqrt()
                }
                _ => 1.0,
            };
            let (value, sigma) = (full.x[j], sigma(full, j, phi) * widen);
            Some(match *l {
                // c_i = K_ii delta_i: reported as delta_i, relative
                Param::Effect {
                    term: Term::Asymmetry,
                    axis,
                    ..
                } => {
                    let kii = full.k_at.first().map(|k| k[axis][axis]).unwrap_or(1.0);
                    Parameter {
                        quantity: Quantity::Delta { axis },
                        value: value / kii,
                        sigma: sigma / kii.abs(),
                    }
                }
                Param::Effect { term, axis, .. } => Parameter {
                    quantity: Quantity::Term { term, axis },
                    value,
                    sigma,
                },
                Param::FixtureAngle { n, .. } => Parameter {
                    quantity: Quantity::Angle { n },
                    value,
                    sigma,
                },
                Param::K { .. } | Param::U0 { .. } => return None,
            })
        })
        .collect()
}

/// The 1-sigma of a structural parameter `v` (a time constant, a knot) from the profile:
/// the larger of the curvature's (chi-square up by the dispersion) and a delete-one-chunk
/// jackknife by the delta method (each chunk's pull on the profile's slope, over its
/// curvature), which holds residuals correlated in time. `make` puts a value into the
/// model's spec.
fn profile_sigma(data: &Data, full: &Fit, phi: f64, v: f64, make: &dyn Fn(f64) -> Spec) -> f64 {
    let h = PROFILE_STEP * v.abs().max(1e-3);
    let (Some(up), Some(down)) = (
        data.fit(&make(v + h), None, Depth::Profile),
        data.fit(&make(v - h), None, Depth::Profile),
    ) else {
        return f64::INFINITY;
    };
    let curv = (up.chi2 + down.chi2 - 2.0 * full.chi2) / (h * h);
    if curv.is_nan() || curv <= 0.0 {
        return f64::INFINITY;
    }
    let mut slope = vec![0.0; data.n_chunks()];
    for (r, o) in data.obs.iter().enumerate() {
        for row in 3 * r..3 * r + 3 {
            slope[o.chunk] += (up.insample_rows[row] - down.insample_rows[row]) / (2.0 * h);
        }
    }
    // without chunk c the profile's slope at v is -slope[c] (the whole is flat there)
    let shifts: Vec<f64> = slope.iter().map(|g| g / (curv / 2.0)).collect();
    let g = shifts.len() as f64;
    let mean = shifts.iter().sum::<f64>() / g;
    let jk = ((g - 1.0) / g * shifts.iter().map(|s| (s - mean).powi(2)).sum::<f64>()).sqrt();
    (2.0 * phi / curv).sqrt().max(jk)
}

/// The structural parameters of a form, with their 1-sigma where a profile defines one.
fn structural_parameters(data: &Data, full: &Fit, e: usize, phi: f64) -> Vec<Parameter> {
    let sigma = |v: f64, make: &dyn Fn(f64) -> Extra| {
        profile_sigma(data, full, phi, v, &|t| full.spec.replaced(e, make(t)))
    };
    let p = |quantity: Quantity, value: f64, sigma: f64| Parameter {
        quantity,
        value,
        sigma,
    };
    let tau = |pole: u8, axis: Option<usize>| Quantity::Tau { pole, axis };
    match full.spec.extras[e].clone() {
        Extra::Warmup { tau_s, restart } => {
            vec![p(
                tau(1, None),
                tau_s,
                sigma(tau_s, &|t| Extra::Warmup { tau_s: t, restart }),
            )]
        }
        Extra::Lag { taus } => {
            if taus.iter().all(|t| *t == taus[0]) {
                let [t1, t2] = taus[0];
                let mut v = vec![p(
                    tau(1, None),
                    t1,
                    sigma(t1, &|t| Extra::Lag { taus: [[t, t2]; 3] }),
                )];
                if t2 > 0.0 {
                    v.push(p(
                        tau(2, None),
                        t2,
                        sigma(t2, &|t| Extra::Lag { taus: [[t1, t]; 3] }),
                    ));
                }
                v
            } else {
                (0..3)
                    .map(|i| {
                        let make = |t: f64| {
                            let mut v = taus;
                            v[i][0] = t;
                            Extra::Lag { taus: v }
                        };
                        p(tau(1, Some(i)), taus[i][0], sigma(taus[i][0], &make))
                    })
                    .collect()
            }
        }
        Extra::Rate { tau_s, .. } => vec![p(Quantity::RateTau, tau_s, f64::NAN)],
        Extra::Hysteresis {
            threshold_c,
            initial,
            ..
        } => vec![
            if threshold_c < 0.0 {
                // a play operator of half-width -threshold_c: linear over twice that
                p(Quantity::PlayWidth, -2.0 * threshold_c, f64::NAN)
            } else {
                p(Quantity::Threshold, threshold_c, f64::NAN)
            },
            p(Quantity::InitialDirection, initial, f64::NAN),
        ],
        Extra::Bend { knot_c } => vec![p(
            Quantity::Knot,
            knot_c,
            sigma(knot_c, &|k| Extra::Bend { knot_c: k }),
        )],
        Extra::Curvature(b) => vec![p(Quantity::Breakpoints, b.len() as f64, 0.0)],
        Extra::Fixture(_, Some(n)) => vec![p(Quantity::FromStop, n as f64, f64::NAN)],
        Extra::Discovered { term, axis } => match term.tau_s() {
            Some(tau) => vec![p(
                Quantity::Tau {
                    pole: 1,
                    axis: None,
                },
                tau,
                sigma(tau, &|t| Extra::Discovered {
                    term: term.with_tau(t),
                    axis,
                }),
            )],
            None => Vec::new(),
        },
        Extra::K2 | Extra::Asymmetry | Extra::Fixture(_, None) => Vec::new(),
    }
}

/// The finding of extra `e` of the final model `full`; `reduced` is `full` without it.
/// `None` when it matters on no axis.
///
/// `added` is [`profiled_variance`] of `full`, made once for all its findings.
pub fn finding(data: &Data, full: &Fit, reduced: &Fit, e: usize, added: &[f64]) -> Option<Finding> {
    let phi = dispersion(data, full);
    let gains = axis_gains(data, full, reduced, phi);
    let zs = data.rules.z_significant;
    // where the effect has its own per-axis terms, one of them must be significant too
    let term_z = |i: usize| {
        (0..full.k)
            .filter(|&j| {
                full.labels[j].extra() == Some(e) && full.labels[j].effect_axis() == Some(i)
            })
            .map(|j| full.x[j].abs() / sigma(full, j, phi))
            .reduce(f64::max)
    };
    let axes: Vec<String> = (0..3)
        .filter(|&i| gains[i] >= zs * zs && term_z(i).is_none_or(|z| z >= zs))
        .map(|i| AXES[i].to_string())
        .collect();
    if axes.is_empty() {
        return None;
    }
    let extra = &full.spec.extras[e];
    let parameters = Parameters {
        output_unit: data.rec.output_unit.to_string(),
        list: linear_parameters(full, e, phi, added)
            .into_iter()
            .chain(structural_parameters(data, full, e, phi))
            .collect(),
        term_unit: if let Extra::Discovered { term, .. } = extra {
            Some(term.coefficient_unit(data.rec.output_unit.as_str()))
        } else {
            None
        },
    };
    let j = judge(data, reduced, full, e);
    Some(Finding {
        effect: extra.id(),
        form: extra.form(),
        axes,
        parameters,
        delta_bic: -j.gain,
        share: j.share,
        heldout_gain: j.heldout_gain,
        reproduced: reproduced(data, full, reduced),
        residual_rms_after: residual_rms(full),
        max_abs_dg_mg_after: max_dg(data, full),
        evidence: evidence(data, full, reduced, extra),
        position: if let Extra::Fixture(p, _) = extra {
            Some(data.rec.positions.name(*p).to_string())
        } else {
            None
        },
        // every term of the library is one of the vocabulary (a unit test holds it)
        term: if let Extra::Discovered { term, .. } = extra {
            term.named().ok()
        } else {
            None
        },
        equivalent: Vec::new(),
        corrects: if let Extra::Discovered { term, .. } = extra {
            Some(if term.of_unit() {
                Corrects::Unit
            } else {
                Corrects::Calibration
            })
        } else {
            None
        },
    })
}

/// Whether extra `e` shows the same signature on both halves of the data (even and odd
/// time chunks, each spanning the whole recording): on each half alone, the residual
/// without the effect projects onto the effect's contribution with an amplitude within
/// [`crate::model::rules::Rules::reproduced_amplitude`] of the joint fit's, at least
/// `z_significant` sigmas from zero. The rest of the model is held at the joint fit (a
/// half alone need not determine it).
pub fn reproduced(data: &Data, full: &Fit, reduced: &Fit) -> bool {
    let c = contribution(data, full, reduced);
    (0..2).all(|half| {
        let (mut rc, mut cc, mut rr) = (0.0, 0.0, 0.0);
        let mut n = 0usize;
        for r in (0..data.n_rows()).filter(|r| data.obs[r / 3].chunk % 2 == half) {
            let z = reduced.resid[r / 3][r % 3] * data.w[r].sqrt();
            rc += z * c[r];
            cc += c[r] * c[r];
            rr += z * z;
            n += 1;
        }
        if cc <= 0.0 {
            return false;
        }
        let s = rc / cc;
        let phi = ((rr - s * rc) / n.saturating_sub(1).max(1) as f64).max(1.0);
        let z = s / (phi / cc).sqrt();
        let (lo, hi) = data.rules.reproduced_amplitude;
        (lo..=hi).contains(&s) && z >= data.rules.z_significant
    })
}

/// Where the effect shows: the groups where its contribution is largest, and the residual
/// there with and without it.
fn evidence(data: &Data, full: &Fit, reduced: &Fit, extra: &Extra) -> String {
    let c = contribution(data, full, reduced);
    let z: Vec<[f64; 3]> = c.chunks(3).map(|v| [v[0], v[1], v[2]]).collect();
    let raw: Vec<[f64; 3]> = (0..data.obs.len())
        .map(|r| std::array::from_fn(|i| reduced.resid[r][i] - full.resid[r][i]))
        .collect();
    let spots = locate(data, &z, &raw, 0.0);
    let top: Vec<String> = spots
        .iter()
        .filter(|h| h.group != Grouping::Direction || matches!(extra, Extra::Hysteresis { .. }))
        .take(2)
        .map(|h| {
            format!(
                "{} axis in {} {} ({:.1}x the floor)",
                h.axis, h.group, h.value, h.rms_sigma
            )
        })
        .collect();
    let why = match extra {
        Extra::Lag { .. } => "the residual follows the temperature changes and scales with each coefficient's temperature slope, as a lagging element temperature does",
        Extra::Rate { .. } => "the offset residual is proportional to dT/dt, not to any coefficient's temperature slope",
        Extra::Hysteresis { .. } => "the same temperature reached by heating and by cooling gives different coefficients",
        Extra::K2 => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as a_i^2 in tilted positions",
        Extra::Asymmetry => "the mid-point of the +1 g and -1 g readings differs from the 0 g readings and grows as |a_i| in tilted positions",
        Extra::Fixture(_, None) => "one position disagrees with all others at every temperature",
        Extra::Fixture(_, Some(_)) => "one position agrees with the others up to a stop and disagrees from it on, at every temperature after (re-clamped or slipped between two stops)",
        Extra::Warmup { .. } => "the offset residual decays with time since power-on (or a restart), independent of temperature",
        Extra::Curvature(_) | Extra::Bend { .. } => "the coefficients bend between the temperatures more than the best polynomial the data support",
        Extra::Discovered { .. } => "no catalogue effect expresses it; a term of the library explains it on data it was not fitted on, chosen in most resamples of the time chunks",
    };
    format!(
        "Shows most on {}; {why} ({}).",
        if top.is_empty() {
            "no group".into()
        } else {
            top.join(" and ")
        },
        extra.form()
    )
}

/// The ambiguity of discovered term `e` (in the model) with the `others` the design
/// cannot tell from it, and the positions that would separate them (None: `e` is not a
/// discovered term).
pub fn term_set(e: &Extra, others: &[crate::model::library::Candidate]) -> Option<Ambiguity> {
    let Extra::Discovered { term, axis } = e else {
        return None;
    };
    let mut terms = vec![format!("{term} on {}", AXES[*axis])];
    terms.extend(others.iter().map(ToString::to_string));
    let mut needed: Vec<&str> = vec![term.identifying_positions()];
    for o in others {
        let n = o.term.identifying_positions();
        if !needed.contains(&n) {
            needed.push(n);
        }
    }
    Some(Ambiguity {
        candidates: vec![EffectId::Discovered],
        terms,
        needed: format!("data where these terms differ: {}", needed.join("; ")),
    })
}

/// The measurement that would separate the candidates of an ambiguous group (the first
/// against the second; a group of one needs nothing the data lack but more of them).
pub fn needed(group: &[EffectId]) -> String {
    use EffectId::{Hysteresis, NonlinearityK2, ScaleAsymmetry, TempRate, ThermalLag, WarmupDrift};
    let (a, b) = match group {
        [a, b, ..] => (*a, Some(*b)),
        [a] => (*a, None),
        [] => return String::new(),
    };
    let pair = |x: EffectId, y: EffectId| b.is_some_and(|b| (a, b) == (x, y) || (a, b) == (y, x));
    if pair(NonlinearityK2, ScaleAsymmetry) {
        "tilted positions (e.g. PP1..PP6) where a_i^2 and |a_i| differ".into()
    } else if pair(ThermalLag, TempRate) {
        "a soak after a ramp long enough to watch the error decay (lag) or vanish with dT/dt (rate), or ramps at two rates".into()
    } else if pair(Hysteresis, ThermalLag) || pair(Hysteresis, TempRate) {
        "a temperature visited from both directions after a long soak (`plan --from-diagnosis` ends its stops with such a return)".into()
    } else if pair(WarmupDrift, ThermalLag) || pair(WarmupDrift, TempRate) {
        "a power cycle or handling at a steady temperature, away from any temperature change".into()
    } else {
        format!(
            "data that changes {a} and {} differently (other positions, temperatures or timing)",
            b.map(EffectId::as_str).unwrap_or("")
        )
    }
}
