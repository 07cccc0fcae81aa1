//! Reading shard files back as columns: every file verified as the merge verifies it
//! (`shard_record::read_shard`: each line's form and place, every checkpoint, the end
//! line's digests; a converged θ_P in \[0, π/2\], `shard_record::Sample::check_angles`), one
//! job across the files, and an index present in two files only if its lines are identical;
//! each file checked to be a regular file (links followed) *before* it is opened, so a FIFO
//! or a device is refused at once (`InvalidInputError`, exit code 3), as the merge refuses it; the samples in index order, each field of the sample lines a column
//! ([`crate::columns`]). With `partial`, an incomplete file (a run still going, or stopped)
//! gives the lines its last checkpoint verifies.

use crate::columns::Table;
use crate::errors::{Failure, Kind};
use crate::summary::Collecting;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shard_record::{
    Begin, MAX_BEGIN_LINE_BYTES, Record, parse_record, read_line, read_shard, scan_shard,
};
use std::hash::{DefaultHasher, Hasher};
use std::path::{Path, PathBuf};

/// The begin line of `path`, if it reads and parses (the full read reports any fault).
fn header(path: &Path) -> Option<Begin> {
    let mut line = Vec::new();
    let file = std::fs::File::open(path).ok()?;
    let mut reader = std::io::BufReader::new(file);
    read_line(&mut reader, &mut line, MAX_BEGIN_LINE_BYTES).ok()??;
    match parse_record(&line) {
        Ok(Record::Begin(b)) => Some(b),
        _ => None,
    }
}

/// A 64-bit fingerprint of a line's bytes (SipHash with fixed keys: the same in every run).
fn fingerprint(line: &[u8]) -> u64 {
    let mut h = DefaultHasher::new();
    h.write(line);
    h.finish()
}

/// What the files hold: the first file's header, the samples as columns, and as the merge
/// keeps them (for its statistics).
struct Read {
    begin: Begin,
    table: Table,
    collected: crate::summary::PyCollected,
}

/// Reads `files` (see the module doc).
fn read(files: &[PathBuf], partial: bool) -> Result<Read, Failure> {
    if files.is_empty() {
        return Err(Failure::new(Kind::Usage, "no shard files given"));
    }
    for f in files {
        run_dir::input::check_regular(f).map_err(|e| match e {
            run_dir::RunDirError::NotRegular { .. } => {
                Failure::new(Kind::InvalidInput, e.to_string())
            }
            e => Failure::new(Kind::Io, e.to_string()),
        })?;
    }
    let mut order: Vec<(u64, &PathBuf)> = files
        .iter()
        .map(|f| (header(f).map_or(0, |b| b.range.start), f))
        .collect();
    order.sort();
    let mut table = Table::new();
    // The samples as the merge keeps them, once the first header names the job.
    let mut collecting: Option<Collecting> = None;
    // (index, fingerprint, file) of every sample taken, in index order.
    let mut taken: Vec<(u64, u64, usize)> = Vec::new();
    let mut first: Option<(Begin, &PathBuf)> = None;
    for (n, (_, path)) in order.iter().enumerate() {
        if collecting.is_none()
            && let Some(b) = header(path)
        {
            collecting = Some(Collecting::new(
                &b.job_id,
                b.job_samples,
                &b.cases,
                b.budget,
                &b.program,
                &b.program_version,
            ));
        }
        let visit = |_line_number: u64, sample: &shard_record::Sample, line: &[u8]| {
            sample.check_angles()?;
            let index = sample.index;
            let fp = fingerprint(line);
            if let Some(&(last, _, _)) = taken.last()
                && index <= last
            {
                let at = taken.partition_point(|t| t.0 < index);
                return match taken.get(at) {
                    Some(&(i, f, other)) if i == index && f != fp => Err(format!(
                        "index {index} differs from its line in {} (overlapping shards disagree)",
                        order[other].1.display()
                    )),
                    _ => Ok(()),
                };
            }
            let record: serde_json::Map<String, serde_json::Value> =
                serde_json::from_slice(line).map_err(|e| format!("not a JSON object: {e}"))?;
            table.push(&record);
            if let Some(c) = collecting.as_mut() {
                c.add(sample, line).map_err(|f| f.message)?;
            }
            taken.push((index, fp, n));
            Ok(())
        };
        let scan = if partial {
            scan_shard(path, visit)
        } else {
            read_shard(path, visit)
        }
        .map_err(Failure::from)?;
        match &first {
            None => first = Some((scan.begin, path)),
            Some((begin, first_path))
                if (&begin.job_id, begin.job_samples, &begin.cases)
                    != (
                        &scan.begin.job_id,
                        scan.begin.job_samples,
                        &scan.begin.cases,
                    ) =>
            {
                return Err(Failure::new(
                    Kind::Verification,
                    format!(
                        "{}: a shard of job {} ({} samples), but {} is of job {} ({} samples): \
                         shards of two jobs",
                        path.display(),
                        scan.begin.job_id,
                        scan.begin.job_samples,
                        first_path.display(),
                        begin.job_id,
                        begin.job_samples
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    let (begin, _) = first.expect("at least one file was read");
    let collecting = collecting.ok_or_else(|| {
        Failure::new(
            Kind::Verification,
            "no readable begin line in the shard files",
        )
    })?;
    // Incomplete files read on purpose are a selection of the job: their statistics allow
    // the rest to be missing (otherwise missing samples are refused, as the merge refuses
    // them, unless asked).
    let selection = partial;
    Ok(Read {
        begin,
        table,
        collected: collecting.finish(selection)?,
    })
}

/// Reads shard files (see the module doc): returns `job_id`, `job_samples`, `cases` (as the
/// headers list them: `name`, `start`, `samples`, `parameters`) and `columns`.
#[pyfunction]
#[pyo3(signature = (files, partial = false))]
pub fn read_shard_files<'py>(
    py: Python<'py>,
    files: Vec<PathBuf>,
    partial: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let read = py.detach(|| read(&files, partial))?;
    let out = PyDict::new(py);
    out.set_item("job_id", &read.begin.job_id)?;
    out.set_item("job_samples", read.begin.job_samples)?;
    out.set_item(
        "cases",
        crate::columns::cases(py, read.begin.cases.into_iter())?,
    )?;
    out.set_item("columns", read.table.to_python(py)?)?;
    out.set_item("collected", Py::new(py, read.collected)?)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use shard_record::{CaseInfo, Sample, SampleDigest, ShardRange, Status, to_line};

    /// A complete shard of one sample whose θ_P is `theta_p`, its digests computed after.
    fn shard(dir: &Path, theta_p: f64) -> PathBuf {
        let range = ShardRange { start: 0, end: 1 };
        let case = CaseInfo {
            name: "a".into(),
            start: 0,
            samples: 1,
            parameters: Default::default(),
        };
        let begin = Begin::new("mc-shard", "0.1.0", &"0".repeat(64), range, 1, vec![case]);
        let sample = Sample {
            index: 0,
            case: "a".into(),
            sample: 0,
            status: Status::Converged,
            iterations: 3,
            theta_p: Some(theta_p),
            tan_theta_x: Some(0.0),
            tan_theta_y: Some(0.0),
            decenter_x: None,
            decenter_y: None,
            decenter: None,
            despace: None,
            residual: Some(1e-11),
            slack_cables: Some(0),
            loose_joints: None,
            floating: None,
            holding_force: None,
            limit_ratio: None,
            reason: None,
        };
        let line = sample.to_line();
        let mut digest = SampleDigest::new();
        digest.add_line(line.as_bytes(), false);
        let text = to_line(&Record::Begin(begin)) + &line + &to_line(&Record::End(digest.end()));
        let path = dir.join(range.file_name());
        std::fs::write(&path, text).unwrap();
        path
    }

    /// θ_P = 2 rad verifies its digests but is no angle between the surfaces: refused as
    /// the merge refuses it, naming the file and line; 0.5 rad reads.
    #[test]
    fn angles_beyond_a_right_angle_do_not_verify() {
        let dir = tempfile::tempdir().unwrap();
        let path = shard(dir.path(), 2.0);
        let e = read(std::slice::from_ref(&path), false).err().unwrap();
        assert_eq!(e.kind, Kind::Verification);
        assert!(
            e.message.contains("not a distortion angle"),
            "{}",
            e.message
        );
        let path = shard(dir.path(), 0.5);
        read(&[path], false).unwrap();
    }

    /// A FIFO is refused before it is opened (an open would wait for a writer forever).
    #[test]
    fn a_fifo_is_refused_at_once() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("shard.jsonl");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        let e = read(&[fifo], false).err().unwrap();
        assert_eq!(e.kind, Kind::InvalidInput);
        assert!(e.message.contains("not a regular file"), "{}", e.message);
    }
}
