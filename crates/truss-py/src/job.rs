//! `truss_mc._native.Job`: a validated job file, and its samples computed in-process by the
//! shard runner's own code: the job crate's sample engine ([`truss_job::engine`]) writing
//! the runner's records ([`mc_shard::worker::record`]), the
//! drawn inputs of [`mc_shard::inputs::InputTable`], and [`mc_shard::reproduce`]. So every
//! number equals the shard line's, `mc-shard inputs`' and `mc-shard reproduce`'s, bit for
//! bit, whatever the thread count. The interpreter lock is released while samples are
//! solved; Ctrl-C stops the run (the finished samples are dropped) and raises
//! `KeyboardInterrupt`.

use crate::columns::{Table, bytes, f64_bytes};
use crate::errors::Failure;
use crate::model::PyModel;
use crate::summary::Collecting;
use mc_shard::inputs::{Draws, InputTable};
use mc_shard::select;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use shard_record::ShardRange;
use std::path::PathBuf;
use std::sync::Arc;
use truss_job::Job;
use truss_job::engine::Engine;
use truss_job::solve::{SampleResult, SampleSolver};

/// A validated job.
#[pyclass(frozen, name = "Job", module = "truss_mc._native")]
pub struct PyJob {
    job: Arc<Job>,
}

/// The case (if named) and the global indices `range ∩ that case's samples`.
fn selection(
    job: &Job,
    case: Option<&str>,
    range: Option<&str>,
) -> Result<(Option<usize>, ShardRange), Failure> {
    let c = case.map(|name| select::case_named(job, name)).transpose()?;
    let r = match range {
        Some(text) => select::range_within(job, "range", text)?,
        None => ShardRange::new(0, job.samples()),
    };
    Ok(match c {
        None => (None, r),
        Some(c) => {
            let (from, to) = (
                job.cases[c].start,
                job.cases[c].start + job.cases[c].samples,
            );
            let start = r.start.clamp(from, to);
            (Some(c), ShardRange::new(start, r.end.clamp(start, to)))
        }
    })
}

/// The job's cases as a shard's begin line lists them.
fn case_infos(job: &Job) -> Vec<shard_record::CaseInfo> {
    job.cases
        .iter()
        .map(|c| shard_record::CaseInfo {
            name: c.name.clone(),
            start: c.start,
            samples: c.samples,
            parameters: c.parameters.clone(),
        })
        .collect()
}

/// The inputs of `table`'s width per row, absent cells NaN, as a dict for Python.
fn inputs_dict<'py>(
    py: Python<'py>,
    table: &InputTable,
    values: &[f64],
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("member_ids", PyList::new(py, &table.members)?)?;
    out.set_item("joint_ids", PyList::new(py, &table.joints)?)?;
    out.set_item("columns", PyList::new(py, table.header())?)?;
    out.set_item("values", f64_bytes(py, values))?;
    Ok(out)
}

/// One sample's draws as cells (NaN where absent), appended to `values`.
fn push_row(
    job: &Job,
    table: &InputTable,
    index: u64,
    draws: &mut Draws,
    row: &mut [Option<f64>],
    values: &mut Vec<f64>,
) {
    let (c, k) = job.case_of(index).expect("an index within the job");
    if !table.row(job, c, k, draws, row) {
        row.fill(None);
    }
    values.extend(row.iter().map(|v| v.unwrap_or(f64::NAN)));
}

#[pymethods]
impl PyJob {
    /// Reads and validates a job file (model files relative to it).
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let job = py.detach(|| Job::read(&path)).map_err(Failure::from)?;
        Ok(Self { job: Arc::new(job) })
    }

    /// Parses and validates a job's text; model files are relative to `base`.
    #[staticmethod]
    #[pyo3(signature = (text, base = PathBuf::from(".")))]
    fn from_json(py: Python<'_>, text: &str, base: PathBuf) -> PyResult<Self> {
        let job = py
            .detach(|| Job::from_json(text, &base))
            .map_err(Failure::from)?;
        Ok(Self { job: Arc::new(job) })
    }

    /// The job id (SHA-256 of its canonical form, with the numerics version).
    #[getter]
    fn id(&self) -> String {
        self.job.id.clone()
    }

    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.job.seed
    }

    /// The number of samples over all cases.
    #[getter]
    fn samples(&self) -> u64 {
        self.job.samples()
    }

    /// The job file, if read from one.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.job.path.clone()
    }

    /// The cases: `name`, `start` (global index of the first sample), `samples`,
    /// `parameters` (as the shard header writes them).
    #[getter]
    fn cases<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        crate::columns::cases(py, case_infos(&self.job).into_iter())
    }

    /// The model of case `case`.
    fn model(&self, case: &str) -> PyResult<PyModel> {
        let c = select::case_named(&self.job, case).map_err(Failure::from)?;
        Ok(PyModel {
            model: Arc::clone(&self.job.cases[c].model),
        })
    }

    /// Solves the samples of `case` (all cases if None) within the global indices `range`
    /// (`"A..B"`, all if None) on `threads` threads (default: all cores). Returns
    /// `columns` (see `columns.rs`: one per field of the shard's sample lines) and, with
    /// `inputs`, the drawn inputs of each sample as `mc-shard inputs` writes them.
    #[pyo3(signature = (case = None, range = None, threads = None, inputs = false))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        case: Option<&str>,
        range: Option<&str>,
        threads: Option<usize>,
        inputs: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let job = Arc::clone(&self.job);
        let (c, range) = selection(&job, case, range)?;
        let threads = mc_shard::cli::check_threads("threads", truss_threads::or_available(threads))
            .map_err(Failure::from)?;
        let table = inputs.then(|| InputTable::new(&job, c, range));
        let selection = c.is_some() || range != ShardRange::new(0, job.samples());
        let (samples, values, collected) = py.detach(|| {
            let mut samples = Table::new();
            let mut values = Vec::new();
            // The samples as the merge keeps them, for its statistics (`Samples.summary`).
            let mut collected = Collecting::new(
                &job.id,
                job.samples(),
                &case_infos(&job),
                mc_shard::shard::budget(&job),
                "truss_mc",
                env!("CARGO_PKG_VERSION"),
            );
            type Row = (shard_record::Sample, Vec<u8>, Option<Vec<f64>>);
            let each = |chunk: &mut Vec<Row>, _: &SampleSolver<'_>, result: SampleResult| {
                // The shard line's bytes, read back into columns on the calling thread: a
                // worker allocates little that another thread frees (the allocator's
                // arenas would be contended).
                let mut line = Vec::with_capacity(256);
                let sample = mc_shard::worker::record(&job, &result);
                sample.write_line(&mut line);
                let row = table.as_ref().map(|t| {
                    let mut v = Vec::with_capacity(t.width());
                    let mut row = vec![None; t.width()];
                    push_row(
                        &job,
                        t,
                        result.index,
                        &mut Draws::default(),
                        &mut row,
                        &mut v,
                    );
                    v
                });
                chunk.push((sample, line, row));
            };
            let engine = Engine::new(&job, threads);
            engine.run(range.start..range.end, each, |chunk| match chunk {
                Some(chunk) => {
                    for (sample, line, row) in chunk {
                        let record: serde_json::Map<String, serde_json::Value> =
                            serde_json::from_slice(&line).map_err(|e| {
                                PyRuntimeError::new_err(format!(
                                    "a sample line does not read back: {e}"
                                ))
                            })?;
                        samples.push(&record);
                        collected.add(&sample, &line)?;
                        values.extend(row.unwrap_or_default());
                    }
                    Ok(())
                }
                None => Python::attach(|py| py.check_signals()),
            })?;
            Ok::<_, PyErr>((samples, values, collected.finish(selection)?))
        })?;
        let out = PyDict::new(py);
        out.set_item("columns", samples.to_python(py)?)?;
        out.set_item("collected", Py::new(py, collected)?)?;
        match &table {
            Some(t) => out.set_item("inputs", inputs_dict(py, t, &values)?)?,
            None => out.set_item("inputs", py.None())?,
        }
        Ok(out)
    }

    /// The drawn inputs of `case`'s samples (all cases if None) within `range`, without
    /// solving: `mc-shard inputs`' rows, with `index`, `case` and `sample` per row.
    #[pyo3(signature = (case = None, range = None))]
    fn inputs<'py>(
        &self,
        py: Python<'py>,
        case: Option<&str>,
        range: Option<&str>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let job = Arc::clone(&self.job);
        let (c, range) = selection(&job, case, range)?;
        let table = InputTable::new(&job, c, range);
        let (rows, values) = py.detach(|| {
            let mut rows: Vec<(u64, usize, u64)> = Vec::new();
            let mut values = Vec::new();
            let (mut draws, mut row) = (Draws::default(), vec![None; table.width()]);
            for index in range.start..range.end {
                let (case, k) = job.case_of(index).expect("an index within the job");
                if c.is_none_or(|c| c == case) {
                    push_row(&job, &table, index, &mut draws, &mut row, &mut values);
                    rows.push((index, case, k));
                }
            }
            (rows, values)
        });
        let out = inputs_dict(py, &table, &values)?;
        out.set_item(
            "index",
            bytes(py, rows.iter().map(|r| (r.0 as i64).to_le_bytes())),
        )?;
        let names = rows.iter().map(|r| job.cases[r.1].name.as_str());
        out.set_item("case", PyList::new(py, names)?)?;
        out.set_item(
            "sample",
            bytes(py, rows.iter().map(|r| (r.2 as i64).to_le_bytes())),
        )?;
        Ok(out)
    }

    /// `mc-shard reproduce`'s output for sample `sample` of case `case`: the shard's line
    /// (with its newline), or with `detail` the JSON detail (draws, iterations,
    /// displacements, forces).
    #[pyo3(signature = (case, sample, detail = false))]
    fn reproduce(&self, py: Python<'_>, case: &str, sample: u64, detail: bool) -> PyResult<String> {
        let c = select::case_named(&self.job, case).map_err(Failure::from)?;
        select::check_sample(&self.job, c, sample).map_err(Failure::from)?;
        let job = Arc::clone(&self.job);
        Ok(py.detach(move || mc_shard::reproduce::reproduce(&job, c, sample, detail)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Job(id={}…, {} cases, {} samples)",
            &self.job.id[..12],
            self.job.cases.len(),
            self.job.samples()
        )
    }
}
