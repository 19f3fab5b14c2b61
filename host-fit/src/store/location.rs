//! Where a record store lives, as `--db` gives it: a path is an SQLite file; a
//! `postgresql://` (or `postgres://`) URL is a database on a PostgreSQL server. The
//! password is taken from the URL, else `PGPASSWORD`, else a pgpass file (`PGPASSFILE`
//! or `~/.pgpass`, the server's own format and rules), and is never shown: a location
//! prints as its URL without the password, the form every message, record and report
//! uses. The environment is read by `main`, once ([`set_environment`]); the library
//! alone (tests, examples) knows only what the URL says.
use crate::error::{ErrorKind, HostError, Result};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// What the environment says about a login: `PGUSER`, `PGHOST`, `PGPASSWORD`, the
/// pgpass file (`PGPASSFILE`, else `$HOME/.pgpass`) and the login name (`USER`, the
/// operator when none is given).
#[derive(Clone, Default, PartialEq, Eq)]
pub struct Environment {
    /// `PGUSER`.
    pub pg_user: Option<String>,
    /// `PGHOST`.
    pub pg_host: Option<String>,
    /// `PGPASSWORD` (never printed).
    pg_password: Option<String>,
    /// The pgpass file.
    pub pg_passfile: Option<PathBuf>,
    /// `USER`.
    pub login: Option<String>,
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Environment {{ pg_user: {:?}, pg_host: {:?}, pg_password: {}, pg_passfile: {:?}, login: {:?} }}",
            self.pg_user,
            self.pg_host,
            if self.pg_password.is_some() { "(set)" } else { "None" },
            self.pg_passfile,
            self.login
        )
    }
}

impl Environment {
    /// From the variables `get` gives (main passes the process environment's).
    pub fn from_vars(get: impl Fn(&str) -> Option<String>) -> Environment {
        let var = |k: &str| get(k).filter(|v| !v.is_empty());
        Environment {
            pg_user: var("PGUSER"),
            pg_host: var("PGHOST"),
            pg_password: var("PGPASSWORD"),
            pg_passfile: var("PGPASSFILE")
                .map(PathBuf::from)
                .or_else(|| var("HOME").map(|h| Path::new(&h).join(".pgpass"))),
            login: var("USER"),
        }
    }
}

static ENVIRONMENT: OnceLock<Environment> = OnceLock::new();

/// Set the environment the store's logins use (main does, once, before anything).
pub fn set_environment(e: Environment) {
    let _ = ENVIRONMENT.set(e);
}

/// The environment main set (none in a library run: the URL alone).
pub fn environment() -> &'static Environment {
    static NONE: OnceLock<Environment> = OnceLock::new();
    ENVIRONMENT
        .get()
        .unwrap_or_else(|| NONE.get_or_init(Environment::default))
}

/// A record store's location.
#[derive(Clone, PartialEq, Eq)]
pub enum Location {
    /// An SQLite file.
    Sqlite(PathBuf),
    /// A PostgreSQL database.
    Postgres(PgUrl),
}

/// A PostgreSQL database's URL, parsed; its password is kept apart and never printed.
#[derive(Clone, PartialEq, Eq)]
pub struct PgUrl {
    /// The user (the URL's, else `PGUSER`, else `USER`).
    pub user: String,
    /// The host (a name, an address, or a socket directory starting with `/`).
    pub host: String,
    /// The port.
    pub port: u16,
    /// The database.
    pub dbname: String,
    /// The password, when the URL, `PGPASSWORD` or a pgpass file gives one.
    password: Option<String>,
}

/// PostgreSQL's default port.
pub const PG_PORT: u16 = 5432;

impl std::fmt::Debug for PgUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PgUrl({self})")
    }
}

impl std::fmt::Display for PgUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let host = if self.host.starts_with('/') {
            format!("[{}]", self.host)
        } else {
            self.host.clone()
        };
        write!(
            f,
            "postgresql://{}@{host}:{}/{}",
            self.user, self.port, self.dbname
        )
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::Sqlite(p) => write!(f, "{}", p.display()),
            Location::Postgres(u) => write!(f, "{u}"),
        }
    }
}

impl std::fmt::Debug for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Location({self})")
    }
}

/// `%XX` escapes of a URL part decoded.
fn percent_decode(s: &str, what: &str, shown: &str) -> Result<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = s
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok());
            let Some(v) = hex else {
                return Err(HostError::new(
                    ErrorKind::Invalid,
                    format!("--db {shown}: a `%` in its {what} is not followed by two hex digits"),
                ));
            };
            out.push(v);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| {
        HostError::new(
            ErrorKind::Invalid,
            format!("--db {shown}: its {what} is not UTF-8"),
        )
    })
}

impl Location {
    /// The location `--db` gives: a `postgresql://` or `postgres://` URL, else a path.
    pub fn parse(s: &str) -> Result<Location> {
        let rest = s
            .strip_prefix("postgresql://")
            .or_else(|| s.strip_prefix("postgres://"));
        match rest {
            Some(r) => PgUrl::parse(r).map(Location::Postgres),
            None if s.contains("://") => Err(HostError::new(ErrorKind::Invalid, format!(
                "--db `{}`: not a store this host-fit knows: give a file path (SQLite) or postgresql://user@host:port/database",
                s.split("://").next().unwrap_or_default()
            ))),
            None => Ok(Location::Sqlite(PathBuf::from(s))),
        }
    }

    /// The SQLite file, for a store that is one.
    pub fn sqlite_path(&self) -> Option<&Path> {
        match self {
            Location::Sqlite(p) => Some(p),
            Location::Postgres(_) => None,
        }
    }

    /// The path errors name: the SQLite file, or the URL (without its password) as a
    /// path-like name.
    pub fn error_path(&self) -> PathBuf {
        PathBuf::from(self.to_string())
    }
}

impl std::str::FromStr for Location {
    type Err = HostError;
    fn from_str(s: &str) -> Result<Location> {
        Location::parse(s)
    }
}

impl PgUrl {
    /// Parse what follows `postgresql://`: `[user[:password]@]host[:port][/dbname][?...]`
    /// (`host` may be `[/socket/dir]` or `[::1]`).
    fn parse(r: &str) -> Result<PgUrl> {
        // what is shown of a bad URL never holds its password
        let shown = match r.rfind('@') {
            Some(at) => format!(
                "postgresql://{}@{}",
                r[..at].split(':').next().unwrap_or_default(),
                &r[at + 1..]
            ),
            None => format!("postgresql://{r}"),
        };
        let r = r.split('?').next().unwrap_or_default();
        let (auth, rest) = match r.rfind('@') {
            Some(at) => (Some(&r[..at]), &r[at + 1..]),
            None => (None, r),
        };
        let (user, password) = match auth {
            Some(a) => match a.split_once(':') {
                Some((u, p)) => (
                    Some(percent_decode(u, "user", &shown)?),
                    Some(percent_decode(p, "password", &shown)?),
                ),
                None => (Some(percent_decode(a, "user", &shown)?), None),
            },
            None => (None, None),
        };
        // a bracketed host (`[/socket/dir]`, `[::1]`) may hold slashes
        let from = if rest.starts_with('[') {
            rest.find(']').unwrap_or(0)
        } else {
            0
        };
        let (hostport, dbname) = match rest[from..].find('/') {
            Some(k) => (
                &rest[..from + k],
                percent_decode(&rest[from + k + 1..], "database name", &shown)?,
            ),
            None => (rest, String::new()),
        };
        let (host, port) = if let Some(inner) = hostport.strip_prefix('[') {
            let (h, after) = inner.split_once(']').ok_or_else(|| {
                HostError::new(
                    ErrorKind::Invalid,
                    format!("--db {shown}: a `[` in its host is not closed"),
                )
            })?;
            (h.to_string(), after.strip_prefix(':'))
        } else {
            match hostport.rsplit_once(':') {
                Some((h, p)) => (h.to_string(), Some(p)),
                None => (hostport.to_string(), None),
            }
        };
        let port = match port {
            Some(p) => p.parse::<u16>().map_err(|_| {
                HostError::new(
                    ErrorKind::Invalid,
                    format!("--db {shown}: port `{p}` is not a port number"),
                )
            })?,
            None => PG_PORT,
        };
        let env = environment();
        let user = user
            .filter(|u| !u.is_empty())
            .or_else(|| env.pg_user.clone())
            .or_else(|| env.login.clone())
            .ok_or_else(|| {
                HostError::new(
                    ErrorKind::Invalid,
                    format!("--db {shown}: no user: give postgresql://USER@host:port/database"),
                )
            })?;
        let host = match host.as_str() {
            "" => env.pg_host.clone().unwrap_or_else(|| "localhost".into()),
            _ => percent_decode(&host, "host", &shown)?,
        };
        let dbname = if dbname.is_empty() {
            user.clone()
        } else {
            dbname
        };
        let mut u = PgUrl {
            user,
            host,
            port,
            dbname,
            password,
        };
        if u.password.is_none() {
            u.password = env
                .pg_password
                .clone()
                .or_else(|| env.pg_passfile.as_deref().and_then(|f| pgpass(f, &u)));
        }
        Ok(u)
    }

    /// The client's configuration (the password included: never printed).
    pub fn config(&self) -> postgres::Config {
        let mut c = postgres::Config::new();
        c.user(&self.user)
            .host(&self.host)
            .port(self.port)
            .dbname(&self.dbname)
            .application_name("host-fit")
            .connect_timeout(std::time::Duration::from_secs(10));
        if let Some(p) = &self.password {
            c.password(p);
        }
        c
    }

    /// Whether a password was found (for messages: never the password itself).
    pub fn has_password(&self) -> bool {
        self.password.is_some()
    }

    /// The same server and user, another database (tests, `store copy`).
    pub fn with_dbname(&self, dbname: &str) -> PgUrl {
        PgUrl {
            dbname: dbname.to_string(),
            ..self.clone()
        }
    }
}

/// The password the pgpass file `path` gives for `u`: lines of
/// `host:port:database:user:password`, `*` matching anything, `\:` and `\\` escaped;
/// the first line that matches wins. As libpq does, a file that the group or others
/// can read is ignored.
fn pgpass(path: &Path, u: &PgUrl) -> Option<String> {
    use std::os::unix::fs::PermissionsExt;
    let meta = std::fs::metadata(path).ok()?;
    if !meta.is_file() || meta.permissions().mode() & 0o077 != 0 {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    let host = if u.host.starts_with('/') {
        "localhost".to_string()
    } else {
        u.host.clone()
    };
    let want = [host, u.port.to_string(), u.dbname.clone(), u.user.clone()];
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .find_map(|l| {
            let f = pgpass_fields(l);
            (f.len() == 5
                && f.iter()
                    .zip(&want)
                    .all(|(field, w)| field == "*" || field == w))
            .then(|| f[4].clone())
        })
}

/// The fields of a pgpass line (`:` separates, `\` escapes).
fn pgpass_fields(l: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut chars = l.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => {
                if let (Some(n), Some(last)) = (chars.next(), out.last_mut()) {
                    last.push(n);
                }
            }
            ':' if out.len() < 5 => out.push(String::new()),
            c => {
                if let Some(last) = out.last_mut() {
                    last.push(c);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_parse_and_never_show_their_password() {
        let l =
            Location::parse("postgresql://op:s3cr%40t@db.plant:6543/line?sslmode=disable").unwrap();
        let Location::Postgres(u) = &l else {
            panic!("{l}")
        };
        assert_eq!(
            (u.user.as_str(), u.host.as_str(), u.port, u.dbname.as_str()),
            ("op", "db.plant", 6543, "line")
        );
        assert_eq!(u.password.as_deref(), Some("s3cr@t"));
        assert_eq!(l.to_string(), "postgresql://op@db.plant:6543/line");
        assert!(!format!("{l:?}").contains("s3cr"));
        let s = Location::parse("postgres://a@[/tmp/sock]:7000/d").unwrap();
        assert_eq!(s.to_string(), "postgresql://a@[/tmp/sock]:7000/d");
        assert_eq!(
            Location::parse("runs/line.sqlite").unwrap(),
            Location::Sqlite("runs/line.sqlite".into())
        );
        let e = Location::parse("mysql://x@y/z").unwrap_err();
        assert!(e.to_string().contains("mysql"), "{e}");
        let e = Location::parse("postgresql://op:hush@h:port/d").unwrap_err();
        assert!(e.to_string().contains("port") && !e.to_string().contains("hush"));
    }

    #[test]
    fn a_pgpass_file_gives_the_password_only_when_private() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("pgpass");
        std::fs::write(
            &f,
            "# the line\nother:5432:*:op:no\ndb.plant:*:line:op:yes\n",
        )
        .unwrap();
        let Location::Postgres(u) = Location::parse("postgresql://op@db.plant:6000/line").unwrap()
        else {
            panic!()
        };
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o644)).unwrap();
        assert_eq!(pgpass(&f, &u), None);
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
        assert_eq!(pgpass(&f, &u).as_deref(), Some("yes"));
    }

    #[test]
    fn pgpass_lines_match_with_wildcards_and_escapes() {
        assert_eq!(
            pgpass_fields(r"h:5432:*:u:pa\:ss\\w"),
            ["h", "5432", "*", "u", r"pa:ss\w"]
        );
        assert_eq!(pgpass_fields("a:b:c:d:e:f"), ["a", "b", "c", "d", "e:f"]);
    }
}
