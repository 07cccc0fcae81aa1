//! `truss-mc`: see the library's crate doc and `truss-mc --help`.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = truss_mc::cli::Cli::parse();
    match truss_mc::cli::run(cli, &mut std::io::stdout().lock()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.interrupted().is_some() => {
            eprintln!("{e}");
            std::process::ExitCode::from(e.exit_code())
        }
        Err(e) => {
            eprintln!("truss-mc: {e}");
            std::process::ExitCode::from(e.exit_code())
        }
    }
}
