//! The paper's N-stage triangular prism truss (section 2.1, Fig. 1, Table 1).
//!
//! Level `k = 0..=N` lies at `z = k·h`; its vertices `j = 0, 1, 2` are at `(0, 0)`, `(l, 0)`,
//! `(l/2, √3·l/2)` (the paper's Fig. 5 numbering 1, 2, 3 of the top nodes). Stage `s = 1..=N`
//! joins level `s − 1` to level `s`.
//!
//! | ids | joins | group | default |
//! |---|---|---|---|
//! | `n{k}.{j}` | node | | |
//! | `batten.{k}.{j}` | `n{k}.{j}`–`n{k}.{(j+1)%3}` | `batten` | A = 14.9 mm², E = 70 000 MPa, bar |
//! | `longeron.{s}.{j}` | `n{s-1}.{j}`–`n{s}.{j}` | `longeron` | A = 14.9 mm², E = 70 000 MPa, bar |
//! | `diagonal.{s}.{j}.a` | `n{s-1}.{j}`–`n{s}.{(j+1)%3}` | `diagonal` | A = 3.1 mm², E = 70 000 MPa, cable, L₀ = 537.4 mm |
//! | `diagonal.{s}.{j}.b` | `n{s-1}.{(j+1)%3}`–`n{s}.{j}` | `diagonal` | as above |
//!
//! Members are listed level 0's battens first, then stage by stage: its three longerons, its
//! six diagonals (face by face, `a` before `b`), and the battens of its top level. This order
//! is the order in which a Monte Carlo sample draws length errors. Level 0 is fully fixed.
//! The top surface is `n{N}.0`, `n{N}.1`, `n{N}.2` against the normal (0, 0, 1).
//!
//! With [`PrismOptions::backlash`] every longeron end is a pin joint with backlash (section 4
//! of the paper; see [`crate::joint`]). The node `n{k}.{j}` above becomes the *shaft* node,
//! the batten-end fitting's shaft, where the battens and the diagonals attach. Each
//! longeron end has its own hole on that shaft: in a deployable mast each stage's longerons
//! are separate members, so the longeron below a node and the longeron above it sit in two
//! holes with independent clearances, and the longeron is not continuous through the node.
//! So `longeron.{s}.{j}` joins the hole node `n{s-1}.{j}.above` (its bottom end) to the hole
//! node `n{s}.{j}.below` (its top end), and the joints `joint.{k}.{j}.above` and
//! `joint.{k}.{j}.below` join each hole node to the shaft `n{k}.{j}`: two joints at each
//! vertex of the levels between stages, one at the bottom and top levels, `6·N` in all (30
//! for the paper's 5 stages). The diagonals attach on the
//! batten side because the batten-end fitting, which carries the shaft, is where a
//! deployable truss anchors its diagonals; it is also what the paper's Fig. 13 shows: the
//! shortened diagonals pull the battens towards each other, and each shaft comes to rest
//! against the edge of its hole along the longeron, shortening the truss by the clearances.
//! The shaft's axis is horizontal and radial (from the prism's axis through the vertex), the
//! bisector of the normals of the two side faces that meet there, so that the clearance
//! acts in each face's plane as in the paper's two-dimensional panel (Fig. 12). The bottom
//! shaft nodes are fixed; the top surface is the top shaft nodes (the battens' plane). Hole
//! nodes are listed after all shaft nodes, and hole nodes and joints level by level, vertex
//! by vertex, `below` before `above`; members keep the order above, so a sample's length
//! errors are drawn alike with and without backlash.
//!
//! Table 1's diagonal natural length, 537.4 mm, is 1.15 µm shorter than the face diagonal
//! 380·√2 = 537.401 15 mm, so the diagonals start slightly in tension (0.46 N) and the frame
//! slightly in compression; [`PrismOptions::diagonal_length`] `None` gives the exact length.

use crate::joint::{DEFAULT_JOINT_COMPRESSION_RATIO, DEFAULT_JOINT_TENSION_FACTOR};
use crate::model::{
    MAX_AREA, MAX_CLEARANCE_FRACTION, MAX_COORDINATE, MAX_JOINT_COMPRESSION_RATIO, MAX_MODULUS,
};
use crate::model_file::JointSpec;
use crate::model_file::{
    BehaviourSpec, MemberSpec, ModelFile, NodeSpec, SupportSpec, TopSurfaceSpec,
};
use crate::{DEFAULT_COMPRESSION_RATIO, Model, ModelError};

/// The diagonal natural length of the paper's Table 1 \[mm\].
pub const TABLE1_DIAGONAL_LENGTH: f64 = 537.4;

/// Options of the prism generator; the defaults are the paper's Table 1. A job file writes
/// them as JSON (see [`crate::prism_spec`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PrismOptions {
    /// Number of stages N ≥ 1.
    pub stages: usize,
    /// Batten length l, the side of the triangle \[mm\].
    pub side: f64,
    /// Stage height h, the longeron length \[mm\].
    pub height: f64,
    /// Batten cross-section \[mm²\].
    pub batten_area: f64,
    /// Batten Young's modulus \[MPa\].
    pub batten_modulus: f64,
    /// Longeron cross-section \[mm²\].
    pub longeron_area: f64,
    /// Longeron Young's modulus \[MPa\].
    pub longeron_modulus: f64,
    /// Diagonal cross-section \[mm²\].
    pub diagonal_area: f64,
    /// Diagonal Young's modulus \[MPa\].
    pub diagonal_modulus: f64,
    /// Diagonal natural length \[mm\]; `None` for the exact face diagonal √(l² + h²).
    pub diagonal_length: Option<f64>,
    /// Diagonals' compression stiffness ratio (they are tension-only cables); 0, the
    /// default, is the paper's: they carry nothing when slack (see [`crate::limit`]).
    pub compression_ratio: f64,
    /// Pin joints with backlash at every node (see the module doc); `None` for rigid nodes.
    pub backlash: Option<BacklashOptions>,
}

/// The joints of a prism with backlash (in a job: any field may be left out for its
/// default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BacklashOptions {
    /// Nominal clearance of every joint \[mm\] (a job may draw one per joint and sample).
    pub clearance: f64,
    /// Contact stiffness over the longeron's axial stiffness `E·A/h`.
    pub tension_factor: f64,
    /// Regularisation of a loose joint over its contact stiffness (0, the default: none).
    pub compression_ratio: f64,
}

/// The largest stage count accepted, 1000.
///
/// Memory and time grow linearly with the stages (a block-banded stiffness; 12 members and 9
/// degrees of freedom per stage, 27 with backlash joints): the largest prism is a model of
/// 12,003 members, 3.4 MB as `truss model prism` writes it (6.1 MB with backlash joints),
/// which takes some tens of MB to build and solve. Real deployable masts have tens of stages
/// (the paper's truss 5; the 60 m mast of the Shuttle Radar Topography Mission 87), so 1000
/// leaves room for any mast, and for convergence studies, while refusing at once, by name,
/// a count such as 2⁶⁴ − 1 that would exhaust the memory (and whose model file could not
/// be read back: it would pass [`crate::model_file::MAX_INPUT_BYTES`] beyond some 19,000
/// stages).
pub const MAX_STAGES: usize = 1000;

/// The paper's size of the backlash at a node, "about 0.01 mm" (section 4.1) \[mm\].
pub const PAPER_CLEARANCE: f64 = 0.01;

impl Default for BacklashOptions {
    fn default() -> Self {
        Self {
            clearance: PAPER_CLEARANCE,
            tension_factor: DEFAULT_JOINT_TENSION_FACTOR,
            compression_ratio: DEFAULT_JOINT_COMPRESSION_RATIO,
        }
    }
}

impl Default for PrismOptions {
    fn default() -> Self {
        Self {
            stages: 5,
            side: 380.0,
            height: 380.0,
            batten_area: 14.9,
            batten_modulus: 70_000.0,
            longeron_area: 14.9,
            longeron_modulus: 70_000.0,
            diagonal_area: 3.1,
            diagonal_modulus: 70_000.0,
            diagonal_length: Some(TABLE1_DIAGONAL_LENGTH),
            compression_ratio: DEFAULT_COMPRESSION_RATIO,
            backlash: None,
        }
    }
}

impl PrismOptions {
    /// The paper's truss with `stages` stages and Table 1's other values.
    pub fn with_stages(stages: usize) -> Self {
        Self {
            stages,
            ..Self::default()
        }
    }

    /// Checks every option before any is used; the error is the field's name as a job
    /// writes it (`stages`, `backlash.clearance`, …) and what is wrong. Limits: `1 ≤ stages ≤`
    /// [`MAX_STAGES`]; lengths in (0, [`MAX_COORDINATE`]] mm; areas in (0, [`MAX_AREA`]] mm²;
    /// moduli in (0, [`MAX_MODULUS`]] MPa; cable compression ratio in [0, 1); the diagonal's
    /// natural length in (0, [`MAX_COORDINATE`]] mm and within
    /// [`MAX_LENGTH_ERROR_FRACTION`](crate::MAX_LENGTH_ERROR_FRACTION) of itself (plus the
    /// joints' summed clearance) of the face diagonal, an initial strain within the elastic
    /// range ([`crate::model::initial_strain_fault`]); a clearance in
    /// [0, [`MAX_CLEARANCE_FRACTION`] × the shorter of side and height]; joint tension
    /// factor in (0, 10⁹]; joint compression ratio in [0, [`MAX_JOINT_COMPRESSION_RATIO`]].
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if !(1..=MAX_STAGES).contains(&self.stages) {
            return Err((
                "stages",
                format!(
                    "must be from 1 to {MAX_STAGES} (the limit keeps a model within memory), got {}",
                    self.stages
                ),
            ));
        }
        let within = |field: &'static str, v: f64, max: f64, unit: &str| {
            if v.is_finite() && v > 0.0 && v <= max {
                Ok(())
            } else {
                Err((
                    field,
                    format!(
                        "must be positive and at most {max:e} {unit}, got {}",
                        crate::readable(v)
                    ),
                ))
            }
        };
        within("side", self.side, MAX_COORDINATE, "mm")?;
        within("height", self.height, MAX_COORDINATE, "mm")?;
        within("batten_area", self.batten_area, MAX_AREA, "mm²")?;
        within("longeron_area", self.longeron_area, MAX_AREA, "mm²")?;
        within("diagonal_area", self.diagonal_area, MAX_AREA, "mm²")?;
        within("batten_modulus", self.batten_modulus, MAX_MODULUS, "MPa")?;
        within(
            "longeron_modulus",
            self.longeron_modulus,
            MAX_MODULUS,
            "MPa",
        )?;
        within(
            "diagonal_modulus",
            self.diagonal_modulus,
            MAX_MODULUS,
            "MPa",
        )?;
        if !(0.0..1.0).contains(&self.compression_ratio) {
            return Err((
                "compression_ratio",
                format!("must be in [0, 1), got {}", self.compression_ratio),
            ));
        }
        // The clearance first: the diagonals' check below reads it.
        if let Some(b) = &self.backlash {
            let max = MAX_CLEARANCE_FRACTION * self.side.min(self.height);
            if !(b.clearance.is_finite() && (0.0..=max).contains(&b.clearance)) {
                return Err((
                    "backlash.clearance",
                    format!(
                        "must be from 0 to {max} mm ({}% of the shorter of side and height), got {}",
                        100.0 * MAX_CLEARANCE_FRACTION,
                        crate::readable(b.clearance)
                    ),
                ));
            }
            within("backlash.tension_factor", b.tension_factor, 1e9, "")?;
            if !(0.0..=MAX_JOINT_COMPRESSION_RATIO).contains(&b.compression_ratio) {
                return Err((
                    "backlash.compression_ratio",
                    format!(
                        "must be in [0, {MAX_JOINT_COMPRESSION_RATIO:e}], got {}",
                        b.compression_ratio
                    ),
                ));
            }
        }
        if let Some(d) = self.diagonal_length {
            within("diagonal_length", d, MAX_COORDINATE, "mm")?;
            let face = self.side.hypot(self.height);
            // Each stage has six joints (a hole at each end of its three longerons).
            let play = self
                .backlash
                .as_ref()
                .map_or(0.0, |b| 6.0 * self.stages as f64 * b.clearance);
            let what = "the face diagonal √(side² + height²)";
            if let Some(fault) = crate::model::initial_strain_fault(d, face, play, what) {
                return Err(("diagonal_length", fault));
            }
        }
        Ok(())
    }

    /// The model file of the prism (after [`PrismOptions::check`], whose field it names as
    /// `prism.FIELD`).
    pub fn file(&self) -> Result<ModelFile, ModelError> {
        self.check()
            .map_err(|(field, message)| ModelError::Invalid {
                item: format!("prism.{field}"),
                message,
            })?;
        let (l, h) = (self.side, self.height);
        let vertex = |j: usize, k: usize| match j {
            0 => [0.0, 0.0, k as f64 * h],
            1 => [l, 0.0, k as f64 * h],
            _ => [l / 2.0, 3f64.sqrt() / 2.0 * l, k as f64 * h],
        };
        let node = |k: usize, j: usize| format!("n{k}.{j}");
        let mut nodes = Vec::new();
        for k in 0..=self.stages {
            for j in 0..3 {
                nodes.push(NodeSpec {
                    id: node(k, j),
                    xyz: vertex(j, k),
                });
            }
        }
        // With backlash, the longerons' ends are the hole nodes, one per end: `side` is
        // "below" for the top end of the longeron below level k, "above" for the bottom end of
        // the longeron above it.
        let hole = |k: usize, j: usize, side: &str| match self.backlash {
            Some(_) => format!("n{k}.{j}.{side}"),
            None => node(k, j),
        };
        let sides = |k: usize| {
            [("below", k > 0), ("above", k < self.stages)]
                .into_iter()
                .filter_map(|(side, present)| present.then_some(side))
        };
        if self.backlash.is_some() {
            for k in 0..=self.stages {
                for j in 0..3 {
                    for side in sides(k) {
                        nodes.push(NodeSpec {
                            id: hole(k, j, side),
                            xyz: vertex(j, k),
                        });
                    }
                }
            }
        }
        let position = |id: &str| nodes.iter().find(|n| n.id == id).map(|n| n.xyz);
        let mut members = Vec::new();
        let mut push = |id: String, a: String, b: String, group: &str| {
            let (pa, pb) = (position(&a).unwrap(), position(&b).unwrap());
            let length = crate::model::distance(pa, pb);
            let (area, modulus, natural, behaviour, ratio) = match group {
                "batten" => (
                    self.batten_area,
                    self.batten_modulus,
                    length,
                    BehaviourSpec::Bar,
                    None,
                ),
                "longeron" => (
                    self.longeron_area,
                    self.longeron_modulus,
                    length,
                    BehaviourSpec::Bar,
                    None,
                ),
                _ => (
                    self.diagonal_area,
                    self.diagonal_modulus,
                    self.diagonal_length.unwrap_or(length),
                    BehaviourSpec::Cable,
                    Some(self.compression_ratio),
                ),
            };
            members.push(MemberSpec {
                id,
                nodes: [a, b],
                group: group.to_string(),
                area,
                youngs_modulus: modulus,
                natural_length: Some(natural),
                behaviour,
                compression_ratio: ratio,
            });
        };
        let battens = |k: usize, push: &mut dyn FnMut(String, String, String, &str)| {
            for j in 0..3 {
                push(
                    format!("batten.{k}.{j}"),
                    node(k, j),
                    node(k, (j + 1) % 3),
                    "batten",
                );
            }
        };
        battens(0, &mut push);
        for s in 1..=self.stages {
            for j in 0..3 {
                push(
                    format!("longeron.{s}.{j}"),
                    hole(s - 1, j, "above"),
                    hole(s, j, "below"),
                    "longeron",
                );
            }
            for j in 0..3 {
                let jn = (j + 1) % 3;
                push(
                    format!("diagonal.{s}.{j}.a"),
                    node(s - 1, j),
                    node(s, jn),
                    "diagonal",
                );
                push(
                    format!("diagonal.{s}.{j}.b"),
                    node(s - 1, jn),
                    node(s, j),
                    "diagonal",
                );
            }
            battens(s, &mut push);
        }
        let supports = (0..3)
            .map(|j| SupportSpec {
                node: node(0, j),
                fixed: "xyz".into(),
            })
            .collect();
        let top_surface = Some(TopSurfaceSpec {
            nodes: [0, 1, 2].map(|j| node(self.stages, j)),
            reference_normal: [0.0, 0.0, 1.0],
        });
        let mut joints = Vec::new();
        if let Some(b) = &self.backlash {
            let tension = b.tension_factor * self.longeron_modulus * self.longeron_area / h;
            // Horizontal unit vectors from the prism's axis through each vertex.
            let half = 3f64.sqrt() / 2.0;
            let radial = [[-half, -0.5, 0.0], [half, -0.5, 0.0], [0.0, 1.0, 0.0]];
            for k in 0..=self.stages {
                for (j, axis) in radial.iter().enumerate() {
                    for side in sides(k) {
                        joints.push(JointSpec {
                            id: format!("joint.{k}.{j}.{side}"),
                            shaft: node(k, j),
                            hole: hole(k, j, side),
                            axis: Some(*axis),
                            clearance: b.clearance,
                            tension_stiffness: Some(tension),
                            compression_ratio: Some(b.compression_ratio),
                            axial_stiffness: Some(tension),
                        });
                    }
                }
            }
        }
        Ok(ModelFile {
            nodes,
            members,
            supports,
            loads: Vec::new(),
            top_surface,
            joints,
        })
    }

    /// The validated model of the prism.
    pub fn model(&self) -> Result<Model, ModelError> {
        Model::new(self.file()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stage counts outside 1..=MAX_STAGES and implausible values are refused by field,
    /// before any node is made (2⁶⁴ − 1 stages used to fill the memory).
    #[test]
    fn options_are_checked_by_field_before_building() {
        for stages in [0, MAX_STAGES + 1, usize::MAX] {
            let e = PrismOptions::with_stages(stages).check().unwrap_err();
            assert_eq!(e.0, "stages", "{stages}");
            let m = PrismOptions::with_stages(stages).file().unwrap_err();
            assert!(m.to_string().starts_with("prism.stages: "), "{m}");
        }
        assert!(PrismOptions::with_stages(MAX_STAGES).check().is_ok());
        let field = |o: PrismOptions| o.check().unwrap_err().0;
        let t = PrismOptions::default;
        assert_eq!(field(PrismOptions { side: 1e308, ..t() }), "side");
        assert_eq!(
            field(PrismOptions {
                height: -1.0,
                ..t()
            }),
            "height"
        );
        let nan = PrismOptions {
            batten_modulus: f64::NAN,
            ..t()
        };
        assert_eq!(field(nan), "batten_modulus");
        let loose = PrismOptions {
            backlash: Some(BacklashOptions {
                clearance: 1e308,
                ..BacklashOptions::default()
            }),
            ..t()
        };
        assert_eq!(field(loose), "backlash.clearance");
        // A negative or NaN clearance is named as itself, not as the diagonals' length
        // that the clearance's play enters.
        for bad in [-0.01, f64::NAN] {
            let o = PrismOptions {
                diagonal_length: Some(428.1),
                backlash: Some(BacklashOptions {
                    clearance: bad,
                    ..BacklashOptions::default()
                }),
                ..t()
            };
            assert_eq!(field(o), "backlash.clearance", "{bad}");
        }
        let exaggerated = PrismOptions {
            backlash: Some(BacklashOptions {
                clearance: 30.0,
                ..BacklashOptions::default()
            }),
            ..t()
        };
        assert!(exaggerated.check().is_ok(), "the paper's Fig. 15 clearance");
    }
}
