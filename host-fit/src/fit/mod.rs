//! The fit layer: from a recording's dwells to the 12 coefficients and their temperature
//! models, with one least-squares solver.
pub mod coverage;
pub mod describe;
pub mod equilibrium;
pub mod folds;
pub mod identify;
pub mod lsq;
pub mod noise;
pub mod orientation;
pub mod pipeline;
pub mod predict;
pub mod route;
pub mod select;
pub mod temperature;
