//! The bench side of the accelerometer calibration: read recordings, identify the 12
//! coefficients, fit their temperature models, build coefficient blobs, verify.
//!
//! The model itself (formulas (1)-(8), (13)) is `firmware-core`'s, evaluated here in
//! f64 and, for checks, in the firmware's own f32 path.
#![forbid(unsafe_code)]

pub mod batch;
pub mod blind;
pub mod calib;
pub mod cli;
pub mod demo;
pub mod diagnose;
pub mod error;
pub mod fwcheck;
pub mod identify;
pub mod io;
pub mod linalg;
pub mod positions;
pub mod recording;
pub mod report;
pub mod rng;
pub mod simulate;
pub mod temperature;
pub mod verify;
