//! SVG plots of the measured against the simulated distributions, before and after the
//! effect is added, in the plot style every truss-mc plot shares (`truss-plot`):
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
use truss_plot::frame::{captioned, panel, render, styled_mesh, styled_panel_mesh, titled_panels};
use truss_plot::legend::{Legend, Swatch};
use truss_plot::style::{
    CHART_HEIGHT, MEASURED, PANEL_ROW_HEIGHT, PANELS_WIDTH, SIMULATED, TITLE_HEIGHT, WIDTH, sub,
    subscript_svg, theta_p,
};
use truss_units::{MICROMETRE_PER_MM, MICRORAD_PER_RAD};

type Drawn = Result<String, Box<dyn std::error::Error>>;

fn ecdf(v: &[f64]) -> Vec<(f64, f64)> {
    let mut s: Vec<f64> = v.iter().map(|x| x * MICRORAD_PER_RAD).collect();
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

/// The measured and the simulated series, as the legend names them.
fn legend(measured: usize, simulated: usize, swatch: fn(RGBColor) -> Swatch) -> Legend {
    let mut legend = Legend::default();
    legend.add(swatch(MEASURED), format!("measured (n = {measured})"));
    legend.add(swatch(SIMULATED), format!("simulated (N = {simulated})"));
    legend
}

fn ecdf_plot(measured: &Measured, sim: &Simulation, title: &str) -> Drawn {
    let hi = measured
        .theta_p
        .iter()
        .chain(&sim.theta_p)
        .fold(0.0f64, |a, &b| a.max(b))
        * MICRORAD_PER_RAD
        * 1.02;
    let line = |c: RGBColor| Swatch::Line(c, 2, None);
    let legend = legend(measured.theta_p.len(), sim.theta_p.len(), line);
    render(WIDTH, CHART_HEIGHT, &legend, |_, area| {
        let mut chart =
            captioned(area, title.to_string()).build_cartesian_2d(0.0..hi.max(1e-9), 0.0..1.0)?;
        styled_mesh(&mut chart.configure_mesh())
            .x_desc(format!("{} [µrad]", theta_p()))
            .y_desc("cumulative fraction")
            .draw()?;
        chart.draw_series(LineSeries::new(
            ecdf(&sim.theta_p),
            SIMULATED.stroke_width(2),
        ))?;
        chart.draw_series(LineSeries::new(
            ecdf(&measured.theta_p),
            MEASURED.stroke_width(2),
        ))?;
        Ok(())
    })
}

fn scatter_plot(measured: &Measured, sim: &Simulation, top: [[usize; 3]; 3], title: &str) -> Drawn {
    let d = measured.d();
    let m_rows: Vec<&[f64]> = measured.y.chunks_exact(d).collect();
    let s_rows: Vec<&[f64]> = sim.x_noisy.chunks_exact(d).take(1000).collect();
    let marker = |c: RGBColor| Swatch::Marker(c, 2);
    let legend = legend(m_rows.len(), s_rows.len(), marker);
    let height = TITLE_HEIGHT + 2 * PANEL_ROW_HEIGHT;
    render(PANELS_WIDTH, height, &legend, |_, area| {
        let cells = titled_panels(area, title, (2, 3))?;
        for (cell_index, cell) in cells.iter().enumerate() {
            let (row, node) = (cell_index / 3, cell_index % 3);
            let (ax, ay) = if row == 0 { (0, 1) } else { (0, 2) };
            let (ix, iy) = (top[node][ax], top[node][ay]);
            let pts = |rows: &[&[f64]]| -> Vec<(f64, f64)> {
                rows.iter()
                    .map(|r| (r[ix] * MICROMETRE_PER_MM, r[iy] * MICROMETRE_PER_MM))
                    .collect()
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
            let caption = format!(
                "{id}: {} against {}",
                sub("u", names[ay]),
                sub("u", names[ax])
            );
            let mut chart = panel(cell, caption).build_cartesian_2d(range(0), range(1))?;
            styled_panel_mesh(&mut chart.configure_mesh())
                .x_desc(format!("{} [µm]", sub("u", names[ax])))
                .y_desc(format!("{} [µm]", sub("u", names[ay])))
                .draw()?;
            chart.draw_series(
                sp.iter()
                    .map(|&p| Circle::new(p, 2, SIMULATED.mix(0.35).filled())),
            )?;
            chart.draw_series(mp.iter().map(|&p| Circle::new(p, 2, MEASURED.filled())))?;
        }
        Ok(())
    })
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
    let ecdf = ecdf_plot(
        measured,
        sim,
        &format!("{}: measured (red) and {label} (blue)", theta_p()),
    )
    .map_err(|err| plot_error(&e, err))?;
    let s = format!("top-scatter-{suffix}.svg");
    let scatter = scatter_plot(
        measured,
        sim,
        top,
        &format!("Top-node displacements: measured (red) and {label} (blue)"),
    )
    .map_err(|err| plot_error(&s, err))?;
    let (ecdf, scatter) = (subscript_svg(&ecdf), subscript_svg(&scatter));
    out.write(&e, ecdf.as_bytes())?;
    out.write(&s, scatter.as_bytes())?;
    Ok(vec![e, s])
}
