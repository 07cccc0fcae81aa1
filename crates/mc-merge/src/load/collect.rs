//! Samples already in memory as a [`Dataset`], for a merge's statistics without shard files:
//! a job run in-process, or shards the Python package has read back. Each sample goes into the
//! same per-case columns as a shard file's (by global index, in any order), under the same
//! checks a shard's line meets at the merge (a converged θ_P in [0, π/2], one copy per index
//! unless the lines are identical), and [`Collector::finish`] applies the same coverage rule,
//! so [`crate::build_report`] of the result is the report `mc-merge` writes for shards of the
//! same lines, to the byte.

use super::store::{Conflict, Dataset, LoadOptions, Rec, ShardWriter, Store, check_coverage};
use crate::errors::MergeError;
use shard_record::{Budget, CaseInfo, Sample};

/// Collects the samples of one job from memory.
pub struct Collector {
    job_id: String,
    job_samples: u64,
    store: Store,
    writer: ShardWriter,
    added: u64,
    budget: Option<Budget>,
}

impl Collector {
    /// An empty collection for the job `job_id` of `job_samples` samples in `cases` (as a
    /// shard's begin line lists them), whose samples `writer` computed.
    pub fn new(
        job_id: impl Into<String>,
        job_samples: u64,
        cases: &[CaseInfo],
        writer: ShardWriter,
    ) -> Self {
        Self {
            job_id: job_id.into(),
            job_samples,
            store: Store::new(cases),
            writer,
            added: 0,
            budget: None,
        }
    }

    /// The job's alignment budget (as a shard's begin line carries it), for the report's
    /// budget section.
    pub fn with_budget(mut self, budget: Option<Budget>) -> Self {
        self.budget = budget;
        self
    }

    /// Adds a sample and its shard line's bytes (`sample.to_line()`; the copy of an index
    /// given twice is compared by them). Refused: an index outside the job's cases, a second
    /// copy with another line, a converged θ_P outside [0, π/2] rad.
    pub fn add(&mut self, sample: &Sample, line: &[u8]) -> Result<(), MergeError> {
        let refuse = |message: String| MergeError::Sample {
            index: sample.index,
            message,
        };
        if self.store.case_of(sample.index).is_none() {
            return Err(refuse(format!(
                "outside the job's {} samples",
                self.job_samples
            )));
        }
        sample.check_angles().map_err(refuse)?;
        self.added += 1;
        self.store
            .put(0, Rec::new(self.added, sample, line))
            .map_err(|c| match c {
                Conflict::Disagree { .. } => refuse("given twice with different lines".to_string()),
                Conflict::Memory(message) => MergeError::Internal { message },
            })
    }

    /// The dataset. Missing samples and failed ones are refused as the merge refuses them
    /// ([`crate::errors::MergeError::Missing`], [`crate::errors::MergeError::FailedSamples`])
    /// unless `options` tolerate them.
    pub fn finish(self, options: LoadOptions) -> Result<Dataset, MergeError> {
        let data = Dataset {
            budget: self.budget,
            job_id: self.job_id,
            job_samples: self.job_samples,
            cases: self.store.into_cases(),
            files: vec![],
            writers: vec![ShardWriter {
                files: 0,
                ..self.writer
            }],
        };
        check_coverage(&data, options)?;
        Ok(data)
    }
}
