//! What every command shares: reading a recording with its positions, the unit's serial,
//! writing a line of output.
use super::args::Input;
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use std::io::Write;

/// Write one line of output.
pub(super) fn w(out: &mut dyn Write, s: impl std::fmt::Display) -> Result<()> {
    writeln!(out, "{s}").map_err(|e| HostError::msg(format!("cannot write output: {e}")))
}

/// Read the recording of `input` (with its positions file), the named positions made the
/// verification positions when `check` is given; warnings go to `err`.
pub(super) fn load(
    input: &Input,
    check: Option<&[String]>,
    err: &mut dyn Write,
) -> Result<Recording> {
    let (mut pos, mut warns) = match &input.positions {
        Some(p) => Positions::with_file(p)?,
        None => (Positions::default(), Vec::new()),
    };
    if let Some(names) = check {
        pos.set_verification(names, "--positions-for-check")?;
    }
    let rec = Recording::read(&input.recording, pos)?;
    warns.extend(rec.warnings.iter().cloned());
    for wn in &warns {
        let _ = writeln!(err, "warning: {wn}");
    }
    Ok(rec)
}

/// The unit's serial, `UNKNOWN` when the recording has none.
pub(super) fn serial(rec: &Recording) -> &str {
    if rec.unit.is_empty() {
        "UNKNOWN"
    } else {
        rec.unit.as_str()
    }
}
