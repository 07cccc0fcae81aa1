//! Running a shard: samples computed on T threads by the job crate's sample engine
//! ([`truss_job::engine`]), written in index order to the shard file.
//!
//! The engine's workers take chunks of consecutive indices and format each chunk's lines into
//! one buffer; the writer (this thread) receives the chunks in index order and appends each
//! in one write. Memory stays flat in the sample count: the engine holds at most the chunks
//! in flight. Each sample's line depends only on the job and its index, so the file is the
//! same bytes for any thread count. A crash loses at most the chunks being computed, which
//! are re-solved on resume.
//!
//! After SIGINT or SIGTERM (once [`crate::interrupt::install`]ed) workers stop before their
//! next sample and send what they finished; the writer appends every line that is next in
//! order, syncs the file and returns with [`RunSummary::interrupted`] set, leaving the shard
//! without its end line for a rerun to resume.

use crate::errors::{RunError, ShardError};
use crate::interrupt::{self, Signal};
use crate::job::Job;
use crate::progress::Progress;
use crate::shard::{Opened, ShardWriter, begin};
use crate::worker::record;
use shard_record::{ShardRange, Status};
use std::path::{Path, PathBuf};
use std::time::Instant;
use truss_job::Engine;
use truss_job::solve::{SampleResult, SampleSolver};

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
    let halt = || interrupt::requested().is_some();
    let engine = Engine::new(job, options.threads).halting_when(&halt);
    // Each chunk's lines back to back, and per line its length and whether it failed:
    // formatted on the workers, appended by this thread in index order, in one write.
    let each = |(bytes, lines): &mut ChunkLines, _: &SampleSolver<'_>, result: SampleResult| {
        let sample = record(job, &result);
        let before = bytes.len();
        sample.write_line(bytes);
        lines.push((bytes.len() - before, sample.status == Status::Failed));
    };
    let result: Result<u64, ShardError> = engine
        .run(first..range.end, each, |chunk| match chunk {
            Some((bytes, lines)) => {
                writer.append(&bytes, &lines)?;
                progress.advance(lines.len() as u64);
                Ok(())
            }
            None => Ok(()),
        })
        .map(|handed| first + handed);
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
