//! `mc-shard work`: a worker that claims the next unclaimed shard of a job in a shared
//! directory, runs it, and repeats until none is left. Safe with several workers on several
//! machines (cron on workstations sharing a directory).
//!
//! ## Protocol
//!
//! - **Claim.** Shard `i` of `K` is claimed by creating `DIR/claims/shard-i-of-K.claim` with
//!   `O_CREAT|O_EXCL` (atomic: exactly one creator wins), holding the claimant's host, pid
//!   and claim time as JSON.
//! - **Heartbeat.** While it works, the claimant rewrites its claim's modification time
//!   every `heartbeat` (default 5 s).
//! - **Stale claims are taken over.** A claim not touched for `stale_after` (default 60 s)
//!   belongs to a dead worker. To replace it a worker first creates the takeover lock
//!   `shard-i-of-K.claim.takeover` (again `O_EXCL`, so one worker at a time), re-checks that the
//!   claim is still stale, replaces it, and removes the lock. A takeover lock itself older
//!   than `stale_after` is removed.
//! - **The shard file's own lock decides.** Running a shard takes the exclusive OS lock on
//!   its file (see [`crate::shard`]), so even two workers that both believe they hold a claim
//!   cannot write one file together: the second finds it locked and moves on. A dead
//!   worker's partial shard is resumed from its last whole line.
//! - **A finished shard is never rerun**: a complete file is recognised (its end line) and
//!   skipped; the claim of a finished shard is removed.
//!
//! - **One split per directory.** The first worker writes `DIR/claims/pool.json` (the job id
//!   and the shard count K, created atomically by a hard link); a worker started with another
//!   `--shards` count is refused (usage, exit 2), one of another job as a file in the way
//!   (exit 5), before it claims anything. Without `pool.json`, shard files whose ranges are
//!   not of this split (left by `mc-shard run` with another K) refuse the worker the same way.
//! - **A damaged shard is set aside, not a stop.** A shard file that cannot be resumed or
//!   skipped (a line that breaks the format or its checkpoint, a changed header, another
//!   job's file, an old format, a file that is not a shard, a link or a non-file at its
//!   name) is quarantined: `DIR/quarantine/shard-i-of-K.json` records
//!   the reason, host, pid and time, the claim is released, the file is left untouched for
//!   inspection, and the worker goes on with the other shards. Later workers skip a
//!   quarantined shard. When no shard is left, a worker exits with the file-in-the-way code
//!   (5) if any shard is quarantined, naming them; `mc-shard status` lists them. To retry a
//!   shard: move its file away (or repair it), delete its marker, and run again.
//!
//! - **Nothing through a link.** `claims/` and `quarantine/` are refused (exit 5) when they
//!   are symbolic links, `pool.json` and the markers are written through temporary files
//!   with unpredictable names, and claims and markers are opened without following links
//!   (crate `run-dir`).
//!
//! Claims and locks need a shared filesystem with atomic `O_EXCL` create and working file
//! locks across machines (a local disk, NFSv4, CephFS, Lustre).
//!
//! Each action is printed as one JSON line on stdout (`{"shard": i, "action": "completed",
//! "computed": n, "kept": m, "host": …, "pid": …}`), for logs and tests.

use crate::errors::{RunError, ShardError};
use crate::job::Job;
use crate::runner::{RunOptions, run_shard};
use shard_record::ShardRange;
use std::fs::OpenOptions;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, SystemTime};

/// Options of a worker.
#[derive(Debug, Clone)]
pub struct WorkOptions {
    /// Number of shards the job is split into.
    pub shards: u64,
    /// Threads per shard.
    pub threads: usize,
    /// How often the claim is touched.
    pub heartbeat: Duration,
    /// A claim untouched this long is stale.
    pub stale_after: Duration,
    /// Show no progress.
    pub quiet: bool,
}

/// One thing a worker did.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Action {
    /// Shard index.
    pub shard: u64,
    /// `completed`, `already-complete`, `claimed-elsewhere`, `locked-elsewhere`, `took-over`,
    /// `interrupted` (SIGINT/SIGTERM: the claim is released, the shard left to resume),
    /// `quarantined` (set aside now, with `reason`), `skipped-quarantined` (set aside before).
    pub action: &'static str,
    /// Samples computed by this worker.
    pub computed: u64,
    /// Samples kept from an earlier, interrupted run.
    pub kept: u64,
    /// This worker's host.
    pub host: String,
    /// This worker's pid.
    pub pid: u32,
    /// Why the shard was quarantined.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The quarantine marker of shard `i` of `k` in `dir`.
pub fn quarantine_path(dir: &Path, i: u64, k: u64) -> PathBuf {
    dir.join("quarantine")
        .join(format!("shard-{i}-of-{k}.json"))
}

/// The longest quarantine marker read \[bytes\].
const MAX_MARKER_BYTES: u64 = 1 << 20;

/// The reason recorded in shard `i` of `k`'s quarantine marker, if it has one (a marker
/// that is a link or not a regular file is not read).
pub fn quarantined(dir: &Path, i: u64, k: u64) -> Option<String> {
    let file = run_dir::input::open_own(&quarantine_path(dir, i, k), OpenOptions::new().read(true))
        .ok()?;
    let mut text = String::new();
    file.take(MAX_MARKER_BYTES).read_to_string(&mut text).ok()?;
    Some(
        serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v["reason"].as_str().map(String::from))
            .unwrap_or_else(|| format!("(unreadable marker) {}", text.trim())),
    )
}

/// Writes shard `i` of `k`'s quarantine marker.
fn quarantine(
    dir: &Path,
    i: u64,
    k: u64,
    range: ShardRange,
    reason: &str,
    host: &str,
    pid: u32,
) -> Result<(), RunError> {
    let path = quarantine_path(dir, i, k);
    run_dir::create_dir(path.parent().expect("a marker has a directory"))
        .map_err(|e| RunError::Shard(e.into()))?;
    let since = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let marker = serde_json::json!({
        "shard": i, "shards": k, "range": range, "file": range.file_name(),
        "reason": reason, "host": host, "pid": pid, "quarantined_at_unix": since,
    });
    run_dir::write_file(&path, format!("{marker}\n").as_bytes())
        .map_err(|e| RunError::Shard(e.into()))
}

/// Checks that the directory's worker pool is of this job and split (see the module doc),
/// writing `DIR/claims/pool.json` if no worker has yet.
fn check_pool(job: &Job, dir: &Path, claims: &Path, ranges: &[ShardRange]) -> Result<(), RunError> {
    let shards = ranges.len() as u64;
    let pool = claims.join("pool.json");
    let io = |path: &Path, source| {
        RunError::Shard(ShardError::Io {
            path: path.to_path_buf(),
            source,
        })
    };
    if !pool.exists() {
        // Shard files of another split (from `mc-shard run --shard I/K'`).
        let ours: std::collections::BTreeSet<String> =
            ranges.iter().map(|r| r.file_name()).collect();
        let entries = std::fs::read_dir(dir).map_err(|e| io(dir, e))?;
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with("shard-") && name.ends_with(".jsonl") && !ours.contains(&name) {
                return Err(RunError::Usage(format!(
                    "{}: holds a shard that is not one of {shards} shards of this job; workers on one directory must all use the split its files were made with (check `mc-shard status`), or use another --out",
                    entry.path().display()
                )));
            }
        }
        let text = serde_json::json!({"job_id": job.id, "shards": shards});
        let files = |e: run_dir::RunDirError| RunError::Shard(e.into());
        let mut out = run_dir::OutputFile::create(&pool).map_err(files)?;
        writeln!(out, "{text}").map_err(|e| io(&pool, e))?;
        if out.commit_new().map_err(files)? {
            return Ok(());
        }
    }
    let mut text = String::new();
    run_dir::input::open_own(&pool, OpenOptions::new().read(true))
        .map_err(|e| RunError::Shard(e.into()))?
        .take(MAX_MARKER_BYTES)
        .read_to_string(&mut text)
        .map_err(|e| io(&pool, e))?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        RunError::Shard(ShardError::Pool {
            path: pool.clone(),
            message: format!("not valid JSON ({e})"),
        })
    })?;
    if value["job_id"].as_str() != Some(job.id.as_str()) {
        return Err(RunError::Shard(ShardError::Pool {
            path: pool.clone(),
            message: format!(
                "the directory's workers run job {}, not this job {}; use another --out",
                value["job_id"], job.id
            ),
        }));
    }
    match value["shards"].as_u64() {
        Some(k) if k == shards => Ok(()),
        Some(k) => Err(RunError::Usage(format!(
            "{}: the directory's workers split the job into {k} shards; this worker was started with --shards {shards} (every worker on a directory must use the same --shards)",
            pool.display()
        ))),
        None => Err(RunError::Shard(ShardError::Pool {
            path: pool.clone(),
            message: "no shard count".into(),
        })),
    }
}

/// This machine's host name.
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .ok()
        .filter(|s| !s.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".into())
}

/// Works until every shard of `job` in `dir` is complete (or claimed by a live worker),
/// calling `report` with each action. Returns the actions.
pub fn work(
    job: &Job,
    dir: &Path,
    options: &WorkOptions,
    mut report: impl FnMut(&Action),
) -> Result<Vec<Action>, RunError> {
    let ranges = ShardRange::partition(options.shards, job.samples())
        .map_err(|e| RunError::Usage(e.to_string()))?;
    std::fs::create_dir_all(dir).map_err(|source| ShardError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let claims = dir.join("claims");
    run_dir::create_dir(&claims).map_err(ShardError::from)?;
    check_pool(job, dir, &claims, &ranges)?;
    let host = host_name();
    let pid = std::process::id();
    let mut actions = Vec::new();
    let mut act = |shard: u64, action: &'static str, computed: u64, kept: u64, reason| {
        let a = Action {
            shard,
            action,
            computed,
            kept,
            host: host.clone(),
            pid,
            reason,
        };
        report(&a);
        actions.push(a);
    };
    let expected = |range: ShardRange| crate::shard::begin(job, range);
    for (i, range) in ranges.iter().enumerate() {
        let i = i as u64;
        if crate::interrupt::requested().is_some() {
            break;
        }
        if quarantined(dir, i, options.shards).is_some() {
            act(i, "skipped-quarantined", 0, 0, None);
            continue;
        }
        if looks_complete(&dir.join(range.file_name()), &expected(*range)) {
            continue;
        }
        let claim = claims.join(format!("shard-{i}-of-{}.claim", options.shards));
        let took_over = match try_claim(&claim, &host, pid, options.stale_after)? {
            Claim::Ours { took_over } => took_over,
            Claim::Live => {
                act(i, "claimed-elsewhere", 0, 0, None);
                continue;
            }
        };
        if took_over {
            act(i, "took-over", 0, 0, None);
        }
        let result = with_heartbeat(&claim, options.heartbeat, || {
            run_shard(
                job,
                dir,
                *range,
                &RunOptions {
                    threads: options.threads,
                    quiet: options.quiet,
                },
            )
        });
        match result {
            Ok(summary) => {
                let _ = std::fs::remove_file(&claim);
                if summary.interrupted.is_some() {
                    // Released at once for another worker (or a rerun) to resume.
                    act(i, "interrupted", summary.computed, summary.resumed, None);
                    break;
                }
                if summary.already_complete {
                    act(i, "already-complete", 0, summary.resumed, None);
                } else {
                    act(i, "completed", summary.computed, summary.resumed, None);
                }
            }
            Err(RunError::Shard(ShardError::Locked { .. })) => {
                // Another worker writes it: its claim will show it; leave ours to go stale.
                let _ = std::fs::remove_file(&claim);
                act(i, "locked-elsewhere", 0, 0, None);
            }
            Err(RunError::Shard(e)) if e.is_damage() => {
                let reason = e.to_string();
                let marked = quarantine(dir, i, options.shards, *range, &reason, &host, pid);
                let _ = std::fs::remove_file(&claim);
                marked?;
                act(i, "quarantined", 0, 0, Some(reason));
            }
            Err(e) => {
                let _ = std::fs::remove_file(&claim);
                return Err(e);
            }
        }
    }
    Ok(actions)
}

/// Whether a shard file's header is `begin`'s and it ends with an end line (a cheap look;
/// running it verifies every line).
fn looks_complete(path: &Path, begin: &shard_record::Begin) -> bool {
    let Ok(mut f) = run_dir::input::open_own(path, OpenOptions::new().read(true)) else {
        return false;
    };
    let mut header = Vec::new();
    let max = shard_record::MAX_BEGIN_LINE_BYTES;
    let same = shard_record::read_line(&mut std::io::BufReader::new(&f), &mut header, max)
        .is_ok_and(|n| n.is_some())
        && matches!(shard_record::parse_record(&header),
                    Ok(shard_record::Record::Begin(b)) if b.same_shard(begin));
    if !same {
        return false;
    }
    let len = f.metadata().map_or(0, |m| m.len());
    let tail = len.min(512);
    let mut buf = vec![0; tail as usize];
    if f.seek(SeekFrom::End(-(tail as i64))).is_err() || f.read_exact(&mut buf).is_err() {
        return false;
    }
    let text = String::from_utf8_lossy(&buf);
    let last = text
        .trim_end_matches('\n')
        .rsplit('\n')
        .next()
        .unwrap_or("");
    text.ends_with('\n') && last.starts_with(r#"{"record":"end""#)
}

enum Claim {
    Ours { took_over: bool },
    Live,
}

/// Claims `path` (see the module doc).
fn try_claim(path: &Path, host: &str, pid: u32, stale_after: Duration) -> Result<Claim, RunError> {
    let io = |source| {
        RunError::Shard(ShardError::Io {
            path: path.to_path_buf(),
            source,
        })
    };
    match create_claim(path, host, pid) {
        Ok(()) => return Ok(Claim::Ours { took_over: false }),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io(e)),
    }
    if !is_stale(path, stale_after) {
        return Ok(Claim::Live);
    }
    let lock = path.with_extension("claim.takeover");
    if is_stale(&lock, stale_after) {
        let _ = std::fs::remove_file(&lock);
    }
    match OpenOptions::new().write(true).create_new(true).open(&lock) {
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Ok(Claim::Live),
        Err(e) => return Err(io(e)),
    }
    // Holding the takeover lock: re-check, then replace the stale claim.
    let result = if is_stale(path, stale_after) || !path.exists() {
        let _ = std::fs::remove_file(path);
        match create_claim(path, host, pid) {
            Ok(()) => Ok(Claim::Ours { took_over: true }),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(Claim::Live),
            Err(e) => Err(io(e)),
        }
    } else {
        Ok(Claim::Live)
    };
    let _ = std::fs::remove_file(&lock);
    result
}

fn create_claim(path: &Path, host: &str, pid: u32) -> std::io::Result<()> {
    let mut f = OpenOptions::new().write(true).create_new(true).open(path)?;
    let since = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    writeln!(
        f,
        "{}",
        serde_json::json!({"host": host, "pid": pid, "claimed_at_unix": since})
    )?;
    f.sync_all()
}

/// Whether `path` exists and was last modified more than `stale_after` ago.
fn is_stale(path: &Path, stale_after: Duration) -> bool {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.elapsed().ok())
        .is_some_and(|age| age > stale_after)
}

/// Runs `f` while a thread touches `claim` every `every`.
fn with_heartbeat<T>(claim: &Path, every: Duration, f: impl FnOnce() -> T) -> T {
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| {
            let step = Duration::from_millis(50).min(every);
            let mut since = Duration::ZERO;
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(step);
                since += step;
                if since >= every {
                    since = Duration::ZERO;
                    if let Ok(f) = run_dir::input::open_own(claim, OpenOptions::new().append(true))
                    {
                        let _ = f.set_modified(SystemTime::now());
                    }
                }
            }
        });
        let out = f();
        done.store(true, Ordering::Relaxed);
        out
    })
}
