//! The answer a user runs the merge for ([`AnswerReport`], the `answer` section of
//! `report.json`), drawn from the cases and the sweeps of the same report: which cases meet
//! the target at the target percentile, the allowable σ of each σ-series with its conservative
//! end, and the Rayleigh verdicts against what chance alone gives (the expected number of
//! rejections, m·α, and Holm's adjustment across the cases) with each one's effect size. The
//! console ([`crate::table::answer`]) prints it last, the readable report
//! ([`crate::readable::compose()`]) shows it first, and the Python package reads it from
//! `report.json`: all three read it from here.

use crate::report::{
    AllowableAnswer, AnswerReport, CaseAgainstTarget, CaseReport, Figure, RayleighVerdict,
    RayleighVerdicts, Real, SweepReport,
};
use crate::settings::Settings;

/// The answer of cases whose θ_P at the target percentile are `targets` (one per case, as
/// the sweeps use them), with their sweeps.
pub fn answer(
    cases: &[CaseReport],
    targets: &[Figure],
    sweep: &SweepReport,
    settings: &Settings,
) -> AnswerReport {
    let placed = cases
        .iter()
        .zip(targets)
        .map(|(case, value)| CaseAgainstTarget {
            case: case.name.clone(),
            against: match value.get() {
                Some(t) if t > settings.target_angle => "above",
                Some(_) => "within",
                None => "undefined",
            },
            value: value.clone(),
        })
        .collect();
    let allowable_sigma = sweep
        .sigma_series
        .iter()
        .map(|s| {
            let sigma = s.allowable_sigma.through_origin.clone();
            AllowableAnswer {
                series: s.name.clone(),
                sigma,
                extrapolated: s.allowable_sigma.extrapolated,
            }
        })
        .collect();
    AnswerReport {
        target_angle: Real(settings.target_angle),
        percentile: Real(settings.target_percentile),
        cases: placed,
        allowable_sigma,
        rayleigh: verdicts(cases, settings.gof_level),
    }
}

/// The Rayleigh verdicts of the tested cases, with Holm's adjustment of their p-values.
fn verdicts(cases: &[CaseReport], level: f64) -> RayleighVerdicts {
    let tested: Vec<(&CaseReport, &'static str, f64)> = cases
        .iter()
        .filter_map(|c| {
            let (verdict, ks, ad) = (c.gof.verdict?, c.gof.ks.as_ref()?, c.gof.ad.as_ref()?);
            Some((c, verdict, ks.p_value.0.min(ad.p_value.0)))
        })
        .collect();
    let p: Vec<f64> = tested.iter().map(|t| t.2).collect();
    let adjusted = truss_stats::two_sample::holm(&p);
    let verdicts: Vec<RayleighVerdict> = tested
        .iter()
        .zip(&adjusted)
        .map(|(&(case, verdict, p), &holm)| RayleighVerdict {
            case: case.name.clone(),
            verdict,
            p_value: Real(p),
            holm_p_value: Real(holm),
            relative_difference: case.gof.effect.as_ref().map_or_else(
                || Figure::null("no effect size"),
                |e| e.relative_difference.clone(),
            ),
        })
        .collect();
    RayleighVerdicts {
        tested: verdicts.len(),
        level: Real(level),
        expected_by_chance: Real(verdicts.len() as f64 * level),
        holm_rejected: verdicts
            .iter()
            .filter(|v| v.holm_p_value.0 < level)
            .map(|v| v.case.clone())
            .collect(),
        cases: verdicts,
    }
}

impl AnswerReport {
    /// The cases above the target, in job order.
    pub fn above(&self) -> impl Iterator<Item = &CaseAgainstTarget> {
        self.cases.iter().filter(|c| c.against == "above")
    }

    /// The cases at or below the target, in job order.
    pub fn within(&self) -> impl Iterator<Item = &CaseAgainstTarget> {
        self.cases.iter().filter(|c| c.against == "within")
    }

    /// The cases without a θ_P at the target percentile, by name.
    pub fn undefined(&self) -> impl Iterator<Item = &str> {
        self.cases
            .iter()
            .filter(|c| c.against == "undefined")
            .map(|c| c.case.as_str())
    }
}

impl RayleighVerdicts {
    /// The verdicts that reject the law at the level, unadjusted.
    pub fn rejected(&self) -> impl Iterator<Item = &RayleighVerdict> {
        self.cases.iter().filter(|v| v.verdict == "rejected")
    }

    /// The smallest Holm-adjusted p-value, if any case was tested.
    pub fn smallest_holm_p(&self) -> Option<f64> {
        self.cases
            .iter()
            .map(|v| v.holm_p_value.0)
            .min_by(f64::total_cmp)
    }
}
