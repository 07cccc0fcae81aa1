//! # truss-plot: the one plot style of truss-mc
//!
//! The merge's plots (`mc-merge`), the diagnosis's (`truss-diagnose`) and the tolerance
//! study's (`truss-tolerance`) are drawn with `plotters` into SVG in one style, defined here:
//!
//! - [`style`]: the font and its sizes by role ([`style::text`]), the canvas sizes, the
//!   series palette and the named colours, tick-label and angle formats (angles in µrad with
//!   their arcseconds, from `truss-units`), and real subscripts (θ_P as θ with P lowered);
//! - [`legend`]: a legend below the chart whose swatches are drawn exactly like their series;
//! - [`frame`]: the white canvas with the legend below the chart, the caption, margins and
//!   label areas of a chart or of a panel in a figure of panels, and the styles of the axes.
//!
//! A plot module then says only what it draws. Every SVG a plot writes passes through
//! [`style::subscript_svg`], which turns the subscript markers into `tspan`s.

pub mod frame;
pub mod legend;
pub mod style;

/// The result of drawing one plot.
pub type PlotResult = Result<(), Box<dyn std::error::Error>>;
