//! The compiled, immutable form of a model that solvers share: node numbering, per-member
//! constants, assembly targets, and the factorised all-taut material stiffness `K₀`.
//!
//! A [`Structure`] is built once per model and shared (behind an `Arc`) by every thread's
//! [`Solver`](crate::Solver). `K₀ = Σ k_m b_m b_mᵀ` (every cable taut, nominal geometry, no
//! geometric stiffness) is factorised here once: it proves the model is not a mechanism,
//! and with the Woodbury data over the cables it solves the linearised problem of every
//! sample (see the `linearised` module).
//!
//! [`Structure::new`] compiles a model in stages, a file each, in this order:
//!
//! 1. **numbering** (`numbering.rs`): the unknowns, a block of three rows per node with a free
//!    direction, ordered for a narrow band; a joint's hole node gets none;
//! 2. **joints** (`joints.rs`): the members compiled, the backlash joints condensed into them
//!    (see [`crate::joint`]): a member end in a hole acts on the joint's shaft node, and a
//!    member with joints at its ends becomes two one-sided members in parallel, its
//!    tension-only half in the member's own place and its compression-only half after all
//!    the model's members;
//! 3. **sparsity** (`sparsity.rs`): which member first writes each block of the band,
//!    which blocks none reaches, and the lowest row each one-sided member reaches;
//! 4. **factorisation** (`factorisation.rs`): `K₀` assembled and factorised; then
//!    (`framing.rs`) the working compression ratio of the cables of ratio 0, from whether the
//!    bars frame the top surface's tilt (what the ratios stand for: [`crate::limit`]);
//! 5. **low-rank basis** (`basis.rs`): the Woodbury data over the cables.
//!
//! The compiled pieces (`parts.rs`) and the [`Structure`] type (`compiled.rs`) sit below the
//! stages, which import them and never each other's callers.

mod basis;
mod compiled;
mod factorisation;
mod framing;
mod joints;
mod numbering;
mod parts;
mod sparsity;

pub(crate) use basis::CableBasis;
pub use compiled::Structure;
pub(crate) use framing::tilt_loads;
pub use framing::{FRAMED_RATIO, LIMIT_RATIO};
pub(crate) use parts::{FIXED, Link, NONE as NONE_SLOT};

use crate::ModelError;
use crate::model::Model;

impl Structure {
    /// Compiles `model` and factorises `K₀`; fails if the model is a mechanism.
    pub fn new(model: &Model) -> Result<Self, ModelError> {
        let nodes = model.nodes();
        let numbering = numbering::Numbering::new(model);
        let mut members = joints::compile_members(model, &numbering)?;
        let joints = joints::compile_joints(model);
        let loads = numbering.loads(model);
        let mut k = numbering.matrix;
        let writers = sparsity::slot_writers(
            &members,
            &numbering.identity_rows,
            k.blocks() * (k.bandwidth() + 1),
        );
        let untouched = sparsity::mark_first_writers(&mut members, &writers, &k);
        let one_sided_by_row = sparsity::one_sided_by_lowest_row(&members, numbering.free);
        let mut structure = Self {
            node_ids: nodes.iter().map(|n| n.id.clone()).collect(),
            node_xyz: nodes.iter().map(|n| n.xyz).collect(),
            node_dofs: numbering.node_dofs,
            dof_owner: numbering.dof_owner,
            free: numbering.free,
            members,
            model_members: model.members().len(),
            hole_joint: numbering.hole_joint,
            joints,
            identity_rows: numbering.identity_rows,
            untouched,
            writers,
            one_sided_by_row,
            loads,
            nominal: crate::block::BlockBandMatrix::new(0, 0),
            basis: None,
            top_surface: model.top_surface().cloned(),
            tilt_framed: false,
        };
        factorisation::factorise_nominal(&structure, &mut k)?;
        structure.nominal = k;
        let (tilt_framed, working) = framing::working_ratio(&structure);
        structure.tilt_framed = tilt_framed;
        for c in structure.members.iter_mut().filter(|c| c.limit) {
            c.compression_ratio = working;
        }
        structure.basis =
            CableBasis::for_members(&structure.members, structure.free, &structure.nominal);
        Ok(structure)
    }
}
