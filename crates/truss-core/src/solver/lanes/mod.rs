//! Many samples per pass: the solves of `W` samples of a case run side by side, each in its
//! own lane, and the kernels they wait for run once for all of them, as vector instructions
//! over `W` lanes.
//!
//! ## How
//! A solve is written once, as an `async` function of the [`Solver`](super::Solver) whose
//! kernels are awaited through its [`Kernels`]: [`Kernels::OneSample`] runs each kernel at
//! once (the future never waits; [`finish`] drives it), [`Kernels::Lane`] posts the kernel's
//! request in the lane's [`LaneSlot`] and waits. A driver ([`run_lanes`], used by the one
//! sample engine of `truss-job`) polls the lanes' futures until each waits or is done, then
//! calls [`BatchKernels::run`], and polls the answered lanes again. A lane that is done is
//! refilled with the next sample, so a slow sample holds no other.
//!
//! The batched kernels are the three that cost most in a solve of the paper's prism:
//! - the member evaluation (out-of-balance force, member states and strain energy at a
//!   point; the `evaluate` module);
//! - the factorisation of the tangent and the triangular solves with it (the `band`
//!   module; a lane keeps its factor for the solves that reuse it);
//!
//! while the rest of a solve (the linearised start and its Woodbury solves, assembly, the
//! line search's arithmetic) runs in each lane's own code. Each round runs one kernel: the
//! one most lanes wait for, unless a lane has waited [`PATIENCE`] rounds; the others keep
//! waiting, so that lanes fall into step (a kernel costs as much for one lane as for four).
//! Structures above [`BATCHED_DOFS`] unknowns run their lanes' kernels one lane at a time.
//!
//! ## Bit for bit
//! Every lane performs exactly the IEEE operations of the one-sample path, in the same order
//! (see the `evaluate` and `band` modules): no fused multiply-add, no sum across lanes, no
//! decision in one lane that depends on another. The control flow of a solve (iterations,
//! line-search trials, slack sets) is the same code in both paths. So a sample's bytes
//! depend neither on its lane, nor on its neighbours, nor on `W`, nor on the instruction set
//! the kernels use: AVX2 where the processor has it, chosen at run time by the `pulp` crate
//! (the default build targets baseline x86-64, whose SSE2 carries two lanes per
//! instruction; `TRUSS_KERNELS=baseline` forces it). No `unsafe` code: a waiting lane's
//! buffers are moved into its [`LaneSlot`] and back.

mod band;
mod drive;
mod evaluate;
mod lane;

pub use drive::{LaneSolve, LaneWork, run_lanes};

use super::evaluate::{Evaluation, evaluate_with};
use crate::block::{BlockBandMatrix, PivotFailure};
use crate::element::{AxialMember, AxialState};
use crate::structure::Structure;
use band::{BandLanes, FactorLane, SolveLane};
use evaluate::{EvalBuffers, EvalLanes, SampleKey};
use std::cell::{Cell, RefCell};
use std::future::Future;
use std::sync::Arc;
use std::task::{Context, Poll, Waker};

/// Lanes per batch: four f64 lanes fill an AVX2 register (two SSE2 ones).
pub const LANES: usize = 4;

pub(crate) use crate::block::arch;

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

/// What a lane waits for, its inputs and outputs moved out of its solver.
#[derive(Debug)]
enum Request {
    /// The out-of-balance force and member states at a point.
    Evaluate(EvalBuffers),
    /// A factorisation, collecting up to `max` failed pivots.
    Factor {
        matrix: BlockBandMatrix,
        failures: Vec<PivotFailure>,
        max: usize,
    },
    /// A solve with a factorised matrix, in place.
    Solve {
        matrix: BlockBandMatrix,
        rhs: Vec<f64>,
    },
}

/// The kernels a lane can wait for: requests of one kind and one structure run together.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// [`Request::Evaluate`].
    Evaluate,
    /// [`Request::Factor`].
    Factor,
    /// [`Request::Solve`].
    Solve,
}

impl Request {
    /// Which kernel.
    fn kind(&self) -> Kind {
        match self {
            Request::Evaluate(_) => Kind::Evaluate,
            Request::Factor { .. } => Kind::Factor,
            Request::Solve { .. } => Kind::Solve,
        }
    }
}

/// A request posted by a lane: its structure, which sample, and the request.
#[derive(Debug)]
struct Posted {
    structure: Arc<Structure>,
    key: SampleKey,
    request: Request,
}

/// One lane's mailbox: the request its solve waits for, answered in place (the kernels
/// work on the request's buffers where they lie).
#[derive(Debug, Default)]
pub struct LaneSlot {
    posted: RefCell<Option<Posted>>,
    answered: Cell<bool>,
    evaluation: Cell<Option<Evaluation>>,
    /// Rounds this lane's request has waited while other kernels ran.
    waited: Cell<u32>,
}

impl LaneSlot {
    /// Posts `request` and waits for the batch to answer it; returns the request's
    /// buffers, with the evaluation for an evaluation.
    async fn ask(
        &self,
        structure: &Arc<Structure>,
        key: SampleKey,
        request: Request,
    ) -> (Request, Option<Evaluation>) {
        *self.posted.borrow_mut() = Some(Posted {
            structure: Arc::clone(structure),
            key,
            request,
        });
        self.answered.set(false);
        std::future::poll_fn(|_| {
            if self.answered.get() {
                let posted = self.posted.borrow_mut().take().expect("answered in place");
                Poll::Ready((posted.request, self.evaluation.take()))
            } else {
                Poll::Pending
            }
        })
        .await
    }

    /// Whether the lane's solve waits for a kernel that has not run yet (polling it would
    /// do nothing).
    pub fn waiting(&self) -> bool {
        !self.answered.get() && self.posted.borrow().is_some()
    }
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

/// One structure's batched kernels.
#[derive(Debug)]
struct StructureLanes {
    /// `None` for a structure above [`BATCHED_DOFS`]: its lanes' kernels run one lane at a
    /// time.
    batched: Option<(EvalLanes<LANES>, BandLanes<LANES>)>,
}

/// Structures with more unknowns than this run their lanes' kernels one lane at a time: the
/// lanes' copies of a tall tower's band and members outgrow the caches (300 stages, 2,700
/// unknowns: 0.82 times the speed of one sample at a time, though with 22 % fewer
/// instructions; 30 stages, 270 unknowns: 1.22 times).
pub const BATCHED_DOFS: usize = 1024;

/// The batched kernels' buffers, one set per structure met (a batch's lanes may hold
/// samples of different cases; each structure's lanes run together).
#[derive(Debug)]
pub struct BatchKernels {
    arch: pulp::Arch,
    /// Structures with more unknowns run one lane at a time ([`BATCHED_DOFS`]).
    batched_dofs: usize,
    structures: Vec<(Arc<Structure>, StructureLanes)>,
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
            batched_dofs: BATCHED_DOFS,
            structures: Vec::new(),
        }
    }

    /// The kernels of `structure`, made on first use.
    fn of(&mut self, structure: &Arc<Structure>) -> &mut StructureLanes {
        let at = match self
            .structures
            .iter()
            .position(|(s, _)| Arc::ptr_eq(s, structure))
        {
            Some(i) => i,
            None => {
                let lanes = StructureLanes {
                    batched: (structure.free <= self.batched_dofs).then(|| {
                        (
                            EvalLanes::new(structure, self.arch),
                            BandLanes::new(
                                structure.nominal.blocks(),
                                structure.nominal.bandwidth(),
                                self.arch,
                            ),
                        )
                    }),
                };
                self.structures.push((Arc::clone(structure), lanes));
                self.structures.len() - 1
            }
        };
        &mut self.structures[at].1
    }

    /// Runs one kernel for the lanes that wait for it: the kernel (and structure) most
    /// lanes wait for, unless a lane has waited [`PATIENCE`] rounds, whose kernel then
    /// runs. The other lanes keep waiting, so that lanes fall into step (a kernel run for
    /// one lane costs as much as for four). Returns how many lanes were answered.
    pub fn run(&mut self, slots: &LaneSlots) -> usize {
        let Some((structure, kind)) = choose(slots) else {
            return 0;
        };
        let mut posted: [Option<std::cell::RefMut<'_, Option<Posted>>>; LANES] =
            std::array::from_fn(|l| {
                let slot = &slots.slots[l];
                let p = slot.posted.borrow_mut();
                let chosen = !slot.answered.get()
                    && p.as_ref().is_some_and(|p| {
                        p.request.kind() == kind && Arc::ptr_eq(&p.structure, &structure)
                    });
                if chosen {
                    slot.waited.set(0);
                    Some(p)
                } else {
                    if p.is_some() && !slot.answered.get() {
                        slot.waited.set(slot.waited.get() + 1);
                    }
                    None
                }
            });
        let Some((evaluation, band)) = &mut self.of(&structure).batched else {
            for (slot, p) in slots.slots.iter().zip(posted.iter_mut()) {
                let Some(p) = p.as_mut().and_then(|p| p.as_mut()) else {
                    continue;
                };
                match &mut p.request {
                    Request::Evaluate(b) => slot.evaluation.set(Some(evaluate_with(
                        &structure,
                        &b.members,
                        b.tension.iter().copied(),
                        &b.loads,
                        &b.u,
                        &mut b.r,
                        &mut b.states,
                    ))),
                    Request::Factor {
                        matrix,
                        failures,
                        max,
                    } => matrix.factor_collecting(failures, *max),
                    Request::Solve { matrix, rhs } => {
                        let n = matrix.size();
                        matrix.solve_in_place(&mut rhs[..n]);
                    }
                }
                slot.answered.set(true);
            }
            return posted.iter().flatten().count();
        };
        let mut mine = posted
            .iter_mut()
            .map(|p| p.as_mut().and_then(|p| p.as_mut()));
        match kind {
            Kind::Evaluate => {
                let mut io: [Option<(SampleKey, &mut EvalBuffers)>; LANES] =
                    std::array::from_fn(|_| match mine.next().flatten() {
                        Some(Posted {
                            key,
                            request: Request::Evaluate(b),
                            ..
                        }) => Some((*key, b)),
                        _ => None,
                    });
                let evaluations = evaluation.evaluate(&structure, &mut io);
                for (slot, e) in slots.slots.iter().zip(evaluations) {
                    if e.is_some() {
                        slot.evaluation.set(e);
                    }
                }
            }
            Kind::Factor => {
                let mut io: [Option<FactorLane<'_>>; LANES] =
                    std::array::from_fn(|_| match mine.next().flatten() {
                        Some(Posted {
                            request:
                                Request::Factor {
                                    matrix,
                                    failures,
                                    max,
                                },
                            ..
                        }) => Some((matrix, failures, *max)),
                        _ => None,
                    });
                band.factor(&mut io);
            }
            Kind::Solve => {
                let mut io: [Option<SolveLane<'_>>; LANES] =
                    std::array::from_fn(|_| match mine.next().flatten() {
                        Some(Posted {
                            request: Request::Solve { matrix, rhs },
                            ..
                        }) => {
                            let n = matrix.size();
                            Some((&*matrix, &mut rhs[..n]))
                        }
                        _ => None,
                    });
                band.solve(&mut io);
            }
        }
        let mut answered = 0;
        for (slot, p) in slots.slots.iter().zip(&posted) {
            if p.is_some() {
                slot.answered.set(true);
                answered += 1;
            }
        }
        answered
    }
}

/// Rounds a lane's request may wait while other kernels run before its own runs. Longer
/// waits fill more lanes per kernel: measured with cachegrind (whole `mc-shard run`, one
/// thread), 8 rounds against 2 take 2.0 % fewer instructions for the rigid 5-stage prism,
/// 1.5 % for the 30-stage one, 1.6 % for the Fig. 16 case and 2.9 % for pin joints with
/// taut diagonals; 32 and 1,000 gain nothing more. Which lane runs when never changes a
/// result (see the module doc).
pub const PATIENCE: u32 = 8;

/// The kernel to run next (see [`BatchKernels::run`]): its structure and kind.
fn choose(slots: &LaneSlots) -> Option<(Arc<Structure>, Kind)> {
    let posted: [_; LANES] = std::array::from_fn(|l| slots.slots[l].posted.borrow());
    let same = |a: &Posted, b: &Posted| {
        a.request.kind() == b.request.kind() && Arc::ptr_eq(&a.structure, &b.structure)
    };
    let mut best: Option<(bool, usize, usize)> = None;
    let waiting: [bool; LANES] = std::array::from_fn(|l| !slots.slots[l].answered.get());
    for (l, p) in posted.iter().enumerate() {
        let Some(p) = p.as_ref().filter(|_| waiting[l]) else {
            continue;
        };
        let count = posted
            .iter()
            .zip(waiting)
            .filter(|(q, w)| *w && q.as_ref().is_some_and(|q| same(p, q)))
            .count();
        let overdue = slots.slots[l].waited.get() >= PATIENCE;
        if best.is_none_or(|(o, c, _)| (overdue, count) > (o, c)) {
            best = Some((overdue, count, l));
        }
    }
    let (_, _, l) = best?;
    let p = posted[l].as_ref().expect("chosen");
    Some((Arc::clone(&p.structure), p.request.kind()))
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
                let buffers = EvalBuffers {
                    members: std::mem::take(e.members),
                    tension: std::mem::take(e.tension),
                    loads: std::mem::take(e.loads),
                    u: std::mem::take(e.u),
                    r: std::mem::take(e.r),
                    states: std::mem::take(e.states),
                };
                let answer = slot
                    .ask(e.structure, e.key, Request::Evaluate(buffers))
                    .await;
                let (Request::Evaluate(b), Some(evaluation)) = answer else {
                    unreachable!("an evaluation is answered with an evaluation")
                };
                (*e.members, *e.tension, *e.loads) = (b.members, b.tension, b.loads);
                (*e.u, *e.r, *e.states) = (b.u, b.r, b.states);
                evaluation
            }
        }
    }

    /// Factorises `matrix` in place, collecting up to `max` failed pivots into `failures`
    /// (see [`BlockBandMatrix::factor_collecting`]): at once, or in the batch.
    pub(super) async fn factor(
        self,
        structure: &Arc<Structure>,
        key: SampleKey,
        matrix: &mut BlockBandMatrix,
        failures: &mut Vec<PivotFailure>,
        max: usize,
    ) {
        match self {
            Kernels::OneSample => matrix.factor_collecting(failures, max),
            Kernels::Lane(slot) => {
                let request = Request::Factor {
                    matrix: std::mem::replace(matrix, BlockBandMatrix::new(0, 0)),
                    failures: std::mem::take(failures),
                    max,
                };
                let answer = slot.ask(structure, key, request).await;
                let (
                    Request::Factor {
                        matrix: m,
                        failures: f,
                        ..
                    },
                    _,
                ) = answer
                else {
                    unreachable!("a factorisation is answered with its matrix")
                };
                (*matrix, *failures) = (m, f);
            }
        }
    }

    /// Solves `matrix·x = b` in place in the first `matrix.size()` entries of `rhs`, with
    /// `matrix` factorised (see [`BlockBandMatrix::solve_in_place`]): at once, or in the
    /// batch.
    pub(super) async fn solve(
        self,
        structure: &Arc<Structure>,
        key: SampleKey,
        matrix: &mut BlockBandMatrix,
        rhs: &mut Vec<f64>,
    ) {
        match self {
            Kernels::OneSample => {
                let n = matrix.size();
                matrix.solve_in_place(&mut rhs[..n]);
            }
            Kernels::Lane(slot) => {
                let request = Request::Solve {
                    matrix: std::mem::replace(matrix, BlockBandMatrix::new(0, 0)),
                    rhs: std::mem::take(rhs),
                };
                let answer = slot.ask(structure, key, request).await;
                let (Request::Solve { matrix: m, rhs: b }, _) = answer else {
                    unreachable!("a solve is answered with its matrix")
                };
                (*matrix, *rhs) = (m, b);
            }
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
