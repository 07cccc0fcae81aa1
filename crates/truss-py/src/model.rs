//! `truss_mc._native.Model`: a validated truss model (the paper's prism with any Table 1
//! value overridden, or a model file) and one equilibrium of it, solved by the solver
//! `truss solve` uses and reported with the same types (`truss_core::output`).

use crate::columns::f64_bytes;
use crate::errors::{Failure, Kind};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;
use truss_core::output::EquilibriumById;
use truss_core::{Model, SolveOptions, Solver};

/// A validated model (units mm, N, MPa).
#[pyclass(frozen, name = "Model", module = "truss_mc._native")]
pub struct PyModel {
    /// The model.
    pub model: Arc<Model>,
}

#[pymethods]
impl PyModel {
    /// Reads and validates a model file (JSON, as `truss model` writes it).
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let model = py.detach(|| Model::read(&path)).map_err(Failure::from)?;
        Ok(Self {
            model: Arc::new(model),
        })
    }

    /// Parses and validates a model file's text; `origin` names it in messages.
    #[staticmethod]
    #[pyo3(signature = (text, origin = "<string>"))]
    fn from_json(text: &str, origin: &str) -> PyResult<Self> {
        let model = Model::from_json(text, origin).map_err(Failure::from)?;
        Ok(Self {
            model: Arc::new(model),
        })
    }

    /// The paper's prism from its options as a job writes them (JSON text of
    /// `{"stages": 5, …}`); faults are named by their path under `prism`.
    #[staticmethod]
    fn prism(py: Python<'_>, options: &str) -> PyResult<Self> {
        let value: serde_json::Value = serde_json::from_str(options)
            .map_err(|e| Failure::new(Kind::InvalidInput, format!("prism: {e}")))?;
        let options = truss_job::job::parse_prism(&value, "prism").map_err(Failure::from)?;
        let model = py.detach(|| options.model()).map_err(Failure::from)?;
        Ok(Self {
            model: Arc::new(model),
        })
    }

    /// Node ids, model order.
    #[getter]
    fn node_ids(&self) -> Vec<String> {
        self.model.nodes().iter().map(|n| n.id.clone()).collect()
    }

    /// Member ids, model order.
    #[getter]
    fn member_ids(&self) -> Vec<String> {
        self.model.members().iter().map(|m| m.id.clone()).collect()
    }

    /// Each member's group, model order.
    #[getter]
    fn member_groups(&self) -> Vec<String> {
        self.model
            .members()
            .iter()
            .map(|m| m.group.clone())
            .collect()
    }

    /// Joint ids, model order (empty without backlash joints).
    #[getter]
    fn joint_ids(&self) -> Vec<String> {
        self.model.joints().iter().map(|j| j.id.clone()).collect()
    }

    /// The model file's text, every default written out.
    fn to_json(&self) -> String {
        self.model.to_file().to_json()
    }

    /// Solves the equilibrium with the given member length errors (`[(member id, mm)]`,
    /// natural minus nominal length); raises `SolveFailedError` when it does not converge.
    /// Returns the numbers of `truss solve`: `theta_p` \[rad\], `tan_theta_x`,
    /// `tan_theta_y`, `decenter_x`, `decenter_y`, `decenter`, `despace` \[mm\] (see
    /// `truss_core::measure`; all None without a top surface), `iterations`, `factorisations`,
    /// `residual` \[N\], `node_ids` with `displacements` (f64 bytes, 3 per node, mm),
    /// `member_ids` with `forces` (f64 bytes, N, tension positive), `slack_cables`, and
    /// `joint_ids` with `joint_offsets` (3 per joint, mm), `joint_contact` (N) and
    /// `joint_loose`.
    #[pyo3(signature = (length_errors = Vec::new()))]
    fn solve<'py>(
        &self,
        py: Python<'py>,
        length_errors: Vec<(String, f64)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = &self.model;
        let mut errors = vec![0.0; model.members().len()];
        for (id, value) in &length_errors {
            let at = |e: String| Failure::new(Kind::Usage, format!("length_errors[{id:?}]: {e}"));
            let m = model
                .member_index(id)
                .ok_or_else(|| at(format!("no member {id:?}")))?;
            model.check_length_error(m, *value).map_err(at)?;
            errors[m] = *value;
        }
        let model = Arc::clone(&self.model);
        let (report, solver) = py
            .detach(move || {
                let mut solver = Solver::new(&model, SolveOptions::default())?;
                let report = solver.solve(&errors).map_err(|e| {
                    Failure::new(Kind::SolveFailed, format!("the solve failed: {e}"))
                })?;
                Ok::<_, Failure>((report, solver))
            })
            .map_err(PyErr::from)?;
        let model = &self.model;
        let eq = EquilibriumById::of(model, &solver);
        let d = solver.distortion();
        let out = PyDict::new(py);
        out.set_item("theta_p", d.map(|d| d.theta_p))?;
        out.set_item("tan_theta_x", d.map(|d| d.tan_theta_x))?;
        out.set_item("tan_theta_y", d.map(|d| d.tan_theta_y))?;
        let p = truss_core::output::placement(model, &solver);
        out.set_item("decenter_x", p.map(|p| p.decenter_x))?;
        out.set_item("decenter_y", p.map(|p| p.decenter_y))?;
        out.set_item("decenter", p.map(|p| p.decenter))?;
        out.set_item("despace", p.map(|p| p.despace))?;
        out.set_item("iterations", report.iterations)?;
        out.set_item("factorisations", report.factorisations)?;
        out.set_item("residual", report.residual)?;
        let ids = |pairs: Vec<String>| PyList::new(py, pairs);
        out.set_item(
            "node_ids",
            ids(eq.displacements.0.iter().map(|(k, _)| k.clone()).collect())?,
        )?;
        let flat: Vec<f64> = eq.displacements.0.iter().flat_map(|(_, u)| *u).collect();
        out.set_item("displacements", f64_bytes(py, &flat))?;
        out.set_item(
            "member_ids",
            ids(eq.forces.0.iter().map(|(k, _)| k.clone()).collect())?,
        )?;
        let forces: Vec<f64> = eq.forces.0.iter().map(|(_, f)| *f).collect();
        out.set_item("forces", f64_bytes(py, &forces))?;
        out.set_item("slack_cables", ids(eq.slack_cables)?)?;
        let joints = eq.joints.map(|j| j.0).unwrap_or_default();
        out.set_item(
            "joint_ids",
            ids(joints.iter().map(|(k, _)| k.clone()).collect())?,
        )?;
        let offsets: Vec<f64> = joints.iter().flat_map(|(_, j)| j.offset).collect();
        out.set_item("joint_offsets", f64_bytes(py, &offsets))?;
        let contact: Vec<f64> = joints.iter().map(|(_, j)| j.contact).collect();
        out.set_item("joint_contact", f64_bytes(py, &contact))?;
        let loose: Vec<bool> = joints.iter().map(|(_, j)| j.loose).collect();
        out.set_item("joint_loose", loose)?;
        Ok(out)
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({} nodes, {} members, {} joints)",
            self.model.nodes().len(),
            self.model.members().len(),
            self.model.joints().len()
        )
    }
}
