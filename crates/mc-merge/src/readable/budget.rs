//! The alignment budget's section, first in the readable report when the job states one
//! ([`crate::budget`]): the lines, per case each line's percentile against its limit and the
//! allowable σ meeting every line with the line that binds, per σ-series the same from its
//! lines through the origin.

use super::document::{Document, Line, Table, strong, text};
use super::words::{figure_interval, figure_value, plain, sci};
use crate::report::{BudgetReport, Report};
use truss_units::ARCSEC_PER_RAD;

/// A line's number in the unit an engineer writes it: arcsec for θ_P, µm for lengths.
fn engineer(quantity: &str, v: f64) -> String {
    if quantity == "theta_p" {
        format!("{:.2}″", v * ARCSEC_PER_RAD)
    } else {
        format!("{:.2} µm", v * 1e3)
    }
}

/// The section, if the report has a budget.
pub fn budget_section(doc: &mut Document, report: &Report) {
    let Some(b) = &report.budget else {
        return;
    };
    doc.heading(2, "The alignment budget", "budget");
    let lines: Vec<String> = b
        .lines
        .iter()
        .map(|l| format!("{} ≤ {}", l.of, engineer(l.quantity, l.limit.0)))
        .collect();
    doc.text(format!(
        "The job holds every case to {} at the {}th percentile. A line passes when its empirical percentile is within its limit; the allowable σ is the case's σ times the least limit/percentile over the lines (each percentile is proportional to σ under small errors), with the bootstrap interval of that minimum, and the line attaining it binds.",
        lines.join(", "),
        plain(b.percentile.0)
    ));
    doc.list(answer(b, report.settings.confidence));
    let mut header = vec!["case".to_string(), "σ [mm]".to_string()];
    header.extend(b.lines.iter().map(|l| format!("{} [{}]", l.of, l.unit)));
    header.push("verdict".into());
    let rows = b
        .cases
        .iter()
        .map(|c| {
            let mut row = vec![c.case.clone(), c.sigma.map_or("-".into(), |s| plain(s.0))];
            row.extend(c.lines.iter().map(|l| {
                let word = match l.passes {
                    Some(true) => "passes",
                    Some(false) => "FAILS",
                    None => "-",
                };
                format!("{} {word}", figure_value(&l.value, sci))
            }));
            row.push(match c.passes {
                Some(true) => "passes".into(),
                Some(false) => "FAILS".into(),
                None => "-".into(),
            });
            row
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "Each case's percentile of every line (Hyndman–Fan definition 1) against its limit, at the {}th percentile.",
            plain(b.percentile.0)
        ),
        header,
        rows,
    });
}

/// One item per case and σ-series: the allowable σ, its interval and the line that binds.
fn answer(b: &BudgetReport, confidence: f64) -> Vec<Line> {
    let binds = |line: Option<&str>, share: Option<crate::report::Real>| match line {
        Some(l) => format!(
            "; {l} binds{}",
            share.map_or(String::new(), |s| format!(
                " (in {} % of the bootstrap replicates)",
                plain((100.0 * s.0).round())
            ))
        ),
        None => String::new(),
    };
    let conf = plain(100.0 * confidence);
    let mut items: Vec<Line> = b
        .series
        .iter()
        .map(|s| {
            vec![
                text(format!(
                    "Allowable σ meeting every line, series {}: ",
                    s.name
                )),
                strong(format!("{} mm", figure_value(&s.allowable_sigma, sci))),
                text(format!(
                    ", {conf} % interval {} mm{}{}.",
                    figure_interval(&s.allowable_sigma, sci),
                    binds(s.binding, s.binding_share),
                    if s.extrapolated {
                        ", extrapolated beyond the σ range of the series"
                    } else {
                        ""
                    }
                )),
            ]
        })
        .collect();
    items.extend(b.cases.iter().map(|c| {
        vec![
            text(format!("Case {}: allowable σ ", c.case)),
            strong(format!("{} mm", figure_value(&c.allowable_sigma, sci))),
            text(format!(
                ", {conf} % interval {} mm{}.",
                figure_interval(&c.allowable_sigma, sci),
                binds(c.binding, c.binding_share)
            )),
        ]
    }));
    items
}
