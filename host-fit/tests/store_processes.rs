//! The record store under real processes (the release of `host-fit` this crate builds),
//! on SQLite and on a real PostgreSQL server (`tests/src/pg.rs`: `HOSTFIT_TEST_PG`, or
//! a throwaway cluster of this binary's own): eight stations running `batch` on 150 units
//! each at once lose and duplicate nothing; a station killed mid-lot and run again with
//! the same command resumes (the units recorded are kept, not recomputed, never
//! `error`; the rest are done; the summary is whole); a new store is readable by the
//! group and others as the umask allows.
use host_fit::simulate::{simulate, SimConfig};
use host_fit::store::record::{blob_run_id, Command, Record, Trace};
use host_fit::store::{Location, Store};
use std::path::{Path, PathBuf};
use std::process::{Command as Process, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

#[path = "../../tests/src/pg.rs"]
#[allow(dead_code)]
mod pg;

/// Units per station.
const UNITS: usize = 50;
/// Stations writing at once.
const STATIONS: usize = 8;
/// The killed station's lot: this many copies of the 50 units.
const KILLED_COPIES: usize = 8;
/// Each of the eight stations' lots: this many copies of the 50 units, more than two
/// chunks of `batch::RECORD_CHUNK`, so that every station writes in at least three
/// transactions however fast it fits (a lot written in one transaction, as 50 units in
/// under a second, cannot interleave with another's, and the test would not show the
/// stations writing at once).
const STATION_COPIES: usize = 3;

/// The recordings of 50 twin units (seeds 1..=50), fast ones (one row per dwell, as a
/// voltmeter that averages each position), made once per test binary.
fn recordings() -> &'static Vec<String> {
    static R: OnceLock<Vec<String>> = OnceLock::new();
    R.get_or_init(|| {
        (0..UNITS as u64)
            .map(|i| {
                let mut cfg = SimConfig {
                    seed: 1 + i,
                    ..SimConfig::default()
                };
                cfg.unit.serial = "SERIAL".into();
                cfg.schedule.dwell_means = true;
                simulate(&cfg, |_| {}).unwrap().csv
            })
            .collect()
    })
}

/// A lot of the 50 units, serials `PREFIX-i`, in `dir`.
fn lot(dir: &Path, prefix: &str) {
    lot_of(dir, prefix, 1);
}

/// A lot of `copies` x 50 units (each recording under `copies` serials), in `dir`.
fn lot_of(dir: &Path, prefix: &str, copies: usize) {
    std::fs::create_dir_all(dir).unwrap();
    let all = recordings().iter().cycle().take(copies * UNITS);
    for (i, csv) in all.enumerate() {
        let serial = format!("{prefix}-{i:03}");
        let text = csv.replacen("# unit=SERIAL", &format!("# unit={serial}"), 1);
        assert_ne!(&text, csv);
        std::fs::write(dir.join(format!("{serial}.csv")), text).unwrap();
    }
}

fn batch(dir: &Path, out: &Path, db: &str, station: &str) -> Process {
    let mut c = Process::new(env!("CARGO_BIN_EXE_host-fit"));
    c.arg("batch")
        .arg(dir)
        .arg("--out")
        .arg(out)
        .args(["--db", db, "--jobs", "1", "--station", station])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

fn store(db: &str) -> Store {
    Store::open_existing(Location::parse(db).unwrap()).unwrap()
}

/// Every record is whole: its input hash, a blob with a CRC that checks and its own run
/// id in it, coefficients, a verdict that is no error, a test record.
fn assert_whole(all: &[Record]) {
    for r in all {
        assert_eq!(r.command, Command::Batch);
        assert_eq!(r.input_sha256.as_ref().map(String::len), Some(64), "{r:?}");
        let blob = r.blob.as_ref().expect("a blob");
        let n = blob.len();
        assert_eq!(
            Some(firmware_core::crc::crc32(&blob[..n - 4])),
            r.blob_crc()
        );
        assert_eq!(blob_run_id(blob), Some(r.run_id));
        assert!(r.at_t0.is_some() && r.worst_dg_mg.is_some() && r.test_record.is_some());
        let j = r.judged.as_ref().unwrap();
        assert_eq!(
            j.verdict,
            host_fit::batch::UnitStatus::Pass,
            "{}: {}",
            r.serial,
            j.reason
        );
    }
}

/// The rows of a summary.csv: (unit, acceptance).
fn summary(out: &Path) -> Vec<(String, String)> {
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    r.records()
        .map(|row| {
            let row = row.unwrap();
            (row[0].to_string(), row[2].to_string())
        })
        .collect()
}

fn eight_stations_at_once(root: &Path, db: &str) {
    let mut procs = Vec::new();
    const { assert!(STATION_COPIES * UNITS > 2 * host_fit::batch::RECORD_CHUNK) };
    let per_station = STATION_COPIES * UNITS;
    // every lot written before the first station starts, so they start together
    for k in 0..STATIONS {
        lot_of(
            &root.join(format!("lot-{k}")),
            &format!("S{k}"),
            STATION_COPIES,
        );
    }
    for k in 0..STATIONS {
        let dir = root.join(format!("lot-{k}"));
        let out = root.join(format!("out-{k}"));
        procs.push((
            k,
            out.clone(),
            batch(&dir, &out, db, &format!("ST-{k}")).spawn().unwrap(),
        ));
    }
    for (k, out, p) in procs {
        let o = p.wait_with_output().unwrap();
        assert!(
            o.status.success(),
            "station {k}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(summary(&out).len(), per_station);
    }
    let all = store(db).all().unwrap();
    assert_eq!(
        all.len(),
        STATIONS * per_station,
        "every unit of every station recorded"
    );
    let mut runs: Vec<String> = all.iter().map(|r| r.run_id.to_string()).collect();
    runs.sort();
    runs.dedup();
    assert_eq!(runs.len(), STATIONS * per_station, "run ids are unique");
    let mut serials: Vec<&str> = all.iter().map(|r| r.serial.as_str()).collect();
    serials.sort();
    serials.dedup();
    assert_eq!(serials.len(), STATIONS * per_station, "no unit twice");
    for k in 0..STATIONS {
        let mine: Vec<&Record> = all
            .iter()
            .filter(|r| r.lot.as_deref() == Some(&format!("lot-{k}")))
            .collect();
        assert_eq!(mine.len(), per_station);
        assert!(mine.iter().all(|r| r.serial.starts_with(&format!("S{k}-"))
            && r.trace.station.as_deref() == Some(&format!("ST-{k}"))));
    }
    // they wrote at the same time: the stations' records interleave in the table
    let first_last = |k: usize| {
        let ids: Vec<i64> = all
            .iter()
            .filter(|r| r.trace.station.as_deref() == Some(&format!("ST-{k}")))
            .map(|r| r.id)
            .collect();
        (*ids.iter().min().unwrap(), *ids.iter().max().unwrap())
    };
    let (a0, a1) = first_last(0);
    assert!(
        (1..STATIONS).any(|k| {
            let (b0, b1) = first_last(k);
            a0 < b1 && b0 < a1
        }),
        "not concurrent"
    );
    assert_whole(&all);
}

#[test]
fn eight_stations_writing_one_sqlite_store_lose_and_duplicate_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("line.sqlite").display().to_string();
    eight_stations_at_once(tmp.path(), &db);
    let c = rusqlite::Connection::open(&db).unwrap();
    let ok: String = c
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    assert_eq!(ok, "ok");
}

#[test]
fn eight_stations_writing_one_postgresql_store_lose_and_duplicate_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let db = pg::database("eight");
    eight_stations_at_once(tmp.path(), &db);
}

/// A station killed (SIGKILL) once its first records are in, then run again with the
/// same command, no `--force`.
fn killed_and_run_again(root: &Path, db: &str) {
    let dir = root.join("lot-k");
    // a unit of one row per dwell fits in a few ms: a lot long enough (seconds) that the
    // writer's first chunk (after FLUSH_AFTER) lands well before the lot's end
    let units = KILLED_COPIES * UNITS;
    lot_of(&dir, "K", KILLED_COPIES);
    let out = root.join("out");
    let mut p = batch(&dir, &out, db, "ST-K").spawn().unwrap();
    let t = Instant::now();
    let count = || {
        Store::open_existing(Location::parse(db).unwrap())
            .and_then(|mut s| s.count())
            .unwrap_or(0)
    };
    while count() == 0 {
        assert!(
            t.elapsed() < Duration::from_secs(120),
            "no record in 2 minutes"
        );
        assert!(
            p.try_wait().unwrap().is_none(),
            "the batch ended before it was killed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    p.kill().unwrap();
    p.wait().unwrap();
    let before = store(db).all().unwrap();
    let n = before.len();
    assert_whole(&before);
    assert!(n > 0 && n < units, "{n} records at the kill");
    // the files of the units recorded, as the killed run left them
    let kept: Vec<(PathBuf, Vec<u8>)> = before
        .iter()
        .map(|r| {
            let b = out.join(format!("{}.blob", r.serial));
            let bytes = std::fs::read(&b).unwrap();
            (b, bytes)
        })
        .collect();
    let o = batch(&dir, &out, db, "ST-K").output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        text.contains(&format!("resumed: {n} units already recorded")),
        "{text}"
    );
    assert!(
        text.contains(&format!("{units} pass, 0 fail, 0 error")),
        "{text}"
    );
    let after = store(db).all().unwrap();
    assert_eq!(
        after.len(),
        units,
        "every unit once: {n} kept, the rest done"
    );
    assert_whole(&after);
    // the units recorded before the kill are the same records, their blobs untouched
    for r in &before {
        assert!(after.iter().any(|a| a == r), "{} changed", r.serial);
    }
    for (b, bytes) in kept {
        assert_eq!(std::fs::read(&b).unwrap(), bytes, "{}", b.display());
    }
    // every unit's blob carries its record's run id; the summary is whole
    for r in &after {
        let blob = std::fs::read(out.join(format!("{}.blob", r.serial))).unwrap();
        assert_eq!(blob_run_id(&blob), Some(r.run_id), "{}", r.serial);
        assert!(out.join(format!("{}.test-record.json", r.serial)).exists());
    }
    let rows = summary(&out);
    assert_eq!(rows.len(), units);
    assert!(rows.iter().all(|r| r.1 == "pass"), "{rows:?}");
}

#[test]
fn a_station_killed_mid_lot_resumes_on_sqlite() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("records.sqlite").display().to_string();
    killed_and_run_again(tmp.path(), &db);
}

#[test]
fn a_station_killed_mid_lot_resumes_on_postgresql() {
    let tmp = tempfile::tempdir().unwrap();
    let db = pg::database("killed");
    killed_and_run_again(tmp.path(), &db);
}

#[test]
fn a_new_store_is_readable_as_the_umask_allows() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("lot-u");
    lot(&dir, "U");
    // two units are enough
    for e in std::fs::read_dir(&dir).unwrap().flatten().skip(2) {
        std::fs::remove_file(e.path()).unwrap();
    }
    for (umask, want) in [("022", 0o644), ("002", 0o664), ("077", 0o600)] {
        let out = tmp.path().join(format!("out-{umask}"));
        let st = Process::new("sh")
            .arg("-c")
            .arg(format!(
                "umask {umask} && exec \"$0\" batch \"$1\" --out \"$2\" --jobs 1"
            ))
            .arg(env!("CARGO_BIN_EXE_host-fit"))
            .arg(&dir)
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        let mode = std::fs::metadata(out.join("records.sqlite"))
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, want, "umask {umask}: {mode:o}");
    }
}

/// Every record names where and by whom it was made: the station, the chamber, the
/// tilter and the operator, from the environment (`HOSTFIT_STATION`, `HOSTFIT_CHAMBER`,
/// `HOSTFIT_TILTER`, `HOSTFIT_OPERATOR`: a station's login sets them once) or from the
/// flags, a flag winning over the environment.
#[test]
fn every_record_names_its_station_chamber_tilter_and_operator() {
    let tmp = tempfile::tempdir().unwrap();
    // two lots of two units (a lot run again would resume: nothing new recorded)
    for prefix in ["TR", "TS"] {
        let dir = tmp.path().join(prefix);
        std::fs::create_dir_all(&dir).unwrap();
        for (i, csv) in recordings().iter().take(2).enumerate() {
            let serial = format!("{prefix}-{i}");
            let text = csv.replacen("# unit=SERIAL", &format!("# unit={serial}"), 1);
            std::fs::write(dir.join(format!("{serial}.csv")), text).unwrap();
        }
    }
    let db = tmp.path().join("line.sqlite").display().to_string();
    // every field of the trace, by its own name: a field added to `Trace` is tested here
    // without a change to this test
    let names = Trace::names();
    let run = |lot: &str, out: &str, flags: &[String]| {
        let mut p = Process::new(env!("CARGO_BIN_EXE_host-fit"));
        p.arg("batch")
            .arg(tmp.path().join(lot))
            .arg("--out")
            .arg(tmp.path().join(out))
            .args(["--db", &db, "--jobs", "1"])
            .args(flags);
        for n in &names {
            p.env(format!("HOSTFIT_{}", n.to_uppercase()), format!("{n}-env"));
        }
        let o = p.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run("TR", "from-env", &[]);
    let flags: Vec<String> = names
        .iter()
        .flat_map(|n| [format!("--{n}"), format!("{n}-flag")])
        .collect();
    run("TS", "from-flags", &flags);
    let all = store(&db).all().unwrap();
    assert_eq!(all.len(), 4);
    let by = |from: &str| -> Vec<(String, Option<String>)> {
        names
            .iter()
            .map(|n| (n.clone(), Some(format!("{n}-{from}"))))
            .collect()
    };
    let traces: Vec<Vec<(String, Option<String>)>> = all.iter().map(|r| r.trace.fields()).collect();
    let (env, flag) = (by("env"), by("flag"));
    assert_eq!(
        traces,
        vec![env.clone(), env, flag.clone(), flag],
        "{all:?}"
    );
    // the named fields are among them
    for n in ["station", "chamber", "tilter", "operator"] {
        assert!(names.iter().any(|x| x == n), "{n}");
    }
}
