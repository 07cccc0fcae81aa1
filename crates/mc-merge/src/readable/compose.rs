//! The readable report's content, built from the [`Report`] that `report.json` is written
//! from (nothing is computed again), section by section: the run's identity, a summary at
//! the target percentile and every percentile ([`super::percentiles`]), the Rayleigh law
//! ([`super::rayleigh`]), floating stages and loose joints ([`super::floating`]), the
//! caveats, the sweeps with the allowable σ ([`super::sweeps`]), each case's plots
//! ([`super::plots`]) and the definitions in words.

use super::document::{Block, Document, Line, Span, code, strong, text};
use super::floating::floating_section;
use super::percentiles::{percentiles_section, summary_section, target};
use super::plots;
use super::rayleigh::rayleigh_section;
use super::sweeps;
use super::words::{
    NONE, arcsec, figure_interval, figure_value, parameters, plain, rad, sci, signed_percent,
    verdict,
};
use crate::load::ShardWriter;
use crate::report::Report;
use std::collections::BTreeSet;
use truss_units::ARCSEC_PER_RAD;

/// The report's title.
pub const TITLE: &str = "Distortion angle θ_P: Monte Carlo report";

/// The document of `report`, whose shards were written by `writers`; `files` names the plot
/// files written beside it (none with `--no-plots`).
pub fn compose(report: &Report, writers: &[ShardWriter], files: &BTreeSet<String>) -> Document {
    let mut doc = Document {
        title: TITLE.into(),
        blocks: vec![],
    };
    doc.heading(1, TITLE, "top");
    doc.text(
        "Percentiles of the distortion angle θ_P between the truss's top and bottom surfaces with their confidence intervals, the paper's Rayleigh law, the floating stages, the sweeps over σ and the allowable σ for the pointing target, from the verified shards of one job. Every number is also in report.json beside this file, at full precision; this report is written from the same results.",
    );
    super::budget::budget_section(&mut doc, report);
    answer_section(&mut doc, report);
    run_section(&mut doc, report, writers);
    let contents_at = doc.blocks.len();
    summary_section(&mut doc, report);
    percentiles_section(&mut doc, report);
    rayleigh_section(&mut doc, report);
    floating_section(&mut doc, report);
    caveats_section(&mut doc, report);
    sweeps::sweeps(&mut doc, report, files);
    cases_section(&mut doc, report, files);
    definitions_section(&mut doc, report);
    let contents = contents(&doc);
    doc.blocks.insert(contents_at, Block::List(contents));
    doc.blocks.insert(
        contents_at,
        Block::Heading {
            level: 2,
            text: "Contents".into(),
            anchor: "contents".into(),
        },
    );
    doc
}

/// A link to each section.
fn contents(doc: &Document) -> Vec<Line> {
    doc.blocks
        .iter()
        .filter_map(|b| match b {
            Block::Heading {
                level: 2,
                text,
                anchor,
            } => Some(vec![Span::Anchor {
                text: text.clone(),
                anchor: anchor.clone(),
            }]),
            _ => None,
        })
        .collect()
}

/// The answer first, in three lines ([`crate::report::AnswerReport`]): the allowable σ for
/// the target with its interval, the cases above and below the target, and what the Rayleigh
/// verdicts mean given how many were tested (the rejections chance alone gives, Holm's
/// adjustment across the cases) and how much they matter (each rejection's effect size).
fn answer_section(doc: &mut Document, report: &Report) {
    let a = &report.answer;
    let pct = plain(a.percentile.0);
    let target = format!("θ_P{pct} ≤ {}", report.settings.target());
    doc.heading(2, "The answer", "answer");
    let mut items: Vec<Line> = vec![];
    if a.allowable_sigma.is_empty() {
        items.push(vec![text(format!(
            "Allowable σ: none here, since no cases of this job differ only in σ (a σ-series); the cases are compared with the target {target} one by one below."
        ))]);
    }
    for sigma in &a.allowable_sigma {
        let mut line = vec![
            text(format!(
                "Allowable σ for {target}, series {}: ",
                sigma.series
            )),
            strong(format!("{} mm", figure_value(&sigma.sigma, sci))),
            text(format!(
                ", {} % interval {} mm",
                plain(100.0 * report.settings.confidence),
                figure_interval(&sigma.sigma, sci)
            )),
        ];
        if let Some((lo, _)) = sigma.sigma.interval() {
            line.push(text("; the conservative choice is "));
            line.push(strong(format!("σ ≤ {} mm", sci(lo))));
            line.push(text(" (the interval's lower end)"));
        }
        if sigma.extrapolated {
            line.push(text(", extrapolated beyond the σ range of the series"));
        }
        line.push(text("."));
        items.push(line);
    }
    let list = |v: Vec<&crate::report::CaseAgainstTarget>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|c| format!("{} ({} arcsec)", c.case, figure_value(&c.value, arcsec)))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let mut cases = format!(
        "θ_P{pct} above the target: {}; at or below it: {}",
        list(a.above().collect()),
        list(a.within().collect())
    );
    let undefined: Vec<&str> = a.undefined().collect();
    if !undefined.is_empty() {
        cases += &format!("; too few samples for θ_P{pct}: {}", undefined.join(", "));
    }
    items.push(vec![text(cases + ".")]);
    let r = &a.rayleigh;
    if r.tested > 0 {
        let rejected: Vec<String> = r
            .rejected()
            .map(|v| {
                format!(
                    "{} (p = {:.3}; its Rayleigh θ_P{pct} differs from the empirical by {})",
                    v.case,
                    v.p_value.0,
                    signed_figure(&v.relative_difference)
                )
            })
            .collect();
        let rejected = if rejected.is_empty() {
            format!("in none of the {} cases tested", r.tested)
        } else {
            format!(
                "in {} of the {} cases tested: {}",
                rejected.len(),
                r.tested,
                rejected.join("; ")
            )
        };
        let holm = if r.holm_rejected.is_empty() {
            format!(
                "after Holm's adjustment across the {} cases none is rejected (smallest adjusted p = {:.3})",
                r.tested,
                r.smallest_holm_p().unwrap_or(1.0)
            )
        } else {
            format!(
                "after Holm's adjustment across the {} cases it is still rejected in {}",
                r.tested,
                r.holm_rejected.join(", ")
            )
        };
        items.push(vec![text(format!(
            "The paper's Rayleigh law is rejected at level {} {rejected}. With {} tests, {:.2} rejections are expected by chance alone where it holds; {holm}. The θ_P{pct} above are the empirical percentiles, whatever the verdict; the Rayleigh figure is a cross-check (section The Rayleigh law gives the difference).",
            plain(r.level.0),
            r.tested,
            r.expected_by_chance.0
        ))]);
    }
    doc.list(items);
}

/// A relative difference with its interval, in percent: `−0.3 % [−1.2 %, +0.6 %]`.
fn signed_figure(f: &crate::report::Figure) -> String {
    match (f.get(), f.interval()) {
        (Some(v), Some((lo, hi))) => format!(
            "{} [{}, {}]",
            signed_percent(v),
            signed_percent(lo),
            signed_percent(hi)
        ),
        (Some(v), None) => signed_percent(v),
        _ => NONE.to_string(),
    }
}

fn run_section(doc: &mut Document, report: &Report, writers: &[ShardWriter]) {
    let s = &report.settings;
    let c = &report.coverage;
    doc.heading(2, "The run", "run");
    let samples = if c.complete {
        format!("{} of {} (complete)", c.present, c.expected)
    } else {
        format!(
            "{} of {}: PARTIAL, {} missing index range(s); every figure of an affected case says so",
            c.present, c.expected, c.missing_ranges
        )
    };
    let failed = match (report.failed.total, report.failed.excluded) {
        (0, _) => "none".to_string(),
        (n, true) => format!("{n}, excluded from every figure (--allow-failed)"),
        (n, false) => format!("{n}"),
    };
    let written_by = if writers.is_empty() {
        NONE.to_string()
    } else {
        writers
            .iter()
            .map(|w| {
                format!(
                    "{} {} (shard format {})",
                    w.program, w.program_version, w.format_version
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let conf = plain(100.0 * s.confidence);
    doc.list(vec![
        vec![text("Job id: "), code(&report.job_id)],
        vec![text(format!("Samples: {samples}."))],
        vec![text(format!("Failed samples: {failed}."))],
        vec![text(format!("Cases: {}.", report.cases.len()))],
        vec![text(format!("Shards written by: {written_by}."))],
        vec![text(
            "Numerics version: not written in the shards; it is part of the job id (the same job under other numerics has another id).",
        )],
        vec![text(format!(
            "Merged by: {} {} (report format {} {}).",
            report.program, report.program_version, report.format, report.format_version
        ))],
        vec![text(format!(
            "Statistics: percentiles by Hyndman–Fan definition 1; {conf} % intervals: BCa and percentile method from a Poisson bootstrap with B = {} replicates, seed {}, and the distribution-free order-statistic interval; the Rayleigh law tested by Kolmogorov–Smirnov and Anderson–Darling with {} simulated null samples at level {}.",
            s.replicates,
            s.bootstrap_seed,
            s.gof_replicates,
            plain(s.gof_level)
        ))],
        vec![text(format!(
            "Target: θ_P{} ≤ {}.",
            plain(s.target_percentile),
            s.target()
        ))],
        vec![text(format!(
            "Units: angles in rad and in arcsec (1 rad = {ARCSEC_PER_RAD:.1} arcsec); σ, the member length standard deviation, in mm; tan θ_x, tan θ_y dimensionless."
        ))],
    ]);
}

fn caveats_section(doc: &mut Document, report: &Report) {
    doc.heading(2, "Caveats", "caveats");
    let mut items: Vec<Line> = vec![];
    if !report.coverage.complete {
        items.push(vec![text(format!(
            "The job is incomplete: {} of {} samples present, {} index range(s) missing (--allow-partial).",
            report.coverage.present, report.coverage.expected, report.coverage.missing_ranges
        ))]);
    }
    for case in &report.cases {
        for c in &case.caveats {
            items.push(vec![strong(&case.name), text(format!(": {c}."))]);
        }
    }
    if items.is_empty() {
        doc.text("None: every sample present, no failed sample, and no case with more floating stages than the tail its target percentile reads.");
    } else {
        doc.list(items);
    }
}

fn cases_section(doc: &mut Document, report: &Report, files: &BTreeSet<String>) {
    doc.heading(2, "Plots of each case", "cases");
    if files.is_empty() {
        doc.text("No plots were written with this report (mc-merge --no-plots).");
    } else {
        doc.text("Angles in µrad on the lower axis and in arcsec on the upper one; each plot is also beside this report as an SVG file, and as a PNG at twice the size where mc-merge was built with PNG output.");
    }
    let names: Vec<&str> = report.cases.iter().map(|c| c.name.as_str()).collect();
    for (k, (case, stem)) in report
        .cases
        .iter()
        .zip(crate::plot::file_stems(&names))
        .enumerate()
    {
        doc.heading(3, format!("Case {}", case.name), format!("case-{}", k + 1));
        doc.paragraph(vec![
            text("Parameters: "),
            text(parameters(case)),
            text(format!(
                ". Samples: {} converged of {} ({} present, {} failed).",
                case.n, case.expected, case.present, case.failed.count
            )),
        ]);
        if let Some((f, _)) = target(report, case) {
            doc.paragraph(vec![
                text(format!("θ_P{}: ", plain(report.sweep.percentile.0))),
                strong(format!(
                    "{} rad ({} arcsec)",
                    figure_value(&f, rad),
                    figure_value(&f, arcsec)
                )),
                text(format!(
                    ", interval {} arcsec; Rayleigh law: {}.",
                    figure_interval(&f, arcsec),
                    verdict(case)
                )),
            ]);
        }
        for p in plots::case_plots(report, case, &stem, files) {
            doc.blocks.push(Block::Plot(p));
        }
    }
}

fn definitions_section(doc: &mut Document, report: &Report) {
    let d = &report.definitions;
    doc.heading(2, "Definitions", "definitions");
    let item = |name: &str, words: &str| vec![strong(name), text(format!(": {words}."))];
    doc.list(vec![
        item("Units", d.units),
        item("Percentile", d.percentile),
        item("Bootstrap", d.bootstrap.description),
        item("Bootstrap generator", d.bootstrap.rng),
        item("Percentile interval", d.bootstrap.percentile_interval),
        item("BCa interval", d.bootstrap.bca_interval),
        item("Order-statistic interval", d.order_statistic),
        item("Rayleigh law", d.rayleigh),
        item("Goodness of fit", d.gof),
        item("Sweeps", d.sweep),
        item("Floating stages", d.floating),
        item("Loose joints", d.loose_joints),
    ]);
    doc.paragraph(vec![
        text(format!(
            "Written by {} {} for job ",
            report.program, report.program_version
        )),
        code(&report.job_id),
        text("."),
    ]);
}
