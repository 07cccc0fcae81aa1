//! What a tolerance study found: per group the allocated σ, shares and sensitivities, the
//! verification runs, the uniform σ and the costs. The study fills it ([`crate::study`]);
//! the report and the plots read it ([`crate::report`], [`crate::plot`]). Units: σ in mm,
//! angles in rad.

use crate::sensitivity::Sensitivity;
use crate::verify::Percentile;
use std::path::PathBuf;

/// One group's result.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupResult {
    /// Name.
    pub name: String,
    /// Allocated σ \[mm\] (the pinned one if fixed).
    pub sigma: f64,
    /// σ in the input case \[mm\].
    pub input_sigma: f64,
    /// Share of the tilt's variance at the input σ, with its 95 % interval.
    pub share: (f64, (f64, f64)),
    /// `S_g` \[mm⁻²\]: the tilt's half-trace variance per unit σ_g².
    pub sensitivity: f64,
    /// `∂θ_Pq/∂σ_g` at the input σ \[rad/mm\].
    pub derivative: f64,
    /// Members.
    pub members: usize,
    /// Cost weight.
    pub weight: f64,
    /// Pinned by `--fix`, or a lot part (held at its σ).
    pub fixed: bool,
    /// A production lot's shared part (`GROUP.lot`; see [`crate::setup`]).
    pub lot: bool,
}

/// The study's result.
#[derive(Debug, Clone)]
pub struct Tolerance {
    /// The case.
    pub case: String,
    /// The input job's id.
    pub job_id: String,
    /// θ* \[rad\].
    pub target_rad: f64,
    /// The target as it was set (its `Display` is the target's one spelling).
    pub target_set: truss_units::TargetAngle,
    /// The percentile in %.
    pub percentile: f64,
    /// Per group.
    pub groups: Vec<GroupResult>,
    /// Per member (with errors): id, group index, the sensitivity fit's shares.
    pub members: Vec<(String, usize)>,
    /// The member shares with intervals.
    pub sensitivity: Sensitivity,
    /// θ_Pq at the input σ, from the sensitivity run.
    pub input: Percentile,
    /// The model's θ_Pq at the input σ \[rad\].
    pub input_model: f64,
    /// The common σ meeting the target \[mm\].
    pub uniform_sigma: f64,
    /// The uniform σ's runs (how many) and the last one's θ_Pq.
    pub uniform_run: (usize, Percentile),
    /// Costs (allocated, uniform).
    pub cost: (f64, f64),
    /// Every verification run in order: (σ per group \[mm\], θ_Pq, model θ_Pq \[rad\]).
    pub runs: Vec<(Vec<f64>, Percentile, f64)>,
    /// The tilt covariance's eigenvalue ratio λ₂/λ₁ at the allocation (1: isotropic).
    pub isotropy: f64,
    /// Whether the last run verifies.
    pub verified: bool,
    /// The allocation against the job's alignment budget, if the job states one.
    pub budget: Option<BudgetCheck>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

impl Tolerance {
    /// The last verification run.
    pub fn verified_run(&self) -> &(Vec<f64>, Percentile, f64) {
        self.runs.last().expect("at least one verification run")
    }

    /// The cost ratio, allocated over uniform.
    pub fn cost_ratio(&self) -> f64 {
        self.cost.0 / self.cost.1
    }
}

/// The allocation against the job's alignment budget (see `crate::study`): each line's
/// percentile at the allocated σ, on the last verification run's samples.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetCheck {
    /// The budget's percentile, in %.
    pub percentile: f64,
    /// Per line: the quantity (`theta_p`, `decenter`, `despace`), its limit (rad, mm), its
    /// percentile with the 95 % BCa interval (of θ_P, decenter, |despace|), and whether the
    /// interval's upper end is within the limit.
    pub lines: Vec<(&'static str, f64, Percentile, bool)>,
    /// The common factor `c` on every group's σ that meets every line, `min over lines of
    /// limit/percentile` corrected by runs (below 1: some line fails at the allocation).
    pub scale: f64,
    /// The line attaining the minimum.
    pub binding: &'static str,
    /// The allocated σ times `c`, per group \[mm\]: the allocation meeting every line.
    pub sigmas: Vec<f64>,
    /// The lines at the last run's σ (the allocation's own when `c` needed no run).
    pub scaled: Vec<(&'static str, f64, Percentile, bool)>,
}
