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
//! | `cases[].name` | unique, at most [`MAX_CASE_NAME_BYTES`] bytes, no control characters; names the case in shard files, reports and plot file names |
//! | `cases[].samples` | ≥ 1 |
//! | `cases[].model` | optional: this case's own model, same forms as `model` |
//! | `cases[].length_errors` | per member group, a distribution of the length error (natural length minus nominal, mm): `{"normal": {"sigma": s}}` (optional `"mean"`), `{"uniform": {"low": a, "high": b}}`, `{"constant": {"value": v}}`, `{"truncated_normal": {"sigma": s, "limit": t}}` (optional `"mean"`: a normal whose parts beyond mean ± t are scrapped at inspection; see [`crate::distribution::TruncatedNormal`]). Groups not named get none. |
//! | `cases[].length_errors.G.lot` | optional, inside a group's distribution: a part of the error shared by each production lot of the group, `{"by": "level" | [["id", …], …], <distribution>}`, drawn once per lot and sample and added to each member's own draw; see [`crate::lot`] |
//! | `cases[].backlash` | optional: `{"clearance": distribution}`, each joint's clearance (mm, ≥ 0), drawn per joint and sample; needs a model with joints (`{"prism": {"stages": 5, "backlash": true}}`) |
//! | `cases[].effects` | optional deterministic effects: `gravity` (self-weight) and `thermal_gradient` (a linear temperature field); see [`crate::effects`] |
//! | `budget` | optional: the alignment budget every case is held to, `{"theta_p": {"arcsec": 20}, "decenter": {"mm": 0.05}, "despace": {"mm": 0.03}, "percentile": 95}` (any one or more lines); see [`crate::budget`] |
//!
//! Unknown fields are refused. Every fault is reported with its JSON path
//! (`cases[2].length_errors.longron: the model has no group "longron" …`).
//!
//! ## Limits
//!
//! A job is refused, naming the field, before any model is built or any sample drawn, when:
//! the file is not a regular file, is larger than
//! [`MAX_INPUT_BYTES`](truss_core::model_file::MAX_INPUT_BYTES) or is not UTF-8 (a leading
//! UTF-8 byte-order mark is accepted); a prism has more than
//! [`MAX_STAGES`](truss_core::prism::MAX_STAGES) stages or an implausible option (see
//! [`PrismOptions::check`]); a case has more than [`MAX_CASE_SAMPLES`] samples, or the job
//! more than [`MAX_JOB_SAMPLES`]; a length error can reach beyond
//! [`MAX_LENGTH_ERROR_FRACTION`](truss_core::MAX_LENGTH_ERROR_FRACTION) of a member's
//! natural length (a normal's `|mean| + 6σ`, see
//! [`NORMAL_REACH`](crate::distribution::NORMAL_REACH); a uniform's bounds; a constant; a
//! truncated normal's `|mean| + limit`),
//! alone or with a thermal effect's `α·ΔT·L`; a clearance can exceed
//! [`MAX_CLEARANCE_FRACTION`](truss_core::model::MAX_CLEARANCE_FRACTION) of a jointed
//! member's length; an effect's value is implausible (see [`crate::effects`]); a group is
//! named twice, or given two distributions; a case name is longer than
//! [`MAX_CASE_NAME_BYTES`] or holds a control character ([`check_case_name`]). A model file
//! the job names that cannot be read (missing, no permission) is an I/O failure
//! ([`JobError::ModelIo`]), as the job file's own is; one that is not a model is invalid.
//!
//! ## Job id
//!
//! The SHA-256 (hex) of the job's canonical form: the seed, and per case its name, sample
//! count, distributions, and the *content* of its model as validated (every member written
//! out, so a model file's path, whitespace and key order do not matter, but any change of a
//! number does), the budget in rad and mm when there is one, with the versions of the job
//! format and of the numerics. Keys are in a
//! fixed order and numbers in shortest round-trip form. Shards carry the id; merging refuses
//! to mix ids.

use crate::budget::{Budget, BudgetSpec};
use crate::distribution::DistributionSpec;
use crate::effects::{Applied, EffectsSpec};
use crate::errors::JobError;
use crate::lot::{self, CaseLot, LengthErrors};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use truss_core::model_file::ModelFile;
use truss_core::prism::PrismOptions;
use truss_core::{Model, Structure};

/// Version of the numerics: bumped whenever the solver or the sampling would give different
/// numbers for the same job, so that the job id changes and old and new shards never mix.
pub const NUMERICS_VERSION: u32 = 14;

/// The most samples a case may have, 10⁸. At 10⁸ samples the 95th percentile's relative
/// standard error is about 10⁻⁴, far finer than any input of the model is known; and the
/// merge keeps each case's θ_P values in memory (8 bytes each: 800 MB at the limit).
pub const MAX_CASE_SAMPLES: u64 = 100_000_000;

/// The most samples a job may have over all its cases, 10⁹ (about 14 CPU-hours of the
/// paper's 5-stage truss at some 50 µs a sample).
pub const MAX_JOB_SAMPLES: u64 = 1_000_000_000;

/// A job file as written: read with [`JobSpec::from_json`], written with
/// [`JobSpec::to_json`], validated into a [`Job`] by [`Job::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "M: Deserialize<'de>, B: Deserialize<'de>")
)]
pub struct JobSpec<M = ModelSpec, B = BudgetSpec> {
    /// The default model of every case.
    pub model: M,
    /// The seed of all random draws.
    pub seed: u64,
    /// The cases, in order.
    pub cases: Vec<CaseSpec<M>>,
    /// The alignment budget every case is held to, if the job states one (see
    /// [`crate::budget`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget: Option<B>,
}

/// One case as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, bound(deserialize = "M: Deserialize<'de>"))]
pub struct CaseSpec<M = ModelSpec> {
    /// Unique name.
    pub name: String,
    /// Number of samples.
    pub samples: u64,
    /// This case's own model, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<M>,
    /// Length-error distribution per member group \[mm\], with its shared lot part where
    /// it has one (see [`crate::lot`]).
    #[serde(default, skip_serializing_if = "LengthErrors::is_empty")]
    pub length_errors: LengthErrors,
    /// Deterministic effects: self-weight, a temperature field (see [`crate::effects`]).
    #[serde(default, skip_serializing_if = "EffectsSpec::is_empty")]
    pub effects: EffectsSpec,
    /// Joint clearances drawn per joint and sample; needs a model with joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub backlash: Option<CaseBacklash>,
}

/// A model as a job writes it: `{"prism": {...}}` (the paper's prism, any Table 1 value
/// overridden: see [`truss_core::prism_spec`]), or a model file, `"path.json"` or
/// `{"file": "path.json"}`, relative to the job file.
#[derive(Debug, Clone, PartialEq)]
pub enum ModelSpec {
    /// The paper's prism with these options.
    Prism(PrismOptions),
    /// A model file.
    File(PathBuf),
}

impl Serialize for ModelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(1))?;
        match self {
            ModelSpec::Prism(o) => m.serialize_entry("prism", o)?,
            ModelSpec::File(p) => m.serialize_entry("file", p)?,
        }
        m.end()
    }
}

impl ModelSpec {
    /// Parses a model as written, naming faults by their JSON path under `path`.
    pub fn parse(value: &serde_json::Value, path: &str) -> Result<Self, JobError> {
        let bad = || {
            JobError::at(
                path,
                "expected {\"prism\": {...}}, a model file path, or {\"file\": \"path\"}",
            )
        };
        match value {
            serde_json::Value::String(file) => Ok(ModelSpec::File(PathBuf::from(file))),
            serde_json::Value::Object(map) if map.len() == 1 => {
                let (key, inner) = map.iter().next().expect("one entry");
                match key.as_str() {
                    "file" => inner
                        .as_str()
                        .map(|f| ModelSpec::File(PathBuf::from(f)))
                        .ok_or_else(|| JobError::at(&format!("{path}.file"), "expected a path")),
                    "prism" => Ok(ModelSpec::Prism(parse_prism(
                        inner,
                        &format!("{path}.prism"),
                    )?)),
                    _ => Err(bad()),
                }
            }
            _ => Err(bad()),
        }
    }

    /// The model file paths made absolute against `base` (for a job written elsewhere).
    pub fn absolute(self, base: &Path) -> Self {
        match self {
            ModelSpec::File(p) if p.is_relative() => ModelSpec::File(base.join(p)),
            other => other,
        }
    }
}

/// Parses a prism's options as a job writes them (`{"stages": 5, …}`, see
/// [`truss_core::prism_spec`]) and checks them, naming faults by their JSON path under `at`.
pub fn parse_prism(value: &serde_json::Value, at: &str) -> Result<PrismOptions, JobError> {
    let options: PrismOptions = serde_path_to_error::deserialize(value).map_err(|e| {
        let sub = e.path().to_string();
        JobError::at(
            &if sub == "." {
                at.to_string()
            } else {
                format!("{at}.{sub}")
            },
            &e.into_inner().to_string(),
        )
    })?;
    options
        .check()
        .map_err(|(field, m)| JobError::at(&format!("{at}.{field}"), &m))?;
    Ok(options)
}

impl JobSpec {
    /// Reads a job file (a regular file of at most
    /// [`MAX_INPUT_BYTES`](truss_core::model_file::MAX_INPUT_BYTES) in UTF-8: a FIFO or a
    /// device is refused before it is opened) and parses it, naming the file in any fault.
    pub fn read(path: &Path) -> Result<Self, JobError> {
        use truss_core::model_file::{ReadFailure, read_input};
        let text = read_input(path).map_err(|e| match e {
            ReadFailure::Io(source) => JobError::Io {
                path: path.to_path_buf(),
                source,
            },
            ReadFailure::Refused(reason) => JobError::Refused {
                path: path.to_path_buf(),
                reason,
            },
        })?;
        Self::from_json(&text).map_err(|e| e.in_file(path))
    }

    /// Parses a job's text, naming faults by their JSON path.
    /// A leading UTF-8 byte-order mark is accepted and dropped.
    pub fn from_json(text: &str) -> Result<Self, JobError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let de = &mut serde_json::Deserializer::from_str(text);
        let raw: JobSpec<serde_json::Value, serde_json::Value> =
            serde_path_to_error::deserialize(de).map_err(|e| {
                let path = e.path().to_string();
                let inner = e.into_inner();
                JobError::Invalid {
                    path: if path == "." { String::new() } else { path },
                    message: format!("{inner}"),
                }
            })?;
        let cases = raw
            .cases
            .into_iter()
            .enumerate()
            .map(|(i, c)| {
                let model = c
                    .model
                    .map(|m| ModelSpec::parse(&m, &format!("cases[{i}].model")))
                    .transpose()?;
                Ok(CaseSpec {
                    name: c.name,
                    samples: c.samples,
                    model,
                    length_errors: c.length_errors,
                    effects: c.effects,
                    backlash: c.backlash,
                })
            })
            .collect::<Result<_, JobError>>()?;
        Ok(JobSpec {
            model: ModelSpec::parse(&raw.model, "model")?,
            seed: raw.seed,
            cases,
            budget: raw
                .budget
                .map(|b| BudgetSpec::parse(&b, "budget"))
                .transpose()?,
        })
    }

    /// The job as pretty JSON (a trailing newline included), as `from_json` reads it.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("a job spec always serialises");
        s.push('\n');
        s
    }
}

/// A case's backlash: the distribution of each joint's clearance \[mm\], drawn per joint
/// and sample (`{"clearance": {"uniform": {"low": 0.004, "high": 0.017}}}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseBacklash {
    /// Clearance distribution \[mm\]; its support must not go below zero.
    pub clearance: DistributionSpec,
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
    /// The distributions by group name, with their lots.
    pub length_errors: LengthErrors,
    /// The distribution of each member's own length error, in model order.
    pub member_errors: Vec<Option<DistributionSpec>>,
    /// The groups' lots, in group order (see [`crate::lot`]).
    pub lots: Vec<CaseLot>,
    /// Each member's lot, numbered over all of `lots`' lots in order; `None` for a member
    /// whose group has no lot part.
    pub member_lot: Vec<Option<usize>>,
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
    /// The alignment budget in canonical units (rad, mm), if the job states one.
    pub budget: Option<Budget>,
    /// SHA-256 (hex) of the canonical form.
    pub id: String,
    /// Where the job file is, if it came from one.
    pub path: Option<PathBuf>,
}

impl Job {
    /// Reads and validates a job file.
    pub fn read(path: &Path) -> Result<Self, JobError> {
        let spec = JobSpec::read(path)?;
        let base = path.parent().unwrap_or(Path::new("."));
        let mut job = Self::new(&spec, base).map_err(|e| e.in_file(path))?;
        job.path = Some(path.to_path_buf());
        Ok(job)
    }

    /// Parses and validates a job's text; model file paths are relative to `base`.
    pub fn from_json(text: &str, base: &Path) -> Result<Self, JobError> {
        Self::new(&JobSpec::from_json(text)?, base)
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
            check_case_name(&c.name).map_err(|m| JobError::at(&at("name"), &m))?;
            if let Some(j) = cases.iter().position(|o| o.name == c.name) {
                return Err(JobError::at(
                    &at("name"),
                    &format!("{:?} is also the name of cases[{j}]", c.name),
                ));
            }
            if c.samples == 0 {
                return Err(JobError::at(&at("samples"), "must be at least 1"));
            }
            if c.samples > MAX_CASE_SAMPLES {
                return Err(JobError::at(
                    &at("samples"),
                    &format!(
                        "must be at most {MAX_CASE_SAMPLES} (10⁸) per case, got {}",
                        c.samples
                    ),
                ));
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
            let mut lots = Vec::new();
            for (group, l) in &c.length_errors.lots {
                let path = at(&format!("length_errors.{group}.lot"));
                l.distribution
                    .check()
                    .map_err(|m| JobError::at(&path, &m))?;
                let key = lot::lot_key(spec.seed, &c.name, group);
                lots.push(lot::resolve(l, group, &model, stages, key, &path)?);
            }
            let mut member_lot = vec![None; model.members().len()];
            for (n, members) in lots.iter().flat_map(|l| &l.lots).enumerate() {
                for &m in members {
                    member_lot[m] = Some(n);
                }
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
                        &format!(
                            "a clearance cannot be negative: give a distribution whose values \
                             are all ≥ 0 (this one reaches down to {} mm)",
                            truss_core::readable(b.clearance.lowest())
                        ),
                    ));
                }
            }
            let applied = c.effects.apply(&model);
            check_reach(&model, &c.length_errors, &applied, &at)?;
            if let Some(b) = &c.backlash {
                check_clearance(&model, &b.clearance, &at("backlash.clearance"))?;
            }
            let member_errors = model
                .members()
                .iter()
                .map(|m| c.length_errors.get(&m.group).copied())
                .collect();
            let mut parameters = BTreeMap::new();
            let sigma = c
                .length_errors
                .keys()
                .map(|g| c.length_errors.total_std_dev(g))
                .fold(0.0, f64::max);
            parameters.insert("sigma".to_string(), sigma);
            // Cases whose groups share a lot part form their own series, by the largest
            // share of a member's variance a lot holds; absent without lots.
            if !lots.is_empty() {
                let share = lots
                    .iter()
                    .map(|l| l.variance_share(&c.length_errors[&l.group]))
                    .fold(0.0, f64::max);
                parameters.insert("lot_share".to_string(), share);
            }
            if let Some(n) = stages {
                parameters.insert("stages".to_string(), n as f64);
            }
            // A distribution's own mark (the uniform's, the truncated normal's shape), the
            // largest of its groups' values: cases differing in it form their own series.
            let lot_distributions = c.length_errors.lots.values().map(|l| &l.distribution);
            for (key, value) in c
                .length_errors
                .values()
                .chain(lot_distributions)
                .filter_map(|d| d.series_marker())
            {
                let kept = parameters.entry(key.to_string()).or_insert(value);
                *kept = kept.max(value);
            }
            // Cases whose cables have another compression ratio than the default (the first
            // cable's: a prism gives all its diagonals one) form their own series too; absent
            // at the default, so the records of earlier jobs stay as they were.
            let cable_ratio = model.members().iter().find_map(|m| match m.behaviour {
                truss_core::Behaviour::Cable { compression_ratio } => Some(compression_ratio),
                truss_core::Behaviour::Bar => None,
            });
            if let Some(r) = cable_ratio.filter(|&r| r != truss_core::DEFAULT_COMPRESSION_RATIO) {
                parameters.insert("cable_compression_ratio".to_string(), r);
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
                lots,
                member_lot,
                parameters,
                effects: c.effects.clone(),
                applied,
                backlash: c.backlash,
            });
            start += c.samples;
            if start > MAX_JOB_SAMPLES {
                return Err(JobError::at(
                    &at("samples"),
                    &format!(
                        "the job's cases have {start} samples up to here, more than the \
                         {MAX_JOB_SAMPLES} (10⁹) a job may have"
                    ),
                ));
            }
        }
        let budget = spec.budget.as_ref().map(BudgetSpec::budget);
        let id = job_id(spec.seed, &cases, budget.as_ref());
        Ok(Self {
            seed: spec.seed,
            cases,
            budget,
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

/// The longest case name \[bytes\]. A case's name becomes part of file names (the merge's
/// plots, `exceedance-NAME.png`, with `~K` appended where the name is not plain, see
/// mc-merge's `file_stems`), and file systems take at most 255 bytes a name.
pub const MAX_CASE_NAME_BYTES: usize = 200;

/// Checks a case name: not empty, at most [`MAX_CASE_NAME_BYTES`], and no control characters
/// (a terminal escape sequence printed by `plan`, a NUL or a line break in a file name or
/// the merge's SVG, which XML does not allow) nor the XML non-characters U+FFFE and U+FFFF.
/// The message shows the name escaped and shortened, never its raw characters. (Plot file
/// names stay unique however names are sanitised: mc-merge appends a name's position to any
/// name that is not plain.)
pub fn check_case_name(name: &str) -> Result<(), String> {
    let shown = || {
        let head: String = name.chars().take(40).collect();
        if head.len() < name.len() {
            format!("{head:?}… ({} bytes)", name.len())
        } else {
            format!("{head:?}")
        }
    };
    if name.is_empty() {
        return Err("must not be empty".into());
    }
    if name.len() > MAX_CASE_NAME_BYTES {
        return Err(format!(
            "{} is longer than {MAX_CASE_NAME_BYTES} bytes: case names become part of the merge's file names",
            shown()
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|c| c.is_control() || matches!(c, '\u{fffe}' | '\u{ffff}'))
    {
        return Err(format!(
            "{} holds the control character {c:?}: case names are printed and become file names and SVG text; use letters, digits and punctuation",
            shown()
        ));
    }
    Ok(())
}

/// Refuses length errors that can reach beyond
/// [`MAX_LENGTH_ERROR_FRACTION`](truss_core::MAX_LENGTH_ERROR_FRACTION) of a member's
/// natural length ([`Model::max_length_error`]): a group's distribution alone (its
/// [`DistributionSpec::reach`]), a thermal effect alone, or both together. `at` makes a
/// field's JSON path.
fn check_reach(
    model: &Model,
    length_errors: &LengthErrors,
    applied: &Applied,
    at: &dyn Fn(&str) -> String,
) -> Result<(), JobError> {
    let percent = 100.0 * truss_core::MAX_LENGTH_ERROR_FRACTION;
    for (m, member) in model.members().iter().enumerate() {
        let max = model.max_length_error(m);
        let thermal = applied.length_changes.get(m).map_or(0.0, |x| x.abs());
        let dist = length_errors.get(&member.group);
        let lot = length_errors
            .lots
            .get(&member.group)
            .map(|l| &l.distribution);
        let reach = dist.map_or(0.0, DistributionSpec::reach) + lot.map_or(0.0, |l| l.reach());
        let what = dist.map_or_else(String::new, DistributionSpec::reach_in_words)
            + &lot.map_or_else(String::new, |l| {
                format!(", plus its lot part's {}", l.reach_in_words())
            });
        let limit = format!(
            "more than {percent}% of member {:?}'s natural length {} mm ({max} mm): a \
             length error beyond the elastic range, where the model means nothing (see \
             truss_core::MAX_LENGTH_ERROR_FRACTION)",
            member.id, member.natural_length
        );
        if reach > max {
            return Err(JobError::at(
                &at(&format!("length_errors.{}", member.group)),
                &format!("{what} is {limit}"),
            ));
        }
        if thermal > max {
            return Err(JobError::at(
                &at("effects.thermal_gradient"),
                &format!(
                    "a thermal length change of {} mm is {limit}",
                    truss_core::readable(thermal)
                ),
            ));
        }
        if reach + thermal > max {
            return Err(JobError::at(
                &at("effects.thermal_gradient"),
                &format!(
                    "a thermal length change of {} mm with length_errors.{}'s {what} is {limit}",
                    truss_core::readable(thermal),
                    member.group
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a clearance distribution that can exceed
/// [`MAX_CLEARANCE_FRACTION`](truss_core::model::MAX_CLEARANCE_FRACTION) of the length of
/// a member held by a joint.
fn check_clearance(
    model: &Model,
    clearance: &DistributionSpec,
    path: &str,
) -> Result<(), JobError> {
    let fraction = truss_core::model::MAX_CLEARANCE_FRACTION;
    let shortest = model
        .joints()
        .iter()
        .flat_map(|j| {
            model
                .members()
                .iter()
                .filter(move |m| m.nodes.contains(&j.hole))
        })
        .map(|m| m.natural_length)
        .fold(f64::INFINITY, f64::min);
    let max = fraction * shortest;
    let highest = clearance.highest();
    if highest <= max {
        Ok(())
    } else {
        Err(JobError::at(
            path,
            &format!(
                "a clearance can reach {} mm, more than {}% of the shortest jointed \
                 member's length {shortest} mm ({max} mm): free play that large is not a pin \
                 joint (see truss_core::model::MAX_CLEARANCE_FRACTION)",
                truss_core::readable(highest),
                100.0 * fraction
            ),
        ))
    }
}

/// A model and its compiled structure, with the prism's stage count if it is one.
type Resolved = (Arc<Model>, Arc<Structure>, Option<usize>);

/// Builds the model a job names at JSON path `path`.
fn resolve_model(spec: &ModelSpec, path: &str, base: &Path) -> Result<Resolved, JobError> {
    let (model, stages) = match spec {
        ModelSpec::File(file) => (read_model(file, path, base)?, None),
        ModelSpec::Prism(options) => {
            let at = format!("{path}.prism");
            let model = options
                .model()
                .map_err(|e| JobError::at(&at, &e.to_string()))?;
            (model, Some(options.stages))
        }
    };
    let structure = Structure::new(&model).map_err(|e| JobError::at(path, &e.to_string()))?;
    Ok((Arc::new(model), Arc::new(structure), stages))
}

fn read_model(file: &Path, path: &str, base: &Path) -> Result<Model, JobError> {
    let full = base.join(file);
    let text = truss_core::model_file::read_input(&full).map_err(|e| match e {
        truss_core::model_file::ReadFailure::Io(source) => JobError::ModelIo {
            at: path.to_string(),
            path: full.clone(),
            source,
        },
        truss_core::model_file::ReadFailure::Refused(r) => JobError::at(
            path,
            &format!("cannot read model file {}: {r}", full.display()),
        ),
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
    #[serde(skip_serializing_if = "Option::is_none")]
    budget: Option<&'a Budget>,
}

#[derive(Serialize)]
struct CanonicalCase<'a> {
    name: &'a str,
    samples: u64,
    length_errors: &'a LengthErrors,
    effects: &'a EffectsSpec,
    #[serde(skip_serializing_if = "Option::is_none")]
    backlash: Option<CaseBacklash>,
    model: ModelFile,
}

/// The job id: SHA-256 of the canonical form.
fn job_id(seed: u64, cases: &[Case], budget: Option<&Budget>) -> String {
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
        budget,
    };
    let text = serde_json::to_string(&canonical).expect("the canonical form always serialises");
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The message of the job `text` refused.
    fn refusal(text: &str) -> String {
        Job::from_json(text, Path::new("."))
            .map(|_| ())
            .unwrap_err()
            .to_string()
    }

    /// A job of one case of the 1-stage prism, `case` spliced into the case.
    fn job(case: &str) -> String {
        format!(
            r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 1,
                "cases": [{{"name": "a", "samples": 10{case}}}]}}"#
        )
    }

    /// A stage count of 2⁶⁴ − 1 or 100,000 is refused from the spec, by its JSON path,
    /// before any model is built (it used to fill the memory).
    #[test]
    fn stage_counts_are_refused_by_path() {
        let m = refusal(
            r#"{"model": {"prism": {"stages": 18446744073709551615}}, "seed": 1,
                "cases": [{"name": "a", "samples": 1}]}"#,
        );
        assert!(
            m.starts_with("model.prism.stages: must be from 1 to 1000"),
            "{m}"
        );
        let m = refusal(&job(r#", "model": {"prism": {"stages": 100000}}"#));
        assert!(m.starts_with("cases[0].model.prism.stages: "), "{m}");
        let m = refusal(&job(r#", "model": {"prism": {"side": 1e308}}"#));
        assert!(m.starts_with("cases[0].model.prism.side: "), "{m}");
    }

    /// σ, means, bounds and constants that reach beyond 1 % of a member's length (3.8 mm of
    /// 380 mm; a normal's |mean| + 6σ) are refused by their group; those within are not.
    #[test]
    fn length_errors_beyond_the_elastic_range_are_refused() {
        let group = |dist: &str| job(&format!(r#", "length_errors": {{"longeron": {dist}}}"#));
        for dist in [
            r#"{"normal": {"sigma": 50}}"#,
            r#"{"normal": {"sigma": 1e308}}"#,
            r#"{"normal": {"mean": 1e308, "sigma": 0.01}}"#,
            r#"{"normal": {"sigma": 0.64}}"#,
            r#"{"uniform": {"low": -0.2, "high": 1e308}}"#,
            r#"{"constant": {"value": -3.81}}"#,
            r#"{"truncated_normal": {"mean": 0.01, "sigma": 0.01, "limit": 3.8}}"#,
        ] {
            let m = refusal(&group(dist));
            assert!(
                m.starts_with("cases[0].length_errors.longeron: ")
                    && m.contains(
                        "more than 1% of member \"longeron.1.0\"'s natural length 380 mm (3.8 mm)"
                    ),
                "{dist}: {m}"
            );
        }
        for dist in [
            r#"{"normal": {"sigma": 0.63}}"#,
            r#"{"uniform": {"low": -3.8, "high": 3.8}}"#,
            r#"{"truncated_normal": {"sigma": 50, "limit": 3.8}}"#,
        ] {
            Job::from_json(&group(dist), Path::new(".")).unwrap();
        }
    }

    /// A truncated normal's σ and limit must be positive and finite, refused by the group's
    /// JSON path; a valid one marks its case's parameters with its shape limit/σ (the
    /// largest of its groups'), and its standard deviation is the truncated one.
    #[test]
    fn truncated_normals_are_checked_and_marked() {
        let group = |dist: &str| job(&format!(r#", "length_errors": {{"longeron": {dist}}}"#));
        for (dist, said) in [
            (r#"{"sigma": 0, "limit": 0.01}"#, "sigma must be positive"),
            (
                r#"{"sigma": -0.01, "limit": 0.01}"#,
                "sigma must be positive",
            ),
            (r#"{"sigma": 0.01, "limit": 0}"#, "limit must be positive"),
            (r#"{"sigma": 0.01}"#, "missing field `limit`"),
            (
                r#"{"sigma": 0.01, "limit": 0.02, "max": 1}"#,
                "unknown field `max`",
            ),
        ] {
            let m = refusal(&group(&format!(r#"{{"truncated_normal": {dist}}}"#)));
            assert!(
                m.starts_with("cases[0].length_errors.longeron: ") && m.contains(said),
                "{dist}: {m}"
            );
        }
        let text = job(
            r#", "length_errors": {"longeron": {"truncated_normal": {"sigma": 0.01, "limit": 0.02}},
                                   "batten": {"truncated_normal": {"sigma": 0.01, "limit": 0.015}}}"#,
        );
        let j = Job::from_json(&text, Path::new(".")).unwrap();
        let c = &j.cases[0];
        assert_eq!(c.parameters["truncated_normal"], 2.0);
        assert!(!c.parameters.contains_key("uniform"));
        let sd = c.length_errors["longeron"].std_dev();
        // σ·√(1 − 2a·φ(a)/erf(a/√2)) at a = 2: 0.879 626 0… σ.
        assert!((sd / 0.01 - 0.879_626).abs() < 1e-6, "{sd}");
        assert_eq!(c.parameters["sigma"], sd);
    }

    /// A thermal strain α·ΔT beyond 1 % is refused by the effect's path; implausible effect
    /// values by their field.
    #[test]
    fn effects_beyond_plausible_values_are_refused() {
        let m = refusal(&job(
            r#", "effects": {"thermal_gradient": {"gradient": [0, 0, 0], "offset": 500, "alpha": 1e-4}}"#,
        ));
        assert!(
            m.starts_with("cases[0].effects.thermal_gradient: a thermal length change of 19 mm"),
            "{m}"
        );
        let m = refusal(&job(
            r#", "effects": {"gravity": {"direction": [0, 0, -1], "g": 1e308}}"#,
        ));
        assert!(
            m.starts_with("cases[0].effects.gravity.g: 1e308 is beyond"),
            "{m}"
        );
    }

    /// A clearance that can exceed a tenth of the jointed member is refused.
    #[test]
    fn implausible_clearances_are_refused() {
        let m = refusal(
            r#"{"model": {"prism": {"stages": 1, "backlash": true}}, "seed": 1,
                "cases": [{"name": "a", "samples": 1,
                           "backlash": {"clearance": {"uniform": {"low": 0, "high": 1e308}}}}]}"#,
        );
        assert!(
            m.starts_with("cases[0].backlash.clearance: a clearance can reach 1e308 mm"),
            "{m}"
        );
    }

    /// Samples are capped per case and per job.
    #[test]
    fn sample_counts_are_capped() {
        let m =
            refusal(&job("0000000").replace("\"samples\": 100000000", "\"samples\": 100000001"));
        assert!(
            m.starts_with("cases[0].samples: must be at most 100000000"),
            "{m}"
        );
        let case = |n: usize| format!(r#"{{"name": "c{n}", "samples": 100000000}}"#);
        let cases: Vec<String> = (0..11).map(case).collect();
        let m = refusal(&format!(
            r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 1, "cases": [{}]}}"#,
            cases.join(",")
        ));
        assert!(
            m.starts_with("cases[10].samples: the job's cases have 1100000000"),
            "{m}"
        );
    }

    /// Two distributions for one group, or one group named twice, are refused naming the
    /// group (not serde's bare "expected …").
    #[test]
    fn a_group_gets_one_distribution() {
        let m = refusal(&job(
            r#", "length_errors": {"batten": {"normal": {"sigma": 0.01}, "uniform": {"low": 0, "high": 0.1}}}"#,
        ));
        assert!(
            m.starts_with(
                "cases[0].length_errors.batten: one distribution at a time, got 2 (normal, uniform)"
            ),
            "{m}"
        );
        let m = refusal(&job(
            r#", "length_errors": {"batten": {"normal": {"sigma": 0.01}}, "batten": {"normal": {"sigma": 0.02}}}"#,
        ));
        assert!(m.contains("group \"batten\" is given twice"), "{m}");
    }

    /// A job file with a UTF-8 byte-order mark is the same job; /dev/zero and invalid UTF-8
    /// are refused (invalid input, not I/O), naming the file.
    #[test]
    fn job_files_are_read_as_text_files_only() {
        let text = job("");
        let plain = Job::from_json(&text, Path::new(".")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bom.json");
        std::fs::write(&path, format!("\u{feff}{text}")).unwrap();
        assert_eq!(Job::read(&path).unwrap().id, plain.id);
        std::fs::write(&path, b"{\"seed\": \xff}").unwrap();
        let e = Job::read(&path).unwrap_err();
        assert!(matches!(e, JobError::Refused { .. }), "{e:?}");
        assert!(
            e.to_string()
                .contains("bom.json: not UTF-8 text: invalid bytes at line 1, column 10"),
            "{e}"
        );
        let e = Job::read(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/dev/zero: not a regular file (a character device); give the path of a file"
        );
    }

    /// Case names are checked when the job is read: too long (10,000 characters, which the
    /// merge could not make a file name of), or holding a NUL, an escape sequence or a line
    /// break, are refused naming `cases[i].name`, and the message shows the name escaped
    /// and shortened, never its raw characters.
    #[test]
    fn case_names_are_checked_when_the_job_is_read() {
        let named = |name: &str| {
            format!(
                r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 1,
                    "cases": [{{"name": {}, "samples": 10}}]}}"#,
                serde_json::to_string(name).unwrap()
            )
        };
        let long = "x".repeat(10_000);
        let m = refusal(&named(&long));
        assert!(m.starts_with("cases[0].name: "), "{m}");
        assert!(m.contains("longer than 200 bytes") && m.len() < 300, "{m}");
        for bad in ["a\0b", "\u{1b}[31mred", "two\nlines", "tab\there"] {
            let m = refusal(&named(bad));
            assert!(m.starts_with("cases[0].name: "), "{bad:?}: {m}");
            assert!(m.contains("control character"), "{m}");
            assert!(!m.chars().any(|c| c.is_control()), "raw in {m:?}");
        }
        let ok = "σ-0.0063 (batten & longeron) / 5 stages";
        Job::from_json(&named(ok), Path::new(".")).unwrap();
        Job::from_json(&named(&"y".repeat(200)), Path::new(".")).unwrap();
    }

    /// A model file the job names that is missing is an I/O failure (exit 4, as a missing
    /// job file is), said with the job file, the JSON path and the model file's path.
    #[test]
    fn a_missing_model_file_is_an_io_failure() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("job.json");
        std::fs::write(
            &path,
            r#"{"model": "absent.json", "seed": 1, "cases": [{"name": "a", "samples": 1}]}"#,
        )
        .unwrap();
        let e = Job::read(&path).unwrap_err();
        assert!(e.is_io(), "{e:?}");
        let m = e.to_string();
        assert!(
            m.contains("job.json: model: cannot read model file") && m.contains("absent.json"),
            "{m}"
        );
        assert!(!Job::read(Path::new("/dev/zero")).unwrap_err().is_io());
        assert!(
            Job::read(&dir.path().join("none.json"))
                .unwrap_err()
                .is_io()
        );
    }
}
