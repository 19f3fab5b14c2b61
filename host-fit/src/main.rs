//! `host-fit`: see `host-fit --help`.
fn main() {
    let code = host_fit::cli::run(
        std::env::args_os(),
        &mut std::io::stdout(),
        &mut std::io::stderr(),
    );
    std::process::exit(code);
}
