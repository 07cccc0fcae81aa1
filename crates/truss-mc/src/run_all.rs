//! `truss-mc run-all`: the whole job on this machine, as concurrent shard processes, then the
//! merge. What the README's main command runs.
//!
//! The job is split into `K` shards (default: as many as workers); up to `W` workers
//! (default: the number of cores) run at once, each a child process `truss-mc run --shard
//! i/K --threads 1 --quiet` (mc-shard's `run`) (so a crash of one loses only its sample in flight, and a rerun
//! resumes every shard where it stopped). tokio runs the children and a single progress
//! display that counts the sample lines the shard files have gained. When all shards are
//! complete the directory is merged with mc-merge into `DIR/report`.

use mc_shard::progress::Progress;
use mc_shard::{Job, RunError};
use shard_record::ShardRange;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// Why `run-all` stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunAllError {
    /// The job, the shard directory or the arguments.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Shard processes failed (each with its stderr).
    #[error("{} shard process(es) failed: {}; run the same command again to resume them", .0.len(), .0.join("; "))]
    Workers(Vec<String>),
    /// The merge failed.
    #[error("merge failed: {0}")]
    Merge(mc_merge::MergeError),
}

/// Options of `run-all`.
#[derive(Debug, Clone)]
pub struct RunAllOptions {
    /// The job file (children read it).
    pub job_path: PathBuf,
    /// Shard directory.
    pub out: PathBuf,
    /// Number of shards.
    pub shards: u64,
    /// Concurrent worker processes.
    pub workers: usize,
    /// Show no progress.
    pub quiet: bool,
    /// Skip the merge.
    pub no_merge: bool,
}

/// Runs every shard with child processes of the executable `exe`, then merges; writes the
/// merge table to `out`.
pub fn run_all(
    exe: &Path,
    job: &Job,
    options: &RunAllOptions,
    out: &mut dyn Write,
) -> Result<(), RunAllError> {
    let ranges = ShardRange::partition(options.shards, job.samples())
        .map_err(|e| RunError::Usage(e.to_string()))?;
    std::fs::create_dir_all(&options.out).map_err(|source| {
        RunError::Shard(mc_shard::ShardError::Io {
            path: options.out.clone(),
            source,
        })
    })?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| RunError::Usage(format!("cannot start the async runtime: {e}")))?;
    let failures = runtime.block_on(run_children(exe, job, &ranges, options))?;
    if !failures.is_empty() {
        return Err(RunAllError::Workers(failures));
    }
    if options.no_merge {
        return Ok(());
    }
    let merge = mc_merge::Options {
        paths: vec![options.out.clone()],
        out: Some(options.out.join("report")),
        plots: true,
        settings: mc_merge::Settings::default(),
    };
    mc_merge::run(&merge, out).map_err(RunAllError::Merge)?;
    Ok(())
}

/// Runs the shard processes, at most `workers` at once, with one progress display; returns
/// a description of each that failed.
async fn run_children(
    exe: &Path,
    job: &Job,
    ranges: &[ShardRange],
    options: &RunAllOptions,
) -> Result<Vec<String>, RunError> {
    let k = ranges.len();
    let limit = Arc::new(tokio::sync::Semaphore::new(options.workers.max(1)));
    let mut tasks = tokio::task::JoinSet::new();
    for (i, _) in ranges.iter().enumerate() {
        let limit = Arc::clone(&limit);
        let mut cmd = tokio::process::Command::new(exe);
        cmd.args(["run", "--job"])
            .arg(&options.job_path)
            .arg("--out")
            .arg(&options.out)
            .args(["--shard", &format!("{i}/{k}"), "--threads", "1", "--quiet"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .kill_on_drop(true);
        tasks.spawn(async move {
            let _permit = limit
                .acquire_owned()
                .await
                .expect("the semaphore is never closed");
            match cmd.output().await {
                Ok(o) if o.status.success() => None,
                Ok(o) => Some(format!(
                    "shard {i}/{k}: {}",
                    String::from_utf8_lossy(&o.stderr).trim()
                )),
                Err(e) => Some(format!("shard {i}/{k}: cannot start: {e}")),
            }
        });
    }
    // Progress: newlines the shard files have gained.
    let mut progress = Progress::new("run-all", job.samples(), 0, options.quiet);
    let mut counted = vec![(0u64, 0u64); k];
    let mut failures = Vec::new();
    let mut tick = tokio::time::interval(Duration::from_millis(200));
    loop {
        tokio::select! {
            done = tasks.join_next() => match done {
                Some(Ok(Some(failure))) => failures.push(failure),
                Some(Ok(None)) => {}
                Some(Err(e)) => failures.push(format!("a task panicked: {e}")),
                None => break,
            },
            _ = tick.tick() => {}
        }
        let mut gained = 0;
        for (r, (offset, lines)) in ranges.iter().zip(counted.iter_mut()) {
            gained += count_new_lines(&options.out.join(r.file_name()), offset, lines, r.len());
        }
        progress.advance(gained);
    }
    progress.finish();
    Ok(failures)
}

/// Counts the sample lines appended to `path` since `offset` (header and end lines not
/// counted, at most `max` in all), advancing `offset`; returns how many are new.
fn count_new_lines(path: &Path, offset: &mut u64, lines: &mut u64, max: u64) -> u64 {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut f) = std::fs::File::open(path) else {
        return 0;
    };
    let len = f.metadata().map_or(0, |m| m.len());
    if len < *offset {
        // Started afresh (its header had been torn): count again from the start.
        *offset = 0;
        *lines = 0;
    }
    if f.seek(SeekFrom::Start(*offset)).is_err() {
        return 0;
    }
    let mut buf = Vec::new();
    if f.read_to_end(&mut buf).is_err() {
        return 0;
    }
    let end = buf.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    *offset += end as u64;
    let newlines = buf[..end].iter().filter(|&&b| b == b'\n').count() as u64;
    // The first line is the header; the last, once complete, the end line.
    let total = (*lines + newlines).saturating_sub(1).min(max);
    let before = lines.saturating_sub(1).min(max);
    *lines += newlines;
    total - before
}
