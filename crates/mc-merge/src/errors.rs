//! Everything that stops a merge, and the process exit code each maps to.
//!
//! Every variant carries what an engineer needs to find the problem: the file, the line, the
//! global sample indices and the case they belong to. A merge either verifies all of its input
//! and computes, or fails with one of these and computes nothing.

use shard_record::ScanError;
use std::fmt;
use std::path::PathBuf;

/// A run of global sample indices `start..end` that no shard holds, inside one case.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct MissingRange {
    /// First missing global index.
    pub start: u64,
    /// One past the last missing global index.
    pub end: u64,
    /// The case these indices belong to.
    pub case: String,
}

impl fmt::Display for MissingRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}..{} (case {:?}, {} samples)",
            self.start,
            self.end,
            self.case,
            self.end - self.start
        )
    }
}

/// The failed samples of one case, as far as an error message needs them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FailedCase {
    /// Case name.
    pub case: String,
    /// How many of its samples failed.
    pub count: u64,
    /// The first failed global indices (at most a few).
    pub first_indices: Vec<u64>,
    /// The reasons of the first few failures, with their global index.
    pub first_reasons: Vec<(u64, String)>,
}

/// Why a merge stopped.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// The command line is wrong.
    #[error("usage: {message}")]
    Usage {
        /// What is wrong and how to fix it.
        message: String,
    },
    /// No shard file was found among the paths given.
    #[error("no shard files (*.jsonl) found in {}", paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    NoShards {
        /// The paths given.
        paths: Vec<PathBuf>,
    },
    /// A shard file is torn, incomplete, corrupt or has a wrong digest (see [`ScanError`]).
    #[error("{0}")]
    Shard(#[from] ScanError),
    /// A shard belongs to another job than the first file read.
    #[error(
        "{}:1: job id {found} differs from {expected} of {}: the shards belong to different jobs",
        path.display(),
        reference.display()
    )]
    OtherJob {
        /// The file with the other job id.
        path: PathBuf,
        /// Its job id.
        found: String,
        /// The job id of the reference file.
        expected: String,
        /// The first file read, which set the job id.
        reference: PathBuf,
    },
    /// Two shards of one job id disagree about the job's cases or size.
    #[error("{}:1: header disagrees with {} about {what}", path.display(), reference.display())]
    HeaderMismatch {
        /// The file whose header differs.
        path: PathBuf,
        /// The first file read.
        reference: PathBuf,
        /// What differs.
        what: String,
    },
    /// Two shards hold the same global index with different contents.
    #[error(
        "{}:{line}: sample {index} (case {case:?}) differs from the copy in {}: overlapping shards disagree from index {index} on",
        second.display(),
        first.display()
    )]
    OverlapDisagrees {
        /// The file read first that holds the index.
        first: PathBuf,
        /// The file whose copy disagrees.
        second: PathBuf,
        /// Line of the disagreeing sample in `second`.
        line: u64,
        /// The first disagreeing global index.
        index: u64,
        /// The case of that index.
        case: String,
    },
    /// Two shards of the same range are not byte-identical.
    #[error(
        "{} and {} both hold range {range} but their sample lines are not byte-identical (sha256 {first_sha256} vs {second_sha256})",
        first.display(),
        second.display()
    )]
    DuplicateDiffers {
        /// The file read first.
        first: PathBuf,
        /// The other copy.
        second: PathBuf,
        /// The range both hold.
        range: shard_record::ShardRange,
        /// Digest of the first file's sample lines.
        first_sha256: String,
        /// Digest of the second's.
        second_sha256: String,
    },
    /// A sample given from memory ([`crate::load::Collector`]) does not belong: its index is
    /// outside the job, it was given twice with different lines, or its converged θ_P is no
    /// angle between the surfaces.
    #[error("sample {index}: {message}")]
    Sample {
        /// Its global index.
        index: u64,
        /// What is wrong.
        message: String,
    },
    /// Some global indices are in no shard.
    #[error(
        "{present} of {expected} samples present; missing {}{}: give the missing shards, or --allow-partial to compute on what is there",
        ranges.iter().take(10).map(|r| r.to_string()).collect::<Vec<_>>().join(", "),
        if ranges.len() > 10 { format!(" and {} more ranges", ranges.len() - 10) } else { String::new() }
    )]
    Missing {
        /// The missing index ranges, split at case boundaries, in index order.
        ranges: Vec<MissingRange>,
        /// Samples present.
        present: u64,
        /// Samples the job has.
        expected: u64,
    },
    /// Failed samples are present; dropping them silently would bias the upper tail.
    #[error("{}", failed_message(*total, cases))]
    FailedSamples {
        /// Failed samples over all cases.
        total: u64,
        /// The cases with failures.
        cases: Vec<FailedCase>,
    },
    /// A file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The report directory holds another job's report, or a `report.json` that mc-merge did
    /// not write; nothing was changed in it.
    #[error("{}: {message}", path.display())]
    InTheWay {
        /// The file in the way.
        path: PathBuf,
        /// What it is and what to do.
        message: String,
    },
    /// A file of the report directory or the export is in the way (a planted link, something
    /// that is not a file, another process writing the directory), or could not be written;
    /// or a file named on the command line is not a regular file.
    #[error(transparent)]
    Files(#[from] run_dir::RunDirError),
    /// A plot could not be drawn.
    #[error("{}: cannot draw the plot: {message}", path.display())]
    Plot {
        /// The plot file (or the report directory, when no font is found for the PNGs).
        path: PathBuf,
        /// The plotting library's message.
        message: String,
    },
    /// A bug: the report could not be serialised (for example a non-finite number slipped in).
    #[error("internal error: {message}")]
    Internal {
        /// What went wrong.
        message: String,
    },
}

fn failed_message(total: u64, cases: &[FailedCase]) -> String {
    let mut s = format!(
        "{total} failed samples (Newton did not converge); they are not dropped silently because that would bias the upper tail. Fix the model or give --allow-failed to compute on the converged samples:"
    );
    for c in cases {
        let idx: Vec<String> = c.first_indices.iter().map(u64::to_string).collect();
        s.push_str(&format!(
            "\n  case {:?}: {} failed, indices {}{}",
            c.case,
            c.count,
            idx.join(", "),
            if c.count > idx.len() as u64 {
                ", …"
            } else {
                ""
            }
        ));
        for (i, r) in &c.first_reasons {
            s.push_str(&format!("\n    {i}: {r}"));
        }
    }
    s
}

impl MergeError {
    /// The exit code of `mc-merge` for this error, in the scheme every truss-mc binary shares
    /// (`truss-exit`; the crate doc and `--help` list what each code means here): the one
    /// place a failure of a merge becomes a code.
    pub fn exit_code(&self) -> u8 {
        use run_dir::RunDirError;
        use truss_exit::{
            FAILED_SAMPLES, IN_THE_WAY, INTERNAL, INVALID_INPUT, IO, USAGE, VERIFICATION,
        };
        match self {
            MergeError::Usage { .. } => USAGE,
            MergeError::Shard(ScanError::Io { .. })
            | MergeError::Io { .. }
            | MergeError::Plot { .. } => IO,
            MergeError::NoShards { .. }
            | MergeError::Shard(_)
            | MergeError::OtherJob { .. }
            | MergeError::HeaderMismatch { .. }
            | MergeError::OverlapDisagrees { .. }
            | MergeError::DuplicateDiffers { .. }
            | MergeError::Sample { .. }
            | MergeError::Missing { .. } => VERIFICATION,
            MergeError::FailedSamples { .. } => FAILED_SAMPLES,
            MergeError::InTheWay { .. } => IN_THE_WAY,
            MergeError::Files(files) => match files {
                RunDirError::Io { .. } => IO,
                RunDirError::Link { .. }
                | RunDirError::NotAFile { .. }
                | RunDirError::Locked { .. }
                | RunDirError::NotOurs { .. }
                | RunDirError::HardLinked { .. } => IN_THE_WAY,
                RunDirError::NotRegular { .. } => INVALID_INPUT,
            },
            MergeError::Internal { .. } => INTERNAL,
        }
    }
}
