//! The sweeps section of the readable report: each σ-series with its points, its two line
//! fits and the allowable σ for the target (with the conservative choice, the interval's
//! lower end), and each stages series normalised to its smallest stage count (paper Figs. 3,
//! 9, 16).

use super::document::{Block, Document, Table, strong, text};
use super::plots;
use super::words::{
    NONE, arcsec, figure, figure_interval, figure_value, interval, ordinal, plain, rad, sci,
};
use crate::report::{LineFit, Report, SigmaSeries, StagesSeries};
use std::collections::BTreeSet;

/// The anchor of the σ sweeps.
pub const SIGMA_ANCHOR: &str = "sigma-sweeps";
/// The anchor of the stages sweeps.
pub const STAGES_ANCHOR: &str = "stages-sweeps";

/// Appends the sweeps over σ and over stages, if the job has any.
pub fn sweeps(doc: &mut Document, report: &Report, files: &BTreeSet<String>) {
    let sweep = &report.sweep;
    let pct = ordinal(sweep.percentile.0);
    let conf = plain(100.0 * report.settings.confidence);
    if !sweep.sigma_series.is_empty() {
        doc.heading(2, "Sweeps over σ and the allowable σ", SIGMA_ANCHOR);
        doc.text(format!(
            "Cases that differ only in the member length standard deviation σ form a series. Each point is θ_P's {pct} percentile with its {conf} % BCa interval (percentile-method interval where BCa is undefined); the lines are least-squares fits, and the allowable σ is where a line meets the target. Intervals of the fits and of the allowable σ come from refitting every bootstrap replicate."
        ));
        for (k, series) in sweep.sigma_series.iter().enumerate() {
            sigma_series(doc, report, series, k + 1);
        }
        if let Some(p) = plots::sigma_sweep(report, files) {
            doc.blocks.push(Block::Plot(p));
        }
    }
    if !sweep.stages_series.is_empty() {
        doc.heading(2, "Sweeps over the number of stages", STAGES_ANCHOR);
        doc.text(format!(
            "Cases that differ only in the number of stages form a series; θ_P's {pct} percentile is divided by that of the smallest stage count (paper Fig. 9), with the bootstrap interval of the ratio."
        ));
        for (k, series) in sweep.stages_series.iter().enumerate() {
            stages_series(doc, report, series, k + 1);
        }
        if let Some(p) = plots::stages_sweep(report, files) {
            doc.blocks.push(Block::Plot(p));
        }
    }
}

/// A series' fixed parameters in words: `stages = 5, uniform = 0`.
fn fixed_words(name: &str) -> String {
    if name.is_empty() {
        "no other parameter".into()
    } else {
        name.to_string()
    }
}

fn sigma_series(doc: &mut Document, report: &Report, s: &SigmaSeries, k: usize) {
    let pct = plain(report.sweep.percentile.0);
    let conf = plain(100.0 * report.settings.confidence);
    doc.heading(
        3,
        format!("σ-series {k}: {}", fixed_words(&s.name)),
        format!("sigma-series-{k}"),
    );
    doc.table(Table {
        caption: format!("θ_P{pct} against σ, series {k} ({conf} % intervals; rad and arcsec)."),
        header: vec![
            "case".into(),
            "σ [mm]".into(),
            format!("θ_P{pct} [rad]"),
            format!("{conf} % interval [rad]"),
            format!("θ_P{pct} [arcsec]"),
            format!("{conf} % interval [arcsec]"),
        ],
        rows: s
            .points
            .iter()
            .map(|p| {
                vec![
                    p.case.clone(),
                    plain(p.x.0),
                    figure_value(&p.value, rad),
                    figure_interval(&p.value, rad),
                    figure_value(&p.value, arcsec),
                    figure_interval(&p.value, arcsec),
                ]
            })
            .collect(),
    });
    let fit_row = |name: &str, f: &LineFit| {
        vec![
            name.to_string(),
            figure(&f.slope, sci),
            figure(&f.intercept, rad),
            figure(&f.r_squared, |r| format!("{r:.5}")),
        ]
    };
    doc.table(Table {
        caption: format!(
            "Least-squares lines of θ_P{pct} against σ, series {k}, with {conf} % intervals."
        ),
        header: vec![
            "line".into(),
            "slope [rad/mm]".into(),
            "intercept [rad]".into(),
            "R²".into(),
        ],
        rows: vec![
            fit_row("through the origin", &s.through_origin),
            fit_row("with intercept", &s.with_intercept),
        ],
    });
    let a = &s.allowable_sigma;
    let mm = |x: f64| format!("{} mm", sci(x));
    let mut line = vec![text(format!(
        "Allowable σ for θ_P{} ≤ {}: ",
        plain(a.percentile.0),
        report.settings.target()
    ))];
    match a.through_origin.get() {
        Some(v) => line.push(strong(mm(v))),
        None => line.push(text(figure_value(&a.through_origin, mm))),
    }
    line.push(text(format!(
        " {} (line through the origin); {} (line with intercept).",
        figure_interval(&a.through_origin, mm),
        figure(&a.with_intercept, mm)
    )));
    if let Some((lo, _)) = a.through_origin.interval() {
        line.push(text(format!(
            " Conservative choice: σ ≤ {}, the lower end of the {conf} % interval.",
            mm(lo)
        )));
    }
    if a.extrapolated {
        line.push(text(
            " The allowable σ lies outside the σ range of the series: it is extrapolated.",
        ));
    }
    doc.paragraph(line);
    doc.list(
        s.caveats
            .iter()
            .map(|c| vec![text(format!("Caveat: {c}"))])
            .collect(),
    );
}

fn stages_series(doc: &mut Document, report: &Report, s: &StagesSeries, k: usize) {
    let pct = plain(report.sweep.percentile.0);
    let conf = plain(100.0 * report.settings.confidence);
    doc.heading(
        3,
        format!("Stages series {k}: {}", fixed_words(&s.name)),
        format!("stages-series-{k}"),
    );
    doc.table(Table {
        caption: format!(
            "θ_P{pct} against the number of stages, series {k}, normalised to {} stage(s) ({conf} % intervals).",
            plain(s.reference_stages.0)
        ),
        header: vec![
            "case".into(),
            "stages".into(),
            format!("θ_P{pct} [rad]"),
            format!("θ_P{pct} [arcsec]"),
            "normalised [1]".into(),
            "own interval / reference [1]".into(),
        ],
        rows: s
            .points
            .iter()
            .map(|p| {
                vec![
                    p.case.clone(),
                    plain(p.stages.0),
                    figure(&p.value, rad),
                    figure(&p.value, arcsec),
                    figure(&p.normalised, |v| format!("{v:.3}")),
                    interval(&p.relative_interval, |v| format!("{v:.3}")),
                ]
            })
            .collect(),
    });
    doc.text(format!(
        "Peak at {} stages.",
        s.peak_stages.map_or(NONE.to_string(), |p| plain(p.0))
    ));
    doc.list(
        s.caveats
            .iter()
            .map(|c| vec![text(format!("Caveat: {c}"))])
            .collect(),
    );
}
