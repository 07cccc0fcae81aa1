//! The third stage of compiling a structure: the band's sparsity. Assembly visits the
//! members in order; the first to reach each block slot writes it instead of adding to it,
//! so that assembling needs no clearing, and only the slots of the band that no member
//! reaches are zeroed before each assembly.

use super::parts::{CompiledMember, NONE};
use crate::block::BlockBandMatrix;

/// Marks, in each member's link, the slots it is the first to reach, and returns the slots
/// of `k`'s band (within it, not its padding) that no member reaches.
pub(super) fn mark_first_writers(
    members: &mut [CompiledMember],
    k: &BlockBandMatrix,
) -> Vec<usize> {
    let mut touched = vec![false; k.blocks() * (k.bandwidth() + 1)];
    for link in members.iter_mut().map(|c| &mut c.link) {
        for (first, &slot) in link.first.iter_mut().zip(&link.slots) {
            if slot != NONE && !touched[slot] {
                touched[slot] = true;
                *first = true;
            }
        }
    }
    (0..k.blocks())
        .flat_map(|i| (i.saturating_sub(k.bandwidth())..=i).map(move |j| (i, j)))
        .map(|(i, j)| k.slot(i, j))
        .filter(|&slot| !touched[slot])
        .collect()
}
