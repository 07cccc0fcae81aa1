//! The percentile tables of the readable report: a summary at the target percentile (one
//! row per case, against the target, with the Rayleigh law's verdict) and every percentile
//! of every case with its bootstrap interval (BCa, or the percentile method where BCa is
//! undefined) in rad and arcsec beside the distribution-free order-statistic interval.

use super::document::{Document, Table};
use super::words::{
    NONE, arcsec, bracket, figure_interval, figure_value, none, ordinal, parameters, plain, rad,
    verdict,
};
use crate::report::{CaseReport, Figure, PercentileReport, Report};

/// A percentile's estimate with its BCa interval, else its percentile-method interval;
/// `true` when BCa was undefined.
fn with_interval(p: &PercentileReport) -> (Figure, bool) {
    let Some(v) = p.value else {
        return (Figure::null(p.reason.clone().unwrap_or_default()), false);
    };
    match (p.bca.lower, p.bca.upper) {
        (Some(lo), Some(hi)) => (Figure::new(v.0, lo.0, hi.0), false),
        _ => match p.percentile_bootstrap.get() {
            Some((lo, hi)) => (Figure::new(v.0, lo, hi), true),
            None => (
                Figure::without_interval(
                    v.0,
                    p.percentile_bootstrap
                        .reason
                        .clone()
                        .unwrap_or_else(|| "no interval".into()),
                ),
                false,
            ),
        },
    }
}

/// The target percentile of a case.
pub fn target(report: &Report, case: &CaseReport) -> Option<(Figure, bool)> {
    case.percentiles
        .iter()
        .find(|p| p.percentile.0 == report.sweep.percentile.0)
        .map(with_interval)
}

/// Whether a percentile with its interval is below, above or around the target angle.
fn against(f: &Figure, target: f64) -> String {
    match (f.get(), f.interval()) {
        (Some(_), Some((_, hi))) if hi <= target => "below (whole interval)".into(),
        (Some(_), Some((lo, _))) if lo > target => "above (whole interval)".into(),
        (Some(_), Some(_)) => "interval contains the target".into(),
        (Some(v), None) if v <= target => "below (no interval)".into(),
        (Some(_), None) => "above (no interval)".into(),
        _ => NONE.into(),
    }
}

/// Appends the summary at the target percentile.
pub fn summary_section(doc: &mut Document, report: &Report) {
    let s = &report.settings;
    let pct = plain(report.sweep.percentile.0);
    let conf = plain(100.0 * s.confidence);
    doc.heading(
        2,
        format!(
            "Summary at the {} percentile",
            ordinal(report.sweep.percentile.0)
        ),
        "summary",
    );
    let mut fallback = false;
    let rows = report
        .cases
        .iter()
        .map(|case| {
            let (f, pm) = target(report, case).unwrap_or_default();
            fallback |= pm;
            let mark = if pm { " ‡" } else { "" };
            vec![
                case.name.clone(),
                parameters(case),
                case.n.to_string(),
                case.failed.count.to_string(),
                figure_value(&f, rad),
                format!("{}{mark}", figure_interval(&f, rad)),
                figure_value(&f, arcsec),
                format!("{}{mark}", figure_interval(&f, arcsec)),
                against(&f, s.target_angle),
                verdict(case),
            ]
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "θ_P{pct} of each case with its {conf} % BCa interval, in rad and arcsec, against the target {}, and the Rayleigh law's verdict.",
            s.target()
        ),
        header: vec![
            "case".into(),
            "parameters".into(),
            "n (converged)".into(),
            "failed".into(),
            format!("θ_P{pct} [rad]"),
            format!("{conf} % interval [rad]"),
            format!("θ_P{pct} [arcsec]"),
            format!("{conf} % interval [arcsec]"),
            "against the target".into(),
            "Rayleigh law".into(),
        ],
        rows,
    });
    if fallback {
        doc.text("‡ percentile-method interval: BCa is undefined for this case.");
    }
}

/// Appends every percentile of every case.
pub fn percentiles_section(doc: &mut Document, report: &Report) {
    let conf = plain(100.0 * report.settings.confidence);
    doc.heading(2, "Percentiles of θ_P", "percentiles");
    let rows = report
        .cases
        .iter()
        .flat_map(|case| {
            case.percentiles.iter().map(|p| {
                let (f, pm) = with_interval(p);
                let os = &p.order_statistic;
                vec![
                    case.name.clone(),
                    plain(p.percentile.0),
                    figure_value(&f, rad),
                    figure_interval(&f, rad),
                    figure_value(&f, arcsec),
                    figure_interval(&f, arcsec),
                    if f.interval().is_none() {
                        NONE.into()
                    } else if pm {
                        "percentile".into()
                    } else {
                        "BCa".into()
                    },
                    match (os.lower, os.upper) {
                        (Some(lo), Some(hi)) => bracket(lo.0, hi.0, arcsec),
                        _ => none(os.reason.as_deref()),
                    },
                ]
            })
        })
        .collect();
    doc.table(Table {
        caption: format!(
            "Empirical percentiles of θ_P (Hyndman–Fan definition 1) of every case, with their {conf} % bootstrap interval (BCa, or the percentile method where BCa is undefined) in rad and arcsec, and the distribution-free order-statistic interval in arcsec."
        ),
        header: vec![
            "case".into(),
            "percentile [%]".into(),
            "θ_P [rad]".into(),
            format!("{conf} % interval [rad]"),
            "θ_P [arcsec]".into(),
            format!("{conf} % interval [arcsec]"),
            "interval".into(),
            format!("order-statistic {conf} % interval [arcsec]"),
        ],
        rows,
    });
}
