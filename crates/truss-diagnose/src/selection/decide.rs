//! Stage 3 of a step, *decide*: the verdict from the candidates' tests and BIC (named,
//! cannot tell, none, unexplained), the named candidate and those indistinguishable from it
//! by BIC or by Vuong's test of closeness.

use crate::comparison::statistics::Comparison;
use crate::likelihood::score::{CandidateScore, p_is};
use serde::Serialize;

/// Evidence that counts as a clear improvement and as "as good": a BIC difference of 2
/// (Kass & Raftery 1995: below 2 "not worth more than a bare mention").
pub const DELTA_BIC: f64 = 2.0;
/// Vuong's z below which the named candidate is not shown closer to the data's distribution
/// than another significant candidate (two-sided 5 %): the other is listed as
/// indistinguishable.
pub const VUONG_Z: f64 = 1.96;
/// Fewest specimens for the verdict `unexplained`: below it the large-sample intervals of
/// single statistics (covariances above all) are not trusted to show a disagreement that no
/// candidate explains, and the verdict is `cannot_tell`.
pub const MIN_FOR_DISAGREEMENT: usize = 30;
/// The verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// A candidate explains the disagreement and is named.
    Named,
    /// The baseline agrees within tolerance and no candidate improves it significantly.
    None,
    /// The data cannot decide (see the crate doc).
    CannotTell,
    /// The baseline disagrees but no candidate in the library explains it.
    Unexplained,
}

impl Verdict {
    /// The verdict as `diagnosis.json` writes it (`named`, `none`, `cannot_tell`,
    /// `unexplained`).
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Named => "named",
            Verdict::None => "none",
            Verdict::CannotTell => "cannot_tell",
            Verdict::Unexplained => "unexplained",
        }
    }

    /// The verdict in words; `none`'s "these sizes" are the detection limits the reports
    /// give beside it ([`crate::selection::unseen`]).
    pub fn words(self) -> &'static str {
        match self {
            Verdict::Named => "a missing effect is named",
            Verdict::None => "the model agrees; no effect above these sizes is missing",
            Verdict::CannotTell => "the data cannot tell",
            Verdict::Unexplained => "the model disagrees, and no candidate explains it",
        }
    }
}

/// The verdict, why, the named candidate and those indistinguishable from it (indices).
#[derive(Debug, Clone)]
pub struct Decision {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in a sentence or two.
    pub reason: String,
    /// The named candidate.
    pub named: Option<usize>,
    /// Candidates within ΔBIC 2 of the named one.
    pub indistinguishable: Vec<usize>,
}

/// Vuong's (1989) statistic for two non-nested models fitted to the same data: with
/// `a` and `b` the per-unit terms of their maximised ℓ and `d_u` their difference summed
/// over each cluster u (a specimen with its member observations), of n_u clusters,
/// `z = Σ d_u / √(c·n_u·var(d))`, c = 1 + n/N for the simulation's own noise in both fits.
/// Positive: `a` closer. Zero when the two predict the same for every unit.
pub fn vuong(a: &[f64], b: &[f64], clusters: &[usize], inflation: f64) -> f64 {
    let units = clusters.iter().max().map_or(0, |m| m + 1);
    let mut d = vec![0.0; units];
    for ((x, y), &u) in a.iter().zip(b).zip(clusters) {
        d[u] += x - y;
    }
    if units < 2 {
        return 0.0;
    }
    let n = units as f64;
    let sum: f64 = d.iter().sum();
    let mean = sum / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    if var > 0.0 {
        sum / (inflation * n * var).sqrt()
    } else {
        0.0
    }
}

/// The verdict from the candidates' scores and the baseline's comparison (crate doc):
/// `level` is the per-candidate significance level α/K; `closeness(i, j)` is Vuong's z of
/// candidate i against j ([`vuong`]), asked only of significant candidates.
pub fn decide(
    scores: &[&CandidateScore],
    before: &Comparison,
    n: usize,
    level: f64,
    closeness: &dyn Fn(usize, usize) -> f64,
) -> Decision {
    let before_disagrees = before.statistics.iter().any(|s| s.disagrees);
    let best = (0..scores.len())
        .filter(|&i| scores[i].error.is_none())
        .min_by(|&a, &b| scores[a].delta_bic.total_cmp(&scores[b].delta_bic));
    let clear = best.filter(|&i| scores[i].significant && scores[i].delta_bic <= -DELTA_BIC);
    let (verdict, reason, named, indistinguishable) = if let Some(i) = clear {
        let candidates = (0..scores.len()).filter(|&j| j != i && scores[j].error.is_none());
        let by_bic: Vec<usize> = candidates
            .clone()
            .filter(|&j| scores[j].delta_bic < scores[i].delta_bic + DELTA_BIC)
            .collect();
        let by_vuong: Vec<(usize, f64)> = candidates
            .filter(|&j| !by_bic.contains(&j) && scores[j].significant)
            .map(|j| (j, closeness(i, j)))
            .filter(|&(_, z)| z < VUONG_Z)
            .collect();
        let names = |js: &mut dyn Iterator<Item = usize>| {
            js.map(|j| scores[j].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut reason = format!(
            "{} improves the likelihood significantly ({} < α/K = {level:.4}) and is the best by BIC",
            scores[i].name,
            p_is(scores[i].p_value),
        );
        if by_bic.is_empty() && by_vuong.is_empty() {
            reason += &format!(
                " by at least {DELTA_BIC} over every other candidate, and fits significantly closer than every other significant one (Vuong z ≥ {VUONG_Z})"
            );
        }
        if !by_bic.is_empty() {
            reason += &format!(
                "; {} explain the data as well (ΔBIC within {DELTA_BIC})",
                names(&mut by_bic.iter().copied())
            );
        }
        if !by_vuong.is_empty() {
            let (verb, they) = if by_vuong.len() == 1 {
                ("improves", "it does")
            } else {
                ("improve", "they do")
            };
            reason += &format!(
                "; {} also {verb} significantly and it does not fit significantly closer than {they} ({})",
                names(&mut by_vuong.iter().map(|&(j, _)| j)),
                by_vuong
                    .iter()
                    .map(|&(j, z)| format!("Vuong z = {z:.2} against {}", scores[j].name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if !by_bic.is_empty() || !by_vuong.is_empty() {
            reason += ": the data cannot tell them apart";
        }
        let mut others = by_bic;
        others.extend(by_vuong.iter().map(|&(j, _)| j));
        (Verdict::Named, reason, Some(i), others)
    } else if scores
        .iter()
        .any(|s| s.significant || s.delta_bic < -DELTA_BIC)
    {
        (
            Verdict::CannotTell,
            "some candidates improve the fit, but none both significantly (Bonferroni) and by a clear BIC margin: the data cannot decide".into(),
            None,
            Vec::new(),
        )
    } else if before.tolerance.within {
        (
            Verdict::None,
            "no candidate improves the fit significantly, and the model agrees with the measurements within the stated tolerance".into(),
            None,
            Vec::new(),
        )
    } else if before_disagrees && n >= MIN_FOR_DISAGREEMENT {
        (
            Verdict::Unexplained,
            "the measurements disagree with the model, but no candidate effect of the library explains it significantly".into(),
            None,
            Vec::new(),
        )
    } else {
        (
            Verdict::CannotTell,
            format!(
                "no candidate improves the fit significantly, but with {n} specimens the data cannot show that the model agrees within tolerance either ({} outside){}: more specimens are needed",
                before.tolerance.outside.join(", "),
                if before_disagrees {
                    ", and the few statistics that disagree are too uncertain with so few specimens"
                } else {
                    ""
                }
            ),
            None,
            Vec::new(),
        )
    };
    Decision {
        verdict,
        reason,
        named,
        indistinguishable,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn score(name: &str, k: usize, delta_bic: f64, significant: bool) -> CandidateScore {
        CandidateScore::of_test(name, k, delta_bic, significant)
    }

    fn comparison() -> Comparison {
        Comparison::of_energy(0.0, 1.0, 0.0)
    }

    /// The best by BIC is named; a significant candidate 3 BIC worse that it does not fit
    /// significantly closer than (z = 1.0) is indistinguishable, one it does (z = 4.0) is
    /// not, and a candidate that is not significant is not asked about.
    #[test]
    fn indistinguishable_by_bic_or_by_closeness() {
        let s = [
            score("a", 1, -14.0, true),
            score("b", 2, -11.0, true),
            score("c", 2, -10.5, true),
            score("d", 1, -12.5, true),
            score("e", 3, 5.0, false),
        ];
        let refs: Vec<&CandidateScore> = s.iter().collect();
        let asked = std::cell::RefCell::new(Vec::new());
        let z = |i: usize, j: usize| {
            asked.borrow_mut().push((i, j));
            if j == 1 { 1.0 } else { 4.0 }
        };
        let d = decide(&refs, &comparison(), 200, 0.01, &z);
        assert_eq!(d.verdict, Verdict::Named);
        assert_eq!(d.named, Some(0));
        assert_eq!(d.indistinguishable, vec![3, 1]);
        assert_eq!(*asked.borrow(), vec![(0, 1), (0, 2)]);
        assert!(
            d.reason.contains("b also improves significantly")
                && d.reason
                    .contains("closer than it does (Vuong z = 1.00 against b)"),
            "{}",
            d.reason
        );
        let clear = decide(&refs[..3], &comparison(), 200, 0.01, &|_, _| 4.0);
        assert!(clear.indistinguishable.is_empty());
        assert!(
            clear.reason.contains("closer than every other"),
            "{}",
            clear.reason
        );
    }

    /// Vuong's z by hand: units 0, 1, 2 with differences 1, 3, 2 (unit 2's split over two
    /// terms, as a specimen's member observations are): sum 6, variance 1, z = 6/√3; and
    /// with c = 4 half that. Identical fits give 0, and swapping the models changes the sign.
    #[test]
    fn vuong_sums_clusters_and_scales_by_their_spread() {
        let a = [1.0, 3.0, 1.5, 0.5];
        let b = [0.0, 0.0, 0.0, 0.0];
        let clusters = [0, 1, 2, 2];
        let z = vuong(&a, &b, &clusters, 1.0);
        assert!((z - 6.0 / 3f64.sqrt()).abs() < 1e-12, "{z}");
        assert!((vuong(&a, &b, &clusters, 4.0) - z / 2.0).abs() < 1e-12);
        assert_eq!(vuong(&b, &a, &clusters, 1.0), -z);
        assert_eq!(vuong(&a, &a, &clusters, 1.0), 0.0);
    }
}
