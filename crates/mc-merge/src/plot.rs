//! SVG plots for a design review, after the paper's figures:
//!
//! - `theta_p-CASE.svg`: histogram of θ_P (as a density) with the fitted Rayleigh density and the
//!   empirical and Rayleigh target percentiles and the target angle marked (Figs. 4, 7).
//! - `tan-CASE.svg`: histograms of tan θ_x and tan θ_y with the N(0, σ_t²) density (Fig. 6).
//! - `sigma-sweep.svg`: θ_P at the target percentile against σ, every σ-series on one plot
//!   with its error bars, its line through the origin, the target angle and the allowable σ
//!   (Figs. 3, 16).
//! - `stages-sweep.svg`: the normalised percentile against the number of stages with error
//!   bars (Fig. 9).
//!
//! Angles are drawn in µrad, slopes tan θ in units of 10⁻⁶; axis labels carry the units.

use crate::cli::ARCSEC_PER_RAD;
use crate::errors::MergeError;
use crate::load::CaseData;
use crate::report::{CaseReport, Figure, Report};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

type PlotResult = Result<(), Box<dyn std::error::Error>>;

const MICRO: f64 = 1e6;
const SIZE: (u32, u32) = (960, 640);
const FONT: &str = "sans-serif";
const LIGHT: RGBColor = RGBColor(236, 236, 236);

fn palette(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(0, 0, 0),
        RGBColor(200, 30, 30),
        RGBColor(30, 90, 200),
        RGBColor(20, 140, 60),
        RGBColor(150, 60, 170),
        RGBColor(220, 130, 0),
        RGBColor(0, 150, 160),
        RGBColor(120, 80, 40),
    ];
    C[i % C.len()]
}

/// A file-name-safe form of a case name.
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Bins `values` on [lo, hi) into a density histogram: (left, right, density).
fn histogram(
    values: impl Iterator<Item = f64>,
    lo: f64,
    hi: f64,
    bins: usize,
) -> Vec<(f64, f64, f64)> {
    let mut counts = vec![0u64; bins];
    let mut n = 0u64;
    let w = (hi - lo) / bins as f64;
    for v in values {
        n += 1;
        let k = ((v - lo) / w).floor();
        if k >= 0.0 && (k as usize) < bins {
            counts[k as usize] += 1;
        }
    }
    counts
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            let a = lo + k as f64 * w;
            (a, a + w, c as f64 / (n.max(1) as f64 * w))
        })
        .collect()
}

/// Rice's rule, 2·n^(1/3) bins, between 10 and 120.
fn bin_count(n: usize) -> usize {
    ((2.0 * (n as f64).cbrt()).ceil() as usize).clamp(10, 120)
}

fn vline(x: f64, y0: f64, y1: f64, color: RGBColor) -> PathElement<(f64, f64)> {
    PathElement::new(vec![(x, y0), (x, y1)], color.stroke_width(2))
}

fn theta_plot(path: &Path, case: &CaseData, rep: &CaseReport, report: &Report) -> PlotResult {
    let mut thetas: Vec<f64> = case.points().map(|p| p.theta * MICRO).collect();
    if thetas.len() < 2 {
        return Ok(());
    }
    thetas.sort_by(f64::total_cmp);
    let pct = report.sweep.percentile.0;
    let target = report.settings.target_angle * MICRO;
    let q999 = crate::quantile::quantile_sorted(&thetas, 0.999).unwrap_or(1.0);
    let hi = q999.max(target) * 1.08;
    let hist = histogram(thetas.iter().copied(), 0.0, hi, bin_count(thetas.len()));
    let sigma = rep.rayleigh.sigma.get().map(|s| s * MICRO);
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
        .fold(0.0, f64::max);
    // Head room for the legend above the data.
    let ymax = top * 1.5;
    let line_top = top * 1.05;
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let title = format!(
        "{} — distortion angle θ_P, n = {}{}",
        rep.name,
        rep.n,
        if rep.caveats.is_empty() {
            ""
        } else {
            " (see caveats)"
        }
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 22))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..hi, 0.0..ymax.max(1e-12))?;
    chart
        .configure_mesh()
        .x_desc("θ_P [µrad]   (1 µrad = 0.206 arcsec)")
        .y_desc("probability density [1/µrad]")
        .light_line_style(LIGHT)
        .axis_desc_style((FONT, 18))
        .label_style((FONT, 15))
        .draw()?;
    chart
        .draw_series(hist.iter().map(|&(a, b, d)| {
            Rectangle::new(
                [(a, 0.0), (b, d)],
                RGBColor(120, 150, 200).mix(0.6).filled(),
            )
        }))?
        .label(format!("Monte Carlo histogram (n = {})", rep.n))
        .legend(|(x, y)| {
            Rectangle::new(
                [(x, y - 5), (x + 18, y + 5)],
                RGBColor(120, 150, 200).filled(),
            )
        });
    if let Some(s) = sigma {
        chart
            .draw_series(LineSeries::new(curve, RED.stroke_width(3)))?
            .label(format!("Rayleigh fit, σ̂ = {:.3} µrad (eq. 26)", s))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(3)));
    }
    let emp = rep
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value);
    if let Some(e) = emp {
        let x = e.0 * MICRO;
        chart
            .draw_series(std::iter::once(vline(x, 0.0, line_top, palette(2))))?
            .label(format!(
                "empirical θ_P{pct} = {:.2} µrad ({:.2}\")",
                x,
                e.0 * ARCSEC_PER_RAD
            ))
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], palette(2).stroke_width(2))
            });
    }
    if let Some(r) = rep
        .rayleigh
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value.get())
    {
        let x = r * MICRO;
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x, 0.0), (x, line_top)],
                8,
                5,
                RED.stroke_width(2),
            ))?
            .label(format!("Rayleigh θ_P{pct} = {:.2} µrad (eq. 28)", x))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(2)));
    }
    chart
        .draw_series(DashedLineSeries::new(
            vec![(target, 0.0), (target, line_top)],
            4,
            4,
            BLACK.stroke_width(2),
        ))?
        .label(format!(
            "target {:.2} µrad ({:.1}\")",
            target,
            report.settings.target_angle * ARCSEC_PER_RAD
        ))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

fn tan_plot(path: &Path, case: &CaseData, rep: &CaseReport) -> PlotResult {
    let sigma_t = match rep.rayleigh.sigma_t.get() {
        Some(s) if s > 0.0 && rep.n >= 2 => s * MICRO,
        _ => return Ok(()),
    };
    let root = SVGBackend::new(path, (1200, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title_area, body) = root.split_vertically(40);
    title_area.titled(
        &format!(
            "{} — slopes of the top surface, n = {}; red: N(0, σ_t²), σ_t = {:.3}×10⁻⁶ (eqs. 19–20)",
            rep.name, rep.n, sigma_t
        ),
        (FONT, 20),
    )?;
    let panels = body.split_evenly((1, 2));
    let hi = 4.5 * sigma_t;
    for (k, panel) in panels.iter().enumerate() {
        let (label, values, stats): (&str, Vec<f64>, _) = if k == 0 {
            (
                "tan θ_x [×10⁻⁶]",
                case.points().map(|p| p.tan_x * MICRO).collect(),
                &rep.rayleigh.tan_theta_x,
            )
        } else {
            (
                "tan θ_y [×10⁻⁶]",
                case.points().map(|p| p.tan_y * MICRO).collect(),
                &rep.rayleigh.tan_theta_y,
            )
        };
        let caption = format!(
            "mean {:.3}, std {:.3} (×10⁻⁶)",
            stats.mean.get().unwrap_or(0.0) * MICRO,
            stats.std.get().unwrap_or(0.0) * MICRO
        );
        let hist = histogram(values.iter().copied(), -hi, hi, bin_count(values.len()));
        let normal = |x: f64| {
            (-(x * x) / (2.0 * sigma_t * sigma_t)).exp()
                / (sigma_t * (2.0 * std::f64::consts::PI).sqrt())
        };
        let ymax = hist.iter().map(|b| b.2).fold(normal(0.0), f64::max) * 1.15;
        let mut chart = ChartBuilder::on(panel)
            .caption(caption, (FONT, 16))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(-hi..hi, 0.0..ymax)?;
        chart
            .configure_mesh()
            .x_desc(label)
            .y_desc("probability density [1/10⁻⁶]")
            .light_line_style(LIGHT)
            .axis_desc_style((FONT, 17))
            .label_style((FONT, 14))
            .draw()?;
        chart.draw_series(hist.iter().map(|&(a, b, d)| {
            Rectangle::new(
                [(a, 0.0), (b, d)],
                RGBColor(120, 150, 200).mix(0.6).filled(),
            )
        }))?;
        chart.draw_series(LineSeries::new(
            (0..=300).map(|i| {
                let x = -hi + 2.0 * hi * i as f64 / 300.0;
                (x, normal(x))
            }),
            RED.stroke_width(3),
        ))?;
    }
    root.present()?;
    Ok(())
}

fn error_bar(x: f64, lo: f64, hi: f64, half: f64, color: RGBColor) -> Vec<PathElement<(f64, f64)>> {
    vec![
        PathElement::new(vec![(x, lo), (x, hi)], color.stroke_width(2)),
        PathElement::new(vec![(x - half, lo), (x + half, lo)], color.stroke_width(2)),
        PathElement::new(vec![(x - half, hi), (x + half, hi)], color.stroke_width(2)),
    ]
}

fn interval_or_point(f: &Figure) -> Option<(f64, f64, f64)> {
    let v = f.get()?;
    let (lo, hi) = f.interval().unwrap_or((v, v));
    Some((v, lo, hi))
}

fn sigma_plot(path: &Path, report: &Report) -> PlotResult {
    let series = &report.sweep.sigma_series;
    let target = report.settings.target_angle * MICRO;
    let pct = report.sweep.percentile.0;
    let mut xmax: f64 = 0.0;
    let mut ymax: f64 = target;
    for s in series {
        for p in &s.points {
            xmax = xmax.max(p.x.0);
            if let Some((_, _, hi)) = interval_or_point(&p.value) {
                ymax = ymax.max(hi * MICRO);
            }
        }
        if let Some(a) = s.allowable_sigma.through_origin.get() {
            xmax = xmax.max(a);
        }
    }
    let (xmax, ymax) = (xmax * 1.08, ymax * 1.1);
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "θ_P{pct} against member length σ ({:.0} % intervals), target {:.1}\"",
                report.settings.confidence * 100.0,
                report.settings.target_angle * ARCSEC_PER_RAD
            ),
            (FONT, 22),
        )
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)?;
    chart
        .configure_mesh()
        .x_desc("standard deviation of member length σ [mm]")
        .y_desc(format!("{pct}th percentile of θ_P [µrad]"))
        .light_line_style(LIGHT)
        .axis_desc_style((FONT, 18))
        .label_style((FONT, 15))
        .draw()?;
    let half = xmax * 0.006;
    for (k, s) in series.iter().enumerate() {
        let color = palette(k);
        let pts: Vec<(f64, f64, f64, f64)> = s
            .points
            .iter()
            .filter_map(|p| {
                let (v, lo, hi) = interval_or_point(&p.value)?;
                Some((p.x.0, v * MICRO, lo * MICRO, hi * MICRO))
            })
            .collect();
        for &(x, _, lo, hi) in &pts {
            chart.draw_series(error_bar(x, lo, hi, half, color))?;
        }
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y, _, _)| Circle::new((x, y), 5, color.filled())),
            )?
            .label(format!(
                "{} (points, {:.0} % CI)",
                s.name,
                report.settings.confidence * 100.0
            ))
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, color.filled()));
        if let Some(b) = s.through_origin.slope.get() {
            let b = b * MICRO;
            let allow = s.allowable_sigma.through_origin.get();
            chart
                .draw_series(LineSeries::new(
                    vec![(0.0, 0.0), (xmax, b * xmax)],
                    color.stroke_width(2),
                ))?
                .label(format!(
                    "  fit through origin, slope {:.4e} rad/mm; allowable σ = {}",
                    b / MICRO,
                    allow.map_or("-".to_string(), |a| format!("{a:.3e} mm"))
                ))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
            if let Some(a) = allow {
                chart.draw_series(DashedLineSeries::new(
                    vec![(a, 0.0), (a, target)],
                    6,
                    4,
                    color.stroke_width(1),
                ))?;
                chart.draw_series(std::iter::once(Cross::new(
                    (a, target),
                    7,
                    color.stroke_width(3),
                )))?;
                if let Some((lo, hi)) = s.allowable_sigma.through_origin.interval() {
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(lo, target), (hi, target)],
                        color.stroke_width(4),
                    )))?;
                }
            }
        }
    }
    chart
        .draw_series(DashedLineSeries::new(
            vec![(0.0, target), (xmax, target)],
            8,
            5,
            BLACK.stroke_width(1),
        ))?
        .label(format!(
            "target {:.3e} rad ({:.1}\")",
            report.settings.target_angle,
            report.settings.target_angle * ARCSEC_PER_RAD
        ))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

fn stages_plot(path: &Path, report: &Report) -> PlotResult {
    let series = &report.sweep.stages_series;
    let pct = report.sweep.percentile.0;
    let mut xmax: f64 = 1.0;
    let mut ymax: f64 = 1.0;
    for s in series {
        for p in &s.points {
            xmax = xmax.max(p.stages.0);
            if let Some((_, hi)) = p.relative_interval.get() {
                ymax = ymax.max(hi);
            }
            if let Some(v) = p.normalised.get() {
                ymax = ymax.max(v);
            }
        }
    }
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "normalised θ_P{pct} against the number of stages ({:.0} % intervals)",
                report.settings.confidence * 100.0
            ),
            (FONT, 22),
        )
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..xmax * 1.05 + 0.5, 0.0..ymax * 1.15)?;
    chart
        .configure_mesh()
        .x_desc("number of stages [-]")
        .y_desc(format!(
            "θ_P{pct} / θ_P{pct} of the smallest stage count [-]"
        ))
        .light_line_style(LIGHT)
        .x_label_formatter(&|x| format!("{x:.0}"))
        .axis_desc_style((FONT, 18))
        .label_style((FONT, 15))
        .draw()?;
    for (k, s) in series.iter().enumerate() {
        let color = palette(k + 1);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter_map(|p| Some((p.stages.0, p.normalised.get()?)))
            .collect();
        let mut sorted = pts.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        for p in &s.points {
            if let Some((lo, hi)) = p.relative_interval.get() {
                chart.draw_series(error_bar(p.stages.0, lo, hi, 0.15, color))?;
            }
        }
        chart
            .draw_series(LineSeries::new(sorted, color.stroke_width(2)))?
            .label(format!(
                "{} (normalised to {} stage(s)){}",
                s.name,
                s.reference_stages.0,
                s.peak_stages
                    .map_or(String::new(), |p| format!(", peak at {} stages", p.0))
            ))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart.draw_series(
            pts.iter()
                .map(|&(x, y)| Circle::new((x, y), 5, color.filled())),
        )?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .label_font((FONT, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// Draws every plot into `dir`; returns the files written.
pub fn draw_all(
    dir: &Path,
    cases: &[CaseData],
    report: &Report,
) -> Result<Vec<PathBuf>, MergeError> {
    let mut written = vec![];
    let mut run = |path: PathBuf, f: &dyn Fn(&Path) -> PlotResult| -> Result<(), MergeError> {
        f(&path).map_err(|e| MergeError::Plot {
            path: path.clone(),
            message: e.to_string(),
        })?;
        if path.exists() {
            written.push(path);
        }
        Ok(())
    };
    for (case, rep) in cases.iter().zip(&report.cases) {
        let stem = file_stem(&rep.name);
        run(dir.join(format!("theta_p-{stem}.svg")), &|p| {
            theta_plot(p, case, rep, report)
        })?;
        run(dir.join(format!("tan-{stem}.svg")), &|p| {
            tan_plot(p, case, rep)
        })?;
    }
    if !report.sweep.sigma_series.is_empty() {
        run(dir.join("sigma-sweep.svg"), &|p| sigma_plot(p, report))?;
    }
    if !report.sweep.stages_series.is_empty() {
        run(dir.join("stages-sweep.svg"), &|p| stages_plot(p, report))?;
    }
    Ok(written)
}
