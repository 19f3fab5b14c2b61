//! `host-fit store copy SRC DST`: every record of one store into another, either
//! backend to either (a station's SQLite file into the line's PostgreSQL database, or
//! the server's store into a file for an audit). Records keep their run ids, times and
//! blobs bit for bit, and come in the order they were written (their new `id`s follow
//! it); a record whose run id the destination already holds is not copied again, so a
//! copy cut short is finished by running it again, and stations' stores are merged by
//! copying each in turn. Then every run id of the source is checked to be in the
//! destination.
use super::db::{Filter, Store};
use crate::error::{ErrorKind, HostError, Result};
use std::collections::HashSet;

/// Records read and written per transaction.
pub const COPY_CHUNK: i64 = 1000;

/// What a copy did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Copied {
    /// Records in the source.
    pub source: usize,
    /// Records written to the destination.
    pub written: usize,
    /// Records the destination held already (same run id).
    pub already: usize,
}

/// The run ids a store holds.
fn run_ids(s: &mut Store) -> Result<HashSet<String>> {
    Ok(s.select(&["run_id".to_string()], &Filter::default())?
        .iter()
        .filter_map(|r| r.text("run_id"))
        .collect())
}

/// Copy every record of `src` into `dst`.
pub fn copy(src: &mut Store, dst: &mut Store) -> Result<Copied> {
    let mut have = run_ids(dst)?;
    let mut c = Copied {
        source: 0,
        written: 0,
        already: 0,
    };
    let mut after = 0;
    loop {
        let f = Filter {
            after_id: Some(after),
            limit: Some(COPY_CHUNK),
            ..Filter::default()
        };
        let records = src.records(&f)?;
        let Some(last) = records.last() else { break };
        after = last.id;
        let n = records.len();
        c.source += n;
        let mut fresh: Vec<_> = records
            .into_iter()
            .filter(|r| !have.contains(&r.run_id.to_string()))
            .collect();
        c.already += n - fresh.len();
        for r in &mut fresh {
            r.id = 0;
        }
        dst.append(&mut fresh)?;
        c.written += fresh.len();
        have.extend(fresh.iter().map(|r| r.run_id.to_string()));
    }
    let now = run_ids(dst)?;
    let missing = run_ids(src)?
        .into_iter()
        .filter(|r| !now.contains(r))
        .count();
    if missing > 0 {
        return Err(HostError::in_file(ErrorKind::Store, dst.path(),
            format!("{missing} records of {} are not in the copy (written meanwhile?): run the copy again", src.location()),
        ));
    }
    Ok(c)
}
