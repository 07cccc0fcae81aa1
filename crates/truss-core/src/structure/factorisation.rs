//! The fourth stage of compiling a structure: the all-taut material stiffness
//! `K₀ = Σ k_m b_m b_mᵀ` assembled and factorised, which proves the model is not a
//! mechanism; and the assembly of block-band stiffness matrices that every solve uses
//! (members then joints, in order, each adding its `[[K, −K], [−K, K]]` blocks with fixed
//! directions masked).

use super::compiled::Structure;
use super::parts::{Link, NONE};
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
        let [sii, sjj, sij] = c.slots;
        let storage = k.storage_mut();
        if !c.masked {
            // Masks of ones: `x·1·1` is `x` exactly, so this is the masked sum without the
            // multiplications; a block's first member writes it (`0 + x` is `x`).
            for (slot, first) in [(sii, c.first[0]), (sjj, c.first[1])] {
                if slot != NONE {
                    let b = &mut storage[slot];
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
                }
            }
            if sij != NONE {
                let b = &mut storage[sij];
                let full = [[e[0], e[1], e[3]], [e[1], e[2], e[4]], [e[3], e[4], e[5]]];
                if c.first[2] {
                    // Written out: `full.map(|row| row.map(|x| −x))` is not inlined, and
                    // its call cost a sixth of the assembly.
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
        let [mi, mj] = c.masks;
        for (&slot, &first) in c.slots.iter().zip(&c.first) {
            if slot != NONE && first {
                storage[slot] = [[0.0; 3]; 3];
            }
        }
        if sii != NONE {
            add_masked(&mut storage[sii], &full, &mi, &mi, 1.0);
        }
        if sjj != NONE {
            add_masked(&mut storage[sjj], &full, &mj, &mj, 1.0);
        }
        if sij != NONE {
            if c.coupling_rows_i {
                add_masked(&mut storage[sij], &full, &mi, &mj, -1.0);
            } else {
                add_masked(&mut storage[sij], &full, &mj, &mi, -1.0);
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

/// `target += sign · (row mask) ∘ block ∘ (column mask)`.
#[inline(always)]
fn add_masked(target: &mut Block, block: &Block, rows: &[f64; 3], cols: &[f64; 3], sign: f64) {
    for r in 0..3 {
        for c in 0..3 {
            target[r][c] += sign * rows[r] * cols[c] * block[r][c];
        }
    }
}
