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
    /// Run one shard (from --range, --shard, or a batch system's environment: Slurm, AWS
    /// Batch, Google Cloud Batch, Kubernetes, or MC_SHARD_INDEX/MC_SHARD_COUNT).
    Run(RunArgs),
    /// Print the exact line a shard holds for one sample (with --detail, its draws,
    /// iterations, displacements and forces).
    Reproduce(ReproduceArgs),
    /// Show which of K shards in a directory are complete, partial or missing.
    Status(StatusArgs),
    /// Claim the next unclaimed shard, run it, and repeat until none is left (for cron on
    /// machines sharing the directory); a damaged shard is quarantined and the others run.
    Work(WorkArgs),
    /// Re-solve a seeded random sample of a run's lines and compare them byte for byte;
    /// writes audit.json beside the shards.
    Audit(AuditArgs),
    /// Write each sample's drawn member length errors and joint clearances (mm) as CSV,
    /// regenerated from the seed and keyed by the shard lines' index.
    Inputs(InputsArgs),
    /// Print a shell completion script (bash, zsh or fish) to stdout.
    Completions(CompletionsArgs),
    /// Print the man page (roff) to stdout.
    Man,
}

/// The largest `--shards` count: each shard is a file (and for `run-all` a process).
pub const MAX_SHARDS: u64 = 1_000_000;

/// The longest `--heartbeat` or `--stale-after` \[s\]: one week.
pub const MAX_SECONDS: f64 = 7.0 * 24.0 * 3600.0;

pub use truss_threads::MAX_THREADS;

/// Checks a thread or worker count given as `--NAME` (1 to [`MAX_THREADS`]).
pub fn check_threads(name: &str, threads: usize) -> Result<usize, RunError> {
    if truss_threads::accepted(threads) {
        Ok(threads)
    } else {
        Err(RunError::Usage(format!(
            "--{name} must be 1 to {MAX_THREADS}, not {threads}"
        )))
    }
}

/// Checks a shard count given as `--shards` (1 to [`MAX_SHARDS`]).
pub fn check_shards(shards: u64) -> Result<u64, RunError> {
    if (1..=MAX_SHARDS).contains(&shards) {
        Ok(shards)
    } else {
        Err(RunError::Usage(format!(
            "--shards must be 1 to {MAX_SHARDS}, not {shards}"
        )))
    }
}

/// `mc-shard audit`.
#[derive(Debug, Args)]
pub struct AuditArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// Shard directories or files.
    #[arg(required = true, value_name = "DIR_OR_FILE")]
    pub paths: Vec<PathBuf>,
    /// Sample lines to re-solve (at most 1,000,000).
    #[arg(long, default_value_t = 100)]
    pub samples: u64,
    /// Seed of the random choice of lines (the same seed and files give the same choice).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

/// `mc-shard inputs`.
#[derive(Debug, Args)]
pub struct InputsArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// Only this case's samples.
    #[arg(long)]
    pub case: Option<String>,
    /// Only the global sample indices A..B.
    #[arg(long, value_name = "A..B")]
    pub range: Option<String>,
    /// The CSV file to write.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
}

/// `mc-shard completions`.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// `mc-shard work`.
#[derive(Debug, Args)]
pub struct WorkArgs {
    /// The job file.
    #[arg(long)]
    pub job: PathBuf,
    /// The shared shard directory.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// The number of shards the job is split into (the same for every worker).
    #[arg(long)]
    pub shards: u64,
    /// Threads per shard (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Seconds between heartbeats of a claim (more than 0, at most a week, less than
    /// --stale-after).
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
    pub heartbeat: f64,
    /// Seconds after which an untouched claim is stale and taken over (at most a week).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    pub stale_after: f64,
    /// Show no progress.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// `mc-shard plan`.
#[derive(Debug, Args)]
pub struct PlanArgs {
    /// The job file.
    #[arg(long)]
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
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Run shard I of K (0-based).
    #[arg(long, value_name = "I/K", conflicts_with = "range")]
    pub shard: Option<String>,
    /// Run the global sample indices A..B.
    #[arg(long, value_name = "A..B")]
    pub range: Option<String>,
    /// Number of shards, for JOB_COMPLETION_INDEX or MC_SHARD_INDEX (default:
    /// $MC_SHARD_COUNT).
    #[arg(long)]
    pub shards: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Show no progress.
    #[arg(long, short = 'q')]
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
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// The number of shards the job was split into.
    #[arg(long)]
    pub shards: u64,
    /// Print only the 0-based indices of the shards not complete, comma-separated (a Slurm
    /// --array list; an empty line when none).
    #[arg(long, conflicts_with = "json")]
    pub missing: bool,
    /// Print JSON: one object per shard (`shard`, `range`, `state`, `samples`, `reason`).
    #[arg(long)]
    pub json: bool,
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
    /// An audit could not be completed.
    #[error(transparent)]
    Audit(#[from] crate::audit::AuditError),
    /// An audit found lines that differ from their re-solve.
    #[error("audit: {} of {checked} re-solved lines differ from the shards (verification failed; details in {}): {}", .mismatches.len(), .report.display(), .mismatches.iter().take(5).map(|m| format!("{}:{}: index {} (case {:?}, sample {})", m.file.display(), m.line, m.index, m.case, m.sample)).collect::<Vec<_>>().join("; "))]
    AuditMismatch {
        /// The lines that differ.
        mismatches: Vec<crate::audit::Mismatch>,
        /// Lines compared.
        checked: u64,
        /// The audit.json written.
        report: PathBuf,
    },
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
            CliError::Audit(e) => e.exit_code(),
            CliError::AuditMismatch { .. } => exit::VERIFICATION,
            CliError::Quarantined { .. } => exit::IN_THE_WAY,
            CliError::Interrupted { signal, .. } => signal.exit_code(),
        }
    }
}

/// The exit code of a run error (see [`exit`]).
pub fn run_exit_code(e: &RunError) -> u8 {
    match e {
        RunError::Usage(_) => exit::USAGE,
        RunError::Job(e) if e.is_io() => exit::IO,
        RunError::Job(_) => exit::INVALID_INPUT,
        RunError::Shard(ShardError::Io { .. }) => exit::IO,
        RunError::Shard(ShardError::Files(e)) => e.exit_code(),
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
) -> Result<(), CliError> {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut cmd, name, &mut script);
    out.write_all(&script)?;
    Ok(())
}

/// Writes `cmd`'s man page (roff), with a section per subcommand, to `out`.
pub fn man_page(cmd: clap::Command, out: &mut dyn Write) -> Result<(), CliError> {
    let cmd = cmd.after_help(truss_exit::SUMMARY);
    clap_mangen::Man::new(cmd.clone()).render(out)?;
    for sub in cmd.get_subcommands() {
        let name = format!("{}-{}", cmd.get_name(), sub.get_name());
        clap_mangen::Man::new(sub.clone()).title(name).render(out)?;
    }
    Ok(())
}

/// `mc-shard audit`: re-solve a seeded sample of lines; exit 6 on a mismatch.
fn audit_command(a: AuditArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let threads = check_threads("threads", truss_threads::or_available(a.threads))?;
    let job = Job::read(&a.job)?;
    let options = crate::audit::AuditOptions {
        samples: a.samples,
        seed: a.seed,
        threads,
    };
    let report = crate::audit::audit(&job, &a.paths, &options)?;
    audit_result(&report, out)
}

/// Prints an audit's summary line; a mismatch is an error (exit 6).
pub fn audit_result(
    report: &crate::audit::AuditReport,
    out: &mut dyn Write,
) -> Result<(), CliError> {
    if !report.mismatches.is_empty() {
        return Err(CliError::AuditMismatch {
            mismatches: report.mismatches.clone(),
            checked: report.samples_checked,
            report: report.written_to.clone(),
        });
    }
    writeln!(
        out,
        "audit: {} of {} sample lines in {} file(s) re-solved in {:.2} s (seed {}): all byte-identical; {}",
        report.samples_checked,
        report.lines_in_shards,
        report.files.len(),
        report.seconds,
        report.seed,
        report.written_to.display()
    )?;
    Ok(())
}

/// `mc-shard inputs`: the drawn inputs as CSV.
fn inputs_command(a: InputsArgs, out: &mut dyn Write) -> Result<(), CliError> {
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
        CliError::Run(RunError::Shard(ShardError::Io {
            path: a.out.clone(),
            source,
        }))
    };
    // Written whole or not at all: a full disk leaves the old file at its name.
    let files = |e: run_dir::RunDirError| CliError::Run(RunError::Shard(e.into()));
    let mut w = run_dir::OutputFile::create(&a.out).map_err(files)?;
    let rows = crate::inputs::write_inputs(&job, case, range, &mut w).map_err(io)?;
    w.commit().map_err(files)?;
    writeln!(out, "{}: {rows} samples' inputs (mm)", a.out.display())?;
    Ok(())
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
fn reproduce_command(a: ReproduceArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let job = Job::read(&a.job)?;
    let c = crate::select::case_named(&job, &a.case)?;
    crate::select::check_sample(&job, c, a.sample)?;
    out.write_all(crate::reproduce::reproduce(&job, c, a.sample, a.detail).as_bytes())?;
    Ok(())
}

/// `mc-shard work`: claim, run and repeat until no shard is left.
fn work_command(a: WorkArgs, out: &mut dyn Write) -> Result<(), CliError> {
    check_shards(a.shards)?;
    let seconds = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 && v <= MAX_SECONDS {
            Ok(std::time::Duration::from_secs_f64(v))
        } else {
            Err(RunError::Usage(format!(
                "--{name} must be a number of seconds above 0 and at most {MAX_SECONDS} (a week), not {v}"
            )))
        }
    };
    let heartbeat = seconds("heartbeat", a.heartbeat)?;
    let stale_after = seconds("stale-after", a.stale_after)?;
    if heartbeat >= stale_after {
        return Err(RunError::Usage(format!(
            "--heartbeat ({} s) must be shorter than --stale-after ({} s), or live claims would be taken over",
            a.heartbeat, a.stale_after
        ))
        .into());
    }
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
        return Err(CliError::Interrupted {
            signal,
            kept: kept_samples(&job, &a.out, a.shards),
        });
    }
    if let Some(e) = failed {
        return Err(e.into());
    }
    let quarantined: Vec<(u64, String)> = (0..a.shards)
        .filter_map(|i| crate::work::quarantined(&a.out, i, a.shards).map(|why| (i, why)))
        .collect();
    if !quarantined.is_empty() {
        return Err(CliError::Quarantined {
            shards: quarantined,
            dir: a.out.join("quarantine"),
        });
    }
    Ok(())
}

/// `mc-shard status`: which shards are complete, partial, missing or bad.
fn status_command(a: StatusArgs, out: &mut dyn Write) -> Result<(), CliError> {
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

/// The sample lines in the shard files of the `shards` shards of `job` in `dir` (complete
/// or partial): what a rerun keeps.
pub fn kept_samples(job: &Job, dir: &std::path::Path, shards: u64) -> u64 {
    shard_states(job, dir, shards).map_or(0, |states| {
        states
            .iter()
            .map(|(r, s)| match s {
                ShardState::Complete => r.len(),
                ShardState::Partial(n) => *n,
                ShardState::Missing | ShardState::Bad(_) | ShardState::Quarantined(_) => 0,
            })
            .sum()
    })
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
    let cores = truss_threads::available() as u64;
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
