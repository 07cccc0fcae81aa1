//! `mc-shard`: see the library's crate doc and `mc-shard --help`.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = mc_shard::cli::Cli::parse();
    let mut out = truss_exit::Stdout::lock();
    match mc_shard::cli::run(cli, &mut out) {
        Ok(()) => truss_exit::success("mc-shard", &mut out),
        // "interrupted: N samples kept; rerun …" is a notice, not an error.
        Err(e @ mc_shard::cli::CliError::Interrupted { .. }) => {
            eprintln!("{e}");
            std::process::ExitCode::from(e.exit_code())
        }
        Err(e) => truss_exit::finish("mc-shard", &e, e.exit_code(), &out),
    }
}
