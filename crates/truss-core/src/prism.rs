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
//! Table 1's diagonal natural length, 537.4 mm, is 1.15 µm shorter than the face diagonal
//! 380·√2 = 537.401 15 mm, so the diagonals start slightly in tension (0.46 N) and the frame
//! slightly in compression; [`PrismOptions::diagonal_length`] `None` gives the exact length.

use crate::model_file::{
    BehaviourSpec, MemberSpec, ModelFile, NodeSpec, SupportSpec, TopSurfaceSpec,
};
use crate::{DEFAULT_COMPRESSION_RATIO, Model, ModelError};

/// The diagonal natural length of the paper's Table 1 \[mm\].
pub const TABLE1_DIAGONAL_LENGTH: f64 = 537.4;

/// Options of the prism generator; the defaults are the paper's Table 1.
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
    /// Diagonals' compression stiffness ratio (they are tension-only cables).
    pub compression_ratio: f64,
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

    /// The model file of the prism.
    pub fn file(&self) -> Result<ModelFile, ModelError> {
        if self.stages == 0 {
            return Err(ModelError::Invalid {
                item: "prism".into(),
                message: "stages must be at least 1".into(),
            });
        }
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
                    node(s - 1, j),
                    node(s, j),
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
        Ok(ModelFile {
            nodes,
            members,
            supports,
            loads: Vec::new(),
            top_surface,
        })
    }

    /// The validated model of the prism.
    pub fn model(&self) -> Result<Model, ModelError> {
        Model::new(self.file()?)
    }
}
