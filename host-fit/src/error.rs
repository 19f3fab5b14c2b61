//! Host errors: every message names the file, and where it applies the line and field.
use std::fmt;
use std::path::{Path, PathBuf};

/// An error of the host tool, located as precisely as the input allows.
#[derive(Debug, Clone, PartialEq)]
pub struct HostError {
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
    /// An error not tied to a file.
    pub fn msg(message: impl Into<String>) -> Self {
        HostError {
            file: None,
            line: None,
            field: None,
            message: message.into(),
        }
    }
    /// An error in `file`.
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        HostError {
            file: Some(file.to_path_buf()),
            ..Self::msg(message)
        }
    }
    /// An error at `file:line`.
    pub fn at(file: &Path, line: usize, message: impl Into<String>) -> Self {
        HostError {
            line: Some(line),
            ..Self::in_file(file, message)
        }
    }
    /// An error at `file:line` in `field`.
    pub fn at_field(file: &Path, line: usize, field: &str, message: impl Into<String>) -> Self {
        HostError {
            field: Some(field.to_string()),
            ..Self::at(file, line, message)
        }
    }
    /// An I/O error on `file`.
    pub fn io(file: &Path, e: &std::io::Error) -> Self {
        Self::in_file(file, e.to_string())
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
    fn within_names_the_file_and_keeps_a_more_precise_location() {
        let (a, b) = (Path::new("a.csv"), Path::new("b.csv"));
        let e = HostError::msg("bad").within(a);
        assert_eq!(e.to_string(), "a.csv: bad");
        let e = HostError::at_field(a, 7, "temp_c", "not a number").within(b);
        assert_eq!(e.to_string(), "a.csv:7: field `temp_c`: not a number");
        assert_eq!((e.line, e.field.as_deref()), (Some(7), Some("temp_c")));
    }
}
