//! What every plot shares: colours, fonts, tick labels, unit conversions, real subscripts, and a
//! legend drawn below the chart whose swatches are drawn exactly like the series they name
//! (solid, dashed or dotted lines with the same pixel pattern, patches, markers).

use plotters::coord::Shift;
use plotters::prelude::*;

/// The result of drawing one plot.
pub type PlotResult = Result<(), Box<dyn std::error::Error>>;

/// rad → µrad.
pub const MICRO: f64 = 1e6;
/// µrad → arcsec (`truss-units`).
pub use truss_units::ARCSEC_PER_MICRORAD;
/// The font family of every text (resolved by the renderer; see [`super::png`]).
pub const FONT: &str = "sans-serif";
/// Width of every plot in SVG units (pixels at 1×).
pub const WIDTH: u32 = 960;
/// Height of the chart part of a plot (the legend is added below).
pub const CHART_HEIGHT: u32 = 620;
/// Grid lines.
pub const LIGHT: RGBColor = RGBColor(232, 232, 232);
/// Histogram bars.
pub const BAR: RGBColor = RGBColor(150, 175, 215);

/// Opens a subscript in a label; [`subscript_svg`] turns it into a lowered, smaller `tspan`.
pub const SUB_OPEN: char = '\u{E000}';
/// Closes a subscript.
pub const SUB_CLOSE: char = '\u{E001}';

/// `base` with `index` as a real subscript, e.g. `sub("θ", "P95")` for θ with P95 lowered.
pub fn sub(base: &str, index: &str) -> String {
    format!("{base}{SUB_OPEN}{index}{SUB_CLOSE}")
}

/// θ_P with its subscript.
pub fn theta_p() -> String {
    sub("θ", "P")
}

/// θ_P at a percentile, e.g. θ with "P95" lowered.
pub fn theta_pct(pct: f64) -> String {
    sub("θ", &format!("P{}", number(pct)))
}

/// The colours of series, distinguishable in print.
pub fn palette(i: usize) -> RGBColor {
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

/// A number in its shortest plain form: 1400, 0.0063, 2.5 (never "1400.0"); e-notation only
/// below 1e-4 or from 1e7.
pub fn number(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-4..1e7).contains(&a) {
        let s = format!("{v:.2e}");
        return s.replace(".00e", "e").replace("0e", "e");
    }
    // Six significant digits, trailing zeros dropped.
    let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A tick label: [`number`] of the value rounded to 12 significant digits (no "0.30000000004").
pub fn tick(v: &f64) -> String {
    if *v == 0.0 {
        return "0".into();
    }
    let scale = 10f64.powi(11 - v.abs().log10().floor() as i32);
    number((v * scale).round() / scale)
}

/// An angle in µrad with its arcsec in brackets, e.g. "96.9 µrad (20.0″)".
pub fn angle(microrad: f64) -> String {
    format!(
        "{} µrad ({:.1}″)",
        number(round_sig(microrad, 4)),
        microrad * ARCSEC_PER_MICRORAD
    )
}

/// `v` rounded to `digits` significant digits.
pub fn round_sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

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
                (FONT, 15).into_font().color(&BLACK),
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

/// Turns the subscript markers of an SVG's text into `tspan`s: lowered by 0.3 em and at 75 %
/// of the text's size (both renderers, resvg and librsvg, honour `dy` and `font-size`).
pub fn subscript_svg(svg: &str) -> String {
    if !svg.contains(SUB_OPEN) {
        return svg.to_string();
    }
    let mut out = String::with_capacity(svg.len() + 1024);
    let mut rest = svg;
    while let Some(start) = rest.find("<text") {
        let Some(end) = rest[start..].find("</text>").map(|e| start + e) else {
            break;
        };
        out.push_str(&rest[..start]);
        let element = &rest[start..end];
        let size = element
            .find("font-size=\"")
            .and_then(|i| {
                let v = &element[i + 11..];
                v[..v.find('"')?].trim_end_matches("px").parse::<f64>().ok()
            })
            .unwrap_or(15.0);
        let shift = 0.3 * size;
        let mut opened = 0;
        for c in element.chars() {
            match c {
                SUB_OPEN => out.push_str(&format!(
                    "<tspan dy=\"{shift:.1}\" font-size=\"{:.1}\">",
                    0.75 * size
                )),
                SUB_CLOSE => {
                    out.push_str(&format!("</tspan><tspan dy=\"-{shift:.1}\">"));
                    opened += 1;
                }
                c => out.push(c),
            }
        }
        out.push_str(&"</tspan>".repeat(opened));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_without_spurious_decimals() {
        assert_eq!(number(1400.0), "1400");
        assert_eq!(number(0.0063), "0.0063");
        assert_eq!(number(96.9), "96.9");
        assert_eq!(number(-2.5), "-2.5");
        assert_eq!(tick(&(0.1 + 0.2)), "0.3");
        assert_eq!(tick(&1e-7), "1e-7");
        assert_eq!(number(95.0), "95");
        assert_eq!(number(99.9), "99.9");
    }

    #[test]
    fn subscripts_become_tspans() {
        let svg = format!(
            "<svg><text x=\"1\" font-size=\"20\">{} = 5</text><text>plain</text></svg>",
            theta_pct(95.0)
        );
        let out = subscript_svg(&svg);
        assert_eq!(
            out,
            "<svg><text x=\"1\" font-size=\"20\">θ<tspan dy=\"6.0\" font-size=\"15.0\">P95</tspan><tspan dy=\"-6.0\"> = 5</tspan></text><text>plain</text></svg>"
        );
        assert!(!out.contains('_'));
    }
}
