//! The plot of one case's decenter and despace (`placement-STEM`), beside θ_P's: two panels,
//!
//! - decenter's histogram (as a density) with the fitted Rayleigh density
//!   `f(d) = d/σ̂_d² · exp(−d²/2σ̂_d²)`, σ̂_d the report's `decenter.law.sigma`;
//! - despace's histogram (signed) with the fitted normal density N(μ̂, ŝ²), μ̂ and ŝ the
//!   report's `despace.law.mean` and `std`;
//!
//! each with its empirical and fitted percentiles at the budget's percentile (the target
//! percentile without a budget; ± for |despace|) and the budget's limit where the job states
//! that line. Lengths in µm (the report's mm × 1000). Not drawn where the samples do not
//! record decenter and despace (shards of numerics version 7 or earlier) or with fewer
//! than two of them.

use super::distribution::{bin_count, histogram};
use crate::load::CaseData;
use crate::quantile::quantile_sorted;
use crate::report::{CaseReport, QuantityReport, Report};
use plotters::prelude::*;
use truss_plot::frame::*;
use truss_plot::legend::*;
use truss_plot::style::*;
use truss_units::MICROMETRE_PER_MM;

/// A length in µm, four significant digits: "22.35 µm".
fn um(v: f64) -> String {
    format!("{} µm", number(round_sig(v, 4)))
}

/// The percentile the lines are drawn at: the budget's, else the report's target percentile.
fn line_percentile(report: &Report) -> f64 {
    report
        .budget
        .as_ref()
        .map_or(report.sweep.percentile.0, |b| b.percentile.0)
}

/// The budget's limit of `quantity` \[µm\], if the job states that line.
fn limit(report: &Report, quantity: &str) -> Option<f64> {
    let b = report.budget.as_ref()?;
    let line = b.lines.iter().find(|l| l.quantity == quantity)?;
    Some(line.limit.0 * MICROMETRE_PER_MM)
}

/// (empirical, law) percentile `pct` of `q` \[µm\].
fn percentiles(q: &QuantityReport, pct: f64) -> (Option<f64>, Option<f64>) {
    let emp = q
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value)
        .map(|v| v.0 * MICROMETRE_PER_MM);
    let law = q
        .law
        .percentiles
        .iter()
        .find(|p| p.percentile.0 == pct)
        .and_then(|p| p.value.get())
        .map(|v| v * MICROMETRE_PER_MM);
    (emp, law)
}

/// A density curve of 301 points over [lo, hi].
fn curve(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
    (0..=300)
        .map(|i| {
            let x = lo + (hi - lo) * i as f64 / 300.0;
            (x, f(x))
        })
        .collect()
}

/// Vertical lines at `xs`, from 0 to `top`, in `style` (solid where `dash` is None).
fn verticals<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    xs: &[f64],
    top: f64,
    style: ShapeStyle,
    dash: Option<(u32, u32)>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    for &x in xs {
        let points = vec![(x, 0.0), (x, top)];
        match dash {
            Some(d) => chart.draw_series(pattern_series(points, d, style))?,
            None => chart.draw_series(LineSeries::new(points, style))?,
        };
    }
    Ok(())
}

/// One panel of the plot: a histogram as a density \[1/µm\] over `x_range` \[µm\], its fitted
/// law's density curve in the given colour (none when empty), and vertical lines at the
/// empirical percentiles (solid), the law's (dashed) and the budget's limits (dotted).
struct Panel<'a> {
    caption: &'a str,
    x_desc: &'a str,
    x_range: (f64, f64),
    hist: &'a [(f64, f64, f64)],
    fit: (&'a [(f64, f64)], RGBColor),
    lines: [Vec<f64>; 3],
}

/// Draws `p` into `area`, its density axis from 0 to 5 % above the tallest bar or curve.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    p: &Panel,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (curve, colour) = p.fit;
    let top = p
        .hist
        .iter()
        .map(|b| b.2)
        .chain(curve.iter().map(|c| c.1))
        .fold(0.0, f64::max)
        * 1.05;
    let top = top.max(1e-12);
    let mut chart =
        panel(area, p.caption.into()).build_cartesian_2d(p.x_range.0..p.x_range.1, 0.0..top)?;
    styled_panel_mesh(&mut chart.configure_mesh())
        .x_desc(p.x_desc)
        .y_desc("probability density [1/µm]")
        .draw()?;
    chart.draw_series(
        p.hist
            .iter()
            .map(|&(a, b, h)| Rectangle::new([(a, 0.0), (b, h)], BAR.filled())),
    )?;
    if !curve.is_empty() {
        chart.draw_series(LineSeries::new(curve.to_vec(), colour.stroke_width(3)))?;
    }
    let [empirical, law, limit] = &p.lines;
    verticals(&mut chart, empirical, top, palette(2).stroke_width(2), None)?;
    verticals(&mut chart, law, top, BLACK.stroke_width(2), Some(DASHED))?;
    verticals(&mut chart, limit, top, BLACK.stroke_width(2), Some(DOTTED))
}

/// The two-panel plot; `None` where the case does not record decenter and despace or has
/// fewer than two samples that do.
pub fn placement(
    case: &CaseData,
    rep: &CaseReport,
    report: &Report,
) -> Result<Option<String>, Box<dyn std::error::Error>> {
    let (Some(dec), Some(des)) = (&rep.decenter, &rep.despace) else {
        return Ok(None);
    };
    let placed: Vec<_> = case.points().filter(|p| p.placed()).collect();
    if placed.len() < 2 {
        return Ok(None);
    }
    let mut d: Vec<f64> = placed
        .iter()
        .map(|p| p.decenter() * MICROMETRE_PER_MM)
        .collect();
    d.sort_by(f64::total_cmp);
    let mut z: Vec<f64> = placed
        .iter()
        .map(|p| p.despace * MICROMETRE_PER_MM)
        .collect();
    z.sort_by(f64::total_cmp);
    let pct = line_percentile(report);
    let (d_emp, d_law) = percentiles(dec, pct);
    let (z_emp, z_law) = percentiles(des, pct);
    let (d_limit, z_limit) = (limit(report, "decenter"), limit(report, "despace"));
    let sigma = dec.law.sigma.as_ref().and_then(|f| f.get());
    let sigma = sigma.map(|s| s * MICROMETRE_PER_MM).filter(|s| *s > 0.0);
    let mean = des.law.mean.as_ref().and_then(|f| f.get());
    let std = des.law.std.as_ref().and_then(|f| f.get());
    let normal = match (mean, std) {
        (Some(m), Some(s)) if s > 0.0 => Some((m * MICROMETRE_PER_MM, s * MICROMETRE_PER_MM)),
        _ => None,
    };

    // Axes: decenter from 0 to past its 99.9th percentile and its limit; despace symmetric
    // about 0, past its extreme 0.1 % and its limit.
    let q = |v: &[f64], a: f64| quantile_sorted(v, a).unwrap_or(0.0);
    let d_hi = (q(&d, 0.999).max(d_limit.unwrap_or(0.0)) * 1.08).max(1e-9);
    let z_hi = (q(&z, 0.999).abs().max(q(&z, 0.001).abs())).max(z_limit.unwrap_or(0.0)) * 1.08;
    let z_hi = z_hi.max(1e-9);
    let d_hist = histogram(&d, 0.0, d_hi, bin_count(d.len()));
    let z_hist = histogram(&z, -z_hi, z_hi, bin_count(z.len()));
    let d_curve = sigma
        .map(|s| curve(0.0, d_hi, |x| crate::rayleigh::density(s, x)))
        .unwrap_or_default();
    let z_curve = normal
        .map(|(m, s)| {
            curve(-z_hi, z_hi, |x| {
                (-(x - m) * (x - m) / (2.0 * s * s)).exp()
                    / (s * (2.0 * std::f64::consts::PI).sqrt())
            })
        })
        .unwrap_or_default();

    let p_d = format!("decenter{}", plain_pct(pct));
    let p_z = format!("|despace|{}", plain_pct(pct));
    let mut legend = Legend::default();
    legend.add(
        Swatch::Patch(BAR, 1.0),
        format!("Monte Carlo histograms (n = {})", placed.len()),
    );
    if let Some(s) = sigma {
        legend.add(
            Swatch::Line(RED, 3, None),
            format!("left: Rayleigh fit, {} = {}", sub("σ̂", "d"), um(s)),
        );
    }
    if let Some((m, s)) = normal {
        legend.add(
            Swatch::Line(SIMULATED, 3, None),
            format!(
                "right: normal fit, mean {}, standard deviation {}",
                um(m),
                um(s)
            ),
        );
    }
    let both = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => Some(format!("{p_d} = {}, {p_z} = {}", um(a), um(b))),
        (Some(a), None) => Some(format!("{p_d} = {}", um(a))),
        (None, Some(b)) => Some(format!("{p_z} = {}", um(b))),
        (None, None) => None,
    };
    if let Some(t) = both(d_emp, z_emp) {
        legend.add(Swatch::Line(palette(2), 2, None), format!("empirical {t}"));
    }
    if let Some(t) = both(d_law, z_law) {
        legend.add(
            Swatch::Line(BLACK, 2, Some(DASHED)),
            format!("fitted laws' {t} (Rayleigh; folded normal)"),
        );
    }
    if let Some(t) = both(d_limit, z_limit) {
        legend.add(
            Swatch::Line(BLACK, 2, Some(DOTTED)),
            format!(
                "budget: {}",
                t.replace(&p_d, "decenter").replace(&p_z, "|despace|")
            ),
        );
    }

    let title = format!(
        "{} — decenter and despace of the top surface, n = {}{}",
        rep.name,
        placed.len(),
        if rep.caveats.is_empty() {
            ""
        } else {
            " (see the report's caveats)"
        }
    );
    let height = TITLE_HEIGHT + PANEL_ROW_HEIGHT;
    let svg = render(PANELS_WIDTH, height, &legend, |_, area| {
        let panels = titled_panels(area, &title, (1, 2))?;
        let pm = |x: Option<f64>| x.map_or(vec![], |x| vec![-x, x]);
        draw_panel(
            &panels[0],
            &Panel {
                caption: "decenter = |δ projected on the bottom plane|",
                x_desc: "decenter [µm]",
                x_range: (0.0, d_hi),
                hist: &d_hist,
                fit: (&d_curve, RED),
                lines: [
                    d_emp.into_iter().collect(),
                    d_law.into_iter().collect(),
                    d_limit.into_iter().collect(),
                ],
            },
        )?;
        draw_panel(
            &panels[1],
            &Panel {
                caption: "despace = δ·n (signed, + apart)",
                x_desc: "despace [µm]",
                x_range: (-z_hi, z_hi),
                hist: &z_hist,
                fit: (&z_curve, SIMULATED),
                lines: [pm(z_emp), pm(z_law), pm(z_limit)],
            },
        )?;
        Ok(())
    })?;
    Ok(Some(svg))
}

/// "95" as a subscript-free percentile tag: "P95" is written after the quantity, `₉₅`-free
/// so that the text stays searchable: "decenter P95".
fn plain_pct(pct: f64) -> String {
    format!(" P{}", number(pct))
}
