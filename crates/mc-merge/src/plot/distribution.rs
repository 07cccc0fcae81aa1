//! The plots of one case's θ_P distribution:
//!
//! - [`theta`]: histogram (as a density) with the fitted Rayleigh density, the empirical and
//!   Rayleigh target percentiles and the target angle (paper Figs. 4, 7); the samples beyond
//!   the axis, if any, are counted in the legend;
//! - [`qq`]: sample quantiles against Rayleigh quantiles with a pointwise 95 % band;
//! - [`exceedance`]: 1 − F on a log scale with P99 and P99.9 marked;
//! - [`running`]: the target percentile of the first n samples (index order) with its
//!   distribution-free interval, against n, to show whether n is enough.
//!
//! Angles in µrad with an arcsec axis beside them.

use crate::load::CaseData;
use crate::report::{CaseReport, Report};
use plotters::prelude::*;
use statrs::distribution::{Beta, ContinuousCDF};
use truss_plot::frame::*;
use truss_plot::legend::*;
use truss_plot::style::*;
use truss_units::{ARCSEC_PER_MICRORAD, MICRORAD_PER_RAD};

/// The case's θ_P in µrad, ascending.
fn sorted_micro(case: &CaseData) -> Vec<f64> {
    let mut v: Vec<f64> = case.points().map(|p| p.theta * MICRORAD_PER_RAD).collect();
    v.sort_by(f64::total_cmp);
    v
}

/// Bins `values` on [lo, hi) into a density histogram: (left, right, density).
pub fn histogram(values: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<(f64, f64, f64)> {
    let mut counts = vec![0u64; bins];
    let w = (hi - lo) / bins as f64;
    for v in values {
        let k = ((v - lo) / w).floor();
        if k >= 0.0 && (k as usize) < bins {
            counts[k as usize] += 1;
        }
    }
    let n = values.len().max(1) as f64;
    counts
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let a = lo + k as f64 * w;
            (a, a + w, c as f64 / (n * w))
        })
        .collect()
}

/// Rice's rule, 2·n^(1/3) bins, between 10 and 120.
pub fn bin_count(n: usize) -> usize {
    ((2.0 * (n as f64).cbrt()).ceil() as usize).clamp(10, 120)
}

/// The upper end of the θ_P axis and how many samples lie beyond it. The axis ends 8 %
/// above the larger of the 99.9th percentile and the target; when the largest sample is
/// within 25 % of that, the axis is extended to hold every sample.
pub fn axis_end(sorted: &[f64], target: f64) -> (f64, usize) {
    let q999 = crate::quantile::quantile_sorted(sorted, 0.999).unwrap_or(1.0);
    let max = sorted.last().copied().unwrap_or(1.0);
    let hi = q999.max(target) * 1.08;
    if max <= hi * 1.25 {
        (hi.max(max * 1.02), 0)
    } else {
        (hi, sorted.len() - sorted.partition_point(|v| *v < hi))
    }
}

/// The figure at the report's target percentile: (empirical, Rayleigh) in µrad.
fn target_percentiles(rep: &CaseReport, pct: f64) -> (Option<f64>, Option<f64>) {
    let emp = rep
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value)
        .map(|v| v.0 * MICRORAD_PER_RAD);
    let ray = rep
        .rayleigh
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value.get())
        .map(|v| v * MICRORAD_PER_RAD);
    (emp, ray)
}

fn title(rep: &CaseReport, what: &str) -> String {
    format!(
        "{} — {what}, n = {}{}",
        rep.name,
        rep.n,
        if rep.caveats.is_empty() {
            ""
        } else {
            " (see the report's caveats)"
        }
    )
}

/// The histogram plot; `None` with fewer than two samples.
pub fn theta(
    case: &CaseData,
    rep: &CaseReport,
    report: &Report,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let thetas = sorted_micro(case);
    if thetas.len() < 2 {
        return Ok(None);
    }
    let pct = report.sweep.percentile.0;
    let target = report.settings.target_angle * MICRORAD_PER_RAD;
    let (hi, beyond) = axis_end(&thetas, target);
    let hist = histogram(&thetas, 0.0, hi, bin_count(thetas.len()));
    let sigma = rep.rayleigh.sigma.get().map(|s| s * MICRORAD_PER_RAD);
    let curve: Vec<(f64, f64)> = sigma
        .map(|s| {
            (0..=300)
                .map(|i| {
                    let x = hi * i as f64 / 300.0;
                    (x, crate::rayleigh::density(s, x))
                })
                .collect()
        })
        .unwrap_or_default();
    let top = hist
        .iter()
        .map(|b| b.2)
        .chain(curve.iter().map(|c| c.1))
        .fold(0.0, f64::max)
        * 1.05;
    let (emp, ray) = target_percentiles(rep, pct);

    let mut legend = Legend::default();
    legend.add(
        Swatch::Patch(BAR, 1.0),
        format!("Monte Carlo histogram (n = {})", rep.n),
    );
    if let Some(s) = sigma {
        legend.add(
            Swatch::Line(RED, 3, None),
            format!("Rayleigh fit, σ̂ = {} (eq. 26)", angle(s)),
        );
    }
    if let Some(x) = emp {
        legend.add(
            Swatch::Line(palette(2), 2, None),
            format!("empirical {} = {}", theta_pct(pct), angle(x)),
        );
    }
    if let Some(x) = ray {
        legend.add(
            Swatch::Line(RED, 2, Some(DASHED)),
            format!("Rayleigh {} = {} (eq. 28)", theta_pct(pct), angle(x)),
        );
    }
    legend.add(
        Swatch::Line(BLACK, 2, Some(DOTTED)),
        format!("target {}", angle(target)),
    );
    if beyond > 0 {
        legend.add(
            Swatch::Text,
            format!(
                "{beyond} of {} samples ({}) lie beyond {} µrad (largest {} µrad): see the exceedance plot",
                rep.n,
                percent(beyond as f64 / thetas.len() as f64),
                number(round_sig(hi, 4)),
                number(round_sig(*thetas.last().unwrap_or(&hi), 4))
            ),
        );
    }

    let svg = render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let mut chart = captioned(area, title(rep, &format!("distortion angle {}", theta_p())))
            .top_x_label_area_size(50)
            .build_cartesian_2d(0.0..hi, 0.0..top.max(1e-12))?
            .set_secondary_coord(0.0..hi * ARCSEC_PER_MICRORAD, 0.0..top.max(1e-12));
        styled_mesh(&mut chart.configure_mesh())
            .x_desc(format!("{} [µrad]", theta_p()))
            .y_desc("probability density [1/µrad]")
            .draw()?;
        styled_secondary(&mut chart.configure_secondary_axes())
            .x_desc(format!("{} [arcsec]", theta_p()))
            .draw()?;
        chart.draw_series(
            hist.iter()
                .map(|&(a, b, d)| Rectangle::new([(a, 0.0), (b, d)], BAR.filled())),
        )?;
        if !curve.is_empty() {
            chart.draw_series(LineSeries::new(curve, RED.stroke_width(3)))?;
        }
        if let Some(x) = emp {
            chart.draw_series(LineSeries::new(
                vec![(x, 0.0), (x, top)],
                palette(2).stroke_width(2),
            ))?;
        }
        if let Some(x) = ray {
            chart.draw_series(pattern_series(
                vec![(x, 0.0), (x, top)],
                DASHED,
                RED.stroke_width(2),
            ))?;
        }
        chart.draw_series(pattern_series(
            vec![(target, 0.0), (target, top)],
            DOTTED,
            BLACK.stroke_width(2),
        ))?;
        Ok(())
    })?;
    Ok(Some(svg))
}

/// A fraction as a percentage with two significant digits.
pub fn percent(f: f64) -> String {
    format!("{} %", number(round_sig(100.0 * f, 2)))
}

/// The histograms of tan θ_x and tan θ_y with N(0, σ_t²); `None` without σ_t.
pub fn tan(
    case: &CaseData,
    rep: &CaseReport,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let sigma_t = match rep.rayleigh.sigma_t.get() {
        Some(s) if s > 0.0 && rep.n >= 2 => s * MICRORAD_PER_RAD,
        _ => return Ok(None),
    };
    let mut legend = Legend::default();
    legend.add(
        Swatch::Patch(BAR, 1.0),
        format!("Monte Carlo histogram (n = {})", rep.n),
    );
    legend.add(
        Swatch::Line(RED, 3, None),
        format!(
            "N(0, {}²), {} = {} × 10⁻⁶ (pooled, eqs. 19–20)",
            sub("σ", "t"),
            sub("σ", "t"),
            number(round_sig(sigma_t, 4))
        ),
    );
    let height = TITLE_HEIGHT + PANEL_ROW_HEIGHT;
    let svg = render(PANELS_WIDTH, height, &legend, |_, area| {
        let panels = titled_panels(area, &title(rep, "slopes of the top surface"), (1, 2))?;
        let hi = 4.5 * sigma_t;
        for (k, panel) in panels.iter().enumerate() {
            let (axis, stats) = if k == 0 {
                ("x", &rep.rayleigh.tan_theta_x)
            } else {
                ("y", &rep.rayleigh.tan_theta_y)
            };
            let values: Vec<f64> = case
                .points()
                .map(|p| if k == 0 { p.tan_x } else { p.tan_y } * MICRORAD_PER_RAD)
                .collect();
            let caption = format!(
                "mean {}, standard deviation {} (× 10⁻⁶)",
                number(round_sig(
                    stats.mean.get().unwrap_or(0.0) * MICRORAD_PER_RAD,
                    3
                )),
                number(round_sig(
                    stats.std.get().unwrap_or(0.0) * MICRORAD_PER_RAD,
                    4
                ))
            );
            let hist = histogram(&values, -hi, hi, bin_count(values.len()));
            let normal = |x: f64| {
                (-(x * x) / (2.0 * sigma_t * sigma_t)).exp()
                    / (sigma_t * (2.0 * std::f64::consts::PI).sqrt())
            };
            let ymax = hist.iter().map(|b| b.2).fold(normal(0.0), f64::max) * 1.05;
            let mut chart =
                truss_plot::frame::panel(panel, caption).build_cartesian_2d(-hi..hi, 0.0..ymax)?;
            styled_panel_mesh(&mut chart.configure_mesh())
                .x_desc(format!("10⁶ · tan {} [-]  (≈ µrad)", sub("θ", axis)))
                .y_desc("probability density [-]")
                .draw()?;
            chart.draw_series(
                hist.iter()
                    .map(|&(a, b, d)| Rectangle::new([(a, 0.0), (b, d)], BAR.filled())),
            )?;
            chart.draw_series(LineSeries::new(
                (0..=300).map(|i| {
                    let x = -hi + 2.0 * hi * i as f64 / 300.0;
                    (x, normal(x))
                }),
                RED.stroke_width(3),
            ))?;
        }
        Ok(())
    })?;
    Ok(Some(svg))
}

/// At most this many points are drawn per curve (all of the top [`TAIL`] order statistics,
/// the rest evenly spaced), so a plot of 10 million samples stays a small file.
const THIN: usize = 600;
/// The largest order statistics always drawn.
const TAIL: usize = 200;

/// The ranks (0-based) drawn of `n` sorted values.
fn thinned_ranks(n: usize) -> Vec<usize> {
    if n <= THIN + TAIL {
        return (0..n).collect();
    }
    let body = n - TAIL;
    let mut r: Vec<usize> = (0..THIN).map(|k| k * body / THIN).collect();
    r.extend(body..n);
    r
}

/// The Rayleigh QQ plot; `None` without a Rayleigh fit.
pub fn qq(
    case: &CaseData,
    rep: &CaseReport,
    report: &Report,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let Some(sigma) = rep.rayleigh.sigma.get().map(|s| s * MICRORAD_PER_RAD) else {
        return Ok(None);
    };
    let thetas = sorted_micro(case);
    let n = thetas.len();
    if n < 2 {
        return Ok(None);
    }
    let conf = report.settings.confidence;
    // Plotting positions (i − ½)/n; the band: the i-th of n uniform order statistics is
    // Beta(i, n + 1 − i), mapped through the fitted Rayleigh quantile.
    let rq = |u: f64| sigma * (-2.0 * (-u).ln_1p()).sqrt();
    let ranks = thinned_ranks(n);
    let points: Vec<(f64, f64)> = ranks
        .iter()
        .map(|&i| (rq((i as f64 + 0.5) / n as f64), thetas[i]))
        .collect();
    let band: Vec<(f64, f64, f64)> = ranks
        .iter()
        .step_by((ranks.len() / 150).max(1))
        .chain(ranks.last())
        .filter_map(|&i| {
            let b = Beta::new(i as f64 + 1.0, (n - i) as f64).ok()?;
            let x = rq((i as f64 + 0.5) / n as f64);
            Some((
                x,
                rq(b.inverse_cdf((1.0 - conf) / 2.0)),
                rq(b.inverse_cdf((1.0 + conf) / 2.0)),
            ))
        })
        .collect();
    let hi = points
        .iter()
        .map(|p| p.0.max(p.1))
        .chain(band.iter().map(|b| b.2))
        .fold(0.0, f64::max)
        * 1.04;
    let mut legend = Legend::default();
    legend.add(
        Swatch::Marker(palette(2), 3),
        format!(
            "sample quantiles against the fitted Rayleigh (σ̂ = {}){}",
            angle(sigma),
            if n > THIN + TAIL {
                format!(": {THIN} evenly spaced and the top {TAIL} of {n}")
            } else {
                String::new()
            }
        ),
    );
    legend.add(Swatch::Line(BLACK, 2, None), "y = x: a Rayleigh law");
    legend.add(
        Swatch::Patch(RED, 0.2),
        format!(
            "pointwise {} band of the order statistics under the fitted law",
            percent(conf)
        ),
    );
    let svg = render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let a = hi * ARCSEC_PER_MICRORAD;
        let mut chart = captioned(
            area,
            title(rep, &format!("Rayleigh QQ plot of {}", theta_p())),
        )
        .top_x_label_area_size(50)
        .right_y_label_area_size(70)
        .build_cartesian_2d(0.0..hi, 0.0..hi)?
        .set_secondary_coord(0.0..a, 0.0..a);
        styled_mesh(&mut chart.configure_mesh())
            .x_desc("Rayleigh quantile [µrad]")
            .y_desc(format!("sample quantile of {} [µrad]", theta_p()))
            .draw()?;
        styled_secondary(&mut chart.configure_secondary_axes())
            .x_desc("Rayleigh quantile [arcsec]")
            .y_desc("sample quantile [arcsec]")
            .draw()?;
        let mut outline: Vec<(f64, f64)> = band.iter().map(|b| (b.0, b.1)).collect();
        outline.extend(band.iter().rev().map(|b| (b.0, b.2)));
        chart.draw_series(std::iter::once(Polygon::new(
            outline,
            RED.mix(0.2).filled(),
        )))?;
        chart.draw_series(LineSeries::new(
            vec![(0.0, 0.0), (hi, hi)],
            BLACK.stroke_width(2),
        ))?;
        chart.draw_series(
            points
                .iter()
                .map(|&p| Circle::new(p, 3, palette(2).filled())),
        )?;
        Ok(())
    })?;
    Ok(Some(svg))
}

/// The exceedance plot; `None` with fewer than two samples.
pub fn exceedance(
    case: &CaseData,
    rep: &CaseReport,
    report: &Report,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let thetas = sorted_micro(case);
    let n = thetas.len();
    if n < 2 {
        return Ok(None);
    }
    let nf = n as f64;
    // 1 − F_n just below each order statistic x₍ᵢ₎ (1-based i): (n − i + 1)/n, from 1 to 1/n.
    let points: Vec<(f64, f64)> = thinned_ranks(n)
        .into_iter()
        .map(|i| (thetas[i], (n - i) as f64 / nf))
        .collect();
    let hi = thetas[n - 1] * 1.04;
    let floor = 0.5 / nf;
    let sigma = rep.rayleigh.sigma.get().map(|s| s * MICRORAD_PER_RAD);
    let target = report.settings.target_angle * MICRORAD_PER_RAD;
    let pct = report.sweep.percentile.0;
    let mut marks: Vec<(f64, f64, RGBColor)> = vec![];
    for (k, p) in [pct / 100.0, 0.99, 0.999].into_iter().enumerate() {
        // A percentile is marked only where at least 10 samples lie above it.
        if (1.0 - p) * nf >= 10.0
            && !marks.iter().any(|m| m.0 == p)
            && let Some(q) = crate::quantile::quantile_sorted(&thetas, p)
        {
            marks.push((p, q, palette(k + 3)));
        }
    }
    let mut legend = Legend::default();
    legend.add(
        Swatch::Line(palette(2), 2, None),
        format!("Monte Carlo, 1 − F(x) = fraction of the {n} samples at or above x"),
    );
    if let Some(s) = sigma {
        legend.add(
            Swatch::Line(RED, 2, Some(DASHED)),
            format!("fitted Rayleigh, exp(−x²/2σ̂²), σ̂ = {}", angle(s)),
        );
    }
    for &(p, q, color) in &marks {
        legend.add(
            Swatch::Line(color, 2, None),
            format!("empirical {} = {}", theta_pct(100.0 * p), angle(q)),
        );
    }
    for p in [0.99, 0.999] {
        if !marks.iter().any(|m| m.0 == p) {
            legend.add(
                Swatch::Text,
                format!(
                    "{}: not marked, fewer than 10 of {n} samples lie above it",
                    theta_pct(100.0 * p)
                ),
            );
        }
    }
    legend.add(
        Swatch::Line(BLACK, 2, Some(DOTTED)),
        format!("target {}", angle(target)),
    );
    let svg = render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let xmax = hi.max(target * 1.04);
        let mut chart = captioned(area, title(rep, &format!("exceedance of {}", theta_p())))
            .top_x_label_area_size(50)
            .build_cartesian_2d(0.0..xmax, (floor..1.0).log_scale())?
            .set_secondary_coord(0.0..xmax * ARCSEC_PER_MICRORAD, (floor..1.0).log_scale());
        styled_mesh(&mut chart.configure_mesh())
            .x_desc(format!("{} [µrad]", theta_p()))
            .y_desc("1 − F: probability of exceeding [-]")
            .draw()?;
        styled_secondary(&mut chart.configure_secondary_axes())
            .x_desc(format!("{} [arcsec]", theta_p()))
            .draw()?;
        chart.draw_series(LineSeries::new(points, palette(2).stroke_width(2)))?;
        if let Some(s) = sigma {
            let curve: Vec<(f64, f64)> = (0..=300)
                .map(|i| xmax * i as f64 / 300.0)
                .map(|x| (x, (-(x * x) / (2.0 * s * s)).exp()))
                .take_while(|p| p.1 >= floor)
                .collect();
            chart.draw_series(pattern_series(curve, DASHED, RED.stroke_width(2)))?;
        }
        for &(p, q, color) in &marks {
            chart.draw_series(LineSeries::new(
                vec![(0.0, 1.0 - p), (q, 1.0 - p), (q, floor)],
                color.stroke_width(2),
            ))?;
        }
        chart.draw_series(pattern_series(
            vec![(target, floor), (target, 1.0)],
            DOTTED,
            BLACK.stroke_width(2),
        ))?;
        Ok(())
    })?;
    Ok(Some(svg))
}

/// The running target percentile; `None` when n is too small for one interval.
pub fn running(
    case: &CaseData,
    rep: &CaseReport,
    report: &Report,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let in_order: Vec<f64> = case.points().map(|p| p.theta * MICRORAD_PER_RAD).collect();
    let n = in_order.len();
    let pct = report.sweep.percentile.0;
    let p = pct / 100.0;
    let conf = report.settings.confidence;
    // Sample counts on a log grid, 10 per decade, up to n.
    let mut counts: Vec<usize> = (0..)
        .map(|k| (10f64.powf(1.0 + k as f64 / 10.0)).round() as usize)
        .take_while(|&m| m < n)
        .collect();
    counts.dedup();
    counts.push(n);
    let mut rows: Vec<(f64, f64, f64, f64)> = vec![];
    for &m in &counts {
        let mut prefix = in_order[..m].to_vec();
        prefix.sort_by(f64::total_cmp);
        if let (Some(q), Ok(ci)) = (
            crate::quantile::quantile_sorted(&prefix, p),
            crate::quantile::order_statistic_interval(&prefix, p, conf),
        ) {
            rows.push((m as f64, q, ci.lower, ci.upper));
        }
    }
    if rows.len() < 2 {
        return Ok(None);
    }
    let target = report.settings.target_angle * MICRORAD_PER_RAD;
    let last = rows[rows.len() - 1];
    let (lo, hi) = rows
        .iter()
        .fold((f64::MAX, target), |(lo, hi), r| (lo.min(r.2), hi.max(r.3)));
    let (ylo, yhi) = ((lo.min(target) * 0.95).max(0.0), hi * 1.03);
    let x0 = rows[0].0;
    let mut legend = Legend::default();
    legend.add(
        Swatch::Line(palette(2), 2, None),
        format!(
            "{} of the first n samples (in index order), {} at n = {}",
            theta_pct(pct),
            angle(last.1),
            n
        ),
    );
    legend.add(
        Swatch::Patch(palette(2), 0.2),
        format!(
            "distribution-free {} interval (order statistics), [{}, {}] µrad at n = {}",
            percent(conf),
            number(round_sig(last.2, 4)),
            number(round_sig(last.3, 4)),
            n
        ),
    );
    legend.add(
        Swatch::Line(BLACK, 2, Some(DOTTED)),
        format!("target {}", angle(target)),
    );
    let svg = render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let xr = (x0..n as f64 * 1.05).log_scale();
        let mut chart = captioned(
            area,
            title(
                rep,
                &format!("running {} against the sample count", theta_pct(pct)),
            ),
        )
        .right_y_label_area_size(70)
        .build_cartesian_2d(xr.clone(), ylo..yhi)?
        .set_secondary_coord(xr, ylo * ARCSEC_PER_MICRORAD..yhi * ARCSEC_PER_MICRORAD);
        styled_mesh(&mut chart.configure_mesh())
            .x_desc("samples n [-]")
            .y_desc(format!("{} [µrad]", theta_pct(pct)))
            .draw()?;
        styled_secondary(&mut chart.configure_secondary_axes())
            .y_desc(format!("{} [arcsec]", theta_pct(pct)))
            .draw()?;
        let mut outline: Vec<(f64, f64)> = rows.iter().map(|r| (r.0, r.2)).collect();
        outline.extend(rows.iter().rev().map(|r| (r.0, r.3)));
        chart.draw_series(std::iter::once(Polygon::new(
            outline,
            palette(2).mix(0.2).filled(),
        )))?;
        chart.draw_series(LineSeries::new(
            rows.iter().map(|r| (r.0, r.1)),
            palette(2).stroke_width(2),
        ))?;
        chart.draw_series(pattern_series(
            vec![(x0, target), (n as f64 * 1.05, target)],
            DOTTED,
            BLACK.stroke_width(2),
        ))?;
        Ok(())
    })?;
    Ok(Some(svg))
}
