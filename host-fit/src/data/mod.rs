//! The data layer: recordings, positions (with their roles) and coefficient tables, read
//! exactly per `recording-format.md`; every bad field is an error naming file, line, field.
pub mod door;
pub mod fields;
pub mod output_unit;
pub mod positions;
pub mod recording;
pub mod stops;
pub mod table;
