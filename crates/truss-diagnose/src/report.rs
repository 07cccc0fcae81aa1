//! `diagnosis.json` and `diagnosis.md`.
//!
//! ## diagnosis.json (format `truss-diagnose`, version 3)
//!
//! ```text
//! format, format_version, program_version
//! job {path, id, case, seed}, samples (N per simulation), measurement_sigma [mm]
//! data        {file, rows, specimens_in_file, specimens_used, left_out_count, left_out[],
//!              nodes[], unknown_nodes[], rare_nodes[], supports[], member_rows, unknown_members[]}
//! verdict     "named" | "none" | "cannot_tell" | "unexplained";  reason (words)
//! named_effect "none" or the effect's name
//! parameters  [{name, unit, value, interval, wald_interval, joint_interval?, range, null}]
//!              (the named effect's)
//!   interval   {lower, upper, lower_at_range_end, upper_at_range_end, method, threshold?}:
//!              method "profile" (2(ℓ̂ − ℓ_p) ≤ threshold) for the named effect and those
//!              indistinguishable from it, else "wald"; lower/upper null when not found;
//!              an end at the range end is the range's (the interval is cut there)
//!   joint_interval  where profiled: the joint 95 % region of all k parameters projected on
//!              this one (same fields, threshold χ²_k(0.95)·c·λ̄): every parameter inside its
//!              joint interval at once with 95 % confidence
//! indistinguishable [names]   (explain the data as well: ΔBIC within 2, or significant and
//!              not shown further from the data than the named one, Vuong z < 1.96; empty
//!              when clear)
//! baseline    {log_likelihood}
//! candidates  [{name, mechanism, k, parameters[], log_likelihood, lr_statistic, adjustment,
//!               p_value, significant, delta_bic, evaluations, profile_evaluations, seconds,
//!               vuong_z?, error?}]   (vuong_z: the named one's Vuong z against this one,
//!               for significant candidates when one is named)
//! skipped     [{name, reason}]
//! statistics  {before: Comparison, after: Comparison | null}
//!   Comparison {specimens, samples, energy, energy_p, tolerance {within, outside[], bands},
//!               statistics[] {id, kind, unit, measured, simulated, comparison, estimate
//!               {value, lower, upper}, p_value, p_holm, disagrees, words}}
//! discrepancy_before, discrepancy_after   (energy distance; after = before when no effect is added)
//! method      {likelihood, fit, intervals, selection, verdicts, statistics, discrepancy}
//!             (in words)
//! timing      {simulations, solves, seconds}
//! ```
//!
//! Version 3 (from 2): `candidates[].vuong_z`, and `indistinguishable` also lists
//! significant candidates the named one does not fit significantly better than (Vuong).
//!
//! Version 2 (from 1): intervals are profile-likelihood intervals for the named effect, with
//! the Wald interval beside them (`wald_interval`), the joint region's projection
//! (`joint_interval`), `method` and `threshold`; the one `at_range_end` flag became one per
//! end; `adjustment`, `profile_evaluations` and `method.intervals` are new; `delta_bic`
//! charges the misspecification adjustment λ̄ in the penalty (k·λ̄·ln n) instead of dividing
//! the likelihood ratio by it.

use crate::baseline::Baseline;
use crate::compare::{Comparison, Statistic};
use crate::diagnose::{CandidateScore, Diagnosis, FittedParameter, Verdict};
use crate::measured::{DataReport, Measured};
use serde::Serialize;

/// Format name.
pub const FORMAT: &str = "truss-diagnose";
/// Format version.
pub const FORMAT_VERSION: u32 = 3;

#[derive(Serialize)]
struct JobRef<'a> {
    path: String,
    id: &'a str,
    case: &'a str,
    seed: u64,
}

#[derive(Serialize)]
struct Statistics<'a> {
    before: &'a Comparison,
    after: Option<&'a Comparison>,
}

#[derive(Serialize)]
struct Skipped<'a> {
    name: &'a str,
    reason: &'a str,
}

#[derive(Serialize)]
struct Baseline0 {
    log_likelihood: f64,
}

#[derive(Serialize)]
struct Timing {
    simulations: usize,
    solves: usize,
    seconds: f64,
}

#[derive(Serialize)]
struct Method {
    likelihood: &'static str,
    fit: &'static str,
    intervals: &'static str,
    selection: &'static str,
    verdicts: &'static str,
    statistics: &'static str,
    discrepancy: &'static str,
}

/// The method, in words (also in the crate doc).
const METHOD: Method = Method {
    likelihood: "Gaussian synthetic likelihood of the specimens' displacement vectors at the compared coordinates: N(μ, Σ) with μ and Σ the mean and covariance of N simulated samples (common random numbers: same seed and case name as the baseline) plus (σ_m² + τ²)·I, τ = 0.1 µm; ℓ = Σ ln N(yᵢ; μ, Σ). With --measured-members, plus Σ ln N(e; E ε, Var ε + σ_m² + τ²) over the measured member length errors.",
    fit: "each candidate's ℓ maximised over its plausible range (log scale for σ, |g| ≤ 1 for gravity) from the best of its null (the baseline) and a scan along each parameter, by a trust-region Newton method on the unit cube; gradient, curvature A and score variability B by finite differences whose step along each parameter is adapted to the likelihood's own scale (the central second difference about one unit of ℓ, i.e. a step of about one standard error; 1e-7 to 0.05 of the range).",
    intervals: "95 % profile-likelihood intervals for the named effect and any indistinguishable from it: the values θ_j where 2(ℓ̂ − ℓ_p(θ_j)) ≤ χ²₁(0.95)·c·λ_j, ℓ_p the maximum over the other parameters, c = 1 + n/N for the simulation's own noise, λ_j = max(1, (A⁻¹BA⁻¹)_jj/(A⁻¹)_jj) for misspecification (Royall & Tsou 2003; the one-parameter form of the test's λ̄); ends found by safeguarded root-finding on √(2(ℓ̂ − ℓ_p)) with common random numbers, to 5 % in the threshold; an end that reaches the plausible range is cut there and flagged. For all k parameters at once, the joint 95 % region 2(ℓ̂ − ℓ(θ)) ≤ χ²_k(0.95)·c·λ̄ projected on each parameter (joint_interval; the same computation with that threshold). Every candidate also has the sandwich Wald interval t̂ ± 1.96·√(c·A⁻¹BA⁻¹) (wald_interval), which assumes ℓ quadratic; the verdict and checks use the profile interval.",
    selection: "likelihood-ratio statistic Λ = 2(ℓ − ℓ₀)/(c·λ̄) against the baseline, c = 1 + n/N, λ̄ = max(1, tr(A⁻¹B)/k); p = P(χ²_k ≥ Λ), significant when p < 0.05/K (Bonferroni over the K candidates); ΔBIC = k·λ̄·ln n − 2(ℓ − ℓ₀)/c = λ̄·(k ln n − Λ) (n specimens), the BIC of a misspecified likelihood whose penalty counts the effective number of parameters tr(A⁻¹B) = k·λ̄ (Gao & Song 2010), so that candidates' likelihoods are compared unscaled. Named: the candidate with the lowest ΔBIC if it is significant and ΔBIC ≤ −2; indistinguishable: other candidates with ΔBIC within 2 of it, and significant candidates the named one does not fit significantly closer than by Vuong's test for non-nested models, z = Σ_u d_u/√(c·n·var d) < 1.96 with d_u the difference of the two maximised ℓ's terms for specimen u (its member observations included) (Vuong 1989): BIC then prefers the named one, but by its penalty or by a difference in ℓ within the specimens' own scatter, not by a fit the data show to be closer. Significant means better than the baseline, not present: when the baseline misses some effect, any candidate that mimics part of it improves on the baseline, and BIC chooses between them.",
    verdicts: "named: as above. cannot_tell: some candidate improves the fit but not both significantly and by ΔBIC ≤ −2, or none improves it and the data cannot show the baseline agrees within tolerance. none: no candidate improves it and the baseline agrees within tolerance (every coordinate's mean within ±0.5 predicted SD, its SD and θ_P's median and 95th percentile within a factor 1.3, judged by their 95 % intervals). unexplained: no candidate improves it, yet the baseline disagrees (a Holm-significant statistic, with at least 30 specimens; with fewer, cannot_tell).",
    statistics: "per coordinate, piston (mean top z), tan θ_x, tan θ_y: mean difference (Welch interval), SD ratio (interval on ln with kurtosis-corrected variance), covariances (fourth-moment variance); θ_P percentiles 50/90/95/99 (Hyndman–Fan definition 1) as ratios with Poisson-bootstrap intervals (B = 1000); KS on θ_P; energy distance with a permutation test (R = 199). The simulation carries the instrument's noise. Disagrees: Holm-adjusted p < 0.05.",
    discrepancy: "energy distance (unbiased U-statistic, Székely & Rizzo 2004) between the measured and simulated displacement vectors, each coordinate divided by its measured SD: 0 when the distributions agree.",
};

#[derive(Serialize)]
struct Report<'a> {
    format: &'static str,
    format_version: u32,
    program_version: &'static str,
    job: JobRef<'a>,
    samples: usize,
    measurement_sigma: f64,
    data: &'a DataReport,
    verdict: Verdict,
    reason: &'a str,
    named_effect: &'a str,
    parameters: &'a [FittedParameter],
    indistinguishable: &'a [String],
    baseline: Baseline0,
    candidates: &'a [CandidateScore],
    skipped: Vec<Skipped<'a>>,
    statistics: Statistics<'a>,
    discrepancy_before: f64,
    discrepancy_after: f64,
    method: Method,
    timing: Timing,
}

/// The named effect's name, or `none`.
pub fn named_effect(d: &Diagnosis) -> &str {
    d.named.map_or("none", |i| d.candidates[i].name.as_str())
}

/// diagnosis.json.
pub fn json(baseline: &Baseline, measured: &Measured, d: &Diagnosis, sigma_m: f64) -> String {
    let report = Report {
        format: FORMAT,
        format_version: FORMAT_VERSION,
        program_version: env!("CARGO_PKG_VERSION"),
        job: JobRef {
            path: baseline.path.display().to_string(),
            id: &baseline.job.id,
            case: &baseline.case_name,
            seed: baseline.seed,
        },
        samples: d.samples,
        measurement_sigma: sigma_m,
        data: &measured.report,
        verdict: d.verdict,
        reason: &d.reason,
        named_effect: named_effect(d),
        parameters: d.named.map_or(&[][..], |i| &d.candidates[i].parameters),
        indistinguishable: &d.indistinguishable,
        baseline: Baseline0 {
            log_likelihood: d.baseline_log_likelihood,
        },
        candidates: &d.candidates,
        skipped: d
            .skipped
            .iter()
            .map(|(n, r)| Skipped { name: n, reason: r })
            .collect(),
        statistics: Statistics {
            before: &d.before,
            after: d.after.as_ref(),
        },
        discrepancy_before: d.before.energy,
        discrepancy_after: d.after.as_ref().map_or(d.before.energy, |a| a.energy),
        method: METHOD,
        timing: Timing {
            simulations: d.work.0,
            solves: d.work.1,
            seconds: d.work.2,
        },
    };
    let mut s = serde_json::to_string_pretty(&report).expect("the report serialises");
    s.push('\n');
    s
}

fn g(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if v.abs() >= 1e-3 && v.abs() < 1e4 {
        format!("{:.4}", v)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{v:.3e}")
    }
}

fn parameter_text(p: &FittedParameter) -> String {
    let i = &p.interval;
    let end = |v: Option<f64>| v.map_or("?".to_string(), g);
    // The joint region's projection, where it differs from the parameter's own interval
    // (k > 1).
    let joint = match &p.joint_interval {
        Some(j) if *j != p.interval && (j.lower.is_some() || j.upper.is_some()) => {
            format!("; all parameters jointly {}–{}", end(j.lower), end(j.upper))
        }
        _ => String::new(),
    };
    let iv = if i.lower.is_none() && i.upper.is_none() {
        format!(" (interval undetermined{joint})")
    } else {
        format!(
            " (95 % {} CI {}–{}{}{joint})",
            i.method,
            end(i.lower),
            end(i.upper),
            match (i.lower_at_range_end, i.upper_at_range_end) {
                (true, true) => ", both ends cut at the plausible range",
                (true, false) => ", lower end cut at the plausible range",
                (false, true) => ", upper end cut at the plausible range",
                (false, false) => "",
            }
        )
    };
    format!("{} = {} {}{iv}", p.name, g(p.value), p.unit)
}

fn statistic_row(s: &Statistic) -> String {
    format!(
        "| {} | {} | {} | {} {} [{}, {}] | {} |",
        s.id,
        g(s.measured),
        g(s.simulated),
        s.comparison,
        g(s.estimate.value),
        g(s.estimate.lower),
        g(s.estimate.upper),
        if s.disagrees {
            "**disagrees**"
        } else {
            "agrees"
        }
    )
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
    effect_section(&mut m, baseline, d);
    before_after_section(&mut m, d);
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
    push(
        m,
        &format!(
            "**Verdict: {}** — named effect: `{}`.\n",
            match d.verdict {
                Verdict::Named => "a missing effect is named",
                Verdict::None => "the baseline agrees; no effect is missing",
                Verdict::CannotTell => "the data cannot tell",
                Verdict::Unexplained => "the baseline disagrees, and no candidate explains it",
            },
            named_effect(d)
        ),
    );
    push(m, &format!("{}.\n", d.reason));
    if let Some(i) = d.named {
        let c = &d.candidates[i];
        push(
            m,
            &format!(
                "Fitted: {}.\n",
                c.parameters
                    .iter()
                    .map(parameter_text)
                    .collect::<Vec<_>>()
                    .join("; ")
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
                "Member measurements: {rows} used{}.\n",
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

/// `## 1.`: the statistics that disagree, before any effect is added.
fn disagreement_section(m: &mut String, d: &Diagnosis) {
    push(m, "## 1. Where simulation and measurement disagree\n");
    let mut flagged: Vec<&Statistic> = d.before.statistics.iter().filter(|s| s.disagrees).collect();
    flagged.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
    if flagged.is_empty() {
        push(m, "No statistic disagrees (Holm-adjusted p < 0.05).\n");
    } else {
        push(
            m,
            &format!(
                "{} of {} statistics disagree (Holm-adjusted p < 0.05); the strongest:\n",
                flagged.len(),
                d.before.statistics.len()
            ),
        );
        for s in flagged.iter().take(12) {
            push(m, &format!("- {} (p = {:.1e})", s.words, s.p_value));
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

/// `## 2.` and `## 3.`: the candidates, their fits and tests, and what was added.
fn effect_section(m: &mut String, baseline: &Baseline, d: &Diagnosis) {
    push(m, "## 2. Which effect\n");
    push(
        m,
        "| candidate | k | ℓ | Λ | p | ΔBIC | Vuong z | fitted |\n|---|---|---|---|---|---|---|---|",
    );
    push(
        m,
        &format!(
            "| baseline | 0 | {:.1} | | | 0 | | |",
            d.baseline_log_likelihood
        ),
    );
    let mut order: Vec<&CandidateScore> = d.candidates.iter().collect();
    order.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    for c in order {
        push(
            m,
            &format!(
                "| {}{} | {} | {:.1} | {:.1} | {:.2e} | {:.1} | {} | {} |",
                c.name,
                if c.significant { " *" } else { "" },
                c.k,
                c.log_likelihood,
                c.lr_statistic,
                c.p_value,
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
        "\n\\* significant at 0.05/K (Bonferroni). Vuong z: how much closer the named effect fits than this one (below 1.96: not significantly).\n",
    );
    for (n, why) in &d.skipped {
        push(m, &format!("- `{n}` not tried: {why}."));
    }
    push(m, "\n## 3. The updated job\n");
    push(
        m,
        &match d.named {
            Some(i) => format!(
                "`updated-job.json` is the baseline job with `{}` added to case `{}` at its fitted values; run it with mc-shard and mc-merge like any other job.\n",
                d.candidates[i].name, baseline.case_name
            ),
            None => "No effect was added: `updated-job.json` is the baseline job.\n".into(),
        },
    );
}

/// `## 4.`: the discrepancy before and after, statistic by statistic.
fn before_after_section(m: &mut String, d: &Diagnosis) {
    push(m, "## 4. Before and after\n");
    let after_e = d.after.as_ref().map_or(d.before.energy, |a| a.energy);
    push(
        m,
        &format!(
            "Overall discrepancy (energy distance, standardised): before {:.4} (p = {:.3}), after {:.4}{}.\n",
            d.before.energy,
            d.before.energy_p,
            after_e,
            d.after
                .as_ref()
                .map_or(" (no effect added)".to_string(), |a| format!(
                    " (p = {:.3}); {:.0} % of the gap closed",
                    a.energy_p,
                    100.0 * (1.0 - a.energy / d.before.energy)
                ))
        ),
    );
    push(
        m,
        "| statistic | measured | before: simulated | before: comparison [95 % CI] | | after: simulated | after: comparison [95 % CI] | |\n|---|---|---|---|---|---|---|---|",
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
        let before = statistic_row(s);
        let after = d.after.as_ref().map_or("| | | |".to_string(), |a| {
            let t = &a.statistics[i];
            format!(
                "| {} | {} {} [{}, {}] | {} |",
                g(t.simulated),
                t.comparison,
                g(t.estimate.value),
                g(t.estimate.lower),
                g(t.estimate.upper),
                if t.disagrees {
                    "**disagrees**"
                } else {
                    "agrees"
                }
            )
        });
        push(
            m,
            &format!("{}{}", before.trim_end_matches('|').trim_end(), after),
        );
    }
    push(
        m,
        "\nEvery statistic, before and after, with its interval and p-value, is in `diagnosis.json`.\n",
    );
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
        ("Verdicts", METHOD.verdicts),
        ("Statistics", METHOD.statistics),
        ("Discrepancy", METHOD.discrepancy),
    ] {
        push(m, &format!("- **{k}.** {v}"));
    }
    push(
        m,
        &format!(
            "\n{} simulations ({} solves) in {:.1} s.",
            d.work.0, d.work.1, d.work.2
        ),
    );
}
