//! The `mc-shard` command line: the flags of each command, parsed by clap and checked
//! against their documented ranges. What a command does is [`crate::commands`]'s; the exit
//! code of each failure is [`crate::commands::exit_code`]'s.

use crate::errors::RunError;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::time::Duration;

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

/// The most threads (or `run-all` workers) a command starts.
pub const MAX_THREADS: usize = 1024;

/// Checks a thread or worker count given as `--NAME` (1 to [`MAX_THREADS`]).
pub fn check_threads(name: &str, threads: usize) -> Result<usize, RunError> {
    if (1..=MAX_THREADS).contains(&threads) {
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

impl WorkArgs {
    /// `--heartbeat` and `--stale-after`, each above 0 and at most [`MAX_SECONDS`], the
    /// heartbeat the shorter (or live claims would be taken over).
    pub fn durations(&self) -> Result<(Duration, Duration), RunError> {
        let seconds = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 && v <= MAX_SECONDS {
                Ok(Duration::from_secs_f64(v))
            } else {
                Err(RunError::Usage(format!(
                    "--{name} must be a number of seconds above 0 and at most {MAX_SECONDS} (a week), not {v}"
                )))
            }
        };
        let heartbeat = seconds("heartbeat", self.heartbeat)?;
        let stale_after = seconds("stale-after", self.stale_after)?;
        if heartbeat >= stale_after {
            return Err(RunError::Usage(format!(
                "--heartbeat ({} s) must be shorter than --stale-after ({} s), or live claims would be taken over",
                self.heartbeat, self.stale_after
            )));
        }
        Ok((heartbeat, stale_after))
    }
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

/// The default thread or worker count: the machine's cores.
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
