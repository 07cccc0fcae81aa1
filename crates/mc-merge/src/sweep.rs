//! Sweeps: θ_P at the target percentile against σ (with the allowable σ for the target angle,
//! paper section 3.1, Figs. 3 and 16) and against the number of stages (section 3.4, Fig. 9).
//!
//! ## Series
//!
//! Cases whose `parameters` agree on everything except `sigma` form a σ-series when they hold at
//! least two distinct σ; likewise for `stages`. Cases without the parameter are in no series of
//! that kind. Series are listed in the job order of their first case.
//!
//! ## σ-series
//!
//! Two least-squares lines of the percentile y against σ: through the origin, `y = bσ`,
//! `b = Σσy/Σσ²`, and with intercept, `y = a + bσ`. `R² = 1 − SS_res/SS_tot` with `SS_tot`
//! about the mean of y for both (so the two are comparable; it can be negative for the line
//! through the origin). The allowable σ is where the line reaches the target angle:
//! `σ_a = θ_target/b`, or `(θ_target − a)/b`.
//!
//! Intervals (slope, intercept, R², σ_a) come from the bootstrap replicates: replicate `r` of
//! every case gives a replicate series, refitted; the percentile interval of the refitted
//! quantity is reported. The cases' replicates are independent (disjoint samples), so this
//! propagates the uncertainty of every point. Replicates where a point is undefined, or where the
//! slope is not positive (for σ_a), are left out.
//!
//! ## Stages series
//!
//! Each percentile is divided by that of the smallest stage count present (1 in the paper). The
//! interval of the ratio is the percentile interval of the replicate ratios; `relative_interval`
//! is the point's own interval divided by the reference value, as the error bars of Fig. 9.

use crate::analysis::{CaseAnalysis, replicate_interval};
use crate::report::*;
use crate::settings::Settings;
use shard_record::parameters::{SIGMA, STAGES};
use std::collections::BTreeMap;
use truss_units::ARCSEC_PER_RAD;

/// A least-squares fit's numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Intercept (0 for the line through the origin).
    pub intercept: f64,
    /// Slope.
    pub slope: f64,
    /// 1 − SS_res/SS_tot (SS_tot about the mean); `None` if SS_tot = 0.
    pub r_squared: Option<f64>,
}

fn r_squared(x: &[f64], y: &[f64], line: (f64, f64)) -> Option<f64> {
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let ss_tot: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    let ss_res: f64 = x
        .iter()
        .zip(y)
        .map(|(xi, yi)| (yi - line.0 - line.1 * xi).powi(2))
        .sum();
    (ss_tot > 0.0).then(|| 1.0 - ss_res / ss_tot)
}

/// Least squares through the origin, `y = b x`. `None` if Σx² = 0.
pub fn fit_through_origin(x: &[f64], y: &[f64]) -> Option<Line> {
    let sxx: f64 = x.iter().map(|v| v * v).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>() / sxx;
    Some(Line {
        intercept: 0.0,
        slope,
        r_squared: r_squared(x, y, (0.0, slope)),
    })
}

/// Ordinary least squares `y = a + b x`. `None` with fewer than two distinct x.
pub fn fit_with_intercept(x: &[f64], y: &[f64]) -> Option<Line> {
    let n = x.len() as f64;
    if x.len() < 2 {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    Some(Line {
        intercept,
        slope,
        r_squared: r_squared(x, y, (intercept, slope)),
    })
}

/// Where a line reaches `target`: `(target − a)/b`, if the slope is positive.
pub fn allowable(line: &Line, target: f64) -> Option<f64> {
    (line.slope > 0.0).then(|| (target - line.intercept) / line.slope)
}

/// A group of cases differing only in one parameter.
#[derive(Debug, Clone)]
pub struct Series {
    /// Indices into the case list, in job order.
    pub members: Vec<usize>,
    /// The shared parameters.
    pub fixed: BTreeMap<String, f64>,
}

/// Groups cases into series over `param` (see the module doc).
pub fn series_over(params: &[&BTreeMap<String, f64>], param: &str) -> Vec<Series> {
    let mut groups: Vec<(Vec<(String, u64)>, Series)> = vec![];
    for (i, p) in params.iter().enumerate() {
        if !p.contains_key(param) {
            continue;
        }
        let key: Vec<(String, u64)> = p
            .iter()
            .filter(|(k, _)| k.as_str() != param)
            .map(|(k, v)| (k.clone(), v.to_bits()))
            .collect();
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, s)) => s.members.push(i),
            None => groups.push((
                key,
                Series {
                    members: vec![i],
                    fixed: p
                        .iter()
                        .filter(|(k, _)| k.as_str() != param)
                        .map(|(k, v)| (k.clone(), *v))
                        .collect(),
                },
            )),
        }
    }
    groups
        .into_iter()
        .map(|(_, s)| s)
        .filter(|s| {
            let mut xs: Vec<u64> = s
                .members
                .iter()
                .map(|&i| params[i][param].to_bits())
                .collect();
            xs.sort_unstable();
            xs.dedup();
            xs.len() >= 2
        })
        .collect()
}

/// Whether the σ `sigma` (mm; false where null) lies outside the range of the series' σs `x`.
pub(crate) fn outside_range(sigma: &Figure, x: &[f64]) -> bool {
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    sigma.get().is_some_and(|v| v < lo || v > hi)
}

fn series_name(fixed: &BTreeMap<String, f64>) -> String {
    if fixed.is_empty() {
        "all cases".into()
    } else {
        fixed
            .iter()
            .map(|(k, v)| format!("{k}={}", short(*v)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

fn reals(m: &BTreeMap<String, f64>) -> BTreeMap<String, Real> {
    m.iter()
        .filter_map(|(k, v)| real(*v).map(|r| (k.clone(), r)))
        .collect()
}

fn union_caveats(cases: &[&CaseAnalysis]) -> Vec<String> {
    let mut out = vec![];
    for c in cases {
        for cv in &c.report.caveats {
            out.push(format!("{}: {cv}", c.report.name));
        }
    }
    out
}

/// The replicate series: for each replicate where every member is defined, the member values.
fn replicate_rows(members: &[&CaseAnalysis]) -> Vec<Vec<f64>> {
    let b = members
        .iter()
        .map(|c| c.target_replicates.len())
        .min()
        .unwrap_or(0);
    (0..b)
        .filter_map(|r| {
            members
                .iter()
                .map(|c| c.target_replicates[r])
                .collect::<Option<Vec<f64>>>()
        })
        .collect()
}

fn figure_from(
    value: Option<f64>,
    reps: impl Iterator<Item = f64>,
    confidence: f64,
    why_null: &str,
) -> Figure {
    match value {
        None => Figure::null(why_null),
        Some(v) => match replicate_interval(reps, confidence) {
            Some((lo, hi)) => Figure::new(v, lo, hi),
            None => Figure::without_interval(v, "no usable bootstrap replicate"),
        },
    }
}

fn line_fit(line: Option<Line>, reps: &[Option<Line>], confidence: f64, origin: bool) -> LineFit {
    let why = "fewer than two distinct σ with a defined percentile";
    let slope = figure_from(
        line.map(|l| l.slope),
        reps.iter().flatten().map(|l| l.slope),
        confidence,
        why,
    );
    let intercept = if origin {
        Figure::without_interval(0.0, "fixed at 0 by construction")
    } else {
        figure_from(
            line.map(|l| l.intercept),
            reps.iter().flatten().map(|l| l.intercept),
            confidence,
            why,
        )
    };
    let r_squared = figure_from(
        line.and_then(|l| l.r_squared),
        reps.iter().flatten().filter_map(|l| l.r_squared),
        confidence,
        "R² undefined (all percentiles equal, or too few points)",
    );
    LineFit {
        slope,
        intercept,
        r_squared,
    }
}

fn sigma_series(
    s: &Series,
    params: &[&BTreeMap<String, f64>],
    cases: &[CaseAnalysis],
    settings: &Settings,
) -> SigmaSeries {
    let conf = settings.confidence;
    let target = settings.target_angle;
    let all: Vec<&CaseAnalysis> = s.members.iter().map(|&i| &cases[i]).collect();
    let points: Vec<SeriesPoint> = s
        .members
        .iter()
        .map(|&i| SeriesPoint {
            case: cases[i].report.name.clone(),
            x: Real(params[i][SIGMA]),
            value: cases[i].target.clone(),
        })
        .collect();
    // Fit on the points with a defined percentile.
    let used: Vec<usize> = (0..s.members.len())
        .filter(|&k| all[k].target.get().is_some())
        .collect();
    let x: Vec<f64> = used.iter().map(|&k| params[s.members[k]][SIGMA]).collect();
    let y: Vec<f64> = used.iter().filter_map(|&k| all[k].target.get()).collect();
    let used_cases: Vec<&CaseAnalysis> = used.iter().map(|&k| all[k]).collect();
    let rows = replicate_rows(&used_cases);
    let origin = fit_through_origin(&x, &y);
    let inter = fit_with_intercept(&x, &y);
    let origin_reps: Vec<Option<Line>> = rows.iter().map(|r| fit_through_origin(&x, r)).collect();
    let inter_reps: Vec<Option<Line>> = rows.iter().map(|r| fit_with_intercept(&x, r)).collect();
    let allow = |line: Option<Line>, reps: &[Option<Line>]| {
        figure_from(
            line.as_ref().and_then(|l| allowable(l, target)),
            reps.iter().flatten().filter_map(|l| allowable(l, target)),
            conf,
            "the fitted line does not rise with σ",
        )
    };
    let through_origin = allow(origin, &origin_reps);
    let with_intercept = allow(inter, &inter_reps);
    let extrapolated = outside_range(&through_origin, &x);
    SigmaSeries {
        name: series_name(&s.fixed),
        fixed: reals(&s.fixed),
        points,
        through_origin: line_fit(origin, &origin_reps, conf, true),
        with_intercept: line_fit(inter, &inter_reps, conf, false),
        allowable_sigma: AllowableSigma {
            target_angle: Real(target),
            target_arcsec: Real(target * ARCSEC_PER_RAD),
            percentile: Real(settings.target_percentile),
            through_origin,
            with_intercept,
            extrapolated,
        },
        replicates_used: rows.len(),
        caveats: union_caveats(&all),
    }
}

fn stages_series(
    s: &Series,
    params: &[&BTreeMap<String, f64>],
    cases: &[CaseAnalysis],
    settings: &Settings,
) -> StagesSeries {
    let conf = settings.confidence;
    let all: Vec<&CaseAnalysis> = s.members.iter().map(|&i| &cases[i]).collect();
    let stages = |k: usize| params[s.members[k]][STAGES];
    // The reference: the smallest stage count (first in job order among equals).
    let reference = (0..all.len())
        .min_by(|&a, &b| stages(a).total_cmp(&stages(b)).then(a.cmp(&b)))
        .expect("a series has members");
    let ref_case = all[reference];
    let ref_value = ref_case.target.get().filter(|v| *v > 0.0);
    let points: Vec<StagesPoint> = (0..all.len())
        .map(|k| {
            let c = all[k];
            let (normalised, relative_interval) = match (c.target.get(), ref_value) {
                (Some(v), Some(r)) => {
                    let reps = c
                        .target_replicates
                        .iter()
                        .zip(&ref_case.target_replicates)
                        .filter_map(|(a, b)| Some((*a)? / (*b).filter(|b| *b > 0.0)?));
                    let rel = match c.target.interval() {
                        Some((lo, hi)) => Interval::new(lo / r, hi / r),
                        None => Interval::null("the point has no interval"),
                    };
                    (figure_from(Some(v / r), reps, conf, ""), rel)
                }
                _ => (
                    Figure::null("the point or the reference percentile is undefined or zero"),
                    Interval::null("the point or the reference percentile is undefined or zero"),
                ),
            };
            StagesPoint {
                case: c.report.name.clone(),
                stages: Real(stages(k)),
                value: c.target.clone(),
                normalised,
                relative_interval,
            }
        })
        .collect();
    let peak_stages = points
        .iter()
        .filter_map(|p| Some((p.normalised.get()?, p.stages.0)))
        .fold(None::<(f64, f64)>, |best, (v, st)| match best {
            Some((bv, _)) if bv >= v => best,
            _ => Some((v, st)),
        })
        .map(|(_, st)| Real(st));
    StagesSeries {
        name: series_name(&s.fixed),
        fixed: reals(&s.fixed),
        reference_stages: Real(stages(reference)),
        points,
        peak_stages,
        caveats: union_caveats(&all),
    }
}

/// The sweep section of the report.
pub fn sweep(
    params: &[&BTreeMap<String, f64>],
    cases: &[CaseAnalysis],
    settings: &Settings,
) -> SweepReport {
    SweepReport {
        percentile: Real(settings.target_percentile),
        sigma_series: series_over(params, SIGMA)
            .iter()
            .map(|s| sigma_series(s, params, cases, settings))
            .collect(),
        stages_series: series_over(params, STAGES)
            .iter()
            .map(|s| stages_series(s, params, cases, settings))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line through the origin is recovered exactly from exact data, and its allowable σ is
    /// target/slope (paper section 3.1: θ_P95 = 9.69e-5 rad at σ = 6.30e-3 mm gives slope
    /// 0.01538 rad/mm).
    #[test]
    fn exact_line_and_allowable_sigma() {
        let slope = 9.69e-5 / 6.30e-3;
        let x = [0.0033, 0.0067, 0.017, 0.033, 0.067];
        let y: Vec<f64> = x.iter().map(|s| slope * s).collect();
        let l = fit_through_origin(&x, &y).unwrap();
        assert!((l.slope / slope - 1.0).abs() < 1e-12);
        assert!((allowable(&l, 9.69e-5).unwrap() - 6.30e-3).abs() < 1e-15);
        let li = fit_with_intercept(&x, &y).unwrap();
        assert!(li.intercept.abs() < 1e-18 && (li.r_squared.unwrap() - 1.0).abs() < 1e-12);
    }

    /// Ordinary least squares by hand: (0,1), (1,3), (2,4): b = 1.5, a = 7/6, R² = 0.9643.
    #[test]
    fn ols_by_hand() {
        let l = fit_with_intercept(&[0.0, 1.0, 2.0], &[1.0, 3.0, 4.0]).unwrap();
        assert!((l.slope - 1.5).abs() < 1e-12);
        assert!((l.intercept - 7.0 / 6.0).abs() < 1e-12);
        // SS_tot = 14/3, SS_res = 1/6.
        assert!((l.r_squared.unwrap() - (1.0 - (1.0 / 6.0) / (14.0 / 3.0))).abs() < 1e-12);
        assert!(fit_with_intercept(&[1.0, 1.0], &[1.0, 2.0]).is_none());
    }

    #[test]
    fn series_group_by_the_other_parameters() {
        let p = |s: f64, st: f64, b: f64| -> BTreeMap<String, f64> {
            [
                ("sigma".into(), s),
                ("stages".into(), st),
                ("backlash".into(), b),
            ]
            .into()
        };
        let ps = [
            p(0.01, 5.0, 0.0),
            p(0.02, 5.0, 0.0),
            p(0.01, 5.0, 1.0),
            p(0.02, 5.0, 1.0),
            p(0.067, 1.0, 0.0),
            p(0.067, 4.0, 0.0),
            p(0.5, 9.0, 1.0),
        ];
        let refs: Vec<&BTreeMap<String, f64>> = ps.iter().collect();
        let sig = series_over(&refs, "sigma");
        assert_eq!(sig.len(), 2);
        assert_eq!(sig[0].members, vec![0, 1]);
        assert_eq!(sig[1].members, vec![2, 3]);
        let st = series_over(&refs, "stages");
        assert_eq!(st.len(), 1);
        assert_eq!(st[0].members, vec![4, 5]);
        assert_eq!(series_name(&st[0].fixed), "backlash=0, sigma=0.067");
    }
}
