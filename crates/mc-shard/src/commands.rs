//! What each `mc-shard` command does with its parsed flags ([`crate::cli`]): it calls the
//! library (the runner, the worker pool, the audit, the plan, the status of a directory)
//! and writes the command's report to stdout; a failure is a [`CommandError`], whose exit
//! code [`exit_code`] gives, in the one place `mc-shard` maps errors to codes. `truss-mc`
//! runs the same commands.

use crate::audit::AuditError;
use crate::cli::{
    AuditArgs, Cli, Command, InputsArgs, PlanArgs, ReproduceArgs, RunArgs, StatusArgs, WorkArgs,
    check_shards, check_threads,
};
use crate::errors::{RunError, ShardError};
use crate::interrupt::Signal;
use crate::job::Job;
use crate::plan::Plan;
use crate::runner::{RunOptions, run_shard};
use crate::select::select;
use crate::status::{ShardState, shard_states};
use run_dir::RunDirError;
use shard_record::ScanError;
use std::io::Write;
use std::path::PathBuf;
use truss_job::JobError;

/// An error of a command (`mc-shard`'s, and those `truss-mc` shares).
#[derive(Debug, thiserror::Error)]
pub enum CommandError {
    /// From the run machinery.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Writing output failed.
    #[error("cannot write output: {0}")]
    Output(#[from] std::io::Error),
    /// An audit could not be completed, or found lines that differ from their re-solve.
    #[error(transparent)]
    Audit(#[from] AuditError),
    /// Workers set shards aside as damaged; the other shards ran.
    #[error("{} shard(s) quarantined as damaged (the other shards ran): {}; move each file away (or repair it), delete its marker in {}, and run again", .shards.len(), .shards.iter().map(|(i, why)| format!("shard {i}: {why}")).collect::<Vec<_>>().join("; "), .dir.display())]
    Quarantined {
        /// Each quarantined shard with its reason.
        shards: Vec<(u64, String)>,
        /// The quarantine directory.
        dir: PathBuf,
    },
    /// Stopped by SIGINT or SIGTERM; `kept` sample lines are in the shard files.
    #[error("{}", crate::interrupt::message(*.kept))]
    Interrupted {
        /// The signal.
        signal: Signal,
        /// Sample lines in the shard files, kept for a rerun.
        kept: u64,
    },
}

impl From<JobError> for CommandError {
    fn from(e: JobError) -> Self {
        CommandError::Run(RunError::Job(e))
    }
}

/// The exit code of `mc-shard` (and of `truss-mc`'s mc-shard commands) for an error, in the
/// scheme every truss-mc binary shares (`truss-exit`): the one place a failure becomes a
/// code.
pub fn exit_code(e: &CommandError) -> u8 {
    use truss_exit::{IN_THE_WAY, INVALID_INPUT, IO, USAGE, VERIFICATION};
    match e {
        CommandError::Run(RunError::Usage(_)) | CommandError::Audit(AuditError::Samples(_)) => {
            USAGE
        }
        CommandError::Run(RunError::Job(e)) if e.is_io() => IO,
        CommandError::Run(RunError::Job(_)) => INVALID_INPUT,
        CommandError::Output(_)
        | CommandError::Run(RunError::Shard(ShardError::Io { .. }))
        | CommandError::Audit(AuditError::Io { .. } | AuditError::Scan(ScanError::Io { .. })) => IO,
        CommandError::Run(RunError::Shard(ShardError::Files(files)))
        | CommandError::Audit(AuditError::Files(files)) => match files {
            RunDirError::Io { .. } => IO,
            RunDirError::Link { .. }
            | RunDirError::NotAFile { .. }
            | RunDirError::Locked { .. }
            | RunDirError::NotOurs { .. }
            | RunDirError::HardLinked { .. } => IN_THE_WAY,
            RunDirError::NotRegular { .. } => INVALID_INPUT,
        },
        CommandError::Run(RunError::Shard(
            ShardError::OtherJob { .. }
            | ShardError::HeaderMismatch { .. }
            | ShardError::OldFormat { .. }
            | ShardError::Pool { .. }
            | ShardError::Locked { .. }
            | ShardError::NotAShard { .. }
            | ShardError::Corrupt(_),
        ))
        | CommandError::Audit(AuditError::OtherJob { .. })
        | CommandError::Quarantined { .. } => IN_THE_WAY,
        CommandError::Audit(
            AuditError::Scan(_) | AuditError::NoShards(_) | AuditError::Mismatch { .. },
        ) => VERIFICATION,
        CommandError::Interrupted { signal, .. } => signal.exit_code(),
    }
}

/// Runs a command, writing its report to `out`; progress goes to stderr.
pub fn run(cli: Cli, out: &mut dyn Write) -> Result<(), CommandError> {
    match cli.command {
        Command::Plan(a) => plan_command(&a, out),
        Command::Run(a) => run_command(a, out),
        Command::Reproduce(a) => reproduce_command(a, out),
        Command::Work(a) => work_command(a, out),
        Command::Status(a) => status_command(a, out),
        Command::Audit(a) => audit_command(a, out),
        Command::Inputs(a) => inputs_command(a, out),
        Command::Completions(a) => completions(
            a.shell,
            <Cli as clap::CommandFactory>::command(),
            "mc-shard",
            out,
        ),
        Command::Man => man_page(<Cli as clap::CommandFactory>::command(), out),
    }
}

/// Writes `cmd`'s completion script for `shell` to `out`, through memory first:
/// `clap_complete` panics when its writer fails (a full disk), and a failed write is an
/// I/O error like any other.
pub fn completions(
    shell: clap_complete::Shell,
    mut cmd: clap::Command,
    name: &str,
    out: &mut dyn Write,
) -> Result<(), CommandError> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut cmd, name, &mut script);
    out.write_all(&script)?;
    Ok(())
}

/// Writes `cmd`'s man pages (roff), one per command and subcommand, to `out`
/// ([`truss_man::pages`]).
pub fn man_page(cmd: clap::Command, out: &mut dyn Write) -> Result<(), CommandError> {
    truss_man::pages(cmd.after_help(truss_exit::SUMMARY), out)?;
    Ok(())
}

/// `mc-shard audit`: re-solve a seeded sample of lines; exit 6 on a mismatch.
fn audit_command(a: AuditArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    let threads = check_threads("threads", truss_threads::or_available(a.threads))?;
    let job = Job::read(&a.job)?;
    let options = crate::audit::AuditOptions {
        samples: a.samples,
        seed: a.seed,
        threads,
    };
    let report = crate::audit::audit(&job, &a.paths, &options)?;
    writeln!(out, "{}", report.verdict()?)?;
    Ok(())
}

/// `mc-shard inputs`: the drawn inputs as CSV.
fn inputs_command(a: InputsArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    let job = Job::read(&a.job)?;
    let case = match &a.case {
        None => None,
        Some(name) => Some(crate::select::case_named(&job, name)?),
    };
    let range = match &a.range {
        None => shard_record::ShardRange::new(0, job.samples()),
        Some(text) => crate::select::range_within(&job, "--range", text)?,
    };
    let io = |source| {
        CommandError::Run(RunError::Shard(ShardError::Io {
            path: a.out.clone(),
            source,
        }))
    };
    // Written whole or not at all: a full disk leaves the old file at its name.
    let files = |e: run_dir::RunDirError| CommandError::Run(RunError::Shard(e.into()));
    let mut w = run_dir::OutputFile::create(&a.out).map_err(files)?;
    let rows = crate::inputs::write_inputs(&job, case, range, &mut w).map_err(io)?;
    w.commit().map_err(files)?;
    writeln!(out, "{}: {rows} samples' inputs (mm)", a.out.display())?;
    Ok(())
}

/// `mc-shard run`: one shard, crash-safe and resumable.
fn run_command(a: RunArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    let job = Job::read(&a.job)?;
    let (range, source) = select(
        a.range.as_deref(),
        a.shard.as_deref(),
        a.shards,
        job.samples(),
        |k| std::env::var(k).ok(),
    )?;
    let threads = truss_threads::or_available(a.threads);
    check_threads("threads", threads)?;
    crate::interrupt::install()?;
    let summary = run_shard(
        &job,
        &a.out,
        range,
        &RunOptions {
            threads,
            quiet: a.quiet,
        },
    )?;
    if let Some(signal) = summary.interrupted {
        return Err(CommandError::Interrupted {
            signal,
            kept: summary.resumed + summary.computed,
        });
    }
    if summary.already_complete {
        writeln!(
            out,
            "{}: already complete and verified ({} samples, {} failed)",
            summary.path.display(),
            summary.resumed,
            summary.failed
        )?;
    } else {
        writeln!(
            out,
            "{}: {} samples ({} computed now{}, {} failed) in {:.2} s, {:.0} samples/s (range from {})",
            summary.path.display(),
            range.len(),
            summary.computed,
            if summary.resumed > 0 {
                format!(", {} kept from before", summary.resumed)
            } else {
                String::new()
            },
            summary.failed,
            summary.seconds,
            summary.computed as f64 / summary.seconds.max(1e-9),
            source
        )?;
    }
    Ok(())
}

/// `mc-shard reproduce`: one sample's line, or its detail.
fn reproduce_command(a: ReproduceArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    let job = Job::read(&a.job)?;
    let c = crate::select::case_named(&job, &a.case)?;
    crate::select::check_sample(&job, c, a.sample)?;
    out.write_all(crate::reproduce::reproduce(&job, c, a.sample, a.detail).as_bytes())?;
    Ok(())
}

/// `mc-shard work`: claim, run and repeat until no shard is left.
fn work_command(a: WorkArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    check_shards(a.shards)?;
    let (heartbeat, stale_after) = a.durations()?;
    let threads = check_threads("threads", truss_threads::or_available(a.threads))?;
    let job = Job::read(&a.job)?;
    let options = crate::work::WorkOptions {
        shards: a.shards,
        threads,
        heartbeat,
        stale_after,
        quiet: a.quiet,
    };
    crate::interrupt::install()?;
    let mut failed = None;
    crate::work::work(&job, &a.out, &options, |action| {
        let line = serde_json::to_string(action).expect("actions serialise");
        if let Err(e) = writeln!(out, "{line}").and_then(|_| out.flush()) {
            failed.get_or_insert(e);
        }
    })?;
    if let Some(signal) = crate::interrupt::requested() {
        return Err(CommandError::Interrupted {
            signal,
            kept: crate::status::kept_samples(&job, &a.out, a.shards),
        });
    }
    if let Some(e) = failed {
        return Err(e.into());
    }
    let quarantined: Vec<(u64, String)> = (0..a.shards)
        .filter_map(|i| crate::work::quarantined(&a.out, i, a.shards).map(|why| (i, why)))
        .collect();
    if !quarantined.is_empty() {
        return Err(CommandError::Quarantined {
            shards: quarantined,
            dir: a.out.join("quarantine"),
        });
    }
    Ok(())
}

/// `mc-shard status`: which shards are complete, partial, missing or bad.
fn status_command(a: StatusArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    check_shards(a.shards)?;
    let job = Job::read(&a.job)?;
    let states = shard_states(&job, &a.out, a.shards).map_err(RunError::Usage)?;
    if a.json {
        let shards: Vec<serde_json::Value> = states
            .iter()
            .enumerate()
            .map(|(i, (r, s))| {
                let (state, samples, reason) = match s {
                    ShardState::Complete => ("complete", r.len(), None),
                    ShardState::Partial(n) => ("partial", *n, None),
                    ShardState::Missing => ("missing", 0, None),
                    ShardState::Bad(why) => ("bad", 0, Some(why.as_str())),
                    ShardState::Quarantined(why) => ("quarantined", 0, Some(why.as_str())),
                };
                serde_json::json!({"shard": i, "range": r, "state": state,
                                   "samples": samples, "reason": reason})
            })
            .collect();
        let value = serde_json::json!({"job_id": job.id, "shards": a.shards, "status": shards});
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(&value).expect("serialises")
        )?;
    } else if a.missing {
        let missing: Vec<String> = states
            .iter()
            .enumerate()
            .filter(|(_, (_, s))| *s != ShardState::Complete)
            .map(|(i, _)| i.to_string())
            .collect();
        writeln!(out, "{}", missing.join(","))?;
    } else {
        for (i, (r, s)) in states.iter().enumerate() {
            let what = match s {
                ShardState::Complete => "complete".to_string(),
                ShardState::Partial(n) => format!("partial ({n} of {} samples)", r.len()),
                ShardState::Missing => "missing".to_string(),
                ShardState::Bad(why) => format!("bad: {why}"),
                ShardState::Quarantined(why) => format!("quarantined: {why}"),
            };
            writeln!(out, "shard {i}/{} {r}: {what}", a.shards)?;
        }
    }
    Ok(())
}

/// `mc-shard plan`: the job's id and cases, and a split suggested from a short timing.
fn plan_command(a: &PlanArgs, out: &mut dyn Write) -> Result<(), CommandError> {
    let job = Job::read(&a.job)?;
    let plan = Plan::time(&job);
    if a.json {
        let value = plan.json(&job);
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(&value).expect("serialises")
        )?;
    } else {
        out.write_all(plan.text(&job, &a.job.display().to_string()).as_bytes())?;
    }
    Ok(())
}
