//! What each `truss-mc` command does with its parsed flags ([`crate::cli`]): `run-all`
//! ([`crate::run_all`]), or one of mc-shard's commands as `mc-shard` runs it; and the one
//! function that maps a failure to the exit code ([`exit_code`]).

use crate::cli::{Cli, Command};
use crate::run_all::{RunAllError, RunAllOptions, run_all};
use mc_shard::commands::CommandError;
use mc_shard::{Job, RunError};
use std::io::Write;
use std::time::Instant;

/// An error of a command.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// From one of mc-shard's commands.
    #[error(transparent)]
    Shard(#[from] CommandError),
    /// From `run-all`.
    #[error(transparent)]
    RunAll(#[from] RunAllError),
}

/// The exit code of `truss-mc` for an error, in the scheme every truss-mc binary shares
/// (`truss-exit`, see `--help`): mc-shard's commands and the audit exit as `mc-shard` does,
/// the merge as `mc-merge` does, failed shard processes as [`worker_failure`] says.
///
/// [`worker_failure`]: crate::run_all::worker_failure
pub fn exit_code(e: &Error) -> u8 {
    match e {
        Error::Shard(e) | Error::RunAll(RunAllError::Shard(e)) => mc_shard::commands::exit_code(e),
        Error::RunAll(RunAllError::Workers(f)) => crate::run_all::worker_failure(f).0,
        Error::RunAll(RunAllError::Merge(e)) => e.exit_code(),
        Error::RunAll(RunAllError::Interrupted { signal, .. }) => signal.exit_code(),
    }
}

impl Error {
    /// The signal that interrupted the command, if one did.
    pub fn interrupted(&self) -> Option<mc_shard::interrupt::Signal> {
        match self {
            Error::Shard(CommandError::Interrupted { signal, .. })
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
        Command::Shard(mc_shard::cli::Command::Completions(a)) => {
            Ok(mc_shard::commands::completions(
                a.shell,
                <Cli as clap::CommandFactory>::command(),
                "truss-mc",
                out,
            )?)
        }
        Command::Shard(mc_shard::cli::Command::Man) => Ok(mc_shard::commands::man_page(
            <Cli as clap::CommandFactory>::command(),
            out,
        )?),
        Command::Shard(command) => Ok(mc_shard::commands::run(
            mc_shard::cli::Cli { command },
            out,
        )?),
        Command::RunAll(a) => {
            let workers = truss_threads::or_available(a.workers);
            mc_shard::cli::check_threads("workers", workers).map_err(CommandError::from)?;
            if let Some(k) = a.shards {
                mc_shard::cli::check_shards(k).map_err(CommandError::from)?;
            }
            if a.audit_samples > mc_shard::audit::MAX_AUDIT_SAMPLES {
                let usage = RunError::Usage(format!(
                    "--audit-samples must be at most {}",
                    mc_shard::audit::MAX_AUDIT_SAMPLES
                ));
                return Err(CommandError::Run(usage).into());
            }
            let job = Job::read(&a.job).map_err(CommandError::from)?;
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
            let exe = std::env::current_exe().map_err(CommandError::from)?;
            let started = Instant::now();
            // The merge's table comes last: its last lines are the answer and the report.
            let mut table = Vec::new();
            run_all(&exe, &job, &options, &mut table)?;
            writeln!(
                out,
                "run-all: {} samples in {} shards on {} workers, {:.2} s{}",
                job.samples(),
                options.shards,
                workers,
                started.elapsed().as_secs_f64(),
                if a.no_merge { "" } else { "; the merge:" }
            )
            .map_err(CommandError::from)?;
            out.write_all(&table).map_err(CommandError::from)?;
            Ok(())
        }
    }
}
