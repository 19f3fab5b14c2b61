//! Host errors: one small set of kinds, each error located as precisely as the input
//! allows (file, and where it applies the line and field); the message says what is wrong
//! and, where useful, what to do.
use std::fmt;
use std::path::{Path, PathBuf};

/// What kind of thing went wrong: what a caller (or a test) tells errors apart by. The
/// message says the particulars; the kind never changes the words the user reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// A file's text is not what its format says: a header, a column, a value, the encoding.
    Malformed,
    /// The data are well formed but do not determine what was asked (too few positions,
    /// temperatures, dwells or windows; no static dwell; an empty folder).
    Insufficient,
    /// The system refused a read or a write (its own error is quoted).
    Io,
    /// A file is where one would be written: refused without `--force`.
    Exists,
    /// An option or a configuration's setting is out of range, unknown or contradicts another.
    Invalid,
    /// Inputs that belong to different units (a blob, a truth or a run of another serial).
    Mismatch,
    /// A numerical result that cannot be trusted: a singular or ill-conditioned matrix, the
    /// f32 path departing from f64 over its bound.
    Numerical,
    /// A calibration blob that is not one (magic, version, CRC) or cannot be built (serial).
    Blob,
    /// What this build cannot do: a format version it does not read, a fitted term the
    /// firmware cannot flash.
    Unsupported,
    /// Nothing meets the target asked for (no test plan within the limits).
    Unmet,
    /// The record store refused: not a store, cut short or corrupt, locked, a newer schema,
    /// no such run.
    Store,
    /// A broken invariant of host-fit itself (a bug: please report it).
    Internal,
}

/// An error of the host tool: its kind, where it is, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct HostError {
    kind: ErrorKind,
    /// The file the problem is in, if any.
    pub file: Option<PathBuf>,
    /// 1-based line number in that file.
    pub line: Option<usize>,
    /// The column / field name.
    pub field: Option<String>,
    /// What is wrong, and where useful what to do.
    pub message: String,
}

/// Result with [`HostError`].
pub type Result<T> = std::result::Result<T, HostError>;

impl HostError {
    /// An error of `kind` not tied to a file.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        HostError {
            kind,
            file: None,
            line: None,
            field: None,
            message: message.into(),
        }
    }
    /// An error of `kind` in `file`.
    pub fn in_file(kind: ErrorKind, file: &Path, message: impl Into<String>) -> Self {
        HostError {
            file: Some(file.to_path_buf()),
            ..Self::new(kind, message)
        }
    }
    /// An error of `kind` at `file:line`.
    pub fn at(kind: ErrorKind, file: &Path, line: usize, message: impl Into<String>) -> Self {
        HostError {
            line: Some(line),
            ..Self::in_file(kind, file, message)
        }
    }
    /// An error of `kind` at `file:line` in `field`.
    pub fn at_field(
        kind: ErrorKind,
        file: &Path,
        line: usize,
        field: &str,
        message: impl Into<String>,
    ) -> Self {
        HostError {
            field: Some(field.to_string()),
            ..Self::at(kind, file, line, message)
        }
    }
    /// An I/O error on `file` ([`ErrorKind::Io`]).
    pub fn io(file: &Path, e: &std::io::Error) -> Self {
        Self::in_file(ErrorKind::Io, file, e.to_string())
    }

    /// What kind of error this is.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// This error located in `file` when it names no file yet; a file, line and field it
    /// already names are kept (they are more precise than the caller's).
    pub fn within(self, file: &Path) -> Self {
        if self.file.is_some() {
            return self;
        }
        HostError {
            file: Some(file.to_path_buf()),
            ..self
        }
    }
}

impl fmt::Display for HostError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}", file.display())?;
            if let Some(line) = self.line {
                write!(f, ":{line}")?;
            }
            f.write_str(": ")?;
        }
        if let Some(field) = &self.field {
            write!(f, "field `{field}`: ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for HostError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_names_the_file_and_keeps_a_more_precise_location_and_the_kind() {
        let (a, b) = (Path::new("a.csv"), Path::new("b.csv"));
        let e = HostError::new(ErrorKind::Insufficient, "bad").within(a);
        assert_eq!(e.to_string(), "a.csv: bad");
        assert_eq!(e.kind(), ErrorKind::Insufficient);
        let e = HostError::at_field(ErrorKind::Malformed, a, 7, "temp_c", "not a number").within(b);
        assert_eq!(e.to_string(), "a.csv:7: field `temp_c`: not a number");
        assert_eq!((e.line, e.field.as_deref()), (Some(7), Some("temp_c")));
        assert_eq!(e.kind(), ErrorKind::Malformed);
    }

    #[test]
    fn an_io_error_is_of_the_io_kind_and_quotes_the_system() {
        let sys = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file");
        let e = HostError::io(Path::new("x.csv"), &sys);
        assert_eq!(
            (e.kind(), e.to_string()),
            (ErrorKind::Io, "x.csv: No such file".into())
        );
    }
}
