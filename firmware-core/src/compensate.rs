//! Real-time compensation of every sample by method 1 or method 2 (model.md section 6).
//!
//! Per sample the work is fixed: a finiteness check, one 3x3 product (method 1) or two
//! (method 2), and the range flags. The temperature-dependent matrices are cached and
//! recomputed only when the temperature has moved by more than the blob's update step.
//!
//! The compensator is told its sample period when it is made (fixed-rate sampling:
//! [`Compensator::compensate`]); [`Compensator::compensate_dt`] takes each sample's own
//! time step instead (a temperature read at its own rate, a logger with gaps). Only the
//! physics terms and the discovered terms use the time (their state machines,
//! [`crate::inflight`]).
//!
//! # Discovered terms
//! A blob's term table ([`crate::terms`]) takes the physics path: each term's state part
//! (its `dT`, `dTdt` and `decay(power_on,TAU)` factors, from the machines: the sensor
//! temperature, the rate and the time since power-on at their last step) times its
//! coefficient is kept when the machines step; at every sample its force part is
//! evaluated at the estimated specific force and the sum on each axis removed after the
//! inversion, as the K2 and scale-asymmetry terms are: `a = a_hat - N e(a_hat)` with `N`
//! the inverse in use (N(T) for method 1, N(T0) for method 2). The error of that first-
//! order correction is second order in the terms: `|a - a_true| <= |N|^2 L |e|`, `L` the
//! Lipschitz constant of `e` in `a` (held by `tests/terms.rs`). The work per sample is
//! fixed by the table's size (at most [`crate::terms::MAX_TERMS`]): no other loop.
//!
//! # Error bound against f64
//! The f32 path stays within `F32_BOUND_G` (2e-6 g, [`crate::model`]) of the f64 path
//! of the same code for the tables alone; with discovered terms the terms' f32 error adds
//! at most [`TERMS_F32_BOUND_G`] for terms of the catalogue's sizes (held by
//! `tests/terms.rs` at 10 Hz, 100 Hz and 1 kHz).
use crate::error::Error;
#[cfg(feature = "physics")]
use crate::inflight::{Machines, Tick};
use crate::model::{
    add3, all_finite, apply, diagonal, invert, mat_mul, mat_sub, mat_vec, sub3, Coeffs, Mat3, Vec3,
};
use crate::real::Real;
use crate::temperature::{eval_table, Calibration, Source, WithTerms};
use crate::terms::TermEntry;
#[cfg(feature = "terms")]
use crate::terms::{force_values, product, set_decay, state_values, UnitState, MAX_TERMS};

/// What discovered terms add to the f32 path's departure from the f64 one, g, for
/// terms whose contributions stay within 1e-3 of the output scale (each at most 1e-3 V
/// on a 0.5 V/g unit, 2 mg, at |a| <= 1 g and the machines' state): the f32 rounding of
/// the state parts (the rate's f32 error, 1e-5 C/s, is the largest: 6e-4 C/min on a
/// dTdt coefficient) and of the force parts at the estimated specific force, whose own
/// f32 error moves them. Held by `tests/terms.rs` (the departure with the terms minus
/// the departure without them, sample by sample: at most 5e-7 g seen).
pub const TERMS_F32_BOUND_G: f64 = 1e-6;

/// Which temperature-error model method 2 subtracts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorModel {
    /// Formulas (6)/(7): `N(T0)(dK a + dU0)`.
    Full,
    /// Formula (8): only the diagonal of `N(T0)`.
    Simplified,
}

/// The compensation method, chosen at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// Method 1: coefficients at the current temperature, `a = N(T)(U - U0(T))`.
    CorrectConstants,
    /// Method 2: T0 constants, then subtract the temperature error.
    CorrectResult(ErrorModel),
}

/// Status flags of one compensated sample (a bit set; 0 = all good).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status(u8);

impl Status {
    /// The temperature is outside the blob's valid range (extrapolated or clamped).
    pub const TEMP_OUT_OF_RANGE: Status = Status(1);
    /// The temperature was clamped to the valid range (blob option `clamp`).
    pub const TEMP_CLAMPED: Status = Status(2);
    /// The temperature input is NaN or infinite: the last good temperature was used
    /// (T0 if there was none).
    pub const TEMP_NON_FINITE: Status = Status(4);
    /// A voltage input is NaN or infinite: the acceleration is NaN in all axes.
    pub const INPUT_NON_FINITE: Status = Status(8);
    /// K(T) was singular at the new temperature: the last good matrices were kept.
    pub const SINGULAR: Status = Status(16);
    /// The result overflowed (huge inputs): the acceleration is NaN in all axes.
    pub const OUTPUT_NON_FINITE: Status = Status(32);
    /// The time step given to [`Compensator::compensate_dt`] was negative or not finite:
    /// it was taken as 0.
    pub const BAD_TIME_STEP: Status = Status(64);

    /// No flag set.
    pub const fn is_ok(self) -> bool {
        self.0 == 0
    }
    /// All flags of `other` are set.
    pub const fn contains(self, other: Status) -> bool {
        self.0 & other.0 == other.0
    }
    /// The raw bits.
    pub const fn bits(self) -> u8 {
        self.0
    }
    /// Set the flags of `other`.
    #[inline]
    pub fn insert(&mut self, other: Status) {
        self.0 |= other.0;
    }
}

/// One compensated sample.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output<R> {
    /// Specific force in g along the unit's axes (NaN when the input was not finite).
    pub accel: Vec3<R>,
    /// What happened on the way.
    pub status: Status,
}

/// Which code path a sample takes: the method and the physics terms folded into one
/// dispatch, so the per-sample path tests one byte, not a flag and then a method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Path {
    Constants,
    Result,
    #[cfg(feature = "physics")]
    Physics,
}

/// The compensator: borrows the calibration (a [`crate::blob::BlobView`] of the blob in
/// flash, or an owned [`Calibration`] on the host) and holds only the cached matrices,
/// the machines' state and the discovered terms' weights (240 bytes in f32 on the MCU;
/// at most 256 on the MCU and a 64-bit host alike, checked when the crate compiles).
#[derive(Clone, Debug)]
pub struct Compensator<S: Source> {
    src: S,
    path: Path,
    method: Method,
    /// Flags of the cached temperature (range, clamping, SINGULAR), set at each update.
    sticky: Status,
    /// N(T0), U0(T0): the passport constants (K(T0) at the end: read only by updates).
    n0: Mat3<S::Real>,
    u00: Vec3<S::Real>,
    /// Temperature of the cached matrices (the raw input, before any clamping).
    t_cached: S::Real,
    /// Method 1: N(T), U0(T). Method 2: `delta = m a_hat + e`.
    n: Mat3<S::Real>,
    u0: Vec3<S::Real>,
    /// Copies of the calibration's range and step: the per-sample path reads only self.
    t_min: S::Real,
    t_max: S::Real,
    step: S::Real,
    /// The sample period of [`Compensator::compensate`], s.
    period: S::Real,
    /// The state machines of the physics terms.
    #[cfg(feature = "physics")]
    ph: Machines<S::Real>,
    /// Each discovered term's coefficient times its state part, as of the machines' last
    /// step.
    #[cfg(feature = "terms")]
    weights: [S::Real; MAX_TERMS],
    /// K(T0), for method 2's dK at each update. With `terms` it is re-evaluated there
    /// instead (the same evaluation, the same bits): the weights take its room, so the
    /// state stays within 256 bytes on a 64-bit host too.
    #[cfg(not(feature = "terms"))]
    k0: Mat3<S::Real>,
}

/// The compensator over a blob in flash, in f32: what the firmware holds.
pub type FlashCompensator<'a> = Compensator<crate::blob::BlobView<'a>>;

// Size contract: the firmware's compensator state fits 256 bytes (the C interface
// reserves exactly that), on the MCU and on a 64-bit host alike.
const _: () = assert!(core::mem::size_of::<FlashCompensator<'static>>() <= 256);

impl<'a, R: Real> Compensator<&'a Calibration<R>> {
    /// Build a compensator over an owned calibration (the host, tests), sampling every
    /// `sample_period_s` seconds; the cache starts at T0, the physics terms at power-on.
    ///
    /// Refused: a sample period that is not a positive finite number
    /// ([`Error::BadSamplePeriod`]); without the `physics` feature, a calibration with
    /// physics terms ([`Error::PhysicsNotBuiltIn`]).
    pub fn new(cal: &'a Calibration<R>, method: Method, sample_period_s: R) -> Result<Self, Error> {
        cal.validate()?;
        Self::with_source(cal, method, sample_period_s)
    }
}

impl<'a, R: Real> Compensator<WithTerms<'a, R>> {
    /// [`Compensator::new`] over an owned calibration and its discovered terms (the host's
    /// form of a blob with a term table: `Blob::calibration` and `Blob::terms`).
    ///
    /// Refused as `new`, and: a term table that is not valid
    /// ([`crate::temperature::source_terms`]); without the `terms` feature, any term
    /// ([`Error::TermsNotBuiltIn`]).
    pub fn with_terms(
        cal: &'a Calibration<R>,
        terms: &'a [TermEntry<R>],
        method: Method,
        sample_period_s: R,
    ) -> Result<Self, Error> {
        let src = WithTerms {
            calibration: cal,
            terms,
        };
        cal.validate()?;
        crate::temperature::validate_source(&src)?;
        Self::with_source(src, method, sample_period_s)
    }
}

impl<'a> Compensator<crate::blob::BlobView<'a>> {
    /// Build a compensator that reads the tables from a validated blob in place (flash),
    /// for an MCU sampling every `sample_period_s` seconds; the cache starts at T0, the
    /// physics terms at power-on ([`crate::inflight`]).
    ///
    /// Refused: a sample period that is not a positive finite number
    /// ([`Error::BadSamplePeriod`]); without the `physics` feature, a blob with physics
    /// terms ([`Error::PhysicsNotBuiltIn`]).
    // Not inlined into the caller: its code is the library's, and counts as such in
    // the flash figures of `cargo xtask embedded`.
    #[inline(never)]
    pub fn from_blob(
        blob: crate::blob::BlobView<'a>,
        method: Method,
        sample_period_s: f32,
    ) -> Result<Self, Error> {
        Self::with_source(blob, method, sample_period_s)
    }
}

impl<S: Source<Real = R>, R: Real> Compensator<S> {
    /// `src` has been validated (an owned calibration by `new`, a view by construction).
    // The negated comparison is the point: it is true for NaN.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn with_source(src: S, method: Method, sample_period_s: R) -> Result<Self, Error> {
        if !(sample_period_s > R::ZERO && sample_period_s.is_finite()) {
            return Err(Error::BadSamplePeriod);
        }
        #[cfg(not(feature = "terms"))]
        if src.term_count() > 0 {
            return Err(Error::TermsNotBuiltIn);
        }
        #[cfg(not(feature = "physics"))]
        if src.has_physics() {
            return Err(Error::PhysicsNotBuiltIn);
        }
        let t0 = src.t0_c();
        let c0 = Coeffs::from_array(&eval_table(src.table(), t0, t0));
        let n0 = invert(&c0.k).ok_or(Error::Singular)?;
        let mut s = Compensator {
            src,
            path: Path::Constants,
            method,
            n0,
            #[cfg(not(feature = "terms"))]
            k0: c0.k,
            u00: c0.u0,
            t_cached: t0,
            n: n0,
            u0: c0.u0,
            t_min: src.t_min_c(),
            t_max: src.t_max_c(),
            step: src.update_step_c(),
            period: sample_period_s,
            sticky: Status::default(),
            #[cfg(feature = "physics")]
            // power-on: the machines start at the first sample in range
            ph: Machines::default(),
            #[cfg(feature = "terms")]
            weights: [R::ZERO; MAX_TERMS],
        };
        // until the machines start, the terms' state is that of power-on at T0
        #[cfg(feature = "terms")]
        s.weigh_terms(&UnitState::default());
        s.set_method(method);
        Ok(s)
    }

    /// The method in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Switch method at run time (recomputes the cache at the cached temperature).
    pub fn set_method(&mut self, method: Method) {
        self.method = method;
        self.path = match method {
            Method::CorrectConstants => Path::Constants,
            Method::CorrectResult(_) => Path::Result,
        };
        #[cfg(feature = "physics")]
        if self.src.has_physics() || self.src.term_count() > 0 {
            self.path = Path::Physics;
        }
        self.update(self.t_cached);
    }

    /// The temperature the cached matrices were computed for.
    pub fn cached_temperature(&self) -> R {
        self.t_cached
    }

    /// The calibration the compensator reads.
    pub fn source(&self) -> &S {
        &self.src
    }

    /// The sample period of [`Compensator::compensate`], s.
    pub fn sample_period(&self) -> R {
        self.period
    }

    /// The sensor was powered on again `since_s` seconds before the next sample, while
    /// this compensator kept its state (an MCU that stays up over a power cycle of the
    /// sensor; host-fit at each power-off a recording states): the warm-up clock starts
    /// again from the power-on; the lag, the rate and the hysteresis run on, the next
    /// sample stepping them across the gap ([`crate::inflight`]). An MCU that itself
    /// powered up makes a new compensator instead: every machine starts at its first
    /// sample. Without physics terms nothing changes.
    pub fn power_on(&mut self, since_s: R) {
        #[cfg(feature = "physics")]
        self.ph.power_on(since_s);
        #[cfg(not(feature = "physics"))]
        let _ = since_s;
    }

    /// The state machines of the physics terms (their outputs: the model temperature and
    /// the offsets, as of their last step).
    #[cfg(feature = "physics")]
    pub fn machines(&self) -> &Machines<R> {
        &self.ph
    }

    fn effective_temperature(&self, t: R) -> R {
        if !self.src.clamp() {
            t
        } else if t < self.t_min {
            self.t_min
        } else if t > self.t_max {
            self.t_max
        } else {
            t
        }
    }

    /// The temperature moved by more than the step, or is not finite: recompute the
    /// cache (finite) or keep it (NaN, infinite); the status of this sample.
    #[cold]
    #[inline(never)]
    fn refresh(&mut self, t: R) -> Status {
        if !t.is_finite() {
            let mut s = self.sticky;
            s.insert(Status::TEMP_NON_FINITE);
            return s;
        }
        self.update(t);
        self.sticky
    }

    /// K(T0): kept without `terms`, re-evaluated with it (as at construction: the same
    /// evaluation, so the same bits).
    #[inline]
    fn k0(&self) -> Mat3<R> {
        #[cfg(not(feature = "terms"))]
        let k0 = self.k0;
        #[cfg(feature = "terms")]
        let k0 = {
            let t0 = self.src.t0_c();
            Coeffs::from_array(&eval_table(self.src.table(), t0, t0)).k
        };
        k0
    }

    /// Recompute the cached matrices and range flags for a finite temperature `t`.
    fn update(&mut self, t: R) {
        let te = self.effective_temperature(t);
        let c = Coeffs::from_array(&eval_table(self.src.table(), self.src.t0_c(), te));
        self.t_cached = t;
        match self.method {
            Method::CorrectConstants => match invert(&c.k) {
                Some(n) => {
                    self.n = n;
                    self.u0 = c.u0;
                    self.sticky = Status::default();
                }
                None => self.sticky = Status::SINGULAR,
            },
            Method::CorrectResult(em) => {
                let dk = mat_sub(&c.k, &self.k0());
                let du0 = sub3(c.u0, self.u00);
                // delta = N0 (dK a + dU0) = (N0 dK) a + N0 dU0; the simplified model
                // uses diag(N0) in place of N0.
                let left = match em {
                    ErrorModel::Full => self.n0,
                    ErrorModel::Simplified => {
                        let [d0, d1, d2] = diagonal(&self.n0);
                        let z = R::ZERO;
                        [[d0, z, z], [z, d1, z], [z, z, d2]]
                    }
                };
                self.n = mat_mul(&left, &dk);
                self.u0 = mat_vec(&left, du0);
                self.sticky = Status::default();
            }
        }
        if t < self.t_min || t > self.t_max {
            self.sticky.insert(if self.src.clamp() {
                Status(Status::TEMP_OUT_OF_RANGE.0 | Status::TEMP_CLAMPED.0)
            } else {
                Status::TEMP_OUT_OF_RANGE
            });
        }
    }

    /// Compensate one sample: output voltages `u` at sensor temperature `temp_c`, one
    /// sample period after the previous sample (or after power-on): the fixed-rate case.
    /// [`Compensator::compensate_dt`] with the sample period.
    ///
    /// Never panics. Non-finite voltages give NaN acceleration with
    /// [`Status::INPUT_NON_FINITE`]; a non-finite temperature keeps the last good one
    /// and sets [`Status::TEMP_NON_FINITE`].
    ///
    /// The fast path has one dispatch (method and physics terms folded into one byte)
    /// and two data-independent tests: the cache step (NaN fails every comparison, so
    /// `!(|T - Tc| <= step)` also catches a non-finite temperature) and one finiteness
    /// test of the output sum (any non-finite input makes the output non-finite); the
    /// rare cases are classified off the fast path. The range flags are those of the
    /// cached temperature, evaluated at each update: within one update step of a range
    /// limit they may lag by up to that step.
    // One copy of the per-sample paths for both entry points (flash): `compensate_dt`
    // calls this one for the paths that do not use the time.
    #[inline(never)]
    pub fn compensate(&mut self, u: Vec3<R>, temp_c: R) -> Output<R> {
        match self.path {
            Path::Constants => self.core(u, temp_c, false),
            #[cfg(feature = "physics")]
            Path::Result => self.shared_core(u, temp_c, true),
            #[cfg(not(feature = "physics"))]
            Path::Result => self.core(u, temp_c, true),
            #[cfg(feature = "physics")]
            Path::Physics => self.compensate_physics(u, temp_c, self.period),
        }
    }

    /// The core path with the method chosen at run time, one copy for method 2 and the
    /// physics path (flash); method 1 inlines its own (its per-sample budget).
    #[cfg(feature = "physics")]
    #[inline(never)]
    fn shared_core(&mut self, u: Vec3<R>, temp_c: R, m2: bool) -> Output<R> {
        self.core(u, temp_c, m2)
    }

    /// Compensate one sample taken `dt_s` seconds after the previous one (or after
    /// power-on): a temperature read at its own rate, a logger with gaps, a recording
    /// replayed on its own clock. A negative or non-finite `dt_s` is taken as 0 and
    /// flagged ([`Status::BAD_TIME_STEP`]). Otherwise as [`Compensator::compensate`].
    pub fn compensate_dt(&mut self, u: Vec3<R>, temp_c: R, dt_s: R) -> Output<R> {
        let good = dt_s >= R::ZERO && dt_s.is_finite();
        let mut out = match self.path {
            #[cfg(feature = "physics")]
            Path::Physics => self.compensate_physics(u, temp_c, if good { dt_s } else { R::ZERO }),
            _ => self.compensate(u, temp_c),
        };
        if !good {
            out.status.insert(Status::BAD_TIME_STEP);
        }
        out
    }

    /// Start or step the physics terms' machines at sensor temperature `x`: reads every
    /// term from the source (flash); at most once per [`crate::inflight::MIN_STEP_S`]. A
    /// source with discovered terms and no physics section steps neutral machines (their
    /// clock, rate and time since power-on), then the terms' weights are renewed.
    #[cfg(feature = "terms")]
    #[inline(never)]
    fn step_machines(&mut self, tick: Tick<R>, x: R) {
        let p = self
            .src
            .physics()
            .unwrap_or_else(crate::temperature::Physics::neutral);
        let t0 = self.src.t0_c();
        let rate = self.ph.apply(tick, &p, x, t0);
        self.weigh_terms(&UnitState {
            dt_c: self.ph.sensor_temperature() - t0,
            dtdt_c_per_min: rate * R::from_f32(60.0),
            since_power_on_s: self.ph.since_power_on(),
        });
    }

    /// Start or step the physics terms' machines (without the `terms` feature: a source
    /// on the physics path has physics terms).
    #[cfg(all(feature = "physics", not(feature = "terms")))]
    #[inline(never)]
    fn step_machines(&mut self, tick: Tick<R>, x: R) {
        if let Some(p) = self.src.physics() {
            let _ = self.ph.apply(tick, &p, x, self.src.t0_c());
        }
    }

    /// Each discovered term's coefficient times its state part in state `s`
    /// ([`crate::terms::TermEntry::weight`]'s arithmetic), read from the source (flash).
    #[cfg(feature = "terms")]
    fn weigh_terms(&mut self, s: &UnitState<R>) {
        let n = self.src.term_count();
        // the state table once, its decay slot per term: `state_values(s, tau)` each time
        let mut v = state_values(s, 0.0);
        for (j, w) in self.weights.iter_mut().enumerate().take(n) {
            let t = self.src.term_raw(j);
            set_decay(&mut v, s, t.tau_s);
            *w = t.coefficient * product(&v, t.codes);
        }
    }

    /// Add each discovered term's contribution at specific force `a` to its axis's
    /// error `e` (its weight times its force part; table order).
    #[cfg(feature = "terms")]
    #[inline]
    fn add_terms(&self, e: &mut [R; 3], a: Vec3<R>) {
        let n = self.src.term_count();
        if n == 0 {
            return;
        }
        let f = force_values(a);
        // a fourth slot takes an axis code that is none (never after validation): the
        // masked index needs no bounds check
        let [e0, e1, e2] = *e;
        let mut acc = [e0, e1, e2, R::ZERO];
        for (j, w) in self.weights.iter().enumerate().take(n) {
            let (axis, codes) = self.src.term_shape(j);
            if let Some(slot) = acc.get_mut(usize::from(axis & 3)) {
                *slot = *slot + *w * product(&f, codes);
            }
        }
        let [a0, a1, a2, _] = acc;
        *e = [a0, a1, a2];
    }

    /// The physics terms around the core path: the temperature (when within 40 C of the
    /// valid range) steps the machines on their clock ([`crate::inflight`]); the model is
    /// evaluated at the lagged element temperature and the offsets of temperature rate,
    /// hysteresis and warm-up are removed from the voltages (both as of the machines'
    /// last step); then the K2 and scale-asymmetry terms and the discovered terms are
    /// corrected to first order (`a = a_hat - N (k2 a_hat^2 + c |a_hat| + e_terms(a_hat))`,
    /// error second order in those terms), read from the source (flash) on every sample.
    #[cfg(feature = "physics")]
    #[inline(never)]
    fn compensate_physics(&mut self, u: Vec3<R>, temp_c: R, dt_s: R) -> Output<R> {
        let m2 = matches!(self.method, Method::CorrectResult(_));
        // A glitch far outside the valid range (a broken sensor reading) must not poison
        // the filters for minutes: such a sample only lets its time pass, as a NaN does,
        // and is evaluated at its own temperature (flagged by the core).
        let margin = R::from_f32(40.0);
        let t_model = if temp_c >= self.t_min - margin && temp_c <= self.t_max + margin {
            let tick = self.ph.clock().tick(dt_s);
            if tick != Tick::Hold {
                self.step_machines(tick, temp_c);
            }
            self.ph.model_temperature()
        } else {
            self.ph.clock().wait(dt_s);
            temp_c
        };
        let mut out = self.shared_core(sub3(u, self.ph.offset()), t_model, m2);
        if out.status.contains(Status::INPUT_NON_FINITE)
            || out.status.contains(Status::OUTPUT_NON_FINITE)
        {
            return out;
        }
        // Path::Physics: physics terms, discovered terms, or both
        #[cfg(feature = "terms")]
        let mut e = match self.src.physics() {
            Some(p) => second_order(&p, out.accel),
            None => [R::ZERO; 3],
        };
        #[cfg(feature = "terms")]
        self.add_terms(&mut e, out.accel);
        // without `terms`, Path::Physics is set only for a source with physics terms
        #[cfg(not(feature = "terms"))]
        let Some(e) = self.src.physics().map(|p| second_order(&p, out.accel)) else {
            return out;
        };
        let n = if m2 { &self.n0 } else { &self.n };
        out.accel = sub3(out.accel, mat_vec(n, e));
        let [b0, b1, b2] = out.accel;
        if !(b0 + b1 + b2).is_finite() {
            // the quadratic term overflowed on a huge (finite) input
            out.status.insert(Status::OUTPUT_NON_FINITE);
            out.accel = [R::NAN; 3];
        }
        out
    }

    // The negated comparisons are the point: they are true for NaN.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline(always)]
    fn core(&mut self, u: Vec3<R>, temp_c: R, m2: bool) -> Output<R> {
        let mut status = self.sticky;
        if !((temp_c - self.t_cached).abs() <= self.step) {
            status = self.refresh(temp_c);
        }
        let accel = if m2 {
            let a_hat = apply(&self.n0, u, self.u00);
            sub3(a_hat, add3(mat_vec(&self.n, a_hat), self.u0))
        } else {
            apply(&self.n, u, self.u0)
        };
        let [a0, a1, a2] = accel;
        if !(a0 + a1 + a2).is_finite() {
            status.insert(non_finite_status(&u));
            return Output {
                accel: [R::NAN; 3],
                status,
            };
        }
        Output { accel, status }
    }
}

/// The K2 and scale-asymmetry terms at the estimated specific force `a`, per axis.
#[cfg(feature = "physics")]
#[inline]
fn second_order<R: Real>(p: &crate::temperature::Physics<R>, a: Vec3<R>) -> Vec3<R> {
    let [a0, a1, a2] = a;
    let [k0, k1, k2] = p.k2;
    let [c0, c1, c2] = p.asymmetry;
    [
        k0 * a0 * a0 + c0 * a0.abs(),
        k1 * a1 * a1 + c1 * a1.abs(),
        k2 * a2 * a2 + c2 * a2.abs(),
    ]
}

/// Why the output is not finite: a non-finite input, or an overflow. Either way the
/// acceleration is one canonical NaN (the sign and payload of a NaN made by the FPU
/// differ between targets: ARM's default NaN is positive, x86's negative).
#[cold]
#[inline(never)]
fn non_finite_status<R: Real>(u: &Vec3<R>) -> Status {
    if all_finite(u) {
        Status::OUTPUT_NON_FINITE
    } else {
        Status::INPUT_NON_FINITE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::example_blob;

    #[test]
    fn method1_inverts_forward_model_at_calibration_temperatures() {
        let blob = example_blob();
        let cal: Calibration<f64> = blob.calibration.convert();
        let mut comp = Compensator::new(&cal, Method::CorrectConstants, 1.0).unwrap();
        for t in [-40.0, -10.0, 20.0, 45.0, 70.0] {
            let c = Coeffs::from_array(&cal.model.eval(cal.t0_c, t));
            let a = [0.42261826, 0.0, 0.90630779];
            let out = comp.compensate(c.forward(a), t);
            assert!(out.status.is_ok());
            for (x, y) in out.accel.iter().zip(a.iter()) {
                assert!((x - y).abs() < 1e-12, "{t}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn cache_is_kept_within_step_and_flags_are_set() {
        let blob = example_blob();
        let mut comp = Compensator::new(&blob.calibration, Method::CorrectConstants, 1.0).unwrap();
        comp.compensate([0.0, 0.0, -0.55], 25.0);
        assert_eq!(comp.cached_temperature(), 25.0);
        comp.compensate([0.0, 0.0, -0.55], 25.05);
        assert_eq!(comp.cached_temperature(), 25.0);
        comp.compensate([0.0, 0.0, -0.55], 25.2);
        assert_eq!(comp.cached_temperature(), 25.2);
        let o = comp.compensate([0.0, 0.0, -0.55], 90.0);
        assert!(o.status.contains(Status::TEMP_OUT_OF_RANGE));
        assert!(!o.status.contains(Status::TEMP_CLAMPED));
        let o = comp.compensate([0.0, f32::NAN, -0.55], f32::NAN);
        assert!(o.status.contains(Status::INPUT_NON_FINITE));
        assert!(o.status.contains(Status::TEMP_NON_FINITE));
        assert!(o.accel.iter().all(|v| v.is_nan()));
        assert_eq!(comp.cached_temperature(), 90.0);
        let o = comp.compensate([3e38, 3e38, 3e38], 20.0);
        assert!(o.status.contains(Status::OUTPUT_NON_FINITE));
        assert!(o.accel.iter().all(|v| v.to_bits() == f32::NAN.to_bits()));
    }

    #[test]
    fn the_sample_period_must_be_a_positive_number_of_seconds() {
        let blob = example_blob();
        for bad in [0.0f32, -0.01, f32::NAN, f32::INFINITY] {
            assert_eq!(
                Compensator::new(&blob.calibration, Method::CorrectConstants, bad).err(),
                Some(Error::BadSamplePeriod),
                "{bad}"
            );
        }
        let c = Compensator::new(&blob.calibration, Method::CorrectConstants, 0.001).unwrap();
        assert_eq!(c.sample_period(), 0.001);
    }

    #[cfg(feature = "physics")]
    fn with_physics() -> Calibration<f32> {
        let mut cal = example_blob().calibration;
        cal.physics = Some(crate::blob::example_physics());
        cal
    }

    /// A sample's temperature over a fast warming: -20 C, +6 C/min from 60 s.
    #[cfg(feature = "physics")]
    fn warming(t: f64) -> f32 {
        (-20.0 + 0.1 * (t - 60.0).max(0.0)) as f32
    }

    #[cfg(feature = "physics")]
    #[test]
    fn the_fixed_period_is_the_explicit_step_of_that_length() {
        let cal = with_physics();
        let mut fixed = Compensator::new(&cal, Method::CorrectConstants, 0.01).unwrap();
        let mut explicit = Compensator::new(&cal, Method::CorrectConstants, 1.0).unwrap();
        let u = [0.0045, -0.0044, -0.5521];
        for k in 0..30_000 {
            let t = warming(k as f64 * 0.01);
            let (a, b) = (fixed.compensate(u, t), explicit.compensate_dt(u, t, 0.01));
            assert_eq!(a.accel.map(f32::to_bits), b.accel.map(f32::to_bits), "{k}");
        }
    }

    /// The same blob at 10 Hz, 100 Hz and 1 kHz gives the same compensation at every
    /// 0.1 s (where all three machines have just stepped), within the f32 bound of
    /// 2e-6 g, and the f32 path at 1 kHz follows the f64 one at 10 Hz as closely; between
    /// steps the 1 kHz output is held (at 6 C/min the temperature moves 0.01 C per 0.1 s).
    #[cfg(feature = "physics")]
    #[test]
    fn ten_hundred_and_thousand_hertz_compensate_alike() {
        let cal = with_physics();
        let cal64: Calibration<f64> = cal.convert();
        let u = [0.0045f32, -0.0044, -0.5521];
        let run = |hz: u32| -> Vec<[f32; 3]> {
            let mut c = Compensator::new(&cal, Method::CorrectConstants, 1.0 / hz as f32).unwrap();
            let per = (hz / 10) as usize;
            (0..6000 * per)
                .filter_map(|k| {
                    let o = c.compensate(u, warming(k as f64 / f64::from(hz)));
                    (k % per == 0).then_some(o.accel)
                })
                .collect()
        };
        let mut c64 = Compensator::new(&cal64, Method::CorrectConstants, 0.1).unwrap();
        let reference: Vec<[f64; 3]> = (0..6000)
            .map(|k| {
                c64.compensate(u.map(f64::from), f64::from(warming(k as f64 * 0.1)))
                    .accel
            })
            .collect();
        let runs = [run(10), run(100), run(1000)];
        let mut worst: f64 = 0.0;
        for r in &runs {
            assert_eq!(r.len(), reference.len());
            for (a, b) in r.iter().zip(&reference) {
                for (x, y) in a.iter().zip(b) {
                    worst = worst.max((f64::from(*x) - y).abs());
                }
            }
        }
        assert!(worst < 2e-6, "worst {worst:e} g");
        // the terms act: the warming's rate offset alone is 0.02 V per C/s x 0.1 C/s
        let without = {
            let plain = example_blob();
            let mut c =
                Compensator::new(&plain.calibration, Method::CorrectConstants, 0.1).unwrap();
            c.compensate(u, warming(300.0)).accel
        };
        assert!((without[0] - runs[0][3000][0]).abs() > 1e-3);
    }

    /// A power-on of the sensor brings the warm-up back (the example's 2e-4 V on x); at
    /// a constant temperature nothing else moves.
    #[cfg(feature = "physics")]
    #[test]
    fn a_power_on_brings_the_warm_up_back() {
        let cal = with_physics();
        let mut c = Compensator::new(&cal, Method::CorrectConstants, 0.1).unwrap();
        let u = [0.0045, -0.0044, -0.5521];
        let first = c.compensate_dt(u, 20.0, 0.0).accel;
        for _ in 0..100_000 {
            c.compensate(u, 20.0);
        }
        let later = c.compensate(u, 20.0).accel;
        assert!((first[0] - later[0]).abs() > 1e-4, "the warm-up decayed");
        c.power_on(0.0);
        let again = c.compensate_dt(u, 20.0, 0.0).accel;
        assert!((again[0] - first[0]).abs() < 1e-6, "{again:?} {first:?}");
    }

    #[test]
    fn a_bad_time_step_is_flagged_and_taken_as_zero() {
        let blob = example_blob();
        let mut c = Compensator::new(&blob.calibration, Method::CorrectConstants, 1.0).unwrap();
        let u = [0.0045, -0.0044, -0.5521];
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            let o = c.compensate_dt(u, 20.0, bad);
            assert_eq!(o.status, Status::BAD_TIME_STEP);
            assert!(o.accel.iter().all(|v| v.is_finite()));
        }
        assert!(c.compensate_dt(u, 20.0, 0.0).status.is_ok());
    }
}
