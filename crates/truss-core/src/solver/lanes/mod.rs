//! Many samples per pass: the solves of `W` samples of a case run side by side, each in its
//! own lane, and the kernels they wait for run once for all of them, as vector instructions
//! over `W` lanes.
//!
//! ## How
//! A solve is written once, as an `async` function of the [`Solver`](super::Solver) whose
//! kernels are awaited through its [`Kernels`]: [`Kernels::OneSample`] runs each kernel at
//! once (the future never waits; [`finish`] drives it), [`Kernels::Lane`] posts the kernel's
//! inputs in the lane's [`LaneSlot`] and waits. A driver (the one sample engine of
//! `truss-job`) polls the `W` lanes' futures until each waits or is done, then calls
//! [`BatchKernels::run`], which evaluates every waiting lane at once, and polls again. A
//! lane that is done is refilled with the next sample, so a slow sample holds no other.
//!
//! ## Bit for bit
//! Every lane performs exactly the IEEE operations of the one-sample path, in the same order
//! (see [`evaluate`]): no fused multiply-add, no sum across lanes, no decision in one lane
//! that depends on another. The control flow of a solve (iterations, line-search trials,
//! slack sets) is the same code in both paths. So a sample's bytes depend neither on its
//! lane, nor on its neighbours, nor on `W`, nor on the instruction set the kernels use:
//! AVX2 where the processor has it, chosen at run time by the `pulp` crate (the default
//! build targets baseline x86-64, whose SSE2 carries two lanes per instruction). No
//! `unsafe` code: a waiting lane's buffers are moved into its [`LaneSlot`] and back.
//!
//! Today the member evaluation (the out-of-balance force at a point, the largest single
//! kernel of a 5-stage solve) is batched; the factorisations and triangular solves run one
//! lane at a time inside the lane's solve.

mod drive;
mod evaluate;

pub use drive::{LaneSolve, LaneWork, run_lanes};

use super::evaluate::{Evaluation, evaluate_with};
use crate::element::{AxialMember, AxialState};
use crate::structure::Structure;
use evaluate::{EvalBuffers, EvalLanes, SampleKey};
use std::cell::RefCell;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll, Waker};

/// Lanes per batch: four f64 lanes fill an AVX2 register (two SSE2 ones).
pub const LANES: usize = 4;

/// The instruction set for the batched kernels: the best this processor has, unless
/// `TRUSS_KERNELS=baseline` asks for baseline x86-64 (for the test that both give the same
/// bytes, and for benchmarks).
pub(crate) fn arch() -> pulp::Arch {
    use std::sync::OnceLock;
    static BASELINE: OnceLock<bool> = OnceLock::new();
    if *BASELINE.get_or_init(|| std::env::var_os("TRUSS_KERNELS").is_some_and(|v| v == "baseline"))
    {
        pulp::Arch::Scalar
    } else {
        pulp::Arch::new()
    }
}

/// The instruction set the batched kernels use on this processor, in words.
pub fn kernel_set() -> &'static str {
    match arch() {
        pulp::Arch::Scalar => "baseline",
        #[allow(unreachable_patterns)]
        _ => "avx2",
    }
}

/// How a solve runs its kernels.
#[derive(Debug, Clone, Copy)]
pub enum Kernels<'p> {
    /// At once, on this sample alone: the solve's future never waits.
    OneSample,
    /// Through this lane of a batch: the solve waits while [`BatchKernels::run`] evaluates.
    Lane(&'p LaneSlot),
}

/// An evaluation a lane waits for: its structure, which sample, and its buffers.
#[derive(Debug)]
struct Posted {
    structure: Arc<Structure>,
    key: SampleKey,
    buffers: EvalBuffers,
}

/// One lane's mailbox: the evaluation its solve waits for, and then the answer (the
/// buffers back, and the evaluation).
#[derive(Debug, Default)]
pub struct LaneSlot {
    posted: RefCell<Option<Posted>>,
    answer: RefCell<Option<(EvalBuffers, Evaluation)>>,
}

/// The lanes' mailboxes of a batch (borrowed by the lanes' futures).
#[derive(Debug)]
pub struct LaneSlots {
    slots: [LaneSlot; LANES],
}

impl Default for LaneSlots {
    fn default() -> Self {
        Self {
            slots: std::array::from_fn(|_| LaneSlot::default()),
        }
    }
}

impl LaneSlots {
    /// Lane `l`'s mailbox, `l < LANES`.
    pub fn lane(&self, l: usize) -> &LaneSlot {
        &self.slots[l]
    }
}

/// The batched kernels' buffers, one set per structure met (a batch's lanes may hold
/// samples of different cases; each structure's lanes are evaluated together).
#[derive(Debug)]
pub struct BatchKernels {
    arch: pulp::Arch,
    evaluation: Vec<(Arc<Structure>, EvalLanes<LANES>)>,
}

impl Default for BatchKernels {
    fn default() -> Self {
        Self::with_arch(arch())
    }
}

impl BatchKernels {
    /// Kernels compiled for `arch` (the default: the best this processor has).
    fn with_arch(arch: pulp::Arch) -> Self {
        Self {
            arch,
            evaluation: Vec::new(),
        }
    }

    /// Runs the kernels the lanes wait for: every posted evaluation, the lanes of one
    /// structure at once. Returns how many lanes were answered.
    pub fn run(&mut self, slots: &LaneSlots) -> usize {
        let mut posted: [Option<Posted>; LANES] =
            std::array::from_fn(|l| slots.slots[l].posted.borrow_mut().take());
        let mut answers: [Option<Evaluation>; LANES] = [None; LANES];
        let mut left = [false; LANES];
        for (x, p) in left.iter_mut().zip(&posted) {
            *x = p.is_some();
        }
        while let Some(first) = left.iter().position(|&x| x) {
            let structure = Arc::clone(&posted[first].as_ref().expect("posted").structure);
            let at = match self
                .evaluation
                .iter()
                .position(|(s, _)| Arc::ptr_eq(s, &structure))
            {
                Some(i) => i,
                None => {
                    let lanes = EvalLanes::new(&structure, self.arch);
                    self.evaluation.push((Arc::clone(&structure), lanes));
                    self.evaluation.len() - 1
                }
            };
            let mut io: [Option<(SampleKey, &mut EvalBuffers)>; LANES] =
                std::array::from_fn(|_| None);
            for ((x, p), l) in io.iter_mut().zip(posted.iter_mut()).zip(left.iter_mut()) {
                if let Some(p) = p
                    && *l
                    && Arc::ptr_eq(&p.structure, &structure)
                {
                    *x = Some((p.key, &mut p.buffers));
                    *l = false;
                }
            }
            let evaluations = self.evaluation[at].1.evaluate(&structure, &mut io);
            for (a, e) in answers.iter_mut().zip(evaluations) {
                if e.is_some() {
                    *a = e;
                }
            }
        }
        let mut answered = 0;
        for ((slot, p), e) in slots.slots.iter().zip(posted).zip(answers) {
            if let (Some(p), Some(e)) = (p, e) {
                *slot.answer.borrow_mut() = Some((p.buffers, e));
                answered += 1;
            }
        }
        answered
    }
}

/// One sample's evaluation, its buffers borrowed from its solver (see [`evaluate_with`]).
pub(super) struct Evaluate<'a> {
    pub structure: &'a Arc<Structure>,
    pub key: SampleKey,
    pub members: &'a mut Vec<AxialMember>,
    pub tension: &'a mut Vec<f64>,
    pub loads: &'a mut Vec<f64>,
    pub u: &'a mut Vec<f64>,
    pub r: &'a mut Vec<f64>,
    pub states: &'a mut Vec<AxialState>,
}

impl Kernels<'_> {
    /// `r = g(u) − f` and the member states at `u` (see [`evaluate_with`]): at once, or in
    /// the batch.
    pub(super) async fn evaluate(self, e: Evaluate<'_>) -> Evaluation {
        match self {
            Kernels::OneSample => evaluate_with(
                e.structure,
                e.members,
                e.tension.iter().copied(),
                e.loads,
                e.u,
                e.r,
                e.states,
            ),
            Kernels::Lane(slot) => {
                *slot.posted.borrow_mut() = Some(Posted {
                    structure: Arc::clone(e.structure),
                    key: e.key,
                    buffers: EvalBuffers {
                        members: std::mem::take(e.members),
                        tension: std::mem::take(e.tension),
                        loads: std::mem::take(e.loads),
                        u: std::mem::take(e.u),
                        r: std::mem::take(e.r),
                        states: std::mem::take(e.states),
                    },
                });
                Wait(false).await;
                let (b, evaluation) = slot
                    .answer
                    .borrow_mut()
                    .take()
                    .expect("a lane is polled again only after the batch answered it");
                (*e.members, *e.tension, *e.loads) = (b.members, b.tension, b.loads);
                (*e.u, *e.r, *e.states) = (b.u, b.r, b.states);
                evaluation
            }
        }
    }
}

/// Waits once: pending at the first poll, ready at the next.
struct Wait(bool);

impl Future for Wait {
    type Output = ();
    fn poll(mut self: Pin<&mut Self>, _: &mut Context<'_>) -> Poll<()> {
        if self.0 {
            Poll::Ready(())
        } else {
            self.0 = true;
            Poll::Pending
        }
    }
}

/// Drives a solve whose kernels run at once ([`Kernels::OneSample`]) to its end.
///
/// # Panics
/// If the future waits: it was given a lane.
pub fn finish<F: Future>(future: F) -> F::Output {
    let mut future = std::pin::pin!(future);
    match future
        .as_mut()
        .poll(&mut Context::from_waker(Waker::noop()))
    {
        Poll::Ready(out) => out,
        Poll::Pending => panic!("a one-sample solve waited for a batch"),
    }
}

#[cfg(test)]
mod tests;
