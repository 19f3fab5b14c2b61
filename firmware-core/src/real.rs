//! The small float abstraction that lets the model be written once for f32 and f64.
//!
//! Implemented with `libm` on purpose: `num-traits` switches to std maths when its
//! `std` feature is on (nalgebra turns it on in the host), which would make the host's
//! f32 evaluation differ from the MCU's.
use core::fmt::Debug;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point scalar the model can be evaluated in.
pub trait Real:
    Copy
    + Debug
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Machine epsilon of the type.
    const EPSILON: Self;
    /// Not a number.
    const NAN: Self;
    /// Exact conversion from f32 (tables are stored in f32).
    fn from_f32(x: f32) -> Self;
    /// Conversion from f64, rounding to nearest for f32.
    fn from_f64(x: f64) -> Self;
    /// Exact widening to f64.
    fn to_f64(self) -> f64;
    /// Absolute value (exact).
    fn abs(self) -> Self;
    /// Square root, correctly rounded (libm).
    fn sqrt(self) -> Self;
    /// Neither NaN nor infinite.
    fn is_finite(self) -> bool;
    /// `exp(-u) - 1` for `u >= 0` (a negative `u` is treated as 0, NaN stays NaN): f32
    /// by [`crate::exp::expm1_neg_f32`] (no soft-double; relative error within
    /// [`crate::exp::EXPM1_NEG_F32_BOUND`]), f64 by libm's `expm1` (the host).
    fn expm1_neg(self) -> Self;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const EPSILON: Self = f32::EPSILON;
    const NAN: Self = f32::NAN;
    #[inline]
    fn from_f32(x: f32) -> Self {
        x
    }
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrtf(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    #[inline]
    fn expm1_neg(self) -> Self {
        crate::exp::expm1_neg_f32(self)
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const EPSILON: Self = f64::EPSILON;
    const NAN: Self = f64::NAN;
    #[inline]
    fn from_f32(x: f32) -> Self {
        f64::from(x)
    }
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[inline]
    fn expm1_neg(self) -> Self {
        if self > 0.0 {
            libm::expm1(-self)
        } else if self.is_nan() {
            self
        } else {
            0.0
        }
    }
}
