//! Discovered terms of the unit's state (physics-catalogue.md, "Beyond the catalogue:
//! discovered terms"): the vocabulary's MCU subset as types, its canonical text, and the
//! terms' evaluation, written once for the firmware (f32) and the host (f64).
//!
//! # The MCU subset of the vocabulary
//! A term is a product of one to three [`Factor`]s (`a_x^3` is three): the specific-force
//! components `a_x`, `a_y`, `a_z` (g) and their magnitudes `abs(a_i)`, `dT` (the sensor
//! temperature minus T0, C), `dTdt` (its rate, C/min) and `decay(power_on,TAU)`
//! (`exp(-t_on / TAU)`, `t_on` the time since the unit's latest power-on). A term enters
//! the output of one axis additively, `U_i += c * term` ([`TermEntry`]). The rest of the
//! vocabulary (`t`, `step(EVENT)`, `decay(stop|position,TAU)`) describes the rig or the
//! recording's time, corrects the calibration on the host (host-fit's `terms` module) and
//! is never flashed.
//!
//! # Canonical form
//! The factors in the order of their codes: `a_x`, `abs(a_x)`, `a_y`, `abs(a_y)`, `a_z`,
//! `abs(a_z)`, `dT`, `dTdt`, `decay(power_on,TAU)` (force factors first, x, y, z, then
//! `dT`, `dTdt`, then the event factor, as the catalogue writes them); a repeated factor
//! written as a power (`a_x^3`), factors joined by `*`. `abs(a_i)` appears at most once
//! per axis (`abs(a_x)^2` is `a_x^2`; [`Term::new`] rewrites it so) and there is at most
//! one decay (two decays of one event are one decay). TAU is written in whole minutes
//! when it is a whole number of minutes (`20min`), else in seconds (`25s`).
//!
//! # Evaluation, and its error bounds
//! A term's value is its state part times its force part
//! ([`Term::state`] x [`Term::force`], each the product of its factors in canonical
//! order; a missing factor is an exact 1). The compensator evaluates the state part,
//! times the coefficient, when its temperature machines step (every 0.1 s, on the unit's
//! clock: [`crate::inflight`]), and the force part at every sample at the estimated
//! specific force, so the host's f64 evaluation of [`TermEntry::contribution`] is the
//! very same arithmetic. In f32:
//! - [`Term::force`]: at most two roundings, so within `2 eps |F|` of the exact product
//!   of its (f32) inputs ([`FORCE_F32_REL_BOUND`]);
//! - [`decay_weight`]: `exp(-t_on/TAU)` within [`DECAY_F32_BOUND`] (absolute) of the f64
//!   value for the same `t_on` and TAU (one division and [`crate::exp::expm1_neg_f32`]);
//!   `t_on` itself is summed step by step with a compensation term
//!   ([`crate::inflight::Elapsed`]), within `2 eps t_on` of the sum of the steps;
//! - [`Term::state`]: the product of at most three factors, so within `2 eps` of the
//!   product of its inputs, plus the decay's bound times the other factors.
//!
//! Held by the tests `force_and_state_f32_follow_f64` here and the property tests of
//! `tests/terms.rs` (the whole compensation with terms, f32 against f64).
use crate::error::Error;
use crate::model::Vec3;
use crate::real::Real;
use core::fmt;

/// The most terms a blob carries. Each costs 4 bytes of compensator state (its state
/// part times its coefficient, kept between the machines' steps), 12 bytes of flash and
/// about 25 instructions per sample; a sparse model of one unit keeps a few terms per
/// axis (more would fit the recording, not the unit), and 8 keeps the compensator within
/// its 256-byte state with room for all three axes.
pub const MAX_TERMS: usize = 8;
/// The most factors of one term (`a_x^3` is three).
pub const MAX_FACTORS: usize = 3;
/// Relative error bound of [`Term::force`] in f32: two roundings (`2 eps`, eps = 2^-24)
/// of the exact product of its f32 inputs.
pub const FORCE_F32_REL_BOUND: f64 = 2.0 * 5.960_464_477_539_063e-8;
/// Absolute error bound of [`decay_weight`] in f32 against f64, for the same `t_on` and
/// TAU: the division's rounding (relative `eps`, worth at most `eps / e` on the weight),
/// [`crate::exp::EXPM1_NEG_F32_BOUND`] and the final addition's half ulp of 1.
pub const DECAY_F32_BOUND: f64 = 4.0e-7;

/// The axis whose output a term enters.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// x.
    X = 0,
    /// y.
    Y = 1,
    /// z.
    Z = 2,
}

impl Axis {
    /// The three axes, in the order of the model's vectors.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// The index into the model's vectors (0, 1, 2), also the axis's code in a blob.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The axis of a blob's code; `None` for a code above 2.
    pub const fn from_code(code: u8) -> Option<Axis> {
        match code {
            0 => Some(Axis::X),
            1 => Some(Axis::Y),
            2 => Some(Axis::Z),
            _ => None,
        }
    }

    /// `x`, `y` or `z`, as a finding's `"axes"` writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }
}

/// One factor of a term of the unit's state; its discriminant is its code in a blob's
/// term table (0 is no factor), and the order of the codes is the canonical order.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Factor {
    /// `a_x`: the specific force along x, g.
    Ax = 1,
    /// `abs(a_x)`.
    AbsAx = 2,
    /// `a_y`, g.
    Ay = 3,
    /// `abs(a_y)`.
    AbsAy = 4,
    /// `a_z`, g.
    Az = 5,
    /// `abs(a_z)`.
    AbsAz = 6,
    /// `dT`: the sensor temperature minus T0, C.
    DT = 7,
    /// `dTdt`: the rate of the sensor temperature, C/min (the firmware's rate estimate:
    /// the physics section's rate estimator, [`crate::inflight::Rate`], zero-lag when
    /// its `rate_tau_s` is negative).
    DTdt = 8,
    /// `decay(power_on,TAU)`: `exp(-t_on / TAU)`, `t_on` the time since power-on; TAU is
    /// the term's ([`Term::tau`]).
    DecayPowerOn = 9,
}

/// The number of slots of the factor value tables: a code masked to 4 bits indexes them
/// without a bounds check (slots 10..16, no factor's, hold NaN, so a bug would show).
pub const SLOTS: usize = 16;
/// The mask of a code into the value tables.
const SLOT_MASK: u8 = 15;

impl Factor {
    /// Every factor, in canonical order.
    pub const ALL: [Factor; 9] = [
        Factor::Ax,
        Factor::AbsAx,
        Factor::Ay,
        Factor::AbsAy,
        Factor::Az,
        Factor::AbsAz,
        Factor::DT,
        Factor::DTdt,
        Factor::DecayPowerOn,
    ];

    /// The factor's code in a blob (1..=9).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The factor of a code; `None` for 0 (no factor) and codes above 9.
    pub const fn from_code(code: u8) -> Option<Factor> {
        Some(match code {
            1 => Factor::Ax,
            2 => Factor::AbsAx,
            3 => Factor::Ay,
            4 => Factor::AbsAy,
            5 => Factor::Az,
            6 => Factor::AbsAz,
            7 => Factor::DT,
            8 => Factor::DTdt,
            9 => Factor::DecayPowerOn,
            _ => return None,
        })
    }

    /// A factor of the specific force (evaluated at every sample).
    pub const fn is_force(self) -> bool {
        (self as u8) <= (Factor::AbsAz as u8)
    }

    /// The axis of a force factor.
    pub const fn axis(self) -> Option<Axis> {
        match self {
            Factor::Ax | Factor::AbsAx => Some(Axis::X),
            Factor::Ay | Factor::AbsAy => Some(Axis::Y),
            Factor::Az | Factor::AbsAz => Some(Axis::Z),
            Factor::DT | Factor::DTdt | Factor::DecayPowerOn => None,
        }
    }

    /// The factor as the vocabulary writes it (`a_x`, `abs(a_y)`, `dT`, `dTdt`);
    /// `decay(power_on,TAU)` without its TAU, as `decay(power_on)`.
    pub const fn name(self) -> &'static str {
        match self {
            Factor::Ax => "a_x",
            Factor::AbsAx => "abs(a_x)",
            Factor::Ay => "a_y",
            Factor::AbsAy => "abs(a_y)",
            Factor::Az => "a_z",
            Factor::AbsAz => "abs(a_z)",
            Factor::DT => "dT",
            Factor::DTdt => "dTdt",
            Factor::DecayPowerOn => "decay(power_on)",
        }
    }
}

/// A decay's time constant TAU, s: positive and finite (so it is ordered and hashed by
/// its bits).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tau(f32);

impl Tau {
    /// TAU of `s` seconds; `None` unless positive and finite.
    pub fn from_seconds(s: f32) -> Option<Tau> {
        (s > 0.0 && s.is_finite()).then_some(Tau(s))
    }

    /// The time constant, s.
    pub fn seconds(self) -> f32 {
        self.0
    }

    /// Whole minutes, when TAU is a whole number of minutes (the canonical text's unit).
    pub fn whole_minutes(self) -> Option<f32> {
        let m = self.0 / 60.0;
        (m >= 1.0 && libm::truncf(m) == m && m * 60.0 == self.0).then_some(m)
    }
}

impl Eq for Tau {}

impl PartialOrd for Tau {
    fn partial_cmp(&self, other: &Self) -> Option<core::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Tau {
    fn cmp(&self, other: &Self) -> core::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

impl core::hash::Hash for Tau {
    fn hash<H: core::hash::Hasher>(&self, state: &mut H) {
        self.0.to_bits().hash(state);
    }
}

impl fmt::Display for Tau {
    /// `20min` for a whole number of minutes, else `25s` / `2.5s` (the shortest text
    /// that reads back as the same f32).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.whole_minutes() {
            Some(m) => write!(f, "{m}min"),
            None => write!(f, "{}s", self.0),
        }
    }
}

/// A term of the unit's state: one to three factors in canonical order, and the TAU of
/// its decay when it has one. Made only by [`Term::new`] or [`Term::from_codes`], so
/// every value is canonical and two equal terms compare equal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Term {
    /// Canonical order, `None` after the last factor.
    factors: [Option<Factor>; MAX_FACTORS],
    tau: Option<Tau>,
}

impl Term {
    /// The term of `factors` (any order; `abs(a_i)` twice is rewritten `a_i^2`), with the
    /// time constant of its decay. Refused: no factor or more than three
    /// ([`Error::TermFactors`]), two decays (also `TermFactors`), a decay without a TAU or
    /// a TAU without a decay ([`Error::TermTimeConstant`]).
    pub fn new(factors: &[Factor], tau: Option<Tau>) -> Result<Term, Error> {
        if factors.is_empty() || factors.len() > MAX_FACTORS {
            return Err(Error::TermFactors);
        }
        let mut f = [None; MAX_FACTORS];
        for (slot, x) in f.iter_mut().zip(factors) {
            *slot = Some(*x);
        }
        // abs(a_i)^2 = a_i^2: a pair of the same magnitude becomes the plain square
        for (plain, abs) in [
            (Factor::Ax, Factor::AbsAx),
            (Factor::Ay, Factor::AbsAy),
            (Factor::Az, Factor::AbsAz),
        ] {
            if f.iter().filter(|x| **x == Some(abs)).count() >= 2 {
                let mut left = 2;
                for x in f.iter_mut() {
                    if *x == Some(abs) && left > 0 {
                        *x = Some(plain);
                        left -= 1;
                    }
                }
            }
        }
        sort3(&mut f);
        let codes = f.map(|x| x.map_or(0, Factor::code));
        Term::from_codes(codes, tau.map_or(0.0, Tau::seconds))
    }

    /// The term of a blob entry's three factor codes (canonical: ascending, zeros after
    /// the last factor) and its decay's TAU, s (0 when it has no decay). Refused as
    /// [`Term::new`] refuses, and a code that is no factor or out of canonical order
    /// ([`Error::TermFactors`]).
    pub fn from_codes(codes: [u8; MAX_FACTORS], tau_s: f32) -> Result<Term, Error> {
        check_codes(codes, tau_s)?;
        let factors = codes.map(Factor::from_code);
        let tau = Tau::from_seconds(tau_s);
        Ok(Term { factors, tau })
    }

    /// The factors, in canonical order.
    pub fn factors(&self) -> impl Iterator<Item = Factor> + '_ {
        self.factors.iter().flatten().copied()
    }

    /// The factor codes as a blob stores them (zeros after the last factor).
    pub fn codes(&self) -> [u8; MAX_FACTORS] {
        self.factors.map(|f| f.map_or(0, Factor::code))
    }

    /// The decay's time constant, if the term has a decay.
    pub fn tau(&self) -> Option<Tau> {
        self.tau
    }

    /// The decay's time constant as a blob stores it, s (0: no decay).
    pub fn tau_s(&self) -> f32 {
        self.tau.map_or(0.0, Tau::seconds)
    }

    /// The number of factors (a power counts its multiplicity).
    pub fn degree(&self) -> usize {
        self.factors().count()
    }

    /// Whether any factor is of the specific force (evaluated at every sample).
    pub fn has_force(&self) -> bool {
        self.factors().any(Factor::is_force)
    }

    /// The product of the force factors at specific force `a` (g), 1 when there are
    /// none: [`force_values`] at the term's codes, in canonical order.
    #[inline]
    pub fn force<R: Real>(&self, a: Vec3<R>) -> R {
        product(&force_values(a), self.codes())
    }

    /// The product of the state factors in state `s` ([`state_values`] at the term's
    /// codes), 1 when there are none.
    #[inline]
    pub fn state<R: Real>(&self, s: &UnitState<R>) -> R {
        product(&state_values(s, self.tau_s()), self.codes())
    }
}

/// The rules of a canonical term on a blob entry's codes and TAU, checked where the entry
/// lies (no term built: the firmware's validation): at least one factor, the codes known
/// (1..=9) and ascending, zeros only after the last factor ([`Error::TermFactors`]);
/// `abs(a_i)` (the even codes 2, 4, 6) and the decay (9) at most once, so never equal to
/// their neighbour (also `TermFactors`); a decay's TAU positive and finite, 0 without a
/// decay, and that 0 is +0.0, whose bits are all zero, so the entry has one encoding
/// ([`Error::TermTimeConstant`]).
#[inline]
pub fn check_codes(codes: [u8; MAX_FACTORS], tau_s: f32) -> Result<(), Error> {
    let [a, b, c] = codes;
    let last = Factor::DecayPowerOn.code();
    let ordered = a != 0 && (b == 0 || b >= a) && (c == 0 || (b != 0 && c >= b)) && c <= last;
    let known = a <= last && b <= last;
    let once = |x: u8| x == last || (x & 1 == 0 && x <= Factor::AbsAz.code());
    let twice = |x: u8, y: u8| x != 0 && x == y && once(x);
    if !ordered || !known || twice(a, b) || twice(b, c) {
        return Err(Error::TermFactors);
    }
    let decay = a == last || b == last || c == last;
    let tau_ok = if decay {
        tau_s > 0.0 && tau_s.is_finite()
    } else {
        // -0.0 == 0.0, but its sign bit would re-encode as +0.0: not canonical
        tau_s.to_bits() == 0
    };
    if !tau_ok {
        return Err(Error::TermTimeConstant);
    }
    Ok(())
}

/// Sort three optional factors ascending, `None` last (a three-element network: fixed
/// work).
fn sort3(f: &mut [Option<Factor>; MAX_FACTORS]) {
    let key = |x: Option<Factor>| x.map_or(u8::MAX, Factor::code);
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if let (Some(&a), Some(&b)) = (f.get(i), f.get(j)) {
            if key(a) > key(b) {
                f.swap(i, j);
            }
        }
    }
}

impl fmt::Display for Term {
    /// The canonical text: `a_x*a_y`, `a_x^3`, `a_z^2*dT`, `dT*decay(power_on,20min)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        let mut i = 0;
        while let Some(Some(x)) = self.factors.get(i) {
            let run = self
                .factors
                .get(i..)
                .unwrap_or(&[])
                .iter()
                .take_while(|y| **y == Some(*x))
                .count()
                .max(1);
            if !first {
                f.write_str("*")?;
            }
            first = false;
            match (x, self.tau) {
                (Factor::DecayPowerOn, Some(t)) => write!(f, "decay(power_on,{t})")?,
                _ => f.write_str(x.name())?,
            }
            if run > 1 {
                write!(f, "^{run}")?;
            }
            i += run;
        }
        Ok(())
    }
}

/// What a term's state factors are evaluated at: the unit's state as of the temperature
/// machines' last step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnitState<R> {
    /// `dT`: the sensor temperature minus T0, C.
    pub dt_c: R,
    /// `dTdt`: the rate of the sensor temperature, C/min.
    pub dtdt_c_per_min: R,
    /// The time since the latest power-on, s.
    pub since_power_on_s: R,
}

/// `exp(-t_on / tau_s)`, the weight of `decay(power_on,TAU)` `t_on` seconds after
/// power-on: `1 + expm1(-t_on/TAU)` (exactly 0 from 17 time constants on in f32); 1 for
/// `t_on <= 0`. Error bound in f32: [`DECAY_F32_BOUND`].
#[inline]
pub fn decay_weight<R: Real>(since_power_on_s: R, tau_s: R) -> R {
    R::ONE + (since_power_on_s / tau_s).expm1_neg()
}

/// The force factors' values at specific force `a`, by code (code 0 and the state
/// factors' codes hold an exact 1).
#[inline]
pub fn force_values<R: Real>(a: Vec3<R>) -> [R; SLOTS] {
    let [x, y, z] = a;
    let (one, nan) = (R::ONE, R::NAN);
    [
        one,
        x,
        x.abs(),
        y,
        y.abs(),
        z,
        z.abs(),
        one,
        one,
        one,
        nan,
        nan,
        nan,
        nan,
        nan,
        nan,
    ]
}

/// The state factors' values in state `s`, the decay's with time constant `tau_s` (s; 0:
/// no decay), by code (code 0 and the force factors' codes hold an exact 1).
#[inline]
pub fn state_values<R: Real>(s: &UnitState<R>, tau_s: f32) -> [R; SLOTS] {
    let (one, nan) = (R::ONE, R::NAN);
    let mut v = [
        one,
        one,
        one,
        one,
        one,
        one,
        one,
        s.dt_c,
        s.dtdt_c_per_min,
        one,
        nan,
        nan,
        nan,
        nan,
        nan,
        nan,
    ];
    set_decay(&mut v, s, tau_s);
    v
}

/// Set the decay's slot of a state table to the weight for time constant `tau_s` (s; 0:
/// no decay, an exact 1): the one slot that differs from term to term.
#[inline]
pub fn set_decay<R: Real>(v: &mut [R; SLOTS], s: &UnitState<R>, tau_s: f32) {
    let w = if tau_s > 0.0 {
        decay_weight(s.since_power_on_s, R::from_f32(tau_s))
    } else {
        R::ONE
    };
    if let Some(slot) = v.get_mut(usize::from(Factor::DecayPowerOn.code())) {
        *slot = w;
    }
}

/// The product of the values at three codes, in order (a code that is no factor's reads
/// as NaN: never for a validated term).
#[inline]
pub fn product<R: Real>(values: &[R; SLOTS], codes: [u8; MAX_FACTORS]) -> R {
    let v = |c: u8| {
        values
            .get(usize::from(c & SLOT_MASK))
            .copied()
            .unwrap_or(R::NAN)
    };
    let [c0, c1, c2] = codes;
    v(c0) * v(c1) * v(c2)
}

/// One discovered term on one axis: `U_axis += coefficient * term`, the coefficient in
/// output units per the term's units (per g^k of its force factors, per C of `dT`, per
/// C/min of `dTdt`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TermEntry<R> {
    /// The axis whose output the term enters.
    pub axis: Axis,
    /// The term.
    pub term: Term,
    /// Its coefficient.
    pub coefficient: R,
}

impl<R: Real> TermEntry<R> {
    /// The coefficient times the term's state part: what the compensator keeps between
    /// the machines' steps.
    #[inline]
    pub fn weight(&self, s: &UnitState<R>) -> R {
        self.coefficient * self.term.state(s)
    }

    /// The entry's contribution to its axis's output at specific force `a` in state `s`:
    /// `(coefficient * state) * force`, the compensator's own association.
    #[inline]
    pub fn contribution(&self, a: Vec3<R>, s: &UnitState<R>) -> R {
        self.weight(s) * self.term.force(a)
    }

    /// Convert the coefficient to another float type (f64 -> f32 rounds to nearest).
    pub fn convert<S: Real>(&self) -> TermEntry<S> {
        TermEntry {
            axis: self.axis,
            term: self.term,
            coefficient: S::from_f64(self.coefficient.to_f64()),
        }
    }
}

/// A term-table entry as stored: a blob's bytes read where they lie, or an owned entry's
/// codes; [`RawTerm::entry`] checks it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawTerm<R> {
    /// The axis's code (0, 1, 2).
    pub axis: u8,
    /// The factor codes, canonical ([`Term::codes`]).
    pub codes: [u8; MAX_FACTORS],
    /// The decay's time constant, s (0: no decay).
    pub tau_s: f32,
    /// The coefficient.
    pub coefficient: R,
}

impl<R: Real> RawTerm<R> {
    /// No entry (out of a table's range): no axis, no factor, a NaN coefficient.
    pub fn none() -> Self {
        RawTerm {
            axis: u8::MAX,
            codes: [0; MAX_FACTORS],
            tau_s: 0.0,
            coefficient: R::NAN,
        }
    }

    /// The typed entry. Refused, in this order: an axis code above 2
    /// ([`Error::TermAxis`]), factors or a TAU that are no canonical term
    /// ([`Term::from_codes`]), a coefficient that is not finite ([`Error::NonFinite`]).
    pub fn entry(&self) -> Result<TermEntry<R>, Error> {
        let axis = Axis::from_code(self.axis).ok_or(Error::TermAxis)?;
        let term = Term::from_codes(self.codes, self.tau_s)?;
        if !self.coefficient.is_finite() {
            return Err(Error::NonFinite);
        }
        Ok(TermEntry {
            axis,
            term,
            coefficient: self.coefficient,
        })
    }
}

impl<R: Real> TermEntry<R> {
    /// As a table stores it.
    #[inline]
    pub fn raw(&self) -> RawTerm<R> {
        RawTerm {
            axis: self.axis as u8,
            codes: self.term.codes(),
            tau_s: self.term.tau_s(),
            coefficient: self.coefficient,
        }
    }
}

/// The checks a list of entries passes (a blob's table, an owned list): at most
/// [`MAX_TERMS`] ([`Error::TooManyTerms`]), finite coefficients ([`Error::NonFinite`]),
/// no term twice on one axis ([`Error::DuplicateTerm`]). Each entry's term is canonical
/// by construction.
pub fn validate_entries<R: Real>(entries: &[TermEntry<R>]) -> Result<(), Error> {
    if entries.len() > MAX_TERMS {
        return Err(Error::TooManyTerms);
    }
    if !entries.iter().all(|e| e.coefficient.is_finite()) {
        return Err(Error::NonFinite);
    }
    for (i, e) in entries.iter().enumerate() {
        let later = entries.get(i.saturating_add(1)..).unwrap_or(&[]);
        if later.iter().any(|l| l.axis == e.axis && l.term == e.term) {
            return Err(Error::DuplicateTerm);
        }
    }
    Ok(())
}

/// The terms of a calibration: at most [`MAX_TERMS`] entries.
pub type TermList<R> = heapless::Vec<TermEntry<R>, MAX_TERMS>;

#[cfg(test)]
mod tests {
    use super::*;

    fn term(f: &[Factor], tau: Option<f32>) -> Term {
        Term::new(f, tau.and_then(Tau::from_seconds)).unwrap()
    }

    #[test]
    fn the_catalogue_examples_print_canonically() {
        use Factor::*;
        assert_eq!(term(&[Ay, Ax], None).to_string(), "a_x*a_y");
        assert_eq!(term(&[Ax, Ax, Ax], None).to_string(), "a_x^3");
        assert_eq!(term(&[DT, Az, Az], None).to_string(), "a_z^2*dT");
        assert_eq!(
            term(&[DecayPowerOn, DT], Some(1200.0)).to_string(),
            "dT*decay(power_on,20min)"
        );
        assert_eq!(
            term(&[DecayPowerOn], Some(25.0)).to_string(),
            "decay(power_on,25s)"
        );
        assert_eq!(
            term(&[DecayPowerOn], Some(90.0)).to_string(),
            "decay(power_on,90s)"
        );
        assert_eq!(
            term(&[DecayPowerOn], Some(2.5)).to_string(),
            "decay(power_on,2.5s)"
        );
        assert_eq!(term(&[AbsAz, Ax], None).to_string(), "a_x*abs(a_z)");
        assert_eq!(term(&[AbsAx, Ax], None).to_string(), "a_x*abs(a_x)");
        assert_eq!(term(&[DTdt, DTdt], None).to_string(), "dTdt^2");
        // abs(a_x)^2 is a_x^2; abs(a_x)^3 is a_x^2*abs(a_x)
        assert_eq!(term(&[AbsAx, AbsAx], None), term(&[Ax, Ax], None));
        assert_eq!(
            term(&[AbsAx, AbsAx, AbsAx], None).to_string(),
            "a_x^2*abs(a_x)"
        );
    }

    #[test]
    fn refusals_name_the_kind() {
        use Factor::*;
        let t = Tau::from_seconds(60.0);
        assert_eq!(Term::new(&[], None), Err(Error::TermFactors));
        assert_eq!(Term::new(&[Ax; 4], None), Err(Error::TermFactors));
        assert_eq!(
            Term::new(&[DecayPowerOn, DecayPowerOn], t),
            Err(Error::TermFactors)
        );
        assert_eq!(
            Term::new(&[DecayPowerOn], None),
            Err(Error::TermTimeConstant)
        );
        assert_eq!(Term::new(&[Ax], t), Err(Error::TermTimeConstant));
        assert_eq!(Tau::from_seconds(0.0), None);
        assert_eq!(Tau::from_seconds(f32::INFINITY), None);
        assert_eq!(Tau::from_seconds(f32::NAN), None);
        // codes: out of order, a gap, unknown, none, abs twice
        for codes in [[3, 1, 0], [1, 0, 3], [10, 0, 0], [0, 0, 0], [2, 2, 0]] {
            assert_eq!(
                Term::from_codes(codes, 0.0),
                Err(Error::TermFactors),
                "{codes:?}"
            );
        }
        assert_eq!(
            Term::from_codes([9, 0, 0], -1.0),
            Err(Error::TermTimeConstant)
        );
        assert_eq!(
            Term::from_codes([9, 0, 0], f32::NAN),
            Err(Error::TermTimeConstant)
        );
        // a fuzz find: -0.0 passed `== 0.0` and re-encoded as +0.0
        assert_eq!(
            Term::from_codes([1, 0, 0], -0.0),
            Err(Error::TermTimeConstant)
        );
        assert_eq!(
            Term::from_codes([1, 0, 0], 5.0),
            Err(Error::TermTimeConstant)
        );
        assert!(Term::from_codes([1, 1, 7], 0.0).is_ok());
    }

    #[test]
    fn every_term_round_trips_through_its_codes() {
        // every multiset of up to three factors that is canonical
        let mut n = 0;
        for a in 0..=9u8 {
            for b in 0..=9u8 {
                for c in 0..=9u8 {
                    let has_decay = [a, b, c].contains(&9);
                    let tau = if has_decay { 300.0 } else { 0.0 };
                    if let Ok(t) = Term::from_codes([a, b, c], tau) {
                        n += 1;
                        assert_eq!(t.codes(), [a, b, c]);
                        let f: heapless::Vec<Factor, 3> = t.factors().collect();
                        assert_eq!(Term::new(&f, t.tau()), Ok(t));
                        assert_eq!(t.degree(), f.len());
                    }
                }
            }
        }
        // 9 + 42 + (multisets of 3 of 9 minus those with abs twice or decay twice)
        assert!(n > 150, "{n} terms");
    }

    #[test]
    fn values_are_the_products_of_the_factors() {
        use Factor::*;
        let a = [0.5f64, -0.25, 2.0];
        let s = UnitState {
            dt_c: -10.0,
            dtdt_c_per_min: 3.0,
            since_power_on_s: 600.0,
        };
        let t = term(&[Ax, Ay, AbsAy], None);
        assert_eq!(t.force(a), 0.5 * -0.25 * 0.25);
        assert_eq!(t.state(&s), 1.0);
        let d = term(&[DT, DecayPowerOn, Az], Some(1200.0));
        assert_eq!(d.force(a), 2.0);
        assert!((d.state(&s) - (-10.0 * (-0.5f64).exp())).abs() < 1e-14);
        let e = TermEntry {
            axis: Axis::Y,
            term: d,
            coefficient: 1e-3,
        };
        assert!((e.contribution(a, &s) - 1e-3 * -10.0 * (-0.5f64).exp() * 2.0).abs() < 1e-16);
        assert_eq!(decay_weight(0.0f64, 10.0), 1.0);
        assert_eq!(decay_weight(1e4f32, 10.0), 0.0);
        assert_eq!(term(&[DTdt], None).state(&s), 3.0);
    }

    /// The f32 evaluation against f64 at the same f32 inputs, on a grid: the force part
    /// within FORCE_F32_REL_BOUND of itself, the decay within DECAY_F32_BOUND.
    #[test]
    fn force_and_state_f32_follow_f64() {
        use Factor::*;
        let terms = [
            term(&[Ax, Ay, Az], None),
            term(&[Ax, Ax, Ax], None),
            term(&[AbsAx, Ay, Ay], None),
        ];
        let mut worst_force: f64 = 0.0;
        for i in 0..200 {
            let a32 = [
                (i as f32 * 0.0137).sin() * 1.9,
                (i as f32 * 0.091).cos(),
                -0.7 + i as f32 * 0.007,
            ];
            let a64 = a32.map(f64::from);
            for t in &terms {
                let (f32v, f64v) = (f64::from(t.force(a32)), t.force(a64));
                if f64v != 0.0 {
                    worst_force = worst_force.max(((f32v - f64v) / f64v).abs());
                }
            }
        }
        assert!(worst_force <= FORCE_F32_REL_BOUND, "{worst_force:e}");
        let mut worst_decay: f64 = 0.0;
        for tau in [1.0f32, 25.0, 600.0, 3600.0, 86_400.0] {
            for k in 0..4000 {
                let t_on = k as f32 * 0.37 * tau / 100.0;
                let w32 = f64::from(decay_weight(t_on, tau));
                let w64 = decay_weight(f64::from(t_on), f64::from(tau));
                worst_decay = worst_decay.max((w32 - w64).abs());
            }
        }
        assert!(worst_decay <= DECAY_F32_BOUND, "{worst_decay:e}");
    }

    #[test]
    fn entries_are_checked_as_a_list() {
        let t = term(&[Factor::Ax, Factor::Ay], None);
        let e = |axis, c: f64| TermEntry {
            axis,
            term: t,
            coefficient: c,
        };
        assert_eq!(
            validate_entries(&[e(Axis::X, 1.0), e(Axis::Y, 1.0)]),
            Ok(())
        );
        assert_eq!(
            validate_entries(&[e(Axis::X, 1.0), e(Axis::X, 2.0)]),
            Err(Error::DuplicateTerm)
        );
        assert_eq!(
            validate_entries(&[e(Axis::X, f64::NAN)]),
            Err(Error::NonFinite)
        );
        assert_eq!(
            validate_entries(&[e(Axis::X, 1.0); MAX_TERMS + 1]),
            Err(Error::TooManyTerms)
        );
        assert_eq!(Axis::from_code(3), None);
        assert_eq!(
            Axis::ALL.map(|a| Axis::from_code(a as u8)),
            Axis::ALL.map(Some)
        );
        for f in Factor::ALL {
            assert_eq!(Factor::from_code(f.code()), Some(f));
        }
        assert_eq!(Factor::from_code(0), None);
        assert_eq!(Factor::from_code(10), None);
    }
}
