//! The figures the README and the book (`docs/`) quote, each produced by the command or
//! test it names. Each is computed once per test run, by the test that checks its values,
//! which also holds the quoted block to it (`crate::readme::same`); `tests/readme.rs`
//! checks the others.
mod diagnosis;
mod paper;
mod production;

pub use diagnosis::{blind_long, cats_tag, physics_blob, real_recordings};
pub use paper::{demo_run, demo_table, golden_table3, DemoRun};
pub use production::{
    coverage, fit_verify, ggir_wrist, imucal, model_choice, ChoiceRow, FitVerified,
};

/// A JSON array of strings as one string.
fn joined(v: &serde_json::Value, sep: &str) -> String {
    v.as_array()
        .into_iter()
        .flatten()
        .filter_map(|a| a.as_str())
        .collect::<Vec<_>>()
        .join(sep)
}
