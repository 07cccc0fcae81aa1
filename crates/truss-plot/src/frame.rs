//! The frame every plot shares, so that each plot's code says only what it draws: a white
//! canvas with the legend below the chart ([`render`]), the chart's caption and margins
//! ([`captioned`], or [`panel`] in a figure of panels), and the styles of the primary mesh
//! ([`styled_mesh`], [`styled_panel_mesh`]) and of the secondary axes
//! ([`styled_secondary`]).

use crate::PlotResult;
use crate::legend::Legend;
use crate::style::{FONT, LIGHT, text, tick};
#[cfg(doc)]
use crate::style::{PANELS_WIDTH, WIDTH};
use plotters::chart::{MeshStyle, SecondaryMeshStyle};
use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;

/// A drawing area of an SVG plot.
pub type Canvas<'s> = DrawingArea<SVGBackend<'s>, Shift>;

/// Draws one plot and returns its SVG: a white canvas `width` wide (most plots: [`WIDTH`])
/// whose top `chart_height` pixels are the chart part and whose rest is `legend`. `draw`
/// gets the whole canvas (for text placed in pixels) and the chart part.
pub fn render(
    width: u32,
    chart_height: u32,
    legend: &Legend,
    draw: impl for<'s> FnOnce(&Canvas<'s>, &Canvas<'s>) -> PlotResult,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, chart_height + legend.height()))
            .into_drawing_area();
        root.fill(&WHITE)?;
        let (area, legend_area) = root.split_vertically(chart_height);
        draw(&root, &area)?;
        legend.draw(&legend_area)?;
        root.present()?;
    }
    Ok(svg)
}

/// A chart builder on `area` with a caption ([`text::CAPTION`]) and the plots' margins and
/// label areas (16 px margin, 50 px below for the x labels, 80 px left for the y labels); add
/// the top or right label areas of secondary axes where a plot has them.
pub fn captioned<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: String,
) -> ChartBuilder<'a, 'b, DB> {
    chart(area, caption, text::CAPTION, 16, (50, 80))
}

/// The primary mesh's style: light grid lines, tick labels by [`tick`], axis descriptions
/// in [`text::DESCRIPTION`] and labels in [`text::LABEL`].
pub fn styled_mesh<'m, 'a, 'b, X, Y, DB>(
    mesh: &'m mut MeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut MeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    DB: DrawingBackend,
{
    mesh_in_sizes(mesh, text::DESCRIPTION, text::LABEL)
}

/// A chart builder for one panel of a figure of panels ([`PANELS_WIDTH`] wide, its title
/// strip drawn by [`titled_panels`]): a caption in [`text::PANEL_CAPTION`], a 14 px margin,
/// 45 px below for the x labels and 70 px left for the y labels.
pub fn panel<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: String,
) -> ChartBuilder<'a, 'b, DB> {
    chart(area, caption, text::PANEL_CAPTION, 14, (45, 70))
}

/// The title strip of a figure of panels ([`crate::style::TITLE_HEIGHT`] high, the title
/// in [`text::TITLE`]) and the `rows` × `columns` panels below it.
pub fn titled_panels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    (rows, columns): (usize, usize),
) -> Result<Vec<DrawingArea<DB, Shift>>, DrawingAreaErrorKind<DB::ErrorType>> {
    let (title_area, body) = area.split_vertically(crate::style::TITLE_HEIGHT);
    title_area.titled(title, (FONT, text::TITLE))?;
    Ok(body.split_evenly((rows, columns)))
}

/// A panel's mesh style: light grid lines, tick labels by [`tick`], axis descriptions in
/// [`text::PANEL_DESCRIPTION`] and labels in [`text::PANEL_LABEL`].
pub fn styled_panel_mesh<'m, 'a, 'b, X, Y, DB>(
    mesh: &'m mut MeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut MeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    DB: DrawingBackend,
{
    mesh_in_sizes(mesh, text::PANEL_DESCRIPTION, text::PANEL_LABEL)
}

/// A chart builder on `area`: its caption in `size` px, `margin` px around it, and
/// `label_areas` px below (x labels) and left (y labels).
fn chart<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    caption: String,
    size: u32,
    margin: u32,
    (below, left): (u32, u32),
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(caption, (FONT, size))
        .margin(margin)
        .x_label_area_size(below)
        .y_label_area_size(left);
    builder
}

/// A mesh with light grid lines, tick labels by [`tick`], axis descriptions in
/// `description` px and labels in `label` px.
fn mesh_in_sizes<'m, 'a, 'b, X, Y, DB>(
    mesh: &'m mut MeshStyle<'a, 'b, X, Y, DB>,
    description: u32,
    label: u32,
) -> &'m mut MeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    DB: DrawingBackend,
{
    mesh.x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .light_line_style(LIGHT)
        .axis_desc_style((FONT, description))
        .label_style((FONT, label))
}

/// The secondary axes' style: tick labels by [`tick`], descriptions in
/// [`text::DESCRIPTION`], labels in [`text::LABEL`] (the same as the primary axes beside
/// them).
pub fn styled_secondary<'m, 'a, 'b, X, Y, DB>(
    axes: &'m mut SecondaryMeshStyle<'a, 'b, X, Y, DB>,
) -> &'m mut SecondaryMeshStyle<'a, 'b, X, Y, DB>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    DB: DrawingBackend,
{
    axes.x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .axis_desc_style((FONT, text::DESCRIPTION))
        .label_style((FONT, text::LABEL))
}
