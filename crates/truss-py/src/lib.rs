//! # truss-py: the Python package `truss_mc`
//!
//! The extension module `truss_mc._native`, built by maturin (the `pyproject.toml` at the
//! repository's root) with PyO3's stable ABI, so one wheel serves CPython 3.9 and later. The
//! pure-Python layer in `python/truss_mc/` turns what this module returns into NumPy arrays
//! (and pandas frames, when pandas is installed) and documents the API; this crate only
//! calls the libraries the command-line tools call, so a number from Python is the number
//! the tools write:
//!
//! | Python | library |
//! |---|---|
//! | `prism(stages=5, …)`, `Model.from_file`, `solve(model, length_errors={…})` | `truss_job::job::parse_prism`, `truss_core::Model`, `truss_core::Solver`, `truss_core::output::EquilibriumById` (as `truss solve`) |
//! | `Job.from_file`, `job.run(case=…, range=…, threads=…, inputs=True)` | `truss_job::Job`, `truss_job::engine::Engine` writing the runner's records (`mc_shard::worker::record`), `mc_shard::inputs::InputTable` (as `mc-shard run` and `mc-shard inputs`) |
//! | `job.reproduce(case, sample, detail=…)` | `mc_shard::reproduce::reproduce` (as `mc-shard reproduce`) |
//! | `read_shards(paths)` | `shard_record::read_shard` (as the merge verifies) |
//! | `samples.summary(…)` (of a run or of shards read back) | `mc_merge::load::Collector`, `mc_merge::build_report`, `mc_merge::table::answer` (as `mc-merge` computes `report.json` and its answer lines) |
//!
//! Errors become the exceptions of `truss_mc.errors` with the tools' messages and exit
//! codes ([`errors`]); no path through this crate panics on a user's input. Solving and
//! reading release the interpreter lock.

pub mod columns;
pub mod errors;
pub mod job;
pub mod model;
pub mod shards;
pub mod summary;

use pyo3::prelude::*;

/// The module `truss_mc._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::PyModel>()?;
    m.add_class::<job::PyJob>()?;
    m.add_class::<summary::PyCollected>()?;
    m.add_function(wrap_pyfunction!(shards::read_shard_files, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("NUMERICS_VERSION", truss_job::NUMERICS_VERSION)?;
    m.add("SHARD_FORMAT_VERSION", shard_record::FORMAT_VERSION)?;
    Ok(())
}
