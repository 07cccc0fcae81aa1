//! The answer a user runs the merge for, taken from the [`Report`] (nothing computed again):
//! which cases meet the target at the target percentile, the allowable σ of each σ-series,
//! and how many Rayleigh-law rejections the cases show against what chance alone gives. The
//! console ([`crate::table::answer`]) prints it last and the readable report
//! ([`crate::readable::compose()`]) shows it first; both read it from here.

use crate::report::{AllowableSigma, Report};

/// A case placed against the target: its name and its θ_P at the target percentile (rad).
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// The case's name.
    pub name: String,
    /// θ_P at the target percentile (rad).
    pub theta: f64,
}

/// The answer of a merge.
#[derive(Debug, Clone)]
pub struct Answer<'a> {
    /// The target percentile, in percent.
    pub percentile: f64,
    /// The target angle (rad), exactly as set.
    pub target: f64,
    /// Cases whose θ_P at the target percentile exceeds the target, in job order.
    pub above: Vec<Placed>,
    /// Cases at or below the target, in job order.
    pub within: Vec<Placed>,
    /// Cases without a θ_P at the target percentile (too few samples), by name.
    pub undefined: Vec<String>,
    /// Each σ-series' name and allowable σ.
    pub allowable: Vec<(&'a str, &'a AllowableSigma)>,
    /// How many cases had their Rayleigh law tested.
    pub tested: usize,
    /// The cases where the Rayleigh law was rejected, by name.
    pub rejected: Vec<String>,
    /// The tests' significance level α.
    pub level: Option<f64>,
}

impl<'a> Answer<'a> {
    /// The answer of `report`.
    pub fn of(report: &'a Report) -> Self {
        let set = &report.settings;
        let mut answer = Answer {
            percentile: set.target_percentile,
            target: set.target_angle,
            above: vec![],
            within: vec![],
            undefined: vec![],
            allowable: report
                .sweep
                .sigma_series
                .iter()
                .map(|s| (s.name.as_str(), &s.allowable_sigma))
                .collect(),
            tested: 0,
            rejected: vec![],
            level: None,
        };
        for case in &report.cases {
            let theta = case
                .percentiles
                .iter()
                .find(|p| p.percentile.0 == set.target_percentile)
                .and_then(|p| p.value);
            match theta {
                Some(t) => {
                    let placed = Placed {
                        name: case.name.clone(),
                        theta: t.0,
                    };
                    if t.0 > set.target_angle {
                        answer.above.push(placed);
                    } else {
                        answer.within.push(placed);
                    }
                }
                None => answer.undefined.push(case.name.clone()),
            }
            if let Some(verdict) = case.gof.verdict {
                answer.tested += 1;
                answer.level = Some(case.gof.level.0);
                if verdict == "rejected" {
                    answer.rejected.push(case.name.clone());
                }
            }
        }
        answer
    }

    /// How many rejections chance alone gives if the law held in every tested case: `m·α`.
    pub fn expected_by_chance(&self) -> Option<f64> {
        self.level.map(|a| self.tested as f64 * a)
    }
}
