//! Many samples per pass: the solves of `W` samples of a case run side by side, each in its
//! own lane, and the kernels they wait for run once for all of them, as vector instructions
//! over `W` lanes.
//!
//! ## How
//! A solve is written once, as an `async` function of the [`Solver`](super::Solver) whose
//! kernels are awaited through its [`Kernels`]: [`Kernels::OneSample`] runs each kernel at
//! once (the future never waits; [`finish`] drives it), [`Kernels::Lane`] posts the kernel's
//! request in the lane's [`LaneSlot`] and waits. A driver ([`run_lanes`], used by the one
//! sample engine of `truss-job`) polls the solves' futures until each waits or is done, then
//! calls [`BatchKernels::run`], and polls the answered ones again. A slot whose solve is
//! done is refilled with the next sample, so a slow sample holds no other. Where kernels
//! are most of a solve's cost, twice as many solves as lanes are in flight
//! ([`in_flight_for`]), so that a kernel finds more of them waiting for it; a solve then
//! runs each kernel in whichever lane is free, preferably one whose caches hold its sample.
//!
//! The batched kernels are the three that cost most in a solve of the paper's prism:
//! - the member evaluation (out-of-balance force, member states and strain energy at a
//!   point; the `evaluate` module);
//! - the factorisation of the tangent and the triangular solves with it (the `band`
//!   module; a lane keeps its factor for the solves that reuse it);
//!
//! while the rest of a solve (the linearised start and its Woodbury solves, assembly, the
//! line search's arithmetic) runs in each lane's own code. Each round runs one kernel: the
//! one most solves wait for, unless one has waited [`PATIENCE`] rounds; the others keep
//! waiting, so that solves fall into step (a kernel costs as much for one lane as for four).
//! Structures above [`BATCHED_DOFS`] unknowns run their lanes' kernels one lane at a time.
//!
//! ## Bit for bit
//! Every lane performs exactly the IEEE operations of the one-sample path, in the same order
//! (see the `evaluate` and `band` modules): no fused multiply-add, no sum across lanes, no
//! decision in one lane that depends on another. The control flow of a solve (iterations,
//! line-search trials, slack sets) is the same code in both paths. So a sample's bytes
//! depend neither on its lane, nor on its neighbours, nor on `W` or how many solves are in
//! flight, nor on the instruction set
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

/// The most solves in flight per batch ([`run_lanes`]'s `in_flight`): twice the kernels'
/// lanes, so that a kernel finds more of them waiting for it.
pub const IN_FLIGHT: usize = 2 * LANES;

/// The solves a batch keeps in flight for `structure`: [`IN_FLIGHT`] where factorisations
/// are most of what a solve costs (a model solved at the limit `r → 0`, whose samples
/// factorise about 23 times each against 1.4 for the rigid 5-stage prism, or one larger
/// than that prism), else [`LANES`], one per lane.
///
/// With one solve per lane, a kernel runs for 2.4 to 3.1 lanes on average (the solves wait
/// for different kernels), at about the cost of four. With twice as many in flight it
/// runs for 3.5 to 3.8, but eight solves share four lanes' caches (a sample's member
/// constants, a factor for its solves), which then are gathered again. Measured with
/// cachegrind (whole `mc-shard run`, one thread, instructions against one per lane): the
/// paper's Fig. 16 case −7.4 %, the 10- and 30-stage prisms (90 and 270 unknowns) −7.5 %,
/// but the rigid 5-stage prism (45) +1.7 %, whose kernels are cheap beside its one-sample
/// work. Above [`BATCHED_DOFS`] the kernels run one lane at a time anyway. Which solve runs
/// in which lane never changes a result (see the module doc).
pub fn in_flight_for(structure: &Structure) -> usize {
    let n = structure.free_dofs();
    if n <= BATCHED_DOFS && (structure.near_the_limit() || n > WIDE_UNKNOWNS) {
        IN_FLIGHT
    } else {
        LANES
    }
}

/// Models of more unknowns than this (the paper's 5-stage prism) keep [`IN_FLIGHT`] solves
/// in flight ([`in_flight_for`]).
pub const WIDE_UNKNOWNS: usize = 45;

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
    /// A factorisation, collecting up to `max` failed pivots, from block row `from` (the
    /// rows before hold their factor: [`BlockBandMatrix::refactor_collecting`]). Both fit
    /// in 32 bits (a band of at most 2³² rows), so that the request is no larger than an
    /// evaluation's, which moves far more often.
    Factor {
        matrix: BlockBandMatrix,
        failures: Vec<PivotFailure>,
        max: u32,
        from: u32,
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
    slots: [LaneSlot; IN_FLIGHT],
    /// Solves in flight: the first this many slots hold them.
    in_flight: usize,
}

impl Default for LaneSlots {
    fn default() -> Self {
        Self {
            slots: std::array::from_fn(|_| LaneSlot::default()),
            in_flight: LANES,
        }
    }
}

impl LaneSlots {
    /// Mailboxes for `in_flight` solves (at most [`IN_FLIGHT`]).
    pub fn new(in_flight: usize) -> Self {
        Self {
            in_flight: in_flight.clamp(1, IN_FLIGHT),
            ..Self::default()
        }
    }

    /// How many solves these mailboxes serve.
    pub fn in_flight(&self) -> usize {
        self.in_flight
    }

    /// Solve `l`'s mailbox, `l <` [`LaneSlots::in_flight`].
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

    /// Runs one kernel for the solves that wait for it: the kernel (and structure) most
    /// solves wait for, unless one has waited [`PATIENCE`] rounds, whose kernel then runs,
    /// for at most [`LANES`] of them (those that waited longest, each preferably in a lane
    /// whose caches hold its sample). The others keep waiting, so that solves fall into step
    /// (a kernel run for one lane costs as much as for four). Returns how many solves were
    /// answered.
    pub fn run(&mut self, slots: &LaneSlots) -> usize {
        let asked = asked(slots);
        let Some(first) = choose(&asked) else {
            return 0;
        };
        let Some(chosen) = asked[first] else {
            return 0;
        };
        let kind = chosen.kind;
        let structure = {
            let posted = slots.slots[first].posted.borrow();
            let p = posted.as_ref().expect("a solve that asked has posted");
            Arc::clone(&p.structure)
        };
        let lanes = self.of(&structure);
        let wants = |a: &Asked| a.same_kernel(&chosen);
        let lane_of = match (&lanes.batched, slots.in_flight > LANES) {
            (Some((evaluation, band)), true) => {
                // The lane whose caches already hold what a solve's request needs: its
                // factor for a solve, else its sample's member constants (where its last
                // factor is likely held).
                let cached = |s: usize, a: &Asked| {
                    let sample = evaluation.lane_caching(a.key);
                    match &slots.slots[s].posted.borrow().as_ref()?.request {
                        Request::Solve { matrix, .. } => {
                            band.lane_holding(matrix.identity()).or(sample)
                        }
                        _ => sample,
                    }
                };
                // A lane whose caches belong to no solve in flight (its sample ended): taken
                // before one whose caches another solve will want again.
                let dead = |l: usize| {
                    evaluation
                        .cached_sample(l)
                        .is_none_or(|key| !asked.iter().flatten().any(|a| a.key == key))
                };
                assign_lanes(&asked, wants, cached, dead)
            }
            // No lanes' caches (the kernels run one lane at a time).
            (None, true) => assign_lanes(&asked, wants, |_, _| None, |_| true),
            // One solve per lane: each keeps its own.
            (_, false) => {
                std::array::from_fn(|l| asked[l].as_ref().is_some_and(wants).then_some(l))
            }
        };
        for (slot, a) in slots.slots.iter().zip(&asked) {
            if a.is_some() {
                slot.waited.set(slot.waited.get() + 1);
            }
        }
        // Kernel lane `l` serves the solve in slot `lane_of[l]`.
        let mut posted: [Option<std::cell::RefMut<'_, Option<Posted>>>; LANES] =
            std::array::from_fn(|l| {
                lane_of[l].map(|s| {
                    slots.slots[s].waited.set(0);
                    slots.slots[s].posted.borrow_mut()
                })
            });
        let served = lane_of.map(|s| s.map(|s| &slots.slots[s]));
        let Some((evaluation, band)) = &mut lanes.batched else {
            for (slot, p) in served.iter().zip(posted.iter_mut()) {
                let Some(slot) = slot else {
                    continue;
                };
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
                        from,
                    } => matrix.refactor_collecting(*from as usize, failures, *max as usize),
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
                for (slot, e) in served.iter().zip(evaluations) {
                    if let (Some(slot), Some(_)) = (slot, e) {
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
                                    from,
                                },
                            ..
                        }) => {
                            // Batched solves never restart from a later row
                            // (`Kernels::refactors_from_a_row`): the batched kernel
                            // factorises whole matrices only.
                            assert_eq!(*from, 0, "a batched factorisation restarted at a row");
                            Some((matrix, failures, *max as usize))
                        }
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
        for slot in served.iter().flatten() {
            slot.answered.set(true);
            answered += 1;
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

/// What a solve waits for, read once per round: its kernel (kind and structure), its
/// sample, and how many rounds it has waited.
#[derive(Debug, Clone, Copy)]
struct Asked {
    kind: Kind,
    structure: *const Structure,
    key: SampleKey,
    waited: u32,
}

impl Asked {
    /// Whether both wait for the same kernel: of one kind, for one structure.
    fn same_kernel(&self, other: &Asked) -> bool {
        self.kind == other.kind && std::ptr::eq(self.structure, other.structure)
    }
}

/// What each slot's solve waits for (`None`: answered, or no solve).
fn asked(slots: &LaneSlots) -> [Option<Asked>; IN_FLIGHT] {
    std::array::from_fn(|s| {
        let slot = &slots.slots[s];
        if s >= slots.in_flight || slot.answered.get() {
            return None;
        }
        let posted = slot.posted.borrow();
        let p = posted.as_ref()?;
        Some(Asked {
            kind: p.request.kind(),
            structure: Arc::as_ptr(&p.structure),
            key: p.key,
            waited: slot.waited.get(),
        })
    })
}

/// The slots a kernel serves, by kernel lane: of the solves that `wants` (those waiting for
/// it), at most [`LANES`], those that waited longest first (then in slot order); each in
/// the lane whose caches hold what its request needs (`cached`: a sample's member
/// constants, a factor for its solves) where that is free, else in its own lane
/// (`slot % LANES`: with [`LANES`] solves in flight, each keeps its lane), else in a free
/// lane whose caches no solve in flight needs (`dead`), else in the first free one.
fn assign_lanes(
    asked: &[Option<Asked>; IN_FLIGHT],
    wants: impl Fn(&Asked) -> bool,
    cached: impl Fn(usize, &Asked) -> Option<usize>,
    dead: impl Fn(usize) -> bool,
) -> [Option<usize>; LANES] {
    let mut order: [usize; IN_FLIGHT] = [0; IN_FLIGHT];
    let mut count = 0;
    for (s, a) in asked.iter().enumerate() {
        if a.as_ref().is_some_and(&wants) {
            order[count] = s;
            count += 1;
        }
    }
    let waited = |s: usize| asked[s].map_or(0, |a| a.waited);
    let order = &mut order[..count];
    // Stable: equal waits keep slot order.
    order.sort_by_key(|&s| std::cmp::Reverse(waited(s)));
    let order = &order[..count.min(LANES)];
    let mut lane_of: [Option<usize>; LANES] = [None; LANES];
    let mut placed = [false; IN_FLIGHT];
    for &s in order {
        let own = asked[s].as_ref().and_then(|a| cached(s, a));
        if let Some(own) = own.filter(|&l| lane_of[l].is_none()) {
            lane_of[own] = Some(s);
            placed[s] = true;
        }
    }
    for &s in order.iter().filter(|&&s| !placed[s]) {
        let free = Some(s % LANES)
            .filter(|&l| lane_of[l].is_none())
            .or_else(|| (0..LANES).find(|&l| lane_of[l].is_none() && dead(l)))
            .or_else(|| (0..LANES).find(|&l| lane_of[l].is_none()));
        if let Some(l) = free {
            lane_of[l] = Some(s);
        }
    }
    lane_of
}

/// The slot whose kernel runs next (see [`BatchKernels::run`]): of the kernel most solves
/// wait for (at most [`LANES`] count), unless one has waited [`PATIENCE`] rounds.
fn choose(asked: &[Option<Asked>; IN_FLIGHT]) -> Option<usize> {
    let mut best: Option<(bool, usize, usize)> = None;
    for (s, a) in asked.iter().enumerate() {
        let Some(a) = a else {
            continue;
        };
        // A kernel serves at most `LANES` solves.
        let count = asked
            .iter()
            .flatten()
            .filter(|b| b.same_kernel(a))
            .count()
            .min(LANES);
        let overdue = a.waited >= PATIENCE;
        if best.is_none_or(|(o, c, _)| (overdue, count) > (o, c)) {
            best = Some((overdue, count, s));
        }
    }
    best.map(|(_, _, s)| s)
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

    /// Whether a factorisation of `structure` may start again from a later block row
    /// ([`Kernels::refactor`]): where its factorisations run one lane at a time (one sample
    /// at a time, or a structure above [`BATCHED_DOFS`]). The batched kernel factorises
    /// whole matrices only: a version that started each lane at its own row ran from the
    /// earliest of its four, rarely a late one, and its rows' masks cost more than that
    /// saved (the paper's Fig. 16 case: 0.6 % more instructions a sample).
    pub(super) fn refactors_from_a_row(self, structure: &Structure) -> bool {
        match self {
            Kernels::OneSample => true,
            Kernels::Lane(_) => structure.free_dofs() > BATCHED_DOFS,
        }
    }

    /// Factorises `matrix` in place from block row `from`, collecting up to `max` failed
    /// pivots into `failures`: 0, the whole matrix (see
    /// [`BlockBandMatrix::factor_collecting`]); later, its earlier rows holding their
    /// factor and `failures` the last factorisation's (see
    /// [`BlockBandMatrix::refactor_collecting`]). At once, or in the batch.
    pub(super) async fn refactor(
        self,
        structure: &Arc<Structure>,
        key: SampleKey,
        matrix: &mut BlockBandMatrix,
        failures: &mut Vec<PivotFailure>,
        max: usize,
        from: usize,
    ) {
        match self {
            Kernels::OneSample => matrix.refactor_collecting(from, failures, max),
            Kernels::Lane(slot) => {
                let request = Request::Factor {
                    matrix: std::mem::replace(matrix, BlockBandMatrix::new(0, 0)),
                    failures: std::mem::take(failures),
                    max: u32::try_from(max).unwrap_or(u32::MAX),
                    from: u32::try_from(from).unwrap_or(u32::MAX),
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
