//! Reproducing one sample by its case and index: the exact line its shard holds, or with
//! detail everything an engineer needs to debug it without rerunning the job.
//!
//! ## Detail (JSON)
//!
//! `line` (the shard's line, byte for byte, without its newline), when it converged
//! `measured` (its `theta_p` \[rad\], `tan_theta_x`, `tan_theta_y`, and where the top
//! surface sits against the bottom: `decenter_x`, `decenter_y`, `decenter`, `despace` \[mm\],
//! see `truss_core::measure`), `length_errors` (mm per
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

/// What a converged sample measured, as its line holds it.
#[derive(Serialize)]
struct Measured {
    theta_p: f64,
    tan_theta_x: f64,
    tan_theta_y: f64,
    #[serde(flatten)]
    placement: truss_core::Placement,
}

#[derive(Serialize)]
struct Detail<'a> {
    line: &'a str,
    /// θ_P, the tangents \[rad, -\], decenter and despace \[mm\], when it converged.
    #[serde(skip_serializing_if = "Option::is_none")]
    measured: Option<Measured>,
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
    let measured = match (sample.angles(), sample.placement()) {
        (Some(a), Some(p)) => Some(Measured {
            theta_p: a.theta_p,
            tan_theta_x: a.tan_theta_x,
            tan_theta_y: a.tan_theta_y,
            placement: truss_core::Placement {
                decenter_x: p.decenter_x,
                decenter_y: p.decenter_y,
                decenter: p.decenter,
                despace: p.despace,
            },
        }),
        _ => None,
    };
    let detail = Detail {
        line: line.trim_end(),
        measured,
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
