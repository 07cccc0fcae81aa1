//! The schema of `report.json`: plain serde types, one per object of the file.
//!
//! Every number is a JSON number; a figure that cannot be computed is `null` with a `reason`
//! string beside it. Numbers go through [`Real`], whose serialisation refuses NaN and ±∞, so a
//! non-finite value can never reach the file silently (serde_json would write it as `null`).

use crate::errors::MissingRange;
use crate::settings::Settings;
use serde::Serialize;
use serde::ser::{Error as _, Serializer};
use std::collections::BTreeMap;

/// The value of the report's `format` field.
pub const REPORT_FORMAT: &str = "truss-mc-merge-report";

/// The report format version.
pub const REPORT_VERSION: u32 = 1;

/// A finite number. Serialising a non-finite one is an error.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Real(pub f64);

impl Serialize for Real {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.is_finite() {
            s.serialize_f64(self.0)
        } else {
            Err(S::Error::custom(format!(
                "non-finite number {} in the report",
                self.0
            )))
        }
    }
}

/// `Some(Real)` when `x` is finite.
pub fn real(x: f64) -> Option<Real> {
    x.is_finite().then_some(Real(x))
}

/// A parameter value in its shortest readable form (0.0099, not 0.009899999999999999).
pub fn short(x: f64) -> String {
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" || s == "0" && x != 0.0 {
        format!("{x:e}")
    } else {
        s.to_string()
    }
}

/// A figure with its confidence interval; `null`s come with a `reason`.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Figure {
    /// The estimate.
    pub value: Option<Real>,
    /// Lower end of the interval.
    pub lower: Option<Real>,
    /// Upper end of the interval.
    pub upper: Option<Real>,
    /// Why the value or the interval is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl Figure {
    /// A figure with an interval.
    pub fn new(value: f64, lower: f64, upper: f64) -> Self {
        let mut f = Self {
            value: real(value),
            lower: real(lower),
            upper: real(upper),
            reason: None,
        };
        if f.value.is_none() || f.lower.is_none() || f.upper.is_none() {
            f.reason = Some("not finite".into());
        }
        f
    }

    /// A figure whose interval could not be computed.
    pub fn without_interval(value: f64, reason: impl Into<String>) -> Self {
        Self {
            value: real(value),
            lower: None,
            upper: None,
            reason: Some(reason.into()),
        }
    }

    /// A figure that could not be computed at all.
    pub fn null(reason: impl Into<String>) -> Self {
        Self {
            reason: Some(reason.into()),
            ..Self::default()
        }
    }

    /// The value as f64.
    pub fn get(&self) -> Option<f64> {
        self.value.map(|r| r.0)
    }

    /// The interval as f64s.
    pub fn interval(&self) -> Option<(f64, f64)> {
        Some((self.lower?.0, self.upper?.0))
    }
}

/// A confidence interval without a point value; `null`s come with a `reason`.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Interval {
    /// Lower end.
    pub lower: Option<Real>,
    /// Upper end.
    pub upper: Option<Real>,
    /// Why the interval is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl Interval {
    /// An interval.
    pub fn new(lower: f64, upper: f64) -> Self {
        Self {
            lower: real(lower),
            upper: real(upper),
            reason: None,
        }
    }

    /// A null interval.
    pub fn null(reason: impl Into<String>) -> Self {
        Self {
            reason: Some(reason.into()),
            ..Self::default()
        }
    }

    /// The ends as f64s.
    pub fn get(&self) -> Option<(f64, f64)> {
        Some((self.lower?.0, self.upper?.0))
    }
}

/// The whole report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Always [`REPORT_FORMAT`].
    pub format: &'static str,
    /// [`REPORT_VERSION`].
    pub format_version: u32,
    /// `mc-merge`.
    pub program: &'static str,
    /// The program version.
    pub program_version: &'static str,
    /// The job id of the shards.
    pub job_id: String,
    /// Samples of the job.
    pub job_samples: u64,
    /// Which samples were present.
    pub coverage: Coverage,
    /// Failed samples over the job.
    pub failed: FailedSummary,
    /// The settings used.
    pub settings: Settings,
    /// Definitions of every statistic, in words.
    pub definitions: Definitions,
    /// Per case results, in job order.
    pub cases: Vec<CaseReport>,
    /// Series over σ and over the number of stages.
    pub sweep: SweepReport,
    /// The answer drawn from the cases and the sweeps: what the console prints last and the
    /// readable report shows first.
    pub answer: AnswerReport,
    /// The job's alignment budget, case by case and per σ-series, if it states one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budget: Option<BudgetReport>,
}

/// The answer a merge is run for, drawn from the cases and the sweeps of the same report:
/// nothing in it is estimated again, except the Holm adjustment of the Rayleigh verdicts'
/// p-values across the cases.
#[derive(Debug, Clone, Serialize)]
pub struct AnswerReport {
    /// The target angle (rad), as set.
    pub target_angle: Real,
    /// The percentile that must meet it, in percent.
    pub percentile: Real,
    /// Each case's θ_P at the target percentile against the target, in job order.
    pub cases: Vec<CaseAgainstTarget>,
    /// Each σ-series' allowable σ (the line through the origin, as the sweep's first).
    pub allowable_sigma: Vec<AllowableAnswer>,
    /// The Rayleigh law's verdicts over the cases, with what chance alone gives.
    pub rayleigh: RayleighVerdicts,
}

/// A case's θ_P at the target percentile against the target.
#[derive(Debug, Clone, Serialize)]
pub struct CaseAgainstTarget {
    /// Case name.
    pub case: String,
    /// θ_P at the target percentile (rad) with its BCa interval (percentile interval where
    /// BCa is null), as the sweeps use it.
    pub value: Figure,
    /// `"above"` the target, `"within"` it (at or below), or `"undefined"` where `value` is
    /// null (its reason says why).
    pub against: &'static str,
}

/// A σ-series' allowable σ in the answer.
#[derive(Debug, Clone, Serialize)]
pub struct AllowableAnswer {
    /// The series' name.
    pub series: String,
    /// The allowable σ (mm) of the line through the origin, with its bootstrap interval
    /// (whose lower end is the conservative choice).
    pub sigma: Figure,
    /// Whether the allowable σ lies outside the σ range of the series.
    pub extrapolated: bool,
}

/// The Rayleigh law's verdicts over the cases.
#[derive(Debug, Clone, Serialize)]
pub struct RayleighVerdicts {
    /// Cases whose Rayleigh law was tested.
    pub tested: usize,
    /// The significance level α of each case's test.
    pub level: Real,
    /// `tested × level`: the rejections expected by chance alone if the law held in every
    /// tested case.
    pub expected_by_chance: Real,
    /// The tested cases, in job order.
    pub cases: Vec<RayleighVerdict>,
    /// The cases still rejected at `level` after Holm's adjustment across the tested cases
    /// (which holds the chance of any false rejection among them at `level`).
    pub holm_rejected: Vec<String>,
}

/// One case's Rayleigh verdict with its multiplicity context and effect size.
#[derive(Debug, Clone, Serialize)]
pub struct RayleighVerdict {
    /// Case name.
    pub case: String,
    /// `"holds"` or `"rejected"` at `level`, as the case's `gof.verdict`.
    pub verdict: &'static str,
    /// The p-value the verdict compares with the level: the smaller of KS's and AD's.
    pub p_value: Real,
    /// That p-value adjusted by Holm's step-down method across the tested cases.
    pub holm_p_value: Real,
    /// (Rayleigh − empirical)/empirical at the target percentile, with its bootstrap
    /// interval: how much the law's verdict matters for the answer.
    pub relative_difference: Figure,
}

/// Coverage of the global index range.
#[derive(Debug, Clone, Serialize)]
pub struct Coverage {
    /// Every sample present.
    pub complete: bool,
    /// Samples present.
    pub present: u64,
    /// Samples of the job.
    pub expected: u64,
    /// The missing ranges (at most the first 100), split at case boundaries.
    pub missing: Vec<MissingRange>,
    /// Number of missing ranges in all.
    pub missing_ranges: usize,
}

/// Failed samples over the job.
#[derive(Debug, Clone, Serialize)]
pub struct FailedSummary {
    /// Failed samples present.
    pub total: u64,
    /// Whether they were excluded (`--allow-failed`).
    pub excluded: bool,
}

/// The definitions used, in words (the crate doc has the same text).
#[derive(Debug, Clone, Serialize)]
pub struct Definitions {
    /// Units of every number.
    pub units: &'static str,
    /// The percentile definition.
    pub percentile: &'static str,
    /// The bootstrap.
    pub bootstrap: BootstrapDefinition,
    /// The distribution-free interval.
    pub order_statistic: &'static str,
    /// The Rayleigh fit and σ_t.
    pub rayleigh: &'static str,
    /// The goodness-of-fit tests.
    pub gof: &'static str,
    /// The sweeps.
    pub sweep: &'static str,
    /// The loose-joint fraction.
    pub loose_joints: &'static str,
    /// How the floating fraction is computed.
    pub floating: &'static str,
    /// The holding force and its summaries.
    pub holding_force: &'static str,
}

/// The bootstrap's definition and parameters.
#[derive(Debug, Clone, Serialize)]
pub struct BootstrapDefinition {
    /// `"poisson"`.
    pub kind: &'static str,
    /// In words.
    pub description: &'static str,
    /// B.
    pub replicates: u32,
    /// The seed.
    pub seed: u64,
    /// The generator, in words.
    pub rng: &'static str,
    /// Confidence level.
    pub confidence: Real,
    /// The percentile interval, in words.
    pub percentile_interval: &'static str,
    /// The BCa interval, in words.
    pub bca_interval: &'static str,
}

/// Results for one case.
#[derive(Debug, Clone, Serialize)]
pub struct CaseReport {
    /// Case name.
    pub name: String,
    /// The case's named parameters (`sigma` in mm, `stages`, …).
    pub parameters: BTreeMap<String, Real>,
    /// Samples the case has.
    pub expected: u64,
    /// Samples present (converged or failed).
    pub present: u64,
    /// Converged samples used for every figure.
    pub n: u64,
    /// Failed samples.
    pub failed: FailedCaseReport,
    /// Conditions every figure of this case is subject to (partial coverage, failures excluded).
    pub caveats: Vec<String>,
    /// Fraction of samples with at least one loose backlash joint.
    pub loose_joints: LooseJoints,
    /// Fraction of samples with a floating stage.
    pub floating: Floating,
    /// How firmly the samples are held: their holding forces.
    pub holding_force: HoldingForces,
    /// Bootstrap bookkeeping.
    pub bootstrap: BootstrapCase,
    /// Empirical percentiles of θ_P with intervals.
    pub percentiles: Vec<PercentileReport>,
    /// The Rayleigh law.
    pub rayleigh: RayleighReport,
    /// Goodness of fit of the Rayleigh law.
    pub gof: GofReport,
    /// Decenter's percentiles and its Rayleigh law; absent where the samples do not record
    /// it (shards of numerics version 7 or earlier).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decenter: Option<QuantityReport>,
    /// |despace|'s percentiles and despace's normal law; absent where not recorded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub despace: Option<QuantityReport>,
}

/// A measured quantity beside θ_P (decenter, despace: mm): its percentiles with the same
/// intervals as θ_P's, the law it follows under small errors, and that law's goodness of fit.
#[derive(Debug, Clone, Serialize)]
pub struct QuantityReport {
    /// `"decenter"` or `"despace"`.
    pub quantity: &'static str,
    /// What the percentiles are of: `"decenter"`, or `"|despace|"` (the budget's reading of
    /// a signed shift).
    pub of: &'static str,
    /// `"mm"`.
    pub unit: &'static str,
    /// Converged samples that record it.
    pub n: u64,
    /// Empirical percentiles with intervals \[mm\].
    pub percentiles: Vec<PercentileReport>,
    /// The law under small errors.
    pub law: LawReport,
    /// Goodness of fit of the law (KS and AD, parameters estimated, Monte Carlo calibrated).
    pub gof: GofReport,
}

/// The law a quantity follows under small errors: Rayleigh for decenter (its two
/// components, decenter_x and decenter_y, nearly N(0, σ²) each, as tan θ_x and tan θ_y are
/// for θ_P), normal for despace.
#[derive(Debug, Clone, Serialize)]
pub struct LawReport {
    /// `"rayleigh"` or `"normal"`.
    pub law: &'static str,
    /// Mean, standard deviation and zero-mean scale of each component (`decenter_x`,
    /// `decenter_y`; `despace`) \[mm\].
    pub components: BTreeMap<&'static str, ComponentReport>,
    /// The Rayleigh scale σ̂ = √(Σ decenter²/2n) with its χ²(2n) interval \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<Figure>,
    /// The normal law's mean (despace's sample mean, Student-t interval) \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean: Option<Figure>,
    /// The normal law's standard deviation (χ²(n−1) interval) \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std: Option<Figure>,
    /// The law's percentiles (Rayleigh's eq. 28 at σ̂; for |despace| the folded normal's
    /// at the mean and standard deviation) beside the empirical ones \[mm\].
    pub percentiles: Vec<RayleighPercentile>,
    /// Caveats (the case's).
    pub caveats: Vec<String>,
}

/// The job's alignment budget against the Monte Carlo: per case, which lines pass and the
/// σ that would meet them all; per σ-series, the same from the fitted lines.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetReport {
    /// The percentile every line is read at, in %.
    pub percentile: Real,
    /// The lines, in the order θ_P, decenter, despace.
    pub lines: Vec<BudgetLine>,
    /// Each case, in job order.
    pub cases: Vec<BudgetCase>,
    /// Each σ-series (cases differing only in σ), as in `sweep.sigma_series`.
    pub series: Vec<BudgetSeries>,
}

/// One line of a budget.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetLine {
    /// `"theta_p"`, `"decenter"` or `"despace"`.
    pub quantity: &'static str,
    /// What its percentile is of: `"θ_P"`, `"decenter"`, `"|despace|"`.
    pub of: &'static str,
    /// The limit (rad for θ_P, mm otherwise).
    pub limit: Real,
    /// `"rad"` or `"mm"`.
    pub unit: &'static str,
}

/// One case against the budget.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetCase {
    /// The case's name.
    pub case: String,
    /// Its σ \[mm\] (the `sigma` parameter), if it has one.
    pub sigma: Option<Real>,
    /// Each line: the percentile with its interval, and whether it passes.
    pub lines: Vec<BudgetCaseLine>,
    /// Whether every line passes (null where some line's percentile is undefined).
    pub passes: Option<bool>,
    /// The σ meeting every line by the scaling of each percentile with σ (homogeneity under
    /// small errors), `σ · min over lines of limit/percentile` \[mm\], with the bootstrap
    /// interval of that minimum.
    pub allowable_sigma: Figure,
    /// The line that binds (the minimum's), if any.
    pub binding: Option<&'static str>,
    /// The fraction of bootstrap replicates in which that line binds.
    pub binding_share: Option<Real>,
}

/// One line's reading for one case.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetCaseLine {
    /// The quantity.
    pub quantity: &'static str,
    /// Its percentile (rad or mm) with the BCa (else percentile) interval.
    pub value: Figure,
    /// The limit.
    pub limit: Real,
    /// `value / limit` \[-\].
    pub ratio: Option<Real>,
    /// Whether the percentile is at or below the limit (null where undefined).
    pub passes: Option<bool>,
    /// Whether the whole interval lies on the same side of the limit as the value.
    pub clear: Option<bool>,
}

/// One σ-series against the budget.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetSeries {
    /// The series' name, as in `sweep.sigma_series`.
    pub name: String,
    /// Its cases, in job order.
    pub cases: Vec<String>,
    /// Per line: the fitted line through the origin and where it meets the limit.
    pub lines: Vec<BudgetSeriesLine>,
    /// The σ meeting every line, `min over lines of limit/slope` \[mm\], with the bootstrap
    /// interval from refitting every replicate series.
    pub allowable_sigma: Figure,
    /// The line that binds, if any.
    pub binding: Option<&'static str>,
    /// The fraction of replicate series in which that line binds.
    pub binding_share: Option<Real>,
    /// Whether the allowable σ lies outside the series' σ range.
    pub extrapolated: bool,
}

/// One line of a σ-series.
#[derive(Debug, Clone, Serialize)]
pub struct BudgetSeriesLine {
    /// The quantity.
    pub quantity: &'static str,
    /// The slope of the percentile against σ, through the origin (rad/mm or mm/mm).
    pub slope: Figure,
    /// `limit / slope` \[mm\].
    pub allowable_sigma: Figure,
}

/// Failed samples of a case.
#[derive(Debug, Clone, Serialize)]
pub struct FailedCaseReport {
    /// How many.
    pub count: u64,
    /// Their global indices as half-open `[start, end)` ranges (at most the first 100).
    pub ranges: Vec<[u64; 2]>,
    /// The reasons of the lowest failed indices.
    pub reasons: Vec<FailedReason>,
}

/// One failure reason.
#[derive(Debug, Clone, Serialize)]
pub struct FailedReason {
    /// Global index.
    pub index: u64,
    /// The solver's reason.
    pub reason: String,
}

/// Loose backlash joints.
#[derive(Debug, Clone, Serialize)]
pub struct LooseJoints {
    /// Converged samples that record `loose_joints`.
    pub recorded: u64,
    /// Of those, samples with at least one loose joint.
    pub with_loose: u64,
    /// `with_loose / recorded` with its Clopper–Pearson interval.
    pub fraction: Figure,
}

/// Floating stages: samples in which some stage's tilt is held by pretension alone.
#[derive(Debug, Clone, Serialize)]
pub struct Floating {
    /// Converged samples that record `floating` (those of models whose bars do not frame the
    /// top surface's tilt).
    pub recorded: u64,
    /// Of those, samples with a floating stage.
    pub floating: u64,
    /// `floating / recorded` with its Clopper–Pearson interval.
    pub fraction: Figure,
}

/// How firmly a case's samples are held: the distribution of their holding forces (the
/// largest force on one top-surface node that, to first order, moves θ_P by at most 1 % and
/// lets no bearing one-sided member go), written where the samples record it.
#[derive(Debug, Clone, Serialize)]
pub struct HoldingForces {
    /// Converged samples that record `holding_force`.
    pub recorded: u64,
    /// Its 5th, 50th and 95th percentiles \[N\] (the percentile definition of θ_P's).
    pub percentiles: Vec<HoldingPercentile>,
    /// The force below which a sample counts as loosely held \[N\]: 1e-6 (1 µN).
    pub loose_below: Real,
    /// Samples held by less than `loose_below`, with their fraction of `recorded` and its
    /// Clopper–Pearson interval.
    pub loose: u64,
    /// `loose / recorded` with its Clopper–Pearson interval.
    pub loose_fraction: Figure,
    /// Of the samples above the target percentile of θ_P that record a holding force, how
    /// many.
    pub tail_recorded: u64,
    /// Of those, how many are held by less than `loose_below`.
    pub tail_loose: u64,
    /// `tail_loose / tail_recorded` with its Clopper–Pearson interval.
    pub tail_loose_fraction: Figure,
}

/// One percentile of the holding force.
#[derive(Debug, Clone, Serialize)]
pub struct HoldingPercentile {
    /// The percentile, in percent.
    pub percentile: Real,
    /// The holding force \[N\]; null where no sample records one.
    pub value: Option<Real>,
    /// Why the value is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Bootstrap bookkeeping of a case.
#[derive(Debug, Clone, Serialize)]
pub struct BootstrapCase {
    /// Replicates drawn.
    pub replicates: u32,
    /// Replicates whose weights were all zero (left out; probability e⁻ⁿ each).
    pub empty_replicates: usize,
}

/// One empirical percentile of θ_P.
#[derive(Debug, Clone, Serialize)]
pub struct PercentileReport {
    /// The percentile, in percent.
    pub percentile: Real,
    /// The estimate (rad) (definition 1).
    pub value: Option<Real>,
    /// Why `value` is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Percentile-method bootstrap interval (rad).
    pub percentile_bootstrap: Interval,
    /// BCa bootstrap interval (rad).
    pub bca: BcaReport,
    /// Distribution-free order-statistic interval (rad).
    pub order_statistic: OrderStatisticReport,
    /// Caveats (same as the case's).
    pub caveats: Vec<String>,
}

/// A BCa interval with its constants.
#[derive(Debug, Clone, Serialize, Default)]
pub struct BcaReport {
    /// Lower end (rad).
    pub lower: Option<Real>,
    /// Upper end (rad).
    pub upper: Option<Real>,
    /// Bias correction z₀.
    pub z0: Option<Real>,
    /// Acceleration a.
    pub acceleration: Option<Real>,
    /// Why null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// An order-statistic interval.
#[derive(Debug, Clone, Serialize, Default)]
pub struct OrderStatisticReport {
    /// Lower end x₍ₗ₎ (rad).
    pub lower: Option<Real>,
    /// Upper end x₍ᵤ₎ (rad).
    pub upper: Option<Real>,
    /// l (1-based).
    pub lower_rank: Option<usize>,
    /// u (1-based).
    pub upper_rank: Option<usize>,
    /// Exact binomial coverage.
    pub coverage: Option<Real>,
    /// Why null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Mean, standard deviation and zero-mean scale of one slope component.
#[derive(Debug, Clone, Serialize)]
pub struct ComponentReport {
    /// Mean with its Student-t interval.
    pub mean: Figure,
    /// Sample standard deviation with its χ²(n−1) interval.
    pub std: Figure,
    /// Zero-mean ML scale √(Σx²/n) with its χ²(n) interval.
    pub rms: Figure,
}

/// The Rayleigh law for one case.
#[derive(Debug, Clone, Serialize)]
pub struct RayleighReport {
    /// tan θ_x.
    pub tan_theta_x: ComponentReport,
    /// tan θ_y.
    pub tan_theta_y: ComponentReport,
    /// Pooled σ_t = √(Σ(tan²θ_x + tan²θ_y)/2n) with its χ²(2n) interval.
    pub sigma_t: Figure,
    /// ML Rayleigh scale of θ_P, σ̂ = √(Σθ²/2n) (rad), with its exact χ²(2n) interval.
    pub sigma: Figure,
    /// Rayleigh percentiles (eq. 28) at σ̂, each beside the empirical one.
    pub percentiles: Vec<RayleighPercentile>,
    /// Caveats (same as the case's).
    pub caveats: Vec<String>,
}

/// One Rayleigh percentile.
#[derive(Debug, Clone, Serialize)]
pub struct RayleighPercentile {
    /// The percentile, in percent.
    pub percentile: Real,
    /// θ_P^α = σ̂ √(−2 ln(1−α)) (rad), interval from σ's interval.
    pub value: Figure,
    /// The empirical percentile (rad).
    pub empirical: Option<Real>,
    /// (Rayleigh − empirical)/empirical, with its Poisson-bootstrap percentile interval.
    pub relative_difference: Figure,
    /// Why `empirical` is null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Goodness of fit of the Rayleigh law.
#[derive(Debug, Clone, Serialize)]
pub struct GofReport {
    /// `"holds"`, `"rejected"`, or null with `reason`.
    pub verdict: Option<&'static str>,
    /// The verdict in words.
    pub summary: String,
    /// The significance level.
    pub level: Real,
    /// Kolmogorov–Smirnov.
    pub ks: Option<TestReport>,
    /// Anderson–Darling.
    pub ad: Option<TestReport>,
    /// The simulated null.
    pub null_calibration: Option<NullCalibrationReport>,
    /// Effect size an engineer can judge.
    pub effect: Option<EffectReport>,
    /// Why null.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Caveats (same as the case's).
    pub caveats: Vec<String>,
}

/// One test.
#[derive(Debug, Clone, Serialize)]
pub struct TestReport {
    /// The statistic (D or A²).
    pub statistic: Real,
    /// Stephens' modified statistic (D* or A*), the one calibrated.
    pub modified: Real,
    /// p-value, scale estimated, Monte Carlo calibrated.
    pub p_value: Real,
    /// Monte Carlo standard error of the p-value.
    pub p_value_se: Real,
}

/// The simulated null distribution.
#[derive(Debug, Clone, Serialize)]
pub struct NullCalibrationReport {
    /// Sample size simulated.
    pub sample_size: usize,
    /// Null samples.
    pub replicates: usize,
}

/// Effect size of a deviation from the law (Rayleigh's for θ_P and decenter, the normal's
/// for despace).
#[derive(Debug, Clone, Serialize)]
pub struct EffectReport {
    /// The percentile compared (the target percentile), in percent.
    pub percentile: Real,
    /// The law's percentile (rad; mm for decenter and |despace|).
    pub rayleigh: Real,
    /// Empirical percentile (rad; mm for decenter and |despace|).
    pub empirical: Real,
    /// (Rayleigh − empirical)/empirical with its bootstrap interval.
    pub relative_difference: Figure,
    /// max |F_n − F_Rayleigh| (the KS D).
    pub max_cdf_gap: Real,
}

/// The sweeps.
#[derive(Debug, Clone, Serialize)]
pub struct SweepReport {
    /// The percentile swept (the target percentile), in percent.
    pub percentile: Real,
    /// Series over σ.
    pub sigma_series: Vec<SigmaSeries>,
    /// Series over the number of stages.
    pub stages_series: Vec<StagesSeries>,
}

/// One point of a series.
#[derive(Debug, Clone, Serialize)]
pub struct SeriesPoint {
    /// Case name.
    pub case: String,
    /// The swept parameter's value (σ in mm, or stages).
    pub x: Real,
    /// The percentile (rad) with its BCa interval (percentile interval where BCa is null).
    pub value: Figure,
}

/// A least-squares line.
#[derive(Debug, Clone, Serialize)]
pub struct LineFit {
    /// Slope (rad/mm).
    pub slope: Figure,
    /// Intercept (rad) (0 by construction for the line through the origin).
    pub intercept: Figure,
    /// Coefficient of determination 1 − SS_res/SS_tot (SS_tot about the mean).
    pub r_squared: Figure,
}

/// The allowable σ for the target.
#[derive(Debug, Clone, Serialize)]
pub struct AllowableSigma {
    /// Target angle (rad).
    pub target_angle: Real,
    /// Target angle (arcsec).
    pub target_arcsec: Real,
    /// The percentile that must meet it, in percent.
    pub percentile: Real,
    /// target / slope of the line through the origin (mm), with its bootstrap interval.
    pub through_origin: Figure,
    /// (target − intercept) / slope of the line with intercept (mm), with its bootstrap interval.
    pub with_intercept: Figure,
    /// Whether the allowable σ lies outside the σ range of the series.
    pub extrapolated: bool,
}

/// A series of cases that differ only in σ.
#[derive(Debug, Clone, Serialize)]
pub struct SigmaSeries {
    /// A name from the fixed parameters.
    pub name: String,
    /// The parameters shared by the series.
    pub fixed: BTreeMap<String, Real>,
    /// Points in job order.
    pub points: Vec<SeriesPoint>,
    /// Least-squares line through the origin.
    pub through_origin: LineFit,
    /// Least-squares line with intercept.
    pub with_intercept: LineFit,
    /// The allowable σ.
    pub allowable_sigma: AllowableSigma,
    /// Bootstrap replicates in which every point was defined.
    pub replicates_used: usize,
    /// Caveats of the series' cases.
    pub caveats: Vec<String>,
}

/// One normalised point of a stages series.
#[derive(Debug, Clone, Serialize)]
pub struct StagesPoint {
    /// Case name.
    pub case: String,
    /// Number of stages.
    pub stages: Real,
    /// The percentile (rad) with its interval.
    pub value: Figure,
    /// value / reference value, with the bootstrap interval of the ratio.
    pub normalised: Figure,
    /// The point's own interval divided by the reference value (the error bars of the paper's Fig. 9).
    pub relative_interval: Interval,
}

/// A series of cases that differ only in the number of stages.
#[derive(Debug, Clone, Serialize)]
pub struct StagesSeries {
    /// A name from the fixed parameters.
    pub name: String,
    /// The parameters shared by the series.
    pub fixed: BTreeMap<String, Real>,
    /// The stage count normalised to (the smallest present).
    pub reference_stages: Real,
    /// Points in job order.
    pub points: Vec<StagesPoint>,
    /// The stage count with the largest normalised value.
    pub peak_stages: Option<Real>,
    /// Caveats of the series' cases.
    pub caveats: Vec<String>,
}
