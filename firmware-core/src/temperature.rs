//! Temperature models of the 12 coefficients as fixed tables (model.md section 4).
//!
//! Both kinds store absolute values (relative beta/gamma are fragile when a
//! cross-sensitivity is near zero, model.md section 4):
//! - polynomial: `c(T) = sum_k p_k dT^k`, `dT = T - T0`, order 1..=5;
//! - piecewise-linear: the coefficient values at 2..=16 strictly increasing breakpoints,
//!   linearly interpolated, the end segments extrapolated.
use crate::error::Error;
use crate::model::N_COEFFS;
use crate::real::Real;
use crate::terms::{validate_entries, RawTerm, TermEntry, TermList, MAX_TERMS};

/// Highest polynomial order a table holds.
pub const MAX_POLY_ORDER: usize = 5;
/// Most breakpoints a piecewise-linear table holds.
pub const MAX_BREAKPOINTS: usize = 16;

/// One value per coefficient, in [`crate::model::COEFF_NAMES`] order.
pub type CoeffRow<R> = [R; N_COEFFS];

/// The temperature model of all 12 coefficients.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TempModel<R> {
    /// Polynomial in `dT = T - T0`: `terms[k]` holds the dT^k coefficient of every
    /// coefficient (so `terms[0]` is the value at T0); `terms.len() = order + 1`.
    Poly {
        /// Coefficients of dT^0, dT^1, ... dT^order.
        terms: heapless::Vec<CoeffRow<R>, { MAX_POLY_ORDER + 1 }>,
    },
    /// Piecewise-linear through breakpoints.
    Pwl {
        /// Strictly increasing temperatures, C.
        breakpoints: heapless::Vec<R, MAX_BREAKPOINTS>,
        /// `values[j]`: the 12 coefficients at `breakpoints[j]`.
        values: heapless::Vec<CoeffRow<R>, MAX_BREAKPOINTS>,
    },
}

/// Everything the compensator needs: the temperature model and how to use it.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration<R> {
    /// Reference temperature T0, C: the "passport" constants are `model` at T0.
    pub t0_c: R,
    /// Lowest temperature the model is valid at, C.
    pub t_min_c: R,
    /// Highest temperature the model is valid at, C.
    pub t_max_c: R,
    /// Outside `[t_min_c, t_max_c]`: clamp the temperature (true) or extrapolate (false).
    /// Either way the output is flagged out of range.
    pub clamp: bool,
    /// Method 1/2 recompute their cached matrices only when the temperature moved by
    /// more than this many C since the last update (0 = on every change).
    pub update_step_c: R,
    /// The coefficient tables.
    pub model: TempModel<R>,
    /// Physics beyond the 12 coefficients, found by `host-fit diagnose` (None = off).
    pub physics: Option<Physics<R>>,
}

/// Defines [`Physics`] from one list of its terms (name, `one` word or `axes` x y z, type,
/// neutral value), in the order a blob stores them: the
/// struct, [`PHYSICS_WORDS`], [`PHYSICS_TERM_NAMES`], the words in and out, the neutral
/// set and the conversion between float types all follow from the list, so a new term is
/// one line (at the end, with the blob's format version bumped).
macro_rules! physics_terms {
    ($( $(#[doc = $doc:literal])* $name:ident : $kind:ident $ty:ty = $neutral:expr ; )*) => {
        /// Terms beyond the paper's model (physics-catalogue.md), applied in flight by
        /// [`crate::inflight::Machines`]. Every time constant is in seconds: the firmware
        /// is told its sample period (or each sample's time step) and derives the per-step
        /// constants itself.
        #[derive(Clone, Debug, PartialEq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct Physics<R> {
            $( $(#[doc = $doc])* pub $name: $ty, )*
        }

        /// Words (f32 in a blob) of the physics terms: the length of [`Physics::to_words`].
        pub const PHYSICS_WORDS: usize = 0 $( + physics_terms!(@n $kind) )*;

        /// The terms' names, in blob order (a per-axis term is one name for its 3 words).
        pub const PHYSICS_TERM_NAMES: &[&str] = &[$( stringify!($name) ),*];

        impl<R: Real> Physics<R> {
            /// The terms in the order a blob stores them (per-axis terms x, y, z).
            pub fn to_words(&self) -> [R; PHYSICS_WORDS] {
                let mut out = [R::ZERO; PHYSICS_WORDS];
                let mut slots = out.iter_mut();
                $(
                    for v in physics_terms!(@words $kind, self.$name) {
                        if let Some(s) = slots.next() {
                            *s = v;
                        }
                    }
                )*
                out
            }

            /// [`Physics::from_words`] with word `i` given by `w(i)`: a blob's section is
            /// read field by field where it lies, without a copy of the section.
            #[inline(always)]
            pub fn from_word_fn(w: impl Fn(usize) -> R) -> Self {
                let at = 0usize;
                $( let (at, $name) = physics_terms!(@read $kind, w, at); )*
                let _ = at;
                Physics { $( $name ),* }
            }

            /// No physics: no lag, no offsets, no K2 or asymmetry.
            pub fn neutral() -> Self {
                Physics { $( $name: physics_terms!(@neutral $kind, $neutral) ),* }
            }

            /// Convert to another float type.
            pub fn convert<S: Real>(&self) -> Physics<S> {
                let c = |v: R| S::from_f64(v.to_f64());
                Physics { $( $name: physics_terms!(@convert $kind, c, self.$name) ),* }
            }
        }
    };
    (@n one) => { 1 };
    (@n axes) => { 3 };
    (@words one, $v:expr) => { [$v] };
    (@words axes, $v:expr) => { $v };
    (@read one, $w:ident, $at:ident) => { ($at + 1, $w($at)) };
    (@read axes, $w:ident, $at:ident) => { ($at + 3, [$w($at), $w($at + 1), $w($at + 2)]) };
    (@neutral one, $v:expr) => { R::from_f32($v) };
    (@neutral axes, $v:expr) => { [R::from_f32($v); 3] };
    (@convert one, $c:ident, $v:expr) => { $c($v) };
    (@convert axes, $c:ident, $v:expr) => { $v.map($c) };
}

physics_terms! {
    /// `thermal_lag`: time constant of the one-pole filter from the sensor's temperature
    /// to the element's, s (0 = no lag).
    lag_tau_s: one R = 0.0;
    /// `temp_rate`: offset per C/s of the temperature rate, per axis (output units).
    rate: axes [R; 3] = 0.0;
    /// Time constant of the low-pass whose change is the rate, s (0 = the plain
    /// difference of successive steps); negative: the zero-lag estimator of the same
    /// time constant `|rate_tau_s|` ([`crate::inflight::Rate`], [`Physics::rate_zero_lag`]).
    rate_tau_s: one R = 0.0;
    /// `hysteresis`: offsets split `+-h/2` by the direction of the last change, per axis.
    hysteresis: axes [R; 3] = 0.0;
    /// A change of more than this (C) sets the direction (a relay); negative `-d`: a
    /// play operator of half-width `d`, the state linear over `2 d` C of travel after a
    /// reversal ([`crate::inflight::Direction`]; `d` at least [`MIN_PLAY_HALF_WIDTH_C`]). A
    /// firmware that predates the play operator refuses a negative threshold (out of its
    /// range), never misreads it.
    hysteresis_threshold_c: one R = 0.0;
    /// Direction at power-on (+1 heated, -1 cooled, 0 unknown), until the first change.
    hysteresis_initial: one R = 0.0;
    /// `nonlinearity_k2`: `U_i += k2_i a_i^2`, per axis (output units per g^2).
    k2: axes [R; 3] = 0.0;
    /// `scale_asymmetry`: `U_i += c_i |a_i|` (`c_i = K_ii delta_i`), per axis.
    asymmetry: axes [R; 3] = 0.0;
    /// `warmup_drift`: `U0_i += d_i exp(-t_on / tau_w)`, `t_on` the time since power-on.
    warmup: axes [R; 3] = 0.0;
    /// The warm-up's time constant tau_w, s (0 = no warm-up term).
    warmup_tau_s: one R = 0.0;
}

/// The narrowest play operator a blob may carry, half-width in C: narrower, the clamp
/// against a sensor's temperature in f32 (its ulp 4e-6 C at 60 C) leaves the state mostly
/// rounding, and no diagnosis profiles one (its narrowest is 3 C).
pub const MIN_PLAY_HALF_WIDTH_C: f32 = 0.01;

impl<R: Real> Physics<R> {
    /// The inverse of [`Physics::to_words`].
    pub fn from_words(w: &[R; PHYSICS_WORDS]) -> Self {
        Self::from_word_fn(|i| w.get(i).copied().unwrap_or(R::NAN))
    }

    /// Check finiteness and ranges.
    pub fn validate(&self) -> Result<(), Error> {
        if !self.to_words().iter().all(|v| v.is_finite()) {
            return Err(Error::NonFinite);
        }
        self.validate_ranges()
    }

    /// Whether the rate is estimated without lag (a negative `rate_tau_s`): the change
    /// of `2 L1 - L2`, `L1` the temperature's low-pass and `L2` the low-pass of `L1`, both
    /// of time constant `|rate_tau_s|`. A blob with it set is refused by a firmware that
    /// predates it (a negative time constant is out of its range), never misread.
    pub fn rate_zero_lag(&self) -> bool {
        self.rate_tau_s < R::ZERO
    }

    /// The range checks of [`Physics::validate`] (values known to be finite): time
    /// constants (but the rate's, whose sign chooses the estimator) not negative, a
    /// negative hysteresis threshold (a play operator) at least [`MIN_PLAY_HALF_WIDTH_C`]
    /// wide, the initial direction -1, 0 or +1.
    pub fn validate_ranges(&self) -> Result<(), Error> {
        let z = R::ZERO;
        let initial = self.hysteresis_initial;
        if self.lag_tau_s < z
            || self.warmup_tau_s < z
            || (self.hysteresis_threshold_c < z
                && -self.hysteresis_threshold_c < R::from_f32(MIN_PLAY_HALF_WIDTH_C))
            || !(initial == z || initial == R::ONE || initial == -R::ONE)
        {
            return Err(Error::BadRange);
        }
        Ok(())
    }
}

/// The piecewise-linear segment rule, written once for the firmware's tables and the
/// host's fits: of `n` breakpoints (read through `breakpoint`), the segment is the last
/// one whose lower breakpoint is <= `t` (the first one when `t` is below the table, or
/// NaN), so the end segments extrapolate. Returns the index of the segment's lower
/// breakpoint and the fraction `(t - b_lo) / (b_hi - b_lo)` (two roundings: within 1.5
/// ulp). Every interior breakpoint is visited, so the time does not depend on `t`. With
/// fewer than two breakpoints the fraction is NaN.
#[inline]
pub fn pwl_segment<R: Real>(n: usize, breakpoint: impl Fn(usize) -> R, t: R) -> (usize, R) {
    let mut seg = 0;
    for j in 1..n.saturating_sub(1) {
        if t >= breakpoint(j) {
            seg = j;
        }
    }
    let (b0, b1) = (breakpoint(seg), breakpoint(seg.saturating_add(1)));
    (seg, (t - b0) / (b1 - b0))
}

/// Which kind of temperature model a table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelKind {
    /// Polynomial in `dT = T - T0`; rows are the terms dT^0 .. dT^order.
    Poly,
    /// Piecewise-linear; rows are the values at the breakpoints.
    Pwl,
}

/// Read access to a temperature table, wherever it lives: an owned [`TempModel`] (the
/// host, tests) or a validated blob in flash ([`crate::blob::BlobView`]). The evaluation
/// and the checks are written once against this trait, so a table read from flash and
/// the same table owned give the same bits.
pub trait Table {
    /// The scalar the table is read in.
    type Real: Real;
    /// Polynomial or piecewise-linear.
    fn kind(&self) -> ModelKind;
    /// Number of rows: polynomial terms (order + 1) or breakpoints.
    fn rows(&self) -> usize;
    /// Breakpoint `j`, C (piecewise-linear tables; NaN when out of range).
    fn breakpoint(&self, j: usize) -> Self::Real;
    /// Row `j`: the 12 coefficients' dT^j terms (polynomial) or values at breakpoint `j`.
    /// NaN when out of range (never after validation).
    fn row(&self, j: usize) -> CoeffRow<Self::Real>;
}

impl<R: Real> Table for TempModel<R> {
    type Real = R;
    #[inline]
    fn kind(&self) -> ModelKind {
        match self {
            TempModel::Poly { .. } => ModelKind::Poly,
            TempModel::Pwl { .. } => ModelKind::Pwl,
        }
    }
    #[inline]
    fn rows(&self) -> usize {
        match self {
            TempModel::Poly { terms } => terms.len(),
            TempModel::Pwl { breakpoints, .. } => breakpoints.len(),
        }
    }
    #[inline]
    fn breakpoint(&self, j: usize) -> R {
        match self {
            TempModel::Poly { .. } => R::NAN,
            TempModel::Pwl { breakpoints, .. } => breakpoints.get(j).copied().unwrap_or(R::NAN),
        }
    }
    #[inline]
    fn row(&self, j: usize) -> CoeffRow<R> {
        let r = match self {
            TempModel::Poly { terms } => terms.get(j),
            TempModel::Pwl { values, .. } => values.get(j),
        };
        r.copied().unwrap_or([R::NAN; N_COEFFS])
    }
}

/// The 12 coefficients of table `tab` at temperature `t` (C), reference `t0` (C).
///
/// Cost is fixed for a given table size (no early exit), so the temperature update
/// takes the same time wherever `t` is. Outside the breakpoints the end segment is
/// extrapolated; the caller flags or clamps.
///
/// Error bound (f32, held by tests): Horner's rule gives
/// `|err| <= 2 n eps sum_k |p_k| |dT|^k` (n = order); the interpolation
/// `v0 + (v1 - v0) f` gives `|err| <= 4 eps max(|v0|, |v1|)`.
pub fn eval_table<T: Table>(tab: &T, t0: T::Real, t: T::Real) -> CoeffRow<T::Real> {
    let zero = <T::Real as Real>::ZERO;
    match tab.kind() {
        ModelKind::Poly => {
            let dt = t - t0;
            let mut acc = [zero; N_COEFFS];
            for k in (0..tab.rows()).rev() {
                let row = tab.row(k);
                for (a, p) in acc.iter_mut().zip(row.iter()) {
                    *a = *a * dt + *p;
                }
            }
            acc
        }
        ModelKind::Pwl => {
            let (seg, f) = pwl_segment(tab.rows(), |j| tab.breakpoint(j), t);
            let next = seg.saturating_add(1);
            // the lower row is interpolated in place: one row less on the stack
            let mut out = tab.row(seg);
            for (o, hi) in out.iter_mut().zip(tab.row(next).iter()) {
                *o = *o + (*hi - *o) * f;
            }
            out
        }
    }
}

/// Sizes, finiteness and breakpoint order of any table.
pub fn validate_table<T: Table>(tab: &T) -> Result<(), Error> {
    table_size(tab)?;
    if !table_finite(tab) {
        return Err(Error::NonFinite);
    }
    breakpoints_increasing(tab)
}

fn table_size<T: Table>(tab: &T) -> Result<(), Error> {
    let n = tab.rows();
    let max = match tab.kind() {
        ModelKind::Poly => MAX_POLY_ORDER.saturating_add(1),
        ModelKind::Pwl => MAX_BREAKPOINTS,
    };
    if n < 2 || n > max {
        return Err(Error::TableSize);
    }
    Ok(())
}

fn table_finite<T: Table>(tab: &T) -> bool {
    let pwl = tab.kind() == ModelKind::Pwl;
    (0..tab.rows()).all(|j| {
        tab.row(j).iter().all(|v| v.is_finite()) && (!pwl || tab.breakpoint(j).is_finite())
    })
}

fn breakpoints_increasing<T: Table>(tab: &T) -> Result<(), Error> {
    if tab.kind() == ModelKind::Pwl {
        for j in 1..tab.rows() {
            if tab.breakpoint(j.saturating_sub(1)) >= tab.breakpoint(j) {
                return Err(Error::BreakpointsNotIncreasing);
            }
        }
    }
    Ok(())
}

impl<R: Real> TempModel<R> {
    /// Check sizes, finiteness and breakpoint order.
    pub fn validate(&self) -> Result<(), Error> {
        if let TempModel::Pwl {
            breakpoints,
            values,
        } = self
        {
            if values.len() != breakpoints.len() {
                return Err(Error::TableSize);
            }
        }
        validate_table(self)
    }

    /// The 12 coefficients at temperature `t` (C), reference `t0` (C): [`eval_table`].
    pub fn eval(&self, t0: R, t: R) -> CoeffRow<R> {
        eval_table(self, t0, t)
    }

    /// Convert the table to another float type (f64 -> f32 rounds to nearest).
    pub fn convert<S: Real>(&self) -> TempModel<S> {
        let row = |r: &CoeffRow<R>| -> CoeffRow<S> { r.map(|v| S::from_f64(v.to_f64())) };
        match self {
            TempModel::Poly { terms } => TempModel::Poly {
                terms: terms.iter().map(row).collect(),
            },
            TempModel::Pwl {
                breakpoints,
                values,
            } => TempModel::Pwl {
                breakpoints: breakpoints
                    .iter()
                    .map(|b| S::from_f64(b.to_f64()))
                    .collect(),
                values: values.iter().map(row).collect(),
            },
        }
    }
}

/// A whole calibration, wherever it lives: an owned [`Calibration`] (by reference) or a
/// validated blob in flash ([`crate::blob::BlobView`]). The compensator is generic over
/// it, so the host evaluates the firmware's code on either.
pub trait Source: Copy {
    /// The scalar the calibration is read in.
    type Real: Real;
    /// The temperature table.
    type Table: Table<Real = Self::Real>;
    /// The table.
    fn table(&self) -> &Self::Table;
    /// Reference temperature T0, C.
    fn t0_c(&self) -> Self::Real;
    /// Lowest valid temperature, C.
    fn t_min_c(&self) -> Self::Real;
    /// Highest valid temperature, C.
    fn t_max_c(&self) -> Self::Real;
    /// Clamp (true) or extrapolate (false) outside the valid range.
    fn clamp(&self) -> bool;
    /// Cache update step, C.
    fn update_step_c(&self) -> Self::Real;
    /// Whether the calibration carries in-flight physics terms.
    fn has_physics(&self) -> bool;
    /// The physics terms, read where they live (once per sample on the physics path).
    fn physics(&self) -> Option<Physics<Self::Real>>;
    /// Every value (scalars, table, physics terms) is finite.
    fn all_finite(&self) -> bool;
    /// The number of discovered terms ([`crate::terms`]; 0: none).
    #[inline]
    fn term_count(&self) -> usize {
        0
    }
    /// Entry `j` of the term table, as stored ([`RawTerm::none`] out of range).
    #[inline]
    fn term_raw(&self, j: usize) -> RawTerm<Self::Real> {
        let _ = j;
        RawTerm::none()
    }
    /// The axis and factor codes of entry `j` (what every sample reads).
    #[inline]
    fn term_shape(&self, j: usize) -> (u8, [u8; 3]) {
        let r = self.term_raw(j);
        (r.axis, r.codes)
    }
}

/// An owned calibration with its discovered terms (the host's form of a blob with a term
/// table): a [`Source`] for [`crate::compensate::Compensator::with_terms`].
#[derive(Clone, Copy, Debug)]
pub struct WithTerms<'a, R> {
    /// The calibration.
    pub calibration: &'a Calibration<R>,
    /// Its discovered terms (at most [`MAX_TERMS`]).
    pub terms: &'a [TermEntry<R>],
}

impl<'a, R: Real> Source for WithTerms<'a, R> {
    type Real = R;
    type Table = TempModel<R>;
    #[inline]
    fn table(&self) -> &TempModel<R> {
        &self.calibration.model
    }
    #[inline]
    fn t0_c(&self) -> R {
        self.calibration.t0_c
    }
    #[inline]
    fn t_min_c(&self) -> R {
        self.calibration.t_min_c
    }
    #[inline]
    fn t_max_c(&self) -> R {
        self.calibration.t_max_c
    }
    #[inline]
    fn clamp(&self) -> bool {
        self.calibration.clamp
    }
    #[inline]
    fn update_step_c(&self) -> R {
        self.calibration.update_step_c
    }
    #[inline]
    fn has_physics(&self) -> bool {
        self.calibration.physics.is_some()
    }
    #[inline]
    fn physics(&self) -> Option<Physics<R>> {
        self.calibration.physics.clone()
    }
    fn all_finite(&self) -> bool {
        Source::all_finite(&self.calibration)
    }
    #[inline]
    fn term_count(&self) -> usize {
        self.terms.len()
    }
    #[inline]
    fn term_raw(&self, j: usize) -> RawTerm<R> {
        self.terms.get(j).map_or_else(RawTerm::none, TermEntry::raw)
    }
}

/// The term table of a source checked where it lies, entry by entry (no term built: the
/// firmware's validation, [`crate::terms::check_codes`]): at most [`MAX_TERMS`]
/// ([`Error::TooManyTerms`]), each axis x, y or z ([`Error::TermAxis`]), canonical codes
/// and TAU, a finite coefficient ([`Error::NonFinite`]), no entry equal to an earlier one
/// on its axis ([`Error::DuplicateTerm`]). The same rules as [`source_terms`].
pub fn validate_terms<S: Source>(s: &S) -> Result<(), Error> {
    let n = s.term_count();
    if n > MAX_TERMS {
        return Err(Error::TooManyTerms);
    }
    for j in 0..n {
        let t = s.term_raw(j);
        if t.axis > 2 {
            return Err(Error::TermAxis);
        }
        crate::terms::check_codes(t.codes, t.tau_s)?;
        if !t.coefficient.is_finite() {
            return Err(Error::NonFinite);
        }
        for k in 0..j {
            let e = s.term_shape(k);
            if e == (t.axis, t.codes) && s.term_raw(k).tau_s.to_bits() == t.tau_s.to_bits() {
                return Err(Error::DuplicateTerm);
            }
        }
    }
    Ok(())
}

/// The term table of a source, each entry checked ([`RawTerm::entry`]) and the list
/// ([`validate_entries`]): at most [`MAX_TERMS`] ([`Error::TooManyTerms`]).
pub fn source_terms<S: Source>(s: &S) -> Result<TermList<S::Real>, Error> {
    let n = s.term_count();
    if n > MAX_TERMS {
        return Err(Error::TooManyTerms);
    }
    let mut out = TermList::new();
    for j in 0..n {
        out.push(s.term_raw(j).entry()?)
            .map_err(|_| Error::TooManyTerms)?;
    }
    validate_entries(&out)?;
    Ok(out)
}

impl<R: Real> Source for &Calibration<R> {
    type Real = R;
    type Table = TempModel<R>;
    #[inline]
    fn table(&self) -> &TempModel<R> {
        &self.model
    }
    #[inline]
    fn t0_c(&self) -> R {
        self.t0_c
    }
    #[inline]
    fn t_min_c(&self) -> R {
        self.t_min_c
    }
    #[inline]
    fn t_max_c(&self) -> R {
        self.t_max_c
    }
    #[inline]
    fn clamp(&self) -> bool {
        self.clamp
    }
    #[inline]
    fn update_step_c(&self) -> R {
        self.update_step_c
    }
    #[inline]
    fn has_physics(&self) -> bool {
        self.physics.is_some()
    }
    #[inline]
    fn physics(&self) -> Option<Physics<R>> {
        self.physics.clone()
    }
    fn all_finite(&self) -> bool {
        let scalars = [self.t0_c, self.t_min_c, self.t_max_c, self.update_step_c];
        scalars.iter().all(|v| v.is_finite())
            && table_finite(&self.model)
            && self
                .physics
                .as_ref()
                .is_none_or(|p| p.to_words().iter().all(|v| v.is_finite()))
    }
}

/// The checks every calibration passes, in the order of their errors: table size,
/// every value finite, range and step, physics ranges, breakpoint order, the discovered
/// terms ([`validate_terms`], with the `terms` feature). (Whether K(T0) is invertible is checked by the blob and the
/// compensator.)
pub fn validate_source<S: Source>(s: &S) -> Result<(), Error> {
    table_size(s.table())?;
    if !s.all_finite() {
        return Err(Error::NonFinite);
    }
    if s.t_min_c() >= s.t_max_c() || s.update_step_c() < <S::Real as Real>::ZERO {
        return Err(Error::BadRange);
    }
    if let Some(p) = s.physics() {
        p.validate_ranges()?;
    }
    breakpoints_increasing(s.table())?;
    // without the `terms` feature a blob with a table is refused when it is opened, an
    // owned one by the compensator: no table is validated (flash), none compensated
    #[cfg(feature = "terms")]
    validate_terms(s)?;
    Ok(())
}

impl<R: Real> Calibration<R> {
    /// Check the range, step and tables.
    pub fn validate(&self) -> Result<(), Error> {
        if let TempModel::Pwl {
            breakpoints,
            values,
        } = &self.model
        {
            if values.len() != breakpoints.len() {
                return Err(Error::TableSize);
            }
        }
        validate_source(&self)
    }

    /// The coefficients at the reference temperature (the passport constants).
    pub fn at_t0(&self) -> CoeffRow<R> {
        self.model.eval(self.t0_c, self.t0_c)
    }

    /// Convert to another float type.
    pub fn convert<S: Real>(&self) -> Calibration<S> {
        let c = |v: R| S::from_f64(v.to_f64());
        Calibration {
            t0_c: c(self.t0_c),
            t_min_c: c(self.t_min_c),
            t_max_c: c(self.t_max_c),
            clamp: self.clamp,
            update_step_c: c(self.update_step_c),
            model: self.model.convert(),
            physics: self.physics.as_ref().map(Physics::convert),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(v: f64) -> CoeffRow<f64> {
        core::array::from_fn(|i| v + i as f64)
    }

    #[test]
    fn poly_is_horner_of_dt() {
        let mut terms = heapless::Vec::new();
        terms.push(row(1.0)).unwrap();
        terms.push([0.5; 12]).unwrap();
        terms.push([0.25; 12]).unwrap();
        let m = TempModel::Poly { terms };
        let v = m.eval(20.0, 22.0);
        assert_eq!(v[0], 1.0 + 0.5 * 2.0 + 0.25 * 4.0);
        assert_eq!(v[11], 12.0 + 0.5 * 2.0 + 0.25 * 4.0);
    }

    #[test]
    fn pwl_interpolates_and_extrapolates_end_segments() {
        let m = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[-40.0, 20.0, 70.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0), row(6.0), row(1.0)]).unwrap(),
        };
        assert_eq!(m.eval(20.0, -10.0)[0], 3.0);
        assert_eq!(m.eval(20.0, 20.0)[0], 6.0);
        assert_eq!(m.eval(20.0, 45.0)[0], 3.5);
        assert_eq!(m.eval(20.0, -100.0)[0], -6.0);
        assert_eq!(m.eval(20.0, 120.0)[0], -4.0);
    }

    #[test]
    fn segment_rule_picks_the_last_lower_breakpoint() {
        let b = [-40.0f64, 20.0, 70.0];
        let seg = |t: f64| pwl_segment(b.len(), |j| b[j], t);
        assert_eq!(seg(-100.0), (0, -1.0));
        assert_eq!(seg(20.0), (1, 0.0));
        assert_eq!(seg(19.999).0, 0);
        assert_eq!(seg(120.0), (1, 2.0));
        assert_eq!(seg(f64::NAN).0, 0);
        let one = [5.0f64];
        assert!(
            pwl_segment(1, |j| one.get(j).copied().unwrap_or(f64::NAN), 0.0)
                .1
                .is_nan()
        );
    }

    #[test]
    fn physics_words_round_trip_in_the_documented_order() {
        let p = Physics {
            lag_tau_s: 1.0,
            rate: [2.0, 3.0, 4.0],
            rate_tau_s: 5.0,
            hysteresis: [6.0, 7.0, 8.0],
            hysteresis_threshold_c: 9.0,
            hysteresis_initial: 10.0,
            k2: [11.0, 12.0, 13.0],
            asymmetry: [14.0, 15.0, 16.0],
            warmup: [17.0, 18.0, 19.0],
            warmup_tau_s: 20.0,
        };
        assert_eq!(PHYSICS_WORDS, 20);
        assert_eq!(PHYSICS_TERM_NAMES.len(), 10);
        assert_eq!(PHYSICS_TERM_NAMES[0], "lag_tau_s");
        let w = p.to_words();
        assert_eq!(w, core::array::from_fn(|i| (i + 1) as f64));
        assert_eq!(Physics::from_words(&w), p);
        assert_eq!(p.convert::<f32>().convert::<f64>(), p);
        assert_eq!(Physics::<f64>::neutral().to_words(), [0.0; PHYSICS_WORDS]);
    }

    #[test]
    fn physics_ranges() {
        let ok = Physics::<f64>::neutral();
        assert_eq!(ok.validate(), Ok(()));
        let bad = |f: &dyn Fn(&mut Physics<f64>)| {
            let mut p = ok.clone();
            f(&mut p);
            p.validate()
        };
        assert_eq!(bad(&|p| p.lag_tau_s = -1.0), Err(Error::BadRange));
        // a negative rate time constant is the zero-lag estimator, a NaN is refused
        assert_eq!(bad(&|p| p.rate_tau_s = -1.0), Ok(()));
        assert_eq!(bad(&|p| p.rate_tau_s = f64::NAN), Err(Error::NonFinite));
        assert_eq!(bad(&|p| p.warmup_tau_s = -1.0), Err(Error::BadRange));
        // a negative threshold is a play operator (at least 0.01 C wide), a NaN is refused
        assert_eq!(bad(&|p| p.hysteresis_threshold_c = -0.1), Ok(()));
        assert_eq!(bad(&|p| p.hysteresis_threshold_c = -0.01), Ok(()));
        assert_eq!(
            bad(&|p| p.hysteresis_threshold_c = -0.009),
            Err(Error::BadRange)
        );
        assert_eq!(
            bad(&|p| p.hysteresis_threshold_c = f64::NAN),
            Err(Error::NonFinite)
        );
        assert_eq!(bad(&|p| p.hysteresis_initial = 0.5), Err(Error::BadRange));
        assert_eq!(bad(&|p| p.k2 = [0.0, f64::NAN, 0.0]), Err(Error::NonFinite));
    }

    #[test]
    fn validate_catches_bad_tables() {
        let bad_order = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[0.0, 0.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0), row(1.0)]).unwrap(),
        };
        assert_eq!(bad_order.validate(), Err(Error::BreakpointsNotIncreasing));
        let bad_len = TempModel::Pwl {
            breakpoints: heapless::Vec::from_slice(&[0.0, 1.0]).unwrap(),
            values: heapless::Vec::from_slice(&[row(0.0)]).unwrap(),
        };
        assert_eq!(bad_len.validate(), Err(Error::TableSize));
        let mut terms = heapless::Vec::new();
        terms.push(row(0.0)).unwrap();
        assert_eq!(
            TempModel::Poly {
                terms: terms.clone()
            }
            .validate(),
            Err(Error::TableSize)
        );
        terms.push([f64::NAN; 12]).unwrap();
        assert_eq!(TempModel::Poly { terms }.validate(), Err(Error::NonFinite));
    }
}
