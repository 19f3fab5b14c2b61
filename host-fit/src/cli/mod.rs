//! The `host-fit` command line: a thin match, one small function per command; every
//! command prints text, or JSON with `--json`, rendered from the same typed outputs.
pub mod args;
mod calibrate;
mod check;
mod common;
mod production;
mod records;
mod study;

use crate::error::Result;
use args::Command;
pub use common::Outcome;
use std::io::Write;

/// Run the tool with `args` (including the program name); returns the exit code.
pub fn run<I, T>(args: I, out: &mut dyn Write, err: &mut dyn Write) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    // a reader that goes away (`host-fit inspect B | head`) ends the output, not the
    // command, and without a word about it
    let (mut out, mut err) = (Closable::new(out), Closable::new(err));
    let (out, err): (&mut dyn Write, &mut dyn Write) = (&mut out, &mut err);
    let cli = match records::parse(args) {
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
        Ok(Outcome::Done) => 0,
        Ok(Outcome::Rejected) => EXIT_REJECTED,
        Ok(Outcome::NotJudged) => EXIT_NOT_JUDGED,
        Err(e) => {
            let _ = writeln!(err, "error: {e}");
            1
        }
    }
}

/// Output to a reader that may go away: once its pipe is closed, what follows is dropped
/// (the command ends as it would have, with its own exit code) instead of ending in
/// "Broken pipe".
struct Closable<'a> {
    inner: &'a mut dyn Write,
    closed: bool,
}

impl<'a> Closable<'a> {
    fn new(inner: &'a mut dyn Write) -> Self {
        Closable {
            inner,
            closed: false,
        }
    }

    /// `r`, or, when the reader has gone, `ok` and nothing more written from now on.
    fn unless_closed<T>(&mut self, r: std::io::Result<T>, ok: T) -> std::io::Result<T> {
        match r {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(ok)
            }
            r => r,
        }
    }
}

impl Write for Closable<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.closed {
            return Ok(buf.len());
        }
        let r = self.inner.write(buf);
        self.unless_closed(r, buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.closed {
            return Ok(());
        }
        let r = self.inner.flush();
        self.unless_closed(r, ())
    }
}

/// The exit code of a command that ran but whose result failed acceptance (`verify`),
/// or in which a unit failed or could not be processed (`batch`). 1 stays "could not run".
pub const EXIT_REJECTED: i32 = 3;

/// The exit code of a command that ran but could not judge a band of the acceptance
/// specification (no verification dwell there): neither a pass nor a failure (`verify`;
/// `batch` when some unit was not judged and none failed or errored).
pub const EXIT_NOT_JUDGED: i32 = 4;

fn dispatch(cmd: Command, out: &mut dyn Write, err: &mut dyn Write) -> Result<Outcome> {
    let done = |r: Result<()>| r.map(|()| Outcome::Done);
    match cmd {
        Command::TempFit(a) => done(calibrate::temp_fit(a, out)),
        Command::Identify(a) => done(calibrate::identify(a, out, err)),
        Command::Fit(a) => done(calibrate::fit(a, out, err)),
        Command::Verify(a) => check::verify(a, out, err),
        Command::Inspect(a) => done(check::inspect(a, out)),
        Command::FwVectors(a) => done(check::fw_vectors(a, out)),
        Command::Diagnose(a) => done(study::diagnose(a, out, err)),
        Command::Report(a) => done(study::report(a, out, err)),
        Command::Blind(a) => done(study::blind(a, out, err)),
        Command::Batch(a) => production::batch(a, out, err),
        Command::Simulate(a) => done(production::simulate(a, out)),
        Command::Plan(a) => done(production::plan(a, out)),
        Command::Demo(a) => done(production::demo(a, out)),
        Command::History(a) => done(records::history(a, out)),
        Command::Trend(a) => done(records::trend(a, out)),
        Command::Store(a) => done(records::store(a, out)),
    }
}
