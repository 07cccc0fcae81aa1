//! The baseline job and case, and the jobs derived from it: the same seed and case name (so
//! every derived case draws the same random words for the same sample: common random
//! numbers), edited through the job crate's (`truss-job`) format, validated by it.

use crate::errors::DiagnoseError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use truss_core::Model;
use truss_job::Job;
use truss_job::distribution::DistributionSpec;
use truss_job::effects::EffectsSpec;
use truss_job::job::{CaseSpec, JobSpec, ModelSpec};

/// The baseline job file and the case being diagnosed.
#[derive(Debug, Clone)]
pub struct Baseline {
    /// The job file.
    pub path: PathBuf,
    /// The job as written, model file paths made absolute.
    pub spec: JobSpec,
    /// Index of the case.
    pub case_index: usize,
    /// The case's name.
    pub case_name: String,
    /// The job's seed.
    pub seed: u64,
    /// The validated baseline job.
    pub job: Job,
}

/// A case being edited, as a typed spec: the case and its effective model (the job's
/// default model unless the case has its own). A candidate effect edits either; see
/// [`Baseline::derived_case`].
#[derive(Debug, Clone, PartialEq)]
pub struct CaseEdit {
    /// The case (`name`, `samples`, `length_errors`, `effects`, `backlash`).
    pub case: CaseSpec,
    /// The case's model.
    pub model: ModelSpec,
    /// Whether `model` was edited (then written into the case).
    pub model_edited: bool,
}

impl CaseEdit {
    /// The distribution of `group`'s length errors, if the case gives one.
    pub fn distribution(&self, group: &str) -> Option<DistributionSpec> {
        self.case.length_errors.get(group).copied()
    }

    /// Sets `group`'s distribution.
    pub fn set_distribution(&mut self, group: &str, d: DistributionSpec) {
        self.case.length_errors.insert(group.to_string(), d);
    }

    /// The case's effects.
    pub fn effects(&self) -> EffectsSpec {
        self.case.effects.clone()
    }

    /// Sets the case's effects.
    pub fn set_effects(&mut self, e: &EffectsSpec) {
        self.case.effects = e.clone();
    }
}

/// The unit tests' baseline: case `as-built` of `jobs/diagnose-baseline.json`.
#[cfg(test)]
impl Baseline {
    pub(crate) fn of_test() -> Self {
        let job = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../jobs/diagnose-baseline.json");
        Self::read(&job, "as-built").expect("the test job reads")
    }
}

impl Baseline {
    /// Reads the job file and finds the case.
    pub fn read(path: &Path, case: &str) -> Result<Self, DiagnoseError> {
        let job = Job::read(path)?;
        let base = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let base = base
            .canonicalize()
            .map_err(|e| DiagnoseError::io(base, e))?;
        let mut spec = JobSpec::read(path)?;
        spec.model = spec.model.absolute(&base);
        for c in &mut spec.cases {
            c.model = c.model.take().map(|m| m.absolute(&base));
        }
        let case_index = job.case_named(case).ok_or_else(|| DiagnoseError::NoCase {
            name: case.to_string(),
            available: job
                .cases
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            seed: job.seed,
            spec,
            case_index,
            case_name: case.to_string(),
            job,
        })
    }

    /// The validated baseline case.
    pub fn case(&self) -> &truss_job::job::Case {
        &self.job.cases[self.case_index]
    }

    /// The baseline case's model.
    pub fn model(&self) -> &Arc<Model> {
        &self.case().model
    }

    /// The baseline case's length-error distributions by group.
    pub fn distributions(&self) -> &BTreeMap<String, DistributionSpec> {
        &self.case().length_errors
    }

    /// A fresh edit of the baseline case.
    pub fn derived_case(&self) -> CaseEdit {
        let case = self.spec.cases[self.case_index].clone();
        let model = case
            .model
            .clone()
            .unwrap_or_else(|| self.spec.model.clone());
        CaseEdit {
            case,
            model,
            model_edited: false,
        }
    }

    /// The case an edit stands for, its model written in when edited.
    fn case_spec(&self, edit: &CaseEdit) -> CaseSpec {
        let mut case = edit.case.clone();
        if edit.model_edited {
            case.model = Some(edit.model.clone());
        }
        case
    }

    /// A one-case job of `samples` samples of the edited case, under the baseline's seed
    /// (common random numbers) or `seed`: validated from the typed spec, no JSON between.
    pub fn job_of(
        &self,
        edit: &CaseEdit,
        samples: u64,
        seed: Option<u64>,
    ) -> Result<Job, DiagnoseError> {
        let spec = JobSpec {
            model: self.spec.model.clone(),
            seed: seed.unwrap_or(self.seed),
            cases: vec![CaseSpec {
                samples,
                ..self.case_spec(edit)
            }],
            budget: self.spec.budget,
        };
        Ok(Job::new(&spec, Path::new("."))?)
    }

    /// The baseline job with the case replaced by the edited one (same name and sample
    /// count), as pretty JSON: the updated job mc-shard and mc-merge run like any other.
    pub fn updated_job_json(&self, edit: &CaseEdit) -> String {
        let mut spec = self.spec.clone();
        spec.cases[self.case_index] = self.case_spec(edit);
        spec.to_json()
    }
}
