//! The study's input: the job and case, the groups whose tolerance is allocated, the
//! `--cost` and `--fix` values, and jobs of the same case with other σ values.
//!
//! A group's length error must be zero-mean and scalable, as its distribution says
//! (`truss_job::distribution::Kind::with_sigma`): `{"normal": {"sigma": σ}}` (mean 0),
//! `{"uniform": {"low": −a, "high": a}}` (σ = a/√3) or
//! `{"truncated_normal": {"sigma": s, "limit": t}}` (mean 0). Changing a group's σ keeps its
//! distribution's type: the normal gets the new σ, the uniform the half-width √3·σ, the
//! truncated normal its s and t scaled together. The draws of a sample are `σ·z` with `z`
//! from the sample's stream (see `truss_job::sampler`), so two runs of the same case at
//! different σ see the same `z`: common random numbers.
//!
//! **Production lots.** A group whose error has a lot part (`"lot"`: member `i` of lot `L`
//! gets `e_i = p_i + s_L`) adds a group of its own to the study, named `GROUP.lot`, after
//! the model's groups: its "members" are the group's lots, its σ the lot part's, and it is
//! held at that σ as `--fix` holds a group (the shared part is the stock's or the batch's,
//! not a machining tolerance the study allocates; a budget's common factor scales it with
//! the rest). Its distribution must be scalable as a group's is; its σ may be 0 (then the
//! study is the study without the lot). The lot draws come from a stream of their own, so
//! a run at other σ values still sees the same `z` and the same lot draws.

use crate::errors::ToleranceError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use truss_job::Job;
use truss_job::distribution::DistributionSpec;
use truss_job::job::{CaseSpec, JobSpec};

/// A group whose tolerance is studied.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Group name (the model's).
    pub name: String,
    /// Its distribution in the input case.
    pub distribution: DistributionSpec,
    /// Its σ in the input case \[mm\].
    pub sigma: f64,
    /// Number of members in the group.
    pub members: usize,
    /// Cost weight `w` (default 1).
    pub weight: f64,
    /// The σ it is pinned at by `--fix` \[mm\], if any (a lot part: its own σ).
    pub fixed: Option<f64>,
    /// For a lot part (`GROUP.lot`): the model group whose lots it is and the members
    /// (model indices) of each lot; `None` for a model group.
    pub lots: Option<(String, Vec<Vec<usize>>)>,
}

impl Group {
    /// Whether this is a production lot's shared part, not a model group.
    pub fn is_lot(&self) -> bool {
        self.lots.is_some()
    }
}

/// The job, the case and its groups.
#[derive(Debug, Clone)]
pub struct Study {
    /// The job as read (model file paths made absolute).
    pub spec: JobSpec,
    /// The case's index in `spec.cases`.
    pub case_index: usize,
    /// The groups with length errors, by name.
    pub groups: Vec<Group>,
    /// Where the job file is (model paths are resolved against it).
    pub base: PathBuf,
}

/// Parses `GROUP=NUMBER` of `flag`.
fn parse_pair(flag: &str, text: &str) -> Result<(String, f64), ToleranceError> {
    let bad = |message: String| ToleranceError::BadValue {
        flag: flag.to_string(),
        message,
    };
    let (group, value) = text
        .split_once('=')
        .ok_or_else(|| bad(format!("expected GROUP=NUMBER, got {text:?}")))?;
    let value: f64 = value
        .trim()
        .parse()
        .map_err(|_| bad(format!("{group}: {value:?} is not a number")))?;
    if !value.is_finite() {
        return Err(bad(format!("{group}: {value} is not a finite number")));
    }
    Ok((group.trim().to_string(), value))
}

impl Study {
    /// Reads the job at `path`, picks `case`, and applies the `--cost` and `--fix` values.
    pub fn read(
        path: &Path,
        case: &str,
        costs: &[String],
        fixes: &[String],
    ) -> Result<Self, ToleranceError> {
        let spec = JobSpec::read(path)?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        // Validate the whole job as given (names the file and JSON path of any fault).
        let job = Job::new(&spec, &base).map_err(|e| e.in_file(path))?;
        Self::new(spec, &job, base, case, costs, fixes)
    }

    /// The study of `case` of a parsed and validated job.
    pub fn new(
        mut spec: JobSpec,
        job: &Job,
        base: PathBuf,
        case: &str,
        costs: &[String],
        fixes: &[String],
    ) -> Result<Self, ToleranceError> {
        let case_index = job.case_named(case).ok_or_else(|| ToleranceError::NoCase {
            case: case.to_string(),
            known: job
                .cases
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
        let validated = &job.cases[case_index];
        let unsupported = |reason: &str| ToleranceError::Unsupported {
            case: case.to_string(),
            reason: reason.to_string(),
        };
        if !validated.effects.is_empty() {
            return Err(unsupported(
                "has effects (gravity, thermal_gradient): the tilt is then not homogeneous in \
                 the length errors, which the allocation rests on; remove them for the study",
            ));
        }
        if validated.backlash.is_some() || !validated.model.joints().is_empty() {
            return Err(unsupported(
                "has pin joints with clearance: the tilt is then not homogeneous in the length \
                 errors, which the allocation rests on; study the case without backlash",
            ));
        }
        if validated.length_errors.is_empty() {
            return Err(ToleranceError::NoLengthErrors {
                case: case.to_string(),
            });
        }
        let mut groups = Vec::new();
        for (name, d) in &validated.length_errors {
            let not = |reason: String| ToleranceError::NotScalable {
                case: case.to_string(),
                group: name.clone(),
                reason,
            };
            // Whether the distribution can be scaled to a σ, in its own words.
            d.with_sigma(d.std_dev()).map_err(not)?;
            let sigma = d.std_dev();
            if sigma <= 0.0 {
                return Err(not(
                    "its length error has σ = 0, so its influence on the tilt cannot be \
                     measured: give it a σ > 0 in the case (the study's starting point)"
                        .into(),
                ));
            }
            let members = validated
                .model
                .members()
                .iter()
                .filter(|m| &m.group == name)
                .count();
            groups.push(Group {
                name: name.clone(),
                distribution: *d,
                sigma,
                members,
                weight: 1.0,
                fixed: None,
                lots: None,
            });
        }
        let known = groups
            .iter()
            .map(|g| g.name.as_str())
            .collect::<Vec<_>>()
            .join(", ");
        // Each group at most once per flag: a repeat is refused, not "the last one wins".
        let find = |flag: &str,
                    text: &str,
                    given: &mut Vec<Option<String>>|
         -> Result<(usize, f64), ToleranceError> {
            let (group, value) = parse_pair(flag, text)?;
            let i = groups.iter().position(|g| g.name == group).ok_or_else(|| {
                ToleranceError::UnknownGroup {
                    flag: flag.to_string(),
                    group: group.clone(),
                    known: known.clone(),
                }
            })?;
            if let Some(first) = &given[i] {
                return Err(ToleranceError::BadValue {
                    flag: format!("{flag} {text}"),
                    message: format!(
                        "group {group:?} is given twice ({flag} {first} before): give each group once"
                    ),
                });
            }
            given[i] = Some(text.to_string());
            Ok((i, value))
        };
        let mut weights = Vec::new();
        let mut given = vec![None; groups.len()];
        for c in costs {
            let (i, w) = find("--cost", c, &mut given)?;
            if w <= 0.0 {
                return Err(ToleranceError::BadValue {
                    flag: "--cost".into(),
                    message: format!("{c}: a cost weight must be positive"),
                });
            }
            weights.push((i, w));
        }
        let mut pins = Vec::new();
        let mut given = vec![None; groups.len()];
        for f in fixes {
            let (i, s) = find("--fix", f, &mut given)?;
            if s < 0.0 {
                return Err(ToleranceError::BadValue {
                    flag: "--fix".into(),
                    message: format!("{f}: a σ must not be negative [mm]"),
                });
            }
            pins.push((i, s));
        }
        for (i, w) in weights {
            groups[i].weight = w;
        }
        for (i, s) in pins {
            groups[i].fixed = Some(s);
        }
        if groups.iter().all(|g| g.fixed.is_some()) {
            return Err(ToleranceError::BadValue {
                flag: "--fix".into(),
                message: "every group is fixed: there is nothing left to allocate".into(),
            });
        }
        // Each lot part, after the model groups, held at its σ.
        for lot in &validated.lots {
            let name = format!("{}.lot", lot.group);
            let not = |reason: String| ToleranceError::NotScalable {
                case: case.to_string(),
                group: name.clone(),
                reason: format!("its production lot's shared part: {reason}"),
            };
            if groups.iter().any(|g| g.name == name) {
                return Err(not(format!(
                    "the model has a group named {name:?} too; rename it for the study"
                )));
            }
            let d = lot.distribution;
            d.with_sigma(d.std_dev()).map_err(not)?;
            groups.push(Group {
                name,
                distribution: d,
                sigma: d.std_dev(),
                members: lot.lots.len(),
                weight: 0.0,
                fixed: Some(d.std_dev()),
                lots: Some((lot.group.clone(), lot.lots.clone())),
            });
        }
        spec.model = spec.model.clone().absolute(&base);
        for c in &mut spec.cases {
            c.model = c.model.take().map(|m| m.absolute(&base));
        }
        Ok(Self {
            spec,
            case_index,
            groups,
            base,
        })
    }

    /// The case as written.
    pub fn case(&self) -> &CaseSpec {
        &self.spec.cases[self.case_index]
    }

    /// The case's name.
    pub fn case_name(&self) -> &str {
        &self.case().name
    }

    /// The case with the groups' σ replaced by `sigmas` (mm, in group order) and `samples`
    /// samples.
    pub fn case_with(&self, sigmas: &[f64], samples: u64) -> CaseSpec {
        let mut case = self.case().clone();
        case.samples = samples;
        // The groups' own parts scaled, and the lot parts.
        for (g, &s) in self.groups.iter().zip(sigmas) {
            if let Some((group, _)) = &g.lots
                && let Some(lot) = case.length_errors.lots.get_mut(group)
            {
                lot.distribution = g
                    .distribution
                    .with_sigma(s)
                    .expect("checked scalable in Study::new");
            }
        }
        case.length_errors.parts = self
            .groups
            .iter()
            .zip(sigmas)
            .filter(|(g, _)| !g.is_lot())
            .map(|(g, &s)| {
                let scaled = g.distribution.with_sigma(s);
                (
                    g.name.clone(),
                    scaled.expect("checked scalable in Study::new"),
                )
            })
            .collect::<BTreeMap<_, _>>();
        case
    }

    /// A job of this one case with σ values `sigmas` (group order) and `samples` samples:
    /// sample `k` of it draws the same `z` as sample `k` of the input case.
    /// A σ the study computed that is no number (its input σ and `--cost` values so extreme
    /// that a ratio overflowed) is refused naming the group ([`ToleranceError::NotScalable`]),
    /// never reported as the job's own "not a finite number".
    pub fn job_with(&self, sigmas: &[f64], samples: u64) -> Result<Job, ToleranceError> {
        for (g, &s) in self.groups.iter().zip(sigmas) {
            let scaled = g.distribution.with_sigma(s).ok();
            let finite = s.is_finite() && scaled.is_none_or(|d| d.std_dev().is_finite());
            if !finite {
                return Err(ToleranceError::NotScalable {
                    case: self.case().name.clone(),
                    group: g.name.clone(),
                    reason: format!(
                        "the σ the study computed for it is {s} mm, not a number: its input σ \
                         ({} mm) or its --cost is too extreme beside the other groups' \
                         (keep them within some hundred orders of magnitude)",
                        truss_core::readable(g.sigma)
                    ),
                });
            }
        }
        let spec = JobSpec {
            model: self.spec.model.clone(),
            seed: self.spec.seed,
            cases: vec![self.case_with(sigmas, samples)],
            budget: self.spec.budget,
        };
        Ok(Job::new(&spec, &self.base)?)
    }

    /// The input job with this case's σ values replaced (everything else as given; model
    /// file paths absolute).
    pub fn allocated_spec(&self, sigmas: &[f64]) -> JobSpec {
        let mut spec = self.spec.clone();
        let samples = self.case().samples;
        spec.cases[self.case_index] = self.case_with(sigmas, samples);
        spec
    }

    /// The input σ of every group \[mm\].
    pub fn input_sigmas(&self) -> Vec<f64> {
        self.groups.iter().map(|g| g.sigma).collect()
    }
}
