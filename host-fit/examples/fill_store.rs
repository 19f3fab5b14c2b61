//! Records for `cargo xtask bench`: `fill_store SOURCE OUT N [CHUNK [PREFIX]]` appends N
//! records to the store OUT (a path or a postgresql:// URL; made when missing or
//! empty), each a copy of a record of SOURCE (a real batch's store, taken in turn)
//! under a serial (`PREFIX` and 6 digits, default `UNIT-`) and run id of its own, in
//! lots of 1000 units one second apart, CHUNK records a transaction (default 10 000; a
//! batch writes 64). Several of it at once are several stations writing; it prints the
//! records written and the seconds it took.
use host_fit::store::record::RunId;
use host_fit::store::{clock, Location, Store};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (source, out, n) = match args.as_slice() {
        [s, o, n, ..] => (s, o, n),
        _ => {
            eprintln!("usage: fill_store SOURCE_STORE STORE N [CHUNK [PREFIX]]");
            std::process::exit(2);
        }
    };
    let fail = |e: host_fit::error::HostError| -> ! {
        eprintln!("error: {e}");
        std::process::exit(1)
    };
    let number = |s: &str| -> usize {
        s.parse().unwrap_or_else(|_| {
            fail(host_fit::error::HostError::new(
                host_fit::error::ErrorKind::Invalid,
                format!("`{s}` is not a number"),
            ))
        })
    };
    let n = number(n);
    let chunk = args.get(3).map_or(10_000, |c| number(c)).max(1);
    let prefix = args.get(4).map_or("UNIT-", String::as_str);
    let src = Location::parse(source)
        .and_then(Store::open_existing)
        .and_then(|mut s| s.all())
        .unwrap_or_else(|e| fail(e));
    if src.is_empty() {
        fail(host_fit::error::HostError::new(
            host_fit::error::ErrorKind::Insufficient,
            "the source store has no records",
        ));
    }
    let mut store = Location::parse(out)
        .and_then(Store::open)
        .unwrap_or_else(|e| fail(e));
    let t = std::time::Instant::now();
    let t0 = clock::now_micros() - (n as i64 / 1000 + 1) * 1_000_000;
    let mut buf = Vec::with_capacity(chunk);
    for i in 0..n {
        let mut r = src[i % src.len()].clone();
        r.id = 0;
        r.run_id = RunId::fresh().unwrap_or_else(|e| fail(e));
        r.serial = format!("{prefix}{i:06}");
        r.lot = Some(format!("{prefix}LOT-{:03}", i / 1000 + 1));
        r.input = format!("{prefix}LOT-{:03}/{prefix}{i:06}.csv", i / 1000 + 1);
        r.time_utc = clock::rfc3339(t0 + (i / 1000) as i64 * 1_000_000);
        buf.push(r);
        if buf.len() == chunk || i + 1 == n {
            store.append(&mut buf).unwrap_or_else(|e| fail(e));
            buf.clear();
        }
    }
    println!(
        "{n} records in {:.3} s into {}",
        t.elapsed().as_secs_f64(),
        store.location()
    );
}
