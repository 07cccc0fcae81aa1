//! The plots as the readable report shows them: which files exist for a case or the job, and
//! what each shows in words. The alternative text carries the plot's message with its key
//! numbers (from the report), so a reader who cannot see the picture loses little.

use super::document::Plot;
use super::words::{arcsec, ordinal, rad};
use crate::report::{CaseReport, Report};
use std::collections::BTreeSet;

/// The plot `stem` as a [`Plot`], if its SVG was written (`files`: names in the report
/// directory).
fn plot(files: &BTreeSet<String>, stem: &str, alt: String, caption: String) -> Option<Plot> {
    let svg = format!("{stem}.svg");
    if !files.contains(&svg) {
        return None;
    }
    let png = Some(format!("{stem}.png")).filter(|p| files.contains(p));
    Some(Plot {
        svg,
        png,
        alt,
        caption,
    })
}

/// `4.123e-5 rad (8.50 arcsec)`.
fn angle(x: f64) -> String {
    format!("{} rad ({} arcsec)", rad(x), arcsec(x))
}

/// The empirical and Rayleigh target percentiles of a case, in words.
fn target_words(report: &Report, case: &CaseReport) -> String {
    let pct = report.sweep.percentile.0;
    let emp = case
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value);
    let ray = case
        .rayleigh
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value.get());
    let mut s = format!("the {} percentile is ", ordinal(pct));
    s.push_str(&emp.map_or("not defined".into(), |v| angle(v.0)));
    if let Some(r) = ray {
        s.push_str(&format!(", the fitted Rayleigh law's {}", angle(r)));
    }
    s
}

/// `0.0223 mm (22.3 µm)`.
fn length(x: f64) -> String {
    format!("{x:.4} mm ({:.1} µm)", x * truss_units::MICROMETRE_PER_MM)
}

/// Decenter's and |despace|'s empirical percentiles at `pct` and their laws' parameters,
/// in words.
fn placement_words(case: &CaseReport, pct: f64) -> String {
    let at = |q: &crate::report::QuantityReport| {
        q.percentiles
            .iter()
            .find(|p| p.percentile.0 == pct)
            .and_then(|p| p.value)
            .map_or("not defined".into(), |v| length(v.0))
    };
    let fig = |f: &Option<crate::report::Figure>| {
        f.as_ref()
            .and_then(|f| f.get())
            .map_or("not defined".into(), length)
    };
    match (&case.decenter, &case.despace) {
        (Some(d), Some(z)) => format!(
            "the {} percentile of decenter is {}, the fitted Rayleigh scale {}; of |despace| {}, the normal law's mean {} and standard deviation {}",
            ordinal(pct),
            at(d),
            fig(&d.law.sigma),
            at(z),
            fig(&z.law.mean),
            fig(&z.law.std)
        ),
        _ => "the samples do not record decenter and despace".into(),
    }
}

/// The six plots of one case whose plot files are named after `stem`, those written.
pub fn case_plots(
    report: &Report,
    case: &CaseReport,
    stem: &str,
    files: &BTreeSet<String>,
) -> Vec<Plot> {
    let name = &case.name;
    let pct = ordinal(report.sweep.percentile.0);
    let target = angle(report.settings.target_angle);
    let verdict = match case.gof.verdict {
        Some("holds") => "holds",
        Some(_) => "is rejected",
        None => "was not tested",
    };
    let placement_pct = report
        .budget
        .as_ref()
        .map_or(report.sweep.percentile.0, |b| b.percentile.0);
    let sigma_t = case
        .rayleigh
        .sigma_t
        .get()
        .map_or("not defined".into(), |s| format!("{s:.3e}"));
    [
        plot(
            files,
            &format!("theta_p-{stem}"),
            format!(
                "Histogram of the distortion angle θ_P of case {name} (n = {}) with the fitted Rayleigh density; {}; the target is {target}.",
                case.n,
                target_words(report, case)
            ),
            "θ_P: histogram (as a density) with the fitted Rayleigh density, the empirical and Rayleigh percentiles and the target; µrad below, arcsec above.".into(),
        ),
        plot(
            files,
            &format!("tan-{stem}"),
            format!(
                "Histograms of tan θ_x and tan θ_y of case {name}, times 10⁶, with the normal density N(0, σ_t²), σ_t = {sigma_t}."
            ),
            "tan θ_x and tan θ_y (× 10⁶) with N(0, σ_t²).".into(),
        ),
        plot(
            files,
            &format!("qq-{stem}"),
            format!(
                "Rayleigh QQ plot of case {name}: the sample quantiles of θ_P against the fitted Rayleigh law's, with the pointwise band of the order statistics; the Rayleigh law {verdict}."
            ),
            "Rayleigh QQ plot with the pointwise band of the order statistics (µrad).".into(),
        ),
        plot(
            files,
            &format!("exceedance-{stem}"),
            format!(
                "Exceedance probability 1 − F of θ_P of case {name} on a log scale, with the fitted Rayleigh law's; {}.",
                target_words(report, case)
            ),
            "1 − F of θ_P on a log scale with the fitted Rayleigh law; P99 and P99.9 marked where enough samples lie above them.".into(),
        ),
        plot(
            files,
            &format!("running-{stem}"),
            format!(
                "The {pct} percentile of θ_P over the first n samples of case {name}, n on a log scale, with its distribution-free interval: where it has settled, n is enough."
            ),
            format!("The {pct} percentile of the first n samples with its interval."),
        ),
        plot(
            files,
            &format!("placement-{stem}"),
            format!(
                "Histograms of the decenter of case {name} with the fitted Rayleigh density and of its despace with the fitted normal density; {}{}.",
                placement_words(case, placement_pct),
                if report.budget.is_some() {
                    "; the budget's limits are marked"
                } else {
                    ""
                }
            ),
            "Decenter with its fitted Rayleigh density and despace with its fitted normal density (µm), their percentiles and the budget's limits.".into(),
        ),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The σ-sweep plot, if written.
pub fn sigma_sweep(report: &Report, files: &BTreeSet<String>) -> Option<Plot> {
    let pct = ordinal(report.sweep.percentile.0);
    plot(
        files,
        "sigma-sweep",
        format!(
            "The {pct} percentile of θ_P against the member length standard deviation σ on log–log axes, one series per set of fixed parameters, with intervals, the line through the origin and the allowable σ for the target {}; below, each point's deviation from its line in percent.",
            angle(report.settings.target_angle)
        ),
        format!(
            "θ_P's {pct} percentile against σ (mm), with the target and the allowable σ; below, the deviations from the line (%)."
        ),
    )
}

/// The stages-sweep plot, if written.
pub fn stages_sweep(report: &Report, files: &BTreeSet<String>) -> Option<Plot> {
    let pct = ordinal(report.sweep.percentile.0);
    plot(
        files,
        "stages-sweep",
        format!(
            "The {pct} percentile of θ_P normalised to that of the smallest stage count, against the number of stages, with intervals."
        ),
        format!(
            "θ_P's {pct} percentile normalised to the smallest stage count, against the number of stages."
        ),
    )
}
