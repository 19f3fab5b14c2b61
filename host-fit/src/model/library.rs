//! The library of discovered terms (physics-catalogue.md, "Beyond the catalogue"): the
//! short products of what a recording measures (the specific force's components, the
//! temperature, its rate, the time, the events) that no catalogue effect expresses, each
//! a column of the diagnosis's design on one output axis, computed on the recording's own
//! rows and clock and averaged into its windows as every other column is.
use crate::data::recording::Recording;
use crate::model::data::Data;
use crate::model::orders::Orders;
use crate::model::regressors::{self, Settle};
use crate::terms::{Factor, Tau, Term, TermError, TermErrorKind};
use firmware_core::model::AXES;
use std::fmt;

/// An event a `decay` or a `step` counts from: the vocabulary's own ([`crate::terms`]),
/// here found on a recording's rows (the start and the end of every stated power-off,
/// [`stop_arrivals`], [`moves`]).
pub use crate::terms::Event;

/// A time-varying factor by value, to key a map: its kind, its event, the exact bits of
/// its TAU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimedKey {
    /// The kind's rank in the canonical order.
    kind: u8,
    /// The event it follows, if any.
    event: Option<Event>,
    /// The TAU's bits (0 without one).
    tau_bits: u64,
}

/// The part of a term that varies in time (everything but the specific force), at most
/// two factors of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Timed {
    /// `dT`: temp_c - T0, C.
    DT,
    /// `dTdt`: the rate of temp_c, C/min (the zero-lag estimator over
    /// [`RATE_TAU_S`], held after the start only).
    Rate,
    /// `t`: hours since the recording's first row.
    Hours,
    /// `decay(EVENT,TAU)`, TAU in seconds.
    Decay(Event, f64),
    /// `step(EVENT)`.
    Step(Event),
}

impl Timed {
    /// The canonical order of factors: dT, dTdt, t, then events.
    fn rank(&self) -> u8 {
        match self {
            Timed::DT => 0,
            Timed::Rate => 1,
            Timed::Hours => 2,
            Timed::Decay(..) => 3,
            Timed::Step(_) => 4,
        }
    }

    /// The factor as a value that can key a map: its kind, its event and the exact bits
    /// of its TAU, so that two TAUs which print alike (the report rounds them) never
    /// share a column.
    pub fn key(&self) -> TimedKey {
        let (event, tau_bits) = match self {
            Timed::DT | Timed::Rate | Timed::Hours => (None, 0),
            Timed::Decay(e, tau) => (Some(*e), tau.to_bits()),
            Timed::Step(e) => (Some(*e), 0),
        };
        TimedKey {
            kind: self.rank(),
            event,
            tau_bits,
        }
    }

    /// Whether the unit itself carries it (compensable on the MCU): the temperature, its
    /// rate and the decay since power-on; the time and the rig's events only correct the
    /// calibration.
    fn of_unit(&self) -> bool {
        matches!(
            self,
            Timed::DT | Timed::Rate | Timed::Decay(Event::PowerOn, _)
        )
    }

    /// The unit of the factor, for the coefficient's unit.
    fn unit(&self) -> &'static str {
        match self {
            Timed::DT => "C",
            Timed::Rate => "(C/min)",
            Timed::Hours => "h",
            Timed::Decay(..) | Timed::Step(_) => "",
        }
    }
}

impl fmt::Display for Timed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Timed::DT => f.write_str("dT"),
            Timed::Rate => f.write_str("dTdt"),
            Timed::Hours => f.write_str("t"),
            Timed::Decay(e, tau) => write!(f, "decay({},{})", e.name(), tau_text(*tau)),
            Timed::Step(e) => write!(f, "step({})", e.name()),
        }
    }
}

/// A time constant as a report names it: to whole minutes from 10 min on, else to
/// whole seconds (a fitted one is known to a few per cent at best).
fn reported_tau_s(tau_s: f64) -> f64 {
    if tau_s >= 600.0 {
        (tau_s / 60.0).round_ties_even() * 60.0
    } else {
        tau_s.round_ties_even()
    }
}

/// A time constant as the vocabulary writes it ([`reported_tau_s`] in
/// `firmware_core::terms::Tau`'s canonical text: `7min` for 420 s, `25s`); a time
/// constant that is no TAU (0, a family's placeholder) in seconds.
fn tau_text(tau_s: f64) -> String {
    let s = reported_tau_s(tau_s);
    Tau::from_seconds(s as f32).map_or_else(|| format!("{s}s"), |t| t.to_string())
}

/// A discovered term: a product of at most three factors entering one output axis
/// additively. The force part is `a_x^p0 * a_y^p1 * a_z^p2` (or `abs(a_j)`), the rest
/// at most two time-varying factors.
#[derive(Debug, Clone, PartialEq)]
pub struct LibTerm {
    /// Powers of a_x, a_y, a_z.
    pub powers: [u8; 3],
    /// `abs(a_j)` instead of powers (then `powers` is zero).
    pub abs: Option<usize>,
    /// The time-varying factors, in canonical order.
    pub timed: Vec<Timed>,
}

impl LibTerm {
    /// Factors counted with their powers.
    pub fn factors(&self) -> usize {
        self.powers.iter().map(|p| *p as usize).sum::<usize>()
            + usize::from(self.abs.is_some())
            + self.timed.len()
    }

    /// The decay's time constant (s), when it has one: a structural unknown, profiled.
    pub fn tau_s(&self) -> Option<f64> {
        self.timed.iter().find_map(|t| match t {
            Timed::Decay(_, tau) => Some(*tau),
            Timed::DT | Timed::Rate | Timed::Hours | Timed::Step(_) => None,
        })
    }

    /// The same term with the decay's time constant `tau_s`.
    pub fn with_tau(&self, tau_s: f64) -> LibTerm {
        let mut t = self.clone();
        for f in &mut t.timed {
            if let Timed::Decay(e, _) = f {
                *f = Timed::Decay(*e, tau_s);
            }
        }
        t
    }

    /// The vocabulary's term ([`crate::terms::Term`]) with the decay's time constant as
    /// fitted (to the blob's f32): what a blob's term table carries, so that the firmware
    /// compensates the very term the coefficients were fitted with (the report's text
    /// rounds a time constant to whole seconds or minutes: flashed from that text, a
    /// decay fitted at 977 s ran on the MCU at 960 s, `16min`).
    pub fn term(&self) -> Result<Term, TermError> {
        self.typed(|tau_s| Tau::from_seconds(tau_s as f32))
    }

    /// The vocabulary's term as a report names it: the decay's time constant rounded as
    /// its text is written (whole minutes from 10 min on, else whole seconds), so that
    /// the finding's term and this term's canonical text are one value. The fitted time
    /// constant is the finding's `tau_s` parameter, with its uncertainty.
    pub fn named(&self) -> Result<Term, TermError> {
        self.typed(|tau_s| Tau::from_seconds(reported_tau_s(tau_s) as f32))
    }

    /// The vocabulary's term, each decay's time constant made by `tau`.
    fn typed(&self, tau: impl Fn(f64) -> Option<Tau>) -> Result<Term, TermError> {
        let refuse = |kind| TermError {
            term: self.to_string(),
            kind,
        };
        let force = [
            (Factor::Ax, Factor::AbsAx),
            (Factor::Ay, Factor::AbsAy),
            (Factor::Az, Factor::AbsAz),
        ];
        let mut factors = Vec::new();
        if let Some(j) = self.abs {
            let (_, abs) = force
                .get(j)
                .ok_or_else(|| refuse(TermErrorKind::UnknownFactor(format!("abs of axis {j}"))))?;
            factors.push(*abs);
        }
        for (&(plain, _), &p) in force.iter().zip(&self.powers) {
            factors.extend(std::iter::repeat_n(plain, usize::from(p)));
        }
        for t in &self.timed {
            factors.push(match *t {
                Timed::DT => Factor::DT,
                Timed::Rate => Factor::DTdt,
                Timed::Hours => Factor::Hours,
                Timed::Decay(e, tau_s) => Factor::Decay(
                    e,
                    tau(tau_s)
                        .ok_or_else(|| refuse(TermErrorKind::BadTau(format!("{tau_s} s"))))?,
                ),
                Timed::Step(e) => Factor::Step(e),
            });
        }
        Term::new(factors)
    }

    /// The same term with any decay's time constant left out: what identifies a family.
    pub fn family(&self) -> String {
        self.with_tau(0.0).to_string()
    }

    /// Whether the unit carries it (the MCU compensates it): every factor a state of the
    /// unit. Terms in time or the rig's events only correct the calibration, like a
    /// fixture error.
    pub fn of_unit(&self) -> bool {
        self.timed.iter().all(Timed::of_unit)
    }

    /// The coefficient's unit, the recording's output unit being `ou`.
    pub fn coefficient_unit(&self, ou: &str) -> String {
        let mut parts: Vec<String> = Vec::new();
        let g: u8 = self.powers.iter().sum::<u8>() + u8::from(self.abs.is_some());
        match g {
            0 => {}
            1 => parts.push("g".into()),
            n => parts.push(format!("g^{n}")),
        }
        for t in &self.timed {
            let u = t.unit();
            if !u.is_empty() {
                parts.push(u.to_string());
            }
        }
        match parts.len() {
            0 => ou.to_string(),
            1 => format!("{ou}/{}", parts[0]),
            _ => format!("{ou}/({})", parts.join("*")),
        }
    }

    /// The force part at specific force `a` (g).
    pub fn force(&self, a: [f64; 3]) -> f64 {
        match self.abs {
            Some(j) => a[j].abs(),
            None => (0..3).map(|j| a[j].powi(self.powers[j] as i32)).product(),
        }
    }

    /// The positions that would identify the force part where the recording's do not,
    /// in words (the same words for every term of one kind, so a report can group them).
    pub fn identifying_positions(&self) -> &'static str {
        let axes = (0..3)
            .filter(|&j| self.powers[j] > 0 || self.abs == Some(j))
            .count();
        let odd = self.powers.iter().any(|p| *p >= 3);
        match axes {
            0 => "a recording that varies it apart from the model's own terms",
            1 if odd => "positions with that component between -1 and +1 g, where its cube differs from itself (tilted, e.g. PP1..PP6)",
            1 => "positions with that component between 0 and 1 g (tilted, e.g. PP1..PP6)",
            _ => "positions with those components all nonzero (tilted between those axes: the 45-degree edge or corner positions of an 18- or 24-position design)",
        }
    }
}

impl fmt::Display for LibTerm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<String> = Vec::new();
        if let Some(j) = self.abs {
            parts.push(format!("abs(a_{})", AXES[j]));
        }
        for j in 0..3 {
            match self.powers[j] {
                0 => {}
                1 => parts.push(format!("a_{}", AXES[j])),
                p => parts.push(format!("a_{}^{p}", AXES[j])),
            }
        }
        parts.extend(self.timed.iter().map(ToString::to_string));
        f.write_str(&parts.join("*"))
    }
}

/// A candidate of the library: a term on one output axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The term.
    pub term: LibTerm,
    /// The output axis it enters.
    pub axis: usize,
}

impl fmt::Display for Candidate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} on {}", self.term, AXES[self.axis])
    }
}

/// The decays' time constants tried before refinement, s: from 10 s by a factor 2.5 to
/// about 2.7 h (the settling of a tilter move to a stop's soak).
pub const DECAY_GRID_S: [f64; 8] = [10.0, 25.0, 62.5, 156.0, 390.0, 977.0, 2441.0, 6104.0];

/// What a recording can judge of the time-varying factors: the specific force's terms
/// need only the positions, `dT` more than one temperature, the time and the events a
/// measured floor (a time series whose noise is known), `dTdt` a temperature that moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reach {
    /// More than one temperature.
    pub temperature: bool,
    /// The floor is measured: time and event terms can be judged.
    pub time: bool,
    /// The temperature moves (and the floor is measured): rate terms.
    pub rate: bool,
}

impl Reach {
    fn reaches(&self, f: &Timed) -> bool {
        match f {
            Timed::DT => self.temperature,
            Timed::Rate => self.rate,
            Timed::Hours | Timed::Decay(..) | Timed::Step(_) => self.time,
        }
    }
}

/// The force parts of the library: degree 2 and 3 monomials of the components and their
/// magnitudes, and (with a time-varying factor) the components themselves.
fn force_parts(with_timed: bool) -> Vec<([u8; 3], Option<usize>)> {
    let mut out = Vec::new();
    for p0 in 0..=3u8 {
        for p1 in 0..=3u8 {
            for p2 in 0..=3u8 {
                let d = p0 + p1 + p2;
                let keep = if with_timed {
                    (1..=2).contains(&d)
                } else {
                    (2..=3).contains(&d)
                };
                if keep {
                    out.push(([p0, p1, p2], None));
                }
            }
        }
    }
    out.extend((0..3).map(|j| ([0, 0, 0], Some(j))));
    out
}

/// The time-varying parts: one factor, or dT times another.
fn timed_parts(power_cycled: bool) -> Vec<Vec<Timed>> {
    let tau = DECAY_GRID_S[0];
    let mut one = vec![
        Timed::DT,
        Timed::Rate,
        Timed::Hours,
        Timed::Decay(Event::PowerOn, tau),
        Timed::Decay(Event::Stop, tau),
        Timed::Decay(Event::Position, tau),
    ];
    if power_cycled {
        one.push(Timed::Step(Event::PowerOn));
    }
    let mut out: Vec<Vec<Timed>> = one.iter().map(|t| vec![*t]).collect();
    out.extend(
        one.iter()
            .filter(|t| !matches!(t, Timed::DT))
            .map(|t| vec![Timed::DT, *t]),
    );
    out
}

/// Whether a catalogue effect or the baseline already expresses `term` on `axis`: the
/// baseline's offset and K row with their temperature polynomials (the offset's up to
/// `orders.offsets`, the K row's up to `orders.k`), `temp_rate` (dTdt alone),
/// `warmup_drift` (decay since power-on alone), `nonlinearity_k2` and
/// `scale_asymmetry` (a_i^2 and |a_i| on axis i).
fn catalogue_expresses(term: &LibTerm, axis: usize, orders: Orders) -> bool {
    let degree: u8 = term.powers.iter().sum();
    let only_dt = term.timed.iter().all(|t| matches!(t, Timed::DT));
    let dt_power = term.timed.len();
    let order = if degree == 0 {
        orders.offsets
    } else {
        orders.k
    };
    if term.abs.is_none() && degree <= 1 && only_dt && dt_power <= order {
        return true;
    }
    if term.abs.is_none() && degree == 0 {
        return matches!(
            term.timed.as_slice(),
            [Timed::Rate] | [Timed::Decay(Event::PowerOn, _)]
        );
    }
    if term.timed.is_empty() {
        let own_square = degree == 2 && term.powers[axis] == 2;
        return own_square || term.abs == Some(axis);
    }
    false
}

/// A term in time (a factor `t`) other than a scale drift `a_i*t` or the bare trend `t`:
/// left out of the library. On one pass through a test a trend in time cannot be told
/// from the arc of any slow disturbance (a cycle of many hours, a smooth step, a
/// wander): it fits each to the floor, so naming it would claim a form the data do not
/// show. A slow disturbance stays "unexplained, here", located in time.
fn in_time(t: &LibTerm) -> bool {
    t.timed.contains(&Timed::Hours) && !is_trend(t) && !is_scale_drift(t)
}

/// The bare trend `t` on an axis: in the library only as the rival of a scale drift,
/// never proposed ([`crate::diagnose::discover`]). A recording that rests most of its
/// time in one position turns a bias trend into a force factor times `t` (`a_z*t` at a
/// rest with a_z = 1); with `t` beside it in the selection, `a_i*t` is chosen only when
/// the drift turns with the force, its sign flipping between +i and -i, which a drifting
/// bias, or a slow disturbance's arc, does not.
pub fn is_trend(t: &LibTerm) -> bool {
    t.powers == [0; 3] && t.abs.is_none() && t.timed == [Timed::Hours]
}

/// A scale that drifts through the test, `a_i*t` (a force of degree one times `t`).
fn is_scale_drift(t: &LibTerm) -> bool {
    t.powers.iter().sum::<u8>() == 1 && t.abs.is_none() && t.timed == [Timed::Hours]
}

/// The library for `data`: every term of at most three factors no catalogue effect
/// expresses (given the baseline's temperature orders `orders`), on every axis, its
/// decays at the first point of [`DECAY_GRID_S`] (the search tries the grid).
pub fn library(data: &Data, orders: Orders, scope: Reach) -> Vec<Candidate> {
    let power_cycled = !data.rec.power_off.is_empty();
    let mut terms: Vec<LibTerm> = Vec::new();
    for (powers, abs) in force_parts(false) {
        terms.push(LibTerm {
            powers,
            abs,
            timed: Vec::new(),
        });
    }
    let timed = timed_parts(power_cycled);
    for t in &timed {
        terms.push(LibTerm {
            powers: [0; 3],
            abs: None,
            timed: t.clone(),
        });
    }
    for (powers, abs) in force_parts(true) {
        for t in &timed {
            let term = LibTerm {
                powers,
                abs,
                timed: t.clone(),
            };
            if term.factors() <= 3 {
                terms.push(term);
            }
        }
    }
    for t in &mut terms {
        t.timed.sort_by_key(Timed::rank);
    }
    terms.retain(|t| t.timed.iter().all(|f| scope.reaches(f)) && !in_time(t));
    let mut out = Vec::new();
    for term in terms {
        for axis in 0..3 {
            if !catalogue_expresses(&term, axis, orders) {
                out.push(Candidate {
                    term: term.clone(),
                    axis,
                });
            }
        }
    }
    out
}

/// The events of a recording and its clock, for the time-varying factors (each factor
/// computed per row when a term needs it).
pub struct Series {
    /// Per event, the event times in order (s).
    events: [Vec<f64>; 3],
    /// `t_s` per row.
    t: Vec<f64>,
}

/// When the unit came to rest at another position: the start of every dwell whose
/// position differs from the previous dwell's. The recording's first dwell is no move
/// (what happened before the recording is not seen), and a return to the same position
/// through rows in transit (a program that "moves" to where the unit already is) turns
/// nothing: the leads a move flexes were not flexed.
pub fn moves(rec: &Recording) -> Vec<f64> {
    let mut out = Vec::new();
    let mut last: Option<usize> = None;
    for d in &rec.dwells {
        let Some(row) = rec.rows.get(d.start) else {
            continue;
        };
        if last.is_some_and(|p| p != d.position) {
            out.push(row.t_s);
        }
        last = Some(d.position);
    }
    out
}

/// When each new temperature stop began: the end of the chamber's ramp to it, read off
/// the chamber's own reading (`chamber_c`). The ramp's middle half (a quarter to three
/// quarters of the way from the previous stop's level) gives its line; the line meets
/// the stop's level `t_x`, a chamber's own lag `tau_c` after the program's ramp ended.
/// For a chamber that follows its set point with one time constant, the reading at `t_x`
/// is `rate tau_c / e` short of the level, which gives `tau_c` and so the ramp's end
/// `t_x - tau_c`. A stop the recording starts at (no ramp seen) has no event. Without a
/// chamber column the sensor's own temperature lags too much to time the ramp's end, and
/// the stop's first static dwell is taken (the event then comes late by the soak, and a
/// settling is only fitted after it).
pub fn stop_arrivals(rec: &Recording) -> Vec<f64> {
    let stops = crate::data::stops::stops(rec, &|_| true, 3.0);
    let first_static = |s: &crate::data::stops::Stop| {
        s.dwells
            .first()
            .and_then(|&d| rec.dwells.get(d))
            .map(|d| d.start)
    };
    if rec.rows.iter().any(|r| r.chamber_c.is_none()) {
        return crate::model::data::stop_starts(rec);
    }
    let chamber = |i: usize| {
        rec.rows
            .get(i)
            .and_then(|r| r.chamber_c)
            .unwrap_or(f64::NAN)
    };
    let mut out = Vec::new();
    let mut prev_level = chamber(0);
    for s in &stops {
        let Some(anchor) = first_static(s) else {
            continue;
        };
        let mut at: Vec<f64> = s
            .dwells
            .iter()
            .filter_map(|&d| rec.dwells.get(d))
            .flat_map(|d| (d.start..d.end).map(chamber))
            .collect();
        at.sort_by(f64::total_cmp);
        let Some(&level) = at.get(at.len() / 2) else {
            continue;
        };
        let step = level - prev_level;
        prev_level = level;
        if let Some(t) = ramp_end(rec, anchor, level, step) {
            out.push(t);
        }
    }
    out
}

/// The end of the chamber's ramp of `step` C to `level` before row `anchor` (see
/// [`stop_arrivals`]); `None` where no ramp is seen.
fn ramp_end(rec: &Recording, anchor: usize, level: f64, step: f64) -> Option<f64> {
    // a stop closer than this to the one before is no ramp (the chamber's own wander)
    if step.abs() < 2.0 {
        return None;
    }
    let frac = |i: usize| {
        let c = rec.rows.get(i).and_then(|r| r.chamber_c)?;
        Some((c - (level - step)) / step)
    };
    let back = |from: usize, below: f64| {
        (0..from)
            .rev()
            .find(|&i| frac(i).is_some_and(|f| f <= below))
    };
    let hi = back(anchor, 0.75)?;
    let lo = back(hi, 0.25)?;
    let rows = rec.rows.get(lo..=hi)?;
    if rows.len() < 5 {
        return None;
    }
    // the ramp's line by least squares
    let n = rows.len() as f64;
    let mt = rows.iter().map(|r| r.t_s).sum::<f64>() / n;
    let mc = rows.iter().filter_map(|r| r.chamber_c).sum::<f64>() / n;
    let (mut stt, mut stc) = (0.0, 0.0);
    for r in rows {
        let dt = r.t_s - mt;
        stt += dt * dt;
        stc += dt * (r.chamber_c.unwrap_or(mc) - mc);
    }
    let rate = stc / stt;
    if rate.is_nan() || rate * step <= 0.0 {
        return None;
    }
    let t_x = mt + (level - mc) / rate;
    // the reading at t_x (the last row at or before it)
    let after = rec.rows.get(hi..anchor.max(hi))?;
    let c_x = after
        .iter()
        .take_while(|r| r.t_s <= t_x)
        .last()?
        .chamber_c?;
    let room = (t_x - rows.last()?.t_s).max(0.0);
    let tau_c = (std::f64::consts::E * (level - c_x) / rate).clamp(0.0, room);
    Some(t_x - tau_c)
}

/// The rate estimator's time constant for `dTdt` terms, s: the zero-lag estimator
/// (`firmware_core::inflight::Rate`) over half a minute, which smooths a quantised
/// sensor's steps on a chamber recording, held after the start only (the unit's physics;
/// see `regressors::rates`). Zero-lag, not the low-pass: a low-pass trails the rate by
/// its time constant where the case turns a ramp, and the fit took that into the term's
/// coefficient (the blind suite's scale-with-rate units, seeds 1-4, with a minute's
/// low-pass: +2.2 % and +2.7 % on two; zero-lag over 30 s: within 0.7 %, over 60 s
/// within 0.8 %, over 120 s off by up to 1.9 %:
/// the longer the estimator, the more of a turn it smears). The blob evaluates the term
/// with the flight's estimator (`model::flashed::FLIGHT_RATE_TAU_S`), which measures
/// the same rate faster; the coefficient is the unit's.
pub const RATE_TAU_S: f64 = 30.0;

impl Series {
    /// The events and clock of `data`'s recording.
    pub fn new(data: &Data) -> Series {
        let rec = data.rec;
        let t: Vec<f64> = rec.rows.iter().map(|r| r.t_s).collect();
        let t_first = t.first().copied().unwrap_or(0.0);
        let mut power: Vec<f64> = vec![t_first];
        power.extend(rec.power_off.iter().map(|s| s[1]));
        power.sort_by(f64::total_cmp);
        Series {
            events: [power, stop_arrivals(rec), moves(rec)],
            t,
        }
    }

    fn events(&self, e: Event) -> &[f64] {
        match e {
            Event::PowerOn => &self.events[0],
            Event::Stop => &self.events[1],
            Event::Position => &self.events[2],
        }
    }

    /// A time-varying factor per row.
    fn factor(&self, data: &Data, f: &Timed) -> Vec<f64> {
        match *f {
            Timed::DT => data.rec.rows.iter().map(|r| r.temp_c - data.t0).collect(),
            Timed::Rate => regressors::rates_of(data.rec, RATE_TAU_S, true, Settle::AfterStart)
                .into_iter()
                .map(|v| v * 60.0)
                .collect(),
            Timed::Hours => {
                let t0 = self.t.first().copied().unwrap_or(0.0);
                self.t.iter().map(|x| (x - t0) / 3600.0).collect()
            }
            // since power-on on the firmware's own clock, as the MCU will run it
            Timed::Decay(Event::PowerOn, tau) => regressors::warmup(data.rec, tau, &[]),
            Timed::Decay(e, tau) => {
                let ev = self.events(e);
                let mut k = 0usize;
                self.t
                    .iter()
                    .map(|&t| {
                        while k < ev.len() && ev[k] <= t {
                            k += 1;
                        }
                        match k.checked_sub(1).and_then(|i| ev.get(i)) {
                            Some(&at) => (-(t - at) / tau).exp(),
                            None => 0.0,
                        }
                    })
                    .collect()
            }
            Timed::Step(e) => {
                // from the first event after the recording's start on
                let ev = self.events(e);
                let first = ev.get(usize::from(e == Event::PowerOn)).copied();
                self.t
                    .iter()
                    .map(|&t| f64::from(first.is_some_and(|at| t >= at)))
                    .collect()
            }
        }
    }

    /// The window means of a term's time-varying part (1 when it has none).
    pub fn timed_means(&self, data: &Data, timed: &[Timed]) -> Vec<f64> {
        if timed.is_empty() {
            return vec![1.0; data.obs.len()];
        }
        let mut prod = self.factor(data, &timed[0]);
        for f in &timed[1..] {
            for (p, v) in prod.iter_mut().zip(self.factor(data, f)) {
                *p *= v;
            }
        }
        data.means(&prod)
    }
}

/// The column of a term on its axis: one value per window (the force part at the
/// window's position times the window mean of the time-varying part).
pub fn column(data: &Data, series: &Series, term: &LibTerm) -> Vec<f64> {
    let m = series.timed_means(data, &term.timed);
    data.obs
        .iter()
        .zip(m)
        .map(|(o, v)| term.force(o.a) * v)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn term(powers: [u8; 3], abs: Option<usize>, timed: Vec<Timed>) -> LibTerm {
        LibTerm { powers, abs, timed }
    }

    /// Two decays whose TAUs print alike (the text rounds to whole seconds, or minutes)
    /// are two columns to the search's cache; the same factor is one.
    #[test]
    fn a_factor_keys_by_its_value_not_its_text() {
        let [a, b, c] = [600.0, 600.4, 610.0].map(|t| Timed::Decay(Event::PowerOn, t));
        assert_eq!(a.to_string(), b.to_string());
        assert_ne!(a.key(), b.key());
        assert_ne!(a.key(), c.key());
        assert_eq!(a.key(), Timed::Decay(Event::PowerOn, 600.0).key());
        assert_ne!(a.key(), Timed::Decay(Event::Stop, 600.0).key());
        assert_ne!(
            Timed::Step(Event::Stop).key(),
            Timed::Step(Event::Position).key()
        );
        assert_ne!(Timed::DT.key(), Timed::Rate.key());
    }

    #[test]
    fn terms_are_written_in_the_catalogue_vocabulary() {
        let cases = [
            (term([1, 1, 0], None, vec![]), "a_x*a_y"),
            (term([3, 0, 0], None, vec![]), "a_x^3"),
            (term([0, 0, 2], None, vec![Timed::DT]), "a_z^2*dT"),
            (term([1, 0, 0], None, vec![Timed::Hours]), "a_x*t"),
            (term([0; 3], None, vec![Timed::Hours]), "t"),
            (
                term([0; 3], None, vec![Timed::Decay(Event::Position, 25.0)]),
                "decay(position,25s)",
            ),
            (
                term([0; 3], None, vec![Timed::Step(Event::PowerOn)]),
                "step(power_on)",
            ),
            (
                term(
                    [0; 3],
                    None,
                    vec![Timed::DT, Timed::Decay(Event::PowerOn, 1200.0)],
                ),
                "dT*decay(power_on,20min)",
            ),
            (term([0; 3], Some(1), vec![Timed::Rate]), "abs(a_y)*dTdt"),
        ];
        for (t, want) in cases {
            assert_eq!(t.to_string(), want);
        }
    }

    /// Every term the library can propose is one of the vocabulary's, at any time
    /// constant: its text is the canonical text of its report name, and the term a blob
    /// flashes keeps the fitted time constant to f32 (not the text's rounding).
    #[test]
    fn every_library_term_is_a_vocabulary_term_and_flashes_its_fitted_tau() {
        let mut terms: Vec<LibTerm> = force_parts(false)
            .into_iter()
            .map(|(powers, abs)| term(powers, abs, vec![]))
            .collect();
        for timed in timed_parts(true) {
            // as `library` makes them: at most three factors
            for (powers, abs) in force_parts(true) {
                terms.push(term(powers, abs, timed.clone()));
            }
            terms.push(term([0; 3], None, timed));
            terms.retain(|t| t.factors() <= 3);
        }
        // the grid, and between its points (a profiled time constant is anywhere)
        let taus: Vec<f64> = (0..=120)
            .map(|i| 10.0 * 2000.0_f64.powf(f64::from(i) / 120.0))
            .chain(DECAY_GRID_S)
            // whole minutes below 10 min, and either side of 10 min
            .chain([60.0, 420.0, 599.4, 599.6, 600.0, 630.0])
            .collect();
        let mut decays = 0;
        for t in &terms {
            let at: Vec<LibTerm> = match t.tau_s() {
                Some(_) => taus.iter().map(|&s| t.with_tau(s)).collect(),
                None => vec![t.clone()],
            };
            for t in at {
                let text = t.to_string();
                let named = t.named().unwrap_or_else(|e| panic!("{text}: {e}"));
                // one text: the library's, the named term's canonical one, read strictly
                assert_eq!(named.to_string(), text);
                assert_eq!(Ok(named.clone()), Term::parse_canonical(&text), "{text}");
                let flashed = t.term().unwrap_or_else(|e| panic!("{text}: {e}"));
                let tau = flashed.factors().iter().find_map(|f| {
                    if let Factor::Decay(_, tau) = f {
                        Some(tau.seconds())
                    } else {
                        None
                    }
                });
                assert_eq!(tau, t.tau_s().map(|s| s as f32), "{text}");
                decays += usize::from(tau.is_some());
                // the same term but for the time constant
                let same: Vec<_> = flashed
                    .factors()
                    .iter()
                    .zip(named.factors())
                    .filter(|(a, b)| {
                        a == b || matches!((a, b), (Factor::Decay(x, _), Factor::Decay(y, _)) if x == y)
                    })
                    .collect();
                assert_eq!(same.len(), named.factors().len(), "{text}");
                assert_eq!(flashed.factors().len(), named.factors().len(), "{text}");
            }
        }
        assert!(
            terms.len() > 100 && decays > 1000,
            "{} terms, {decays} decays",
            terms.len()
        );
    }

    /// A move is a dwell at another position than the one before: none at the
    /// recording's start, none where the unit comes back to where it was.
    #[test]
    fn a_move_is_a_change_of_position() {
        use crate::data::positions::Positions;
        let mut csv = String::from("t_s,position,temp_c,ux_v,uy_v,uz_v\n");
        let mut t = 0.0;
        for (name, n) in [
            ("TP1", 30),
            ("-", 5),
            ("TP1", 30),
            ("-", 5),
            ("TP2", 30),
            ("-", 5),
            ("PP1", 30),
        ] {
            for _ in 0..n {
                csv.push_str(&format!("{t:.1},{name},20.0,0.0,0.0,1.0\n"));
                t += 1.0;
            }
        }
        let rec = Recording::from_reader(
            std::path::Path::new("m.csv"),
            csv.as_bytes(),
            Positions::default(),
        )
        .unwrap();
        assert_eq!(rec.dwells.len(), 4, "{:?}", rec.dwells);
        assert_eq!(moves(&rec), vec![70.0, 105.0]);
    }

    /// A chamber that follows its program with one time constant (90 s): 300 s at
    /// +20 C, a ramp of 1 C/min to -20 C ending at 2700 s, a hold with dwells; the
    /// sensor lags the chamber by 60 s.
    fn ramp_recording(chamber: bool) -> Recording {
        ramp_recording_on(chamber, false)
    }

    /// [`ramp_recording`], on an even 1 Hz clock or unevenly: rows every 10 s while the
    /// unit rests through the ramp, each up to 0.3 s late, and a 2-min gap in the ramp.
    fn ramp_recording_on(chamber: bool, uneven: bool) -> Recording {
        use crate::data::positions::Positions;
        let mut csv = String::from(if chamber {
            "t_s,position,temp_c,chamber_c,ux_v,uy_v,uz_v\n"
        } else {
            "t_s,position,temp_c,ux_v,uy_v,uz_v\n"
        });
        let (mut c, mut s) = (20.0, 20.0);
        for k in 0..6000 {
            let t = k as f64;
            let set = if t < 300.0 {
                20.0
            } else {
                (20.0 - (t - 300.0) / 60.0).max(-20.0)
            };
            c += (set - c) / 90.0;
            s += (c - s) / 60.0;
            let pos = if t < 3600.0 || (t as i64 % 110) >= 100 {
                "-"
            } else if (t as i64 / 110) % 2 == 0 {
                "TP1"
            } else {
                "TP2"
            };
            let resting = t < 3600.0 || (t as i64 % 110) >= 100;
            if uneven && ((resting && k % 10 != 0) || (1500.0..1620.0).contains(&t)) {
                continue;
            }
            let t = if uneven {
                t + 0.3 * ((k * 7919) % 10) as f64 / 10.0
            } else {
                t
            };
            let ch = if chamber {
                format!("{c:.3},")
            } else {
                String::new()
            };
            csv.push_str(&format!("{t:.1},{pos},{s:.4},{ch}0.0,0.0,1.0\n"));
        }
        Recording::from_reader(
            std::path::Path::new("r.csv"),
            csv.as_bytes(),
            Positions::default(),
        )
        .unwrap()
    }

    /// The stop's event is the end of the chamber's ramp, read off its reading; without
    /// a chamber column, the stop's first static dwell.
    #[test]
    fn a_stop_begins_where_the_chamber_ramp_ends() {
        let rec = ramp_recording(true);
        let ev = stop_arrivals(&rec);
        assert_eq!(ev.len(), 1, "{ev:?}");
        assert!((ev[0] - 2700.0).abs() < 5.0, "{ev:?}");
        // the same on an uneven logger clock
        let ev = stop_arrivals(&ramp_recording_on(true, true));
        assert_eq!(ev.len(), 1, "{ev:?}");
        assert!((ev[0] - 2700.0).abs() < 10.0, "{ev:?}");
        let rec = ramp_recording(false);
        let first = rec.dwells.first().map(|d| rec.rows[d.start].t_s);
        assert_eq!(stop_arrivals(&rec).first().copied(), first);
        assert!(first.is_some_and(|t| t >= 3600.0));
    }

    #[test]
    fn units_follow_the_factors() {
        let t = term([2, 0, 0], None, vec![Timed::DT]);
        assert_eq!(t.coefficient_unit("V"), "V/(g^2*C)");
        let t = term([1, 0, 0], None, vec![Timed::Rate]);
        assert_eq!(t.coefficient_unit("V"), "V/(g*(C/min))");
        let t = term([0; 3], None, vec![Timed::Step(Event::PowerOn)]);
        assert_eq!(t.coefficient_unit("mV"), "mV");
        let t = term([1, 1, 0], None, vec![]);
        assert_eq!(t.coefficient_unit("V"), "V/g^2");
    }

    #[test]
    fn the_catalogue_keeps_its_own_terms() {
        let both = |n| Orders { k: n, offsets: n };
        // K2 and the asymmetry on their own axis, the baseline's temperature terms, the
        // rate and the warm-up alone are the catalogue's
        assert!(catalogue_expresses(
            &term([2, 0, 0], None, vec![]),
            0,
            both(3)
        ));
        assert!(!catalogue_expresses(
            &term([2, 0, 0], None, vec![]),
            1,
            both(3)
        ));
        assert!(catalogue_expresses(
            &term([0; 3], Some(2), vec![]),
            2,
            both(3)
        ));
        assert!(!catalogue_expresses(
            &term([0; 3], Some(2), vec![]),
            0,
            both(3)
        ));
        assert!(catalogue_expresses(
            &term([1, 0, 0], None, vec![Timed::DT]),
            1,
            both(1)
        ));
        assert!(!catalogue_expresses(
            &term([1, 0, 0], None, vec![Timed::DT, Timed::DT]),
            1,
            both(1)
        ));
        assert!(catalogue_expresses(
            &term([0; 3], None, vec![Timed::Rate]),
            0,
            both(3)
        ));
        assert!(catalogue_expresses(
            &term([0; 3], None, vec![Timed::Decay(Event::PowerOn, 60.0)]),
            0,
            both(3)
        ));
        assert!(!catalogue_expresses(
            &term([0; 3], None, vec![Timed::Decay(Event::Stop, 60.0)]),
            0,
            both(3)
        ));
        assert!(!catalogue_expresses(
            &term([1, 0, 0], None, vec![Timed::Rate]),
            0,
            both(3)
        ));
        // the offsets' own order: dT^2 alone is the offset's (order 2), a_x*dT^2 on x is
        // not the K row's (order 1)
        let split = Orders { k: 1, offsets: 2 };
        let dt2 = vec![Timed::DT, Timed::DT];
        assert!(catalogue_expresses(
            &term([0; 3], None, dt2.clone()),
            0,
            split
        ));
        assert!(!catalogue_expresses(
            &term([1, 0, 0], None, dt2.clone()),
            0,
            split
        ));
        assert!(!catalogue_expresses(
            &term([0; 3], None, dt2),
            0,
            Orders { k: 2, offsets: 1 }
        ));
    }

    /// Of the terms in time only a scale drift `a_i*t` and its rival, the bare trend
    /// `t`, are in the library (any other cannot be told from a slow disturbance's arc);
    /// the unit's states and the rig's events are.
    #[test]
    fn of_the_trends_in_time_only_a_scale_drift_and_its_rival_are_in() {
        assert!(!in_time(&term([0; 3], None, vec![Timed::Hours])));
        assert!(is_trend(&term([0; 3], None, vec![Timed::Hours])));
        assert!(!in_time(&term([1, 0, 0], None, vec![Timed::Hours])));
        assert!(!is_trend(&term([1, 0, 0], None, vec![Timed::Hours])));
        assert!(in_time(&term([0; 3], None, vec![Timed::DT, Timed::Hours])));
        assert!(in_time(&term([2, 0, 0], None, vec![Timed::Hours])));
        assert!(in_time(&term([0; 3], Some(0), vec![Timed::Hours])));
        assert!(in_time(&term(
            [1, 0, 0],
            None,
            vec![Timed::DT, Timed::Hours]
        )));
        assert!(!in_time(&term([0; 3], None, vec![Timed::DT])));
        assert!(!in_time(&term(
            [1, 0, 0],
            None,
            vec![Timed::Decay(Event::Position, 25.0)]
        )));
    }

    #[test]
    fn only_the_units_own_state_is_compensated_on_the_mcu() {
        assert!(term([1, 1, 0], None, vec![]).of_unit());
        assert!(term(
            [0; 3],
            None,
            vec![Timed::DT, Timed::Decay(Event::PowerOn, 60.0)]
        )
        .of_unit());
        assert!(!term([1, 0, 0], None, vec![Timed::Hours]).of_unit());
        assert!(!term([0; 3], None, vec![Timed::Decay(Event::Position, 25.0)]).of_unit());
        assert!(!term([0; 3], None, vec![Timed::Step(Event::PowerOn)]).of_unit());
    }
}
