//! The fit layer: from a recording's dwells to the 12 coefficients and their temperature
//! models (on the `model` engine's solver and bases), the route a recording is fitted on
//! ([`route`]: detection, the dynamic fit, the choice, and the one function that turns a
//! route's fit into the firmware's calibration), and the predicted compensation error.
pub mod cache;
pub mod coverage;
pub mod describe;
pub mod equilibrium;
pub mod folds;
pub mod identify;
pub mod noise;
pub mod orientation;
pub mod pipeline;
pub mod predict;
pub mod route;
pub mod select;
pub mod temperature;
