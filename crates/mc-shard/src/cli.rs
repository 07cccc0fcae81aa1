//! The `mc-shard` command line: arguments, dispatch, and the exit code of each failure.

use crate::JobError;
use crate::errors::{RunError, ShardError};
use crate::job::Job;
use crate::runner::{RunOptions, run_shard};
use crate::select::select;
use crate::status::{ShardState, shard_states};
use clap::{Args, Parser, Subcommand};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// Exit codes: the scheme every truss-mc binary shares (also in `--help`).
pub use truss_exit as exit;

/// Runs seeded Monte Carlo shards of a truss job and writes them as JSON Lines. Units: mm,
/// N, rad.
#[derive(Debug, Parser)]
#[command(
    name = "mc-shard",
    version,
    about,
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
    /// Validate a job and print its id, cases, sample count and a suggested split.
    Plan(PlanArgs),
    /// Run one shard (from --range, --shard, or the Slurm/Kubernetes environment).
    Run(RunArgs),
    /// Print the exact line a shard holds for one sample (with --detail, its draws,
    /// iterations, displacements and forces).
    Reproduce(ReproduceArgs),
    /// Show which of K shards in a directory are complete, partial or missing.
    Status(StatusArgs),
    /// Claim the next unclaimed shard, run it, and repeat until none is left (for cron on
    /// machines sharing the directory).
    Work(WorkArgs),
}

/// `mc-shard work`.
#[derive(Debug, Args)]
pub struct WorkArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The shared shard directory.
    #[arg(long)]
    pub out: PathBuf,
    /// The number of shards the job is split into (the same for every worker).
    #[arg(long)]
    pub shards: u64,
    /// Threads per shard (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Seconds between heartbeats of a claim.
    #[arg(long, default_value_t = 5.0)]
    pub heartbeat: f64,
    /// Seconds after which an untouched claim is stale and taken over.
    #[arg(long, default_value_t = 60.0)]
    pub stale_after: f64,
    /// Show no progress.
    #[arg(long)]
    pub quiet: bool,
}

/// `mc-shard plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The job file.
    pub job: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `mc-shard run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// Directory for the shard file.
    #[arg(long)]
    pub out: PathBuf,
    /// Run shard I of K (0-based).
    #[arg(long, value_name = "I/K", conflicts_with = "range")]
    pub shard: Option<String>,
    /// Run the global sample indices A..B.
    #[arg(long, value_name = "A..B")]
    pub range: Option<String>,
    /// Number of shards, for JOB_COMPLETION_INDEX (default: $MC_SHARD_COUNT).
    #[arg(long)]
    pub shards: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Show no progress.
    #[arg(long)]
    pub quiet: bool,
}

/// `mc-shard reproduce`.
#[derive(Debug, Args)]
pub struct ReproduceArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The case's name.
    #[arg(long)]
    pub case: String,
    /// The sample's index within the case.
    #[arg(long)]
    pub sample: u64,
    /// Print the draws, Newton iterations, displacements and forces as JSON.
    #[arg(long)]
    pub detail: bool,
}

/// `mc-shard status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The shard directory.
    #[arg(long)]
    pub out: PathBuf,
    /// The number of shards the job was split into.
    #[arg(long)]
    pub shards: u64,
    /// Print only the 0-based indices of the shards not complete, comma-separated (a Slurm
    /// --array list; an empty line when none).
    #[arg(long)]
    pub missing: bool,
}

/// An error of a command, with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// From the run machinery.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Writing output failed.
    #[error("cannot write output: {0}")]
    Output(#[from] std::io::Error),
    /// Stopped by SIGINT or SIGTERM; `kept` sample lines are in the shard files.
    #[error("{}", crate::interrupt::message(*.kept))]
    Interrupted {
        /// The signal.
        signal: crate::interrupt::Signal,
        /// Sample lines in the shard files, kept for a rerun.
        kept: u64,
    },
}

impl From<JobError> for CliError {
    fn from(e: JobError) -> Self {
        CliError::Run(RunError::Job(e))
    }
}

impl CliError {
    /// The exit code (see [`exit`]).
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Run(e) => run_exit_code(e),
            CliError::Output(_) => exit::IO,
            CliError::Interrupted { signal, .. } => signal.exit_code(),
        }
    }
}

/// The exit code of a run error (see [`exit`]).
pub fn run_exit_code(e: &RunError) -> u8 {
    match e {
        RunError::Usage(_) => exit::USAGE,
        RunError::Job(JobError::Io { .. }) => exit::IO,
        RunError::Job(JobError::InFile { source, .. })
            if matches!(**source, JobError::Io { .. }) =>
        {
            exit::IO
        }
        RunError::Job(_) => exit::INVALID_INPUT,
        RunError::Shard(ShardError::Io { .. }) => exit::IO,
        RunError::Shard(_) => exit::IN_THE_WAY,
    }
}

/// Runs a command, writing its report to `out`; progress goes to stderr.
pub fn run(cli: Cli, out: &mut dyn Write) -> Result<(), CliError> {
    match cli.command {
        Command::Plan(a) => plan(&a, out),
        Command::Run(a) => run_command(a, out),
        Command::Reproduce(a) => reproduce_command(a, out),
        Command::Work(a) => work_command(a, out),
        Command::Status(a) => status_command(a, out),
    }
}

/// `mc-shard run`: one shard, crash-safe and resumable.
fn run_command(a: RunArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    let (range, source) = select(
        a.range.as_deref(),
        a.shard.as_deref(),
        a.shards,
        job.samples(),
        |k| std::env::var(k).ok(),
    )?;
    let threads = a
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(RunError::Usage("--threads must be at least 1".into()).into());
    }
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
        return Err(CliError::Interrupted {
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
            "{}: {} samples ({} computed now{}, {} failed) in {:.2} s, {:.0} samples/s [range from {:?}]",
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
fn reproduce_command(a: ReproduceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    let c = job.case_named(&a.case).ok_or_else(|| {
        RunError::Usage(format!(
            "no case {:?} (cases: {})",
            a.case,
            job.cases
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })?;
    if a.sample >= job.cases[c].samples {
        return Err(RunError::Usage(format!(
            "case {:?} has samples 0..{}, not {}",
            a.case, job.cases[c].samples, a.sample
        ))
        .into());
    }
    out.write_all(crate::reproduce::reproduce(&job, c, a.sample, a.detail).as_bytes())?;
    Ok(())
}

/// `mc-shard work`: claim, run and repeat until no shard is left.
fn work_command(a: WorkArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    let seconds = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(std::time::Duration::from_secs_f64(v))
        } else {
            Err(RunError::Usage(format!(
                "--{name} must be a positive number of seconds"
            )))
        }
    };
    let options = crate::work::WorkOptions {
        shards: a.shards,
        threads: a.threads.unwrap_or_else(default_threads),
        heartbeat: seconds("heartbeat", a.heartbeat)?,
        stale_after: seconds("stale-after", a.stale_after)?,
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
        return Err(CliError::Interrupted {
            signal,
            kept: kept_samples(&job, &a.out, a.shards),
        });
    }
    match failed {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

/// `mc-shard status`: which shards are complete, partial, missing or bad.
fn status_command(a: StatusArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    let states = shard_states(&job, &a.out, a.shards).map_err(RunError::Usage)?;
    if a.missing {
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
            };
            writeln!(out, "shard {i}/{} {r}: {what}", a.shards)?;
        }
    }
    Ok(())
}

/// The sample lines in the shard files of the `shards` shards of `job` in `dir` (complete
/// or partial): what a rerun keeps.
pub fn kept_samples(job: &Job, dir: &std::path::Path, shards: u64) -> u64 {
    shard_states(job, dir, shards).map_or(0, |states| {
        states
            .iter()
            .map(|(r, s)| match s {
                ShardState::Complete => r.len(),
                ShardState::Partial(n) => *n,
                ShardState::Missing | ShardState::Bad(_) => 0,
            })
            .sum()
    })
}

/// The default thread or worker count: the machine's cores.
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `mc-shard plan`: the job's id and cases, and a split suggested from a short timing.
fn plan(a: &PlanArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    // Time a few samples of each case (at most 50, at most about half a second in all).
    let mut cpu_seconds = 0.0;
    let mut per_case = Vec::new();
    let mut worker = crate::worker::Worker::new(&job);
    for c in &job.cases {
        let n = c.samples.min(50);
        let t = Instant::now();
        let mut done = 0;
        for k in 0..n {
            worker.sample(c.start + k);
            done += 1;
            if t.elapsed().as_secs_f64() > 0.5 / job.cases.len() as f64 {
                break;
            }
        }
        let each = t.elapsed().as_secs_f64() / done as f64;
        cpu_seconds += each * c.samples as f64;
        per_case.push(each);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    let advice = Advice::new(cpu_seconds, cores, job.samples());
    let cluster_shards = advice.cluster_shards.unwrap_or(1);
    if a.json {
        let value = serde_json::json!({
            "job_id": job.id,
            "samples": job.samples(),
            "cases": job.cases.iter().zip(&per_case).map(|(c, t)| serde_json::json!({
                "name": c.name, "start": c.start, "samples": c.samples,
                "parameters": c.parameters, "seconds_per_sample": t,
            })).collect::<Vec<_>>(),
            "estimated_cpu_seconds": cpu_seconds,
            "suggested": {"local_threads": cores, "cluster_shards": cluster_shards,
                          "cluster_advised": advice.cluster_shards.is_some()},
        });
        writeln!(
            out,
            "{}",
            serde_json::to_string_pretty(&value).expect("serialises")
        )?;
        return Ok(());
    }
    writeln!(out, "job id   {}", job.id)?;
    writeln!(
        out,
        "samples  {} in {} case(s)",
        job.samples(),
        job.cases.len()
    )?;
    for (c, t) in job.cases.iter().zip(&per_case) {
        let params: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        writeln!(
            out,
            "  {:<24} {:>9} samples  indices {}..{}  ~{:.0} µs/sample  {}",
            c.name,
            c.samples,
            c.start,
            c.start + c.samples,
            t * 1e6,
            params.join(" ")
        )?;
    }
    writeln!(out, "estimated {cpu_seconds:.1} CPU-seconds")?;
    writeln!(out, "{}", advice.text(&a.job.display().to_string()))?;
    Ok(())
}

/// A cluster task's work: about five minutes of one core \[s\].
pub const CLUSTER_TASK_SECONDS: f64 = 300.0;

/// Below this wall time on this machine a job is not worth a cluster \[s\].
pub const CLUSTER_WORTHWHILE_SECONDS: f64 = 600.0;

/// `mc-shard plan`'s suggestion: this machine, and a cluster split only for a job that
/// would take this machine more than [`CLUSTER_WORTHWHILE_SECONDS`].
#[derive(Debug, Clone, PartialEq)]
pub struct Advice {
    /// The job's estimated CPU time \[s\].
    pub cpu_seconds: f64,
    /// This machine's cores.
    pub cores: u64,
    /// Shards of about [`CLUSTER_TASK_SECONDS`] each, when a cluster is worth it.
    pub cluster_shards: Option<u64>,
}

impl Advice {
    /// The advice for a job of `cpu_seconds` CPU time and `samples` samples on `cores` cores.
    pub fn new(cpu_seconds: f64, cores: u64, samples: u64) -> Self {
        let cores = cores.max(1);
        let local = cpu_seconds / cores as f64;
        let cluster_shards = (local > CLUSTER_WORTHWHILE_SECONDS)
            .then(|| ((cpu_seconds / CLUSTER_TASK_SECONDS).ceil() as u64).clamp(2, samples.max(2)));
        Advice {
            cpu_seconds,
            cores,
            cluster_shards,
        }
    }

    /// The line `plan` prints for the job file `job`.
    pub fn text(&self, job: &str) -> String {
        let local = self.cpu_seconds / self.cores as f64;
        let here = format!(
            "suggested: this machine, about {} on {} (truss-mc run-all --job {job} --out DIR)",
            duration(local),
            plural(self.cores, "core", "cores"),
        );
        match self.cluster_shards {
            None => format!("{here}; no cluster needed"),
            Some(k) => format!(
                "{here}; or a cluster, {} of about {} each (--shard I/{k})",
                plural(k, "shard", "shards"),
                duration(self.cpu_seconds / k as f64),
            ),
        }
    }
}

/// `1 shard`, `2 shards`.
fn plural(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// A duration for people: `9.5 s`, `4 min`, `2.5 h`.
fn duration(seconds: f64) -> String {
    if seconds < 60.0 {
        format!("{seconds:.1} s")
    } else if seconds < 5400.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Advice;

    /// A job of seconds gets no cluster advice; a long one gets a split with the right
    /// grammar, never "1 shards".
    #[test]
    fn plan_advises_a_cluster_only_for_long_jobs() {
        let short = Advice::new(9.5, 2, 1000).text("job.json");
        assert_eq!(
            short,
            "suggested: this machine, about 4.8 s on 2 cores \
             (truss-mc run-all --job job.json --out DIR); no cluster needed"
        );
        assert!(Advice::new(0.2, 1, 10).text("j").contains("on 1 core "));
        // 20 CPU-hours on 8 cores: 2.5 h here, or 240 shards of 5 min.
        let long = Advice::new(72_000.0, 8, 300_000).text("j");
        assert!(long.contains("about 2.5 h on 8 cores"), "{long}");
        assert!(long.contains("a cluster, 240 shards of about 5 min each (--shard I/240)"));
        // Just over the threshold: at least two shards.
        let edge = Advice::new(700.0, 1, 50).cluster_shards;
        assert_eq!(edge, Some(3));
        assert_eq!(Advice::new(601.0, 1, 50).cluster_shards, Some(3));
        assert_eq!(Advice::new(599.0, 1, 50).cluster_shards, None);
        for cpu in [0.0, 1.0, 650.0, 1e4, 1e6] {
            assert!(!Advice::new(cpu, 1, 100).text("j").contains("1 shards"));
        }
    }
}
