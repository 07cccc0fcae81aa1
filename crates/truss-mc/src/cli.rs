//! The command line: `run-all`, and every command of `mc-shard` as it is.

use crate::run_all::{RunAllError, RunAllOptions, run_all};
use clap::{Args, Parser, Subcommand};
use mc_shard::cli::{CliError, run_exit_code};
use mc_shard::{Job, RunError};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

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

/// An error of a command, with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// From one of mc-shard's commands.
    #[error(transparent)]
    Shard(#[from] CliError),
    /// From `run-all`.
    #[error(transparent)]
    RunAll(#[from] RunAllError),
}

impl Error {
    /// The process exit code (see `--help`).
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Shard(e) => e.exit_code(),
            Error::RunAll(RunAllError::Run(e)) => run_exit_code(e),
            Error::RunAll(RunAllError::Workers(f)) => crate::run_all::worker_failure(f).0,
            Error::RunAll(RunAllError::Audit(e)) => e.exit_code(),
            Error::RunAll(RunAllError::Merge(e)) => e.exit_code(),
            Error::RunAll(RunAllError::Interrupted { signal, .. }) => signal.exit_code(),
        }
    }
}

impl Error {
    /// The signal that interrupted the command, if one did.
    pub fn interrupted(&self) -> Option<mc_shard::interrupt::Signal> {
        match self {
            Error::Shard(CliError::Interrupted { signal, .. })
            | Error::RunAll(RunAllError::Interrupted { signal, .. }) => Some(*signal),
            _ => None,
        }
    }
}

/// Runs a command, writing its report to `out`; progress goes to stderr.
pub fn run(cli: Cli, out: &mut dyn Write) -> Result<(), Error> {
    if let Command::Shard(mc_shard::cli::Command::Run(_)) = &cli.command {
        crate::run_all::die_with_parent();
    }
    match cli.command {
        Command::Shard(mc_shard::cli::Command::Completions(a)) => Ok(mc_shard::cli::completions(
            a.shell,
            <Cli as clap::CommandFactory>::command(),
            "truss-mc",
            out,
        )?),
        Command::Shard(mc_shard::cli::Command::Man) => Ok(mc_shard::cli::man_page(
            <Cli as clap::CommandFactory>::command(),
            out,
        )?),
        Command::Shard(command) => Ok(mc_shard::cli::run(mc_shard::cli::Cli { command }, out)?),
        Command::RunAll(a) => {
            let workers = truss_threads::or_available(a.workers);
            mc_shard::cli::check_threads("workers", workers).map_err(CliError::from)?;
            if let Some(k) = a.shards {
                mc_shard::cli::check_shards(k).map_err(CliError::from)?;
            }
            if a.audit_samples > mc_shard::audit::MAX_AUDIT_SAMPLES {
                let usage = RunError::Usage(format!(
                    "--audit-samples must be at most {}",
                    mc_shard::audit::MAX_AUDIT_SAMPLES
                ));
                return Err(CliError::Run(usage).into());
            }
            let job = Job::read(&a.job).map_err(CliError::from)?;
            let options = RunAllOptions {
                job_path: a.job.clone(),
                out: a.out.clone(),
                shards: a.shards.unwrap_or(workers as u64),
                workers,
                quiet: a.quiet,
                no_merge: a.no_merge,
                audit_samples: a.audit_samples,
                allow_failed: a.allow_failed,
            };
            let exe = std::env::current_exe().map_err(CliError::from)?;
            let started = Instant::now();
            run_all(&exe, &job, &options, out)?;
            writeln!(
                out,
                "run-all: {} samples in {} shards on {} workers, {:.2} s{}",
                job.samples(),
                options.shards,
                workers,
                started.elapsed().as_secs_f64(),
                if a.no_merge {
                    String::new()
                } else {
                    format!("; report in {}", a.out.join("report").display())
                }
            )
            .map_err(CliError::from)?;
            Ok(())
        }
    }
}
