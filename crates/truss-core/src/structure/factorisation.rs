//! The fourth stage of compiling a structure: the all-taut material stiffness
//! `K₀ = Σ k_m b_m b_mᵀ` assembled and factorised, which proves the model is not a
//! mechanism; and the assembly of block-band stiffness matrices that every solve uses
//! (members then joints, in order, each adding its `[[K, −K], [−K, K]]` blocks with fixed
//! directions masked).

use super::compiled::Structure;
use super::parts::{Link, NONE, Role};
use crate::ModelError;
use crate::block::{Block, BlockBandMatrix};

/// Assembles `K₀` into `k` (of the structure's band) and factorises it; a zero or negative
/// pivot is a mechanism, named by the node and direction of its row.
pub(super) fn factorise_nominal(
    structure: &Structure,
    k: &mut BlockBandMatrix,
) -> Result<(), ModelError> {
    structure.assemble_material(k, |_| 1.0);
    k.factor().map_err(|e| {
        let (node, dof) = structure.describe_dof(e.index);
        ModelError::Mechanism { node, dof }
    })
}

impl Structure {
    /// Assembles the linearised material stiffness `Σ f(m)·k_m·b_m b_mᵀ` (nominal `k_m`
    /// and directions, `f(m)` a per-member factor such as a slack cable's compression
    /// ratio) into `k`, identity rows included.
    pub(crate) fn assemble_material(&self, k: &mut BlockBandMatrix, factor: impl Fn(usize) -> f64) {
        self.begin_assembly(k);
        for (m, c) in self.members.iter().enumerate() {
            let kk = factor(m) * c.rigidity / c.natural_length;
            let n = c.unit;
            let block = [
                kk * n[0] * n[0],
                kk * n[1] * n[0],
                kk * n[1] * n[1],
                kk * n[2] * n[0],
                kk * n[2] * n[1],
                kk * n[2] * n[2],
            ];
            self.add_block(k, &c.link, &block);
        }
        self.set_identity_rows(k);
    }

    /// Prepares `k` for [`Structure::add_block`] of every member, in order: zeroes the blocks that none writes (the first to reach a block writes it).
    #[inline]
    pub(crate) fn begin_assembly(&self, k: &mut BlockBandMatrix) {
        let storage = k.storage_mut();
        for &slot in &self.untouched {
            storage[slot] = [[0.0; 3]; 3];
        }
    }

    /// Adds a member's or joint's contribution `[[K, −K], [−K, K]]` (from the six distinct
    /// entries of the symmetric 3×3 `K`, order `[xx, yx, yy, zx, zy, zz]`), fixed
    /// directions masked; called for every member then every joint, in order, after
    /// [`Structure::begin_assembly`]. Only the lower triangles of diagonal blocks are
    /// written (the only part read).
    #[inline]
    pub(crate) fn add_block(&self, k: &mut BlockBandMatrix, c: &Link, e: &[f64; 6]) {
        let storage = k.storage_mut();
        for role in [Role::Ii, Role::Jj, Role::Ij] {
            add_to_slot(storage, c, e, role);
        }
    }

    /// Assembles again, in `storage` (a matrix this structure assembled), the slots listed
    /// in `slots`, with `block(m)` member `m`'s six entries as [`Structure::add_block`]
    /// takes them: each slot is summed over the members that reach it, in assembly order,
    /// with the operations of a whole assembly, and its identity rows set. So where only
    /// the listed slots' members changed since `storage` was assembled, it then holds the
    /// bits a whole assembly would give.
    pub(crate) fn reassemble_slots(
        &self,
        storage: &mut [Block],
        slots: &[usize],
        block: impl Fn(usize) -> [f64; 6],
    ) {
        let w = &self.writers;
        for &slot in slots {
            let (from, to) = (w.start[slot] as usize, w.start[slot + 1] as usize);
            for &(m, role) in &w.members[from..to] {
                let m = m as usize;
                add_to_slot(storage, &self.members[m].link, &block(m), role);
            }
            for (d, row) in storage[slot].iter_mut().enumerate() {
                if w.identity[slot] & (1 << d) != 0 {
                    row[d] = 1.0;
                }
            }
        }
    }

    /// Puts 1 on the diagonal of every fixed direction of an active node.
    #[inline]
    pub(crate) fn set_identity_rows(&self, k: &mut BlockBandMatrix) {
        let storage = k.storage_mut();
        for &(slot, d) in &self.identity_rows {
            storage[slot][d][d] = 1.0;
        }
    }
}

/// [`Structure::add_block`]'s part for one slot of link `c`: the first element to reach it
/// writes it (`0 + x` is `x`), later ones add; a masked link's first element zeroes it, then
/// adds the masked block.
#[inline(always)]
fn add_to_slot(storage: &mut [Block], c: &Link, e: &[f64; 6], role: Role) {
    let index = role as usize;
    let slot = c.slots[index];
    if slot == NONE {
        return;
    }
    let first = c.first[index];
    let b = &mut storage[slot];
    if !c.masked {
        // Masks of ones: `x·1·1` is `x` exactly, so this is the masked sum without the
        // multiplications.
        if role != Role::Ij {
            if first {
                b[0][0] = e[0];
                b[1][0] = e[1];
                b[1][1] = e[2];
                b[2][0] = e[3];
                b[2][1] = e[4];
                b[2][2] = e[5];
            } else {
                b[0][0] += e[0];
                b[1][0] += e[1];
                b[1][1] += e[2];
                b[2][0] += e[3];
                b[2][1] += e[4];
                b[2][2] += e[5];
            }
        } else {
            let full = [[e[0], e[1], e[3]], [e[1], e[2], e[4]], [e[3], e[4], e[5]]];
            if first {
                // Written out: `full.map(|row| row.map(|x| −x))` is not inlined, and its
                // call cost a sixth of the assembly.
                for (row, f) in b.iter_mut().zip(&full) {
                    for (x, y) in row.iter_mut().zip(f) {
                        *x = -y;
                    }
                }
            } else {
                for (row, f) in b.iter_mut().zip(&full) {
                    for (x, y) in row.iter_mut().zip(f) {
                        *x -= y;
                    }
                }
            }
        }
        return;
    }
    let full: Block = [[e[0], e[1], e[3]], [e[1], e[2], e[4]], [e[3], e[4], e[5]]];
    if first {
        *b = [[0.0; 3]; 3];
    }
    let [mi, mj] = &c.masks;
    match role {
        Role::Ii => add_masked(b, &full, mi, mi, 1.0),
        Role::Jj => add_masked(b, &full, mj, mj, 1.0),
        Role::Ij if c.coupling_rows_i => add_masked(b, &full, mi, mj, -1.0),
        Role::Ij => add_masked(b, &full, mj, mi, -1.0),
    }
}

/// `target += sign · (row mask) ∘ block ∘ (column mask)`.
#[inline(always)]
fn add_masked(target: &mut Block, block: &Block, rows: &[f64; 3], cols: &[f64; 3], sign: f64) {
    for r in 0..3 {
        for c in 0..3 {
            target[r][c] += sign * rows[r] * cols[c] * block[r][c];
        }
    }
}
