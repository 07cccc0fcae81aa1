//! Running a shard: samples computed on T threads, written in index order to the shard file.
//!
//! Workers take chunks of consecutive indices from a shared counter, write the chunk's lines
//! into one buffer and send it to the writer (this thread), which keeps a small reordering
//! buffer and appends every chunk that is next in order, in one write. Memory stays flat in the sample count:
//! the buffer holds at most the lines in flight. Each sample's line depends only on the job
//! and its index, so the file is the same bytes for any thread count.
//!
//! After SIGINT or SIGTERM (once [`crate::interrupt::install`]ed) workers stop before their
//! next sample and send what they finished; the writer appends every line that is next in
//! order, syncs the file and returns with [`RunSummary::interrupted`] set, leaving the shard
//! without its end line for a rerun to resume.

use crate::errors::RunError;
use crate::interrupt::{self, Signal};
use crate::job::Job;
use crate::progress::Progress;
use crate::shard::{Opened, ShardWriter, begin};
use crate::worker::Worker;
use shard_record::{ShardRange, Status};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::sync_channel;
use std::time::Instant;

/// Indices a worker takes at a time. Each chunk wakes the writer and costs one write: at 16
/// (about 0.2 ms of 5-stage samples) those wakeups, on a machine with as many cores as
/// workers, held two threads to 1.73 times one on `scripts/bench-shard.sh`'s job; at 64,
/// 1.84 times. A crash loses at most the chunks being computed, which are re-solved on resume.
const CHUNK: u64 = 64;

/// How a shard run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// The shard file.
    pub path: PathBuf,
    /// Its range.
    pub range: ShardRange,
    /// Whether it was already complete (nothing computed).
    pub already_complete: bool,
    /// Samples kept from an interrupted run.
    pub resumed: u64,
    /// Samples computed now.
    pub computed: u64,
    /// Failed samples in the whole shard.
    pub failed: u64,
    /// Wall time of this run \[s\].
    pub seconds: f64,
    /// The signal that stopped the run before the shard was complete, if one did.
    pub interrupted: Option<Signal>,
}

/// Options of a shard run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads (at least 1).
    pub threads: usize,
    /// Show no progress.
    pub quiet: bool,
}

/// A finished chunk: its record lines back to back, and per line its length
/// in bytes and whether the sample failed.
type ChunkLines = (Vec<u8>, Vec<(usize, bool)>);

/// Runs (or resumes, or verifies as complete) the shard `range` of `job` in `dir`.
pub fn run_shard(
    job: &Job,
    dir: &Path,
    range: ShardRange,
    options: &RunOptions,
) -> Result<RunSummary, RunError> {
    let range = range
        .within(job.samples())
        .map_err(|e| RunError::Usage(e.to_string()))?;
    let started = Instant::now();
    let mut writer = match ShardWriter::open(dir, &begin(job, range))? {
        Opened::Complete { path, scan } => {
            return Ok(RunSummary {
                path,
                range,
                already_complete: true,
                resumed: scan.digest.samples(),
                computed: 0,
                failed: scan.digest.end().failed,
                seconds: started.elapsed().as_secs_f64(),
                interrupted: None,
            });
        }
        Opened::Writer(w) => w,
    };
    let resumed = writer.resumed();
    let first = writer.next_index();
    let mut progress = Progress::new(
        &format!("shard {range}"),
        range.len(),
        first - range.start,
        options.quiet,
    );
    let threads = options.threads.max(1);
    let next = AtomicU64::new(first);
    let stop = AtomicBool::new(false);
    // One message per chunk: its first index, its lines' bytes, and each line's length and
    // whether it failed.
    let (tx, rx) = sync_channel::<(u64, ChunkLines)>(64 * threads);
    let result = std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, stop) = (&next, &stop);
            scope.spawn(move || {
                let mut worker = Worker::new(job);
                loop {
                    let start = next.fetch_add(CHUNK, Ordering::Relaxed);
                    let halt = || stop.load(Ordering::Relaxed) || interrupt::requested().is_some();
                    if start >= range.end || halt() {
                        break;
                    }
                    let end = (start + CHUNK).min(range.end);
                    let mut bytes = Vec::with_capacity(300 * (end - start) as usize);
                    let mut lines = Vec::with_capacity((end - start) as usize);
                    for index in start..end {
                        if halt() {
                            // Interrupted: send the samples finished so far.
                            break;
                        }
                        let sample = worker.sample(index);
                        let before = bytes.len();
                        sample.write_line(&mut bytes);
                        lines.push((bytes.len() - before, sample.status == Status::Failed));
                    }
                    let partial = lines.len() as u64 != end - start;
                    if !lines.is_empty() && tx.send((start, (bytes, lines))).is_err() {
                        return;
                    }
                    if partial {
                        return;
                    }
                }
            });
        }
        drop(tx);
        // The writer: append runs of chunks in index order as they complete.
        let mut pending: BTreeMap<u64, ChunkLines> = BTreeMap::new();
        let mut expect = first;
        for (start, chunk) in rx {
            pending.insert(start, chunk);
            while let Some((bytes, lines)) = pending.remove(&expect) {
                expect += lines.len() as u64;
                if let Err(e) = writer.append(&bytes, &lines) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
                progress.advance(lines.len() as u64);
            }
        }
        Ok(expect)
    });
    progress.finish();
    let written = result?;
    let path = writer.path().to_path_buf();
    if written < range.end {
        // Interrupted (the only way the workers stop early without an error).
        writer.stop()?;
        return Ok(RunSummary {
            path,
            range,
            already_complete: false,
            resumed,
            computed: written - first,
            failed: writer.failed(),
            seconds: started.elapsed().as_secs_f64(),
            interrupted: Some(interrupt::requested().unwrap_or(Signal::Terminate)),
        });
    }
    let end = writer.finish()?;
    Ok(RunSummary {
        path,
        range,
        already_complete: false,
        resumed,
        computed: range.end - first,
        failed: end.failed,
        seconds: started.elapsed().as_secs_f64(),
        interrupted: None,
    })
}
