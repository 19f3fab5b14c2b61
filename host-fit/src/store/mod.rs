//! The line's memory: a record store, one interface on two backends chosen by `--db`: a
//! path is an SQLite file (the SQLite compiled into host-fit; a station's own store),
//! `postgresql://user@host:port/database` a database on a PostgreSQL server that every
//! station of a line writes to ([`location`]). Written by `fit`, `verify` and
//! `diagnose` with `--db`, by `batch` (into its output folder unless told otherwise) and
//! by `demo` (into its folder); read by `history`, `trend` and `store copy`.
//!
//! One record per run and unit, never changed or deleted (triggers refuse it): a unit
//! calibrated again keeps every record, and the view `latest_calibrations` (a query, no
//! flag that an update could lose) names each unit's newest calibration.
//!
//! # Schema (version [`schema::SCHEMA_VERSION`]; see [`schema`] for where each backend keeps its version)
//!
//! Table `runs`, one row per record:
//!
//! | column | type | what |
//! |---|---|---|
//! | `id` | INTEGER PRIMARY KEY | order of writing (1, 2, ...) |
//! | `run_id` | TEXT, unique | 16 random bytes as 32 lowercase hex digits; the blob's `run_id` (format 4) |
//! | `serial` | TEXT | the unit's serial (as in its blob) |
//! | `time_utc` | TEXT | when the run started, UTC, RFC 3339 with microseconds (`2026-12-01T18:29:03.123456Z`; text order is time order); a batch's units share it |
//! | `host_fit_version`, `host_fit_commit` | TEXT | the tool that wrote it, and the git commit it was built from (`unknown` outside a checkout) |
//! | `command` | TEXT | `fit`, `verify`, `diagnose`, `batch` (one record per unit) or `demo` (one per model) |
//! | `options` | TEXT (JSON object) | every option of the command with its value, defaults included |
//! | `lot` | TEXT | the lot: a batch's folder name or `--lot`; `--lot` elsewhere; NULL when none was given |
//! | `input`, `input_sha256` | TEXT | the recording as given, and the SHA-256 of its bytes (64 hex digits) |
//! | `output_unit` | TEXT | the recording's output unit: K is in it per g, U0 in it |
//! | `model` | TEXT | the model in the blob (`poly3`, `pwl`, `diagnosed (temp_rate)`, ...) |
//! | `t0_c` | REAL | T0, C |
//! | `kxx` .. `u0z` | REAL | the 12 coefficients at T0 |
//! | `sigma_kxx` .. `sigma_u0z` | REAL | their 1-sigma (fit, batch; NULL where the run does not estimate them) |
//! | `blob`, `blob_crc` | BLOB, INTEGER | the blob made (fit, diagnose `--out`, batch, demo) or verified (verify), bit for bit, and its CRC-32 |
//! | `acceptance`, `reason` | TEXT | `pass`, `fail` or `error` (a batch unit that could not be processed) against the acceptance specification, and why |
//! | `worst_dg_mg` | REAL | the worst compensated \|dg\| over the verification dwells, mg |
//! | `diagnosis_verdict`, `findings` | TEXT, TEXT (JSON) | the diagnosis' verdict and findings, as in its JSON contract |
//! | `station`, `chamber`, `tilter`, `operator`, ... | TEXT | where and by whom: every field of [`trace::Trace`], each added by the version its table names |
//! | `test_record` | TEXT (JSON) | the unit's test record for the line's systems (version 2, batch units; see [`test_record`]) |
//!
//! The columns are defined once, in [`columns`]; PostgreSQL spells the types its way
//! (DOUBLE PRECISION, BIGINT, BYTEA, text in byte order).
//!
//! Indexes `runs_by_serial (serial, id)`, `runs_by_time (time_utc, id)` and
//! `runs_by_lot (lot, id)`; view
//! `latest_calibrations` (the newest record per serial that made a blob and did not end in
//! an error; `verify` records are checks of a blob, not calibrations).
//!
//! # Many writers, no half records
//! Every write is one transaction, one per record or per chunk of a batch, so batches
//! writing one store at once lose nothing, and a writer killed mid-way leaves the
//! records it committed, whole. SQLite runs in WAL mode with `synchronous = FULL`
//! (`BEGIN IMMEDIATE`: a writer waits for another up to [`BUSY_TIMEOUT`]); PostgreSQL
//! takes each station's transactions side by side.
//!
//! # Bad stores
//! A store of a newer schema is refused with its version named; a file that is not an
//! SQLite database, an empty one, one cut short of the length its header states, or
//! another program's database is reported, naming the file, and never re-created or
//! altered.
pub mod clock;
pub mod columns;
pub mod copy;
pub mod db;
pub mod fault;
pub mod history;
pub mod location;
pub mod pg;
pub mod record;
pub mod resume;
pub mod schema;
pub mod sqlite;
pub mod test_document;
pub mod test_record;
pub mod trace;
pub mod trend;

pub use db::{record_columns, Filter, Order, Store, Target, Writer, FLUSH_AFTER};
pub use fault::{db_error, BUSY_TIMEOUT};
pub use location::Location;
pub use record::Invocation;
