//! What a tolerance study is asked: the job, case, target, percentile, costs, pins, sample
//! counts and output directory, with the checks of the values a command line or a library
//! user gives (each refusal names its flag) before any work.

use crate::errors::ToleranceError;
use std::path::PathBuf;
pub use truss_units::TargetAngle;

/// What to study.
#[derive(Debug, Clone)]
pub struct Options {
    /// The job file.
    pub job: PathBuf,
    /// The case's name.
    pub case: String,
    /// The target θ*, as it was set (in rad or in arcsec).
    pub target: TargetAngle,
    /// The percentile, in % (0 < p < 100).
    pub percentile: f64,
    /// `GROUP=WEIGHT` cost weights.
    pub costs: Vec<String>,
    /// `GROUP=SIGMA` pinned σ \[mm\].
    pub fixes: Vec<String>,
    /// Output directory.
    pub out: PathBuf,
    /// Samples of each verification run.
    pub samples: usize,
    /// Samples of the sensitivity run.
    pub sensitivity_samples: usize,
    /// Draw the SVG plots.
    pub plots: bool,
    /// Worker threads (None: the machine's; results do not depend on it).
    pub threads: Option<usize>,
    /// No progress on stderr.
    pub quiet: bool,
}

impl Options {
    /// Default options for a job, case, target and output directory.
    pub fn new(job: PathBuf, case: &str, target: TargetAngle, out: PathBuf) -> Self {
        Self {
            job,
            case: case.to_string(),
            target,
            percentile: 95.0,
            costs: Vec::new(),
            fixes: Vec::new(),
            out,
            samples: 20_000,
            sensitivity_samples: 4_000,
            plots: true,
            threads: None,
            quiet: true,
        }
    }
}

impl Options {
    /// Refuses values outside their documented ranges, naming the flag: the target in
    /// (0, 324000) arcsec (below π/2 rad), the percentile in (0, 100) %, at least 1000 verification samples.
    /// (The sensitivity run's least sample count depends on the model, so
    /// [`crate::run`] checks it once the members are known.)
    pub fn check(&self) -> Result<(), ToleranceError> {
        let arcsec = self.target.arcsec();
        if !(arcsec.is_finite() && arcsec > 0.0 && arcsec < 324_000.0) {
            return Err(match self.target {
                TargetAngle::Arcsec(a) => bad(
                    "--target-arcsec",
                    format!("{a} is not an angle in (0, 324000) arcsec"),
                ),
                TargetAngle::Rad(r) => bad(
                    "--target-angle",
                    format!("{r} is not an angle in (0, π/2) rad"),
                ),
            });
        }
        if !(self.percentile.is_finite() && self.percentile > 0.0 && self.percentile < 100.0) {
            return Err(bad(
                "--percentile",
                format!("{} is not a percentage in (0, 100)", self.percentile),
            ));
        }
        if self.samples < 1000 {
            return Err(bad(
                "--samples",
                format!("{} verification samples: need at least 1000", self.samples),
            ));
        }
        Ok(())
    }
}

/// A refusal of a flag's value.
pub(crate) fn bad(flag: &str, message: String) -> ToleranceError {
    ToleranceError::BadValue {
        flag: flag.into(),
        message,
    }
}
