//! `truss-mc run-all`: the whole job on this machine, as concurrent shard processes, then the
//! merge. What the README's main command runs.
//!
//! The job is split into `K` shards (default: as many as workers); up to `W` workers
//! (default: the number of cores) run at once, each a child process `truss-mc run --shard
//! i/K --threads 1 --quiet` (mc-shard's `run`) (so a crash of one loses only its sample in flight, and a rerun
//! resumes every shard where it stopped). tokio runs the children and a single progress
//! display that counts the sample lines the shard files have gained. When all shards are
//! complete, a seeded sample of [`DEFAULT_AUDIT_SAMPLES`] lines is re-solved and compared
//! byte for byte (`mc-shard audit`; `--audit-samples N`, 0 to skip; exit 6 on a mismatch),
//! then the directory is merged with mc-merge into `DIR/report` (`--allow-failed` passed
//! on).
//!
//! **Failed shard processes** map to one exit code and advice ([`worker_failure`]): a file
//! in the way (another job's shard, a damaged file: 5) is named with the advice to move it
//! away, since a rerun would meet it again; a shard another live process is writing (5) with
//! the advice to wait for it or stop it; otherwise 6 and "run the same command again to
//! resume".
//!
//! **No shard process outlives `run-all`.** Each child asks the kernel for SIGTERM when
//! `run-all` ends, however it ends (`kill -9`, the out-of-memory killer): a parent-death
//! signal (Linux `prctl(PR_SET_PDEATHSIG)`, [`die_with_parent`]). The child then stops as
//! on any SIGTERM, keeping every finished line, and its shard's lock is released.
//!
//! **The report directory** `DIR/report` is refused before any shard runs when it is a
//! symbolic link (exit 5): the merge would write wherever it points.
//!
//! **Interrupts.** On SIGINT or SIGTERM sent to `run-all` alone (`kill PID`, a supervisor, a
//! batch system's time limit) or to its whole process group (Ctrl-C), no further shard
//! starts, each running child is sent SIGTERM (its runner appends what it finished and
//! stops; SIGKILL after a grace period), a merge in progress is abandoned, and `run-all`
//! returns [`RunAllError::Interrupted`]: the binary prints "interrupted: N samples kept;
//! rerun the same command to resume" and exits 130 (SIGINT) or 143 (SIGTERM). No child
//! outlives it.

use mc_shard::commands::CommandError;
use mc_shard::interrupt::Signal;
use mc_shard::progress::Progress;
use mc_shard::status::kept_samples;
use mc_shard::{Job, RunError};
use shard_record::ShardRange;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// Why `run-all` stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunAllError {
    /// The job, the shard directory or the arguments; or the audit before the merge, which
    /// could not be completed or found lines that differ from their re-solve.
    #[error(transparent)]
    Shard(#[from] CommandError),
    /// Shard processes failed (each with its exit code and stderr); the code `run-all`
    /// exits with and the advice follow from the children's codes ([`worker_failure`]).
    #[error("{} shard process(es) failed: {}; {}", .0.len(), .0.iter().map(|(_, m)| m.as_str()).collect::<Vec<_>>().join("; "), worker_failure(.0).1)]
    Workers(Vec<(u8, String)>),
    /// The merge failed.
    #[error("merge failed: {0}{hint}", hint = merge_hint(.0))]
    Merge(mc_merge::MergeError),
    /// Stopped by SIGINT or SIGTERM; `kept` sample lines are in the shard files.
    #[error("{}", mc_shard::interrupt::message(*.kept))]
    Interrupted {
        /// The signal.
        signal: Signal,
        /// Sample lines in the shard files, kept for a rerun.
        kept: u64,
    },
}

/// The exit code and advice for failed shard processes: a file in the way (5: another
/// job's shard, a damaged file) when any child says so, which a rerun does not cure (only
/// shards locked by live processes: wait for them); the children's own code when they agree on another (a usage or input error);
/// otherwise the verification code (6), which a rerun resumes.
pub fn worker_failure(failures: &[(u8, String)]) -> (u8, &'static str) {
    let in_the_way: Vec<&str> = failures
        .iter()
        .filter(|(c, _)| *c == truss_exit::IN_THE_WAY)
        .map(|(_, m)| m.as_str())
        .collect();
    if !in_the_way.is_empty()
        && in_the_way
            .iter()
            .all(|m| m.contains(mc_shard::errors::LOCKED))
    {
        return (
            truss_exit::IN_THE_WAY,
            "a shard is being written by another process: wait for it or stop it, then run the same command again; the other shards are kept",
        );
    }
    if !in_the_way.is_empty() {
        return (
            truss_exit::IN_THE_WAY,
            "a file is in the way: move it away (or use another --out), then run the same command again; the other shards are kept",
        );
    }
    match failures.first() {
        Some((c, _))
            if failures.iter().all(|(d, _)| d == c)
                && [truss_exit::USAGE, truss_exit::INVALID_INPUT, truss_exit::IO].contains(c) =>
        {
            (
                *c,
                "fix the cause above, then run the same command again to resume",
            )
        }
        _ => (
            truss_exit::VERIFICATION,
            "run the same command again to resume them",
        ),
    }
}

impl From<RunError> for RunAllError {
    fn from(e: RunError) -> Self {
        RunAllError::Shard(e.into())
    }
}

/// What `run-all` adds to a merge error: for failed samples, that it takes `--allow-failed`.
fn merge_hint(e: &mc_merge::MergeError) -> &'static str {
    if matches!(e, mc_merge::MergeError::FailedSamples { .. }) {
        " (run-all takes --allow-failed too: rerun the same command with it; the finished shards are kept)"
    } else {
        ""
    }
}

/// Sample lines `run-all` audits before it merges, by default.
pub const DEFAULT_AUDIT_SAMPLES: u64 = 32;

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
    /// Lines to audit before the merge (0: none).
    pub audit_samples: u64,
    /// Merge with failed samples present (mc-merge's `--allow-failed`).
    pub allow_failed: bool,
}

/// Runs every shard with child processes of the executable `exe`, then merges; writes the
/// merge table to `out`.
///
/// On SIGINT or SIGTERM (see the module doc) it stops: no new shard starts, every running
/// child gets SIGTERM (and SIGKILL after [`GRACE`]), and it returns
/// [`RunAllError::Interrupted`] with the sample lines the shard files keep.
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
    if !options.no_merge {
        // Before any work: the merge must not write through a link.
        run_dir::create_dir(&options.out.join("report")).map_err(|e| RunError::Shard(e.into()))?;
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| RunError::Usage(format!("cannot start the async runtime: {e}")))?;
    let result = runtime.block_on(run_and_merge(exe, job, &ranges, options));
    // A merge still running on a blocking thread after a signal is not waited for.
    runtime.shutdown_background();
    match result {
        Ok(table) => out.write_all(&table).map_err(|source| {
            RunAllError::Merge(mc_merge::MergeError::Io {
                path: PathBuf::from("<stdout>"),
                source,
            })
        }),
        Err(RunAllError::Interrupted { signal, .. }) => Err(RunAllError::Interrupted {
            signal,
            kept: kept_samples(job, &options.out, options.shards),
        }),
        Err(e) => Err(e),
    }
}

/// The signals `run-all` stops on, as a stream of [`Signal`]s.
struct Signals {
    interrupt: tokio::signal::unix::Signal,
    terminate: tokio::signal::unix::Signal,
}

impl Signals {
    fn new() -> Result<Self, RunError> {
        use tokio::signal::unix::{SignalKind, signal};
        let fail = |e: std::io::Error| RunError::Usage(format!("cannot handle signals: {e}"));
        Ok(Signals {
            interrupt: signal(SignalKind::interrupt()).map_err(fail)?,
            terminate: signal(SignalKind::terminate()).map_err(fail)?,
        })
    }

    async fn recv(&mut self) -> Signal {
        tokio::select! {
            _ = self.interrupt.recv() => Signal::Interrupt,
            _ = self.terminate.recv() => Signal::Terminate,
        }
    }
}

/// Runs the children, then (unless `no_merge`) the merge; returns the merge's table.
async fn run_and_merge(
    exe: &Path,
    job: &Job,
    ranges: &[ShardRange],
    options: &RunAllOptions,
) -> Result<Vec<u8>, RunAllError> {
    let mut signals = Signals::new()?;
    let (failures, interrupted) = run_children(exe, job, ranges, options, &mut signals).await?;
    if let Some(signal) = interrupted {
        // `kept` is counted by `run_all` once the runtime has stopped.
        return Err(RunAllError::Interrupted { signal, kept: 0 });
    }
    if !failures.is_empty() {
        return Err(RunAllError::Workers(failures));
    }
    if options.no_merge {
        return Ok(Vec::new());
    }
    let mut table = Vec::new();
    if options.audit_samples > 0 {
        if !options.quiet {
            eprintln!(
                "run-all: auditing: re-solving {} sampled lines and comparing them byte for byte…",
                options.audit_samples
            );
        }
        let audit_options = mc_shard::audit::AuditOptions {
            samples: options.audit_samples,
            seed: 0,
            threads: options.workers.max(1),
        };
        let (job, out) = (job.clone(), options.out.clone());
        let auditing = tokio::task::spawn_blocking(move || {
            let report =
                mc_shard::audit::audit(&job, &[out], &audit_options).map_err(CommandError::from)?;
            let verdict = report.verdict().map_err(CommandError::from)?;
            Ok::<_, RunAllError>(format!("{verdict}\n").into_bytes())
        });
        tokio::select! {
            done = auditing => match done {
                Ok(result) => table.extend(result?),
                Err(e) => return Err(RunError::Usage(format!("the audit panicked: {e}")).into()),
            },
            signal = signals.recv() => return Err(RunAllError::Interrupted { signal, kept: 0 }),
        }
    }
    let merge = mc_merge::Options {
        paths: vec![options.out.clone()],
        out: Some(options.out.join("report")),
        plots: true,
        progress: !options.quiet,
        settings: mc_merge::Settings {
            allow_failed: options.allow_failed,
            ..mc_merge::Settings::default()
        },
    };
    if !options.quiet {
        eprintln!(
            "run-all: merging: verifying every shard, bootstrapping the intervals, drawing the plots…"
        );
    }
    let merging =
        tokio::task::spawn_blocking(move || mc_merge::run(&merge, &mut table).map(|_| table));
    tokio::select! {
        done = merging => match done {
            Ok(result) => result.map_err(RunAllError::Merge),
            Err(e) => Err(RunError::Usage(format!("the merge panicked: {e}")).into()),
        },
        signal = signals.recv() => Err(RunAllError::Interrupted { signal, kept: 0 }),
    }
}

/// The environment variable through which `run-all` gives its shard processes its pid.
pub const PARENT_PID_ENV: &str = "TRUSS_MC_RUN_ALL_PID";

/// In a shard process of `run-all` ([`PARENT_PID_ENV`] set): asks the kernel to send this
/// process SIGTERM when `run-all` ends, however it ends, and sends it now if `run-all` is
/// already gone (it died before the request was made). Elsewhere, or on a system without
/// parent-death signals, nothing.
pub fn die_with_parent() {
    let Some(parent) = std::env::var(PARENT_PID_ENV)
        .ok()
        .and_then(|p| p.parse::<i32>().ok())
    else {
        return;
    };
    #[cfg(target_os = "linux")]
    {
        use rustix::process::{Pid, Signal, getpid, getppid, kill_process};
        if rustix::process::set_parent_process_death_signal(Some(Signal::TERM)).is_ok()
            && Pid::as_raw(getppid()) != parent
        {
            let _ = kill_process(getpid(), Signal::TERM);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = parent;
}

/// Which shards a rerun reuses, by their number `I` of `--shard I/K`: those complete (skipped:
/// their files are verified, not rerun) and those resumed where they stopped, with the lines
/// they keep; `counted` holds each shard file's (offset, sample lines).
fn reused(ranges: &[ShardRange], counted: &[(u64, u64)]) -> String {
    let k = ranges.len();
    let complete: Vec<usize> = (0..k)
        .filter(|&i| counted[i].1 == ranges[i].len())
        .collect();
    let resumed: Vec<String> = (0..k)
        .filter(|&i| counted[i].1 > 0 && counted[i].1 < ranges[i].len())
        .map(|i| format!("{i} ({} of {})", counted[i].1, ranges[i].len()))
        .collect();
    let complete = match complete.len() {
        0 => format!("no shard of {k} complete"),
        n if n == k => format!("all {k} shards complete (verified, not rerun)"),
        n => format!(
            "{n} of {k} shards complete (verified, not rerun): {}",
            index_runs(&complete)
        ),
    };
    if resumed.is_empty() {
        complete
    } else {
        format!(
            "{complete}; resumed where they stopped: {}",
            resumed.join(", ")
        )
    }
}

/// Ascending indices as runs: `0-3, 5, 7-8`.
fn index_runs(indices: &[usize]) -> String {
    let mut runs: Vec<(usize, usize)> = vec![];
    for &i in indices {
        match runs.last_mut() {
            Some((_, end)) if *end + 1 == i => *end = i,
            _ => runs.push((i, i)),
        }
    }
    runs.iter()
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// How long a child may take to stop after SIGTERM before it is killed.
pub const GRACE: Duration = Duration::from_secs(10);

/// Runs the shard processes, at most `workers` at once, with one progress display; returns
/// the exit code and a description of each that failed, and the signal that interrupted the
/// run if one did.
async fn run_children(
    exe: &Path,
    job: &Job,
    ranges: &[ShardRange],
    options: &RunAllOptions,
    signals: &mut Signals,
) -> Result<(Vec<(u8, String)>, Option<Signal>), RunError> {
    let k = ranges.len();
    // Progress: the sample lines the shard files hold before any child starts (kept from
    // an interrupted run: not counted in the rate), then the lines they gain.
    let mut counted = vec![(0u64, 0u64); k];
    let mut kept = 0;
    for (r, (offset, lines)) in ranges.iter().zip(counted.iter_mut()) {
        kept += count_new_lines(&options.out.join(r.file_name()), offset, lines, r.len());
    }
    if kept > 0 && !options.quiet {
        eprintln!(
            "run-all: reusing {kept} samples already in {}: {}",
            options.out.display(),
            reused(ranges, &counted)
        );
    }
    let limit = Arc::new(tokio::sync::Semaphore::new(options.workers.max(1)));
    let (cancel_tx, cancel_rx) = tokio::sync::watch::channel(false);
    let mut tasks = tokio::task::JoinSet::new();
    for (i, _) in ranges.iter().enumerate() {
        let limit = Arc::clone(&limit);
        let mut cancel = cancel_rx.clone();
        let mut cmd = tokio::process::Command::new(exe);
        cmd.env(PARENT_PID_ENV, std::process::id().to_string())
            .args(["run", "--job"])
            .arg(&options.job_path)
            .arg("--out")
            .arg(&options.out)
            .args(["--shard", &format!("{i}/{k}"), "--threads", "1", "--quiet"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .kill_on_drop(true);
        tasks.spawn(async move {
            let _permit = tokio::select! {
                permit = limit.acquire_owned() => permit.expect("the semaphore is never closed"),
                _ = cancel.changed() => return None,
            };
            if *cancel.borrow() {
                return None;
            }
            let child = match cmd.spawn() {
                Ok(child) => child,
                Err(e) => {
                    return Some((truss_exit::IO, format!("shard {i}/{k}: cannot start: {e}")));
                }
            };
            let pid = child.id();
            let output = child.wait_with_output();
            tokio::pin!(output);
            let output = tokio::select! {
                o = &mut output => o,
                _ = cancel.changed() => {
                    if let Some(pid) = pid.and_then(|p| rustix::process::Pid::from_raw(p as i32)) {
                        let _ = rustix::process::kill_process(pid, rustix::process::Signal::TERM);
                    }
                    // After the grace period the future is dropped: kill_on_drop kills it.
                    let _ = tokio::time::timeout(GRACE, &mut output).await;
                    return None;
                }
            };
            match output {
                Ok(o) if o.status.success() => None,
                Ok(o) => Some((
                    o.status
                        .code()
                        .and_then(|c| u8::try_from(c).ok())
                        .unwrap_or(truss_exit::VERIFICATION),
                    format!(
                        "shard {i}/{k}: {}",
                        String::from_utf8_lossy(&o.stderr).trim()
                    ),
                )),
                Err(e) => Some((truss_exit::IO, format!("shard {i}/{k}: cannot run: {e}"))),
            }
        });
    }
    let mut progress = Progress::new("run-all", job.samples(), kept, options.quiet);
    let mut failures = Vec::new();
    let mut interrupted = None;
    let mut tick = tokio::time::interval(Duration::from_millis(200));
    loop {
        tokio::select! {
            done = tasks.join_next() => match done {
                Some(Ok(Some(failure))) => failures.push(failure),
                Some(Ok(None)) => {}
                Some(Err(e)) => failures.push((truss_exit::INTERNAL, format!("a task panicked: {e}"))),
                None => break,
            },
            signal = signals.recv(), if interrupted.is_none() => {
                interrupted = Some(signal);
                let _ = cancel_tx.send(true);
            }
            _ = tick.tick() => {}
        }
        let mut gained = 0;
        for (r, (offset, lines)) in ranges.iter().zip(counted.iter_mut()) {
            gained += count_new_lines(&options.out.join(r.file_name()), offset, lines, r.len());
        }
        progress.advance(gained);
    }
    progress.finish();
    Ok((failures, interrupted))
}

/// Counts the sample lines appended to `path` since `offset` (header, checkpoint and end
/// lines not counted, at most `max` in all), advancing `offset`; returns how many are new.
fn count_new_lines(path: &Path, offset: &mut u64, lines: &mut u64, max: u64) -> u64 {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut f) = run_dir::input::open_own(path, std::fs::OpenOptions::new().read(true)) else {
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
    let samples = buf[..end]
        .split(|&b| b == b'\n')
        .filter(|l| l.starts_with(br#"{"record":"sample""#))
        .count() as u64;
    let total = (*lines + samples).min(max);
    let before = (*lines).min(max);
    *lines += samples;
    total - before
}
