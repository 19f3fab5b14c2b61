//! A real PostgreSQL server for the tests, never a mock: the one whose URL
//! `HOSTFIT_TEST_PG` gives (`cargo xtask test` starts a throwaway cluster and sets it;
//! the URL's user must be allowed to create databases), else a throwaway cluster of
//! this test binary's own, started once (the same code as xtask's: initdb and pg_ctl as
//! the `postgres` user, a private port and socket folder, trust on 127.0.0.1 only) and
//! stopped by a watchdog when the binary ends. Without a server binary a test fails
//! saying how to get one; it never passes without a server. Each test takes a database
//! of its own ([`database`]), so tests run in parallel.
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

#[path = "../../xtask/src/pgcluster.rs"]
mod cluster;

pub use cluster::TEST_PG_VAR;

/// The URL of the server's `postgres` database without its name: `postgresql://u@h:p/`.
fn server() -> &'static str {
    static SERVER: OnceLock<Result<String, String>> = OnceLock::new();
    let r = SERVER.get_or_init(|| {
        if let Ok(url) = std::env::var(TEST_PG_VAR) {
            let cut = url.split('?').next().unwrap_or_default();
            let at = cut
                .rfind('/')
                .filter(|i| *i > "postgresql://".len())
                .unwrap_or(cut.len());
            return Ok(format!("{}/", &cut[..at]));
        }
        // kept past the test process: the cluster's own watchdog removes it once this
        // process has ended (stop_after)
        let dir = tempfile::Builder::new()
            .prefix("host-fit-pg-")
            .tempdir()
            .map_err(|e| format!("no temporary folder for the cluster: {e}"))?
            .keep();
        let c = cluster::Cluster::start(&dir, false)?;
        let base = c.url("");
        c.stop_after(std::process::id())?;
        Ok(base)
    });
    match r {
        Ok(u) => u,
        Err(e) => panic!(
            "these tests need a PostgreSQL server: set {TEST_PG_VAR}=postgresql://USER@HOST:PORT/postgres (a user that may create databases), or install Debian's server (apt-get install postgresql) for a throwaway cluster (cargo xtask test does both): {e}"
        ),
    }
}

/// A new, empty database on the test server for the test `name`: its URL.
pub fn database(name: &str) -> String {
    static N: AtomicUsize = AtomicUsize::new(0);
    let base = server();
    let db: String = format!(
        "hf_{}_{}_{}",
        name.chars()
            .map(|c| if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            })
            .take(30)
            .collect::<String>(),
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    );
    let mut admin = postgres::Client::connect(&format!("{base}postgres"), postgres::NoTls)
        .unwrap_or_else(|e| panic!("cannot reach the test server {base}: {e}"));
    admin
        .batch_execute(&format!("CREATE DATABASE \"{db}\""))
        .unwrap_or_else(|e| panic!("CREATE DATABASE {db}: {e}"));
    format!("{base}{db}")
}
