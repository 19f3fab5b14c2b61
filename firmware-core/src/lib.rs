//! Temperature compensation of a triaxial accelerometer, for the unit's MCU.
//!
//! The metrological model `U = K a + U0` (model.md, formula (1)), its temperature
//! dependence (formulas (3), (4), (12)), the temperature error (formulas (5)-(8)) and
//! the two compensation methods (section 6) live here once. They are generic over
//! [`Real`], so the host tool evaluates the very same code in `f64` while the MCU runs
//! it in `f32`.
//!
//! ```
//! use firmware_core::{blob::BlobView, compensate::{Compensator, Method}};
//! # let bytes = firmware_core::blob::example_blob_bytes();
//! // `bytes` is the coefficient blob flashed beside the firmware: validated where it
//! // lies, and read there by the compensator (no copy of the tables).
//! let blob = BlobView::new(&bytes).expect("a valid blob");
//! // the MCU samples at 100 Hz: the compensator is told so when it is made
//! let mut comp = Compensator::from_blob(blob, Method::CorrectConstants, 0.01)
//!     .expect("K(T0) invertible");
//! let out = comp.compensate([0.0045, -0.0044, -0.5521], 21.3);
//! assert!(out.status.is_ok());
//! assert!((out.accel[2] - 1.0).abs() < 0.01);
//! ```
//!
//! # Features
//! - `physics` (default): the in-flight terms found by `host-fit diagnose` (thermal lag,
//!   temperature rate, hysteresis, warm-up, K2, scale asymmetry), on the sample period the
//!   compensator is given (or each sample's own time step, [`compensate::Compensator::compensate_dt`]).
//!   Without it the compensation path is smaller, and a blob that carries such terms is
//!   refused by [`compensate::Compensator::new`] with [`Error::PhysicsNotBuiltIn`].
//! - `terms` (default, needs `physics`): the discovered terms of a blob's term table
//!   ([`terms`]: force products and powers, `dT`, `dTdt`, `decay(power_on,TAU)`), on the
//!   same clock. Without it a blob with such terms is refused by
//!   [`compensate::Compensator::new`] with [`Error::TermsNotBuiltIn`].
//! - `defmt`: `defmt::Format` on the public types.
// no_std always (the error type uses core::error::Error); unit tests use std.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// `clippy::arithmetic_side_effects` is denied in the modules with integer arithmetic
// (`blob`, `crc`); in the generic float modules it would flag every `R + R`.

pub mod blob;
pub mod compensate;
pub mod crc;
pub mod error;
pub mod exp;
pub mod format;
pub mod inflight;
pub mod model;
pub mod real;
pub mod temperature;
pub mod terms;

pub use error::Error;
pub use real::Real;

#[doc = include_str!("../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The book's firmware chapter: its Rust example is compiled and run like the README's.
#[doc = include_str!("../../docs/firmware.md")]
#[cfg(doctest)]
pub struct FirmwareChapterDoctests;
