//! Database errors said plainly, naming the store: not a database, corrupt, locked too
//! long, not writable, disk full.
use crate::error::{ErrorKind, HostError};
use std::path::Path;
use std::time::Duration;

/// How long a writer waits for another to finish its transaction.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(60);

/// A database error on `path`, said plainly for the cases a user meets.
pub fn db_error(path: &Path, e: rusqlite::Error) -> HostError {
    use rusqlite::ErrorCode as C;
    let m = match e.sqlite_error_code() {
        Some(C::NotADatabase) => {
            format!("is not a record store (not an SQLite database: {e}); it is left as it is")
        }
        Some(C::DatabaseCorrupt) => format!(
            "the record store is corrupt ({e}); it is left as it is: restore it from a copy"
        ),
        Some(C::DatabaseBusy) | Some(C::DatabaseLocked) => format!(
            "the record store stayed locked by another process for {} s ({e})",
            BUSY_TIMEOUT.as_secs()
        ),
        Some(C::ReadOnly) | Some(C::CannotOpen) | Some(C::PermissionDenied) => {
            format!("cannot write the record store ({e})")
        }
        Some(C::DiskFull) => format!("the disk is full: the record was not written ({e})"),
        _ => format!("record store: {e}"),
    };
    HostError::in_file(ErrorKind::Store, path, m)
}
