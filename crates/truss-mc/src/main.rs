//! `truss-mc`: see the library's crate doc and `truss-mc --help`.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = truss_mc::cli::Cli::parse();
    let mut out = truss_exit::Stdout::lock();
    match truss_mc::commands::run(cli, &mut out) {
        Ok(()) => truss_exit::success("truss-mc", &mut out),
        // "interrupted: N samples kept; rerun …" is a notice, not an error.
        Err(e) if e.interrupted().is_some() => {
            eprintln!("{e}");
            std::process::ExitCode::from(truss_mc::commands::exit_code(&e))
        }
        Err(e) => truss_exit::finish("truss-mc", &e, truss_mc::commands::exit_code(&e), &out),
    }
}
