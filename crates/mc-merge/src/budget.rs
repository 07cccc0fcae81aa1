//! The job's alignment budget against the Monte Carlo: per case, which lines pass and the σ
//! that meets them all, saying which line binds; per σ-series, the same from the fitted lines.
//!
//! ## Lines
//!
//! A budget (the shards' begin lines carry it: [`shard_record::Budget`]) holds each
//! quantity's `p`-th percentile to a limit: θ_P \[rad\], decenter \[mm\], |despace| \[mm\]. A
//! case's line reads its empirical percentile `q` (Hyndman–Fan definition 1, with the BCa
//! interval, else the percentile interval, of the case's Poisson bootstrap) and **passes**
//! when `q ≤ limit`; it is **clear** when the whole interval lies on the same side of the
//! limit as `q`. The merge adds `p` to the percentiles it computes.
//!
//! ## Allowable σ
//!
//! Under small errors every measured quantity is linear in the length errors, so each
//! percentile is proportional to σ (θ_P's, the paper's eq. 28 and Fig. 3; decenter's and
//! |despace|'s by the same homogeneity). For a case at σ:
//!
//! ```text
//! σ_allow = σ · min over lines of (limit / q)              [mm]
//! ```
//!
//! the line attaining the minimum **binds**. Its interval is the percentile interval over
//! the bootstrap replicates of the same minimum (each replicate's `q` of every line, which
//! share the replicate's Poisson weights); `binding_share` is the fraction of those
//! replicates in which the same line binds. For a σ-series (cases differing only in σ,
//! as in the sweep) each line is fitted through the origin, `q = bσ` with
//! `b = Σσq/Σσ²`, and `σ_allow = min over lines of limit/b`, with intervals from refitting
//! every replicate series. A case without a `sigma` parameter has no allowable σ.

use crate::analysis::{CaseAnalysis, Levels, replicate_interval};
use crate::report::*;
use crate::settings::Settings;
use crate::sweep::{fit_through_origin, outside_range, series_over};
use shard_record::Budget;
use shard_record::parameters::SIGMA;
use std::collections::BTreeMap;

/// A member's percentile of one line and its replicates, where it records the quantity.
type Reading<'a> = Option<(&'a Figure, &'a [Option<f64>])>;

/// What each quantity's percentile is of, and its unit.
fn describe(quantity: &str) -> (&'static str, &'static str) {
    match quantity {
        "theta_p" => ("θ_P", "rad"),
        "decenter" => ("decenter", "mm"),
        _ => ("|despace|", "mm"),
    }
}

/// The name a line's quantity is known by, as `'static`.
fn name(quantity: &str) -> &'static str {
    match quantity {
        "theta_p" => "theta_p",
        "decenter" => "decenter",
        _ => "despace",
    }
}

/// The case's percentiles of `quantity`, if it records them.
fn levels<'a>(a: &'a CaseAnalysis, quantity: &str) -> Option<&'a Levels> {
    match quantity {
        "theta_p" => Some(&a.theta),
        "decenter" => a.decenter.as_ref(),
        _ => a.despace.as_ref(),
    }
}

/// The smallest `limit / q` over the lines and the index of its line; `None` where some
/// line's `q` is undefined or not positive.
fn binding(limits: &[f64], qs: &[Option<f64>]) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for (j, (l, q)) in limits.iter().zip(qs).enumerate() {
        let q = (*q).filter(|q| *q > 0.0)?;
        let r = l / q;
        if best.is_none_or(|(b, _)| r < b) {
            best = Some((r, j));
        }
    }
    best
}

/// The replicate values of every line's percentile, row by row (replicate `r`: one value
/// per line), where every line has a replicate `r`.
fn replicate_rows(per_line: &[&[Option<f64>]]) -> Vec<Vec<Option<f64>>> {
    let b = per_line.iter().map(|r| r.len()).min().unwrap_or(0);
    (0..b)
        .map(|r| per_line.iter().map(|reps| reps[r]).collect())
        .collect()
}

/// The allowable σ, its binding line and the share of replicates it binds in, from the
/// point estimates `qs`, the replicate rows and a scale `scale(r)` that turns a minimum
/// ratio into a σ.
fn allowable(
    lines: &[(&'static str, f64)],
    qs: &[Option<f64>],
    rows: &[Vec<Option<f64>>],
    scale: f64,
    confidence: f64,
) -> (Figure, Option<&'static str>, Option<Real>) {
    let limits: Vec<f64> = lines.iter().map(|l| l.1).collect();
    let Some((ratio, j)) = binding(&limits, qs) else {
        return (
            Figure::null("some line's percentile is undefined or zero"),
            None,
            None,
        );
    };
    let reps: Vec<(f64, usize)> = rows.iter().filter_map(|r| binding(&limits, r)).collect();
    let share = (!reps.is_empty())
        .then(|| reps.iter().filter(|(_, k)| *k == j).count() as f64 / reps.len() as f64);
    let value = scale * ratio;
    let figure = match replicate_interval(reps.iter().map(|(r, _)| scale * r), confidence) {
        Some((lo, hi)) => Figure::new(value, lo, hi),
        None => Figure::without_interval(value, "no usable bootstrap replicate"),
    };
    (figure, Some(lines[j].0), share.and_then(real))
}

fn case_budget(
    a: &CaseAnalysis,
    sigma: Option<f64>,
    lines: &[(&'static str, f64)],
    pct: f64,
    confidence: f64,
) -> BudgetCase {
    let mut qs = Vec::new();
    let mut reps: Vec<&[Option<f64>]> = Vec::new();
    let mut out = Vec::new();
    for &(quantity, limit) in lines {
        let at = levels(a, quantity).and_then(|l| l.at(pct));
        let value = at.map_or_else(
            || Figure::null(format!("the samples do not record {quantity}")),
            |(f, _)| f.clone(),
        );
        let q = value.get();
        qs.push(q);
        reps.push(at.map_or(&[][..], |(_, r)| r));
        let passes = q.map(|q| q <= limit);
        let clear = match (passes, value.interval()) {
            (Some(p), Some((lo, hi))) => Some(if p { hi <= limit } else { lo > limit }),
            _ => None,
        };
        out.push(BudgetCaseLine {
            quantity,
            value,
            limit: Real(limit),
            ratio: q.and_then(|q| real(q / limit)),
            passes,
            clear,
        });
    }
    let passes = out
        .iter()
        .map(|l| l.passes)
        .collect::<Option<Vec<bool>>>()
        .map(|p| p.iter().all(|x| *x));
    let (allowable_sigma, binding, binding_share) = match sigma {
        Some(s) if s > 0.0 => allowable(lines, &qs, &replicate_rows(&reps), s, confidence),
        _ => (
            Figure::null("the case has no σ (no length errors, or no sigma parameter)"),
            None,
            None,
        ),
    };
    BudgetCase {
        case: a.report.name.clone(),
        sigma: sigma.and_then(real),
        lines: out,
        passes,
        allowable_sigma,
        binding,
        binding_share,
    }
}

fn series_budget(
    members: &[usize],
    fixed: &BTreeMap<String, f64>,
    params: &[&BTreeMap<String, f64>],
    cases: &[CaseAnalysis],
    lines: &[(&'static str, f64)],
    pct: f64,
    confidence: f64,
) -> BudgetSeries {
    let x: Vec<f64> = members.iter().map(|&i| params[i][SIGMA]).collect();
    // Per line: each member's percentile and replicates.
    let per_line: Vec<Vec<Reading>> = lines
        .iter()
        .map(|(q, _)| {
            members
                .iter()
                .map(|&i| levels(&cases[i], q).and_then(|l| l.at(pct)))
                .collect()
        })
        .collect();
    let slope_of = |ys: &[Option<f64>]| {
        let y: Option<Vec<f64>> = ys.iter().copied().collect();
        fit_through_origin(&x, &y?).map(|l| l.slope)
    };
    let b = per_line
        .iter()
        .flatten()
        .map(|m| m.map_or(0, |(_, r)| r.len()))
        .min()
        .unwrap_or(0);
    let mut slopes = Vec::new();
    let mut slope_reps: Vec<Vec<Option<f64>>> = Vec::new();
    let mut out = Vec::new();
    for (j, &(quantity, limit)) in lines.iter().enumerate() {
        let ys: Vec<Option<f64>> = per_line[j]
            .iter()
            .map(|m| m.and_then(|(f, _)| f.get()))
            .collect();
        let slope = slope_of(&ys);
        let reps: Vec<Option<f64>> = (0..b)
            .map(|r| {
                let ys: Vec<Option<f64>> = per_line[j]
                    .iter()
                    .map(|m| m.and_then(|(_, reps)| reps[r]))
                    .collect();
                slope_of(&ys)
            })
            .collect();
        let figure = |v: Option<f64>, reps: &mut dyn Iterator<Item = f64>| match v {
            None => Figure::null("a member's percentile is undefined"),
            Some(v) => match replicate_interval(reps, confidence) {
                Some((lo, hi)) => Figure::new(v, lo, hi),
                None => Figure::without_interval(v, "no usable bootstrap replicate"),
            },
        };
        let positive = |s: &Option<f64>| s.filter(|s| *s > 0.0);
        out.push(BudgetSeriesLine {
            quantity,
            slope: figure(slope, &mut reps.iter().flatten().copied()),
            allowable_sigma: figure(
                positive(&slope).map(|s| limit / s),
                &mut reps.iter().filter_map(positive).map(|s| limit / s),
            ),
        });
        slopes.push(slope);
        slope_reps.push(reps);
    }
    // A slope b is a percentile per unit σ: limit/b = σ · limit/q at σ = 1.
    let rows: Vec<Vec<Option<f64>>> = (0..b)
        .map(|r| slope_reps.iter().map(|reps| reps[r]).collect())
        .collect();
    let (allowable_sigma, binding, binding_share) =
        allowable(lines, &slopes, &rows, 1.0, confidence);
    let extrapolated = outside_range(&allowable_sigma, &x);
    BudgetSeries {
        name: if fixed.is_empty() {
            "all cases".into()
        } else {
            fixed
                .iter()
                .map(|(k, v)| format!("{k}={}", short(*v)))
                .collect::<Vec<_>>()
                .join(", ")
        },
        cases: members
            .iter()
            .map(|&i| cases[i].report.name.clone())
            .collect(),
        lines: out,
        allowable_sigma,
        binding,
        binding_share,
        extrapolated,
    }
}

/// The budget report of the cases `cases` with parameters `params` (see the module doc).
pub fn budget_report(
    budget: &Budget,
    params: &[&BTreeMap<String, f64>],
    cases: &[CaseAnalysis],
    settings: &Settings,
) -> BudgetReport {
    let lines: Vec<(&'static str, f64)> = budget
        .lines()
        .into_iter()
        .map(|(q, l)| (name(q), l))
        .collect();
    let pct = budget.percentile;
    let conf = settings.confidence;
    BudgetReport {
        percentile: Real(pct),
        lines: lines
            .iter()
            .map(|&(quantity, limit)| {
                let (of, unit) = describe(quantity);
                BudgetLine {
                    quantity,
                    of,
                    limit: Real(limit),
                    unit,
                }
            })
            .collect(),
        cases: cases
            .iter()
            .zip(params)
            .map(|(a, p)| case_budget(a, p.get(SIGMA).copied(), &lines, pct, conf))
            .collect(),
        series: series_over(params, SIGMA)
            .iter()
            .map(|s| series_budget(&s.members, &s.fixed, params, cases, &lines, pct, conf))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: limits (2, 10) against percentiles (1, 4): ratios 2 and 2.5, so the first
    /// line binds and σ_allow = 2σ; a zero or missing percentile leaves it undefined.
    #[test]
    fn the_smallest_ratio_binds() {
        assert_eq!(
            binding(&[2.0, 10.0], &[Some(1.0), Some(4.0)]),
            Some((2.0, 0))
        );
        assert_eq!(
            binding(&[2.0, 10.0], &[Some(1.0), Some(5.0 + 1.0)]),
            Some((10.0 / 6.0, 1))
        );
        assert_eq!(binding(&[2.0, 10.0], &[Some(1.0), None]), None);
        assert_eq!(binding(&[2.0], &[Some(0.0)]), None);
        let lines = [("theta_p", 2.0), ("decenter", 10.0)];
        let rows = vec![
            vec![Some(1.0), Some(4.0)],
            vec![Some(0.9), Some(6.0)],
            vec![Some(1.1), Some(4.0)],
            vec![Some(1.0), Some(4.5)],
        ];
        let (f, line, share) = allowable(&lines, &[Some(1.0), Some(4.0)], &rows, 0.004, 0.95);
        assert!((f.get().unwrap() - 0.008).abs() < 1e-15);
        assert_eq!(line, Some("theta_p"));
        // Replicate 2 has decenter binding (10/6 < 2/0.9).
        assert_eq!(share.unwrap().0, 0.75);
    }
}
