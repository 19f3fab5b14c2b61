//! The engine below `fit` and `diagnose`: what a model of a recording is built from and
//! judged by, whichever command fits it.
//!
//! Read bottom-up: [`lsq`] (the one least-squares solver) and [`basis`] (the temperature
//! basis of the 12 coefficients); the [`rules`] everything is judged by; the error
//! [`floor`] measured inside the dwells; the windows of a recording ([`observations`],
//! [`regressors`] of the in-flight terms through firmware-core's own filters, [`data`]:
//! built once, with [`weights`] from the floor); the terms a model may hold ([`effects`]:
//! the catalogue's, with their structural unknowns; [`params`]: every column typed) and
//! their columns ([`design`]); the solve with held-out blocks of time and Newey-West
//! errors ([`solve`], the baseline's normal equations kept once per data by
//! [`normal_cache`]); the structural unknowns profiled ([`profile`]); the figures of
//! merit and the judge of a larger model against a smaller one ([`metrics`]); the
//! [`baseline`]; the model in the firmware's forms ([`flashed`]), its cache step
//! ([`cache`]) and its f32 path against f64 ([`precision`]); the [`units`] of every
//! parameter. `fit` takes its dynamic route on it, `diagnose` its search.
pub mod baseline;
pub mod basis;
pub mod cache;
pub mod data;
pub mod design;
pub mod effects;
pub mod flashed;
pub mod floor;
pub mod library;
pub mod lsq;
pub mod metrics;
pub mod normal_cache;
pub mod observations;
pub mod orders;
pub mod params;
pub mod precision;
pub mod profile;
pub mod regressors;
pub mod rules;
pub mod solve;
pub mod units;
pub mod weights;
