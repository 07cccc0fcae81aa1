//! The state of a job's shards in a directory: which of K shards are complete, partial,
//! missing, in the way (another job's file, a changed header) or quarantined by a worker, for
//! resubmitting what is missing. A partial shard counts its lines verified by a checkpoint.

use crate::job::Job;
use shard_record::{ShardRange, Tail, scan_shard};
use std::path::Path;

/// The state of one shard file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShardState {
    /// Complete and verified.
    Complete,
    /// Started: this many sample lines so far.
    Partial(u64),
    /// No file.
    Missing,
    /// The file is damaged or belongs to another job; the reason.
    Bad(String),
    /// A worker set the shard aside (`DIR/quarantine/`); the reason it recorded.
    Quarantined(String),
}

/// The state of each of the `count` shards of `job` in `dir`.
pub fn shard_states(
    job: &Job,
    dir: &Path,
    count: u64,
) -> Result<Vec<(ShardRange, ShardState)>, String> {
    let ranges = ShardRange::partition(count, job.samples()).map_err(|e| e.to_string())?;
    Ok(ranges
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let path = dir.join(r.file_name());
            let expected = crate::shard::begin(job, r);
            let state = if let Some(why) = crate::work::quarantined(dir, i as u64, count) {
                ShardState::Quarantined(why)
            } else if !path.exists() {
                ShardState::Missing
            } else {
                match scan_shard(&path, |_, _, _| Ok(())) {
                    Err(e) => ShardState::Bad(e.to_string()),
                    Ok(scan) if scan.begin.job_id != job.id => {
                        ShardState::Bad(format!("holds job {}", scan.begin.job_id))
                    }
                    Ok(scan) if !scan.begin.same_shard(&expected) => ShardState::Bad(
                        "its header differs from the job's cases or parameters".into(),
                    ),
                    Ok(scan) => match scan.tail {
                        Tail::Complete(_) => ShardState::Complete,
                        _ if scan.begin.checkpoint_every.is_none() => ShardState::Bad(format!(
                            "an incomplete shard of format version {} (no checkpoints): it is not resumed",
                            scan.begin.format_version
                        )),
                        _ => ShardState::Partial(scan.digest.samples()),
                    },
                }
            };
            (r, state)
        })
        .collect())
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
