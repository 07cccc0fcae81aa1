//! The job's error: what is wrong, with the JSON path or file of the fault.

use std::path::PathBuf;

/// A job that cannot be run.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The job file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The job file was refused before it was parsed: not a regular file, too large, or not
    /// UTF-8 (see [`truss_core::model_file::read_input`]).
    #[error("{}: {reason}", path.display())]
    Refused {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: truss_core::InputRefusal,
    },
    /// A model file the job names could not be read (missing, no permission): an I/O
    /// failure, as the job file's own is.
    #[error("{at}: cannot read model file {}: {source}", path.display())]
    ModelIo {
        /// JSON path of the model in the job (`model`, `cases[1].model`).
        at: String,
        /// The model file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
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

    /// Whether a file could not be read (the job file, or a model file it names): an I/O
    /// failure (exit code 4), not an invalid job (3).
    pub fn is_io(&self) -> bool {
        match self {
            JobError::Io { .. } | JobError::ModelIo { .. } => true,
            JobError::InFile { source, .. } => source.is_io(),
            JobError::Refused { .. } | JobError::Invalid { .. } => false,
        }
    }

    /// This error, said of the job file `file`.
    pub fn in_file(self, file: &std::path::Path) -> Self {
        match self {
            e @ (JobError::Io { .. } | JobError::Refused { .. }) => e,
            e => JobError::InFile {
                file: file.to_path_buf(),
                source: Box::new(e),
            },
        }
    }
}
