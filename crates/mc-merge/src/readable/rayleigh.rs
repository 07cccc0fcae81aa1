//! The Rayleigh law in the readable report: per case σ_t, the fitted scale σ, the Rayleigh
//! and empirical target percentiles and their relative difference, the Kolmogorov–Smirnov
//! and Anderson–Darling p-values and the verdict, then each verdict in words (paper §3.2).

use super::document::{Document, Table, strong, text};
use super::words::{NONE, figure, figure_value, plain, rad, signed_percent, value, verdict};
use crate::analysis::format_p;
use crate::report::Report;

/// A p-value for a table cell: `0.15`, `0.0042`, `≤ 1.0e-3` (the Monte Carlo floor).
fn p_value(p: f64, replicates: usize) -> String {
    let s = format_p(p, replicates);
    s.strip_prefix("p = ")
        .or_else(|| s.strip_prefix("p "))
        .unwrap_or(&s)
        .to_string()
}

/// Appends the Rayleigh law of every case.
pub fn rayleigh_section(doc: &mut Document, report: &Report) {
    let pct = plain(report.sweep.percentile.0);
    let conf = plain(100.0 * report.settings.confidence);
    doc.heading(2, "The Rayleigh law", "rayleigh");
    doc.text(format!(
        "The paper's law: tan θ_x and tan θ_y are N(0, σ_t²), so θ_P is Rayleigh distributed and its percentiles follow from one scale σ (eq. 28). The fit is tested by Kolmogorov–Smirnov and Anderson–Darling at level {}; the relative difference of the Rayleigh and empirical θ_P{pct} says how much the law's answer is off.",
        plain(report.settings.gof_level)
    ));
    let rows = report
        .cases
        .iter()
        .map(|case| {
            let r = &case.rayleigh;
            let at = r
                .percentiles
                .iter()
                .find(|p| p.percentile.0 == report.sweep.percentile.0);
            let replicates = case
                .gof
                .null_calibration
                .as_ref()
                .map_or(0, |n| n.replicates);
            vec![
                case.name.clone(),
                figure_value(&r.sigma_t, |x| format!("{x:.3e}")),
                figure(&r.sigma, rad),
                at.map_or(NONE.into(), |p| figure(&p.value, rad)),
                at.map_or(NONE.into(), |p| {
                    value(p.empirical, p.reason.as_deref(), rad)
                }),
                at.map_or(NONE.into(), |p| {
                    figure(&p.relative_difference, signed_percent)
                }),
                case.gof
                    .ks
                    .as_ref()
                    .map_or(NONE.into(), |t| p_value(t.p_value.0, replicates)),
                case.gof
                    .ad
                    .as_ref()
                    .map_or(NONE.into(), |t| p_value(t.p_value.0, replicates)),
                verdict(case),
            ]
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "The Rayleigh fit of each case with {conf} % intervals: σ_t of the tilts, the scale σ of θ_P, its θ_P{pct} beside the empirical one, and the tests' p-values (Monte Carlo; ≤ marks the smallest p-value the null samples resolve)."
        ),
        header: vec![
            "case".into(),
            "σ_t [1]".into(),
            "σ [rad]".into(),
            format!("Rayleigh θ_P{pct} [rad]"),
            format!("empirical θ_P{pct} [rad]"),
            "Rayleigh − empirical [% of empirical]".into(),
            "KS p-value".into(),
            "AD p-value".into(),
            "verdict".into(),
        ],
        rows,
    });
    doc.list(
        report
            .cases
            .iter()
            .map(|case| vec![strong(&case.name), text(format!(": {}", case.gof.summary))])
            .collect(),
    );
}
