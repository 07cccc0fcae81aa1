//! The plots over several cases:
//!
//! - [`sigma`]: θ_P at the target percentile against σ on log–log axes (a line through the
//!   origin is a straight line of slope 1 there, and close σ values stay apart), every
//!   σ-series with its confidence intervals, its line through the origin, the target and the
//!   allowable σ (paper Figs. 3, 16); below it, each point's relative deviation from its line,
//!   where the intervals are large enough to see;
//! - [`stages`]: the normalised percentile against the number of stages (paper Fig. 9).

use crate::report::{Figure, Report};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use truss_plot::frame::*;
use truss_plot::legend::*;
use truss_plot::style::*;
use truss_units::{ARCSEC_PER_MICRORAD, MICRORAD_PER_RAD};

type Drawn = Result<Option<String>, Box<dyn std::error::Error>>;

fn error_bar(x: (f64, f64), lo: f64, hi: f64, color: RGBColor) -> Vec<PathElement<(f64, f64)>> {
    // Caps a few percent of the (log) x range wide: x multiplied and divided by 1.04.
    let (x, half) = x;
    vec![
        PathElement::new(vec![(x, lo), (x, hi)], color.stroke_width(2)),
        PathElement::new(vec![(x / half, lo), (x * half, lo)], color.stroke_width(2)),
        PathElement::new(vec![(x / half, hi), (x * half, hi)], color.stroke_width(2)),
    ]
}

fn interval_or_point(f: &Figure) -> Option<(f64, f64, f64)> {
    let v = f.get()?;
    let (lo, hi) = f.interval().unwrap_or((v, v));
    Some((v, lo, hi))
}

/// The σ-sweep plot; `None` without a σ-series with a positive σ.
pub fn sigma(report: &Report) -> Drawn {
    let series = &report.sweep.sigma_series;
    let target = report.settings.target_angle * MICRORAD_PER_RAD;
    let pct = report.sweep.percentile.0;
    let conf = percent_label(report.settings.confidence);
    // (σ mm, value, lower, upper in µrad) per series, positive σ only (log axis).
    let points: Vec<Vec<(f64, f64, f64, f64)>> = series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .filter(|p| p.x.0 > 0.0)
                .filter_map(|p| {
                    let (v, lo, hi) = interval_or_point(&p.value)?;
                    (lo > 0.0).then_some((
                        p.x.0,
                        v * MICRORAD_PER_RAD,
                        lo * MICRORAD_PER_RAD,
                        hi * MICRORAD_PER_RAD,
                    ))
                })
                .collect()
        })
        .collect();
    let all = points.iter().flatten();
    let (mut xlo, mut xhi, mut ylo, mut yhi) = (f64::MAX, 0.0f64, target, target);
    for &(x, _, lo, hi) in all {
        xlo = xlo.min(x);
        xhi = xhi.max(x);
        ylo = ylo.min(lo);
        yhi = yhi.max(hi);
    }
    for s in series {
        if let Some(a) = s.allowable_sigma.through_origin.get().filter(|a| *a > 0.0) {
            xlo = xlo.min(a);
            xhi = xhi.max(a);
        }
    }
    if xhi <= 0.0 || xlo > xhi {
        return Ok(None);
    }
    let (xlo, xhi, ylo, yhi) = (xlo / 1.3, xhi * 1.3, ylo / 1.3, yhi * 1.3);
    let slopes: Vec<Option<f64>> = series
        .iter()
        .map(|s| s.through_origin.slope.get().map(|b| b * MICRORAD_PER_RAD))
        .collect();
    // Relative deviations from the line through the origin, in percent.
    let deviations: Vec<Vec<(f64, f64, f64, f64)>> = points
        .iter()
        .zip(&slopes)
        .map(|(pts, b)| match b {
            Some(b) if *b > 0.0 => pts
                .iter()
                .map(|&(x, v, lo, hi)| {
                    let line = b * x;
                    (
                        x,
                        100.0 * (v / line - 1.0),
                        100.0 * (lo / line - 1.0),
                        100.0 * (hi / line - 1.0),
                    )
                })
                .collect(),
            _ => vec![],
        })
        .collect();
    let dev = deviations
        .iter()
        .flatten()
        .map(|d| d.2.abs().max(d.3.abs()))
        .fold(1.0, f64::max)
        * 1.2;

    let mut legend = Legend::default();
    for (k, s) in series.iter().enumerate() {
        let color = palette(k);
        legend.add(
            Swatch::MarkerWithBar(color, 4),
            format!(
                "{}: {} with its {conf} interval (bootstrap)",
                s.name,
                theta_pct(pct)
            ),
        );
        if let Some(b) = slopes[k] {
            let allow = &s.allowable_sigma.through_origin;
            legend.add(
                Swatch::Line(color, 2, None),
                format!(
                    "line through the origin, {} = {} µrad/mm · σ",
                    theta_pct(pct),
                    number(round_sig(b, 4))
                ),
            );
            if let Some(a) = allow.get() {
                legend.add(
                    Swatch::Cross(color),
                    format!(
                        "allowable σ = {} mm{}{}",
                        number(round_sig(a, 3)),
                        allow.interval().map_or(String::new(), |(lo, hi)| format!(
                            ", {conf} interval [{}, {}] mm (bar)",
                            number(round_sig(lo, 3)),
                            number(round_sig(hi, 3))
                        )),
                        if s.allowable_sigma.extrapolated {
                            ", extrapolated beyond the σ range"
                        } else {
                            ""
                        }
                    ),
                );
            }
        }
    }
    legend.add(
        Swatch::Line(BLACK, 1, Some(DOTTED)),
        format!("target {}", angle(target)),
    );

    let (main_height, dev_height) = (560, 240);
    let svg = render(WIDTH, main_height + dev_height, &legend, |root, upper| {
        let (main, lower) = upper.split_vertically(main_height);
        let xr = (xlo..xhi).log_scale();
        let mut chart = captioned(
            &main,
            format!(
                "{} against the member length σ ({conf} intervals), target {}",
                theta_pct(pct),
                angle(target)
            ),
        )
        .x_label_area_size(40)
        .right_y_label_area_size(70)
        .build_cartesian_2d(xr.clone(), (ylo..yhi).log_scale())?
        .set_secondary_coord(
            xr.clone(),
            (ylo * ARCSEC_PER_MICRORAD..yhi * ARCSEC_PER_MICRORAD).log_scale(),
        );
        styled_mesh(&mut chart.configure_mesh())
            .y_desc(format!("{} [µrad]", theta_pct(pct)))
            .x_label_formatter(&|_| String::new())
            .y_label_formatter(&|_| String::new())
            .draw()?;
        styled_secondary(&mut chart.configure_secondary_axes())
            .y_desc(format!("{} [arcsec]", theta_pct(pct)))
            .draw()?;
        for t in log_ticks(ylo, yhi) {
            let (px, py) = chart.backend_coord(&(xlo, t));
            root.draw(&Text::new(
                tick(&t),
                (px - 8, py),
                label_style(HPos::Right, VPos::Center),
            ))?;
        }
        let cap = 10f64.powf((xhi / xlo).log10() * 0.006);
        chart.draw_series(pattern_series(
            vec![(xlo, target), (xhi, target)],
            DOTTED,
            BLACK.stroke_width(1),
        ))?;
        // The target marked on the θ axis, where its line starts, and on the arcsec axis,
        // where it ends (a tick and its value in arcsec, beside that axis's own labels).
        let (px, py) = chart.backend_coord(&(xlo, target));
        root.draw(&Text::new(
            format!("target {}", angle(target)),
            (px + 6, py - 4),
            label_style(HPos::Left, VPos::Bottom),
        ))?;
        let (qx, qy) = chart.backend_coord(&(xhi, target));
        root.draw(&PathElement::new(
            vec![(qx, qy), (qx + 6, qy)],
            BLACK.stroke_width(1),
        ))?;
        root.draw(&Text::new(
            format!("{:.2}″", target * ARCSEC_PER_MICRORAD),
            (qx + 9, qy),
            label_style(HPos::Left, VPos::Center),
        ))?;
        for (k, s) in series.iter().enumerate() {
            let color = palette(k);
            if let Some(b) = slopes[k] {
                chart.draw_series(LineSeries::new(
                    vec![(xlo, b * xlo), (xhi, b * xhi)],
                    color.stroke_width(2),
                ))?;
                if let Some(a) = s.allowable_sigma.through_origin.get().filter(|a| *a > 0.0) {
                    if let Some((lo, hi)) = s.allowable_sigma.through_origin.interval() {
                        chart.draw_series(std::iter::once(PathElement::new(
                            vec![(lo.max(xlo), target), (hi.min(xhi), target)],
                            color.mix(0.6).stroke_width(6),
                        )))?;
                    }
                    chart.draw_series(std::iter::once(Cross::new(
                        (a, target),
                        7,
                        color.stroke_width(3),
                    )))?;
                    // The allowable σ marked on the σ axis: dropped from the target line
                    // and written where it meets the axis.
                    chart.draw_series(pattern_series(
                        vec![(a, ylo), (a, target)],
                        DOTTED,
                        color.stroke_width(1),
                    ))?;
                    let (px, py) = chart.backend_coord(&(a, ylo));
                    root.draw(&Text::new(
                        format!("σ = {} mm", number(round_sig(a, 3))),
                        (px + 4, py - 4),
                        label_style(HPos::Left, VPos::Bottom),
                    ))?;
                }
            }
            for &(x, v, lo, hi) in &points[k] {
                chart.draw_series(error_bar((x, cap), lo, hi, color))?;
                chart.draw_series(std::iter::once(Circle::new((x, v), 4, WHITE.filled())))?;
                chart.draw_series(std::iter::once(Circle::new(
                    (x, v),
                    4,
                    color.stroke_width(2),
                )))?;
            }
        }
        let mut chart = ChartBuilder::on(&lower)
            .margin(16)
            .margin_top(0)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .right_y_label_area_size(70)
            .build_cartesian_2d(xr.clone(), -dev..dev)?
            .set_secondary_coord(xr, -dev..dev);
        chart
            .configure_mesh()
            .x_desc("standard deviation of the member lengths σ [mm]")
            .y_desc("deviation from the line [%]")
            .x_label_formatter(&|_| String::new())
            .y_label_formatter(&tick)
            .y_labels(5)
            .light_line_style(LIGHT)
            .axis_desc_style((FONT, text::PANEL_CAPTION))
            .label_style((FONT, text::LABEL))
            .draw()?;
        // The right-hand label area only keeps the panels aligned: no labels there.
        chart
            .configure_secondary_axes()
            .y_label_formatter(&|_| String::new())
            .draw()?;
        chart.draw_series(LineSeries::new(
            vec![(xlo, 0.0), (xhi, 0.0)],
            BLACK.stroke_width(1),
        ))?;
        // plotters labels a log axis only from its first power of ten on: the σ ticks
        // (1, 2, 5 × 10^k mm) are written here instead.
        for t in log_ticks(xlo, xhi) {
            let (px, py) = chart.backend_coord(&(t, -dev));
            root.draw(&Text::new(
                tick(&t),
                (px, py + 8),
                label_style(HPos::Center, VPos::Top),
            ))?;
        }
        for (k, devs) in deviations.iter().enumerate() {
            let color = palette(k);
            for &(x, v, lo, hi) in devs {
                chart.draw_series(error_bar((x, cap), lo, hi, color))?;
                chart.draw_series(std::iter::once(Circle::new((x, v), 4, WHITE.filled())))?;
                chart.draw_series(std::iter::once(Circle::new(
                    (x, v),
                    4,
                    color.stroke_width(2),
                )))?;
            }
        }
        Ok(())
    })?;
    Ok(Some(svg))
}

/// A tick label's style, anchored as given.
fn label_style(h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle::from((FONT, text::LABEL).into_font()).pos(Pos::new(h, v))
}

/// The ticks 1, 2 and 5 × 10^k in [lo, hi].
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (a..=b)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
        .filter(|t| (lo..=hi).contains(t))
        .collect()
}

/// "95 %" from 0.95.
fn percent_label(f: f64) -> String {
    format!("{} %", number(round_sig(100.0 * f, 4)))
}

/// The stages-sweep plot; `None` without a stages series.
pub fn stages(report: &Report) -> Drawn {
    let series = &report.sweep.stages_series;
    if series.is_empty() {
        return Ok(None);
    }
    let pct = report.sweep.percentile.0;
    let conf = percent_label(report.settings.confidence);
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
    let mut legend = Legend::default();
    for (k, s) in series.iter().enumerate() {
        legend.add(
            Swatch::MarkerWithBar(palette(k + 1), 4),
            format!(
                "{}: normalised to {} stage{}, {conf} intervals{}",
                s.name,
                number(s.reference_stages.0),
                if s.reference_stages.0 == 1.0 { "" } else { "s" },
                s.peak_stages.map_or(String::new(), |p| format!(
                    "; peak at {} stages",
                    number(p.0)
                ))
            ),
        );
    }
    let svg = render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let mut chart = captioned(
            area,
            format!(
                "normalised {} against the number of stages ({conf} intervals)",
                theta_pct(pct)
            ),
        )
        .build_cartesian_2d(0.0..xmax + 0.5, 0.0..ymax * 1.05)?;
        styled_mesh(&mut chart.configure_mesh())
            .x_desc("number of stages [-]")
            .y_desc(format!(
                "{} / {} of the smallest stage count [-]",
                theta_pct(pct),
                theta_pct(pct)
            ))
            .draw()?;
        for (k, s) in series.iter().enumerate() {
            let color = palette(k + 1);
            let mut pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter_map(|p| Some((p.stages.0, p.normalised.get()?)))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?;
            for p in &s.points {
                if let Some((lo, hi)) = p.relative_interval.get() {
                    let x = p.stages.0;
                    for seg in [
                        vec![(x, lo), (x, hi)],
                        vec![(x - 0.12, lo), (x + 0.12, lo)],
                        vec![(x - 0.12, hi), (x + 0.12, hi)],
                    ] {
                        chart.draw_series(std::iter::once(PathElement::new(
                            seg,
                            color.stroke_width(2),
                        )))?;
                    }
                }
            }
            for &p in &pts {
                chart.draw_series(std::iter::once(Circle::new(p, 4, WHITE.filled())))?;
                chart.draw_series(std::iter::once(Circle::new(p, 4, color.stroke_width(2))))?;
            }
        }
        Ok(())
    })?;
    Ok(Some(svg))
}
