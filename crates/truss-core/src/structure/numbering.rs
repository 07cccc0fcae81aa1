//! The first stage of compiling a structure: numbering the unknowns. A joint's hole node gets
//! none (a member end in a hole acts on the joint's shaft); every other node with a free
//! direction gets a block of three rows, in the reverse Cuthill–McKee order of
//! [`crate::ordering`], so that the stiffness matrix is a narrow band of 3×3 node blocks.
//! The numbering also says where each two-node element puts its stiffness ([`Link`]) and
//! which rows carry the external loads.

use super::parts::{FIXED, Link, NONE};
use crate::block::BlockBandMatrix;
use crate::model::Model;
use crate::ordering::number_nodes;

/// The unknowns of a model and the band they give.
pub(super) struct Numbering {
    /// For each node that is a joint's hole, that joint.
    pub hole_joint: Vec<Option<usize>>,
    /// The fixed directions of each node (all three for a hole node).
    pub fixed: Vec<[bool; 3]>,
    /// Each node's block, `None` for a node with no free direction.
    pub block: Vec<Option<usize>>,
    /// Row numbers of each node's directions, [`FIXED`] where held.
    pub node_dofs: Vec<[u32; 3]>,
    /// Node and direction of each row.
    pub dof_owner: Vec<(usize, u8)>,
    /// Block slots and directions of fixed directions of active nodes (identity rows).
    pub identity_rows: Vec<(usize, usize)>,
    /// Number of rows (3 per active node).
    pub free: usize,
    /// The (empty) stiffness matrix of this numbering's band.
    pub matrix: BlockBandMatrix,
}

impl Numbering {
    /// Numbers the unknowns of `model`.
    pub fn new(model: &Model) -> Self {
        let nodes = model.nodes();
        let mut hole_joint = vec![None; nodes.len()];
        for (k, j) in model.joints().iter().enumerate() {
            hole_joint[j.hole] = Some(k);
        }
        let fixed: Vec<[bool; 3]> = (0..nodes.len())
            .map(|i| {
                if hole_joint[i].is_some() {
                    [true; 3]
                } else {
                    model.fixed(i)
                }
            })
            .collect();
        let edges: Vec<[usize; 2]> = model
            .members()
            .iter()
            .map(|m| m.nodes.map(|node| attach(model, &hole_joint, node)))
            .collect();
        let numbering = number_nodes(&fixed, &edges);
        let free = 3 * numbering.blocks;
        let matrix = BlockBandMatrix::new(numbering.blocks, numbering.bandwidth);
        let mut node_dofs = vec![[FIXED; 3]; nodes.len()];
        let mut dof_owner = vec![(0, 0); free];
        let mut identity_rows = Vec::new();
        for (node, block) in numbering.block.iter().enumerate() {
            if let Some(b) = *block {
                for d in 0..3 {
                    dof_owner[3 * b + d] = (node, d as u8);
                    if fixed[node][d] {
                        identity_rows.push((matrix.slot(b, b), d));
                    } else {
                        node_dofs[node][d] = (3 * b + d) as u32;
                    }
                }
            }
        }
        Numbering {
            hole_joint,
            fixed,
            block: numbering.block,
            node_dofs,
            dof_owner,
            identity_rows,
            free,
            matrix,
        }
    }

    /// The node a member end at `node` acts on: the joint's shaft for a hole node.
    pub fn attach(&self, model: &Model, node: usize) -> usize {
        attach(model, &self.hole_joint, node)
    }

    /// Where an element from node `i` to node `j` puts its stiffness blocks and forces
    /// (`first` is set by the sparsity stage).
    pub fn link(&self, i: usize, j: usize) -> Link {
        let (fixed, free, k) = (&self.fixed, self.free, &self.matrix);
        let mut dofs = [free; 6];
        for d in 0..3 {
            for (side, node) in [i, j].into_iter().enumerate() {
                if self.node_dofs[node][d] != FIXED {
                    dofs[3 * side + d] = self.node_dofs[node][d] as usize;
                }
            }
        }
        let (bi, bj) = (self.block[i], self.block[j]);
        let slot = |a: Option<usize>, b: Option<usize>| match (a, b) {
            (Some(a), Some(b)) => k.slot(a.max(b), a.min(b)),
            _ => NONE,
        };
        let mask = |node: usize| fixed[node].map(|f| if f { 0.0 } else { 1.0 });
        Link {
            dofs,
            slots: [slot(bi, bi), slot(bj, bj), slot(bi, bj)],
            coupling_rows_i: bi > bj,
            first: [false; 3],
            masks: [mask(i), mask(j)],
            ends: [bi.unwrap_or(NONE), bj.unwrap_or(NONE)],
            masked: (bi.is_some() && fixed[i].iter().any(|&f| f))
                || (bj.is_some() && fixed[j].iter().any(|&f| f)),
        }
    }

    /// The external load on each row, and 0 in the zero slot after them \[N\].
    pub fn loads(&self, model: &Model) -> Vec<f64> {
        let mut loads = vec![0.0; self.free + 1];
        for (node, dofs) in self.node_dofs.iter().enumerate() {
            let f = model.load(node);
            for d in 0..3 {
                if dofs[d] != FIXED {
                    loads[dofs[d] as usize] = f[d];
                }
            }
        }
        loads
    }
}

/// A member end in a hole acts on the joint's shaft; the hole node has no unknowns.
fn attach(model: &Model, hole_joint: &[Option<usize>], node: usize) -> usize {
    hole_joint[node].map_or(node, |k| model.joints()[k].shaft)
}
