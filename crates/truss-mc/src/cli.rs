//! The command line: `run-all`, and every command of `mc-shard` as it is; the flags, parsed
//! by clap. What a command does, and its exit code, is [`crate::commands`]'.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// The command line of `truss-mc`.
#[derive(Debug, Parser)]
#[command(
    name = "truss-mc",
    version,
    about = "The truss Monte Carlo on one machine: every shard as a concurrent process, then the merge; and mc-shard's commands",
    after_help = truss_exit::SUMMARY
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run every shard on this machine as concurrent processes, then merge into DIR/report.
    RunAll(RunAllArgs),
    /// mc-shard's commands (completions and man pages are truss-mc's own).
    #[command(flatten)]
    Shard(mc_shard::cli::Command),
}

/// `truss-mc run-all`.
#[derive(Debug, Args)]
pub struct RunAllArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// Directory for the shard files; the report goes to DIR/report.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Number of shards (1 to 1,000,000; default: the number of workers).
    #[arg(long)]
    pub shards: Option<u64>,
    /// Concurrent worker processes (default: all cores).
    #[arg(long)]
    pub workers: Option<usize>,
    /// Show no progress.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Do not audit or merge at the end.
    #[arg(long)]
    pub no_merge: bool,
    /// Sample lines re-solved and compared byte for byte before the merge (0: no audit).
    #[arg(long, default_value_t = crate::run_all::DEFAULT_AUDIT_SAMPLES)]
    pub audit_samples: u64,
    /// Merge even with failed samples present, on the converged ones (mc-merge's
    /// --allow-failed; the report says so in every affected case).
    #[arg(long)]
    pub allow_failed: bool,
}
