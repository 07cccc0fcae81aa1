//! `diagnosis.md`'s account of the discrepancy between the model and the measurements:
//! where the baseline disagrees, what each step of the selection tried, named, re-fitted
//! and removed and how much of the gap it closed, and the baseline against the final model
//! statistic by statistic, with what still disagrees.

use crate::comparison::baseline::Baseline;
use crate::comparison::statistics::Statistic;
use crate::likelihood::score::{CandidateScore, FittedParameter};
use crate::likelihood::score::{p_is, p_text};
use crate::report::wording::{
    code_list, effect, g, interval_text, parameter_text, plain_reading, push, spans,
};
use crate::selection::Diagnosis;
use crate::selection::pair::PairOutcome;
use crate::selection::step::Step;

/// A statistic's row: id, unit, measured, simulated, comparison with its interval, verdict.
fn statistic_cells(s: &Statistic) -> String {
    let (what, value, iv) = if s.kind == "energy" {
        (
            "energy distance (standardised)".to_string(),
            g(s.estimate.value),
            format!("permutation {}", p_is(s.p_value)),
        )
    } else {
        (
            s.comparison.to_string(),
            g(s.estimate.value),
            interval_text(s.estimate.lower, s.estimate.upper),
        )
    };
    format!(
        "{} | {what} {value} {iv} | {}",
        if s.kind == "energy" {
            "—".into()
        } else {
            g(s.simulated)
        },
        if s.disagrees {
            "**disagrees**"
        } else {
            "agrees"
        }
    )
}

/// The label of a statistic's row with its unit.
fn statistic_label(s: &Statistic) -> String {
    if s.kind == "energy" {
        "energy distance of the displacement vectors".into()
    } else {
        format!("{} [{}]", s.id, s.unit)
    }
}

/// `## Where the baseline and the measurements disagree`.
pub(super) fn disagreement_section(m: &mut String, d: &Diagnosis) {
    push(m, "## Where the baseline and the measurements disagree\n");
    let mut flagged: Vec<&Statistic> = d.before.statistics.iter().filter(|s| s.disagrees).collect();
    flagged.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
    if flagged.is_empty() {
        push(m, "No statistic disagrees (Holm-adjusted p < 0.025).\n");
    } else {
        push(
            m,
            &format!(
                "{} of {} statistics disagree (Holm-adjusted p < 0.025); the strongest:\n",
                flagged.len(),
                d.before.statistics.len()
            ),
        );
        for s in flagged.iter().take(12) {
            push(m, &format!("- {} ({})", s.words, p_is(s.p_value)));
        }
        push(m, "");
    }
    push(
        m,
        &format!(
            "Tolerance ({}): {}.\n",
            d.before.tolerance.bands,
            if d.before.tolerance.within {
                "the baseline is within it".to_string()
            } else {
                format!("not shown for {}", d.before.tolerance.outside.join(", "))
            }
        ),
    );
}

/// `## Step s`: the candidates against the current model, the decision, the fit, and the
/// discrepancy before and after.
pub(super) fn step_section(m: &mut String, baseline: &Baseline, d: &Diagnosis, s: &Step) {
    let named = code_list(&s.named_effects(), " and ");
    let title = match (s.named_effect(), s.kept) {
        (Some(_), true) => format!("{named} added"),
        (Some(_), false) => format!("{named} named but not kept"),
        (None, _) => "nothing more to add".into(),
    };
    push(m, &format!("## Step {}: {title}\n", s.number));
    push(
        m,
        &format!(
            "Against the {} model (ℓ = {:.1}): {}.\n",
            if s.number == 1 { "baseline" } else { "current" },
            s.log_likelihood_before,
            s.reason.trim_end_matches('.')
        ),
    );
    push(
        m,
        "| candidate | k | ℓ | Λ | p | ΔBIC | Vuong z | fitted |\n|---|---|---|---|---|---|---|---|",
    );
    let mut order: Vec<&CandidateScore> = s.candidates.iter().collect();
    order.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    for c in order {
        let effect = effect(d, &c.name);
        push(
            m,
            &format!(
                "| {}{} | {} | {:.1} | {:.1} | {} | {:.1} | {} | {} |",
                c.name,
                if c.significant { " *" } else { "" },
                c.k,
                c.log_likelihood,
                c.lr_statistic,
                p_text(c.p_value),
                c.delta_bic,
                c.vuong_z.map_or(String::new(), |z| format!("{z:.2}")),
                c.error.clone().unwrap_or_else(|| c
                    .parameters
                    .iter()
                    .enumerate()
                    .map(|(j, p)| parameter_text(effect, j, p))
                    .collect::<Vec<_>>()
                    .join("; "))
            ),
        );
    }
    push(
        m,
        "\n\\* significant at 0.025/K (Bonferroni over this step's K candidates at α/2). ℓ, Λ and ΔBIC are dimensionless; ΔBIC against the model of this step's start (negative: better). Vuong z: how much closer the named effect fits than this one (below 1.96: not significantly).\n",
    );
    if let Some(p) = &s.pair {
        push(
            m,
            &format!(
                "Fitted jointly, because their effects interact: `{}`, k = {}, Λ = {:.1}, {}, ΔBIC = {:.1} against the step's decision's {:.1}: {}.\n",
                p.label(),
                p.k,
                p.lr_statistic,
                p_is(p.p_value),
                p.delta_bic,
                p.decision_delta_bic,
                match p.outcome {
                    PairOutcome::Named => "named as a pair (both enter the model)",
                    PairOutcome::Alternative =>
                        "an alternative reading, within ΔBIC 2 of the named effect",
                    PairOutcome::NotBetter => "not better than the step's decision",
                }
            ),
        );
    }
    let entered: Vec<(&str, &[FittedParameter])> = match (&s.pair, s.partner) {
        (Some(p), Some(_)) => p
            .effects
            .iter()
            .map(String::as_str)
            .zip(p.parameters.iter().map(Vec::as_slice))
            .collect(),
        _ => s
            .named_score()
            .map(|c| (c.name.as_str(), c.parameters.as_slice()))
            .into_iter()
            .collect(),
    };
    if !entered.is_empty() {
        let span = spans(baseline);
        for (name, parameters) in entered {
            let effect = effect(d, name);
            for (j, p) in parameters.iter().enumerate() {
                push(
                    m,
                    &format!(
                        "- {}: {}",
                        parameter_text(effect, j, p),
                        plain_reading(effect, j, p, span)
                    ),
                );
            }
        }
        push(m, "");
    }
    if !s.refitted.is_empty() {
        push(
            m,
            "The model's effects re-fitted jointly (95 % Wald intervals of the joint fit):\n",
        );
        for c in &s.refitted {
            let effect = effect(d, &c.name);
            push(
                m,
                &format!(
                    "- `{}`: {}",
                    c.name,
                    c.parameters
                        .iter()
                        .enumerate()
                        .map(|(j, p)| parameter_text(effect, j, p))
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            );
        }
        push(m, "");
    }
    for r in &s.removed {
        if let Some(by) = &r.replaced_by {
            push(
                m,
                &format!(
                    "**Replaced: `{}`** (added in step {}) by `{by}`: with the other effects, re-fitted jointly, the model fits better with `{by}` in its place (ΔBIC = {:.1}; 2Δℓ/c = {:.1}). What would confirm it: {}.\n",
                    r.name, r.added_in_step, r.delta_bic, r.lr_statistic, r.separate_by
                ),
            );
            continue;
        }
        push(
            m,
            &format!(
                "**Removed: `{}`** (added in step {}): given the other effects, re-fitted jointly, it no longer improves the fit (Λ = {:.1}, {}, ΔBIC = {:.1}).{}\n",
                r.name,
                r.added_in_step,
                r.lr_statistic,
                p_is(r.p_value.unwrap_or(1.0)),
                r.delta_bic,
                r.explained_by.as_ref().map_or(String::new(), |x| format!(
                    " `{x}` took over what it explained: on these data the two are indistinguishable, and the answer names `{x}`. What would separate them: {}.",
                    r.separate_by
                ))
            ),
        );
    }
    let after = s.after.as_ref().map_or(s.before.energy, |a| a.energy);
    push(
        m,
        &format!(
            "Discrepancy (energy distance, standardised): {:.4} before this step, {:.4} after{}.\n",
            s.before.energy,
            after,
            if s.after.is_some() && s.before.energy > 0.0 {
                format!(
                    " ({:.0} % of it closed)",
                    100.0 * (1.0 - after / s.before.energy)
                )
            } else {
                String::new()
            }
        ),
    );
}

/// `## Before and after`: the baseline against the final model, statistic by statistic, and
/// what still disagrees.
pub(super) fn before_after_section(m: &mut String, d: &Diagnosis) {
    push(m, "## Before and after, all steps together\n");
    let after_e = d.after.as_ref().map_or(d.before.energy, |a| a.energy);
    push(
        m,
        &format!(
            "Overall discrepancy (energy distance, standardised; 0 when the distributions agree): baseline {:.4} (permutation {}), final model {:.4}{}.\n",
            d.before.energy,
            p_is(d.before.energy_p),
            after_e,
            d.after
                .as_ref()
                .map_or(" (no effect added)".to_string(), |a| format!(
                    " (permutation {}); {:.0} % of the gap closed",
                    p_is(a.energy_p),
                    100.0 * (1.0 - a.energy / d.before.energy)
                ))
        ),
    );
    push(
        m,
        "| statistic [unit] | measured | baseline: simulated | baseline: comparison [95 % CI] | | final: simulated | final: comparison [95 % CI] | |\n|---|---|---|---|---|---|---|---|",
    );
    let key = |s: &Statistic| {
        s.disagrees
            || s.kind == "percentile"
            || s.id.contains("piston")
            || s.id.contains("tan_theta")
            || s.kind == "ks"
            || s.kind == "energy"
    };
    for (i, s) in d.before.statistics.iter().enumerate() {
        if !key(s) && d.after.as_ref().is_none_or(|a| !a.statistics[i].disagrees) {
            continue;
        }
        let measured = if s.kind == "energy" {
            "—".into()
        } else {
            g(s.measured)
        };
        let after = d
            .after
            .as_ref()
            .map_or(" | | ".to_string(), |a| statistic_cells(&a.statistics[i]));
        push(
            m,
            &format!(
                "| {} | {measured} | {} | {after} |",
                statistic_label(s),
                statistic_cells(s)
            ),
        );
    }
    push(
        m,
        "\nEvery statistic, before and after, with its interval and p-value, is in `diagnosis.json`.\n",
    );
    let last = d.after.as_ref().unwrap_or(&d.before);
    let still: Vec<&Statistic> = last.statistics.iter().filter(|s| s.disagrees).collect();
    if still.is_empty() {
        push(
            m,
            "No statistic disagrees with the final model (Holm-adjusted p < 0.025).\n",
        );
    } else {
        push(m, "**Still disagreeing with the final model:**\n");
        for s in &still {
            push(m, &format!("- {} ({})", s.words, p_is(s.p_value)));
        }
        push(m, "");
    }
    let over: Vec<&Statistic> = last
        .statistics
        .iter()
        .filter(|s| s.kind == "percentile" && s.id != "p50 theta_p" && s.estimate.upper < 1.0)
        .collect();
    if !over.is_empty() {
        push(
            m,
            &format!(
                "**The final model over-predicts the tail of θ_P:** {} (measured against predicted, whole 95 % interval below 1): a budget from it is conservative there.\n",
                over.iter()
                    .map(|s| format!(
                        "{} ratio {} {}",
                        s.id,
                        g(s.estimate.value),
                        interval_text(s.estimate.lower, s.estimate.upper)
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
}
