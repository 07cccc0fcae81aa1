//! The baseline job and case, and the jobs derived from it: the same seed and case name (so
//! every derived case draws the same random words for the same sample: common random
//! numbers), edited through the job crate's (`truss-job`) format, validated by it.

use crate::errors::DiagnoseError;
use serde_json::{Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use truss_core::Model;
use truss_job::Job;
use truss_job::distribution::DistributionSpec;
use truss_job::effects::EffectsSpec;

/// The baseline job file and the case being diagnosed.
#[derive(Debug, Clone)]
pub struct Baseline {
    /// The job file.
    pub path: PathBuf,
    /// The job as JSON, model file paths made absolute.
    pub raw: Value,
    /// Index of the case.
    pub case_index: usize,
    /// The case's name.
    pub case_name: String,
    /// The job's seed.
    pub seed: u64,
    /// The validated baseline job.
    pub job: Job,
}

/// A case being edited: its JSON object and its effective model's JSON (the job's default
/// model unless the case has its own). A candidate effect edits either; see
/// [`Baseline::derived_case`].
#[derive(Debug, Clone)]
pub struct CaseEdit {
    /// The case object (`name`, `samples`, `length_errors`, `effects`, …).
    pub case: Map<String, Value>,
    /// The case's model, `{"prism": {...}}` or a model file reference.
    pub model: Value,
    /// Whether `model` was edited (then written into the case).
    pub model_edited: bool,
}

impl CaseEdit {
    /// The distribution of `group`'s length errors, if the case gives one.
    pub fn distribution(&self, group: &str) -> Option<DistributionSpec> {
        self.case
            .get("length_errors")
            .and_then(|l| l.get(group))
            .and_then(|v| serde_json::from_value(v.clone()).ok())
    }

    /// Sets `group`'s distribution.
    pub fn set_distribution(&mut self, group: &str, d: DistributionSpec) {
        let errors = self
            .case
            .entry("length_errors")
            .or_insert_with(|| Value::Object(Map::new()));
        if let Value::Object(m) = errors {
            m.insert(
                group.to_string(),
                serde_json::to_value(d).expect("a distribution serialises"),
            );
        }
    }

    /// The case's effects.
    pub fn effects(&self) -> EffectsSpec {
        self.case
            .get("effects")
            .and_then(|v| serde_json::from_value(v.clone()).ok())
            .unwrap_or_default()
    }

    /// Sets the case's effects.
    pub fn set_effects(&mut self, e: &EffectsSpec) {
        if e.is_empty() {
            self.case.remove("effects");
        } else {
            self.case.insert(
                "effects".into(),
                serde_json::to_value(e).expect("effects serialise"),
            );
        }
    }
}

fn absolute_model(value: &mut Value, base: &Path) {
    let fix = |s: &str| base.join(s).display().to_string();
    match value {
        Value::String(s) => *s = fix(s),
        Value::Object(m) => {
            if let Some(Value::String(s)) = m.get_mut("file") {
                *s = fix(s);
            }
        }
        _ => {}
    }
}

impl Baseline {
    /// Reads the job file and finds the case.
    pub fn read(path: &Path, case: &str) -> Result<Self, DiagnoseError> {
        let job = Job::read(path)?;
        let text = std::fs::read_to_string(path).map_err(|e| DiagnoseError::io(path, e))?;
        let mut raw: Value = serde_json::from_str(&text).map_err(|e| DiagnoseError::io(path, e))?;
        let base = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let base = base
            .canonicalize()
            .map_err(|e| DiagnoseError::io(base, e))?;
        absolute_model(&mut raw["model"], &base);
        if let Some(cases) = raw["cases"].as_array_mut() {
            for c in cases {
                if let Some(m) = c.get_mut("model") {
                    absolute_model(m, &base);
                }
            }
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
            raw,
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
        let case = self.raw["cases"][self.case_index]
            .as_object()
            .cloned()
            .unwrap_or_default();
        let model = case
            .get("model")
            .cloned()
            .unwrap_or_else(|| self.raw["model"].clone());
        CaseEdit {
            case,
            model,
            model_edited: false,
        }
    }

    /// The case object an edit stands for, its model written in when edited.
    fn case_object(&self, edit: &CaseEdit) -> Map<String, Value> {
        let mut case = edit.case.clone();
        if edit.model_edited {
            case.insert("model".into(), edit.model.clone());
        }
        case
    }

    /// A one-case job of `samples` samples of the edited case, under the baseline's seed
    /// (common random numbers) or `seed`.
    pub fn job_of(
        &self,
        edit: &CaseEdit,
        samples: u64,
        seed: Option<u64>,
    ) -> Result<Job, DiagnoseError> {
        let mut case = self.case_object(edit);
        case.insert("samples".into(), Value::from(samples));
        let job = serde_json::json!({
            "model": self.raw["model"],
            "seed": seed.unwrap_or(self.seed),
            "cases": [Value::Object(case)],
        });
        Ok(Job::from_json(&job.to_string(), Path::new("."))?)
    }

    /// The baseline job with the case replaced by the edited one (same name and sample
    /// count), as pretty JSON: the updated job mc-shard and mc-merge run like any other.
    pub fn updated_job_json(&self, edit: &CaseEdit) -> String {
        let mut raw = self.raw.clone();
        raw["cases"][self.case_index] = Value::Object(self.case_object(edit));
        let mut s = serde_json::to_string_pretty(&raw).expect("JSON serialises");
        s.push('\n');
        s
    }
}
