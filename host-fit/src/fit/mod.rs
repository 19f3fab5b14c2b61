//! The fit layer: from a recording's dwells to the 12 coefficients and their temperature
//! models, with one least-squares solver.
pub mod describe;
pub mod identify;
pub mod lsq;
pub mod noise;
pub mod pipeline;
pub mod temperature;
