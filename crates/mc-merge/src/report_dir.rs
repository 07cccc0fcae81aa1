//! The report directory (`--out`): one merge at a time, written safely, never mixed with
//! another job's files, and only our own files removed. The rules are the workspace's, in
//! the crate `run-dir`:
//!
//! - **Locked.** The directory is locked while a merge writes it (an OS advisory lock on
//!   `.truss-mc.lock`, the kind the shards use); a second merge into it is refused at once
//!   (exit 5), naming the holder's pid: wait for the first, then run again.
//! - **Never through a link.** Every file (`report.json`, each plot, `report.md`,
//!   `report.html`) is written to a temporary file with an unpredictable name in the
//!   directory, flushed to disk and renamed over the old one: a reader, a crash or a full
//!   disk sees the old file or the new one, never a torn file. A symbolic link, or anything but a regular file, at a name we write
//!   is refused (exit 5), naming it; the file it points at is not touched.
//! - **Reused only for the same job.** If the directory holds a `report.json` of another
//!   job, or one that is not an mc-merge report, the merge is refused (exit 5) and nothing
//!   in it is touched: give another `--out`, or remove the old report.
//! - **Only our files removed or replaced.** mc-merge lists what it wrote in
//!   `.mc-merge.manifest`, each file with its device, inode, size and SHA-256; a rerun
//!   removes the files listed there that it does not write again (a renamed case's plots,
//!   the plots of a run with plots when this one has `--no-plots`) after writing the new
//!   ones, and only while each is still the file listed. A manifest that is not the user's
//!   own (another user's, writable by others, edited) lists nothing. Every other file stays:
//!   a user's `theta_p-annotated.svg`, a diagnosis's `theta_p-ecdf-before.svg`; a file that
//!   mc-merge would write over and cannot prove it wrote (a case named `ecdf-before` would
//!   write the diagnosis's plot) is refused (exit 5) before anything is written.

use crate::errors::MergeError;
use crate::report::REPORT_FORMAT;
use run_dir::{OutputDir, RunDirError};
use std::io::Read;
use std::path::Path;

/// The report's file name.
pub const REPORT_FILE: &str = "report.json";

/// The writer's name in the directory's manifest.
pub const WRITER: &str = "mc-merge";

/// The longest `report.json` read to check its owner \[bytes\].
pub const MAX_REPORT_BYTES: u64 = 256 << 20;

/// Opens (creating if needed) and locks the report directory `dir`, refusing it if it
/// holds another job's (or a foreign) report, or if any of the `names` to be written holds
/// a file mc-merge cannot prove it wrote (crate `run-dir`). A refused directory is left as it
/// was: its report is checked before the lock file is created, and again under the lock with
/// every name, before anything is written.
pub fn open(dir: &Path, job_id: &str, names: &[String]) -> Result<OutputDir, MergeError> {
    check_report(dir, job_id)?;
    let out = OutputDir::open(dir, WRITER)?;
    check_report(dir, job_id)?;
    out.check_names(names)?;
    Ok(out)
}

/// Refuses `dir` if its `report.json` (not followed if a link) is not this job's report.
fn check_report(dir: &Path, job_id: &str) -> Result<(), MergeError> {
    let report = dir.join(REPORT_FILE);
    let file = match run_dir::input::open_own(&report, std::fs::OpenOptions::new().read(true)) {
        Ok(file) => file,
        Err(RunDirError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            return Ok(());
        }
        Err(e) => return Err(e.into()),
    };
    let mut bytes = Vec::new();
    file.take(MAX_REPORT_BYTES)
        .read_to_end(&mut bytes)
        .map_err(|source| MergeError::Io {
            path: report.clone(),
            source,
        })?;
    check_owner(&report, &bytes, job_id)
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
