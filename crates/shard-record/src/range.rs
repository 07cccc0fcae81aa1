//! Shard ranges: contiguous runs of the global sample index, and how a job is split into them.
//!
//! ## Partition contract
//!
//! Shard `i` of `k` (0-based, `0 <= i < k`, as Slurm's `SLURM_ARRAY_TASK_ID` and Kubernetes'
//! `JOB_COMPLETION_INDEX` count) of a job with `n` samples is `⌊i·n/k⌋..⌊(i+1)·n/k⌋`.
//! So the `k` shards are contiguous, disjoint, cover `0..n` exactly, and their sizes differ by
//! at most one. The split never changes which sample has which index, so results never depend
//! on it.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A half-open range `start..end` of global sample indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct ShardRange {
    /// First global index in the range.
    pub start: u64,
    /// One past the last global index.
    pub end: u64,
}

/// A shard range or shard number that does not make sense.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardRangeError {
    /// The text is not `A..B` with whole numbers.
    #[error("{text:?} is not a range of the form A..B (whole numbers, A <= B)")]
    Syntax {
        /// What was given.
        text: String,
    },
    /// The text is not `I/K` with whole numbers.
    #[error("{text:?} is not a shard of the form I/K (0 <= I < K)")]
    ShardSyntax {
        /// What was given.
        text: String,
    },
    /// Shard index out of range.
    #[error("shard {index} of {count} does not exist: {}", if *count == 0 { "the shard count must be at least 1".to_string() } else { format!("shards are numbered 0 to {}", count - 1) })]
    NoSuchShard {
        /// The index given.
        index: u64,
        /// The number of shards.
        count: u64,
    },
    /// Range beyond the job.
    #[error("range {range} is outside the job's samples 0..{samples}")]
    OutsideJob {
        /// The range given.
        range: ShardRange,
        /// The job's sample count.
        samples: u64,
    },
}

impl ShardRange {
    /// The range `start..end`.
    pub fn new(start: u64, end: u64) -> Self {
        Self { start, end }
    }

    /// Shard `index` of `count` of a job with `samples` samples (see the module's contract).
    pub fn for_shard(index: u64, count: u64, samples: u64) -> Result<Self, ShardRangeError> {
        if count == 0 || index >= count {
            return Err(ShardRangeError::NoSuchShard { index, count });
        }
        let bound = |i: u64| (u128::from(i) * u128::from(samples) / u128::from(count)) as u64;
        Ok(Self {
            start: bound(index),
            end: bound(index + 1),
        })
    }

    /// All `count` shards of a job with `samples` samples, in order.
    pub fn partition(count: u64, samples: u64) -> Result<Vec<Self>, ShardRangeError> {
        (0..count)
            .map(|i| Self::for_shard(i, count, samples))
            .collect()
    }

    /// Checks the range lies within a job of `samples` samples.
    pub fn within(self, samples: u64) -> Result<Self, ShardRangeError> {
        if self.start <= self.end && self.end <= samples {
            Ok(self)
        } else {
            Err(ShardRangeError::OutsideJob {
                range: self,
                samples,
            })
        }
    }

    /// Number of indices in the range.
    pub fn len(self) -> u64 {
        self.end.saturating_sub(self.start)
    }

    /// Whether the range is empty.
    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// Whether `index` is in the range.
    pub fn contains(self, index: u64) -> bool {
        self.start <= index && index < self.end
    }

    /// The shard file name for this range: `shard-{start:010}-{end:010}.jsonl`, so that file
    /// names sort in index order.
    pub fn file_name(self) -> String {
        format!("shard-{:010}-{:010}.jsonl", self.start, self.end)
    }

    /// Parses `I/K` into (I, K), checking `I < K`.
    pub fn parse_shard_spec(text: &str) -> Result<(u64, u64), ShardRangeError> {
        let syntax = || ShardRangeError::ShardSyntax {
            text: text.to_string(),
        };
        let (i, k) = text.split_once('/').ok_or_else(syntax)?;
        let i: u64 = i.trim().parse().map_err(|_| syntax())?;
        let k: u64 = k.trim().parse().map_err(|_| syntax())?;
        if k == 0 || i >= k {
            return Err(ShardRangeError::NoSuchShard { index: i, count: k });
        }
        Ok((i, k))
    }
}

impl fmt::Display for ShardRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

impl FromStr for ShardRange {
    type Err = ShardRangeError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let syntax = || ShardRangeError::Syntax {
            text: text.to_string(),
        };
        let (a, b) = text.split_once("..").ok_or_else(syntax)?;
        let start: u64 = a.trim().parse().map_err(|_| syntax())?;
        let end: u64 = b.trim().parse().map_err(|_| syntax())?;
        if start > end {
            return Err(syntax());
        }
        Ok(Self { start, end })
    }
}
