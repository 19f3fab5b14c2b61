//! The record store at scale, on SQLite and on PostgreSQL (a throwaway cluster, durable
//! as a plant's server: fsync and synchronous commit on), for `cargo xtask bench`: the
//! records written per second by 8 writers at once (8 `fill_store` processes appending
//! 2000 records each in the batch's chunks of 64, one transaction each), then a store
//! of 100 000 records (copies of the bench batch's records under new serials and run
//! ids) and, through the release binary, `history` of one serial among them and the
//! trend over all of them, against the targets (50 ms, 5 s).
use crate::pgcluster::Cluster;
use std::path::Path;
use std::process::Command;

/// Writers at once, records each, records per transaction (as `batch` writes them).
const WRITERS: usize = 8;
const PER_WRITER: usize = 2000;
const BATCH_CHUNK: usize = 64;

/// Records in the large store.
const LARGE: usize = 100_000;

fn remove_sqlite(p: &Path) {
    for ext in ["", "-wal", "-shm"] {
        let _ = std::fs::remove_file(format!("{}{ext}", p.display()));
    }
}

/// A new database `name` on the cluster: its URL.
fn createdb(c: &Cluster, name: &str) -> Result<String, String> {
    let bin = crate::pgcluster::bindir().ok_or("no PostgreSQL binaries")?;
    let st = Command::new(bin.join("psql"))
        .args([
            "-h",
            "127.0.0.1",
            "-p",
            &c.port.to_string(),
            "-U",
            "postgres",
            "-q",
        ])
        .args(["-c", &format!("CREATE DATABASE {name}"), "postgres"])
        .status()
        .map_err(|e| format!("psql: {e}"))?;
    st.success()
        .then(|| c.url(name))
        .ok_or(format!("CREATE DATABASE {name} failed"))
}

/// Run the writers side by side (spawned first, then waited for): the wall time (s).
fn eight_writers(fill: &Path, source: &Path, out: &str) -> Result<f64, String> {
    let t = std::time::Instant::now();
    let mut children = Vec::new();
    for k in 0..WRITERS {
        let c = Command::new(fill)
            .arg(source)
            .args([out, &PER_WRITER.to_string(), &BATCH_CHUNK.to_string()])
            .arg(format!("W{k}-"))
            .stdout(std::process::Stdio::null())
            .spawn()
            .map_err(|e| format!("fill_store: {e}"))?;
        children.push(c);
    }
    for mut c in children {
        let st = c.wait().map_err(|e| format!("fill_store: {e}"))?;
        if !st.success() {
            return Err(format!("a fill_store writer into {out} failed ({st})"));
        }
    }
    Ok(t.elapsed().as_secs_f64())
}

fn shown(t: f64) -> String {
    if t < 1.0 {
        format!("{:.1} ms", t * 1e3)
    } else {
        format!("{t:.2} s")
    }
}

/// The figures of one backend: 8 writers into `writers_db`, then `LARGE` records into
/// `large_db` and the history and trend timings on it.
fn backend(
    name: &str,
    (bin, fill, source): (&Path, &Path, &Path),
    (writers_db, large_db): (&str, &str),
    trend_out: &Path,
    steps: &mut crate::Steps,
) -> String {
    let mut md = String::new();
    let total = WRITERS * PER_WRITER;
    let w = steps.step(&format!("{name}: {WRITERS} writers at once"), || {
        eight_writers(fill, source, writers_db)
    });
    if let Ok(t) = w {
        md.push_str(&format!(
            "| {name}: {WRITERS} writers at once, {PER_WRITER} records each in transactions of {BATCH_CHUNK} | {:.0} records/s ({total} in {t:.2} s) | |\n",
            total as f64 / t
        ));
    }
    let t = std::time::Instant::now();
    let filled = steps.step(&format!("{name}: a store of {LARGE} records"), || {
        let st = Command::new(fill)
            .arg(source)
            .args([large_db, &LARGE.to_string()])
            .stdout(std::process::Stdio::null())
            .status()
            .map_err(|e| format!("fill_store: {e}"))?;
        st.success()
            .then_some(())
            .ok_or(format!("fill_store into {large_db}: {st}"))
    });
    if filled.is_err() {
        return md;
    }
    md.push_str(&format!(
        "| {name}: write {LARGE} records (10 000 a transaction) | {:.2} s | |\n",
        t.elapsed().as_secs_f64()
    ));
    let cases = [
        (
            format!("{name}: `host-fit history UNIT-054321` among {LARGE} records (a new process: connect, check, query, print)"),
            vec!["history".to_string(), "UNIT-054321".into(), "--db".into(), large_db.into()],
            5,
            0.050,
        ),
        (
            format!("{name}: `host-fit trend` over its {LARGE} calibrations (13 charts, 8 rules, HTML written)"),
            vec!["trend".to_string(), "--db".into(), large_db.into(), "--out".into(), trend_out.display().to_string(), "--force".into()],
            3,
            5.0,
        ),
    ];
    for (what, args, n, target) in cases {
        let timed = steps.step(&what, || {
            crate::bench::best_of(bin, &args, n, &|| {})
                .ok_or(format!("host-fit {} failed", args.join(" ")))
        });
        if let Ok(t) = timed {
            md.push_str(&format!(
                "| {what}, best of {n} | {} | < {} |\n",
                shown(t),
                shown(target)
            ));
        }
    }
    md
}

/// The store's figures on both backends, from the bench batch's store `source`.
pub fn store_figures(bin: &Path, root: &Path, source: &Path, steps: &mut crate::Steps) -> String {
    let dir = root.join("target/bench");
    let mut c = crate::cargo();
    c.args([
        "build",
        "--release",
        "-p",
        "host-fit",
        "--example",
        "fill_store",
    ]);
    if !steps.run("build the fill_store example", c) {
        return String::new();
    }
    let fill = root.join("target/release/examples/fill_store");
    let (w, big) = (
        dir.join("store-writers.sqlite"),
        dir.join("store-100k.sqlite"),
    );
    remove_sqlite(&w);
    remove_sqlite(&big);
    let trend = dir.join("trend-100k.html");
    let mut md = backend(
        "SQLite",
        (bin, &fill, source),
        (&w.display().to_string(), &big.display().to_string()),
        &trend,
        steps,
    );
    let cluster = steps
        .prepare("install postgresql", crate::setup::postgresql)
        .and_then(|()| steps.prepare("start a PostgreSQL cluster", || Cluster::start(&dir, true)));
    let Some(cluster) = cluster else {
        return md;
    };
    let dbs = steps.step("PostgreSQL: create the bench databases", || {
        Ok::<_, String>((createdb(&cluster, "writers")?, createdb(&cluster, "large")?))
    });
    if let Ok((w, big)) = dbs {
        md.push_str(&backend(
            "PostgreSQL",
            (bin, &fill, source),
            (&w, &big),
            &trend,
            steps,
        ));
    }
    md
}

/// Units of the source batch of `cargo xtask bench store`.
const SOURCE_UNITS: u32 = 64;

/// `cargo xtask bench store`: the store's figures alone, from the records of a batch of
/// 64 simulated units of the paper's profile; writes target/bench/store.md.
pub fn store_only(steps: &mut crate::Steps) {
    let root = crate::root();
    let mut c = crate::cargo();
    c.args(["build", "--release", "-p", "host-fit"]);
    if !steps.run("build host-fit", c) {
        return;
    }
    let bin = root.join("target/release/host-fit");
    let dir = root.join("target/bench");
    let units = dir.join("store-units");
    let source = dir.join("store-source.sqlite");
    remove_sqlite(&source);
    let made = steps.step("a batch of 64 units recorded (the records copied)", || {
        std::fs::create_dir_all(&units).map_err(|e| e.to_string())?;
        for seed in 1..=SOURCE_UNITS {
            let p = units.join(format!("unit{seed:03}.csv"));
            if !p.exists() {
                let st = Command::new(&bin)
                    .args(["simulate", "--seed", &seed.to_string(), "--out"])
                    .arg(&p)
                    .output()
                    .map_err(|e| e.to_string())?;
                if !st.status.success() {
                    return Err(format!("host-fit simulate --seed {seed} failed"));
                }
            }
        }
        let o = Command::new(&bin)
            .arg("batch")
            .arg(&units)
            .arg("--out")
            .arg(dir.join("store-source-out"))
            .args(["--force", "--db"])
            .arg(&source)
            .output()
            .map_err(|e| e.to_string())?;
        matches!(o.status.code(), Some(0 | 3))
            .then_some(())
            .ok_or_else(|| String::from_utf8_lossy(&o.stderr).into_owned())
    });
    if made.is_err() {
        return;
    }
    let md = format!(
        "### Record store (`cargo xtask bench store`)\n\n| measure | figure | target |\n|---|---|---|\n{}",
        store_figures(&bin, &root, &source, steps)
    );
    let _ = std::fs::write(dir.join("store.md"), &md);
    println!("{md}");
}
