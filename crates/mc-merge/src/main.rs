//! `mc-merge`: verifies the Monte Carlo shards of one job and reports percentiles with
//! confidence intervals, the Rayleigh law and the allowable σ. Exit codes: see `--help` or
//! [`mc_merge::ExitCodes`].

use clap::Parser;
use mc_merge::{Args, ExitCodes};
use std::process::ExitCode;

fn main() -> ExitCode {
    // Usage errors exit with clap's code 2, which is ExitCodes::USAGE.
    let args = Args::parse();
    let export = args.export.clone();
    let mut out = truss_exit::Stdout::lock();
    let result = args.validate().and_then(|options| match &export {
        Some(to) => mc_merge::export::run(&options, to, &mut out),
        None => mc_merge::run(&options, &mut out).map(|_| ()),
    });
    match result {
        Ok(()) => ExitCode::from(ExitCodes::OK),
        Err(e) => truss_exit::finish("mc-merge", &e, e.exit_code(), &out),
    }
}
