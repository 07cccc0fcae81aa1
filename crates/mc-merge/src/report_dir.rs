//! The report directory (`--out`): written safely, and never mixed with another job's files.
//!
//! - `report.json` is written to a temporary file in the same directory (`.report.json.tmp-PID`),
//!   flushed to disk, then renamed over the old one: a reader, a crash or a full disk sees the
//!   old report or the new one, never a torn file.
//! - A directory is reused only for the same job. If it holds a `report.json` of another job,
//!   or a `report.json` that is not an mc-merge report, the merge is refused (exit 5, a file in
//!   the way) and nothing in it is touched: give another `--out`, or remove the old report.
//! - Before the new files are written, our own earlier files are removed: beside the same
//!   job's `report.json` (which is written before the plots), plot files by their
//!   names ([`crate::plot::is_plot_file`]: `theta_p-*`, `tan-*`, `qq-*`, `exceedance-*`,
//!   `running-*` and the two sweeps, `.svg` or `.png`) and stale temporary reports. So no plot
//!   of an earlier run (a renamed case, a run with plots when this one has `--no-plots`) stays
//!   beside a report it does not belong to. Other files are left alone, and so are files named
//!   like plots in a directory without a report (a diagnosis's `theta_p-ecdf-before.svg`).

use crate::errors::MergeError;
use crate::report::REPORT_FORMAT;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The report's file name.
pub const REPORT_FILE: &str = "report.json";

/// The prefix of temporary report files.
const TEMP_PREFIX: &str = ".report.json.tmp-";

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> MergeError + '_ {
    move |source| MergeError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Creates `dir` if needed, refuses it if it holds another job's (or a foreign) report, and
/// removes our own earlier plots and temporary files from it.
pub fn prepare(dir: &Path, job_id: &str) -> Result<(), MergeError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let report = dir.join(REPORT_FILE);
    let ours_before = match std::fs::read(&report) {
        Ok(bytes) => {
            check_owner(&report, &bytes, job_id)?;
            true
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
        Err(source) => {
            return Err(MergeError::Io {
                path: report,
                source,
            });
        }
    };
    for entry in std::fs::read_dir(dir).map_err(io(dir))? {
        let entry = entry.map_err(io(dir))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        // Plots are ours only beside our report (written before them): in a directory
        // without one, a file named like a plot (`theta_p-ecdf-before.svg` of a diagnosis)
        // is someone else's.
        let ours =
            (ours_before && crate::plot::is_plot_file(name)) || name.starts_with(TEMP_PREFIX);
        if ours && entry.file_type().map_err(io(dir))?.is_file() {
            let path = entry.path();
            std::fs::remove_file(&path).map_err(io(&path))?;
        }
    }
    Ok(())
}

fn check_owner(report: &Path, bytes: &[u8], job_id: &str) -> Result<(), MergeError> {
    let in_the_way = |message: String| MergeError::InTheWay {
        path: report.to_path_buf(),
        message,
    };
    let value: serde_json::Value = serde_json::from_slice(bytes).map_err(|e| {
        in_the_way(format!(
            "is not a readable mc-merge report ({e}); remove it or give another --out directory"
        ))
    })?;
    if value.get("format").and_then(|f| f.as_str()) != Some(REPORT_FORMAT) {
        return Err(in_the_way(format!(
            "is not an mc-merge report (no \"format\": \"{REPORT_FORMAT}\"); remove it or give another --out directory"
        )));
    }
    match value.get("job_id").and_then(|j| j.as_str()) {
        Some(old) if old == job_id => Ok(()),
        old => Err(in_the_way(format!(
            "is the report of job {}, and these shards are of job {job_id}: give another --out directory, or remove the old report and its plots",
            old.unwrap_or("(none)")
        ))),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory, flushed to disk
/// and renamed over `path`; the temporary file is removed if anything fails.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), MergeError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let temp: PathBuf = dir.join(format!("{TEMP_PREFIX}{}", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&temp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&temp, path)
    })();
    result.map_err(|source| {
        let _ = std::fs::remove_file(&temp);
        MergeError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}
