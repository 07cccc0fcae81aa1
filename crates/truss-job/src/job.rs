//! The job file: parsed ([`JobSpec`]), then validated into a [`Job`] whose models are built,
//! whose distributions are checked against the models' groups, and whose id is computed.
//!
//! ## Format (JSON; lengths in mm)
//!
//! ```json
//! {
//!   "model": {"prism": {"stages": 5}},
//!   "seed": 20210325,
//!   "cases": [
//!     {"name": "sigma-0.0063", "samples": 50000,
//!      "length_errors": {"batten":   {"normal": {"sigma": 0.0063}},
//!                        "longeron": {"normal": {"sigma": 0.0063}}}},
//!     {"name": "uniform-30", "samples": 5000, "model": {"prism": {"stages": 30}},
//!      "length_errors": {"longeron": {"uniform": {"low": -0.2, "high": 0.2}}}}
//!   ]
//! }
//! ```
//!
//! | field | meaning |
//! |---|---|
//! | `model` | `{"prism": {...}}` (the paper's truss: `stages` and any of `side`, `height`, `batten_area`, `batten_modulus`, `longeron_area`, `longeron_modulus`, `diagonal_area`, `diagonal_modulus`, `diagonal_length` (mm, or `"exact"`), `compression_ratio`, `backlash`: `true` or `{"clearance", "tension_factor", "compression_ratio"}` for pin joints with clearance, see [`truss_core::prism::BacklashOptions`]), or a model file: `"path.json"` or `{"file": "path.json"}`, relative to the job file |
//! | `seed` | a u64; with the case name and sample index it keys every random draw |
//! | `cases[].name` | unique; names the case in shard files and reports |
//! | `cases[].samples` | ≥ 1 |
//! | `cases[].model` | optional: this case's own model, same forms as `model` |
//! | `cases[].length_errors` | per member group, a distribution of the length error (natural length minus nominal, mm): `{"normal": {"sigma": s}}` (optional `"mean"`), `{"uniform": {"low": a, "high": b}}`, `{"constant": {"value": v}}`. Groups not named get none. |
//! | `cases[].backlash` | optional: `{"clearance": distribution}`, each joint's clearance (mm, ≥ 0), drawn per joint and sample; needs a model with joints (`{"prism": {"stages": 5, "backlash": true}}`) |
//! | `cases[].effects` | optional deterministic effects: `gravity` (self-weight) and `thermal_gradient` (a linear temperature field); see [`crate::effects`] |
//!
//! Unknown fields are refused. Every fault is reported with its JSON path
//! (`cases[2].length_errors.longron: the model has no group "longron" …`).
//!
//! ## Job id
//!
//! The SHA-256 (hex) of the job's canonical form: the seed, and per case its name, sample
//! count, distributions, and the *content* of its model as validated (every member written
//! out, so a model file's path, whitespace and key order do not matter, but any change of a
//! number does), with the versions of the job format and of the numerics. Keys are in a
//! fixed order and numbers in shortest round-trip form. Shards carry the id; merging refuses
//! to mix ids.

use crate::distribution::DistributionSpec;
use crate::effects::{Applied, EffectsSpec};
use crate::errors::JobError;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use truss_core::model_file::ModelFile;
use truss_core::prism::{BacklashOptions, PrismOptions};
use truss_core::{Model, Structure};

/// Version of the numerics: bumped whenever the solver or the sampling would give different
/// numbers for the same job, so that the job id changes and old and new shards never mix.
pub const NUMERICS_VERSION: u32 = 2;

/// A job file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    /// The default model of every case.
    pub model: serde_json::Value,
    /// The seed of all random draws.
    pub seed: u64,
    /// The cases, in order.
    pub cases: Vec<CaseSpec>,
}

/// One case as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSpec {
    /// Unique name.
    pub name: String,
    /// Number of samples.
    pub samples: u64,
    /// This case's own model, if any.
    #[serde(default)]
    pub model: Option<serde_json::Value>,
    /// Length-error distribution per member group \[mm\].
    #[serde(default)]
    pub length_errors: BTreeMap<String, DistributionSpec>,
    /// Deterministic effects: self-weight, a temperature field (see [`crate::effects`]).
    #[serde(default)]
    pub effects: EffectsSpec,
    /// Joint clearances drawn per joint and sample; needs a model with joints.
    #[serde(default)]
    pub backlash: Option<CaseBacklash>,
}

/// The prism generator's options as a job writes them; absent fields take Table 1's values.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrismSpec {
    stages: usize,
    side: Option<f64>,
    height: Option<f64>,
    batten_area: Option<f64>,
    batten_modulus: Option<f64>,
    longeron_area: Option<f64>,
    longeron_modulus: Option<f64>,
    diagonal_area: Option<f64>,
    diagonal_modulus: Option<f64>,
    diagonal_length: Option<DiagonalLength>,
    compression_ratio: Option<f64>,
    backlash: Option<BacklashSpec>,
}

/// The prism's backlash joints as a job writes them: `true` for the defaults, or an object
/// overriding some of `clearance` (mm, the model's own clearance, used when a case draws
/// none), `tension_factor` (contact stiffness over a longeron's `E·A/h`) and
/// `compression_ratio` (a loose joint's regularising stiffness over its contact stiffness;
/// default 0, none).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
enum BacklashSpec {
    Enabled(bool),
    Options(BacklashFields),
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
struct BacklashFields {
    clearance: Option<f64>,
    tension_factor: Option<f64>,
    compression_ratio: Option<f64>,
}

/// A case's backlash: the distribution of each joint's clearance \[mm\], drawn per joint
/// and sample (`{"clearance": {"uniform": {"low": 0.004, "high": 0.017}}}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseBacklash {
    /// Clearance distribution \[mm\]; its support must not go below zero.
    pub clearance: DistributionSpec,
}

/// A diagonal natural length: a number of mm, or `"exact"`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
enum DiagonalLength {
    Value(f64),
    Word(Exact),
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Exact {
    Exact,
}

impl PrismSpec {
    fn options(&self) -> PrismOptions {
        let d = PrismOptions::with_stages(self.stages);
        PrismOptions {
            stages: self.stages,
            side: self.side.unwrap_or(d.side),
            height: self.height.unwrap_or(d.height),
            batten_area: self.batten_area.unwrap_or(d.batten_area),
            batten_modulus: self.batten_modulus.unwrap_or(d.batten_modulus),
            longeron_area: self.longeron_area.unwrap_or(d.longeron_area),
            longeron_modulus: self.longeron_modulus.unwrap_or(d.longeron_modulus),
            diagonal_area: self.diagonal_area.unwrap_or(d.diagonal_area),
            diagonal_modulus: self.diagonal_modulus.unwrap_or(d.diagonal_modulus),
            diagonal_length: match self.diagonal_length {
                None => d.diagonal_length,
                Some(DiagonalLength::Value(v)) => Some(v),
                Some(DiagonalLength::Word(Exact::Exact)) => None,
            },
            compression_ratio: self.compression_ratio.unwrap_or(d.compression_ratio),
            backlash: match self.backlash {
                None | Some(BacklashSpec::Enabled(false)) => None,
                Some(BacklashSpec::Enabled(true)) => Some(BacklashOptions::default()),
                Some(BacklashSpec::Options(f)) => {
                    let b = BacklashOptions::default();
                    Some(BacklashOptions {
                        clearance: f.clearance.unwrap_or(b.clearance),
                        tension_factor: f.tension_factor.unwrap_or(b.tension_factor),
                        compression_ratio: f.compression_ratio.unwrap_or(b.compression_ratio),
                    })
                }
            },
        }
    }
}

/// A validated case.
#[derive(Debug, Clone)]
pub struct Case {
    /// Unique name.
    pub name: String,
    /// Number of samples.
    pub samples: u64,
    /// Global index of its first sample.
    pub start: u64,
    /// Its model.
    pub model: Arc<Model>,
    /// Its model compiled for solving.
    pub structure: Arc<Structure>,
    /// The distributions by group name.
    pub length_errors: BTreeMap<String, DistributionSpec>,
    /// The distribution of each member's length error, in model order.
    pub member_errors: Vec<Option<DistributionSpec>>,
    /// Named numbers describing the case, for sweeps (`sigma`, `stages`, …).
    pub parameters: BTreeMap<String, f64>,
    /// The effects as given.
    pub effects: EffectsSpec,
    /// What the effects do: extra loads per node, extra length errors per member.
    pub applied: Applied,
    /// Joint clearances drawn per joint and sample, if the case draws them.
    pub backlash: Option<CaseBacklash>,
}

/// A validated job (see the module doc).
#[derive(Debug, Clone)]
pub struct Job {
    /// The seed.
    pub seed: u64,
    /// The cases, in order.
    pub cases: Vec<Case>,
    /// SHA-256 (hex) of the canonical form.
    pub id: String,
    /// Where the job file is, if it came from one.
    pub path: Option<PathBuf>,
}

impl Job {
    /// Reads and validates a job file.
    pub fn read(path: &Path) -> Result<Self, JobError> {
        let text = std::fs::read_to_string(path).map_err(|e| JobError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let base = path.parent().unwrap_or(Path::new("."));
        let mut job = Self::from_json(&text, base).map_err(|e| e.in_file(path))?;
        job.path = Some(path.to_path_buf());
        Ok(job)
    }

    /// Parses and validates a job's text; model file paths are relative to `base`.
    pub fn from_json(text: &str, base: &Path) -> Result<Self, JobError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: JobSpec = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            JobError::Invalid {
                path: if path == "." { String::new() } else { path },
                message: format!("{inner}"),
            }
        })?;
        Self::new(&spec, base)
    }

    /// Validates a parsed job.
    pub fn new(spec: &JobSpec, base: &Path) -> Result<Self, JobError> {
        if spec.cases.is_empty() {
            return Err(JobError::at("cases", "a job needs at least one case"));
        }
        let default_model = resolve_model(&spec.model, "model", base)?;
        let mut cases: Vec<Case> = Vec::with_capacity(spec.cases.len());
        let mut start = 0u64;
        for (i, c) in spec.cases.iter().enumerate() {
            let at = |field: &str| format!("cases[{i}].{field}");
            if c.name.is_empty() {
                return Err(JobError::at(&at("name"), "must not be empty"));
            }
            if let Some(j) = cases.iter().position(|o| o.name == c.name) {
                return Err(JobError::at(
                    &at("name"),
                    &format!("{:?} is also the name of cases[{j}]", c.name),
                ));
            }
            if c.samples == 0 {
                return Err(JobError::at(&at("samples"), "must be at least 1"));
            }
            let (model, structure, stages) = match &c.model {
                Some(m) => resolve_model(m, &at("model"), base)?,
                None => default_model.clone(),
            };
            let groups = model.groups();
            for (group, dist) in &c.length_errors {
                let path = at(&format!("length_errors.{group}"));
                if !groups.contains(&group.as_str()) {
                    return Err(JobError::at(
                        &path,
                        &format!(
                            "the model has no group {group:?} (its groups: {})",
                            groups.join(", ")
                        ),
                    ));
                }
                dist.check().map_err(|m| JobError::at(&path, &m))?;
            }
            c.effects
                .check()
                .map_err(|(field, m)| JobError::at(&at(&format!("effects.{field}")), &m))?;
            if let Some(b) = &c.backlash {
                let path = at("backlash.clearance");
                if model.joints().is_empty() {
                    return Err(JobError::at(
                        &at("backlash"),
                        "the model has no joints to give clearances to \
                         (use {\"prism\": {\"stages\": N, \"backlash\": true}} or a model file with joints)",
                    ));
                }
                b.clearance.check().map_err(|m| JobError::at(&path, &m))?;
                if b.clearance.lowest() < 0.0 {
                    return Err(JobError::at(
                        &path,
                        "a clearance cannot be negative: give a distribution whose values are \
                         all ≥ 0 (uniform with low ≥ 0, or a constant)",
                    ));
                }
            }
            let applied = c.effects.apply(&model);
            let member_errors = model
                .members()
                .iter()
                .map(|m| c.length_errors.get(&m.group).copied())
                .collect();
            let mut parameters = BTreeMap::new();
            let sigma = c
                .length_errors
                .values()
                .map(DistributionSpec::std_dev)
                .fold(0.0, f64::max);
            parameters.insert("sigma".to_string(), sigma);
            if let Some(n) = stages {
                parameters.insert("stages".to_string(), n as f64);
            }
            if c.length_errors
                .values()
                .any(|d| matches!(d, DistributionSpec::Uniform { .. }))
            {
                parameters.insert("uniform".to_string(), 1.0);
            }
            if let Some(j) = model.joints().first() {
                // Cases differing in the joints' regularisation form their own series.
                parameters.insert("backlash".to_string(), 1.0);
                parameters.insert("joint_compression_ratio".to_string(), j.compression_ratio);
            }
            cases.push(Case {
                name: c.name.clone(),
                samples: c.samples,
                start,
                model,
                structure,
                length_errors: c.length_errors.clone(),
                member_errors,
                parameters,
                effects: c.effects.clone(),
                applied,
                backlash: c.backlash,
            });
            start = start.checked_add(c.samples).ok_or_else(|| {
                JobError::at(&at("samples"), "the job has more than 2^64 samples")
            })?;
        }
        let id = job_id(spec.seed, &cases);
        Ok(Self {
            seed: spec.seed,
            cases,
            id,
            path: None,
        })
    }

    /// Total number of samples over all cases.
    pub fn samples(&self) -> u64 {
        self.cases.iter().map(|c| c.samples).sum()
    }

    /// The case of global index `index`, with the index within the case.
    pub fn case_of(&self, index: u64) -> Option<(usize, u64)> {
        let pos = self.cases.partition_point(|c| c.start + c.samples <= index);
        self.cases
            .get(pos)
            .filter(|c| index >= c.start && index < c.start + c.samples)
            .map(|c| (pos, index - c.start))
    }

    /// The case named `name`.
    pub fn case_named(&self, name: &str) -> Option<usize> {
        self.cases.iter().position(|c| c.name == name)
    }
}

/// A model and its compiled structure, with the prism's stage count if it is one.
type Resolved = (Arc<Model>, Arc<Structure>, Option<usize>);

/// Builds the model a job names at JSON path `path`.
fn resolve_model(value: &serde_json::Value, path: &str, base: &Path) -> Result<Resolved, JobError> {
    let bad = || {
        JobError::at(
            path,
            "expected {\"prism\": {...}}, a model file path, or {\"file\": \"path\"}",
        )
    };
    let (model, stages) = match value {
        serde_json::Value::String(file) => (read_model(file, path, base)?, None),
        serde_json::Value::Object(map) if map.len() == 1 => {
            let (key, inner) = map.iter().next().expect("one entry");
            match key.as_str() {
                "file" => {
                    let file = inner
                        .as_str()
                        .ok_or_else(|| JobError::at(&format!("{path}.file"), "expected a path"))?;
                    (read_model(file, &format!("{path}.file"), base)?, None)
                }
                "prism" => {
                    let at = format!("{path}.prism");
                    let spec: PrismSpec = serde_path_to_error::deserialize(inner).map_err(|e| {
                        let sub = e.path().to_string();
                        JobError::at(
                            &if sub == "." {
                                at.clone()
                            } else {
                                format!("{at}.{sub}")
                            },
                            &e.into_inner().to_string(),
                        )
                    })?;
                    let options = spec.options();
                    let model = options
                        .model()
                        .map_err(|e| JobError::at(&at, &e.to_string()))?;
                    (model, Some(spec.stages))
                }
                _ => return Err(bad()),
            }
        }
        _ => return Err(bad()),
    };
    let structure = Structure::new(&model).map_err(|e| JobError::at(path, &e.to_string()))?;
    Ok((Arc::new(model), Arc::new(structure), stages))
}

fn read_model(file: &str, path: &str, base: &Path) -> Result<Model, JobError> {
    let full = base.join(file);
    let text = std::fs::read_to_string(&full).map_err(|e| {
        JobError::at(
            path,
            &format!("cannot read model file {}: {e}", full.display()),
        )
    })?;
    Model::from_json(&text, &full.display().to_string())
        .map_err(|e| JobError::at(path, &e.to_string()))
}

/// The canonical form of a job, serialised for hashing (see the module doc).
#[derive(Serialize)]
struct Canonical<'a> {
    format: &'static str,
    format_version: u32,
    numerics_version: u32,
    seed: u64,
    cases: Vec<CanonicalCase<'a>>,
}

#[derive(Serialize)]
struct CanonicalCase<'a> {
    name: &'a str,
    samples: u64,
    length_errors: &'a BTreeMap<String, DistributionSpec>,
    effects: &'a EffectsSpec,
    #[serde(skip_serializing_if = "Option::is_none")]
    backlash: Option<CaseBacklash>,
    model: ModelFile,
}

/// The job id: SHA-256 of the canonical form.
fn job_id(seed: u64, cases: &[Case]) -> String {
    let canonical = Canonical {
        format: "truss-mc-job",
        format_version: 1,
        numerics_version: NUMERICS_VERSION,
        seed,
        cases: cases
            .iter()
            .map(|c| CanonicalCase {
                name: &c.name,
                samples: c.samples,
                length_errors: &c.length_errors,
                effects: &c.effects,
                backlash: c.backlash,
                model: c.model.to_file(),
            })
            .collect(),
    };
    let text = serde_json::to_string(&canonical).expect("the canonical form always serialises");
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
