//! `mc-merge`: verifies the Monte Carlo shards of one job and reports percentiles with
//! confidence intervals, the Rayleigh law and the allowable σ. Exit codes: see `--help` or
//! [`mc_merge::MergeError::exit_code`].

use clap::Parser;
use mc_merge::Args;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Usage errors exit with clap's code 2, which is truss_exit::USAGE.
    let args = Args::parse();
    let mut out = truss_exit::Stdout::lock();
    // A helper command, an export or a merge (see `mc_merge::execute`).
    match mc_merge::execute(args, &mut out) {
        Ok(()) => truss_exit::success("mc-merge", &mut out),
        Err(e) => truss_exit::finish("mc-merge", &e, e.exit_code(), &out),
    }
}
