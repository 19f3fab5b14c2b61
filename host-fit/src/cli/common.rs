//! What every command shares: reading a recording with its positions, the unit's serial,
//! writing a line of output.
use super::args::{Input, PositionArgs};
use crate::data::door::Check;
use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::error::{ErrorKind, HostError, Result};
use std::borrow::Cow;
use std::io::Write;

/// How a command that ran ended (`cli::run` makes it the exit code: 0,
/// `EXIT_REJECTED` or `EXIT_NOT_JUDGED`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Done (and accepted, where acceptance is judged).
    Done,
    /// Ran, but the result failed acceptance (or a unit of a batch failed or errored).
    Rejected,
    /// Ran, but a band of the specification had no judged dwell (in a batch: some unit
    /// was not judged, and none failed or errored).
    NotJudged,
}

/// Write one line of output.
pub(super) fn w(out: &mut dyn Write, s: impl std::fmt::Display) -> Result<()> {
    writeln!(out, "{s}")
        .map_err(|e| HostError::new(ErrorKind::Io, format!("cannot write output: {e}")))
}

/// The positions of `p`: the built-ins and the positions file, the verification
/// positions set by `--positions-for-check`, the file's vectors forgotten with
/// `--unknown-orientations`; with the file's warnings.
pub(super) fn positions(p: &PositionArgs) -> Result<(Positions, Vec<String>)> {
    let (mut pos, warns) = match &p.positions {
        Some(f) => Positions::with_file(f)?,
        None => (Positions::default(), Vec::new()),
    };
    if let Some(names) = &p.positions_for_check {
        pos.set_verification(names, "--positions-for-check")?;
    }
    if p.unknown_orientations {
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
    Ok((pos, warns))
}

/// The checks at the door that refuse a recording read to judge or study it: its units
/// (a recording that covers less than its test promised is a warning).
const REFUSE_TO_STUDY: [Check; 2] = [Check::OutputScale, Check::TemperatureScale];

/// Read the recording of `input` with its positions ([`positions`]), past the checks at
/// the door of its units ([`crate::data::door`]); warnings go to `err`, and the notes on
/// expected features of the data too with `--verbose`.
pub(super) fn load(input: &Input, err: &mut dyn Write) -> Result<Recording> {
    read(input, err, false, &REFUSE_TO_STUDY)
}

/// [`load`] for a command that fits: a position missing at a stop is a warning too,
/// naming the position and the stop (and kept in the recording's warnings).
pub(super) fn load_to_fit(input: &Input, err: &mut dyn Write) -> Result<Recording> {
    read(input, err, true, &REFUSE_TO_STUDY)
}

/// [`load_to_fit`] for a command that writes a blob: a recording that covers less than
/// its test promised is refused too (unless `--allow partial`).
pub(super) fn load_for_blob(input: &Input, err: &mut dyn Write) -> Result<Recording> {
    read(input, err, true, &Check::ALL)
}

fn read(input: &Input, err: &mut dyn Write, fitting: bool, refuse: &[Check]) -> Result<Recording> {
    let (pos, mut warns) = positions(&input.positions)?;
    let mut rec = Recording::read(&input.recording, pos)?;
    let allow: Vec<Check> = input.allow.iter().map(|a| Check::from(*a)).collect();
    crate::data::door::admit(&mut rec, refuse, &allow)?;
    if fitting {
        let missing = crate::fit::coverage::missing(&rec);
        rec.warnings.extend(missing.iter().map(|m| m.text()));
    }
    warns.extend(rec.warnings.iter().cloned());
    for wn in &warns {
        let _ = writeln!(err, "warning: {wn}");
    }
    if input.verbose {
        for n in &rec.notes {
            let _ = writeln!(err, "note: {n}");
        }
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
