//! The state of a job's shards in a directory: which of K shards are complete, partial,
//! missing or in the way (another job's file), for resubmitting what is missing.

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
        .map(|r| {
            let path = dir.join(r.file_name());
            let state = if !path.exists() {
                ShardState::Missing
            } else {
                match scan_shard(&path, |_, _, _| Ok(())) {
                    Err(e) => ShardState::Bad(e.to_string()),
                    Ok(scan) if scan.begin.job_id != job.id => {
                        ShardState::Bad(format!("holds job {}", scan.begin.job_id))
                    }
                    Ok(scan) => match scan.tail {
                        Tail::Complete(_) => ShardState::Complete,
                        _ => ShardState::Partial(scan.digest.samples()),
                    },
                }
            };
            (r, state)
        })
        .collect())
}
