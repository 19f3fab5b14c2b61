//! The engineer's reports: self-contained HTML pages with SVG plots, for the demo (or
//! any recording), for a diagnosis and for the trend of a record store.
pub mod axis;
pub mod demo;
pub mod diagnosis;
pub mod page;
pub mod plan;
pub mod plot;
pub mod svg;
pub mod trace;
pub mod trend;
