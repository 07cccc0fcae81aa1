//! Errors crossing into Python: every library error becomes an exception of
//! `truss_mc.errors` carrying the message the command-line tools print (after
//! `BINARY: error: `), the exit code they exit with, and for an invalid job or prism the
//! JSON path of the fault.
//!
//! | exception (all subclasses of `TrussError`) | exit code | from |
//! |---|---|---|
//! | `UsageError` (also a `ValueError`) | 2 | a case, sample, range or thread count that does not exist |
//! | `InvalidInputError` (also a `ValueError`) | 3 | an invalid job, prism or model file, a length error beyond the model's range |
//! | `TrussIOError` (also an `OSError`) | 4 | a file that could not be read |
//! | `VerificationError` | 6 | a shard file that does not verify, shards of two jobs, a disagreeing overlap |
//! | `SolveFailedError` | 7 | a solve that did not converge |

use mc_shard::RunError;
use pyo3::prelude::*;
use truss_job::JobError;

/// What kind of failure, naming its exception class and exit code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Bad arguments.
    Usage,
    /// An invalid job, prism, model or value.
    InvalidInput,
    /// A file that could not be read.
    Io,
    /// Shards that do not verify.
    Verification,
    /// A solve that failed.
    SolveFailed,
}

impl Kind {
    /// The exception's class name in `truss_mc.errors`.
    fn class(self) -> &'static str {
        match self {
            Kind::Usage => "UsageError",
            Kind::InvalidInput => "InvalidInputError",
            Kind::Io => "TrussIOError",
            Kind::Verification => "VerificationError",
            Kind::SolveFailed => "SolveFailedError",
        }
    }
}

/// A failure on its way to Python.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Its kind.
    pub kind: Kind,
    /// The message, as the tools print it.
    pub message: String,
    /// The JSON path of an invalid value, when there is one.
    pub json_path: Option<String>,
}

impl Failure {
    /// A failure of `kind` with `message` and no JSON path.
    pub fn new(kind: Kind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
            json_path: None,
        }
    }
}

/// The JSON path of a job error, if it names one.
fn json_path(e: &JobError) -> Option<String> {
    match e {
        JobError::Invalid { path, .. } if !path.is_empty() => Some(path.clone()),
        JobError::InFile { source, .. } => json_path(source),
        _ => None,
    }
}

impl From<JobError> for Failure {
    fn from(e: JobError) -> Self {
        let kind = match &e {
            JobError::Io { .. } => Kind::Io,
            JobError::InFile { source, .. } if matches!(**source, JobError::Io { .. }) => Kind::Io,
            _ => Kind::InvalidInput,
        };
        Self {
            kind,
            message: truss_exit::message(&e),
            json_path: json_path(&e),
        }
    }
}

impl From<RunError> for Failure {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Job(e) => e.into(),
            RunError::Usage(message) => Failure::new(Kind::Usage, message),
            // The bindings write no shard files; a shard error is one read back.
            RunError::Shard(e) => Failure::new(Kind::Verification, truss_exit::message(&e)),
        }
    }
}

impl From<truss_core::ModelError> for Failure {
    fn from(e: truss_core::ModelError) -> Self {
        let kind = match &e {
            truss_core::ModelError::Io { .. } => Kind::Io,
            _ => Kind::InvalidInput,
        };
        Failure::new(kind, truss_exit::message(&e))
    }
}

impl From<shard_record::ScanError> for Failure {
    fn from(e: shard_record::ScanError) -> Self {
        let kind = match &e {
            shard_record::ScanError::Io { .. } => Kind::Io,
            _ => Kind::Verification,
        };
        Failure::new(kind, truss_exit::message(&e))
    }
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        Python::attach(|py| {
            let raised = py
                .import("truss_mc.errors")
                .and_then(|m| m.getattr(f.kind.class()))
                .and_then(|class| class.call1((f.message,)))
                .and_then(|e| {
                    if let Some(path) = f.json_path {
                        e.setattr("json_path", path)?;
                    }
                    Ok(e)
                });
            match raised {
                Ok(e) => PyErr::from_value(e),
                Err(e) => e,
            }
        })
    }
}
