//! The `host-fit` command line: a thin match, one small function per command; every
//! command prints text, or JSON with `--json`, rendered from the same typed outputs.
pub mod args;
mod calibrate;
mod check;
mod production;
mod study;

use crate::data::positions::Positions;
use crate::data::recording::Recording;
use crate::error::{HostError, Result};
use args::{Cli, Command, Input};
use clap::Parser;
use std::io::Write;

/// Run the tool with `args` (including the program name); returns the exit code.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            let code = e.exit_code();
            let _ = if code == 0 {
                write!(out, "{}", e.render())
            } else {
                write!(err, "{}", e.render())
            };
            return code;
        }
    };
    match dispatch(cli.command, out, err) {
        Ok(()) => 0,
        Err(e) => {
            let _ = writeln!(err, "error: {e}");
            1
        }
    }
}

fn dispatch(cmd: Command, out: &mut dyn Write, err: &mut dyn Write) -> Result<()> {
    match cmd {
        Command::TempFit(a) => calibrate::temp_fit(a, out),
        Command::Identify(a) => calibrate::identify(a, out, err),
        Command::Fit(a) => calibrate::fit(a, out, err),
        Command::Verify(a) => check::verify(a, out, err),
        Command::Inspect(a) => check::inspect(a, out),
        Command::FwVectors(a) => check::fw_vectors(a, out),
        Command::Diagnose(a) => study::diagnose(a, out, err),
        Command::Report(a) => study::report(a, out, err),
        Command::Blind(a) => study::blind(a, out),
        Command::Batch(a) => production::batch(a, out, err),
        Command::Simulate(a) => production::simulate(a, out),
        Command::Demo(a) => production::demo(a, out),
    }
}

/// Write one line of output.
fn w(out: &mut dyn Write, s: impl std::fmt::Display) -> Result<()> {
    writeln!(out, "{s}").map_err(|e| HostError::msg(format!("cannot write output: {e}")))
}

/// Read the recording of `input` (with its positions file), the named positions made the
/// verification positions when `check` is given; warnings go to `err`.
fn load(input: &Input, check: Option<&[String]>, err: &mut dyn Write) -> Result<Recording> {
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
fn serial(rec: &Recording) -> &str {
    if rec.unit.is_empty() {
        "UNKNOWN"
    } else {
        rec.unit.as_str()
    }
}
