//! Errors of mc-shard, each carrying what is needed to find the fault.

use std::path::PathBuf;

/// A job that cannot be run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JobError {
    /// The job file could not be read.
    #[error("{}: cannot read: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        message: String,
    },
    /// A value is invalid; `path` is its JSON path (`cases[2].length_errors.longeron`).
    #[error("{}{message}", if path.is_empty() { String::new() } else { format!("{path}: ") })]
    Invalid {
        /// JSON path of the fault.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// An error in a given job file.
    #[error("{}: {source}", file.display())]
    InFile {
        /// The job file.
        file: PathBuf,
        /// The error.
        source: Box<JobError>,
    },
}

impl JobError {
    /// An invalid value at JSON path `path`.
    pub fn at(path: &str, message: &str) -> Self {
        JobError::Invalid {
            path: path.to_string(),
            message: message.to_string(),
        }
    }

    /// This error, said of the job file `file`.
    pub fn in_file(self, file: &std::path::Path) -> Self {
        match self {
            e @ JobError::Io { .. } => e,
            e => JobError::InFile {
                file: file.to_path_buf(),
                source: Box::new(e),
            },
        }
    }
}

/// A shard that cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    /// The file or directory could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file holds a shard of another job (or range); it is never appended to.
    #[error("{}: holds a shard of job {found_job} range {found_range}, not of job {job} range {range}; it is never appended to (move it away, or use another --out)", path.display())]
    OtherJob {
        /// The file.
        path: PathBuf,
        /// Its job id.
        found_job: String,
        /// Its range.
        found_range: shard_record::ShardRange,
        /// Our job id.
        job: String,
        /// Our range.
        range: shard_record::ShardRange,
    },
    /// Another process holds the file's lock: it is writing this shard now.
    #[error("{}: another process is writing this shard (its lock is held)", path.display())]
    Locked {
        /// The file.
        path: PathBuf,
    },
    /// The file is damaged in a way no crash produces (a bad line before the end).
    #[error(transparent)]
    Corrupt(shard_record::ScanError),
}

/// Why a run could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The job is invalid.
    #[error(transparent)]
    Job(#[from] JobError),
    /// The shard file is in the way.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// The requested range or shard does not exist, or the arguments disagree.
    #[error("{0}")]
    Usage(String),
}
