//! Output files: written atomically, never over an existing file without `--force`,
//! and the one way JSON and CSV are produced.
use crate::error::{ErrorKind, HostError, Result};
use serde::Serialize;
use std::io::Write;
use std::path::Path;

/// Refuse early (before any work) when `path` exists and `force` is off.
pub fn check_writable(path: &Path, force: bool) -> Result<()> {
    if path.is_dir() {
        return Err(HostError::in_file(
            ErrorKind::Invalid,
            path,
            "is a folder: give the path of a file to write in it (e.g. this folder/unit.blob)",
        ));
    }
    let dir = folder(path);
    if !dir.is_dir() {
        let why = if dir.exists() {
            "is not a folder"
        } else {
            "does not exist"
        };
        return Err(HostError::in_file(
            ErrorKind::Io,
            path,
            format!(
                "cannot be written: `{}` {why} (create the folder first, or give another path)",
                dir.display()
            ),
        ));
    }
    if !force && path.exists() {
        return Err(HostError::in_file(
            ErrorKind::Exists,
            path,
            "exists; refusing to overwrite it (use --force)",
        ));
    }
    Ok(())
}

/// The folder `path` is written in (`.` for a bare file name).
fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Write `bytes` to `path` atomically: a temporary file in the same folder, synced,
/// then moved into place. Without `force` an existing file is never replaced (even one
/// created meanwhile: the final step is a hard link, which fails if the name exists).
/// On any failure the temporary file is removed and nothing is left behind. The file
/// gets the mode a plain create would give (0666 less the user's umask, e.g. 0644), not
/// the temporary file's private 0600: colleagues read the reports on a shared server.
pub fn write_atomic(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    check_writable(path, force)?;
    let dir = folder(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let io = |e: std::io::Error| HostError::io(path, &e);
    let prefix = format!(".{name}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // the mode is given to open(2), which takes the umask off it, as for any new file
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(dir).map_err(io)?;
    tmp.write_all(bytes).map_err(io)?;
    tmp.as_file().sync_all().map_err(io)?;
    let placed = if force {
        tmp.persist(path)
    } else {
        tmp.persist_noclobber(path)
    };
    placed.map(|_| ()).map_err(|e| io(e.error))
}

/// Pretty JSON of a typed output (every JSON the tool writes goes through here).
pub fn json<T: Serialize + ?Sized>(value: &T) -> Result<String> {
    serde_json::to_string_pretty(value)
        .map_err(|e| HostError::new(ErrorKind::Internal, format!("cannot encode JSON: {e}")))
}

/// [`json`] written atomically to `path`.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T, force: bool) -> Result<()> {
    write_atomic(path, json(value)?.as_bytes(), force)
}

/// A CSV text from a header and records (quoted where a field needs it).
pub fn csv<I, R>(header: &[&str], records: I) -> Result<String>
where
    I: IntoIterator<Item = R>,
    R: IntoIterator,
    R::Item: AsRef<[u8]>,
{
    let err = |e: csv::Error| HostError::new(ErrorKind::Internal, format!("cannot write CSV: {e}"));
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header).map_err(err)?;
    for r in records {
        w.write_record(r).map_err(err)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| HostError::new(ErrorKind::Internal, format!("cannot write CSV: {e}")))?;
    String::from_utf8(bytes)
        .map_err(|e| HostError::new(ErrorKind::Internal, format!("CSV is not UTF-8: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_overwrite_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.bin");
        write_atomic(&p, b"one", false).unwrap();
        let e = write_atomic(&p, b"two", false).unwrap_err();
        // the refusal says what to do
        assert_eq!(e.kind(), ErrorKind::Exists);
        assert!(e.to_string().contains("--force"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"one");
        write_atomic(&p, b"two", true).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "no temporary files left");
    }

    #[test]
    fn a_missing_folder_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nodir").join("u.blob");
        let e = write_atomic(&p, b"x", false).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Io);
        let text = e.to_string();
        assert!(
            text.contains("nodir` does not exist") && !text.contains(".u.blob."),
            "{text}"
        );
        std::fs::write(dir.path().join("file"), b"").unwrap();
        let e = check_writable(&dir.path().join("file").join("u.blob"), true).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Io);
        assert!(e.to_string().contains("file` is not a folder"), "{e}");
        let e = check_writable(dir.path(), true).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Invalid);
    }

    #[test]
    fn csv_quotes_fields_with_commas_and_quotes() {
        let s = csv(&["a", "b"], [["x,y", "say \"hi\""]]).unwrap();
        assert_eq!(s, "a,b\n\"x,y\",\"say \"\"hi\"\"\"\n");
    }
}
