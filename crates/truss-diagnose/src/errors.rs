//! Errors of the diagnosis, each carrying what is needed to find the fault.

use std::path::PathBuf;

/// Why a diagnosis (or a synthetic measurement) could not be made.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// The baseline job is invalid.
    #[error(transparent)]
    Job(#[from] truss_job::JobError),
    /// The job has no case of that name.
    #[error("the job has no case {name:?} (its cases: {available})")]
    NoCase {
        /// The name asked for.
        name: String,
        /// The job's case names, comma separated.
        available: String,
    },
    /// A file could not be read or written.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        message: String,
    },
    /// A measured file has a bad row (or a bad header, line 1).
    #[error("{}:{line}: {message}", path.display())]
    BadRow {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the row.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// The measured data cannot be used as a whole (too few specimens, no top surface).
    #[error("{}: {message}", path.display())]
    Measured {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A command-line value is invalid.
    #[error("{0}")]
    Usage(String),
    /// The simulation could not give usable statistics (too many failed solves, a singular
    /// covariance).
    #[error("simulation of {what}: {message}")]
    Simulation {
        /// Which simulation (the candidate and its parameters).
        what: String,
        /// What went wrong.
        message: String,
    },
    /// An output is in the way (a link or a non-file at its name, another process writing
    /// the directory) or could not be written.
    #[error(transparent)]
    Files(#[from] run_dir::RunDirError),
    /// A plot could not be drawn.
    #[error("plot {}: {message}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// The plotting library's error.
        message: String,
    },
}

impl DiagnoseError {
    /// Whether a file could not be read or written (the job file's too).
    pub fn is_io(&self) -> bool {
        matches!(
            self,
            DiagnoseError::Io { .. }
                | DiagnoseError::Plot { .. }
                | DiagnoseError::Files(run_dir::RunDirError::Io { .. })
        ) || matches!(self, DiagnoseError::Job(e) if e.is_io())
    }

    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        DiagnoseError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}
