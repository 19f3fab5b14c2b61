//! A large record store for `cargo xtask bench`: `fill_store SOURCE OUT N` writes N
//! records to OUT (a new store), each a copy of a record of SOURCE (a real batch's store,
//! taken in turn) under a serial and run id of its own, in lots of 1000 units one second
//! apart, 10 000 records a transaction.
use host_fit::store::record::RunId;
use host_fit::store::{clock, Store};
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [source, out, n] = args.as_slice() else {
        eprintln!("usage: fill_store SOURCE_STORE NEW_STORE N");
        std::process::exit(2);
    };
    let n: usize = n.parse().expect("N is a number");
    let fail = |e: host_fit::error::HostError| -> ! {
        eprintln!("error: {e}");
        std::process::exit(1)
    };
    let src = Store::open_existing(Path::new(source))
        .and_then(|s| s.all())
        .unwrap_or_else(|e| fail(e));
    if src.is_empty() {
        fail(host_fit::error::HostError::new(
            host_fit::error::ErrorKind::Insufficient,
            "the source store has no records",
        ));
    }
    if Path::new(out).exists() {
        fail(host_fit::error::HostError::in_file(
            host_fit::error::ErrorKind::Exists,
            Path::new(out),
            "exists: give a new path",
        ));
    }
    let mut store = Store::open(Path::new(out)).unwrap_or_else(|e| fail(e));
    let t0 = clock::now_micros() - (n as i64 / 1000 + 1) * 1_000_000;
    let mut chunk = Vec::with_capacity(10_000);
    for i in 0..n {
        let mut r = src[i % src.len()].clone();
        r.id = 0;
        r.run_id = RunId::fresh().unwrap_or_else(|e| fail(e));
        r.serial = format!("UNIT-{i:06}");
        r.lot = Some(format!("LOT-{:03}", i / 1000 + 1));
        r.input = format!("LOT-{:03}/UNIT-{i:06}.csv", i / 1000 + 1);
        r.time_utc = clock::rfc3339(t0 + (i / 1000) as i64 * 1_000_000);
        chunk.push(r);
        if chunk.len() == 10_000 || i + 1 == n {
            store.append(&mut chunk).unwrap_or_else(|e| fail(e));
            chunk.clear();
        }
    }
    println!("{n} records in {out}");
}
