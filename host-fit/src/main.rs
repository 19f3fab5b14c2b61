//! `host-fit`: see `host-fit --help`. `HOSTFIT_DEBUG=1` logs the library's debug lines
//! (every candidate the diagnosis judges, the orientation estimate's iterations, f32
//! vectors beyond the bound) to stderr: the environment is read here, once (with the
//! record store's login: `PGUSER`, `PGHOST`, `PGPASSWORD`, `PGPASSFILE`, `HOME`, and the
//! operator's login name `USER`).

/// The library's `log` lines to stderr.
struct Stderr;

impl log::Log for Stderr {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }

    fn log(&self, record: &log::Record) {
        eprintln!("{}", record.args());
    }

    fn flush(&self) {}
}

static STDERR: Stderr = Stderr;

fn main() {
    if std::env::var_os("HOSTFIT_DEBUG").is_some() && log::set_logger(&STDERR).is_ok() {
        log::set_max_level(log::LevelFilter::Debug);
    }
    host_fit::store::location::set_environment(host_fit::store::location::Environment::from_vars(
        |k| std::env::var(k).ok(),
    ));
    let code = host_fit::cli::run(
        std::env::args_os(),
        &mut std::io::stdout(),
        &mut std::io::stderr(),
    );
    std::process::exit(code);
}
