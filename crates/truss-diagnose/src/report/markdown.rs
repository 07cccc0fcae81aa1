//! `diagnosis.md`: the diagnosis for people, section by section: the verdict and the
//! fitted values, the data read, where the baseline disagrees with the measurements, each
//! step of the selection, the updated job, the baseline against the final model, what to
//! measure or do next, the plots and the method.

use super::METHOD;
use super::wording::{g, interval_text, p_is, p_text, parameter_text, plain_reading, spans};
use crate::baseline::Baseline;
use crate::compare::Statistic;
use crate::diagnose::{CandidateScore, Diagnosis, FittedParameter, Verdict};
use crate::measured::Measured;
use crate::step::Step;

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

/// diagnosis.md.
pub fn markdown(
    baseline: &Baseline,
    measured: &Measured,
    d: &Diagnosis,
    plots: &[String],
) -> String {
    let mut m = String::new();
    verdict_section(&mut m, baseline, d);
    data_section(&mut m, baseline, measured, d);
    disagreement_section(&mut m, d);
    for s in &d.steps {
        step_section(&mut m, baseline, s);
    }
    for (n, why) in &d.skipped {
        push(&mut m, &format!("- `{n}` not tried: {why}."));
    }
    if !d.skipped.is_empty() {
        push(&mut m, "");
    }
    updated_job_section(&mut m, baseline, d);
    before_after_section(&mut m, d);
    next_step_section(&mut m, measured, d);
    method_section(&mut m, d, plots);
    m
}

/// Appends `s` and a newline.
fn push(m: &mut String, s: &str) {
    m.push_str(s);
    m.push('\n');
}

/// The title, the verdict and the fitted values.
fn verdict_section(m: &mut String, baseline: &Baseline, d: &Diagnosis) {
    push(
        m,
        &format!(
            "# Diagnosis of case `{}` against the measurements\n",
            baseline.case_name
        ),
    );
    let named = d.named_effects();
    push(
        m,
        &format!(
            "**Verdict: {}** — {}.\n",
            d.verdict.words(),
            if named.is_empty() {
                "no effect added".to_string()
            } else {
                format!(
                    "effects added, in order: {}",
                    named
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", then ")
                )
            }
        ),
    );
    push(m, &format!("{}.\n", d.reason.trim_end_matches('.')));
    let span = spans(baseline);
    for e in &d.effects {
        let Some((s, c)) = d
            .steps
            .iter()
            .filter(|s| s.kept)
            .find_map(|s| s.named_score().filter(|c| c.name == e.name).map(|c| (s, c)))
        else {
            // Swapped in: its values and intervals are those of the last joint fit.
            let fit = d
                .steps
                .iter()
                .filter(|s| s.kept)
                .flat_map(|s| &s.refitted)
                .rfind(|r| r.name == e.name);
            push(
                m,
                &format!("Fitted `{}` (swapped in; the last joint re-fit):\n", e.name),
            );
            for p in fit.map_or(&[][..], |f| &f.parameters) {
                push(
                    m,
                    &format!(
                        "- {}: {}",
                        parameter_text(p),
                        plain_reading(&e.name, p, span)
                    ),
                );
            }
            push(m, "");
            continue;
        };
        push(m, &format!("Fitted `{}` (step {}):\n", c.name, s.number));
        // The final value where a later step re-fitted it.
        let last = d
            .effects
            .iter()
            .find(|e| e.name == c.name)
            .map(|e| &e.parameters);
        for p in &c.parameters {
            let now = last
                .and_then(|ps| ps.iter().find(|q| q.0 == p.name))
                .map(|q| q.2)
                .filter(|&v| v != p.value);
            let reading = FittedParameter {
                value: now.unwrap_or(p.value),
                ..p.clone()
            };
            push(
                m,
                &format!(
                    "- {}{}: {}",
                    parameter_text(p),
                    now.map_or(String::new(), |v| format!(
                        "; {} {} after the later steps' re-fit",
                        g(v),
                        p.unit
                    )),
                    plain_reading(&c.name, &reading, span)
                ),
            );
        }
        push(m, "");
    }
}

/// `## Data`: what was read, and what was not used.
fn data_section(m: &mut String, baseline: &Baseline, measured: &Measured, d: &Diagnosis) {
    let r = &measured.report;
    push(m, "## Data\n");
    push(
        m,
        &format!(
            "{} rows from `{}`: {} specimens, {} used, {} left out for a missing node{}. Nodes compared: {}. Job `{}` (id {}), seed {}, N = {} simulated samples per evaluation.\n",
            r.rows,
            r.file,
            r.specimens_in_file,
            r.specimens_used,
            r.left_out_count,
            if r.left_out.is_empty() {
                String::new()
            } else {
                format!(
                    " (first: {})",
                    r.left_out
                        .iter()
                        .take(5)
                        .map(|(s, n)| format!("{s} lacks {}", n.join(" ")))
                        .collect::<Vec<_>>()
                        .join("; ")
                )
            },
            r.nodes.join(", "),
            baseline.path.display(),
            &baseline.job.id[..12],
            baseline.seed,
            d.samples
        ),
    );
    if !r.outliers.is_empty() {
        push(
            m,
            &format!(
                "Outliers left out ({}): {}.\n",
                r.outliers.len(),
                r.outliers
                    .iter()
                    .map(|o| o.words())
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
        );
    }
    if !r.unknown_nodes.is_empty() || !r.rare_nodes.is_empty() {
        push(
            m,
            &format!(
                "Ignored: unknown nodes [{}], nodes measured by fewer than half of the specimens [{}].\n",
                r.unknown_nodes.join(", "),
                r.rare_nodes.join(", ")
            ),
        );
    }
    if let Some(rows) = r.member_rows {
        push(
            m,
            &format!(
                "Member measurements: {rows} used, each specimen's own in its likelihood{}.\n",
                if r.unknown_members.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; unknown members ignored: {}",
                        r.unknown_members.join(", ")
                    )
                }
            ),
        );
    }
}

/// `## Where the baseline and the measurements disagree`.
fn disagreement_section(m: &mut String, d: &Diagnosis) {
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
fn step_section(m: &mut String, baseline: &Baseline, s: &Step) {
    let title = match (s.named_effect(), s.kept) {
        (Some(n), true) => format!("`{n}` added"),
        (Some(n), false) => format!("`{n}` named but not kept"),
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
                    .map(parameter_text)
                    .collect::<Vec<_>>()
                    .join("; "))
            ),
        );
    }
    push(
        m,
        "\n\\* significant at 0.025/K (Bonferroni over this step's K candidates at α/2). ℓ, Λ and ΔBIC are dimensionless; ΔBIC against the model of this step's start (negative: better). Vuong z: how much closer the named effect fits than this one (below 1.96: not significantly).\n",
    );
    if let Some(c) = s.named_score() {
        let span = spans(baseline);
        for p in &c.parameters {
            push(
                m,
                &format!(
                    "- {}: {}",
                    parameter_text(p),
                    plain_reading(&c.name, p, span)
                ),
            );
        }
        push(m, "");
    }
    if !s.refitted.is_empty() {
        push(
            m,
            "The model's effects re-fitted jointly (95 % Wald intervals of the joint fit):\n",
        );
        for c in &s.refitted {
            push(
                m,
                &format!(
                    "- `{}`: {}",
                    c.name,
                    c.parameters
                        .iter()
                        .map(parameter_text)
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

/// `## The updated job`.
fn updated_job_section(m: &mut String, baseline: &Baseline, d: &Diagnosis) {
    push(m, "## The updated job\n");
    let named = d.named_effects();
    push(
        m,
        &if named.is_empty() {
            "No effect was added: `updated-job.json` is the baseline job.\n".into()
        } else {
            format!(
                "`updated-job.json` is the baseline job with {} added to case `{}` at the fitted values; run it with mc-shard and mc-merge like any other job.\n",
                named
                    .iter()
                    .map(|n| format!("`{n}`"))
                    .collect::<Vec<_>>()
                    .join(" and "),
                baseline.case_name
            )
        },
    );
}

/// `## Before and after`: the baseline against the final model, statistic by statistic, and
/// what still disagrees.
fn before_after_section(m: &mut String, d: &Diagnosis) {
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

/// `## Next step`: what to measure or do next.
fn next_step_section(m: &mut String, measured: &Measured, d: &Diagnosis) {
    push(m, "## Next step\n");
    let mut advice = Vec::new();
    let joint_like = ["length_bias", "diagonal_pretension"];
    for s in &d.steps {
        let Some(named) = s.named_effect() else {
            continue;
        };
        let mixes_backlash = (named == "backlash"
            && s.indistinguishable
                .iter()
                .any(|o| joint_like.contains(&o.as_str())))
            || (joint_like.contains(&named) && s.indistinguishable.iter().any(|o| o == "backlash"));
        if mixes_backlash && measured.members.is_none() {
            advice.push(format!(
                "Step {}: `{named}` and {} fit the node positions equally well: joint free play shortens the truss much as a member-length error does. Measure the member lengths one by one (longerons and diagonals, to a few µm) and run again with `--measured-members`: then they separate.",
                s.number,
                s.indistinguishable
                    .iter()
                    .map(|n| format!("`{n}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        } else if !s.indistinguishable.is_empty() {
            advice.push(format!(
                "Step {}: `{named}` cannot be told from {} with these data; what would separate them: {}.",
                s.number,
                s.indistinguishable
                    .iter()
                    .map(|n| format!("`{n}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                s.indistinguishable
                    .iter()
                    .map(|n| format!(
                        "from `{n}`, {}",
                        crate::stepwise::separating_measurement(named, n)
                    ))
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
    }
    match d.verdict {
        Verdict::Named => advice.push(
            "Run `updated-job.json` with mc-shard and mc-merge for the precision budget with the effects added.".into(),
        ),
        Verdict::None => advice.push(
            "None needed: the baseline job's prediction stands for these trusses.".into(),
        ),
        Verdict::CannotTell => advice.push(format!(
            "Measure more specimens: with {} the data cannot decide; about four times as many halve the intervals.",
            measured.n()
        )),
        Verdict::Unexplained => advice.push(
            "Look for a mechanism outside the candidates (a support that moves, a member bent or damaged, the instrument's own error): measure the supports and the instrument against a reference.".into(),
        ),
    }
    if !measured.report.outliers.is_empty() {
        advice.push("Check the outlier rows listed under Data against the instrument's records; they were left out.".into());
    }
    for a in advice {
        push(m, &format!("- {a}"));
    }
    push(m, "");
}

/// The plots and `## Method`: how every number was found.
fn method_section(m: &mut String, d: &Diagnosis, plots: &[String]) {
    if !plots.is_empty() {
        push(m, "Plots:\n");
        for p in plots {
            push(m, &format!("- ![{p}]({p})"));
        }
        push(m, "");
    }
    push(m, "## Method\n");
    for (k, v) in [
        ("Likelihood", METHOD.likelihood),
        ("Fit", METHOD.fit),
        ("Intervals", METHOD.intervals),
        ("Selection", METHOD.selection),
        ("Steps", METHOD.steps),
        ("Verdicts", METHOD.verdicts),
        ("Statistics", METHOD.statistics),
        ("Discrepancy", METHOD.discrepancy),
    ] {
        push(m, &format!("- **{k}.** {v}"));
    }
    push(
        m,
        &format!(
            "\n{} simulations ({} solves) in {:.1} s; per step: {}.",
            d.work.0,
            d.work.1,
            d.work.2,
            d.steps
                .iter()
                .map(|s| format!("{} {:.1} s", s.number, s.seconds))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
}
