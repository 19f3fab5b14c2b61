//! The demo, run once and shared: every test that reads what `host-fit demo` writes and
//! prints reads one run of it. The run lives under `target/tmp/`, keyed by a hash of the
//! sources its output depends on (`tests/build.rs`), so the test binaries of one build
//! share it (the first reader runs it, under a file lock) and a changed source gets a
//! fresh one. Tests that change a
//! demo folder copy it first ([`Demo::copy_to`]).
use crate::{cli, repo, s};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One run of `host-fit demo --out DIR --seed 1`.
#[derive(Debug)]
pub struct Demo {
    /// The folder it wrote.
    pub dir: PathBuf,
    /// What it printed.
    pub out: String,
}

impl Demo {
    /// A copy of the demo's folder at `to` (for a test that runs the demo again over it
    /// or otherwise changes it).
    pub fn copy_to(&self, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(&self.dir).unwrap().flatten() {
            let p = e.path();
            if p.is_file() && p.file_name().is_some_and(|n| n != STDOUT) {
                std::fs::copy(&p, to.join(e.file_name())).unwrap();
            }
        }
    }
}

/// Where the fixture keeps what the demo printed (beside what it wrote).
const STDOUT: &str = "demo-stdout.txt";

/// The shared demo run (see the module doc).
pub fn demo() -> &'static Demo {
    static DEMO: OnceLock<Demo> = OnceLock::new();
    DEMO.get_or_init(|| {
        let base = repo().join("target/tmp");
        std::fs::create_dir_all(&base).unwrap();
        let key = env!("DEMO_FIXTURE_KEY");
        let dir = base.join(format!("demo-fixture-{key}"));
        // one writer at a time (test binaries run side by side under nextest); the run
        // goes where it stays (the store and the history print its folder), its output
        // last, so a folder without it is an interrupted run, run again
        let lock = std::fs::File::create(base.join(format!("demo-fixture-{key}.lock"))).unwrap();
        lock.lock().unwrap();
        if !dir.join(STDOUT).is_file() {
            // earlier sources' runs are of no more use
            for e in std::fs::read_dir(&base).unwrap().flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with("demo-fixture-") && !name.contains(key) {
                    let _ = std::fs::remove_dir_all(e.path());
                    let _ = std::fs::remove_file(e.path());
                }
            }
            let _ = std::fs::remove_dir_all(&dir);
            let (code, out, err) = cli(&["demo", "--out", s(&dir), "--seed", "1"]);
            assert_eq!(code, 0, "host-fit demo: {err}");
            std::fs::write(dir.join(STDOUT), &out).unwrap();
        }
        let out = std::fs::read_to_string(dir.join(STDOUT)).unwrap();
        drop(lock);
        Demo { dir, out }
    })
}
