//! `host-fit plan`: candidate chamber and tilter programs (stops and soaks of several
//! lengths, continuous sweeps at several rates) for a unit type, each tried on the twin
//! (the unit type's noise and thermal time constant, the chamber's range and fastest
//! ramp, the tilter's positions, the sample rate), fitted as `fit` would, and its
//! verification accuracy predicted from the fit's covariance at the verification block's
//! temperatures and positions; the chosen program (shortest that meets an accuracy, or
//! most accurate within the hours) is written with an equilibrium verification block at
//! three temperatures (T0 among them when the range holds it).
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::pipeline::ModelRequest;
use crate::fit::predict::{dwell_noise_of, sigma_of};
use crate::fit::route::{fit_on, Flash, Route};
use crate::model::effects::EffectId;
use crate::simulate::config::CASE_TAU_S;
use crate::simulate::program::Step;
use crate::simulate::{simulate, PerAxis, SimConfig};
use serde::Serialize;
use std::path::Path;

/// The chamber's fastest ramp `plan` assumes when none is given, C/min: a common
/// production chamber's controlled rate (the demo's chamber too).
pub const DEFAULT_MAX_RAMP_C_PER_MIN: f64 = 3.0;

/// Soaks and settle times count the unit's thermal time constant plus its case's
/// ([`CASE_TAU_S`]), s: the element lags the sensor, and the sensor the air.
fn settle_tau_s(l: &Limits) -> f64 {
    l.tau_s + CASE_TAU_S
}

/// What the engineer states about the chamber, the tilter and the unit type.
#[derive(Debug, Clone, Serialize)]
pub struct Limits {
    /// The chamber's range, C.
    pub lo_c: f64,
    /// See `lo_c`.
    pub hi_c: f64,
    /// The fastest ramp, C/min.
    pub max_ramp_c_per_min: f64,
    /// The tilter's positions, in the order visited.
    pub positions: Vec<String>,
    /// Dwell per position, s.
    pub dwell_s: f64,
    /// Move between positions, s.
    pub move_s: f64,
    /// Samples per second.
    pub rate_hz: f64,
    /// The unit type's output noise (1 sigma per sample, output units).
    pub noise_v: f64,
    /// The unit type's thermal time constant (element behind its sensor), s.
    pub tau_s: f64,
    /// Coupled effects a diagnosis of the type found, or could not tell apart, that a
    /// stop-and-soak program must separate ([`to_separate`]; empty: none): such a
    /// program then ends with the [`Separation`] return.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub separate: Vec<EffectId>,
}

/// The effects of a diagnosis (`found`, and its `ambiguous` groups) a stop-and-soak
/// program must separate: a hysteresis found, or left ambiguous, beside a rate or a lag
/// found or left ambiguous (on stops reached only from below the hysteresis's branch is
/// one constant after the first ramp, told from the temperature polynomial only by the
/// cold start, and from a rate only by the ramps: the split a flight, warming and cooling
/// both ways, pays for). Sorted, each once; empty otherwise. A hysteresis alone, and a lag
/// beside a rate alone, ask for nothing: a return was not measured to help there (the
/// stops' soaks after their ramps already separate a lag from a rate; the turn after
/// the cold end shows a gradual hysteresis too: a play over 10 C is found and flies at
/// 0.030 mg on the production test without a return, 0.033 mg with one, 0.034 mg on the
/// sweep this module plans for it, `tests/tests/time_true.rs`). This is the unit type's
/// rule, whatever test found the pair; the diagnosis's `coupled` report
/// ([`crate::diagnose::coupled`]) says when its own recording left the split to the ramps.
pub fn to_separate(found: &[EffectId], ambiguous: &[Vec<EffectId>]) -> Vec<EffectId> {
    use EffectId::{Hysteresis, TempRate, ThermalLag};
    let dynamic = [Hysteresis, ThermalLag, TempRate];
    let mut v: Vec<EffectId> = found
        .iter()
        .chain(ambiguous.iter().flatten())
        .copied()
        .filter(|e| dynamic.contains(e))
        .collect();
    v.sort_by_key(|e| e.as_str());
    v.dedup();
    if v.contains(&Hysteresis) && v.len() >= 2 {
        v
    } else {
        Vec::new()
    }
}

/// The return that separates coupled effects ([`to_separate`]) at the end of a
/// stop-and-soak program (which reaches every stop from below, ending at the hot end):
/// back down to the middle stop at the chamber's fastest ramp, a soak of five of the
/// unit's and the case's time constants (at least 30 min), the positions. That
/// temperature is then seen from both directions after a soak: a hysteresis stays
/// through the soak with the sign of the approach (the polynomial's does not change
/// sign, a rate's vanishes with dT/dt), and a lag's error decays through the soak over
/// its time constant where a rate's vanishes as the case settles.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Separation {
    /// The effects it separates.
    pub effects: Vec<EffectId>,
    /// The middle stop it returns to, C.
    pub temp_c: f64,
    /// The ramp down to it, C/min.
    pub ramp_c_per_min: f64,
    /// The soak there before the positions, s.
    pub soak_s: f64,
}

impl Separation {
    /// One line: what it is and what it separates.
    pub fn describe(&self) -> String {
        let names: Vec<&str> = self.effects.iter().map(|e| e.as_str()).collect();
        format!(
            "a return from the hot end to {:.1} C at {} C/min, a {:.0}-min soak, the positions (separates {})",
            self.temp_c,
            self.ramp_c_per_min,
            self.soak_s / 60.0,
            names.join(", ")
        )
    }
}

/// The return a stop-and-soak program of `l` ends with, when `l` asks to separate
/// effects (see [`Separation`]).
pub fn separation(l: &Limits) -> Option<Separation> {
    (!l.separate.is_empty()).then(|| Separation {
        effects: l.separate.clone(),
        temp_c: l.lo_c + (l.hi_c - l.lo_c) / 2.0,
        ramp_c_per_min: l.max_ramp_c_per_min,
        soak_s: (5.0 * settle_tau_s(l)).max(1800.0),
    })
}

/// A candidate's kind.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Kind {
    /// Five stops over the range, each soaked this long, the positions at each.
    StopSoak {
        /// Soak per stop, min.
        soak_min: f64,
    },
    /// Up and back down at this rate, holding at each end, the tilter turning.
    Sweep {
        /// Ramp rate, C/min.
        c_per_min: f64,
        /// Hold at the hot end, min.
        hold_min: f64,
        /// Hold at the cold end where the sweep ends, min (the start is soaked).
        end_hold_min: f64,
    },
}

impl Kind {
    /// One line.
    pub fn describe(&self) -> String {
        match self {
            Kind::StopSoak { soak_min } => format!("5 stops, {soak_min:.0}-min soaks"),
            Kind::Sweep {
                c_per_min,
                hold_min,
                end_hold_min,
            } if hold_min == end_hold_min => {
                format!("sweep {c_per_min:.1} C/min, {hold_min:.0}-min holds")
            }
            Kind::Sweep {
                c_per_min,
                hold_min,
                end_hold_min,
            } => format!(
                "sweep {c_per_min:.1} C/min, holds {hold_min:.0} min hot, {end_hold_min:.0} cold"
            ),
        }
    }
}

/// One candidate plan and its predicted accuracy.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// What it is.
    pub kind: Kind,
    /// Chamber hours of the calibration program (the verification block apart).
    pub hours: f64,
    /// Predicted worst verification |dg| (3 sigma of the fit's covariance and of a
    /// verification dwell's noise, plus the cache's budget, over the verification
    /// temperatures and positions; see [`predict`]), mg.
    pub predicted_mg: f64,
    /// The thermal lag the fit of the twin's recording kept, s.
    pub lag_s: Option<f64>,
    /// The valid range of the blob fitted to the twin's recording (as `fit --route
    /// dynamic` writes it), C.
    pub valid_c: [f64; 2],
    /// Whether that reaches the range asked for, within [`COVER_TOLERANCE_C`] of each end:
    /// only such a candidate is chosen.
    pub covers: bool,
    /// Whether it separates the coupled effects the plan was asked to ([`Limits::separate`]:
    /// always, when none): a stop-and-soak program with its [`Separation`] return does, a
    /// sweep does not. At one rate each way a sweep's rate term flips sign with the
    /// direction as a hysteresis does, and only its holds tell them apart. Only a
    /// candidate that separates is chosen.
    pub separates: bool,
}

/// A candidate covers the range asked for when its blob's valid range reaches within
/// this of each end, C: as far as a blob of the static route claims beyond its data
/// ([`crate::fit::temperature::RANGE_MARGIN_C`]); further, the unit would be compensated
/// by extrapolation where the engineer asked for a calibration.
pub const COVER_TOLERANCE_C: f64 = crate::fit::temperature::RANGE_MARGIN_C;

impl Candidate {
    /// Its label in the table and on the plot: `A`, `B`, ... by its place.
    pub fn label(i: usize) -> String {
        let letters = b"ABCDEFGHIJKLMNOPQRSTUVWXYZ";
        let n = letters.len();
        let mut s = String::new();
        if i >= n {
            s.push(char::from(letters[(i / n - 1) % n]));
        }
        s.push(char::from(letters[i % n]));
        s
    }

    /// Its valid range as `lo..hi` (C, one decimal).
    pub fn valid_text(&self) -> String {
        format!("{:.1}..{:.1}", self.valid_c[0], self.valid_c[1])
    }
}

/// The reference temperature the fit and the acceptance's tighter band use, C (a
/// recording's default `t0_c`).
pub const T0_C: f64 = 20.0;

/// The verification block's temperatures: 15% and 85% of the range, and between them
/// [`T0_C`] when the range holds it inside those two (else 50%): the acceptance judges
/// the band around T0 apart, so the block must have a dwell there.
pub fn verification_temps(l: &Limits) -> [f64; 3] {
    let span = l.hi_c - l.lo_c;
    let at = |f: f64| ((l.lo_c + f * span) * 10.0).round() / 10.0;
    let (lo, hi) = (at(0.15), at(0.85));
    let mid = if lo < T0_C && T0_C < hi {
        T0_C
    } else {
        at(0.5)
    };
    [lo, mid, hi]
}

fn push(steps: &mut Vec<Step>, t: &mut f64, sp: f64, pos: &str, d: f64) {
    steps.push(Step {
        time_s: *t,
        setpoint_c: sp,
        position: pos.to_string(),
    });
    *t += d;
}

/// The positions visited once at set point `sp` (held): move, dwell, for each.
fn visit(steps: &mut Vec<Step>, t: &mut f64, sp: f64, l: &Limits) {
    for p in &l.positions {
        push(steps, t, sp, "-", l.move_s);
        push(steps, t, sp, p, l.dwell_s);
    }
}

/// The calibration program of `kind` (starting soaked at the low end), and its end time;
/// a stop-and-soak program ends with the [`separation`] return when `l` asks for one (a
/// sweep is left as it is, and then not chosen: see [`Candidate::separates`]).
pub fn program(kind: Kind, l: &Limits) -> (Vec<Step>, f64) {
    let (mut steps, mut t) = (Vec::new(), 0.0);
    let rest = l.positions.first().map(String::as_str).unwrap_or("TP1");
    match kind {
        Kind::StopSoak { soak_min } => {
            let mut sp = l.lo_c;
            for k in 0..5 {
                let to = l.lo_c + (l.hi_c - l.lo_c) * k as f64 / 4.0;
                let ramp = (to - sp).abs() / l.max_ramp_c_per_min * 60.0;
                if ramp > 0.0 {
                    push(&mut steps, &mut t, sp, rest, ramp);
                }
                push(&mut steps, &mut t, to, rest, soak_min * 60.0);
                visit(&mut steps, &mut t, to, l);
                sp = to;
            }
            if let Some(r) = separation(l) {
                let ramp = (sp - r.temp_c).abs() / r.ramp_c_per_min * 60.0;
                push(&mut steps, &mut t, sp, rest, ramp);
                push(&mut steps, &mut t, r.temp_c, rest, r.soak_s);
                visit(&mut steps, &mut t, r.temp_c, l);
                sp = r.temp_c;
            }
            push(&mut steps, &mut t, sp, rest, 0.0);
        }
        Kind::Sweep {
            c_per_min,
            hold_min,
            end_hold_min,
        } => {
            // knots of the set point; the tilter turns through the positions meanwhile
            let ramp = (l.hi_c - l.lo_c) / c_per_min * 60.0;
            let (hold, end_hold) = (hold_min * 60.0, end_hold_min * 60.0);
            let knots = [
                (0.0, l.lo_c),
                (ramp, l.hi_c),
                (ramp + hold, l.hi_c),
                (2.0 * ramp + hold, l.lo_c),
                (2.0 * ramp + hold + end_hold, l.lo_c),
            ];
            let end = knots[4].0;
            let set_at = |t: f64| crate::simulate::program::set_point_at(&knots, t);
            'turning: loop {
                for p in &l.positions {
                    if t + l.move_s + l.dwell_s > end {
                        break 'turning;
                    }
                    let sp = set_at(t);
                    push(&mut steps, &mut t, sp, "-", l.move_s);
                    let sp = set_at(t);
                    push(&mut steps, &mut t, sp, p, l.dwell_s);
                }
            }
            let sp = set_at(t);
            push(&mut steps, &mut t, sp, rest, 0.0);
        }
    }
    (steps, t)
}

/// The equilibrium verification block after a program ending at `t` and `sp`: at each
/// of [`verification_temps`] a ramp, a soak of five of the unit's and the case's time
/// constants (at least 30 min), the positions; the rows at rest unnamed (`-`) so only
/// the equilibrium dwells are judged.
pub fn verification(l: &Limits, mut t: f64, mut sp: f64) -> Vec<Step> {
    let mut steps = Vec::new();
    let soak = (5.0 * settle_tau_s(l)).max(1800.0);
    for to in verification_temps(l) {
        let ramp = (to - sp).abs() / l.max_ramp_c_per_min * 60.0;
        if ramp > 0.0 {
            push(&mut steps, &mut t, sp, "-", ramp);
        }
        push(&mut steps, &mut t, to, "-", soak);
        visit(&mut steps, &mut t, to, l);
        sp = to;
    }
    push(&mut steps, &mut t, sp, "-", 0.0);
    steps
}

/// The twin of the unit type: the paper unit with the stated noise and lag.
pub fn twin(l: &Limits, seed: u64) -> SimConfig {
    let mut c = SimConfig {
        seed,
        ..SimConfig::default()
    };
    c.unit.noise_v = l.noise_v;
    c.schedule.rate_hz = l.rate_hz;
    if l.tau_s > 0.0 {
        c.effects.thermal_lag = Some(PerAxis {
            value: [l.tau_s; 3],
        });
    }
    c
}

/// Run `steps` on `cfg`'s twin: the recording.
pub fn run(cfg: &SimConfig, steps: &[Step], name: &str) -> Result<(String, Recording)> {
    let mut c = cfg.clone();
    c.chamber.start_c = steps
        .first()
        .map(|s| s.setpoint_c)
        .unwrap_or(c.chamber.start_c);
    c.schedule.program = steps.to_vec();
    let sim = simulate(&c, |_| {})?;
    let rec = Recording::from_reader(Path::new(name), sim.csv.as_bytes(), Positions::default())?;
    Ok((sim.csv, rec))
}

/// What [`predict`] predicts of a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Predicted {
    /// The worst verification |dg|, mg.
    pub worst_mg: f64,
    /// The thermal lag the fit kept, s.
    pub lag_s: Option<f64>,
    /// The valid range of the blob of the fit, C.
    pub valid_c: [f64; 2],
}

/// The predicted worst verification |dg| of the dynamic fit of `rec` at `temps` over
/// `positions`, mg, the lag kept and the blob's valid range: 3 sigma of the fit's covariance (dispersion-scaled)
/// and of a verification dwell's own noise (`noise_v` per sample, `dwell_samples`
/// averaged) in quadrature, plus the firmware cache's budget (one dwell sigma, the most
/// `fit`'s default step costs). Not included: the temperature sensor's noise and
/// quantisation, the lag's own uncertainty (profiled, not in the covariance), the f32
/// path (bounded apart).
pub fn predict(
    rec: &Recording,
    temps: &[f64],
    positions: &[String],
    noise_v: f64,
    dwell_samples: f64,
) -> Result<Predicted> {
    let routed = fit_on(
        rec,
        Some(Route::Dynamic),
        &ModelRequest::default(),
        &mut Vec::new(),
    )?;
    let cal = routed.calibration(rec, Flash::default())?.cal;
    let mut worst: f64 = 0.0;
    for &t in temps {
        for name in positions {
            let Some(i) = rec.positions.index(name) else {
                continue;
            };
            let a = rec.positions.vector(i);
            let model = sigma_of(&routed, t, a);
            if model.is_nan() {
                continue;
            }
            let dwell = dwell_noise_of(&routed, t, a, [noise_v * noise_v; 3], dwell_samples);
            // the firmware's cache is chosen to cost at most a dwell's own noise (1 sigma):
            // a bias, added
            worst = worst.max((3.0 * model.hypot(dwell) + dwell) * 1e3);
        }
    }
    Ok(Predicted {
        worst_mg: worst,
        lag_s: routed.lag_tau_s(),
        valid_c: [cal.t_min_c, cal.t_max_c],
    })
}

/// The hold at the hot end (whole minutes) that brings the twin's case, where its
/// temperature sensor sits, within half of [`COVER_TOLERANCE_C`] of the set point after a
/// ramp at `c_per_min`: the chamber's air and the case lag the set point in series
/// (`tau_air`, `tau_case`), by `r (tau_air + tau_case)` at the end of a long ramp at `r`
/// C/s, and close the gap in a hold as
/// `r (tau_case^2 e^(-t/tau_case) - tau_air^2 e^(-t/tau_air)) / (tau_case - tau_air)`
/// (conservative for a ramp shorter than the lags). At most a day.
pub fn cover_hold_min(cfg: &SimConfig, c_per_min: f64) -> f64 {
    let r = c_per_min / 60.0;
    let a = cfg.chamber.tau_air_s.max(0.0);
    // equal time constants: the limit of the formula, approached closely enough
    let c = cfg.chamber.tau_case_s.max(0.0).max(a + 1e-3);
    let decay = |t: f64, tau: f64| if tau > 0.0 { (-t / tau).exp() } else { 0.0 };
    let gap = |t: f64| r * (c * c * decay(t, c) - a * a * decay(t, a)) / (c - a);
    let mut t = 0.0;
    while gap(t) > COVER_TOLERANCE_C / 2.0 && t < 86_400.0 {
        t += 60.0;
    }
    t / 60.0
}

/// The candidates: stops and soaks of 10, 25 and 40 minutes; sweeps at the fastest
/// ramp holding at each end half, one or two of the unit's and the case's time constants
/// (half: the dynamic fit carries the lag, so the element need not settle at the ends;
/// the shortest sweep a slowly lagging unit can have), one held a settle time at the hot
/// end and half of it at the cold end (the start is soaked there already; the hot end is
/// where the element must come close to the top of the range), and at half the ramp with
/// one; and at the fastest ramp and at half of it, held at the hot end until the twin's
/// sensor comes to the top of the range ([`cover_hold_min`]; the start is soaked at the
/// bottom) and a settle time at the cold end, so that a sweep may cover the range asked
/// for.
pub fn kinds(l: &Limits) -> Vec<Kind> {
    let settle_min = (settle_tau_s(l) / 60.0).round();
    let mut v: Vec<Kind> = [10.0, 25.0, 40.0]
        .map(|soak_min| Kind::StopSoak { soak_min })
        .to_vec();
    for (f, hot, cold) in [
        (1.0, 0.5, 0.5),
        (1.0, 1.0, 0.5),
        (1.0, 1.0, 1.0),
        (1.0, 2.0, 2.0),
        (0.5, 1.0, 1.0),
    ] {
        v.push(Kind::Sweep {
            c_per_min: l.max_ramp_c_per_min * f,
            hold_min: (settle_min * hot).round(),
            end_hold_min: (settle_min * cold).round(),
        });
    }
    let cfg = twin(l, 0);
    for f in [1.0, 0.5] {
        let c_per_min = l.max_ramp_c_per_min * f;
        let k = Kind::Sweep {
            c_per_min,
            // the element must settle too where it lags
            hold_min: cover_hold_min(&cfg, c_per_min).max(settle_min),
            // a settle time at the cold end, where the sweep ends: its last turn through
            // the positions at rest, as the symmetric sweeps have
            end_hold_min: settle_min,
        };
        if !v.contains(&k) {
            v.push(k);
        }
    }
    v
}

/// Every candidate tried on the twin (seed `seed`) and predicted.
pub fn candidates(l: &Limits, seed: u64) -> Result<Vec<Candidate>> {
    check(l)?;
    let cfg = twin(l, seed);
    let temps = verification_temps(l);
    kinds(l)
        .into_iter()
        .map(|kind| {
            let (steps, end) = program(kind, l);
            let (_, rec) = run(&cfg, &steps, "candidate.csv")?;
            let p = predict(&rec, &temps, &l.positions, l.noise_v, l.dwell_s * l.rate_hz)?;
            Ok(Candidate {
                kind,
                hours: end / 3600.0,
                predicted_mg: p.worst_mg,
                lag_s: p.lag_s,
                valid_c: p.valid_c,
                covers: p.valid_c[0] <= l.lo_c + COVER_TOLERANCE_C
                    && p.valid_c[1] >= l.hi_c - COVER_TOLERANCE_C,
                separates: l.separate.is_empty() || matches!(kind, Kind::StopSoak { .. }),
            })
        })
        .collect()
}

fn check(l: &Limits) -> Result<()> {
    let ok = l.hi_c > l.lo_c
        && l.max_ramp_c_per_min > 0.0
        && l.rate_hz > 0.0
        && l.noise_v > 0.0
        && l.tau_s >= 0.0
        && l.dwell_s > 0.0
        && l.move_s >= 0.0
        && l.positions.len() >= 6;
    if ok {
        Ok(())
    } else {
        Err(HostError::new(
            ErrorKind::Invalid,
            "plan needs a range lo < hi, a ramp > 0, a rate > 0, a noise > 0, a time constant >= 0, a dwell > 0 and at least 6 positions",
        ))
    }
}

/// What to aim at.
#[derive(Debug, Clone, Copy)]
pub enum Target {
    /// The shortest plan predicted within this worst |dg|, mg.
    AccuracyMg(f64),
    /// The most accurate plan within these chamber hours.
    Hours(f64),
}

/// The chosen candidate's index among those that cover the range asked for (and separate
/// what the plan was asked to), or None when none of them meets the target
/// ([`why_none`] says why).
pub fn choose(c: &[Candidate], target: Target) -> Option<usize> {
    let idx = (0..c.len()).filter(|&i| c[i].covers && c[i].separates);
    match target {
        Target::AccuracyMg(mg) => idx
            .filter(|&i| c[i].predicted_mg <= mg)
            .min_by(|&a, &b| c[a].hours.total_cmp(&c[b].hours)),
        Target::Hours(h) => idx
            .filter(|&i| c[i].hours <= h)
            .min_by(|&a, &b| c[a].predicted_mg.total_cmp(&c[b].predicted_mg)),
    }
}

/// Why no candidate was chosen for `target` over the range of `l`: none covers the range,
/// none that covers it does so within the hours or the accuracy asked (with the shortest,
/// or the most accurate, that does), or none meets the target at all; with effects to
/// separate, of the stop-and-soak candidates alone.
pub fn why_none(c: &[Candidate], target: Target, l: &Limits) -> String {
    let range = format!("{}..{} C", l.lo_c, l.hi_c);
    let covering = || {
        c.iter()
            .enumerate()
            .filter(|(_, x)| x.covers && x.separates)
    };
    let shortest = covering().min_by(|a, b| a.1.hours.total_cmp(&b.1.hours));
    let best = covering().min_by(|a, b| a.1.predicted_mg.total_cmp(&b.1.predicted_mg));
    // with effects to separate, only the stops and soaks are candidates
    let plans = if l.separate.is_empty() {
        "plan".to_string()
    } else {
        let names: Vec<&str> = l.separate.iter().map(|e| e.as_str()).collect();
        format!(
            "stop-and-soak plan (the only ones that separate {})",
            names.join(", ")
        )
    };
    match (target, shortest, best) {
        (_, None, _) | (_, _, None) => format!(
            "no {plans} has a blob that covers the range asked for ({range}, within {COVER_TOLERANCE_C} C of each end: see the valid ranges)"
        ),
        (Target::Hours(h), Some((i, x)), _) => format!(
            "no {plans} covers {range} within {h} chamber hours: the shortest that does is {} ({}, {:.2} h, valid {} C); give --hours {:.2} or more, or a narrower --range-c",
            Candidate::label(i),
            x.kind.describe(),
            x.hours,
            x.valid_text(),
            (x.hours * 100.0).ceil() / 100.0
        ),
        (Target::AccuracyMg(mg), _, Some((i, x))) => format!(
            "no {plans} that covers {range} is predicted within {mg} mg: the most accurate that does is {} ({}, predicted {:.4} mg, {:.2} h)",
            Candidate::label(i),
            x.kind.describe(),
            x.predicted_mg,
            x.hours
        ),
    }
}

/// The table of candidates (the chosen one marked), each with its label, hours,
/// prediction, lag and the valid range of its blob (`short` where it does not cover the
/// range asked for, `does not separate` where it does not separate the effects asked).
pub fn table(c: &[Candidate], chosen: Option<usize>) -> String {
    let w = c
        .iter()
        .map(|x| x.kind.describe().len())
        .chain([4])
        .max()
        .unwrap_or(4);
    let mut s = format!(
        "    {:<w$}  chamber h  predicted worst |dg|, mg  lag kept, s  valid range, C\n",
        "plan"
    );
    for (i, x) in c.iter().enumerate() {
        s.push_str(&format!(
            "{} {:<2} {:<w$}  {:>9.2}  {:>24.4}  {:>11}  {}{}\n",
            if Some(i) == chosen { "*" } else { " " },
            Candidate::label(i),
            x.kind.describe(),
            x.hours,
            x.predicted_mg,
            x.lag_s.map_or("none".into(), |t| format!("{t:.0}")),
            x.valid_text(),
            match (x.covers, x.separates) {
                (true, true) => "",
                (false, _) => " (short)",
                (true, false) => " (does not separate)",
            }
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use EffectId::{Hysteresis, TempRate, ThermalLag, WarmupDrift};

    fn limits(separate: Vec<EffectId>) -> Limits {
        Limits {
            lo_c: -40.0,
            hi_c: 70.0,
            max_ramp_c_per_min: 3.0,
            positions: (1..=6).map(|i| format!("TP{i}")).collect(),
            dwell_s: 50.0,
            move_s: 10.0,
            rate_hz: 1.0,
            noise_v: 2e-5,
            tau_s: 0.0,
            separate,
        }
    }

    #[test]
    fn only_a_hysteresis_beside_dynamics_asks_for_a_return() {
        assert_eq!(
            to_separate(&[TempRate, Hysteresis, WarmupDrift], &[]),
            vec![Hysteresis, TempRate]
        );
        assert!(to_separate(&[Hysteresis], &[]).is_empty());
        assert!(to_separate(&[ThermalLag, TempRate], &[]).is_empty());
        assert!(to_separate(&[TempRate], &[vec![ThermalLag, TempRate]]).is_empty());
        assert_eq!(
            to_separate(&[TempRate], &[vec![TempRate, Hysteresis]]),
            vec![Hysteresis, TempRate]
        );
        assert_eq!(
            to_separate(&[Hysteresis], &[vec![ThermalLag, TempRate]]),
            vec![Hysteresis, TempRate, ThermalLag]
        );
    }

    /// The stop-and-soak program ends, after its hot stop, with a ramp at the fastest
    /// rate down to the middle stop, the soak and every position there; without a
    /// separation it ends at the hot stop; a sweep is the same either way.
    #[test]
    fn the_return_follows_the_hot_stop() {
        let kind = Kind::StopSoak { soak_min: 10.0 };
        let (plain, end0) = program(kind, &limits(Vec::new()));
        let l = limits(vec![Hysteresis, TempRate]);
        let (with, end1) = program(kind, &l);
        let r = separation(&l).unwrap();
        assert_eq!(r.temp_c, 15.0);
        let visits = l.positions.len() as f64 * (l.dwell_s + l.move_s);
        let ramp = 55.0 / 3.0 * 60.0;
        assert!((end1 - end0 - (ramp + r.soak_s + visits)).abs() < 1e-9);
        let n = plain.len() - 1;
        assert_eq!(with[..n], plain[..n]);
        assert_eq!(with[n].setpoint_c, 70.0);
        assert_eq!(with[n + 1].setpoint_c, 15.0);
        assert!((with[n + 1].time_s - with[n].time_s - ramp).abs() < 1e-9);
        let named: Vec<&str> = with[n + 2..]
            .iter()
            .filter(|s| s.position != "-")
            .map(|s| s.position.as_str())
            .collect();
        assert!(l.positions.iter().all(|p| named.contains(&p.as_str())));
        assert!(with[n + 1..].iter().all(|s| s.setpoint_c == 15.0));
        let sweep = Kind::Sweep {
            c_per_min: 3.0,
            hold_min: 10.0,
            end_hold_min: 10.0,
        };
        assert_eq!(program(sweep, &l).0, program(sweep, &limits(Vec::new())).0);
    }
}
