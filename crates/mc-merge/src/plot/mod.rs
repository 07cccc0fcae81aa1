//! Plots for a design review, after the paper's figures, as SVG and (cargo feature `png`, on
//! by default) PNG at twice the size, for slides. Per case (`STEM` is [`file_stems`]' name):
//!
//! - `theta_p-STEM`: histogram of θ_P (as a density) with the fitted Rayleigh density, the
//!   empirical and Rayleigh target percentiles and the target angle (Figs. 4, 7); samples
//!   beyond the axis are counted in the legend;
//! - `tan-STEM`: histograms of tan θ_x and tan θ_y with the N(0, σ_t²) density (Fig. 6);
//! - `qq-STEM`: Rayleigh QQ plot with a pointwise band;
//! - `exceedance-STEM`: 1 − F on a log scale with P99 and P99.9 marked;
//! - `running-STEM`: the target percentile with its interval against the sample count;
//! - `placement-STEM`: histograms of decenter with its fitted Rayleigh density and of
//!   despace with its fitted normal density, their percentiles and the budget's limits, in
//!   µm (where the samples record them);
//!
//! and over the job:
//!
//! - `sigma-sweep`: θ_P at the target percentile against σ (log–log), every σ-series with its
//!   intervals, line through the origin, target and allowable σ, and the deviations from the
//!   line (Figs. 3, 16);
//! - `stages-sweep`: the normalised percentile against the number of stages (Fig. 9).
//!
//! Angles are drawn in µrad with an arcsec axis beside them; slopes tan θ as 10⁶ · tan θ. The
//! legend sits below each chart, its swatches drawn like their series (dashed, dotted). The
//! style (palette, sizes, fonts, the frame and the legend) is `truss-plot`'s, shared with the
//! diagnosis and the tolerance study.

mod distribution;
mod placement;
#[cfg(feature = "png")]
pub mod png;
mod series;

pub use distribution::{axis_end, bin_count, histogram};

use crate::errors::MergeError;
use crate::load::CaseData;
use crate::report::Report;
use run_dir::OutputDir;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The prefixes of the per-case plot files.
pub const CASE_PLOTS: [&str; 6] = ["theta_p", "tan", "qq", "exceedance", "running", "placement"];

/// The names of the plots over the job.
pub const JOB_PLOTS: [&str; 2] = ["sigma-sweep", "stages-sweep"];

/// The file extensions of plots.
pub const EXTENSIONS: [&str; 2] = ["svg", "png"];

fn is_safe(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_'
}

/// File-name-safe, unique stems of the case names, in order. A name made only of ASCII
/// letters, digits, `.`, `-` and `_` is its own stem. Any other character becomes `_`, and
/// such a name, or one that equals another's ignoring letter case (file systems that ignore
/// case), gets `~K` appended, K its position in the job from 1; `~` never occurs in a plain
/// stem, so no two stems are equal: cases `σ` and `δ` give `_~1` and `_~2`; `a/b` and `a_b`
/// give `a_b~1` and `a_b`.
pub fn file_stems(names: &[&str]) -> Vec<String> {
    let mut folded: HashMap<String, usize> = HashMap::new();
    for n in names {
        *folded.entry(n.to_ascii_lowercase()).or_default() += 1;
    }
    names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let plain = !n.is_empty() && n.chars().all(is_safe) && n != &"." && n != &"..";
            let stem: String = n
                .chars()
                .map(|c| if is_safe(c) { c } else { '_' })
                .collect();
            if plain && folded[&n.to_ascii_lowercase()] == 1 {
                stem
            } else {
                format!("{stem}~{}", k + 1)
            }
        })
        .collect()
}

type Drawn = Result<Option<String>, Box<dyn std::error::Error>>;

/// Writes one plot: the SVG, and with the `png` feature its PNG beside it.
struct Writer {
    #[cfg(feature = "png")]
    png: png::Rasteriser,
    written: Vec<PathBuf>,
}

impl Writer {
    /// Fails (with the `png` feature) when the system has no fonts.
    fn new(dir: &Path) -> Result<Self, MergeError> {
        #[cfg(not(feature = "png"))]
        let _ = dir;
        Ok(Self {
            #[cfg(feature = "png")]
            png: png::Rasteriser::new().map_err(|message| MergeError::Plot {
                path: dir.to_path_buf(),
                message,
            })?,
            written: vec![],
        })
    }

    /// Writes the plot `stem` (`.svg`, and `.png` with the feature) into `out`.
    fn write(&mut self, out: &mut OutputDir, stem: &str, drawn: Drawn) -> Result<(), MergeError> {
        let dir = out.path().to_path_buf();
        let plot_error = |name: &str, message: String| MergeError::Plot {
            path: dir.join(name),
            message,
        };
        let svg_name = format!("{stem}.svg");
        let Some(svg) = drawn.map_err(|e| plot_error(&svg_name, e.to_string()))? else {
            return Ok(());
        };
        let svg = truss_plot::style::subscript_svg(&svg);
        self.written.push(out.write(&svg_name, svg.as_bytes())?);
        #[cfg(feature = "png")]
        {
            let png_name = format!("{stem}.png");
            let png = self
                .png
                .png(&svg)
                .map_err(|message| plot_error(&png_name, message))?;
            self.written.push(out.write(&png_name, &png)?);
        }
        Ok(())
    }
}

/// Every file name [`draw_all`] may write for `report` (also a plot it turns out not to draw,
/// such as a sweep of a job without one), to check before anything is written.
pub fn file_names(report: &Report) -> Vec<String> {
    let names: Vec<&str> = report.cases.iter().map(|c| c.name.as_str()).collect();
    let mut stems: Vec<String> = file_stems(&names)
        .iter()
        .flat_map(|stem| CASE_PLOTS.iter().map(move |kind| format!("{kind}-{stem}")))
        .collect();
    stems.extend(JOB_PLOTS.iter().map(|s| s.to_string()));
    let extensions = if cfg!(feature = "png") {
        &EXTENSIONS[..]
    } else {
        &EXTENSIONS[..1]
    };
    stems
        .iter()
        .flat_map(|s| extensions.iter().map(move |e| format!("{s}.{e}")))
        .collect()
}

/// Draws every plot into the report directory `out`; returns the files written.
pub fn draw_all(
    out: &mut OutputDir,
    cases: &[CaseData],
    report: &Report,
) -> Result<Vec<PathBuf>, MergeError> {
    let mut w = Writer::new(out.path())?;
    let names: Vec<&str> = report.cases.iter().map(|c| c.name.as_str()).collect();
    for ((case, rep), stem) in cases.iter().zip(&report.cases).zip(file_stems(&names)) {
        let [theta, tan, qq, exceedance, running, placement] =
            CASE_PLOTS.map(|k| format!("{k}-{stem}"));
        w.write(out, &theta, distribution::theta(case, rep, report))?;
        w.write(out, &tan, distribution::tan(case, rep))?;
        w.write(out, &qq, distribution::qq(case, rep, report))?;
        w.write(
            out,
            &exceedance,
            distribution::exceedance(case, rep, report),
        )?;
        w.write(out, &running, distribution::running(case, rep, report))?;
        w.write(out, &placement, placement::placement(case, rep, report))?;
    }
    let [sigma, stages] = JOB_PLOTS;
    w.write(out, sigma, series::sigma(report))?;
    w.write(out, stages, series::stages(report))?;
    Ok(w.written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_are_unique_after_sanitising() {
        assert_eq!(file_stems(&["σ", "δ"]), ["_~1", "_~2"]);
        assert_eq!(file_stems(&["a/b", "a_b"]), ["a_b~1", "a_b"]);
        assert_eq!(file_stems(&["A", "a", "b"]), ["A~1", "a~2", "b"]);
        assert_eq!(
            file_stems(&["sigma-0.0063", ".."]),
            ["sigma-0.0063", "..~2"]
        );
        let many = ["x y", "x_y", "x?y", "x_y~1"];
        let stems = file_stems(&many);
        let mut unique = stems.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), many.len(), "{stems:?}");
    }
}
