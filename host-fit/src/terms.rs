//! The whole vocabulary of discovered terms (physics-catalogue.md, "Beyond the catalogue:
//! discovered terms") as types: parsed from text (an error says what is wrong), printed in
//! the canonical form, evaluated, and turned into the table a blob carries.
//!
//! The terms of the unit's state (force factors, `dT`, `dTdt`, `decay(power_on,TAU)`) are
//! `firmware_core::terms`'s: the MCU compensates them and this module prints them with
//! that module's names and TAU text, so a report, a record store and the firmware read
//! one term the same way. The rest of the vocabulary describes the rig or the recording's
//! time: `t` (hours since the recording's first row), `step(EVENT)` and
//! `decay(stop|position,TAU)`. Such a term corrects the calibration on the host (like
//! `fixture_error`) and is never flashed: [`AxisTerm::unit_entry`] refuses it.
//!
//! Canonical order: `a_x`, `abs(a_x)`, `a_y`, `abs(a_y)`, `a_z`, `abs(a_z)`, `dT`, `dTdt`,
//! `t`, then the event factors: the decays (by event: power_on, stop, position; then by
//! TAU), then the steps (by event). A repeated factor is a power (`a_x^3`); `*` between
//! factors. Parsing accepts any order, spaces, `^1` and `abs(a_x)^2` (rewritten `a_x^2`)
//! and normalises; [`Term::parse_canonical`] accepts only the canonical text.
pub use firmware_core::terms::Tau;
use firmware_core::terms::{
    self as unit, decay_weight, Axis, TermEntry, TermList, UnitState, MAX_FACTORS, MAX_TERMS,
};
use std::fmt;
use std::str::FromStr;

/// An event of a recording a term can follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Event {
    /// The start of the recording, and the end of every power-off it states
    /// (`power_off_s`).
    PowerOn,
    /// A new temperature stop begins.
    Stop,
    /// The unit was turned to another position.
    Position,
}

impl Event {
    /// Every event, in canonical order.
    pub const ALL: [Event; 3] = [Event::PowerOn, Event::Stop, Event::Position];

    /// As the vocabulary writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Event::PowerOn => "power_on",
            Event::Stop => "stop",
            Event::Position => "position",
        }
    }

    /// The event of a name.
    pub fn from_name(name: &str) -> Option<Event> {
        Event::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The index into [`Values::events`].
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// One factor of the vocabulary; the variants' order is the canonical order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Factor {
    /// `a_x`, g.
    Ax,
    /// `abs(a_x)`.
    AbsAx,
    /// `a_y`, g.
    Ay,
    /// `abs(a_y)`.
    AbsAy,
    /// `a_z`, g.
    Az,
    /// `abs(a_z)`.
    AbsAz,
    /// `dT`: temp_c - T0, C.
    DT,
    /// `dTdt`: the rate of temp_c, C/min.
    DTdt,
    /// `t`: hours since the recording's first row.
    Hours,
    /// `decay(EVENT,TAU)`: `exp(-(t - t_EVENT)/TAU)` after the latest EVENT, 0 before the
    /// first.
    Decay(Event, Tau),
    /// `step(EVENT)`: 1 from the first EVENT after the recording's start on, 0 before.
    Step(Event),
}

impl Factor {
    /// The factor of the unit's state it is, with its TAU (`None`: a factor of the rig or
    /// the recording's time).
    pub fn unit(self) -> Option<(unit::Factor, Option<Tau>)> {
        Some(match self {
            Factor::Ax => (unit::Factor::Ax, None),
            Factor::AbsAx => (unit::Factor::AbsAx, None),
            Factor::Ay => (unit::Factor::Ay, None),
            Factor::AbsAy => (unit::Factor::AbsAy, None),
            Factor::Az => (unit::Factor::Az, None),
            Factor::AbsAz => (unit::Factor::AbsAz, None),
            Factor::DT => (unit::Factor::DT, None),
            Factor::DTdt => (unit::Factor::DTdt, None),
            Factor::Decay(Event::PowerOn, tau) => (unit::Factor::DecayPowerOn, Some(tau)),
            Factor::Hours | Factor::Decay(Event::Stop | Event::Position, _) | Factor::Step(_) => {
                return None
            }
        })
    }

    /// The host's factor of a unit factor (`tau`: a decay's).
    pub fn of_unit(f: unit::Factor, tau: Option<Tau>) -> Option<Factor> {
        Some(match f {
            unit::Factor::Ax => Factor::Ax,
            unit::Factor::AbsAx => Factor::AbsAx,
            unit::Factor::Ay => Factor::Ay,
            unit::Factor::AbsAy => Factor::AbsAy,
            unit::Factor::Az => Factor::Az,
            unit::Factor::AbsAz => Factor::AbsAz,
            unit::Factor::DT => Factor::DT,
            unit::Factor::DTdt => Factor::DTdt,
            unit::Factor::DecayPowerOn => Factor::Decay(Event::PowerOn, tau?),
        })
    }

    /// The plain square of a magnitude factor (`abs(a_x)` -> `a_x`).
    fn plain(self) -> Option<Factor> {
        match self {
            Factor::AbsAx => Some(Factor::Ax),
            Factor::AbsAy => Some(Factor::Ay),
            Factor::AbsAz => Some(Factor::Az),
            Factor::Ax
            | Factor::Ay
            | Factor::Az
            | Factor::DT
            | Factor::DTdt
            | Factor::Hours
            | Factor::Decay(..)
            | Factor::Step(_) => None,
        }
    }

    /// The value in `v` (a decay or step before its first event: 0).
    pub fn value(self, v: &Values) -> f64 {
        let [x, y, z] = v.a;
        match self {
            Factor::Ax => x,
            Factor::AbsAx => x.abs(),
            Factor::Ay => y,
            Factor::AbsAy => y.abs(),
            Factor::Az => z,
            Factor::AbsAz => z.abs(),
            Factor::DT => v.dt_c,
            Factor::DTdt => v.dtdt_c_per_min,
            Factor::Hours => v.hours,
            Factor::Decay(e, tau) => v.events[e.index()]
                .since_s
                .map_or(0.0, |s| decay_weight(s, f64::from(tau.seconds()))),
            Factor::Step(e) => f64::from(u8::from(v.events[e.index()].after_start)),
        }
    }
}

impl fmt::Display for Factor {
    /// The unit's factors by firmware-core's names, the others as the catalogue writes
    /// them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Factor::Hours => f.write_str("t"),
            Factor::Decay(e, tau) => write!(f, "decay({},{tau})", e.name()),
            Factor::Step(e) => write!(f, "step({})", e.name()),
            Factor::Ax
            | Factor::AbsAx
            | Factor::Ay
            | Factor::AbsAy
            | Factor::Az
            | Factor::AbsAz
            | Factor::DT
            | Factor::DTdt => {
                let (u, _) = self.unit().ok_or(fmt::Error)?;
                f.write_str(u.name())
            }
        }
    }
}

/// The clock of one event at a row: the time since its latest occurrence (the recording's
/// start counts for power_on), and whether one occurred after the recording's start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventClock {
    /// Seconds since the latest occurrence; `None` before the first.
    pub since_s: Option<f64>,
    /// Whether the event occurred after the recording's start (what `step` follows).
    pub after_start: bool,
}

/// What a term is evaluated at, for one row of a recording.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Values {
    /// The specific force, g.
    pub a: [f64; 3],
    /// temp_c - T0, C.
    pub dt_c: f64,
    /// The rate of temp_c, C/min.
    pub dtdt_c_per_min: f64,
    /// Hours since the recording's first row.
    pub hours: f64,
    /// The events' clocks, by [`Event::index`].
    pub events: [EventClock; 3],
}

/// What kind of term it is, so where it acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A term of the unit's state: compensated on the MCU (the blob's term table).
    Unit,
    /// A term of the rig or of the recording's time: corrects the calibration on the host.
    Rig,
}

/// A term: one to three factors in canonical order. Made only by [`Term::new`] and the
/// parsers, so every value is canonical and equal terms compare equal.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Term {
    factors: heapless::Vec<Factor, MAX_FACTORS>,
}

/// Why a text or a list of factors is no term of the vocabulary.
#[non_exhaustive]
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TermErrorKind {
    /// No factor at all.
    Empty,
    /// A factor the vocabulary does not have.
    UnknownFactor(String),
    /// An event the vocabulary does not have.
    UnknownEvent(String),
    /// A power that is not a whole number from 1 on.
    BadPower(String),
    /// A power of a decay or a step (another decay, or the step itself).
    PowerOfEvent(String),
    /// A decay's TAU without its unit, not positive, or out of range.
    BadTau(String),
    /// More than three factors (a power counts its multiplicity).
    TooManyFactors(usize),
    /// A step twice, or two decays of one event.
    RepeatedEvent(String),
    /// Not the canonical text (strict parsing): what it is.
    NotCanonical(String),
    /// A term of the rig or the recording's time where a term of the unit's state is
    /// needed (a blob's table).
    NotFlashable,
    /// A table of more than [`MAX_TERMS`] terms, or a term twice on one axis, or a
    /// non-finite coefficient (a blob's table).
    Table(String),
}

/// A term refused, with the text (or the term) it was about.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TermError {
    /// The term's text as given.
    pub term: String,
    /// What is wrong.
    pub kind: TermErrorKind,
}

/// The vocabulary's factors, for an error's hint.
const FACTORS: &str = "a_x, a_y, a_z, abs(a_x), abs(a_y), abs(a_z), dT, dTdt, t, decay(EVENT,TAU), step(EVENT) with EVENT power_on, stop or position";

impl fmt::Display for TermError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = &self.term;
        match &self.kind {
            TermErrorKind::Empty => write!(f, "term `{t}`: no factor (a term is a product of 1 to 3 of: {FACTORS})"),
            TermErrorKind::UnknownFactor(x) => write!(f, "term `{t}`: unknown factor `{x}` (the vocabulary's factors: {FACTORS})"),
            TermErrorKind::UnknownEvent(x) => write!(f, "term `{t}`: unknown event `{x}` (events: power_on, stop, position)"),
            TermErrorKind::BadPower(x) => write!(f, "term `{t}`: power `^{x}` is not a whole number from 1 on (`a_x^3`)"),
            TermErrorKind::PowerOfEvent(x) => write!(f, "term `{t}`: `{x}` takes no power (a power of a decay is a decay with a shorter TAU, a step's power is the step)"),
            TermErrorKind::BadTau(x) => write!(f, "term `{t}`: TAU `{x}` is not a positive time with its unit (`25s`, `12min`, `2h`)"),
            TermErrorKind::TooManyFactors(n) => write!(f, "term `{t}`: {n} factors (a power counts its multiplicity); a term has at most {MAX_FACTORS}"),
            TermErrorKind::RepeatedEvent(x) => write!(f, "term `{t}`: `{x}` twice (a step times itself is the step; two decays of one event are one decay, TAU = ab/(a+b))"),
            TermErrorKind::NotCanonical(c) => write!(f, "term `{t}` is not in canonical form: write `{c}`"),
            TermErrorKind::NotFlashable => write!(f, "term `{t}` is a term of the rig or of the recording's time (`t`, `step`, `decay(stop|position,...)`): it corrects the calibration on the host and is never flashed"),
            TermErrorKind::Table(why) => write!(f, "term `{t}`: {why}"),
        }
    }
}

impl std::error::Error for TermError {}

fn err(term: &str, kind: TermErrorKind) -> TermError {
    TermError {
        term: term.to_string(),
        kind,
    }
}

impl Term {
    /// The term of `factors` in any order: `abs(a_i)` twice becomes `a_i^2`. Refused: none
    /// or more than three factors, a step twice, two decays of one event.
    pub fn new(factors: impl IntoIterator<Item = Factor>) -> Result<Term, TermError> {
        let mut f: Vec<Factor> = factors.into_iter().collect();
        let shown = |f: &[Factor]| {
            f.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("*")
        };
        if f.is_empty() {
            return Err(err("", TermErrorKind::Empty));
        }
        if f.len() > MAX_FACTORS {
            return Err(err(&shown(&f), TermErrorKind::TooManyFactors(f.len())));
        }
        // abs(a_i)^2 = a_i^2
        for abs in [Factor::AbsAx, Factor::AbsAy, Factor::AbsAz] {
            let plain = abs.plain();
            let at: Vec<usize> = (0..f.len()).filter(|&i| f[i] == abs).collect();
            for &i in at.iter().take(at.len() / 2 * 2) {
                f[i] = plain.unwrap_or(abs);
            }
        }
        f.sort();
        for w in f.windows(2) {
            let same_event = match (w[0], w[1]) {
                (Factor::Step(a), Factor::Step(b)) => a == b,
                (Factor::Decay(a, _), Factor::Decay(b, _)) => a == b,
                _ => false,
            };
            if same_event {
                return Err(err(
                    &shown(&f),
                    TermErrorKind::RepeatedEvent(w[1].to_string()),
                ));
            }
        }
        Ok(Term {
            factors: f.into_iter().collect(),
        })
    }

    /// The factors, in canonical order.
    pub fn factors(&self) -> &[Factor] {
        &self.factors
    }

    /// Where the term acts.
    pub fn kind(&self) -> Kind {
        if self.factors.iter().all(|f| f.unit().is_some()) {
            Kind::Unit
        } else {
            Kind::Rig
        }
    }

    /// The term of the unit's state it is (firmware-core's, for a blob's table); `None`
    /// for a term of the rig or the recording's time.
    pub fn unit(&self) -> Option<unit::Term> {
        let mut factors: heapless::Vec<unit::Factor, MAX_FACTORS> = heapless::Vec::new();
        let mut tau = None;
        for f in &self.factors {
            let (u, t) = f.unit()?;
            factors.push(u).ok()?;
            tau = tau.or(t);
        }
        unit::Term::new(&factors, tau).ok()
    }

    /// The text read strictly: the canonical form only (an error names the canonical
    /// text of a term written otherwise).
    pub fn parse_canonical(text: &str) -> Result<Term, TermError> {
        let t: Term = text.parse()?;
        let canonical = t.to_string();
        if canonical != text {
            return Err(err(text, TermErrorKind::NotCanonical(canonical)));
        }
        Ok(t)
    }

    /// The value in `v`: a term of the unit's state as the firmware evaluates it (its
    /// state part times its force part), any other the product of its factors.
    pub fn value(&self, v: &Values) -> f64 {
        if let Some(u) = self.unit() {
            let s = UnitState {
                dt_c: v.dt_c,
                dtdt_c_per_min: v.dtdt_c_per_min,
                since_power_on_s: v.events[Event::PowerOn.index()].since_s.unwrap_or(0.0),
            };
            return u.state(&s) * u.force(v.a);
        }
        self.factors.iter().map(|f| f.value(v)).product()
    }
}

impl From<unit::Term> for Term {
    fn from(u: unit::Term) -> Term {
        Term {
            factors: u
                .factors()
                .filter_map(|f| Factor::of_unit(f, u.tau()))
                .collect(),
        }
    }
}

impl fmt::Display for Term {
    /// The canonical text.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut i = 0;
        while i < self.factors.len() {
            let x = self.factors[i];
            let run = self.factors[i..].iter().take_while(|y| **y == x).count();
            if i > 0 {
                f.write_str("*")?;
            }
            write!(f, "{x}")?;
            if run > 1 {
                write!(f, "^{run}")?;
            }
            i += run;
        }
        Ok(())
    }
}

impl FromStr for Term {
    type Err = TermError;

    /// Any order, spaces around factors, powers; normalised to the canonical term.
    fn from_str(text: &str) -> Result<Term, TermError> {
        let e = |kind| err(text, kind);
        if text.trim().is_empty() {
            return Err(e(TermErrorKind::Empty));
        }
        let mut factors = Vec::new();
        for piece in text.split('*').map(str::trim) {
            let (base, power) = split_power(piece).map_err(e)?;
            let f = parse_factor(base).map_err(e)?;
            if power > 1 && matches!(f, Factor::Decay(..) | Factor::Step(_)) {
                return Err(e(TermErrorKind::PowerOfEvent(base.to_string())));
            }
            if factors.len() + power > MAX_FACTORS {
                let n = factors.len() + power;
                return Err(e(TermErrorKind::TooManyFactors(n)));
            }
            factors.extend(std::iter::repeat_n(f, power));
        }
        Term::new(factors).map_err(|x| err(text, x.kind))
    }
}

/// `a_x^3` -> (`a_x`, 3); no power: 1.
fn split_power(piece: &str) -> Result<(&str, usize), TermErrorKind> {
    match piece.rsplit_once('^') {
        None => Ok((piece, 1)),
        Some((base, k)) => {
            let k = k.trim();
            match k.parse::<usize>() {
                Ok(n) if n >= 1 && k.bytes().all(|b| b.is_ascii_digit()) => Ok((base.trim(), n)),
                _ => Err(TermErrorKind::BadPower(k.to_string())),
            }
        }
    }
}

/// One factor's text.
fn parse_factor(text: &str) -> Result<Factor, TermErrorKind> {
    let simple = [
        ("a_x", Factor::Ax),
        ("abs(a_x)", Factor::AbsAx),
        ("a_y", Factor::Ay),
        ("abs(a_y)", Factor::AbsAy),
        ("a_z", Factor::Az),
        ("abs(a_z)", Factor::AbsAz),
        ("dT", Factor::DT),
        ("dTdt", Factor::DTdt),
        ("t", Factor::Hours),
    ];
    if let Some((_, f)) = simple.iter().find(|(n, _)| *n == text) {
        return Ok(*f);
    }
    let event = |name: &str| {
        let name = name.trim();
        Event::from_name(name).ok_or_else(|| TermErrorKind::UnknownEvent(name.to_string()))
    };
    if let Some(inner) = text
        .strip_prefix("decay(")
        .and_then(|r| r.strip_suffix(')'))
    {
        let (ev, tau) = inner
            .split_once(',')
            .ok_or_else(|| TermErrorKind::BadTau(String::new()))?;
        return Ok(Factor::Decay(event(ev)?, parse_tau(tau.trim())?));
    }
    if let Some(inner) = text.strip_prefix("step(").and_then(|r| r.strip_suffix(')')) {
        return Ok(Factor::Step(event(inner)?));
    }
    Err(TermErrorKind::UnknownFactor(text.to_string()))
}

/// `25s`, `2.5s`, `12min`, `2h` as a [`Tau`]. Seconds and minutes are read as f32 (the
/// canonical text reads back as the very same value); hours are converted in f64.
pub fn parse_tau(text: &str) -> Result<Tau, TermErrorKind> {
    let bad = || TermErrorKind::BadTau(text.to_string());
    let seconds = if let Some(m) = text.strip_suffix("min") {
        m.trim().parse::<f32>().map_err(|_| bad())? * 60.0
    } else if let Some(h) = text.strip_suffix('h') {
        (h.trim().parse::<f64>().map_err(|_| bad())? * 3600.0) as f32
    } else if let Some(s) = text.strip_suffix('s') {
        s.trim().parse::<f32>().map_err(|_| bad())?
    } else {
        return Err(bad());
    };
    Tau::from_seconds(seconds).ok_or_else(bad)
}

impl serde::Serialize for Term {
    /// As its canonical text.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> serde::Deserialize<'de> for Term {
    /// From any text the vocabulary parses (normalised to the canonical term); a text
    /// that is no term is refused with the parser's reason.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Term, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// A term on one axis with its coefficient (output units per the term's units): what a
/// `discovered` finding flashes.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisTerm {
    /// The term.
    pub term: Term,
    /// The axis whose output it enters additively.
    pub axis: Axis,
    /// Its coefficient.
    pub coefficient: f64,
}

impl AxisTerm {
    /// The entry of a blob's term table; refused for a term of the rig or the recording's
    /// time.
    pub fn unit_entry(&self) -> Result<TermEntry<f64>, TermError> {
        let term = self
            .term
            .unit()
            .ok_or_else(|| err(&self.term.to_string(), TermErrorKind::NotFlashable))?;
        Ok(TermEntry {
            axis: self.axis,
            term,
            coefficient: self.coefficient,
        })
    }

    /// The host's form of a blob's entry.
    pub fn of_entry<R: firmware_core::Real>(e: &TermEntry<R>) -> AxisTerm {
        AxisTerm {
            term: Term::from(e.term),
            axis: e.axis,
            coefficient: e.coefficient.to_f64(),
        }
    }
}

/// A blob's term table of `terms`: each a term of the unit's state, at most
/// [`MAX_TERMS`], none twice on one axis, finite coefficients.
pub fn unit_table(terms: &[AxisTerm]) -> Result<TermList<f64>, TermError> {
    let table_err = |t: &AxisTerm, why: String| err(&t.term.to_string(), TermErrorKind::Table(why));
    if let Some(t) = terms.get(MAX_TERMS) {
        return Err(table_err(
            t,
            format!(
                "{} terms; a blob's table holds at most {MAX_TERMS} (firmware_core::terms::MAX_TERMS)",
                terms.len()
            ),
        ));
    }
    let mut out = TermList::new();
    for (i, t) in terms.iter().enumerate() {
        if !t.coefficient.is_finite() {
            return Err(table_err(
                t,
                format!("coefficient {} is not finite", t.coefficient),
            ));
        }
        if terms[..i]
            .iter()
            .any(|p| p.axis == t.axis && p.term == t.term)
        {
            return Err(table_err(
                t,
                format!("twice on axis {} (add the coefficients)", t.axis.name()),
            ));
        }
        out.push(t.unit_entry()?)
            .map_err(|_| table_err(t, "table full".into()))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn p(s: &str) -> Term {
        s.parse().unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_catalogue_examples_read_and_print_as_written() {
        for s in [
            "a_x*a_y",
            "a_x^3",
            "a_z^2*dT",
            "a_x*t",
            "t",
            "decay(position,25s)",
            "step(power_on)",
            "dT*decay(power_on,20min)",
            "a_x*abs(a_x)",
            "dTdt*t*step(stop)",
            "decay(power_on,90s)*decay(stop,2.5s)*step(position)",
        ] {
            assert_eq!(
                Term::parse_canonical(s).map(|t| t.to_string()),
                Ok(s.into())
            );
        }
    }

    #[test]
    fn other_spellings_are_normalised() {
        assert_eq!(p("a_y * a_x").to_string(), "a_x*a_y");
        assert_eq!(p("dT*a_z*a_z").to_string(), "a_z^2*dT");
        assert_eq!(p("abs(a_x)^2").to_string(), "a_x^2");
        assert_eq!(p("a_x^1*dT").to_string(), "a_x*dT");
        assert_eq!(
            p("decay(power_on,1200s)").to_string(),
            "decay(power_on,20min)"
        );
        assert_eq!(
            p("decay(power_on,0.5h)").to_string(),
            "decay(power_on,30min)"
        );
        assert_eq!(
            p("step(stop)*decay(position,10s)").to_string(),
            "decay(position,10s)*step(stop)"
        );
        assert_eq!(
            Term::parse_canonical("dT*a_x").unwrap_err().to_string(),
            "term `dT*a_x` is not in canonical form: write `a_x*dT`"
        );
    }

    #[test]
    fn errors_say_what_is_wrong() {
        let kind = |s: &str| s.parse::<Term>().unwrap_err().kind;
        assert_eq!(kind(""), TermErrorKind::Empty);
        assert_eq!(kind("a_w"), TermErrorKind::UnknownFactor("a_w".into()));
        assert_eq!(kind("a_x^0"), TermErrorKind::BadPower("0".into()));
        assert_eq!(kind("a_x^-1"), TermErrorKind::BadPower("-1".into()));
        assert_eq!(kind("a_x^4"), TermErrorKind::TooManyFactors(4));
        assert_eq!(kind("a_x*a_y*a_z*dT"), TermErrorKind::TooManyFactors(4));
        assert_eq!(
            kind("step(boot)"),
            TermErrorKind::UnknownEvent("boot".into())
        );
        assert_eq!(kind("decay(stop,12)"), TermErrorKind::BadTau("12".into()));
        assert_eq!(kind("decay(stop,-5s)"), TermErrorKind::BadTau("-5s".into()));
        assert_eq!(
            kind("decay(stop,0min)"),
            TermErrorKind::BadTau("0min".into())
        );
        assert_eq!(kind("decay(stop)"), TermErrorKind::BadTau(String::new()));
        assert_eq!(
            kind("step(stop)^2"),
            TermErrorKind::PowerOfEvent("step(stop)".into())
        );
        assert_eq!(
            kind("step(stop)*step(stop)"),
            TermErrorKind::RepeatedEvent("step(stop)".into())
        );
        assert_eq!(
            kind("decay(stop,1s)*decay(stop,2s)"),
            TermErrorKind::RepeatedEvent("decay(stop,2s)".into())
        );
        let msg = "a_x*foo".parse::<Term>().unwrap_err().to_string();
        assert!(
            msg.starts_with("term `a_x*foo`: unknown factor `foo` (the vocabulary's factors: a_x,"),
            "{msg}"
        );
    }

    #[test]
    fn unit_terms_are_firmware_core_terms_with_the_same_text() {
        use unit::Factor as U;
        let u = unit::Term::new(&[U::DT, U::DecayPowerOn], Tau::from_seconds(1200.0)).unwrap();
        let h = Term::from(u);
        assert_eq!(h.to_string(), u.to_string());
        assert_eq!(h.unit(), Some(u));
        assert_eq!(h.kind(), Kind::Unit);
        for rig in [
            "a_x*t",
            "step(power_on)",
            "decay(stop,5min)",
            "decay(position,25s)*a_z",
        ] {
            assert_eq!(p(rig).kind(), Kind::Rig, "{rig}");
            assert_eq!(p(rig).unit(), None);
        }
        let flash = AxisTerm {
            term: p("a_x*t"),
            axis: Axis::Y,
            coefficient: 1e-4,
        };
        assert_eq!(
            flash.unit_entry().unwrap_err().kind,
            TermErrorKind::NotFlashable
        );
    }

    #[test]
    fn values_follow_the_definitions() {
        let mut v = Values {
            a: [0.5, -0.5, 0.7],
            dt_c: 10.0,
            dtdt_c_per_min: 2.0,
            hours: 1.5,
            ..Values::default()
        };
        assert_eq!(p("a_x*abs(a_y)*t").value(&v), 0.5 * 0.5 * 1.5);
        assert_eq!(p("decay(stop,10s)").value(&v), 0.0, "before the first stop");
        assert_eq!(p("step(stop)").value(&v), 0.0);
        v.events[Event::Stop.index()] = EventClock {
            since_s: Some(10.0),
            after_start: true,
        };
        assert!((p("decay(stop,10s)*t").value(&v) - 1.5 * (-1.0f64).exp()).abs() < 1e-15);
        assert_eq!(p("step(stop)*dT").value(&v), 10.0);
        v.events[Event::PowerOn.index()].since_s = Some(60.0);
        assert!((p("dT*decay(power_on,1min)").value(&v) - 10.0 * (-1.0f64).exp()).abs() < 1e-14);
    }

    #[test]
    fn a_table_refuses_what_the_blob_cannot_hold() {
        let t = |s: &str, axis, c| AxisTerm {
            term: p(s),
            axis,
            coefficient: c,
        };
        assert_eq!(unit_table(&[t("a_x*a_y", Axis::Z, 1e-4)]).unwrap().len(), 1);
        let dup = unit_table(&[t("a_x*a_y", Axis::Z, 1e-4), t("a_y*a_x", Axis::Z, 1e-4)]);
        assert!(matches!(dup.unwrap_err().kind, TermErrorKind::Table(w) if w.contains("twice")));
        let nine: Vec<AxisTerm> = (0..9).map(|_| t("a_x", Axis::X, 1.0)).collect();
        assert!(
            matches!(unit_table(&nine).unwrap_err().kind, TermErrorKind::Table(w) if w.contains("at most 8"))
        );
        assert!(unit_table(&[t("a_x", Axis::X, f64::NAN)]).is_err());
        assert_eq!(
            unit_table(&[t("t", Axis::X, 1.0)]).unwrap_err().kind,
            TermErrorKind::NotFlashable
        );
    }

    fn any_factor() -> impl Strategy<Value = Factor> {
        let event = prop::sample::select(Event::ALL.to_vec());
        let tau = prop_oneof![
            (1u32..600).prop_map(|m| m as f32 * 60.0),
            (0.01f32..1e6),
            (1u32..100_000).prop_map(|s| s as f32),
        ]
        .prop_map(|s| Tau::from_seconds(s).unwrap());
        prop_oneof![
            prop::sample::select(vec![
                Factor::Ax,
                Factor::AbsAx,
                Factor::Ay,
                Factor::AbsAy,
                Factor::Az,
                Factor::AbsAz,
                Factor::DT,
                Factor::DTdt,
                Factor::Hours,
            ]),
            (event.clone(), tau).prop_map(|(e, t)| Factor::Decay(e, t)),
            event.prop_map(Factor::Step),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// parse(print(x)) == x, the printed text is canonical, and a unit term prints as
        /// firmware-core prints it.
        #[test]
        fn print_then_parse_is_identity(f in prop::collection::vec(any_factor(), 1..=3)) {
            if let Ok(t) = Term::new(f.clone()) {
                let text = t.to_string();
                prop_assert_eq!(Term::parse_canonical(&text), Ok(t.clone()));
                // any order of the same factors is the same term
                let mut rev = f.clone();
                rev.reverse();
                prop_assert_eq!(Term::new(rev), Ok(t.clone()));
                if let Some(u) = t.unit() {
                    prop_assert_eq!(u.to_string(), text);
                    prop_assert_eq!(Term::from(u), t);
                }
            }
        }
    }
}
