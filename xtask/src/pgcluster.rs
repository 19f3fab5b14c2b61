//! A throwaway PostgreSQL cluster for the tests (std only: `cargo xtask test` and the
//! tests crate's `tests/src/pg.rs` both include this file): Debian's server
//! (`pg_config --bindir`, else the newest `/usr/lib/postgresql/*/bin`), `initdb` into a
//! fresh folder, a private port on 127.0.0.1 and a private socket folder, trust
//! authentication on 127.0.0.1 and the socket only; for the tests without fsync
//! (nothing in it outlives the run), for the benchmark durable as a plant's server. Run as root, `initdb` and `pg_ctl` run as the `postgres` user (the server
//! refuses root). [`Cluster`] stops the server and removes its folder when dropped.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The environment variable that hands a server's URL to the tests.
pub const TEST_PG_VAR: &str = "HOSTFIT_TEST_PG";

/// Debian's server binaries.
pub fn bindir() -> Option<PathBuf> {
    let from_config = Command::new("pg_config")
        .arg("--bindir")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()))
        .filter(|p| p.join("initdb").exists());
    from_config.or_else(|| {
        let mut dirs: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
            .ok()?
            .flatten()
            .filter_map(|e| {
                let v = e.file_name().to_string_lossy().parse::<u32>().ok()?;
                let bin = e.path().join("bin");
                bin.join("initdb").exists().then_some((v, bin))
            })
            .collect();
        dirs.sort();
        dirs.pop().map(|d| d.1)
    })
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

/// `program args` as the `postgres` user when we are root, else as ourselves.
fn as_server_user(program: &Path, args: &[&str]) -> Command {
    if is_root() {
        let mut c = Command::new("runuser");
        c.args(["-u", "postgres", "--"]).arg(program).args(args);
        c
    } else {
        let mut c = Command::new(program);
        c.args(args);
        c
    }
}

/// A free TCP port on 127.0.0.1 (free when asked: the server binds it next).
fn free_port() -> Result<u16, String> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("no free port on 127.0.0.1: {e}"))
}

/// A running throwaway cluster.
pub struct Cluster {
    /// Its folder (data, socket, log).
    pub dir: PathBuf,
    /// Its port on 127.0.0.1.
    pub port: u16,
    bin: PathBuf,
}

impl Cluster {
    /// The URL of the superuser `postgres` on database `db`, over TCP.
    pub fn url(&self, db: &str) -> String {
        format!("postgresql://postgres@127.0.0.1:{}/{db}", self.port)
    }

    fn data(&self) -> PathBuf {
        self.dir.join("data")
    }

    /// Start a cluster in a new folder under `parent`; `durable`: every commit reaches
    /// the disk (fsync, synchronous commit), as on a plant's server.
    pub fn start(parent: &Path, durable: bool) -> Result<Cluster, String> {
        let bin = bindir().ok_or(
            "no PostgreSQL server: apt-get install postgresql (cargo xtask test installs it)",
        )?;
        let dir = parent.join(format!(
            "hostfit-pg-{}-{}",
            std::process::id(),
            free_port()?
        ));
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let c = Cluster {
            dir,
            port: free_port()?,
            bin,
        };
        if is_root() {
            let own = Command::new("chown")
                .args(["-R", "postgres:postgres"])
                .arg(&c.dir)
                .status()
                .map_err(|e| format!("chown: {e}"))?;
            if !own.success() {
                return Err(format!("chown postgres {} failed", c.dir.display()));
            }
            // the server user must reach its folder through the parent
            let _ = Command::new("chmod").arg("o+x").arg(parent).status();
        }
        let data = c.data().display().to_string();
        c.run(
            "initdb",
            &[
                "-D",
                &data,
                "-U",
                "postgres",
                "-A",
                "trust",
                "-E",
                "UTF8",
                "--locale=C",
                "--no-sync",
            ],
        )?;
        let fast = if durable {
            ""
        } else {
            "fsync = off\nsynchronous_commit = off\nfull_page_writes = off\n"
        };
        let conf = format!(
            "listen_addresses = '127.0.0.1'\nport = {}\nunix_socket_directories = '{}'\n{fast}max_connections = 200\nshared_buffers = 128MB\n",
            c.port,
            c.dir.display()
        );
        let hba = "local all all trust\nhost all all 127.0.0.1/32 trust\n";
        let write = |name: &str, text: &str, append: bool| -> Result<(), String> {
            let p = c.data().join(name);
            let mut body = if append {
                std::fs::read_to_string(&p).unwrap_or_default()
            } else {
                String::new()
            };
            body.push_str(text);
            std::fs::write(&p, body).map_err(|e| format!("{}: {e}", p.display()))
        };
        write("postgresql.conf", &conf, true)?;
        write("pg_hba.conf", hba, false)?;
        let log = c.dir.join("server.log").display().to_string();
        c.run(
            "pg_ctl",
            &["-D", &data, "-l", &log, "-w", "-t", "60", "start"],
        )?;
        Ok(c)
    }

    fn run(&self, tool: &str, args: &[&str]) -> Result<(), String> {
        let o = as_server_user(&self.bin.join(tool), args)
            .stdin(Stdio::null())
            .output()
            .map_err(|e| format!("{tool}: {e}"))?;
        if o.status.success() {
            Ok(())
        } else {
            let log = std::fs::read_to_string(self.dir.join("server.log")).unwrap_or_default();
            Err(format!(
                "{tool} {} failed ({}): {}{}\n{log}",
                args.join(" "),
                o.status,
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ))
        }
    }

    /// Stop the server now (fast shutdown: nothing in it is kept).
    pub fn stop(&self) -> Result<(), String> {
        let data = self.data().display().to_string();
        self.run("pg_ctl", &["-D", &data, "-m", "immediate", "-w", "stop"])
    }
}

impl Cluster {
    /// Hand the cluster to a watchdog that stops it and removes its folder once the
    /// process `pid` has ended: for a cluster a test binary keeps in a static, whose
    /// drop never runs. The watchdog then ends too.
    pub fn stop_after(self, pid: u32) -> Result<(), String> {
        let pg_ctl = self.bin.join("pg_ctl");
        let stop = format!(
            "'{}' -D '{}' -m immediate -w stop",
            pg_ctl.display(),
            self.data().display()
        );
        let stop = if is_root() {
            format!("runuser -u postgres -- {stop}")
        } else {
            stop
        };
        let script = format!(
            "while kill -0 {pid} 2>/dev/null; do sleep 1; done; {stop} >/dev/null 2>&1; rm -rf '{}'",
            self.dir.display()
        );
        Command::new("sh")
            .arg("-c")
            .arg(script)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("sh: {e}"))?;
        std::mem::forget(self);
        Ok(())
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = self.stop();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
