//! The readable report: `report.md` and `report.html` beside `report.json`, for people.
//!
//! Both say the same things in the same order, because both render one [`Document`] built
//! from the [`Report`] that `report.json` is serialised from ([`compose()`]: nothing is
//! computed again):
//!
//! 0. **The answer**, first, in three lines ([`crate::answer`]): the allowable σ for the
//!    target with its interval and conservative end, the cases above and below the target,
//!    and the Rayleigh verdicts with how many chance alone gives;
//! 1. **The run**: the job id, the samples present and expected, the failed samples, the
//!    cases, the programs and versions that wrote the shards (as their begin lines name
//!    them; the numerics version is not in the shards, it is part of the job id), the
//!    merge's own version, the statistical settings, the target and the units;
//! 2. **Summary** at the target percentile, one row per case: θ_P in rad and arcsec with its
//!    interval, against the target, and the Rayleigh law's verdict;
//! 3. **Percentiles** of θ_P: every percentile of every case with its BCa (or
//!    percentile-method) interval in rad and arcsec and the order-statistic interval;
//! 4. **The Rayleigh law**: σ_t, σ, the Rayleigh and empirical target percentiles, their
//!    relative difference, the KS and AD p-values, and each verdict in words;
//! 5. **Floating stages and loose joints** (models with pin joints): fractions with their
//!    intervals;
//! 6. **Caveats**: partial coverage, excluded failures, floating stages beyond the tail;
//! 7. **Sweeps** over σ (points, line fits, the allowable σ and its conservative choice) and
//!    over the number of stages, with their plots;
//! 8. **Plots of each case**, each with alternative text that states its message;
//! 9. **Definitions** of every statistic, in words.
//!
//! Angles are given in rad and arcsec, σ in mm, and every column header names its unit.
//! Like `report.json`, neither file depends on how the job was split or on the file order.
//!
//! `report.md` ([`markdown()`]) links the plot files beside it; `report.html` ([`html()`])
//! embeds them (see its module). The plots are read back from the files just written,
//! never through a link, so the page embeds exactly the files the Markdown links.
//!
//! Both files are written like every other file of the report directory: through a
//! temporary file renamed into place, never through a link, and listed in mc-merge's
//! manifest ([`run_dir::OutputDir`]).

pub mod budget;
pub mod compose;
pub mod document;
pub mod floating;
pub mod html;
pub mod markdown;
pub mod percentiles;
pub mod plots;
pub mod rayleigh;
pub mod sweeps;
pub mod words;

pub use compose::compose;
pub use document::Document;
pub use html::html;
pub use markdown::markdown;

use crate::errors::MergeError;
use crate::load::ShardWriter;
use crate::report::Report;
use run_dir::OutputDir;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The Markdown report's file name.
pub const MARKDOWN_FILE: &str = "report.md";

/// The HTML report's file name.
pub const HTML_FILE: &str = "report.html";

/// The largest plot read back to be embedded \[bytes\] (a plot is well under 1 MiB).
pub const MAX_PLOT_BYTES: u64 = 64 << 20;

/// Writes `report.md` and `report.html` into `out`, beside the plot files `plots` (the
/// paths [`crate::plot::draw_all`] returned; none with `--no-plots`); returns their paths.
pub fn write(
    out: &mut OutputDir,
    report: &Report,
    writers: &[ShardWriter],
    plots: &[PathBuf],
) -> Result<Vec<PathBuf>, MergeError> {
    let files: BTreeSet<String> = plots
        .iter()
        .filter_map(|p| p.file_name()?.to_str().map(String::from))
        .collect();
    let doc = compose(report, writers, &files);
    let mut svgs = BTreeMap::new();
    for p in doc.plots() {
        svgs.insert(p.svg.clone(), read_plot(&out.path().join(&p.svg))?);
    }
    Ok(vec![
        out.write(MARKDOWN_FILE, markdown(&doc).as_bytes())?,
        out.write(HTML_FILE, html(&doc, &svgs).as_bytes())?,
    ])
}

/// Reads a plot this merge wrote, refusing a link or a non-file at its name.
fn read_plot(path: &Path) -> Result<Vec<u8>, MergeError> {
    let file = run_dir::input::open_own(path, std::fs::OpenOptions::new().read(true))?;
    let mut bytes = Vec::new();
    file.take(MAX_PLOT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| MergeError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    if bytes.len() as u64 > MAX_PLOT_BYTES {
        return Err(MergeError::Plot {
            path: path.to_path_buf(),
            message: format!("longer than {MAX_PLOT_BYTES} bytes, too long to embed"),
        });
    }
    Ok(bytes)
}
