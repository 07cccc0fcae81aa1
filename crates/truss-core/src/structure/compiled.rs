//! The compiled, immutable form of a model that solvers share (built by
//! [`Structure::new`]'s stages): node numbering, per-member constants, assembly targets, the
//! factorised all-taut material stiffness `K₀` and the low-rank basis over the cables.

use super::basis::CableBasis;
use super::parts::{CompiledJoint, CompiledMember};
use crate::TopSurface;
use crate::block::BlockBandMatrix;
use crate::element::AxialMember;

/// A model compiled for solving (see the module doc).
#[derive(Debug, Clone)]
pub struct Structure {
    pub(crate) node_ids: Vec<String>,
    pub(crate) node_xyz: Vec<[f64; 3]>,
    /// Row numbers of each node's directions, [`FIXED`](super::parts::FIXED) where held.
    pub(crate) node_dofs: Vec<[u32; 3]>,
    /// Node and direction of each row.
    pub(crate) dof_owner: Vec<(usize, u8)>,
    /// Number of rows (3 per active node); vectors have one more entry, the zero slot.
    pub(crate) free: usize,
    pub(crate) members: Vec<CompiledMember>,
    /// Number of the model's members (the first ones of `members`).
    pub(crate) model_members: usize,
    /// For each node that is a joint's hole, that joint: the node has no unknowns, and its
    /// position is its shaft's plus the joint's offset.
    pub(crate) hole_joint: Vec<Option<usize>>,
    /// The joints, in model order.
    pub(crate) joints: Vec<CompiledJoint>,
    /// Block slots and directions of fixed directions of active nodes (identity rows).
    pub(crate) identity_rows: Vec<(usize, usize)>,
    /// Slots of the band (within it, not its padding) that no member adds to: zeroed at
    /// the start of each assembly (a factorisation fills them in).
    pub(crate) untouched: Vec<usize>,
    /// Each slot's members in assembly order, for assembling a few slots again.
    pub(crate) writers: super::sparsity::SlotWriters,
    /// The one-sided members with the lowest row each reaches, in the order of that row
    /// (then of the member): those a direction zero above a row can move.
    pub(crate) one_sided_by_row: Vec<(usize, usize)>,
    /// External load per row (plus the zero slot) \[N\].
    pub(crate) loads: Vec<f64>,
    /// `K₀`, factorised.
    pub(crate) nominal: BlockBandMatrix,
    /// Woodbury data over the cables, for models with few enough cables.
    pub(crate) basis: Option<CableBasis>,
    pub(crate) top_surface: Option<TopSurface>,
    /// Whether the model's bars frame the top surface's tilt by themselves (see
    /// [`crate::limit`]): then no sample floats.
    pub(crate) tilt_framed: bool,
}

impl Structure {
    /// The member's constants for a sample with length error `error` \[mm\] and, for a
    /// half of a member in clearance holes, total clearance `gap` \[mm\]: the tension-only
    /// half's natural length is `L₀ + G`, the compression-only half's `L₀ − G`, and both
    /// have the series stiffness `1/(L₀/(E·A) + Σ 1/k_t)` (see [`crate::joint`]).
    #[inline]
    pub(crate) fn nominal_member(&self, m: &CompiledMember, error: f64, gap: f64) -> AxialMember {
        // `AxialMember::new` with the nominal length computed once.
        let natural_length = m.natural_length + error;
        let (rigidity, initial_stretch) = match &m.band {
            None => (m.rigidity, m.nominal_stretch - error),
            Some(b) => (
                b.member_rigidity * natural_length
                    / (natural_length + b.compliance * b.member_rigidity),
                m.nominal_stretch - error - m.sense * gap,
            ),
        };
        AxialMember {
            reference: m.reference,
            reference_length: m.reference_length,
            natural_length,
            initial_stretch,
            rigidity,
            compression_ratio: m.compression_ratio,
            sense: m.sense,
        }
    }

    /// The total clearance of member `m`'s joints \[mm\], each joint's from `clearance`
    /// (per joint, model order) or, where that is empty, its nominal one.
    #[inline]
    pub(crate) fn band_clearance(&self, m: &CompiledMember, clearance: &[f64]) -> f64 {
        m.band.as_ref().map_or(0.0, |b| {
            b.joints
                .iter()
                .flatten()
                .map(|&j| {
                    clearance
                        .get(j)
                        .copied()
                        .unwrap_or(self.joints[j].clearance)
                })
                .sum()
        })
    }

    /// Whether the model's bars frame the top surface's tilt by themselves (see
    /// [`crate::limit`]): its samples never float, and a cable of ratio 0 works at
    /// [`crate::limit::FRAMED_RATIO`].
    pub fn tilt_framed(&self) -> bool {
        self.tilt_framed
    }

    /// Whether some cable of ratio 0 is solved at its limit `r → 0` itself (the bars do not
    /// frame the tilt), by continuation from [`crate::limit::LIMIT_RATIO`] (see
    /// [`crate::limit`]).
    pub fn near_the_limit(&self) -> bool {
        !self.tilt_framed && self.members.iter().any(|c| c.limit)
    }

    /// Number of rows of the stiffness matrix (3 per node with a free direction).
    pub fn free_dofs(&self) -> usize {
        self.free
    }

    /// Block (node) half-bandwidth of the stiffness matrix in the chosen numbering.
    pub fn bandwidth(&self) -> usize {
        self.nominal.bandwidth()
    }

    /// Nominal length of the shortest member \[mm\].
    pub(crate) fn shortest_member(&self) -> f64 {
        self.members
            .iter()
            .map(|m| m.reference_length)
            .fold(f64::INFINITY, f64::min)
    }

    /// Number of the model's members.
    pub fn member_count(&self) -> usize {
        self.model_members
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.node_ids.len()
    }

    /// Node id and direction (`x`, `y`, `z`) of row `dof`, for messages.
    pub(crate) fn describe_dof(&self, dof: usize) -> (String, char) {
        let (node, dir) = self.dof_owner[dof];
        (self.node_ids[node].clone(), ['x', 'y', 'z'][dir as usize])
    }
}
