//! The `truss` command; see the library for the commands and `truss --help` for use.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = truss_cli::Cli::parse();
    match truss_cli::run(cli, &mut std::io::stdout().lock()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("truss: {e:#}");
            std::process::ExitCode::from(truss_cli::exit_code(&e))
        }
    }
}
