//! A legend drawn below the chart whose swatches are drawn exactly like the series they name
//! (solid, dashed or dotted lines with the same pixel pattern, patches, markers).

use crate::PlotResult;
use crate::style::{FONT, text};
use plotters::coord::Shift;
use plotters::prelude::*;

/// How a series is drawn, for its legend swatch.
#[derive(Debug, Clone, Copy)]
pub enum Swatch {
    /// A line: colour, width, and the dash pattern (dash, gap) in pixels, if any.
    Line(RGBColor, u32, Option<(u32, u32)>),
    /// A filled patch (histogram bars, bands).
    Patch(RGBColor, f64),
    /// A filled circle of a radius.
    Marker(RGBColor, u32),
    /// A circle with a vertical error bar through it.
    MarkerWithBar(RGBColor, u32),
    /// A cross.
    Cross(RGBColor),
    /// No swatch: a line of text.
    Text,
}

/// The dash pattern of dashed lines.
pub const DASHED: (u32, u32) = (10, 6);
/// The dash pattern of dotted lines.
pub const DOTTED: (u32, u32) = (2, 5);

/// A legend: its entries in order.
#[derive(Debug, Default)]
pub struct Legend {
    entries: Vec<(Swatch, String)>,
}

/// Line height of a legend entry.
const ENTRY_HEIGHT: u32 = 24;

impl Legend {
    /// Adds an entry.
    pub fn add(&mut self, swatch: Swatch, text: impl Into<String>) {
        self.entries.push((swatch, text.into()));
    }

    /// The height the legend needs below the chart.
    pub fn height(&self) -> u32 {
        let rows = self.rows() as u32;
        if rows == 0 {
            0
        } else {
            rows * ENTRY_HEIGHT + 16
        }
    }

    fn columns(&self) -> usize {
        1
    }

    fn rows(&self) -> usize {
        self.entries.len().div_ceil(self.columns())
    }

    /// Draws the legend into `area` (pixel coordinates).
    pub fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> PlotResult
    where
        DB::ErrorType: 'static,
    {
        let rows = self.rows();
        let col_width = (area.dim_in_pixel().0 as i32 - 80) / self.columns() as i32;
        for (k, (swatch, text)) in self.entries.iter().enumerate() {
            let (col, row) = (k / rows, k % rows);
            let x = 70 + col as i32 * col_width;
            let y = 8 + row as i32 * ENTRY_HEIGHT as i32 + ENTRY_HEIGHT as i32 / 2;
            draw_swatch(area, *swatch, x, y)?;
            area.draw(&Text::new(
                text.clone(),
                (x + 46, y - 8),
                (FONT, text::LABEL).into_font().color(&BLACK),
            ))?;
        }
        Ok(())
    }
}

/// Draws a pixel-space line from (x0, y) to (x1, y) with a dash pattern, as plotters'
/// `DashedLineSeries` does along a path.
fn dashed<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x0: i32,
    x1: i32,
    y: i32,
    style: ShapeStyle,
    (dash, gap): (u32, u32),
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let mut x = x0;
    while x < x1 {
        let end = (x + dash as i32).min(x1);
        area.draw(&PathElement::new(vec![(x, y), (end, y)], style))?;
        x = end + gap as i32;
    }
    Ok(())
}

fn draw_swatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    swatch: Swatch,
    x: i32,
    y: i32,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    match swatch {
        Swatch::Line(color, width, None) => {
            area.draw(&PathElement::new(
                vec![(x, y), (x + 36, y)],
                color.stroke_width(width),
            ))?;
        }
        Swatch::Line(color, width, Some(pattern)) => {
            dashed(area, x, x + 36, y, color.stroke_width(width), pattern)?;
        }
        Swatch::Patch(color, alpha) => {
            area.draw(&Rectangle::new(
                [(x, y - 7), (x + 36, y + 7)],
                color.mix(alpha).filled(),
            ))?;
        }
        Swatch::Marker(color, r) => {
            area.draw(&Circle::new((x + 18, y), r, color.filled()))?;
        }
        Swatch::MarkerWithBar(color, r) => {
            area.draw(&PathElement::new(
                vec![(x + 18, y - 10), (x + 18, y + 10)],
                color.stroke_width(2),
            ))?;
            for yy in [y - 10, y + 10] {
                area.draw(&PathElement::new(
                    vec![(x + 13, yy), (x + 23, yy)],
                    color.stroke_width(2),
                ))?;
            }
            area.draw(&Circle::new((x + 18, y), r, WHITE.filled()))?;
            area.draw(&Circle::new((x + 18, y), r, color.stroke_width(2)))?;
        }
        Swatch::Cross(color) => {
            area.draw(&Cross::new((x + 18, y), 7, color.stroke_width(3)))?;
        }
        Swatch::Text => {}
    }
    Ok(())
}

/// A dashed or dotted line through data points (pattern in pixels, as in the legend).
pub fn pattern_series<C: Into<ShapeStyle>>(
    points: Vec<(f64, f64)>,
    (dash, gap): (u32, u32),
    style: C,
) -> DashedLineSeries<std::vec::IntoIter<(f64, f64)>, u32> {
    DashedLineSeries::new(points, dash, gap, style.into())
}
