//! `mc-shard`: see the library's crate doc and `mc-shard --help`.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = mc_shard::cli::Cli::parse();
    match mc_shard::cli::run(cli, &mut std::io::stdout().lock()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e @ mc_shard::cli::CliError::Interrupted { .. }) => {
            eprintln!("{e}");
            std::process::ExitCode::from(e.exit_code())
        }
        Err(e) => {
            eprintln!("mc-shard: {e}");
            std::process::ExitCode::from(e.exit_code())
        }
    }
}
