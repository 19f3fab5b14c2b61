//! The engineer's reports: self-contained HTML pages with SVG plots, for the demo (or
//! any recording) and for a diagnosis.
pub mod demo;
pub mod diagnosis;
pub mod page;
pub mod plot;
