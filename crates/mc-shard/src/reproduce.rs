//! Reproducing one sample by its case and index: the exact line its shard holds, or with
//! detail everything an engineer needs to debug it without rerunning the job.
//!
//! ## Detail (JSON)
//!
//! `line` (the shard's line, byte for byte, without its newline), `length_errors` (mm per
//! member id, model order, as drawn), `clearances` (mm per joint id, when the case draws
//! backlash clearances), `iterations` (per Newton iteration: out-of-balance
//! force \[N\], step \[mm\], line-search α, whether the tangent was factorised afresh, the slack
//! cables), and, when it converged, `displacements` (mm per node id), `forces` (N per member
//! id, tension positive), `slack_cables` and, for a model with backlash joints, `joints` (per
//! joint id: the hole centre's `offset` from the shaft centre \[mm\], the `contact` force
//! \[N\], 0 when loose, and whether it is `loose`).

use crate::job::Job;
use crate::worker::Worker;
use serde::Serialize;
use truss_core::SolveOptions;
use truss_core::output::{EquilibriumById, IterationLine, Ordered, UNITS, Units};

#[derive(Serialize)]
struct Detail<'a> {
    line: &'a str,
    units: Units,
    length_errors: Ordered<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    clearances: Option<Ordered<f64>>,
    iterations: Vec<IterationLine>,
    /// The equilibrium by id, when the sample converged (the same type `truss solve`
    /// prints).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    equilibrium: Option<EquilibriumById>,
}

/// The line of sample `k` of case `c` (with its newline), and with `detail` the JSON detail.
pub fn reproduce(job: &Job, c: usize, k: u64, detail: bool) -> String {
    let index = job.cases[c].start + k;
    if !detail {
        return Worker::new(job).sample(index).to_line();
    }
    let options = SolveOptions {
        record_iterations: true,
        ..SolveOptions::default()
    };
    let mut worker = Worker::with_options(job, options);
    let sample = worker.sample(index);
    let line = sample.to_line();
    let model = &job.cases[c].model;
    let solver = worker.solver(c).expect("the worker solved this case");
    let member_id = |m: usize| model.members()[m].id.clone();
    let converged = sample.angles().is_some();
    let detail = Detail {
        line: line.trim_end(),
        units: UNITS,
        length_errors: Ordered(
            worker
                .last_errors()
                .iter()
                .enumerate()
                .map(|(m, &e)| (member_id(m), e))
                .collect(),
        ),
        clearances: (!worker.last_clearances().is_empty()).then(|| {
            Ordered(
                worker
                    .last_clearances()
                    .iter()
                    .zip(model.joints())
                    .map(|(&g, j)| (j.id.clone(), g))
                    .collect(),
            )
        }),
        iterations: IterationLine::log(model, solver),
        equilibrium: converged.then(|| EquilibriumById::of(model, solver)),
    };
    let mut text = serde_json::to_string_pretty(&detail).expect("the detail always serialises");
    text.push('\n');
    text
}
