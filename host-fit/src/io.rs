//! Output files: written atomically, never over an existing file without `--force`.
use crate::error::{HostError, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

fn tmp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = format!(".{name}.tmp-{}", std::process::id());
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// The positions of the `want`ed columns in a CSV header line (names case-insensitive),
/// or an error naming the file, the line and the missing column. A header separated by
/// semicolons is refused with that reason (no guessing at the separator).
pub fn header_columns(path: &Path, line: usize, header: &str, want: &[&str]) -> Result<Vec<usize>> {
    if !header.contains(',') && header.contains(';') {
        return Err(HostError::at(path, line, "the header is separated by semicolons; these files are comma-separated, convert the file"));
    }
    let names: Vec<String> = header
        .split(',')
        .map(|s| s.trim().to_ascii_lowercase())
        .collect();
    want.iter()
        .map(|w| {
            names.iter().position(|n| n == w).ok_or_else(|| {
                HostError::at_field(
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
            path,
            line,
            field,
            format!(
                "`{s}` is beyond +-{MAX_ABS_VALUE:e}: too large to fit in double precision \
                 (check the column's unit and scale)"
            ),
        )),
        _ => Err(HostError::at_field(
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

/// Refuse early (before any work) when `path` exists and `force` is off.
pub fn check_writable(path: &Path, force: bool) -> Result<()> {
    if !force && path.exists() {
        return Err(HostError::in_file(
            path,
            "exists; refusing to overwrite it (use --force)",
        ));
    }
    Ok(())
}

/// Write `bytes` to `path` atomically: a temporary file in the same folder, synced,
/// then moved into place. Without `force` an existing file is never replaced (even one
/// created meanwhile: the final step is a hard link, which fails if the name exists).
pub fn write_atomic(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    check_writable(path, force)?;
    let tmp = tmp_path(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        if force {
            std::fs::rename(&tmp, path)
        } else {
            std::fs::hard_link(&tmp, path)?;
            std::fs::remove_file(&tmp)
        }
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(HostError::io(path, &e));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_overwrite_and_leaves_no_temp() {
        let dir = std::env::temp_dir().join(format!("hf-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.bin");
        let _ = std::fs::remove_file(&p);
        write_atomic(&p, b"one", false).unwrap();
        let e = write_atomic(&p, b"two", false).unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        write_atomic(&p, b"two", true).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "no temporary files left");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
