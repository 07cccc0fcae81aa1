//! The `truss` command; see the library for the commands and `truss --help` for use.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = truss_cli::Cli::parse();
    let mut out = truss_exit::Stdout::lock();
    match truss_cli::run(cli, &mut out) {
        Ok(()) => truss_exit::success("truss", &mut out),
        Err(e) => truss_exit::finish("truss", &*e, truss_cli::exit_code(&e), &out),
    }
}
