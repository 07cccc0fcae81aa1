//! `truss solve`: one equilibrium, printed as JSON.
//!
//! ## Output
//!
//! ```json
//! {
//!   "converged": true, "iterations": 5, "factorisations": 2, "residual": 2.1e-13,
//!   "theta_p": 2.94e-5, "tan_theta_x": -2.55e-5, "tan_theta_y": -1.47e-5,
//!   "units": {"length": "mm", "force": "N", "angle": "rad"},
//!   "displacements": {"n1.0": [0.0, 0.0, 0.0094], …},
//!   "forces": {"batten.0.0": -0.31, …},
//!   "slack_cables": ["diagonal.1.1.a", …],
//!   "joints": {"joint.1.0.below": {"offset": [0.0, 0.0, 0.0101], "contact": 2.3, "loose": false}, …}
//! }
//! ```
//!
//! `joints` is present for a model with backlash joints: per joint id, the hole centre's
//! offset from the shaft centre (mm), the contact force (N; 0 when loose) and whether the
//! joint is loose (a loose pin carries no force; its offset is then its share of the
//! member's free play, one of the positions the statics leaves open).
//!
//! Displacements are in mm per node id, forces in N per member id (tension positive), both
//! in model order. The angles are absent when the model names no top surface. A failed
//! solve prints `"converged": false` with `"error"`, and exits with code 7 (failed samples).

use crate::{CliError, SolveArgs};
use serde::Serialize;
use serde::ser::{SerializeMap, Serializer};
use std::io::Write;
use truss_core::joint::JointSummary;
use truss_core::solver::IterationRecord;
use truss_core::{Model, SolveOptions, Solver};

/// Pairs serialised as a JSON object in their order.
#[derive(Debug)]
pub struct Ordered<T>(pub Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// Units of the output.
#[derive(Debug, Serialize)]
pub struct Units {
    length: &'static str,
    force: &'static str,
    angle: &'static str,
}

/// Units used everywhere: mm, N, rad.
pub const UNITS: Units = Units {
    length: "mm",
    force: "N",
    angle: "rad",
};

/// The JSON printed by `truss solve`.
#[derive(Debug, Serialize)]
pub struct SolveOutput {
    /// Whether the equilibrium was found.
    pub converged: bool,
    /// Why not, when it was not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Linear solves.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// Tangent factorisations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factorisations: Option<u32>,
    /// Final out-of-balance force \[N\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// θ_P \[rad\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub theta_p: Option<f64>,
    /// tan θ_x.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tan_theta_x: Option<f64>,
    /// tan θ_y.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tan_theta_y: Option<f64>,
    /// Units.
    pub units: Units,
    /// Node displacements \[mm\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub displacements: Option<Ordered<[f64; 3]>>,
    /// Member axial forces, tension positive \[N\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forces: Option<Ordered<f64>>,
    /// Ids of the slack cables.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slack_cables: Option<Vec<String>>,
    /// Backlash joints' states, per joint id.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joints: Option<Ordered<JointSummary>>,
    /// Every Newton iteration, with `--iterations`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iteration_log: Option<Vec<IterationLine>>,
}

/// One iteration, as printed.
#[derive(Debug, Serialize)]
pub struct IterationLine {
    iteration: u32,
    residual: f64,
    step: f64,
    alpha: f64,
    refactorised: bool,
    slack: Vec<String>,
}

impl IterationLine {
    /// An iteration record with member ids.
    pub fn new(model: &Model, r: &IterationRecord) -> Self {
        Self {
            iteration: r.iteration,
            residual: r.residual,
            step: r.step,
            alpha: r.alpha,
            refactorised: r.refactorised,
            slack: r
                .slack
                .iter()
                .map(|&m| model.members()[m].id.clone())
                .collect(),
        }
    }
}

/// Parses `ID=MM` length errors into a per-member vector.
pub fn parse_length_errors(model: &Model, specs: &[String]) -> Result<Vec<f64>, CliError> {
    let mut errors = vec![0.0; model.members().len()];
    for spec in specs {
        let (id, value) = spec
            .split_once('=')
            .ok_or_else(|| CliError::Usage(format!("--length-error {spec:?}: expected ID=MM")))?;
        let m = model
            .member_index(id)
            .ok_or_else(|| CliError::Usage(format!("--length-error {spec:?}: no member {id:?}")))?;
        let v: f64 = value
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| {
                CliError::Usage(format!(
                    "--length-error {spec:?}: {value:?} is not a number"
                ))
            })?;
        errors[m] += v;
    }
    Ok(errors)
}

/// Runs `truss solve`.
pub fn run(args: &SolveArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let model = Model::read(&args.model)?;
    let errors = parse_length_errors(&model, &args.length_errors)?;
    let options = SolveOptions {
        record_iterations: args.iterations,
        ..SolveOptions::default()
    };
    let mut solver = Solver::new(&model, options)?;
    let result = solver.solve(&errors);
    let log = args.iterations.then(|| {
        solver
            .iteration_log()
            .iter()
            .map(|r| IterationLine::new(&model, r))
            .collect()
    });
    let output = match &result {
        Ok(report) => {
            let d = solver.distortion();
            let n = model.nodes().len();
            SolveOutput {
                converged: true,
                error: None,
                iterations: Some(report.iterations),
                factorisations: Some(report.factorisations),
                residual: Some(report.residual),
                theta_p: d.map(|d| d.theta_p),
                tan_theta_x: d.map(|d| d.tan_theta_x),
                tan_theta_y: d.map(|d| d.tan_theta_y),
                units: UNITS,
                displacements: Some(Ordered(
                    (0..n)
                        .map(|i| (model.nodes()[i].id.clone(), solver.displacement(i)))
                        .collect(),
                )),
                forces: Some(Ordered(
                    model
                        .members()
                        .iter()
                        .enumerate()
                        .map(|(m, member)| (member.id.clone(), solver.member_force(m)))
                        .collect(),
                )),
                slack_cables: Some(
                    (0..model.members().len())
                        .filter(|&m| solver.is_slack(m))
                        .map(|m| model.members()[m].id.clone())
                        .collect(),
                ),
                joints: (!model.joints().is_empty()).then(|| Ordered(solver.joint_summaries())),
                iteration_log: log,
            }
        }
        Err(e) => SolveOutput {
            converged: false,
            error: Some(e.to_string()),
            iterations: None,
            factorisations: None,
            residual: None,
            theta_p: None,
            tan_theta_x: None,
            tan_theta_y: None,
            units: UNITS,
            displacements: None,
            forces: None,
            slack_cables: None,
            joints: None,
            iteration_log: log,
        },
    };
    let mut text = serde_json::to_string_pretty(&output).expect("the output always serialises");
    text.push('\n');
    out.write_all(text.as_bytes())?;
    result.map(|_| ()).map_err(CliError::Solve)
}
