//! `truss solve`: one equilibrium, printed as JSON.
//!
//! ## Output
//!
//! ```json
//! {
//!   "converged": true, "iterations": 5, "factorisations": 2, "residual": 2.1e-13,
//!   "theta_p": 2.94e-5, "tan_theta_x": -2.55e-5, "tan_theta_y": -1.47e-5,
//!   "decenter_x": 0.0402, "decenter_y": 0.0232, "decenter": 0.0464, "despace": 0.0033,
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
//! in model order. `decenter_x`, `decenter_y`, `decenter` and `despace` (mm) say where the top
//! surface's centroid sits against the bottom's frame (see `truss_core::measure`). The angles
//! and these four are absent when the model names no top surface. A failed
//! solve prints `"converged": false` with `"error"`, and exits with code 7 (failed samples).

use crate::CliError;
use clap::Args;
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;
use truss_core::output::{EquilibriumById, IterationLine, UNITS, Units};
use truss_core::{Model, Placement, SolveOptions, Solver};

/// Options of `truss solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// The model file.
    pub model: PathBuf,
    /// A member's length error, `ID=MM` (natural length = the model's + MM); repeatable.
    #[arg(long = "length-error", value_name = "ID=MM")]
    pub length_errors: Vec<String>,
    /// Record and print every Newton iteration.
    #[arg(long)]
    pub iterations: bool,
}

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
    /// The top surface's decenter and despace \[mm\] (`decenter_x`, `decenter_y`,
    /// `decenter`, `despace`; see `truss_core::measure`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub placement: Option<Placement>,
    /// Units.
    pub units: Units,
    /// The equilibrium by id: displacements, forces, slack cables, joints.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<EquilibriumById>,
    /// Every Newton iteration, with `--iterations`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iteration_log: Option<Vec<IterationLine>>,
}

/// Parses `ID=MM` length errors into a per-member vector, refusing a member given twice
/// and an error beyond [`Model::max_length_error`] (a fraction
/// [`MAX_LENGTH_ERROR_FRACTION`](truss_core::MAX_LENGTH_ERROR_FRACTION) of the member's
/// natural length, beyond which the elastic model means nothing: see there).
pub fn parse_length_errors(model: &Model, specs: &[String]) -> Result<Vec<f64>, CliError> {
    let mut errors = vec![0.0; model.members().len()];
    let mut given: Vec<Option<&str>> = vec![None; errors.len()];
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
        if let Some(first) = given[m] {
            return Err(CliError::Usage(format!(
                "--length-error {spec:?}: member {id:?} already has a length error \
                 (--length-error {first:?}); give each member once"
            )));
        }
        model
            .check_length_error(m, v)
            .map_err(|e| CliError::Usage(format!("--length-error {spec:?}: {e}")))?;
        given[m] = Some(spec.as_str());
        errors[m] = v;
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
    let log = args.iterations.then(|| IterationLine::log(&model, &solver));
    let output = match &result {
        Ok(report) => {
            let d = solver.distortion();
            SolveOutput {
                converged: true,
                error: None,
                iterations: Some(report.iterations),
                factorisations: Some(report.factorisations),
                residual: Some(report.residual),
                theta_p: d.map(|d| d.theta_p),
                tan_theta_x: d.map(|d| d.tan_theta_x),
                tan_theta_y: d.map(|d| d.tan_theta_y),
                placement: truss_core::output::placement(&model, &solver),
                units: UNITS,
                equilibrium: Some(EquilibriumById::of(&model, &solver)),
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
            placement: None,
            units: UNITS,
            equilibrium: None,
            iteration_log: log,
        },
    };
    let mut text = serde_json::to_string_pretty(&output).expect("the output always serialises");
    text.push('\n');
    out.write_all(text.as_bytes())?;
    result.map(|_| ()).map_err(CliError::Solve)
}
