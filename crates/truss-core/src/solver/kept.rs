//! The model stiffness a model step assembled in whole at its point, kept (unfactorised)
//! for the step's later pieces and engagement rounds: at the same point, with a few cables
//! switched in the slack set, only the slots those cables reach are assembled again.
//!
//! Each such slot is summed again over every member that reaches it, in assembly order, with
//! the operations of a whole assembly ([`Structure::reassemble_slots`]), from blocks that
//! changed only for the switched cables: every slot is then the same sum, in the same order,
//! of the same numbers, and the matrix has the bits of a whole assembly (tested against it,
//! bit for bit, in the solver's tests). Units: stiffness entries \[N/mm\].
//!
//! The block rows before the first one that changed are those of the last factorisation's
//! matrix, whose factor the matrix still holds there: the factorisation starts again at
//! that row ([`BlockBandMatrix::refactor_collecting`]), with the same bits as a whole one.

use crate::block::{Block, BlockBandMatrix};
use crate::structure::{NONE_SLOT, Structure};

/// An assembled matrix and the slack set it was assembled for (see the module doc).
#[derive(Debug, Clone, Default)]
pub(super) struct KeptAssembly {
    /// The assembled blocks (the band's storage).
    pub(super) storage: Vec<Block>,
    /// The slack set as assembled.
    slack: Vec<bool>,
    /// Slots to assemble again, each listed once in `slots`.
    dirty: Vec<bool>,
    slots: Vec<usize>,
}

impl KeptAssembly {
    /// Buffers for `s`'s band and members.
    pub(super) fn new(s: &Structure) -> Self {
        let slots = s.nominal.blocks() * (s.bandwidth() + 1);
        Self {
            storage: vec![[[0.0; 3]; 3]; slots],
            slack: vec![false; s.members.len()],
            dirty: vec![false; slots],
            slots: Vec::with_capacity(slots),
        }
    }

    /// Keeps `k`, just assembled (unfactorised) for the slack set `slack`.
    pub(super) fn keep(&mut self, k: &mut BlockBandMatrix, slack: &[bool]) {
        self.storage.copy_from_slice(k.storage_mut());
        self.slack.copy_from_slice(slack);
    }

    /// The kept matrix assembled again for the slack set `slack` at the same point, with
    /// `block(m)` member `m`'s six entries as [`Structure::add_block`] takes them (changed
    /// since the whole assembly only for the members whose place in `slack` changed): the
    /// slots those members reach are summed again (see the module doc). Returns the first
    /// block row that changed (the number of block rows where none did): the rows before
    /// it are as they were.
    pub(super) fn reassemble(
        &mut self,
        s: &Structure,
        slack: &[bool],
        block: impl Fn(usize) -> [f64; 6],
    ) -> usize {
        for (m, (was, now)) in self.slack.iter_mut().zip(slack).enumerate() {
            if was != now {
                *was = *now;
                for &slot in &s.members[m].link.slots {
                    if slot != NONE_SLOT && !self.dirty[slot] {
                        self.dirty[slot] = true;
                        self.slots.push(slot);
                    }
                }
            }
        }
        s.reassemble_slots(&mut self.storage, &self.slots, block);
        let mut lowest = usize::MAX;
        for &slot in &self.slots {
            self.dirty[slot] = false;
            lowest = lowest.min(slot);
        }
        self.slots.clear();
        (lowest / (s.bandwidth() + 1)).min(s.nominal.blocks())
    }

    /// Block rows `from ..` of `k` = the kept matrix's.
    pub(super) fn copy_rows_into(&self, k: &mut BlockBandMatrix, from: usize) {
        let at = (from * (k.bandwidth() + 1)).min(self.storage.len());
        k.storage_mut()[at..].copy_from_slice(&self.storage[at..]);
    }
}
