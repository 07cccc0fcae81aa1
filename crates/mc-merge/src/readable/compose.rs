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
    NONE, arcsec, figure_interval, figure_value, parameters, plain, rad, sci, verdict,
};
use crate::answer::Answer;
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

/// The answer first, in three lines ([`crate::answer::Answer`]): the allowable σ for the
/// target with its interval, the cases above and below the target, and what the Rayleigh
/// verdicts mean given how many were tested.
fn answer_section(doc: &mut Document, report: &Report) {
    let a = Answer::of(report);
    let pct = plain(a.percentile);
    let target = format!(
        "θ_P{pct} ≤ {} rad ({} arcsec)",
        rad(a.target),
        arcsec(a.target)
    );
    doc.heading(2, "The answer", "answer");
    let mut items: Vec<Line> = vec![];
    if a.allowable.is_empty() {
        items.push(vec![text(format!(
            "Allowable σ: none here, since no cases of this job differ only in σ (a σ-series); the cases are compared with the target {target} one by one below."
        ))]);
    }
    for (name, sigma) in &a.allowable {
        let mut line = vec![
            text(format!("Allowable σ for {target}, series {name}: ")),
            strong(format!("{} mm", figure_value(&sigma.through_origin, sci))),
            text(format!(
                ", {} % interval {} mm",
                plain(100.0 * report.settings.confidence),
                figure_interval(&sigma.through_origin, sci)
            )),
        ];
        if let Some((lo, _)) = sigma.through_origin.interval() {
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
    let list = |v: &[crate::answer::Placed]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|p| format!("{} ({} arcsec)", p.name, arcsec(p.theta)))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let mut cases = format!(
        "θ_P{pct} above the target: {}; at or below it: {}",
        list(&a.above),
        list(&a.within)
    );
    if !a.undefined.is_empty() {
        cases += &format!("; too few samples for θ_P{pct}: {}", a.undefined.join(", "));
    }
    items.push(vec![text(cases + ".")]);
    if let (Some(level), Some(chance)) = (a.level, a.expected_by_chance()) {
        let rejected = if a.rejected.is_empty() {
            "in none".to_string()
        } else {
            format!("in {} ({})", a.rejected.len(), a.rejected.join(", "))
        };
        items.push(vec![text(format!(
            "The paper's Rayleigh law is rejected {rejected} of {} cases at level {}: with {} tests, {:.2} rejections are expected by chance alone where it holds. The θ_P{pct} above are the empirical percentiles, whatever the verdict; the Rayleigh figure is a cross-check (section The Rayleigh law gives the difference).",
            a.tested,
            plain(level),
            a.tested,
            chance
        ))]);
    }
    doc.list(items);
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
            "Target: θ_P{} ≤ {} rad ({} arcsec).",
            plain(s.target_percentile),
            rad(s.target_angle),
            arcsec(s.target_angle)
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
