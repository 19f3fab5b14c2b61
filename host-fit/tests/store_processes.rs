//! The record store under real processes (the release of `host-fit` this crate builds):
//! two `batch` processes writing one store at once lose nothing, and a `batch` killed
//! mid-way leaves a store that opens, passes SQLite's integrity check and holds only
//! whole records, to which a new batch appends.
use host_fit::simulate::{simulate, SimConfig};
use host_fit::store::record::Command;
use host_fit::store::Store;
use std::path::Path;
use std::process::{Command as Process, Stdio};
use std::time::{Duration, Instant};

/// A folder of the test's own, named after it, removed when the test ends (passed or
/// failed).
fn tempdir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("hf-store-{name}-"))
        .tempdir()
        .unwrap()
}

/// `n` simulated units of the paper's profile (serials `PREFIX-i`) in `dir`.
fn units(dir: &Path, prefix: &str, n: u64, seed0: u64) {
    std::fs::create_dir_all(dir).unwrap();
    for i in 0..n {
        let mut cfg = SimConfig {
            seed: seed0 + i,
            ..SimConfig::default()
        };
        cfg.unit.serial = format!("{prefix}-{i}");
        let sim = simulate(&cfg, |_| {}).unwrap();
        std::fs::write(dir.join(format!("{prefix}-{i:03}.csv")), sim.csv).unwrap();
    }
}

fn batch(dir: &Path, out: &Path, db: &Path) -> Process {
    let mut c = Process::new(env!("CARGO_BIN_EXE_host-fit"));
    c.arg("batch")
        .arg(dir)
        .arg("--out")
        .arg(out)
        .arg("--db")
        .arg(db)
        .args(["--jobs", "1", "--force"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

/// Every record of a batch is whole: its run, input hash, blob with a CRC that checks,
/// coefficients and verdict.
fn assert_whole(s: &Store) {
    for r in s.all().unwrap() {
        assert_eq!(r.command, Command::Batch);
        assert_eq!(r.input_sha256.as_ref().map(String::len), Some(64), "{r:?}");
        let blob = r.blob.as_ref().expect("a blob");
        let n = blob.len();
        assert_eq!(
            Some(firmware_core::crc::crc32(&blob[..n - 4])),
            r.blob_crc(),
            "{}",
            r.serial
        );
        assert!(r.at_t0.is_some() && r.judged.is_some() && r.worst_dg_mg.is_some());
    }
}

fn integrity(db: &Path) -> String {
    let c = rusqlite::Connection::open(db).unwrap();
    c.query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap()
}

#[test]
fn two_batches_writing_one_store_at_once_lose_nothing() {
    let tmp = tempdir("two");
    let root = tmp.path();
    let (a, b) = (root.join("lot-a"), root.join("lot-b"));
    // 40 units each: several seconds of work, so that each writer commits several
    // chunks (one a second) while the other runs
    units(&a, "A", 40, 100);
    units(&b, "B", 40, 200);
    let db = root.join("shared.sqlite");
    let mut pa = batch(&a, &root.join("out-a"), &db).spawn().unwrap();
    let mut pb = batch(&b, &root.join("out-b"), &db).spawn().unwrap();
    let (ra, rb) = (pa.wait().unwrap(), pb.wait().unwrap());
    let err = |p: std::process::Child| {
        let mut s = String::new();
        use std::io::Read;
        p.stderr.unwrap().read_to_string(&mut s).unwrap();
        s
    };
    assert!(ra.success(), "{}", err(pa));
    assert!(rb.success(), "{}", err(pb));
    let s = Store::open_existing(&db).unwrap();
    let all = s.all().unwrap();
    assert_eq!(all.len(), 80, "every unit of both batches recorded");
    let mut runs: Vec<String> = all.iter().map(|r| r.run_id.to_string()).collect();
    runs.sort();
    runs.dedup();
    assert_eq!(runs.len(), 80, "run ids are unique");
    for (lot, prefix) in [("lot-a", "A-"), ("lot-b", "B-")] {
        let mine: Vec<_> = all
            .iter()
            .filter(|r| r.lot.as_deref() == Some(lot))
            .collect();
        assert_eq!(mine.len(), 40, "{lot}");
        assert!(mine.iter().all(|r| r.serial.starts_with(prefix)));
    }
    // the two wrote at the same time: their records' places in the table interleave
    let ids = |lot: &str| -> Vec<i64> {
        all.iter()
            .filter(|r| r.lot.as_deref() == Some(lot))
            .map(|r| r.id)
            .collect()
    };
    let (ia, ib) = (ids("lot-a"), ids("lot-b"));
    let (a0, a1) = (ia.iter().min().unwrap(), ia.iter().max().unwrap());
    let (b0, b1) = (ib.iter().min().unwrap(), ib.iter().max().unwrap());
    assert!(a0 < b1 && b0 < a1, "not concurrent: ids {ia:?} {ib:?}");
    assert_whole(&s);
    assert_eq!(integrity(&db), "ok");
}

#[test]
fn a_batch_killed_mid_way_leaves_whole_records_and_a_store_that_goes_on() {
    let tmp = tempdir("kill");
    let root = tmp.path();
    let dir = root.join("lot");
    // more units than a few chunks: on a quiet machine the first commit (a chunk, or
    // what was done when the flush timer ran) must still leave units to kill
    let n_units = 3 * host_fit::batch::RECORD_CHUNK;
    units(&dir, "K", n_units as u64, 300);
    let db = root.join("records.sqlite");
    let mut p = batch(&dir, &root.join("out"), &db).spawn().unwrap();
    let t = Instant::now();
    // kill it once a first chunk is in (and long before the last unit)
    let count = |db: &Path| -> i64 {
        rusqlite::Connection::open_with_flags(db, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .and_then(|c| c.query_row("SELECT count(*) FROM runs", [], |r| r.get(0)))
            .unwrap_or(0)
    };
    while count(&db) == 0 {
        assert!(
            t.elapsed() < Duration::from_secs(120),
            "no record in 2 minutes"
        );
        assert!(
            p.try_wait().unwrap().is_none(),
            "the batch ended before it was killed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    p.kill().unwrap();
    p.wait().unwrap();
    let s = Store::open_existing(&db).unwrap();
    let n = s.count().unwrap();
    assert!(n > 0 && n < n_units as i64, "{n} records");
    assert_whole(&s);
    drop(s);
    assert_eq!(integrity(&db), "ok");
    // the store goes on: the batch run again appends every unit
    let o = batch(&dir, &root.join("out"), &db).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = Store::open_existing(&db).unwrap();
    assert_eq!(s.count().unwrap(), n + n_units as i64);
    assert_whole(&s);
}
