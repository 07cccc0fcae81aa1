//! The settings of a merge ([`Settings`]: the statistics, recorded in the report) and a
//! validated merge request ([`Options`]), whether they come from the command line
//! ([`crate::cli`]) or from a library user; every value has a documented range, checked by
//! [`Settings::validate`] naming the flag that sets it.

use crate::errors::MergeError;
use serde::Serialize;
use std::path::PathBuf;

/// The default seed of the bootstrap and of the goodness-of-fit null simulation.
pub const DEFAULT_SEED: u64 = 20_210_325;

/// 20 arcseconds in radians, rounded as in the paper: 9.69e-5 rad.
pub const DEFAULT_TARGET_ANGLE: f64 = 9.69e-5;

/// The most bootstrap replicates `--replicates` accepts. The replicate percentiles are kept
/// (8 bytes × percentiles × B), and the time grows as B × n: 100,000 replicates of 50,000
/// samples take about half a minute; B = 2000 already puts the Monte Carlo error of a 95 %
/// interval's ends well below the interval's width.
pub const MAX_REPLICATES: u32 = 100_000;

/// The most null samples `--gof-replicates` accepts (each is a simulated sample of the
/// case's size, up to the calibration's cap).
pub const MAX_GOF_REPLICATES: u32 = 100_000;

/// The most percentiles `--percentiles` accepts (each one is bootstrapped).
pub const MAX_PERCENTILES: usize = 64;

/// The largest target angle `--target-angle` accepts, in rad: a tilt below a right angle.
pub const MAX_TARGET_ANGLE: f64 = std::f64::consts::FRAC_PI_2;

/// The statistical settings of a merge, recorded in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    /// Percentiles of θ_P in percent, ascending, distinct, including the target percentile.
    pub percentiles: Vec<f64>,
    /// Confidence level of every interval.
    pub confidence: f64,
    /// Bootstrap replicates B.
    pub replicates: u32,
    /// Bootstrap seed.
    pub bootstrap_seed: u64,
    /// Goodness-of-fit null samples M.
    pub gof_replicates: u32,
    /// Goodness-of-fit significance level.
    pub gof_level: f64,
    /// Target angle (rad).
    pub target_angle: f64,
    /// The percentile that must meet the target, in percent.
    pub target_percentile: f64,
    /// Whether missing ranges were tolerated.
    pub allow_partial: bool,
    /// Whether failed samples were tolerated.
    pub allow_failed: bool,
    /// Worker threads (not in the report: results do not depend on it).
    #[serde(skip)]
    pub threads: usize,
}

impl Settings {
    /// The target angle as it was set (`--target-angle`, in rad); its `Display` is the one
    /// spelling of the target in the console, the reports and the plots.
    pub fn target(&self) -> truss_units::TargetAngle {
        truss_units::TargetAngle::Rad(self.target_angle)
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            percentiles: vec![50.0, 90.0, 95.0, 99.0],
            confidence: 0.95,
            replicates: 2000,
            bootstrap_seed: DEFAULT_SEED,
            gof_replicates: 1000,
            gof_level: 0.05,
            target_angle: DEFAULT_TARGET_ANGLE,
            target_percentile: 95.0,
            allow_partial: false,
            allow_failed: false,
            threads: truss_threads::available(),
        }
    }
}

/// A validated merge request.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Shard files or directories.
    pub paths: Vec<PathBuf>,
    /// Report directory.
    pub out: Option<PathBuf>,
    /// Whether to draw plots (only with `out`).
    pub plots: bool,
    /// Whether [`crate::run`] says on stderr where it is (the shards verified, each case,
    /// the plots, the readable reports).
    pub progress: bool,
    /// The statistics.
    pub settings: Settings,
}

fn usage(message: String) -> MergeError {
    MergeError::Usage { message }
}

impl Settings {
    /// Checks every value and returns the settings with the percentiles sorted, distinct and
    /// including the target percentile. [`crate::merge`] calls it, so library users get the
    /// same checks as the command line.
    pub fn validate(&self) -> Result<Settings, MergeError> {
        let open01 = |name: &str, v: f64| {
            if v > 0.0 && v < 1.0 {
                Ok(v)
            } else {
                Err(usage(format!(
                    "--{name} {v}: must be a fraction strictly between 0 and 1 (e.g. 0.95)"
                )))
            }
        };
        open01("confidence", self.confidence)?;
        open01("gof-level", self.gof_level)?;
        let pct_ok = |v: f64| v > 0.0 && v < 100.0;
        if let Some(bad) = self.percentiles.iter().find(|v| !pct_ok(**v)) {
            return Err(usage(format!(
                "--percentiles: {bad} is not a percentile strictly between 0 and 100"
            )));
        }
        if !pct_ok(self.target_percentile) {
            return Err(usage(format!(
                "--target-percentile {}: must be strictly between 0 and 100",
                self.target_percentile
            )));
        }
        if self.percentiles.len() > MAX_PERCENTILES {
            return Err(usage(format!(
                "--percentiles: {} values given, at most {MAX_PERCENTILES}",
                self.percentiles.len()
            )));
        }
        if !(self.target_angle > 0.0 && self.target_angle < MAX_TARGET_ANGLE) {
            return Err(usage(format!(
                "--target-angle {}: must be a positive angle in rad below π/2 (e.g. 9.69e-5, the paper's 20 arcsec rounded)",
                self.target_angle
            )));
        }
        if !(10..=MAX_REPLICATES).contains(&self.replicates) {
            return Err(usage(format!(
                "--replicates {}: must be between 10 and {MAX_REPLICATES} bootstrap replicates (2000 recommended)",
                self.replicates
            )));
        }
        if !(19..=MAX_GOF_REPLICATES).contains(&self.gof_replicates) {
            return Err(usage(format!(
                "--gof-replicates {}: must be between 19 and {MAX_GOF_REPLICATES} null samples (1000 recommended)",
                self.gof_replicates
            )));
        }
        let mut percentiles = self.percentiles.clone();
        percentiles.push(self.target_percentile);
        percentiles.sort_by(f64::total_cmp);
        percentiles.dedup();
        Ok(Settings {
            percentiles,
            threads: self.threads.max(1),
            ..self.clone()
        })
    }
}
