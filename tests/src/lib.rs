//! Helpers for the end-to-end tests, by purpose: running the command line in-process
//! ([`run`]), tiny synthetic recordings ([`synthetic`]), the digital twin's varied
//! recordings ([`twins`]), the demo run once and shared ([`demo`]), the figures the README and the book quote ([`figures`]) and the
//! check that holds their text to them ([`readme`]).
use std::path::PathBuf;

pub mod demo;
pub mod figures;
pub mod four_stops;
pub mod lab;
pub mod pg;
pub mod readme;
pub mod run;
pub mod sweep;
pub mod synthetic;
pub mod time_true;
pub mod twins;

pub use run::{cli, cli_json, real_diagnosis};
pub use synthetic::{forward, synthetic_csv, PAPER_T0, TP};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A path as the `&str` the command line takes.
pub fn s(p: &std::path::Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}
