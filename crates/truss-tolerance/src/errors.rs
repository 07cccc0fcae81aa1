//! The tolerance study's error: what is wrong, with the group, flag or file it concerns.

use std::path::PathBuf;

/// Why a tolerance study cannot be done, or did not verify.
#[derive(Debug, thiserror::Error)]
pub enum ToleranceError {
    /// The job is invalid or unreadable (the job's own error names file and JSON path).
    #[error(transparent)]
    Job(#[from] truss_job::JobError),
    /// The job has no case of that name.
    #[error("the job has no case {case:?} (its cases: {known})")]
    NoCase {
        /// The name asked for.
        case: String,
        /// The job's case names, comma-separated.
        known: String,
    },
    /// A command-line value is malformed or out of range.
    #[error("{flag}: {message}")]
    BadValue {
        /// The flag (`--cost`, `--target-arcsec`, …).
        flag: String,
        /// What is wrong.
        message: String,
    },
    /// `--cost` or `--fix` names a group the case does not allocate.
    #[error("{flag} {group}: the case has no length-error group {group:?} (its groups: {known})")]
    UnknownGroup {
        /// The flag.
        flag: String,
        /// The group named.
        group: String,
        /// The case's groups with length errors, comma-separated.
        known: String,
    },
    /// The case gives no member group a length error: there is nothing to allocate.
    #[error(
        "case {case:?} gives no member group a length error (cases[].length_errors is empty): \
         there is no tolerance to allocate"
    )]
    NoLengthErrors {
        /// The case.
        case: String,
    },
    /// A group's length error cannot be scaled (not zero-mean, or σ = 0), so its sensitivity
    /// cannot be measured or its σ changed.
    #[error("case {case:?}, group {group:?}: {reason}")]
    NotScalable {
        /// The case.
        case: String,
        /// The group.
        group: String,
        /// Why.
        reason: String,
    },
    /// The case has something besides zero-mean length errors (effects, joint clearances)
    /// that breaks the homogeneity the allocation rests on.
    #[error("case {case:?}: {reason}")]
    Unsupported {
        /// The case.
        case: String,
        /// What is present.
        reason: String,
    },
    /// A group has no measurable influence on the tilt: its tolerance is unbounded.
    #[error(
        "group {group:?} has no measurable influence on the tilt (share {share:.2e} of the \
         variance): its tolerance is unbounded; pin it with --fix {group}=SIGMA"
    )]
    ZeroSensitivity {
        /// The group.
        group: String,
        /// Its measured share.
        share: f64,
    },
    /// The fixed groups alone already use up the budget.
    #[error(
        "target unreachable: the fixed groups ({groups}) alone give θ_P{percentile} ≈ \
         {theta_fixed:.3e} rad ({arcsec:.2}″), at or above the target {target}"
    )]
    Unreachable {
        /// The fixed groups, comma-separated.
        groups: String,
        /// The percentile (in %).
        percentile: f64,
        /// The fixed groups' predicted θ_P at that percentile \[rad\].
        theta_fixed: f64,
        /// Its value in arcseconds.
        arcsec: f64,
        /// The target, as it was set.
        target: truss_units::TargetAngle,
    },
    /// Some samples did not solve; none are dropped silently.
    #[error(
        "{failed} of {samples} samples of the {stage} run failed (first: sample {first}: {reason})"
    )]
    FailedSamples {
        /// Which run (`sensitivity`, `verification`, `uniform`).
        stage: &'static str,
        /// How many failed.
        failed: usize,
        /// How many were run.
        samples: usize,
        /// The first failed sample's index within the case.
        first: u64,
        /// Its reason.
        reason: String,
    },
    /// A statistic could not be formed (too few samples for the regression or the bootstrap).
    #[error("{0}")]
    Statistics(String),
    /// The allocation did not verify (the files were written; the report says how far off).
    #[error(
        "verification failed: θ_P{percentile} = {theta:.4e} rad, 95 % interval [{lower:.4e}, \
         {upper:.4e}], target {target} (must have upper ≤ target and estimate ≥ 0.9 × target)"
    )]
    Verification {
        /// The percentile (in %).
        percentile: f64,
        /// The estimate \[rad\].
        theta: f64,
        /// The interval's lower end \[rad\].
        lower: f64,
        /// The interval's upper end \[rad\].
        upper: f64,
        /// The target, as it was set.
        target: truss_units::TargetAngle,
    },
    /// A file could not be written.
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// An output is in the way (a link or a non-file at its name, another process writing
    /// the directory) or could not be written.
    #[error(transparent)]
    Files(#[from] run_dir::RunDirError),
    /// A plot could not be drawn.
    #[error("{}: cannot draw: {message}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl ToleranceError {
    /// Whether the error is the user's command line (a usage error), as opposed to the job.
    pub fn is_usage(&self) -> bool {
        matches!(
            self,
            ToleranceError::NoCase { .. }
                | ToleranceError::BadValue { .. }
                | ToleranceError::UnknownGroup { .. }
        )
    }
}
