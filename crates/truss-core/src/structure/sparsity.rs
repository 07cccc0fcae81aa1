//! The third stage of compiling a structure: the band's sparsity. Assembly visits the
//! members in order; the first to reach each block slot writes it instead of adding to it,
//! so that assembling needs no clearing, and only the slots of the band that no member
//! reaches are zeroed before each assembly.

use super::parts::{CompiledMember, NONE, Role};
use crate::block::BlockBandMatrix;

/// Marks, in each member's link, the slots it is the first to reach (the head of each
/// slot's `writers`), and returns the slots of `k`'s band (within it, not its padding) that
/// no member reaches.
pub(super) fn mark_first_writers(
    members: &mut [CompiledMember],
    writers: &SlotWriters,
    k: &BlockBandMatrix,
) -> Vec<usize> {
    let reaching = |slot: usize| {
        let (from, to) = (
            writers.start[slot] as usize,
            writers.start[slot + 1] as usize,
        );
        &writers.members[from..to]
    };
    for slot in 0..writers.start.len() - 1 {
        if let Some(&(m, role)) = reaching(slot).first() {
            members[m as usize].link.first[role as usize] = true;
        }
    }
    (0..k.blocks())
        .flat_map(|i| (i.saturating_sub(k.bandwidth())..=i).map(move |j| (i, j)))
        .map(|(i, j)| k.slot(i, j))
        .filter(|&slot| reaching(slot).is_empty())
        .collect()
}

/// For each slot of the band, the elements that reach it, in assembly order, and its
/// identity rows: what [`Structure::reassemble_slots`](super::Structure::reassemble_slots)
/// sums again where only some members changed.
#[derive(Debug, Clone, Default)]
pub(crate) struct SlotWriters {
    /// `members[start[s]..start[s + 1]]` reach slot `s`.
    pub start: Vec<u32>,
    /// Member index and which of its link's slots is `s`.
    pub members: Vec<(u32, Role)>,
    /// Bit `d` set: direction `d` of the slot's (diagonal) block is an identity row.
    pub identity: Vec<u8>,
}

/// The [`SlotWriters`] of `members` and `identity_rows` in a band of `slots` slots.
pub(super) fn slot_writers(
    members: &[CompiledMember],
    identity_rows: &[(usize, usize)],
    slots: usize,
) -> SlotWriters {
    let mut lists: Vec<Vec<(u32, Role)>> = vec![Vec::new(); slots];
    for (m, c) in members.iter().enumerate() {
        for (role, &slot) in [Role::Ii, Role::Jj, Role::Ij]
            .into_iter()
            .zip(&c.link.slots)
        {
            if slot != NONE {
                lists[slot].push((m as u32, role));
            }
        }
    }
    let mut identity = vec![0u8; slots];
    for &(slot, d) in identity_rows {
        identity[slot] |= 1 << d;
    }
    let mut start = Vec::with_capacity(slots + 1);
    let mut flat = Vec::new();
    for list in lists {
        start.push(flat.len() as u32);
        flat.extend(list);
    }
    start.push(flat.len() as u32);
    SlotWriters {
        start,
        members: flat,
        identity,
    }
}

/// The one-sided members (cables and the halves of members in clearance holes), each with the
/// lowest row it reaches (`usize::MAX` for one that reaches none), in the order of that row,
/// then of the member: a direction that is zero above row `i` (a failed pivot's, see
/// [`BlockBandMatrix::failed_pivot_direction`]) moves only the prefix whose row is at most
/// `i`, and only those can engage along it.
pub(super) fn one_sided_by_lowest_row(
    members: &[CompiledMember],
    free: usize,
) -> Vec<(usize, usize)> {
    let mut list: Vec<(usize, usize)> = members
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_cable)
        .map(|(m, c)| {
            let lowest = c.link.dofs.iter().copied().filter(|&d| d < free).min();
            (lowest.unwrap_or(usize::MAX), m)
        })
        .collect();
    list.sort_unstable();
    list
}
