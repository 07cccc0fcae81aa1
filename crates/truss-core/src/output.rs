//! An equilibrium as the tools print it, by id: every node's displacement \[mm\], every
//! member's axial force \[N, tension positive\], the slack cables, each backlash joint's state,
//! and the Newton iterations; and where the top surface sits against the bottom
//! ([`placement`]: decenter and despace). `truss solve` and `mc-shard reproduce --detail`
//! both print these types, so they cannot drift apart.

use crate::joint::JointSummary;
use crate::measure::Placement;
use crate::solver::IterationRecord;
use crate::{Model, Solver};
use serde::Serialize;
use serde::ser::{SerializeMap, Serializer};

/// Pairs serialised as a JSON object in their order (model order, not sorted).
#[derive(Debug, Clone, PartialEq)]
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

/// The units of every printed number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Units {
    /// Lengths and displacements.
    pub length: &'static str,
    /// Forces.
    pub force: &'static str,
    /// Angles.
    pub angle: &'static str,
}

/// mm, N, rad.
pub const UNITS: Units = Units {
    length: "mm",
    force: "N",
    angle: "rad",
};

/// A converged equilibrium by id (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EquilibriumById {
    /// Node displacements \[mm\], model order.
    pub displacements: Ordered<[f64; 3]>,
    /// Member axial forces, tension positive \[N\], model order.
    pub forces: Ordered<f64>,
    /// Ids of the slack cables.
    pub slack_cables: Vec<String>,
    /// Backlash joints' states, per joint id; absent without joints.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joints: Option<Ordered<JointSummary>>,
}

impl EquilibriumById {
    /// The last equilibrium of `solver`, a solver of `model`.
    pub fn of(model: &Model, solver: &Solver) -> Self {
        let member = |m: usize| model.members()[m].id.clone();
        Self {
            displacements: Ordered(
                (0..model.nodes().len())
                    .map(|i| (model.nodes()[i].id.clone(), solver.displacement(i)))
                    .collect(),
            ),
            forces: Ordered(
                (0..model.members().len())
                    .map(|m| (member(m), solver.member_force(m)))
                    .collect(),
            ),
            slack_cables: (0..model.members().len())
                .filter(|&m| solver.is_slack(m))
                .map(member)
                .collect(),
            joints: (!model.joints().is_empty()).then(|| Ordered(solver.joint_summaries())),
        }
    }
}

/// The top surface's decenter and despace against the bottom's frame at the last
/// equilibrium of `solver`, a solver of `model`: the bottom is the model's supported nodes
/// (every node with a fixed direction), the frame's normal the top surface's reference
/// normal (see [`crate::measure`]); `None` where the model names no top surface.
pub fn placement(model: &Model, solver: &Solver) -> Option<Placement> {
    let top = model.top_surface()?;
    let bottom: Vec<[f64; 3]> = (0..model.nodes().len())
        .filter(|&i| model.fixed(i).contains(&true))
        .map(|i| solver.displacement(i))
        .collect();
    Some(crate::measure::placement(
        top.nodes.map(|i| solver.displacement(i)),
        &bottom,
        top.reference_normal,
    ))
}

/// One Newton iteration, with member ids.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IterationLine {
    /// Iteration number, from 1.
    pub iteration: u32,
    /// Out-of-balance force before the step, max over free DOFs \[N\].
    pub residual: f64,
    /// Size of the step taken \[mm\].
    pub step: f64,
    /// Line-search step length α.
    pub alpha: f64,
    /// Whether the tangent was factorised afresh.
    pub refactorised: bool,
    /// Ids of the cables slack before the step.
    pub slack: Vec<String>,
}

impl IterationLine {
    /// Every recorded iteration of `solver`'s last solve (empty unless recorded).
    pub fn log(model: &Model, solver: &Solver) -> Vec<Self> {
        solver
            .iteration_log()
            .iter()
            .map(|r| Self::new(model, r))
            .collect()
    }

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
