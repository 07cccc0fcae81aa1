//! Effects that show only together: a pair of candidates whose effects interact
//! ([`Candidate::interacts_with`]) fitted jointly at a step, named in place of the step's
//! single effect when the two explain the data better together, or listed as an alternative
//! reading when they explain them as well.
//!
//! ## Why
//!
//! Forward selection adds one effect at a time, each tested alone against the current
//! model. Two effects that interact can each fit poorly alone: pin joints with free play
//! and diagonals made short (pretension pulls the joints into contact) seen by a backlash
//! candidate alone, against the model's slacker diagonals, loosen joints and float stages
//! the data do not show, so it fits worse than a length bias, and its clearance absorbs
//! part of the pretension; once the bias is in, backlash re-fits to nothing. Neither is
//! then named, though the two together explain the data.
//!
//! ## The rule
//!
//! After a step's decision ([`crate::selection::decide`]), for each pair {a, b} of the
//! step's candidates that interact ([`interact`]), both fitted without error, at least one
//! of them significant at the step (p < α/K) and neither the one the step names (the
//! candidates of a step are those not in the model: [`pairs_to_try`]), the two are fitted
//! jointly against the step's current model (one trust-region Newton fit of their
//! k = k_a + k_b parameters from their own fits at the step, [`crate::likelihood::joint`]),
//! and tested as a candidate is: Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄), p = P(χ²_k ≥ Λ), ΔBIC = λ̄·(k ln n − Λ).
//! With ΔBIC_d the step's decision's (the named candidate's, or 0 when it names nothing):
//!
//! - **named** when the pair is significant at the step's level α/K and
//!   ΔBIC ≤ ΔBIC_d − 2: both effects enter the model at the step in place of the named one
//!   (which stays a candidate for later steps), and the update re-fits every effect
//!   jointly and tests the earlier ones for removal as for a single effect
//!   ([`crate::selection::update`]); the step's adjusted p-value is min(1, K·p) of the pair;
//! - an **alternative reading** when a single effect is named and the pair's ΔBIC is
//!   within 2 of it (ΔBIC < ΔBIC_d + 2): the pair, written `a + b`, is listed beside the
//!   candidates indistinguishable from the named one;
//! - otherwise nothing changes, and the step's reason says how the pair fitted.
//!
//! The cost is bounded: a pair is fitted at most once per step, and only under the trigger
//! (one member significant, so the pair has something to build on; neither named, since a
//! named member's partner is tested given it at the next step). Of several pairs that
//! trigger, the one with the lowest ΔBIC is judged.

use crate::candidates::candidate::{Candidate, interact};
use crate::likelihood::joint::{Combined, joint_fit};
use crate::likelihood::score::{CandidateScore, Evaluator, FittedParameter, Test, p_is, score_of};
use crate::selection::decide::{DELTA_BIC, Decision, Verdict};
use serde::Serialize;
use std::time::Instant;

/// What became of a pair fitted jointly at a step (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PairOutcome {
    /// Significant and better than the step's decision by ΔBIC ≤ −2: both effects enter.
    Named,
    /// Within ΔBIC 2 of the named effect: listed as an alternative reading.
    Alternative,
    /// Neither: the step's decision stands.
    NotBetter,
}

/// A pair of interacting candidates fitted jointly against a step's current model.
#[derive(Debug, Clone, Serialize)]
pub struct PairScore {
    /// The two candidates' names, in the step's order.
    pub effects: [String; 2],
    /// Their indices among the step's candidates.
    #[serde(skip)]
    pub members: [usize; 2],
    /// k = k_a + k_b.
    pub k: usize,
    /// Each member's fitted parameters with the joint fit's 95 % Wald intervals.
    pub parameters: Vec<Vec<FittedParameter>>,
    /// ℓ̂ of the joint fit.
    pub log_likelihood: f64,
    /// Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄) against the step's current model.
    pub lr_statistic: f64,
    /// λ̄ = max(1, tr(A⁻¹B)/k).
    pub adjustment: f64,
    /// P(χ²_k ≥ Λ).
    pub p_value: f64,
    /// Whether p < α/K, the step's level.
    pub significant: bool,
    /// ΔBIC = λ̄·(k ln n − Λ) against the step's current model.
    pub delta_bic: f64,
    /// ΔBIC of the step's decision it was judged against: the named candidate's, 0 when
    /// the step named nothing.
    pub decision_delta_bic: f64,
    /// What became of it.
    pub outcome: PairOutcome,
    /// Simulations of the joint fit.
    pub evaluations: usize,
    /// Wall time of the joint fit \[s\].
    pub seconds: f64,
}

impl PairScore {
    /// The pair as the reports list it beside single effects: `a + b`.
    pub fn label(&self) -> String {
        label(&self.effects[0], &self.effects[1])
    }
}

/// A pair's name in the reports: `a + b`.
pub fn label(a: &str, b: &str) -> String {
    format!("{a} + {b}")
}

/// The pairs of a step's candidates to fit jointly (module doc): i < j interacting
/// (`interacting(i, j)`), both fitted without error, at least one significant, neither
/// `named`.
pub fn pairs_to_try(
    scores: &[CandidateScore],
    interacting: &dyn Fn(usize, usize) -> bool,
    named: Option<usize>,
) -> Vec<[usize; 2]> {
    let open = |i: usize| Some(i) != named && scores[i].error.is_none();
    let mut pairs = Vec::new();
    for i in 0..scores.len() {
        for j in i + 1..scores.len() {
            if open(i)
                && open(j)
                && (scores[i].significant || scores[j].significant)
                && interacting(i, j)
            {
                pairs.push([i, j]);
            }
        }
    }
    pairs
}

/// The outcome of a pair of ΔBIC `delta_bic`, significant or not at the step's level,
/// against the step's decision of ΔBIC `decision` (the named candidate's, if `named`, else
/// 0): named when significant and lower by at least 2, an alternative reading when a single
/// effect is named and it is within 2 of it, else not better.
pub fn judge(significant: bool, delta_bic: f64, decision: f64, named: bool) -> PairOutcome {
    let decision = if named { decision } else { 0.0 };
    if significant && delta_bic <= decision - DELTA_BIC {
        PairOutcome::Named
    } else if named && delta_bic < decision + DELTA_BIC {
        PairOutcome::Alternative
    } else {
        PairOutcome::NotBetter
    }
}

/// The step's decision with the pair's outcome (module doc): when the pair is named, its
/// first member becomes the named candidate, the verdict `named` and the reason says why,
/// the candidates indistinguishable are those within ΔBIC 2 of the pair, and the second
/// member is returned (it enters with the first); otherwise the reason gains a clause on
/// the pair, and `None`.
pub fn settle(d: &mut Decision, pair: &PairScore, scores: &[CandidateScore]) -> Option<usize> {
    let [a, b] = &pair.effects;
    let fit = format!(
        "{a} and {b} fitted together (their effects interact) improve the likelihood by Λ = {:.1} ({}, k = {}), ΔBIC = {:.1}",
        pair.lr_statistic,
        p_is(pair.p_value),
        pair.k,
        pair.delta_bic
    );
    match pair.outcome {
        PairOutcome::Named => {
            let instead = match d.named {
                Some(i) => format!(
                    ", lower by at least {DELTA_BIC} than {} alone (ΔBIC = {:.1})",
                    scores[i].name, scores[i].delta_bic
                ),
                None => format!(", at least {DELTA_BIC} below the current model's"),
            };
            d.reason = format!(
                "{fit}{instead}, and significant (< α/K): the two act together and are named as a pair (alone: {a} ΔBIC = {:.1}, {b} ΔBIC = {:.1}; before: {})",
                scores[pair.members[0]].delta_bic, scores[pair.members[1]].delta_bic, d.reason
            );
            d.verdict = Verdict::Named;
            d.named = Some(pair.members[0]);
            d.indistinguishable = (0..scores.len())
                .filter(|&j| {
                    !pair.members.contains(&j)
                        && scores[j].error.is_none()
                        && scores[j].delta_bic < pair.delta_bic + DELTA_BIC
                })
                .collect();
            Some(pair.members[1])
        }
        PairOutcome::Alternative => {
            d.reason += &format!(
                "; {fit}, within {DELTA_BIC} of the named one: an alternative reading the data cannot tell from it"
            );
            None
        }
        PairOutcome::NotBetter => {
            d.reason += &format!(
                "; {fit}: not better than the step's decision by the rule (significant and ΔBIC lower by {DELTA_BIC})"
            );
            None
        }
    }
}

/// The pairs of a step's `candidates` (scored in `scores`, `named` the step's decision) to
/// fit jointly ([`pairs_to_try`] with the candidates' declared interactions).
pub(crate) fn pairs_of(
    candidates: &[Box<dyn Candidate>],
    scores: &[CandidateScore],
    named: Option<usize>,
) -> Vec<[usize; 2]> {
    pairs_to_try(
        scores,
        &|i, j| interact(candidates[i].as_ref(), candidates[j].as_ref()),
        named,
    )
}

/// The step's `pairs` ([`pairs_of`]), each fitted once jointly against the current model
/// (`ev`, `test`: the step's) from the members' own fits, and the one of lowest ΔBIC
/// judged against the step's decision `named`; `None` when every joint fit failed.
pub(crate) fn consider(
    ev: &Evaluator,
    candidates: &[Box<dyn Candidate>],
    pairs: &[[usize; 2]],
    scores: &[CandidateScore],
    named: Option<usize>,
    test: &Test,
    note: &dyn Fn(&str),
) -> Option<PairScore> {
    let decision = named.map_or(0.0, |i| scores[i].delta_bic);
    let mut best: Option<PairScore> = None;
    for &[i, j] in pairs {
        let (a, b) = (candidates[i].as_ref(), candidates[j].as_ref());
        note(&format!(
            "fitting {} jointly (their effects interact)…",
            label(a.name(), b.name())
        ));
        let clock = Instant::now();
        let before = ev.simulations.get();
        let values =
            |k: usize| -> Vec<f64> { scores[k].parameters.iter().map(|p| p.value).collect() };
        let (va, vb) = (values(i), values(j));
        let fit = match joint_fit(ev, &[(a, &va), (b, &vb)], None, test.level) {
            Ok(f) => f,
            Err(e) => {
                note(&format!("  the joint fit failed ({e})"));
                continue;
            }
        };
        let s = score_of(&Combined::new(vec![a, b]), &fit.fit, test);
        let pair = PairScore {
            effects: [a.name().into(), b.name().into()],
            members: [i, j],
            k: s.k,
            parameters: fit.parameters,
            log_likelihood: s.log_likelihood,
            lr_statistic: s.lr_statistic,
            adjustment: s.adjustment,
            p_value: s.p_value,
            significant: s.significant,
            delta_bic: s.delta_bic,
            decision_delta_bic: decision,
            outcome: judge(s.significant, s.delta_bic, decision, named.is_some()),
            evaluations: ev.simulations.get() - before,
            seconds: clock.elapsed().as_secs_f64(),
        };
        note(&format!(
            "  {}: ΔBIC {:.1} (the step's decision {decision:.1}), Λ {:.1}, {}, {} simulations in {:.1} s: {:?}",
            pair.label(),
            pair.delta_bic,
            pair.lr_statistic,
            p_is(pair.p_value),
            pair.evaluations,
            pair.seconds,
            pair.outcome
        ));
        if best.as_ref().is_none_or(|b| pair.delta_bic < b.delta_bic) {
            best = Some(pair);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comparison::statistics::Comparison;
    use crate::selection::decide::decide;

    fn score(name: &str, k: usize, delta_bic: f64, significant: bool) -> CandidateScore {
        CandidateScore::of_test(name, k, delta_bic, significant)
    }

    fn pair(members: [usize; 2], delta_bic: f64, significant: bool, decision: f64) -> PairScore {
        PairScore {
            effects: ["backlash".into(), "diagonal_pretension".into()],
            members,
            k: 3,
            parameters: Vec::new(),
            log_likelihood: 0.0,
            lr_statistic: 0.0,
            adjustment: 1.0,
            p_value: if significant { 1e-6 } else { 0.5 },
            significant,
            delta_bic,
            decision_delta_bic: decision,
            outcome: judge(significant, delta_bic, decision, true),
            evaluations: 0,
            seconds: 0.0,
        }
    }

    /// The trigger: the interacting pair {0, 2} is tried when one of the two is
    /// significant and neither is named; not when neither is significant, when one is
    /// named, when a fit failed, nor for candidates that do not interact ({0, 1}).
    #[test]
    fn a_pair_is_tried_when_one_member_is_significant_and_neither_named() {
        let interacting = |i: usize, j: usize| (i, j) == (0, 2);
        let s = [
            score("backlash", 2, 3.0, true),
            score("length_bias", 3, -20.0, true),
            score("diagonal_pretension", 1, 1.0, false),
        ];
        assert_eq!(pairs_to_try(&s, &interacting, Some(1)), [[0, 2]]);
        assert_eq!(pairs_to_try(&s, &interacting, None), [[0, 2]]);
        assert!(pairs_to_try(&s, &interacting, Some(0)).is_empty());
        assert!(pairs_to_try(&s, &interacting, Some(2)).is_empty());
        let mut quiet = s.clone();
        quiet[0].significant = false;
        assert!(pairs_to_try(&quiet, &interacting, Some(1)).is_empty());
        let mut failed = s.clone();
        failed[2].error = Some("no solution".into());
        assert!(pairs_to_try(&failed, &interacting, Some(1)).is_empty());
        assert!(pairs_to_try(&s, &|_, _| false, Some(1)).is_empty());
    }

    /// The rule's three outcomes against a named effect of ΔBIC −20: a significant pair at
    /// −22 (2 lower) is named, at −21.9 it is not but is within 2, so an alternative
    /// reading, as is one at −18.1; at −18 (2 above) it is not better. A pair at −30 that
    /// is not significant at the step's level is not named, however low its ΔBIC. With
    /// nothing named the decision is the current model (ΔBIC 0): a significant pair at −2
    /// is named, one at −1.9 is not, and never an alternative reading.
    #[test]
    fn the_pair_is_judged_against_the_steps_decision() {
        use PairOutcome::*;
        assert_eq!(judge(true, -22.0, -20.0, true), Named);
        assert_eq!(judge(true, -21.9, -20.0, true), Alternative);
        assert_eq!(judge(true, -18.1, -20.0, true), Alternative);
        assert_eq!(judge(true, -18.0, -20.0, true), NotBetter);
        assert_eq!(judge(false, -30.0, -20.0, true), Alternative);
        assert_eq!(judge(true, -2.0, -20.0, false), Named);
        assert_eq!(judge(true, -1.9, -20.0, false), NotBetter);
        assert_eq!(judge(false, -9.0, 0.0, false), NotBetter);
    }

    /// The case on constructed scores: a length bias is named (ΔBIC −20), backlash
    /// alone is significant but worse (−8), the pretension alone is not (+1). The pair
    /// {backlash, pretension} at −26 replaces the bias: backlash named, the pretension its
    /// partner, the verdict `named`; thermal (−19), indistinguishable from the bias, is
    /// 7 above the pair and no longer listed. At −19 the bias stays named and the reason
    /// calls the pair an alternative reading.
    #[test]
    fn a_better_pair_replaces_the_named_effect_and_a_close_one_is_an_alternative() {
        let s = [
            score("backlash", 2, -8.0, true),
            score("length_bias", 3, -20.0, true),
            score("thermal_gradient", 4, -19.0, true),
            score("diagonal_pretension", 1, 1.0, false),
        ];
        let refs: Vec<&CandidateScore> = s.iter().collect();
        let before = Comparison::of_energy(0.0, 1.0, 0.0);
        let mut d = decide(&refs, &before, 200, 0.01, &|_, _| 4.0);
        assert_eq!((d.named, &d.indistinguishable[..]), (Some(1), &[2][..]));
        let named = pair([0, 3], -26.0, true, -20.0);
        assert_eq!(named.outcome, PairOutcome::Named);
        assert_eq!(named.label(), "backlash + diagonal_pretension");
        assert_eq!(settle(&mut d, &named, &s), Some(3));
        assert_eq!((d.verdict, d.named), (Verdict::Named, Some(0)));
        assert!(d.indistinguishable.is_empty());
        assert!(
            d.reason.contains("named as a pair") && d.reason.contains("length_bias alone"),
            "{}",
            d.reason
        );
        let mut d = decide(&refs, &before, 200, 0.01, &|_, _| 4.0);
        let close = pair([0, 3], -19.0, true, -20.0);
        assert_eq!(close.outcome, PairOutcome::Alternative);
        assert_eq!(settle(&mut d, &close, &s), None);
        assert_eq!(d.named, Some(1));
        assert!(d.reason.contains("alternative reading"), "{}", d.reason);
    }
}
