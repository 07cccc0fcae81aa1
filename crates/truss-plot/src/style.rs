//! The style every plot shares: the font and its sizes by role, the canvas sizes, the
//! colours, number and angle formats for tick labels and legends, and real subscripts.

use plotters::prelude::*;
use truss_units::ARCSEC_PER_MICRORAD;

/// The font family of every text (resolved by the renderer: a browser, librsvg, or resvg with
/// the system's fonts).
pub const FONT: &str = "sans-serif";
/// Width of a plot of one chart in SVG units (pixels at 1×).
pub const WIDTH: u32 = 960;
/// Height of the chart part of a plot of one chart (the legend is added below).
pub const CHART_HEIGHT: u32 = 620;
/// Width of a figure of panels side by side.
pub const PANELS_WIDTH: u32 = 1200;
/// Height of the title strip above a figure of panels.
pub const TITLE_HEIGHT: u32 = 40;
/// Height of a row of panels in a figure of panels.
pub const PANEL_ROW_HEIGHT: u32 = 520;

/// Text sizes in pixels, by role.
pub mod text {
    /// A chart's caption.
    pub const CAPTION: u32 = 22;
    /// The title above a figure of panels.
    pub const TITLE: u32 = 20;
    /// An axis description.
    pub const DESCRIPTION: u32 = 18;
    /// An axis description in a panel of a figure of panels.
    pub const PANEL_DESCRIPTION: u32 = 17;
    /// A panel's caption; an axis description in a strip below a chart.
    pub const PANEL_CAPTION: u32 = 16;
    /// Tick labels and legend entries.
    pub const LABEL: u32 = 15;
    /// Tick labels in a panel of a figure of panels.
    pub const PANEL_LABEL: u32 = 14;
}
/// Grid lines.
pub const LIGHT: RGBColor = RGBColor(232, 232, 232);
/// Histogram bars.
pub const BAR: RGBColor = RGBColor(150, 175, 215);
/// Measured data, against a simulation ([`SIMULATED`]): the palette's red.
pub const MEASURED: RGBColor = RGBColor(200, 30, 30);
/// A simulation, against measured data ([`MEASURED`]): the palette's blue.
pub const SIMULATED: RGBColor = RGBColor(30, 90, 200);

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

/// The colours of series, distinguishable in print: black, red, blue, green, purple,
/// orange, teal, brown, then again.
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

/// An angle in µrad with its arcsec in brackets, e.g. "96.9 µrad (19.99″)": arcsec to two
/// decimals, as the console and the readable report write them, so that the default target
/// (9.69e-5 rad) reads 19.99″ everywhere and not 20.0″ in the plots.
pub fn angle(microrad: f64) -> String {
    format!(
        "{} µrad ({:.2}″)",
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
