//! SVG plots of the measured against the simulated distributions, before and after the
//! effect is added:
//!
//! - `theta_p-ecdf-before.svg`, `theta_p-ecdf-after.svg`: the empirical CDFs of θ_P \[µrad\]
//!   (simulated with the instrument's noise).
//! - `top-scatter-before.svg`, `top-scatter-after.svg`: per top-surface node, the x–y and
//!   x–z displacement scatter \[µm\] of the specimens over up to 1000 simulated samples.

use crate::comparison::measured::Measured;
use crate::comparison::simulate::Simulation;
use crate::errors::DiagnoseError;
use plotters::prelude::*;
use run_dir::OutputDir;

const SIM: RGBColor = RGBColor(30, 90, 200);
const MEAS: RGBColor = RGBColor(200, 30, 30);
const FONT: &str = "sans-serif";

type PlotResult = Result<(), Box<dyn std::error::Error>>;

fn ecdf(v: &[f64]) -> Vec<(f64, f64)> {
    let mut s: Vec<f64> = v.iter().map(|x| x * 1e6).collect();
    s.sort_by(f64::total_cmp);
    let n = s.len() as f64;
    let mut out = Vec::with_capacity(2 * s.len() + 1);
    out.push((0.0, 0.0));
    for (i, x) in s.iter().enumerate() {
        out.push((*x, i as f64 / n));
        out.push((*x, (i + 1) as f64 / n));
    }
    out
}

fn ecdf_plot(svg: &mut String, measured: &Measured, sim: &Simulation, title: &str) -> PlotResult {
    let root = SVGBackend::with_string(svg, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let hi = measured
        .theta_p
        .iter()
        .chain(&sim.theta_p)
        .fold(0.0f64, |a, &b| a.max(b))
        * 1e6
        * 1.02;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..hi.max(1e-9), 0.0..1.0)?;
    chart
        .configure_mesh()
        .x_desc("θ_P [µrad]")
        .y_desc("cumulative fraction")
        .draw()?;
    chart
        .draw_series(LineSeries::new(ecdf(&sim.theta_p), SIM.stroke_width(2)))?
        .label(format!("simulated (N = {})", sim.theta_p.len()))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], SIM.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            ecdf(&measured.theta_p),
            MEAS.stroke_width(2),
        ))?
        .label(format!("measured (n = {})", measured.theta_p.len()))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], MEAS.stroke_width(2)));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

fn scatter_plot(
    svg: &mut String,
    measured: &Measured,
    sim: &Simulation,
    top: [[usize; 3]; 3],
    title: &str,
) -> PlotResult {
    let root = SVGBackend::with_string(svg, (1200, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let (upper, panels) = root.split_vertically(40);
    upper.titled(title, (FONT, 20))?;
    let cells = panels.split_evenly((2, 3));
    let d = measured.d();
    let m_rows: Vec<&[f64]> = measured.y.chunks_exact(d).collect();
    let s_rows: Vec<&[f64]> = sim.x_noisy.chunks_exact(d).take(1000).collect();
    for (cell_index, cell) in cells.iter().enumerate() {
        let (row, node) = (cell_index / 3, cell_index % 3);
        let (ax, ay) = if row == 0 { (0, 1) } else { (0, 2) };
        let (ix, iy) = (top[node][ax], top[node][ay]);
        let pts = |rows: &[&[f64]]| -> Vec<(f64, f64)> {
            rows.iter().map(|r| (r[ix] * 1e3, r[iy] * 1e3)).collect()
        };
        let (mp, sp) = (pts(&m_rows), pts(&s_rows));
        let range = |k: usize| {
            let vals = mp.iter().chain(&sp).map(|p| if k == 0 { p.0 } else { p.1 });
            let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
            let pad = ((hi - lo) * 0.05).max(1e-3);
            (lo - pad)..(hi + pad)
        };
        let id = &measured.coords[top[node][0]].node_id;
        let names = ["x", "y", "z"];
        let mut chart = ChartBuilder::on(cell)
            .caption(
                format!("{id}: u_{} against u_{}", names[ay], names[ax]),
                (FONT, 14),
            )
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(48)
            .build_cartesian_2d(range(0), range(1))?;
        chart
            .configure_mesh()
            .x_desc(format!("u_{} [µm]", names[ax]))
            .y_desc(format!("u_{} [µm]", names[ay]))
            .draw()?;
        chart.draw_series(
            sp.iter()
                .map(|&p| Circle::new(p, 2, SIM.mix(0.35).filled())),
        )?;
        chart.draw_series(mp.iter().map(|&p| Circle::new(p, 2, MEAS.filled())))?;
    }
    root.present()?;
    Ok(())
}

/// Draws the before (`suffix = "before"`) or after plots into `out`; returns the file names.
pub fn draw(
    out: &mut OutputDir,
    suffix: &str,
    measured: &Measured,
    sim: &Simulation,
    top: [[usize; 3]; 3],
    label: &str,
) -> Result<Vec<String>, DiagnoseError> {
    let plot_error = |name: &str, err: Box<dyn std::error::Error>| DiagnoseError::Plot {
        path: out.path().join(name),
        message: err.to_string(),
    };
    let e = format!("theta_p-ecdf-{suffix}.svg");
    let mut ecdf = String::new();
    ecdf_plot(
        &mut ecdf,
        measured,
        sim,
        &format!("θ_P: measured (red) and {label} (blue)"),
    )
    .map_err(|err| plot_error(&e, err))?;
    let s = format!("top-scatter-{suffix}.svg");
    let mut scatter = String::new();
    scatter_plot(
        &mut scatter,
        measured,
        sim,
        top,
        &format!("Top-node displacements: measured (red) and {label} (blue)"),
    )
    .map_err(|err| plot_error(&s, err))?;
    out.write(&e, ecdf.as_bytes())?;
    out.write(&s, scatter.as_bytes())?;
    Ok(vec![e, s])
}
