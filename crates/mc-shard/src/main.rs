//! `mc-shard`: see the library's crate doc and `mc-shard --help`.

use clap::Parser;
use mc_shard::commands::{CommandError, exit_code};

fn main() -> std::process::ExitCode {
    let cli = mc_shard::cli::Cli::parse();
    let mut out = truss_exit::Stdout::lock();
    match mc_shard::commands::run(cli, &mut out) {
        Ok(()) => truss_exit::success("mc-shard", &mut out),
        // "interrupted: N samples kept; rerun …" is a notice, not an error.
        Err(e @ CommandError::Interrupted { .. }) => {
            eprintln!("{e}");
            std::process::ExitCode::from(exit_code(&e))
        }
        Err(e) => truss_exit::finish("mc-shard", &e, exit_code(&e), &out),
    }
}
