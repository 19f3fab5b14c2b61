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
use crate::error::{HostError, Result};
use crate::fit::pipeline::ModelRequest;
use crate::fit::predict::{dwell_noise_of, sigma_of};
use crate::fit::route::{fit_on, Route};
use crate::simulate::program::Step;
use crate::simulate::{simulate, PerAxis, SimConfig};
use serde::Serialize;
use std::path::Path;

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

/// The calibration program of `kind` (starting soaked at the low end), and its end time.
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
    let soak = (5.0 * (l.tau_s + 600.0)).max(1800.0);
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

/// The predicted worst verification |dg| of the dynamic fit of `rec` at `temps` over
/// `positions`, mg, and the lag kept: 3 sigma of the fit's covariance (dispersion-scaled,
/// [`sigma_of`]) and of a verification dwell's own noise (`noise_v` per sample,
/// `dwell_samples` averaged, [`dwell_noise_of`]) in quadrature, plus the firmware cache's
/// budget (one dwell sigma, the most `fit`'s default step costs). Not included: the
/// temperature sensor's noise and quantisation, the lag's own uncertainty (profiled, not
/// in the covariance), the f32 path (bounded apart).
pub fn predict(
    rec: &Recording,
    temps: &[f64],
    positions: &[String],
    noise_v: f64,
    dwell_samples: f64,
) -> Result<(f64, Option<f64>)> {
    let routed = fit_on(
        rec,
        Some(Route::Dynamic),
        &ModelRequest::default(),
        &mut Vec::new(),
    )?;
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
    Ok((worst, routed.lag_tau_s()))
}

/// The candidates: stops and soaks of 10, 25 and 40 minutes; sweeps at the fastest
/// ramp holding at each end half, one or two of the unit's and the case's time constants
/// (half: the dynamic fit carries the lag, so the element need not settle at the ends;
/// the shortest sweep a slowly lagging unit can have), one held a settle time at the hot
/// end and half of it at the cold end (the start is soaked there already; the hot end is
/// where the element must come close to the top of the range), and at half the ramp with
/// one.
pub fn kinds(l: &Limits) -> Vec<Kind> {
    let settle_min = ((l.tau_s + 600.0) / 60.0).round();
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
            let (predicted_mg, lag_s) =
                predict(&rec, &temps, &l.positions, l.noise_v, l.dwell_s * l.rate_hz)?;
            Ok(Candidate {
                kind,
                hours: end / 3600.0,
                predicted_mg,
                lag_s,
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
        Err(HostError::msg(
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

/// The chosen candidate's index, or None when none meets the target.
pub fn choose(c: &[Candidate], target: Target) -> Option<usize> {
    let idx = 0..c.len();
    match target {
        Target::AccuracyMg(mg) => idx
            .filter(|&i| c[i].predicted_mg <= mg)
            .min_by(|&a, &b| c[a].hours.total_cmp(&c[b].hours)),
        Target::Hours(h) => idx
            .filter(|&i| c[i].hours <= h)
            .min_by(|&a, &b| c[a].predicted_mg.total_cmp(&c[b].predicted_mg)),
    }
}

/// The table of candidates (the chosen one marked).
pub fn table(c: &[Candidate], chosen: Option<usize>) -> String {
    let mut s = String::from(
        "  plan                              chamber h  predicted worst |dg|, mg  lag kept, s\n",
    );
    for (i, x) in c.iter().enumerate() {
        s.push_str(&format!(
            "{} {:<33} {:>9.2}  {:>24.4}  {:>11}\n",
            if Some(i) == chosen { "*" } else { " " },
            x.kind.describe(),
            x.hours,
            x.predicted_mg,
            x.lag_s.map_or("none".into(), |t| format!("{t:.0}"))
        ));
    }
    s
}
