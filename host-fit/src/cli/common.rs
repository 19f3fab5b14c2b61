//! What every command shares: reading a recording with its positions, the unit's serial,
//! writing a line of output.
use super::args::Input;
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use std::borrow::Cow;
use std::io::Write;

/// How a command that ran ended (`cli::run` makes it the exit code: 0, or
/// `EXIT_REJECTED`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Done (and accepted, where acceptance is judged).
    Done,
    /// Ran, but the result failed acceptance (or a unit of a batch failed or errored).
    Rejected,
}

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
    if input.unknown_orientations {
        let builtin = Positions::default();
        let from_file: Vec<String> = pos
            .list
            .iter()
            .filter(|p| {
                builtin
                    .index(&p.name)
                    .is_none_or(|i| builtin.vector(i) != p.a)
            })
            .map(|p| p.name.clone())
            .collect();
        pos.forget_vectors(&from_file);
    }
    let rec = Recording::read(&input.recording, pos)?;
    warns.extend(rec.warnings.iter().cloned());
    for wn in &warns {
        let _ = writeln!(err, "warning: {wn}");
    }
    for n in &rec.notes {
        let _ = writeln!(err, "note: {n}");
    }
    Ok(rec)
}

/// `rec` with its poses of unknown orientation estimated (a note on `err`), for the
/// commands that need every vector.
pub(super) fn oriented(rec: Recording, err: &mut dyn Write) -> Result<Recording> {
    let oriented = crate::fit::pipeline::with_orientations(&rec, None)?;
    if let Some(o) = &oriented.orientation {
        let _ = writeln!(
            err,
            "note: {} poses of unknown orientation estimated from the data ({} alternations){}",
            o.poses.len(),
            o.iterations,
            o.frame
                .as_deref()
                .map(|f| format!("; {f}"))
                .unwrap_or_default()
        );
    }
    Ok(match oriented.rec {
        Cow::Owned(r) => r,
        Cow::Borrowed(_) => rec,
    })
}

/// The unit's serial, `UNKNOWN` when the recording has none.
pub(super) fn serial(rec: &Recording) -> &str {
    if rec.unit.is_empty() {
        "UNKNOWN"
    } else {
        rec.unit.as_str()
    }
}
