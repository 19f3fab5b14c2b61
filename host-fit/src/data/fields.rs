//! The fields of input files: numbers and temperatures checked for range, CSV headers
//! and data lines, every error naming the file, the line and the field.
use crate::error::{ErrorKind, HostError, Result};
use std::path::Path;

/// The positions of the `want`ed columns in a CSV header line (names case-insensitive),
/// or an error naming the file, the line and the missing column. A header separated by
/// semicolons is refused with that reason (no guessing at the separator).
pub fn header_columns(path: &Path, line: usize, header: &str, want: &[&str]) -> Result<Vec<usize>> {
    if !header.contains(',') && header.contains(';') {
        return Err(HostError::at(ErrorKind::Malformed, path, line, "the header is separated by semicolons; these files are comma-separated, convert the file"));
    }
    let names: Vec<String> = header
        .split(',')
        .map(|s| s.trim().to_ascii_lowercase())
        .collect();
    want.iter()
        .map(|w| {
            names.iter().position(|n| n == w).ok_or_else(|| {
                HostError::at_field(
                    ErrorKind::Malformed,
                    path,
                    line,
                    w,
                    format!(
                        "required column `{w}` missing from the header (have: {})",
                        names.join(",")
                    ),
                )
            })
        })
        .collect()
}

/// Largest magnitude accepted in any numeric field of an input file. Beyond it the sums
/// of squares of a fit overflow f64 (a 1e200 reading is finite but unfittable), so it is
/// rejected with a line number instead of surfacing later as a NaN coefficient. 1e12
/// leaves room for raw 32-bit ADC counts and Unix-epoch times.
pub const MAX_ABS_VALUE: f64 = 1e12;
/// Absolute zero, C: a temperature below it is a wrong column or unit, not a reading.
pub const ABSOLUTE_ZERO_C: f64 = -273.15;

/// A numeric field of an input file: finite and within [`MAX_ABS_VALUE`], or an error
/// naming the file, the line and the field.
pub fn number(path: &Path, line: usize, field: &str, s: &str) -> Result<f64> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_ABS_VALUE => Ok(v),
        Ok(v) if v.is_finite() => Err(HostError::at_field(
            ErrorKind::Malformed,
            path,
            line,
            field,
            format!(
                "`{s}` is beyond +-{MAX_ABS_VALUE:e}: too large to fit in double precision \
                 (check the column's unit and scale)"
            ),
        )),
        _ => Err(HostError::at_field(
            ErrorKind::Malformed,
            path,
            line,
            field,
            format!("`{s}` is not a finite number"),
        )),
    }
}

/// A temperature field (C): a [`number`] not below absolute zero.
pub fn temperature(path: &Path, line: usize, field: &str, s: &str) -> Result<f64> {
    let v = number(path, line, field, s)?;
    if v < ABSOLUTE_ZERO_C {
        return Err(HostError::at_field(
            ErrorKind::Malformed,
            path,
            line,
            field,
            format!("`{s}` C is below absolute zero (is the column in C?)"),
        ));
    }
    Ok(v)
}

/// The data-carrying lines of a small CSV text, with their 1-based numbers: a leading
/// UTF-8 BOM, CR line ends and surrounding blanks removed, empty and `#` lines skipped.
pub fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.lines()
        .enumerate()
        .map(|(i, raw)| (i + 1, raw.trim_end_matches('\r').trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}
