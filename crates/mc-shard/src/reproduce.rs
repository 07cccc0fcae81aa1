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
use serde::ser::{SerializeMap, Serializer};
use truss_core::SolveOptions;
use truss_core::joint::JointSummary;

/// Pairs serialised as a JSON object in their order.
struct Ordered<T>(Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

#[derive(Serialize)]
struct Iteration {
    iteration: u32,
    residual: f64,
    step: f64,
    alpha: f64,
    refactorised: bool,
    slack: Vec<String>,
}

#[derive(Serialize)]
struct Detail<'a> {
    line: &'a str,
    units: serde_json::Value,
    length_errors: Ordered<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    clearances: Option<Ordered<f64>>,
    iterations: Vec<Iteration>,
    #[serde(skip_serializing_if = "Option::is_none")]
    displacements: Option<Ordered<[f64; 3]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    forces: Option<Ordered<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    slack_cables: Option<Vec<String>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    joints: Option<Ordered<JointSummary>>,
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
        units: serde_json::json!({"length": "mm", "force": "N", "angle": "rad"}),
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
        iterations: solver
            .iteration_log()
            .iter()
            .map(|r| Iteration {
                iteration: r.iteration,
                residual: r.residual,
                step: r.step,
                alpha: r.alpha,
                refactorised: r.refactorised,
                slack: r.slack.iter().map(|&m| member_id(m)).collect(),
            })
            .collect(),
        displacements: converged.then(|| {
            Ordered(
                (0..model.nodes().len())
                    .map(|i| (model.nodes()[i].id.clone(), solver.displacement(i)))
                    .collect(),
            )
        }),
        forces: converged.then(|| {
            Ordered(
                (0..model.members().len())
                    .map(|m| (member_id(m), solver.member_force(m)))
                    .collect(),
            )
        }),
        slack_cables: converged.then(|| {
            (0..model.members().len())
                .filter(|&m| solver.is_slack(m))
                .map(member_id)
                .collect()
        }),
        joints: (converged && !model.joints().is_empty())
            .then(|| Ordered(solver.joint_summaries())),
    };
    let mut text = serde_json::to_string_pretty(&detail).expect("the detail always serialises");
    text.push('\n');
    text
}
