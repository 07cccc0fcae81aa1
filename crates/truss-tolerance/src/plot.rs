//! SVG plots of the variance shares, in the plot style every truss-mc plot shares
//! (`truss-plot`):
//!
//! Shares span many decades (a fixed bottom batten moves nothing), so the share axes are
//! logarithmic.
//!
//! - `shares-groups.svg`: each group's share of Var tan θ_x + Var tan θ_y with its 95 %
//!   interval, and the nonlinear remainder.
//! - `shares-members.svg`: each member's share with its interval, by stage (x axis) and
//!   position (offset within the stage), one colour per group. Stage and position are read
//!   from member ids of the form `GROUP.STAGE.POSITION` (the prism's `longeron.3.1`); other
//!   ids are placed by their order within the group.

use crate::errors::ToleranceError;
use crate::study::Tolerance;
use plotters::prelude::*;
use run_dir::OutputDir;
use std::path::PathBuf;
use truss_plot::frame::{captioned, render, styled_mesh};
use truss_plot::legend::{Legend, Swatch};
use truss_plot::style::{CHART_HEIGHT, WIDTH, palette, sub, subscript_svg};

type Drawn = Result<String, Box<dyn std::error::Error>>;

/// What the share axes measure.
fn share_axis() -> String {
    format!(
        "share of Var tan {} + Var tan {} [-] (95 % interval, log scale)",
        sub("θ", "x"),
        sub("θ", "y")
    )
}

fn whisker(x: f64, lo: f64, hi: f64, half: f64, c: RGBColor) -> Vec<PathElement<(f64, f64)>> {
    vec![
        PathElement::new(vec![(x, lo), (x, hi)], c.stroke_width(1)),
        PathElement::new(vec![(x - half, lo), (x + half, lo)], c.stroke_width(1)),
        PathElement::new(vec![(x - half, hi), (x + half, hi)], c.stroke_width(1)),
    ]
}

fn groups_plot(t: &Tolerance) -> Drawn {
    let nl = t.sensitivity.nonlinear;
    let mut bars: Vec<(String, f64, (f64, f64))> = t
        .groups
        .iter()
        .map(|g| (g.name.clone(), g.share.0, g.share.1))
        .collect();
    bars.push(("nonlinear".into(), nl.0, nl.1));
    let values: Vec<f64> = bars.iter().flat_map(|b| [b.1, b.2.0, b.2.1]).collect();
    let (bottom, top) = log_range(&values);
    let n = bars.len();
    let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
    let caption = format!("Share of the tilt's variance per group, case {}", t.case);
    render(WIDTH, CHART_HEIGHT, &Legend::default(), |_, area| {
        let mut chart = captioned(area, caption)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), (bottom..top).log_scale())?;
        styled_mesh(&mut chart.configure_mesh())
            .disable_x_mesh()
            .x_labels(n)
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
                    labels[i as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_desc(share_axis())
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()?;
        let clamp = |v: f64| v.max(bottom);
        for (i, (_, v, (lo, hi))) in bars.iter().enumerate() {
            let c = if i + 1 == n {
                RGBColor(150, 150, 150)
            } else {
                palette(i)
            };
            let x = i as f64;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x - 0.3, bottom), (x + 0.3, clamp(*v))],
                c.mix(0.6).filled(),
            )))?;
            if lo.is_finite() && hi.is_finite() {
                chart.draw_series(whisker(x, clamp(*lo), clamp(*hi), 0.1, BLACK))?;
            }
        }
        Ok(())
    })
}

/// A log axis's range covering the positive `values` (a decade's margin below, 50 % above);
/// values at or below zero are drawn at the bottom.
fn log_range(values: &[f64]) -> (f64, f64) {
    let positive = values.iter().filter(|v| v.is_finite() && **v > 0.0);
    let lo = positive.clone().fold(f64::MAX, |a, &b| a.min(b));
    let hi = positive.fold(0.0f64, |a, &b| a.max(b));
    if hi <= 0.0 {
        return (1e-6, 1.0);
    }
    (10f64.powf(lo.log10().floor()), hi * 1.5)
}

/// (stage, position) of a member id, or None.
fn stage_position(id: &str) -> Option<(f64, f64)> {
    let mut parts = id.split('.').skip(1);
    let stage = parts.next()?.parse::<f64>().ok()?;
    let position = parts.next()?.parse::<f64>().ok()?;
    Some((stage, position))
}

fn members_plot(t: &Tolerance) -> Drawn {
    let share = &t.sensitivity.fit.share;
    let intervals = &t.sensitivity.share_interval;
    let groups = t.groups.len().max(1) as f64;
    // Positions per stage, for the offsets.
    let parsed: Vec<Option<(f64, f64)>> = t.members.iter().map(|m| stage_position(&m.0)).collect();
    let all_parsed = parsed.iter().all(Option::is_some);
    let mut counter = vec![0usize; t.groups.len()];
    let places: Vec<(f64, f64)> = t
        .members
        .iter()
        .zip(&parsed)
        .map(|((_, g), p)| {
            let k = counter[*g];
            counter[*g] += 1;
            match (all_parsed, p) {
                (true, Some(sp)) => *sp,
                _ => (k as f64, 0.0),
            }
        })
        .collect();
    let positions = places.iter().map(|p| p.1).fold(0.0f64, f64::max) + 1.0;
    let x_of = |j: usize| -> f64 {
        let (stage, pos) = places[j];
        let g = t.members[j].1 as f64;
        stage + 0.8 * ((g * positions + pos + 0.5) / (groups * positions) - 0.5)
    };
    let (x_lo, x_hi) = places
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let values: Vec<f64> = share
        .iter()
        .chain(intervals.iter().flat_map(|i| [&i.0, &i.1]))
        .copied()
        .collect();
    let (bottom, top) = log_range(&values);
    let clamp = |v: f64| v.max(bottom);
    let mut legend = Legend::default();
    for (g, group) in t.groups.iter().enumerate() {
        legend.add(Swatch::Marker(palette(g), 4), group.name.clone());
    }
    let caption = format!("Share of the tilt's variance per member, case {}", t.case);
    render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let mut chart = captioned(area, caption)
            .build_cartesian_2d((x_lo - 0.6)..(x_hi + 0.6), (bottom..top).log_scale())?;
        styled_mesh(&mut chart.configure_mesh())
            .x_desc(if all_parsed {
                "stage (members of one stage side by side: by group, then position)"
            } else {
                "member (order within its group)"
            })
            .y_desc(share_axis())
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()?;
        for g in 0..t.groups.len() {
            let c = palette(g);
            let js: Vec<usize> = (0..t.members.len())
                .filter(|&j| t.members[j].1 == g)
                .collect();
            chart.draw_series(
                js.iter()
                    .map(|&j| Circle::new((x_of(j), clamp(share[j])), 4, c.filled())),
            )?;
            for &j in &js {
                let (lo, hi) = intervals[j];
                if lo.is_finite() && hi.is_finite() {
                    chart.draw_series(whisker(x_of(j), clamp(lo), clamp(hi), 0.02, c))?;
                }
            }
        }
        Ok(())
    })
}

/// The plots' file names.
pub const PLOTS: [&str; 2] = ["shares-groups.svg", "shares-members.svg"];

/// Draws both plots into `out`; returns their paths.
pub fn draw_all(t: &Tolerance, out: &mut OutputDir) -> Result<Vec<PathBuf>, ToleranceError> {
    let mut files = Vec::new();
    type Draw = fn(&Tolerance) -> Drawn;
    let plots: [(&str, Draw); 2] = [(PLOTS[0], groups_plot), (PLOTS[1], members_plot)];
    for (name, draw) in plots {
        let svg = draw(t).map_err(|e| ToleranceError::Plot {
            path: out.path().join(name),
            message: e.to_string(),
        })?;
        files.push(out.write(name, subscript_svg(&svg).as_bytes())?);
    }
    Ok(files)
}
