//! The compiled pieces of a [`Structure`](super::Structure): members (a member in clearance
//! holes as two one-sided halves), their dead bands, where each puts its stiffness, and the
//! joints; with the two sparse products with a member's direction, `b_mᵀv` and `v += s·b_m`,
//! that the linearised problem is written in.

/// Marks a fixed direction in a node's DOF numbers.
pub(crate) const FIXED: u32 = u32::MAX;

/// Marks an assembly target that does not exist (a fully fixed node).
pub(crate) const NONE: usize = usize::MAX;

/// Which of a link's three slots (see [`Link::slots`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// Node `i`'s diagonal block.
    Ii,
    /// Node `j`'s diagonal block.
    Jj,
    /// The coupling block.
    Ij,
}

/// One member, compiled.
#[derive(Debug, Clone)]
pub(crate) struct CompiledMember {
    /// Where its stiffness and forces go.
    pub link: Link,
    /// Nominal vector `X_j − X_i` \[mm\].
    pub reference: [f64; 3],
    /// Nominal unit direction `(X_j − X_i)/L_r`.
    pub unit: [f64; 3],
    /// Nominal length `L_r = |X_j − X_i|` \[mm\].
    pub reference_length: f64,
    /// Nominal natural length \[mm\].
    pub natural_length: f64,
    /// Nominal `L_r − L₀` \[mm\].
    pub nominal_stretch: f64,
    /// `E·A` \[N\].
    pub rigidity: f64,
    /// Nominal axial stiffness `k = E·A/L₀` \[N/mm\].
    pub stiffness: f64,
    /// 1 for bars; the compression ratio for cables (and a half's slack-side ratio); for a
    /// cable of ratio 0, the working ratio that stands for the limit (see [`crate::limit`]).
    pub compression_ratio: f64,
    /// A cable of model ratio 0: the solver answers for the limit `r → 0`.
    pub limit: bool,
    /// Whether the member is one-sided: a cable, or a half of a member with a dead band.
    pub is_cable: bool,
    /// `σ`: +1 for bars and tension-only members, −1 for a compression-only half.
    pub sense: f64,
    /// The model member this stands for (itself, but for compression-only halves).
    pub model_member: usize,
    /// For a half of a member whose ends sit in clearance holes: its dead band.
    pub band: Option<Band>,
}

/// The dead band of a member whose ends sit in clearance holes (see [`crate::joint`]).
#[derive(Debug, Clone)]
pub(crate) struct Band {
    /// The joints (model order) at the member's first and second node, where there are.
    pub joints: [Option<usize>; 2],
    /// `Σ 1/k_t` over those joints \[mm/N\].
    pub compliance: f64,
    /// The member's own `E·A` \[N\].
    pub member_rigidity: f64,
    /// The other half's index among the structure's members.
    pub partner: usize,
}

/// Where a two-node element (a member or a joint, from node `i` to node `j`) puts its
/// stiffness blocks and forces.
#[derive(Debug, Clone)]
pub(crate) struct Link {
    /// Row numbers of (`i`x, `i`y, `i`z, `j`x, `j`y, `j`z); a fixed direction points at the
    /// zero slot (index `free`), whose value is always zero.
    pub dofs: [usize; 6],
    /// Block slots of (`i`,`i`), (`j`,`j`) and the coupling block, or [`NONE`].
    pub slots: [usize; 3],
    /// Whether the coupling block's rows belong to node `i` (else to node `j`).
    pub coupling_rows_i: bool,
    /// Whether this element is the first, in assembly order (members, then joints), to add
    /// to each of `slots`: it then writes the block instead of adding to it, so assembly
    /// needs no clearing.
    pub first: [bool; 3],
    /// 1 for a free direction, 0 for a fixed one, of node `i` then node `j`.
    pub masks: [[f64; 3]; 2],
    /// Blocks of node `i` and node `j` (rows `3b .. 3b + 3`), or [`NONE`] for a node with
    /// no free direction.
    pub ends: [usize; 2],
    /// Whether a node of the element has a block and a fixed direction, so that its rows
    /// need the masks (never for a node fixed in all or no directions).
    pub masked: bool,
}

/// One joint, compiled: condensed into its member's dead band.
#[derive(Debug, Clone)]
pub(crate) struct CompiledJoint {
    /// Its id, for messages.
    pub id: String,
    /// Its member's tension-only half (the model member's index).
    pub member: usize,
    /// Whether the hole is at the member's first node.
    pub at_start: bool,
    /// The shaft node.
    pub shaft: usize,
    /// Nominal clearance `g` \[mm\].
    pub clearance: f64,
    /// Contact stiffness `k_t` \[N/mm\].
    pub tension_stiffness: f64,
}

impl CompiledMember {
    /// Adds `scale·b_m` to `v`, a vector of `free` rows and the zero slot at index `free`
    /// (`b_m` holds `∓n_m` at the member's two nodes' rows).
    #[inline(always)]
    pub(crate) fn scatter_b(&self, free: usize, scale: f64, v: &mut [f64]) {
        let n = &self.unit;
        if self.link.masked {
            for k in 0..3 {
                v[self.link.dofs[k]] -= scale * n[k];
                v[self.link.dofs[3 + k]] += scale * n[k];
            }
            v[free] = 0.0;
            return;
        }
        let f = [scale * n[0], scale * n[1], scale * n[2]];
        let (blocks, _) = v[..free].as_chunks_mut::<3>();
        if let Some(x) = blocks.get_mut(self.link.ends[0]) {
            for (x, f) in x.iter_mut().zip(&f) {
                *x -= f;
            }
        }
        if let Some(x) = blocks.get_mut(self.link.ends[1]) {
            for (x, f) in x.iter_mut().zip(&f) {
                *x += f;
            }
        }
    }

    /// `b_mᵀ v` for a vector of `free` rows (`v` may omit the zero slot).
    #[inline(always)]
    pub(crate) fn gather_b(&self, free: usize, v: &[f64]) -> f64 {
        let mut sum = 0.0;
        if self.link.masked {
            let at = |d: usize| if d < free { v[d] } else { 0.0 };
            for k in 0..3 {
                sum += self.unit[k] * (at(self.link.dofs[3 + k]) - at(self.link.dofs[k]));
            }
            return sum;
        }
        let (blocks, _) = v[..free].as_chunks::<3>();
        let vi = blocks.get(self.link.ends[0]).copied().unwrap_or([0.0; 3]);
        let vj = blocks.get(self.link.ends[1]).copied().unwrap_or([0.0; 3]);
        for k in 0..3 {
            sum += self.unit[k] * (vj[k] - vi[k]);
        }
        sum
    }
}
