//! What went wrong in a `truss` command, and the one function that maps it to the exit code
//! ([`exit_code`], the scheme of `truss-exit`; the crate doc lists the codes).

use run_dir::RunDirError;
use truss_diagnose::DiagnoseError;
use truss_tolerance::ToleranceError;

/// What went wrong, classified for the exit code.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad arguments.
    #[error("{0}")]
    Usage(String),
    /// An invalid model.
    #[error(transparent)]
    Model(truss_core::ModelError),
    /// The solve failed (the JSON result was printed).
    #[error("the solve failed: {0}")]
    Solve(truss_core::SolveError),
    /// Output could not be written.
    #[error("cannot write output: {0}")]
    Io(#[from] std::io::Error),
    /// A diagnosis (or synthetic measurement) failed.
    #[error(transparent)]
    Diagnose(#[from] DiagnoseError),
    /// A tolerance study failed.
    #[error(transparent)]
    Tolerance(#[from] ToleranceError),
}

impl From<truss_core::ModelError> for CliError {
    fn from(e: truss_core::ModelError) -> Self {
        CliError::Model(e)
    }
}

/// The exit code of `truss` for an error (see the crate doc): the one place a failure
/// becomes a code. Anything but a [`CliError`] is a bug.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    use truss_exit::{
        FAILED_SAMPLES, IN_THE_WAY, INTERNAL, INVALID_INPUT, IO, USAGE, VERIFICATION,
    };
    let Some(e) = e.downcast_ref::<CliError>() else {
        return INTERNAL;
    };
    match e {
        CliError::Usage(_)
        | CliError::Diagnose(DiagnoseError::Usage(_) | DiagnoseError::NoCase { .. })
        | CliError::Tolerance(
            ToleranceError::NoCase { .. }
            | ToleranceError::BadValue { .. }
            | ToleranceError::UnknownGroup { .. },
        ) => USAGE,
        CliError::Diagnose(DiagnoseError::Job(e)) | CliError::Tolerance(ToleranceError::Job(e))
            if e.is_io() =>
        {
            IO
        }
        CliError::Io(_)
        | CliError::Model(truss_core::ModelError::Io { .. })
        | CliError::Diagnose(DiagnoseError::Io { .. } | DiagnoseError::Plot { .. })
        | CliError::Tolerance(ToleranceError::Write { .. } | ToleranceError::Plot { .. }) => IO,
        CliError::Diagnose(DiagnoseError::Files(files))
        | CliError::Tolerance(ToleranceError::Files(files)) => match files {
            RunDirError::Io { .. } => IO,
            RunDirError::Link { .. }
            | RunDirError::NotAFile { .. }
            | RunDirError::Locked { .. }
            | RunDirError::NotOurs { .. }
            | RunDirError::HardLinked { .. } => IN_THE_WAY,
            RunDirError::NotRegular { .. } => INVALID_INPUT,
        },
        CliError::Model(_)
        | CliError::Diagnose(
            DiagnoseError::Job(_) | DiagnoseError::BadRow { .. } | DiagnoseError::Measured { .. },
        )
        | CliError::Tolerance(
            ToleranceError::Job(_)
            | ToleranceError::NoLengthErrors { .. }
            | ToleranceError::NotScalable { .. }
            | ToleranceError::Unsupported { .. }
            | ToleranceError::ZeroSensitivity { .. }
            | ToleranceError::Unreachable { .. },
        ) => INVALID_INPUT,
        CliError::Solve(_)
        | CliError::Diagnose(DiagnoseError::Simulation { .. })
        | CliError::Tolerance(ToleranceError::FailedSamples { .. }) => FAILED_SAMPLES,
        CliError::Tolerance(ToleranceError::Verification { .. }) => VERIFICATION,
        CliError::Tolerance(ToleranceError::Statistics(_)) => INTERNAL,
    }
}
