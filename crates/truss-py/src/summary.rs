//! `truss_mc._native.Collected`: the samples of a run in-process or of shards read back, kept
//! as the merge keeps them ([`mc_merge::load::Collector`]: θ_P, the tilts, the loose-joint,
//! floating and holding-force fields, about 30 bytes a sample), so that Python gets the
//! merge's statistics from the merge's own code: [`mc_merge::build_report`] gives the report
//! `mc-merge` writes as `report.json` for shards of the same lines, byte for byte, and
//! [`mc_merge::table::answer`] the answer lines its console ends with. Nothing is computed
//! here.

use crate::errors::{Failure, Kind};
use mc_merge::load::{Collector, Dataset, LoadOptions, ShardWriter, check_coverage};
use mc_merge::{MergeError, Settings};
use pyo3::prelude::*;
use shard_record::{Budget, CaseInfo, Sample};
use std::sync::Arc;

impl From<MergeError> for Failure {
    fn from(e: MergeError) -> Self {
        let kind = match e.exit_code() {
            truss_exit::USAGE => Kind::Usage,
            truss_exit::INVALID_INPUT => Kind::InvalidInput,
            truss_exit::IO => Kind::Io,
            truss_exit::FAILED_SAMPLES => Kind::SolveFailed,
            _ => Kind::Verification,
        };
        Failure::new(kind, truss_exit::message(&e))
    }
}

/// Collects samples, then hands them to Python as [`PyCollected`].
pub struct Collecting {
    collector: Collector,
}

impl Collecting {
    /// A collection for the job `job_id` of `job_samples` samples in `cases`, whose samples
    /// `program` (version `version`) computed, held to the job's alignment `budget` (as a
    /// shard's begin line carries it: the report's budget section).
    pub fn new(
        job_id: &str,
        job_samples: u64,
        cases: &[CaseInfo],
        budget: Option<Budget>,
        program: &str,
        version: &str,
    ) -> Self {
        let writer = ShardWriter {
            program: program.to_string(),
            program_version: version.to_string(),
            format_version: shard_record::FORMAT_VERSION,
            files: 0,
        };
        Self {
            collector: Collector::new(job_id, job_samples, cases, writer).with_budget(budget),
        }
    }

    /// Adds a sample and its shard line.
    pub fn add(&mut self, sample: &Sample, line: &[u8]) -> Result<(), Failure> {
        Ok(self.collector.add(sample, line)?)
    }

    /// The collection, for Python; `selection` says whether the samples are meant to be a
    /// part of the job (a case or a range), so that the merge's statistics allow the rest
    /// to be missing by default.
    pub fn finish(self, selection: bool) -> Result<PyCollected, Failure> {
        let data = self.collector.finish(LoadOptions {
            allow_partial: true,
            allow_failed: true,
            threads: 1,
        })?;
        Ok(PyCollected {
            data: Arc::new(data),
            selection,
        })
    }
}

/// Samples as the merge keeps them.
#[pyclass(frozen, name = "Collected", module = "truss_mc._native")]
pub struct PyCollected {
    data: Arc<Dataset>,
    selection: bool,
}

#[pymethods]
impl PyCollected {
    /// Whether the samples are a selection of the job's (a case or a range of a run).
    #[getter]
    fn selection(&self) -> bool {
        self.selection
    }

    /// The merge's report of the samples: `(report_json, answer_lines)`, the text of
    /// `report.json` and the console's closing answer lines, under `mc-merge`'s settings,
    /// each `mc-merge`'s default where None (`mc_merge::Settings::default`) and refused as
    /// `mc-merge` refuses it, naming its flag. Missing samples are refused unless
    /// `allow_partial` (by default, whether the samples are a selection), failed ones
    /// unless `allow_failed`, as the merge refuses them.
    #[pyo3(signature = (
        percentiles = None,
        confidence = None,
        replicates = None,
        bootstrap_seed = None,
        gof_replicates = None,
        gof_level = None,
        target_angle = None,
        target_percentile = None,
        allow_partial = None,
        allow_failed = None,
        threads = None,
    ))]
    #[allow(clippy::too_many_arguments)]
    fn report(
        &self,
        py: Python<'_>,
        percentiles: Option<Vec<f64>>,
        confidence: Option<f64>,
        replicates: Option<u32>,
        bootstrap_seed: Option<u64>,
        gof_replicates: Option<u32>,
        gof_level: Option<f64>,
        target_angle: Option<f64>,
        target_percentile: Option<f64>,
        allow_partial: Option<bool>,
        allow_failed: Option<bool>,
        threads: Option<usize>,
    ) -> PyResult<(String, String)> {
        let d = Settings::default();
        let threads = mc_shard::cli::check_threads("threads", truss_threads::or_available(threads))
            .map_err(Failure::from)?;
        let settings = Settings {
            percentiles: percentiles.unwrap_or(d.percentiles),
            confidence: confidence.unwrap_or(d.confidence),
            replicates: replicates.unwrap_or(d.replicates),
            bootstrap_seed: bootstrap_seed.unwrap_or(d.bootstrap_seed),
            gof_replicates: gof_replicates.unwrap_or(d.gof_replicates),
            gof_level: gof_level.unwrap_or(d.gof_level),
            target_angle: target_angle.unwrap_or(d.target_angle),
            target_percentile: target_percentile.unwrap_or(d.target_percentile),
            allow_partial: allow_partial.unwrap_or(self.selection),
            allow_failed: allow_failed.unwrap_or(d.allow_failed),
            threads,
        };
        let data = Arc::clone(&self.data);
        let out = py.detach(move || {
            let settings = settings.validate()?;
            check_coverage(
                &data,
                LoadOptions {
                    allow_partial: settings.allow_partial,
                    allow_failed: settings.allow_failed,
                    threads,
                },
            )?;
            let report = mc_merge::build_report(&data, &settings)?;
            Ok::<_, MergeError>((
                mc_merge::report_json(&report)?,
                mc_merge::table::answer(&report),
            ))
        });
        Ok(out.map_err(Failure::from)?)
    }

    fn __repr__(&self) -> String {
        format!(
            "Collected(job {}…, {} of {} samples)",
            &self.data.job_id[..12.min(self.data.job_id.len())],
            self.data.present(),
            self.data.job_samples
        )
    }
}
