//! `diagnosis.md`: the diagnosis for people. It opens with the answer ([`Answer`]: what is
//! missing and how large, what cannot be told apart or could not have been seen, what to
//! measure next), then shows how it was reached, section by section: the verdict's reason
//! and the fitted values in full, the data read, where the baseline disagrees with the
//! measurements, each step of the selection, the updated job, the baseline against the
//! final model, the plots and the method.

use super::answer::Answer;
use super::method::METHOD;
use super::wording::{code_list, effect, g, parameter_text, plain_reading, push, spans};
use crate::comparison::baseline::Baseline;
use crate::comparison::measured::Measured;
use crate::likelihood::score::p_is;
use crate::selection::Diagnosis;
use crate::selection::confound::WIDENED;
use crate::selection::decide::Verdict;
use discrepancy::{before_after_section, disagreement_section, step_section};

mod discrepancy;

/// diagnosis.md, opening with `answer` (the one [`Answer::of`] `d`).
pub fn markdown(
    baseline: &Baseline,
    measured: &Measured,
    d: &Diagnosis,
    answer: &Answer,
    plots: &[String],
) -> String {
    let mut m = String::new();
    push(
        &mut m,
        &format!(
            "# Diagnosis of case `{}` against the measurements\n",
            baseline.case_name
        ),
    );
    answer_section(&mut m, answer);
    verdict_section(&mut m, baseline, d);
    data_section(&mut m, baseline, measured, d);
    disagreement_section(&mut m, d);
    for s in &d.steps {
        step_section(&mut m, baseline, d, s);
    }
    for (n, why) in &d.skipped {
        push(&mut m, &format!("- `{n}` not tried: {why}."));
    }
    if !d.skipped.is_empty() {
        push(&mut m, "");
    }
    updated_job_section(&mut m, baseline, d);
    before_after_section(&mut m, d);
    method_section(&mut m, d, plots);
    m
}

/// The answer's lines: the verdict, then the list.
fn answer_section(m: &mut String, answer: &Answer) {
    let (verdict, list) = answer
        .lines
        .split_first()
        .expect("an answer has its verdict line");
    push(m, &format!("{verdict}\n"));
    for l in list {
        push(m, l);
    }
    push(m, "");
}

/// How the verdict was reached, and the fitted values in full.
fn verdict_section(m: &mut String, baseline: &Baseline, d: &Diagnosis) {
    push(m, "## How the diagnosis reached it\n");
    let named = d.named_effects();
    push(
        m,
        &format!(
            "{}.\n",
            if named.is_empty() {
                "No effect added".to_string()
            } else {
                format!("Effects added, in order: {}", code_list(&named, ", then "))
            }
        ),
    );
    push(m, &format!("{}.\n", d.reason.trim_end_matches('.')));
    unseen_section(m, baseline, d);
    let span = spans(baseline);
    for e in &d.final_fit {
        let c = effect(d, &e.name);
        let step = d
            .steps
            .iter()
            .filter(|s| s.kept)
            .find(|s| s.named_effects().contains(&e.name.as_str()));
        let joint = d.final_fit.len() > 1
            || step.is_none_or(|s| {
                s.named_score().is_none_or(|n| {
                    n.parameters
                        .iter()
                        .zip(&e.parameters)
                        .any(|(a, b)| a.value != b.value)
                })
            });
        push(
            m,
            &format!(
                "Fitted `{}` ({}{}):\n",
                e.name,
                step.map_or("swapped in".to_string(), |s| format!(
                    "named in step {}",
                    s.number
                )),
                if joint {
                    "; the final model's effects fitted jointly, with that fit's intervals"
                } else {
                    ""
                }
            ),
        );
        for (j, p) in e.parameters.iter().enumerate() {
            let rivals: Vec<&String> = d
                .confounding
                .iter()
                .filter(|k| k.effect == e.name && k.parameters.iter().any(|q| q.name == p.name))
                .map(|k| &k.rival)
                .collect();
            push(
                m,
                &format!(
                    "- {}: {}{}",
                    parameter_text(c, j, p),
                    plain_reading(c, j, p, span),
                    if rivals.is_empty() {
                        String::new()
                    } else {
                        format!(
                            "; confounded with {} (below): this reading holds only without {}",
                            code_list(&rivals, " and "),
                            if rivals.len() == 1 { "it" } else { "them" }
                        )
                    }
                ),
            );
        }
        push(m, "");
    }
    confounding_section(m, d);
}

/// What the data could not have seen: the smallest effect of each candidate not in the
/// final model that its test would have detected with 80 % power, with its hardware reading.
fn unseen_section(m: &mut String, baseline: &Baseline, d: &Diagnosis) {
    let Some(first) = d.unseen.first() else {
        return;
    };
    push(
        m,
        &format!(
            "**Could not have been seen** with these {} specimens (each candidate not in the final model: the smallest effect its test in step {} would have detected with 80 % power, at that test's level α_K, its most visible parameter, the others at their null){}:\n",
            first.specimens,
            first.step,
            if d.verdict == Verdict::None {
                "; no effect above these sizes is missing"
            } else {
                ""
            }
        ),
    );
    let span = spans(baseline);
    for u in &d.unseen {
        let c = effect(d, &u.name);
        let reading = u
            .limit
            .as_ref()
            .and_then(|l| l.most_visible.map(|j| (j, &l.parameters[j])))
            .and_then(|(j, p)| p.value.map(|v| c.reading(j, v, span)))
            .map_or(String::new(), |r| format!(" (at that size: {r})"));
        push(m, &format!("- {}{reading}", u.words(c)));
    }
    push(m, "");
}

/// What the data cannot tell apart within the final model: each rival confounded with an
/// effect's parameters, and the measurement that would separate them.
fn confounding_section(m: &mut String, d: &Diagnosis) {
    for c in &d.confounding {
        push(
            m,
            &format!(
                "**Cannot be told apart: `{}` and `{}`.** With `{}` added and every effect fitted jointly{}, {} of `{}` {} confounded with it: {}; `{}` given the model: Λ = {:.1}, {}, ΔBIC = {:.1}. These data cannot say how that part of the signal divides between the two, so the values above are one reading of it. What would separate them: {}.\n",
                c.effect,
                c.rival,
                c.rival,
                if c.along_ridge {
                    " from along the flat direction the two share (the joint maximum itself moves nothing)"
                } else {
                    ""
                },
                code_list(
                    &c.parameters.iter().map(|p| &p.name).collect::<Vec<_>>(),
                    ", "
                ),
                c.effect,
                if c.parameters.len() == 1 { "is" } else { "are" },
                c.parameters
                    .iter()
                    .map(|p| {
                        if p.moved && c.along_ridge {
                            format!(
                                "`{}` fits as well at {} {} as at {}, outside its interval",
                                p.name,
                                g(p.with_rival),
                                p.unit,
                                g(p.value)
                            )
                        } else if p.moved && p.widening >= WIDENED {
                            format!(
                                "`{}` moves from {} to {} {}, outside its interval, which widens {:.1}-fold",
                                p.name,
                                g(p.value),
                                g(p.with_rival),
                                p.unit,
                                p.widening
                            )
                        } else if p.moved {
                            format!(
                                "`{}` moves from {} to {} {}, outside its interval",
                                p.name,
                                g(p.value),
                                g(p.with_rival),
                                p.unit
                            )
                        } else {
                            format!(
                                "`{}`'s interval widens {:.1}-fold ({} to {} {})",
                                p.name,
                                p.widening,
                                g(p.value),
                                g(p.with_rival),
                                p.unit
                            )
                        }
                    })
                    .collect::<Vec<_>>()
                    .join("; "),
                c.rival,
                c.lr_statistic,
                p_is(c.p_value),
                c.delta_bic,
                c.separate_by
            ),
        );
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
                format!(" (first: {})", r.first_left_out())
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
    for c in &r.checks {
        push(
            m,
            &format!("**Warning (data check `{}`):** {}.\n", c.check, c.words),
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
                code_list(&named, " and "),
                baseline.case_name
            )
        },
    );
    let undetermined: Vec<String> =
        d.final_fit
            .iter()
            .flat_map(|e| {
                e.parameters.iter().filter(|p| !p.determined).map(move |p| {
                    format!("`{}` of `{}` ({} {})", p.name, e.name, g(p.value), p.unit)
                })
            })
            .collect();
    if !undetermined.is_empty() {
        push(
            m,
            &format!(
                "Not determined by these data: {}. The updated job holds the best-fitting value, but the data leave most of the plausible range open: treat it as unknown.\n",
                undetermined.join(", ")
            ),
        );
    }
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
