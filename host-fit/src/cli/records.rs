//! The record store on the command line: what `fit`, `verify` and `diagnose` record
//! with `--db` (one record per run, written before any file, so that no blob leaves the
//! tool without its record), `history` and `trend`, and how the tool was run (every
//! option with its value, defaults included, read from the parser's matches).
use super::args::{Cli, Command, HistoryArgs, RecordArgs, StoreAction, StoreArgs, TrendArgs};
use super::common::w;
use crate::acceptance::Acceptance;
use crate::blob::Inspection;
use crate::data::recording::Recording;
use crate::diagnose::contract::Contract;
use crate::diagnose::Diagnosis;
use crate::error::{ErrorKind, HostError, Result};
use crate::fit::pipeline::FitOutcome;
use crate::fit::predict::coefficient_sigma;
use crate::output::{check_writable, json, write_atomic};
use crate::store::history::{history as unit_history, stored_blob};
use crate::store::record::{sha256_file, stamp, AtT0, Command as Recorded, Record, Trace};
use crate::store::schema::Mode;
use crate::store::trend::{parse_rules, trend as make_trend, Reference};
use crate::store::{clock, Filter, Invocation, Location, Store, Target};
use crate::verify::Verification;
use clap::{ArgMatches, CommandFactory, FromArgMatches};
use firmware_core::blob::Blob;
use firmware_core::temperature::Calibration;
use std::io::Write;
use std::path::Path;

/// Default reference of `trend`: the first this many units.
pub const DEFAULT_REFERENCE: usize = 50;

/// The options that name a record store: their values are recorded without a password.
const STORE_OPTIONS: [&str; 3] = ["db", "src", "dst"];

/// Every option of the subcommand in `m`, with its value (`null` when not given and
/// without a default; flags as booleans); a store's URL without its password.
fn options(name: &str, m: &ArgMatches) -> serde_json::Map<String, serde_json::Value> {
    use serde_json::Value;
    let mut out = serde_json::Map::new();
    let cmd = Cli::command();
    let Some(sub) = cmd.find_subcommand(name) else {
        return out;
    };
    for arg in sub.get_arguments() {
        let id = arg.get_id().as_str();
        if id == "help" || id == "version" {
            continue;
        }
        let raw: Vec<String> = m
            .try_get_raw(id)
            .ok()
            .flatten()
            .map(|v| v.map(|s| s.to_string_lossy().into_owned()).collect())
            .unwrap_or_default();
        let v = match raw.as_slice() {
            [] => Value::Null,
            [one] if !arg.get_action().takes_values() => Value::Bool(one == "true"),
            [one] if STORE_OPTIONS.contains(&id) => Value::String(
                Location::parse(one).map_or_else(|_| "(not a store)".into(), |l| l.to_string()),
            ),
            [one] => Value::String(one.clone()),
            many => Value::Array(many.iter().cloned().map(Value::String).collect()),
        };
        out.insert(id.to_string(), v);
    }
    out
}

impl Command {
    /// The record options of a command that records.
    fn record_args(&mut self) -> Option<&mut RecordArgs> {
        match self {
            Command::Fit(a) => Some(&mut a.record),
            Command::Verify(a) => Some(&mut a.record),
            Command::Diagnose(a) => Some(&mut a.record),
            Command::Batch(a) => Some(&mut a.record),
            Command::TempFit(_)
            | Command::Identify(_)
            | Command::Report(_)
            | Command::Blind(_)
            | Command::Simulate(_)
            | Command::Plan(_)
            | Command::Demo(_)
            | Command::FwVectors(_)
            | Command::Inspect(_)
            | Command::History(_)
            | Command::Trend(_)
            | Command::Store(_) => None,
        }
    }
}

/// Parse the command line, keeping how the tool was run for its record.
pub(super) fn parse<I, T>(args: I) -> std::result::Result<Cli, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let m = Cli::command().try_get_matches_from(args)?;
    let mut cli = Cli::from_arg_matches(&m)?;
    if let (Some((name, sub)), Some(r)) = (m.subcommand(), cli.command.record_args()) {
        r.invocation = Some(Invocation {
            command: name.to_string(),
            options: options(name, sub),
            started: Some(clock::now()),
        });
    }
    Ok(cli)
}

/// Where and by whom, from the flags (and their environment variables); the operator
/// else the login name.
fn trace(a: &RecordArgs) -> Trace {
    let login = || crate::store::location::environment().login.clone();
    let mut t = a.trace.0.clone();
    t.operator = t.operator.or_else(login);
    t
}

/// Where to record, when `--db` is given.
pub(super) fn target(a: &RecordArgs) -> Result<Option<Target>> {
    a.db.as_deref()
        .map(|db| {
            Ok(Target {
                db: Location::parse(db)?,
                lot: a.lot.clone(),
                trace: trace(a),
                invocation: a.invocation.clone(),
            })
        })
        .transpose()
}

/// A run being recorded: where, the unit, its recording, where notes go.
pub(super) struct Run<'a> {
    /// The record options.
    pub args: &'a RecordArgs,
    /// The unit's serial (as in its blob).
    pub serial: &'a str,
    /// Its recording.
    pub rec: &'a Recording,
    /// Notes.
    pub err: &'a mut dyn Write,
}

impl Run<'_> {
    /// Fill a new record of `command` with `fill` and append it to the store; a note
    /// names the run. Returns the record (None without `--db`, when nothing happens).
    fn save(
        self,
        command: Recorded,
        fill: impl FnOnce(&mut Record) -> Result<()>,
    ) -> Result<Option<Record>> {
        let Some(t) = target(self.args)? else {
            return Ok(None);
        };
        // opened (and checked) before the record is made: a bad store is reported
        // before anything is written
        let mut store = Store::open(&t.db)?;
        let mut r = t.record(command, self.serial, &self.rec.path)?;
        r.input_sha256 = Some(sha256_file(&self.rec.path)?);
        r.output_unit = Some(self.rec.output_unit.clone());
        fill(&mut r)?;
        store.append(std::slice::from_mut(&mut r))?;
        let _ = writeln!(
            self.err,
            "note: recorded as run {} in {} (host-fit history {} --db {})",
            r.run_id, t.db, self.serial, t.db
        );
        Ok(Some(r))
    }
}

/// `fit --db`: the model, its coefficients at T0 with their 1-sigma, the blob. Returns
/// the blob to write (as recorded).
pub(super) fn fit(
    run: Run<'_>,
    oc: &FitOutcome,
    cal: &Calibration<f64>,
    blob: Vec<u8>,
) -> Result<Vec<u8>> {
    let sigma = coefficient_sigma(&oc.fit, &oc.noise, cal.t0_c);
    let model = oc.fit.basis.describe();
    let saved = run.save(Recorded::Fit, |r| {
        r.model = Some(model);
        r.at_t0 = Some(AtT0 {
            t0_c: cal.t0_c,
            values: cal.at_t0(),
            sigma: Some(sigma),
        });
        r.blob = Some(stamp(&blob, r.run_id)?);
        Ok(())
    })?;
    Ok(saved.and_then(|r| r.blob).unwrap_or(blob))
}

/// `fit --db` on the dynamic route: the model with its dynamics, its coefficients at T0
/// with their 1-sigma, the blob. Returns the blob to write (as recorded).
pub(super) fn fit_dynamic(
    run: Run<'_>,
    d: &crate::fit::route::dynamic::DynamicFit<'_>,
    cal: &Calibration<f64>,
    blob: Vec<u8>,
) -> Result<Vec<u8>> {
    let sigma = crate::model::metrics::coefficient_sigma(&d.data, &d.flashed.fit, cal.t0_c);
    let model = d.describe();
    let saved = run.save(Recorded::Fit, |r| {
        r.model = Some(model);
        r.at_t0 = Some(AtT0 {
            t0_c: cal.t0_c,
            values: cal.at_t0(),
            sigma: Some(sigma),
        });
        r.blob = Some(stamp(&blob, r.run_id)?);
        Ok(())
    })?;
    Ok(saved.and_then(|r| r.blob).unwrap_or(blob))
}

/// The worst compensated |dg| of a verification, mg.
pub(super) fn worst_dg(v: &Verification) -> Option<f64> {
    v.max_by_temperature
        .iter()
        .map(|t| t.max_abs_dg_mg)
        .reduce(f64::max)
}

/// `verify --db`: the blob verified, its model and coefficients, the verdict, the worst
/// |dg|.
pub(super) fn verify(
    run: Run<'_>,
    (b, bytes): (&Blob, &[u8]),
    v: &Verification,
    acc: &Acceptance,
) -> Result<()> {
    run.save(Recorded::Verify, |r| {
        r.model = Some(Inspection::of(b, bytes.len()).model);
        let c = &b.calibration;
        r.at_t0 = Some(AtT0 {
            t0_c: f64::from(c.t0_c),
            values: c.at_t0().map(f64::from),
            sigma: None,
        });
        r.blob = Some(bytes.to_vec());
        r.worst_dg_mg = worst_dg(v);
        r.with_verdict(acc.acceptance, &acc.reason);
        Ok(())
    })?;
    Ok(())
}

/// `diagnose --db`: the diagnosis' verdict and findings, the flashed model, its
/// coefficients at T0, the blob (with `--out`). Returns the blob to write (as recorded).
pub(super) fn diagnose(
    run: Run<'_>,
    d: &Diagnosis,
    c: &Contract,
    blob: Option<Vec<u8>>,
) -> Result<Option<Vec<u8>>> {
    let cal = d.calibration(run.rec.t0_c).ok();
    let saved = run.save(Recorded::Diagnose, |r| {
        r.model = Some(if c.flashed.model.is_empty() {
            c.final_model.temperature_model.clone()
        } else {
            format!(
                "{} + {}",
                c.final_model.temperature_model,
                c.flashed.model.join(" + ")
            )
        });
        r.at_t0 = cal.map(|cal| AtT0 {
            t0_c: cal.t0_c,
            values: cal.at_t0(),
            sigma: None,
        });
        r.blob = blob.as_deref().map(|b| stamp(b, r.run_id)).transpose()?;
        r.with_diagnosis(c)
    })?;
    Ok(match saved {
        Some(r) => r.blob,
        None => blob,
    })
}

pub(super) fn history(a: HistoryArgs, out: &mut dyn Write) -> Result<()> {
    if let Some(o) = &a.out {
        check_writable(o, a.force)?;
    }
    let mut store = Store::open_existing(Location::parse(&a.db)?)?;
    if let (Some(run), Some(o)) = (&a.blob, &a.out) {
        let (id, bytes) = stored_blob(&mut store, &a.serial, run)?;
        write_atomic(o, &bytes, a.force)?;
        return w(
            out,
            format!(
                "wrote {} ({} bytes, CRC {:#010x}): the blob of run {id} of unit {}, bit for bit",
                o.display(),
                bytes.len(),
                crate::store::record::blob_crc(&bytes).unwrap_or(0),
                a.serial
            ),
        );
    }
    if a.test_record {
        return w(out, test_record(&mut store, &a.serial, a.run.as_deref())?);
    }
    let h = unit_history(&mut store, &a.serial)?;
    if h.records.is_empty() {
        // the store's location as it prints (a URL without its password)
        return Err(HostError::new(
            ErrorKind::Invalid,
            format!(
            "{}: no records of unit `{}` in this store (serials are matched exactly, case and all)",
            Location::parse(&a.db)?,
            a.serial
        ),
        ));
    }
    if a.json {
        w(out, json(&h)?)
    } else {
        w(out, h.text())
    }
}

/// The test record (JSON) of `serial`'s newest record that has one, or of run `run`.
fn test_record(store: &mut Store, serial: &str, run: Option<&str>) -> Result<String> {
    let records = store.records(&Filter::serial(serial))?;
    let run = run.map(str::to_ascii_lowercase);
    let hit = records.iter().rev().find(|r| {
        r.test_record.is_some()
            && run
                .as_deref()
                .is_none_or(|p| r.run_id.to_string().starts_with(p))
    });
    match hit {
        Some(r) => json(&r.test_record),
        None => Err(HostError::in_file(
            ErrorKind::Store,
            store.path(),
            format!(
                "unit `{serial}` has no test record{} (batch units have one; serials are matched exactly)",
                run.map(|p| format!(" of run {p}")).unwrap_or_default()
            ),
        )),
    }
}

/// `store migrate` and `store copy`.
pub(super) fn store(a: StoreArgs, out: &mut dyn Write) -> Result<()> {
    match a.action {
        StoreAction::Migrate { db } => {
            let l = Location::parse(&db)?;
            Store::open_as(l.clone(), Mode::Migrate)?;
            w(
                out,
                format!(
                    "{l}: a record store of schema version {}",
                    crate::store::schema::SCHEMA_VERSION
                ),
            )
        }
        StoreAction::Copy { src, dst } => {
            let (s, d) = (Location::parse(&src)?, Location::parse(&dst)?);
            if s == d {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("store copy: {s} is both source and destination"),
                ));
            }
            let mut from = Store::open_existing(s.clone())?;
            let mut to = Store::open(d.clone())?;
            let c = crate::store::copy::copy(&mut from, &mut to)?;
            w(
                out,
                format!(
                    "copied {} records of {s} into {d} ({} there already; every record of the source is in the copy)",
                    c.written, c.already
                ),
            )
        }
    }
}

pub(super) fn trend(a: TrendArgs, out: &mut dyn Write) -> Result<()> {
    check_writable(&a.out, a.force)?;
    let rules = parse_rules(&a.rules)?;
    let reference = match (&a.reference_from, &a.reference_to, a.reference_first) {
        (Some(f), Some(t), _) => Reference::Between(
            clock::bound("--reference-from", f, false)?,
            clock::bound("--reference-to", t, true)?,
        ),
        (_, _, Some(0)) => {
            return Err(HostError::new(
                ErrorKind::Invalid,
                "--reference-first 0: the limits need reference units (2 or more)",
            ))
        }
        (_, _, n) => Reference::First(n.unwrap_or(DEFAULT_REFERENCE)),
    };
    let mut store = Store::open_existing(Location::parse(&a.db)?)?;
    let t = make_trend(&mut store, reference, &rules)?;
    let html = crate::report::trend::trend_report(&t)?;
    write_atomic(&a.out, html.as_bytes(), a.force)?;
    if a.json {
        w(out, json(&t)?)
    } else {
        w(out, t.text())?;
        w(out, format!("report: {}", a.out.display()))
    }
}

/// The store a batch records into: `--db`, else records.sqlite in its output folder
/// (none with `--no-db`); the lot: `--lot`, else the folder's name.
pub(super) fn batch_store(
    dir: &Path,
    out: &Path,
    a: &RecordArgs,
    no_db: bool,
) -> Result<Option<Target>> {
    if no_db {
        return Ok(None);
    }
    let db = match &a.db {
        Some(db) => Location::parse(db)?,
        None => Location::Sqlite(out.join("records.sqlite")),
    };
    Ok(Some(Target {
        db,
        lot: a.lot.clone().or_else(|| {
            dir.canonicalize()
                .ok()
                .unwrap_or_else(|| dir.to_path_buf())
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
        }),
        trace: trace(a),
        invocation: a.invocation.clone(),
    }))
}
