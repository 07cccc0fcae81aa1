//! Which range a process runs: from `--range A..B`, `--shard I/K`, or the environment of a
//! batch system, in that order of precedence.
//!
//! | source | shard |
//! |---|---|
//! | `--range A..B` | exactly `A..B` |
//! | `--shard I/K` | shard I of K (0-based; see [`shard_record::ShardRange`] for the partition) |
//! | `SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT` | shard `ID` of `COUNT` (a full array `--array=0-(K-1)`) |
//! | `JOB_COMPLETION_INDEX` (Kubernetes Indexed Job) with `MC_SHARD_COUNT` or `--shards K` | shard `INDEX` of `K` |
//! | none of these | the whole job, one shard |

use crate::errors::RunError;
use shard_record::ShardRange;

/// Where a range came from, for messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// `--range`.
    Range,
    /// `--shard`.
    Shard,
    /// Slurm's array variables.
    Slurm,
    /// Kubernetes' completion index.
    Kubernetes,
    /// No selection: the whole job.
    Whole,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Source::Range => "--range",
            Source::Shard => "--shard",
            Source::Slurm => "SLURM_ARRAY_TASK_ID",
            Source::Kubernetes => "JOB_COMPLETION_INDEX",
            Source::Whole => "the whole job",
        })
    }
}

/// Chooses the range (see the module doc); `env` looks up environment variables.
pub fn select(
    range: Option<&str>,
    shard: Option<&str>,
    shards: Option<u64>,
    samples: u64,
    env: impl Fn(&str) -> Option<String>,
) -> Result<(ShardRange, Source), RunError> {
    let usage = |e: shard_record::ShardRangeError| RunError::Usage(e.to_string());
    if let Some(text) = range {
        let r: ShardRange = text.parse().map_err(usage)?;
        return Ok((r.within(samples).map_err(usage)?, Source::Range));
    }
    if let Some(text) = shard {
        let (i, k) = ShardRange::parse_shard_spec(text).map_err(usage)?;
        return Ok((
            ShardRange::for_shard(i, k, samples).map_err(usage)?,
            Source::Shard,
        ));
    }
    let number = |name: &str| -> Result<Option<u64>, RunError> {
        match env(name) {
            None => Ok(None),
            Some(v) => v.trim().parse().map(Some).map_err(|_| {
                RunError::Usage(format!(
                    "environment variable {name}={v:?} is not a whole number"
                ))
            }),
        }
    };
    if let Some(i) = number("SLURM_ARRAY_TASK_ID")? {
        let k = number("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
            RunError::Usage("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not".into())
        })?;
        let r = ShardRange::for_shard(i, k, samples).map_err(usage)?;
        return Ok((r, Source::Slurm));
    }
    if let Some(i) = number("JOB_COMPLETION_INDEX")? {
        let k = match shards {
            Some(k) => k,
            None => number("MC_SHARD_COUNT")?.ok_or_else(|| {
                RunError::Usage(
                    "JOB_COMPLETION_INDEX is set: give the shard count with --shards K or MC_SHARD_COUNT".into(),
                )
            })?,
        };
        let r = ShardRange::for_shard(i, k, samples).map_err(usage)?;
        return Ok((r, Source::Kubernetes));
    }
    Ok((ShardRange::new(0, samples), Source::Whole))
}
