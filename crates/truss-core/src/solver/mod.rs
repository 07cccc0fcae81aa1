//! Newton's method on the total potential energy, with a line search, for one sample at a time.
//!
//! ## Algorithm
//!
//! Equilibrium is the stationary point of `Π(u) = Σ_m W_m(u) − fᵀu` (see [`crate::element`]);
//! its gradient is the out-of-balance force `r(u) = g(u) − f` \[N\], its Hessian the tangent
//! stiffness `K(u)` \[N/mm\].
//!
//! 1. **The linearised problem, exactly.** With linear kinematics the energy is convex and
//!    piecewise quadratic in the set of slack cables; its minimiser is found by an
//!    active-set iteration from the shared factorisation of the all-taut stiffness `K₀`
//!    (see the `linearised` module; models with many cables, and pieces whose slack set
//!    is too large for the Woodbury update, factorise each piece's stiffness instead).
//!    Where every panel keeps a taut diagonal, this point is close to the answer (the
//!    length errors are µm on 380 mm members) with its slack set. A panel whose bracing
//!    is all slack is held only by the slack cables' compression stiffness and the
//!    geometric stiffness of the member forces, which `K_S` lacks: there the linearised
//!    point can be off by percents and its slack set wrong, and its capacitance matrix
//!    says so (a soft pivot), so the solver goes straight to Newton steps (3). In the
//!    paper's prism nearly every sample has such a panel: with σ = 6.3 µm on battens and
//!    longerons, 6.2 of its 15 panels on average, and 5 samples in 2,000 none (those take
//!    4.0 iterations, the others 4.3 to 5.7, more with more such panels: the bench prints
//!    it). [`SolveReport::soft_directions`] counts them.
//! 2. **Chord steps** `d = −K_S⁻¹·r(u)` with the linearised stiffness `K_S` of the current
//!    slack set (a Woodbury update of `K₀`, no factorisation of the full matrix), while they
//!    contract by at least [`SolveOptions::reuse_contraction`] per step.
//! 3. **Newton steps** `d = −K(u)⁻¹·r(u)` with the true tangent, used when chord steps stop
//!    contracting (a panel whose bracing is slack, where the geometric stiffness of the
//!    member forces outweighs the slack cables' small stiffness) or when step 1 fails. A
//!    factorisation is reused while the slack set is unchanged and steps contract. Where
//!    `K(u)` is not positive definite, `K + μ·diag(K)` is used with the smallest `μ` of
//!    1e-9, 1e-7, …, 1e3 that is: a descent direction either way.
//! 4. **Line search** on `φ(α) = Π(u + α·d)` using only its derivative
//!    `φ'(α) = r(u + α·d)·d`, never differences of `Π` (which cancel at this precision): the
//!    full step is taken when `φ'(1) ≤ η·|φ'(0)|` (η = 0.5), else a root of `φ'` in
//!    `(0, 1)` is bracketed (false position, bisecting when the bracket stops halving) until
//!    `|φ'(α)| ≤ η·|φ'(0)|`. `φ'` is continuous because `Π` is continuously differentiable
//!    where cables go slack. A chord step's first trial is not the full step but the
//!    secant root of `φ'` along the last chord step, `α₀·φ₀'(0)/(φ₀'(0) − φ₀'(α₀))`
//!    ([`SolveOptions::chord_secant`]): the chord operator, an earlier tangent, is too
//!    stiff or too soft by about the same factor from one step to the next (in the
//!    directions of the panels whose bracing is slack), and the last step measured it.
//! 5. **Convergence** when either the out-of-balance force is at the rounding floor,
//!    `‖r‖∞ ≤ max(residual_floor·F, 4·ε·k_max·‖u‖∞)` with `F` the largest member force and
//!    `k_max` the stiffest member's `E·A/L₀` (the second term is the force's rounding
//!    noise where the displacements are large, as in a tall tower), or the last step
//!    satisfies `‖α·d‖∞ ≤ step_tolerance·‖u‖∞` and the error it leaves is no larger than the
//!    step (a fresh tangent's quadratic convergence, or a measured contraction ≤ ½), or the
//!    force has stopped falling within a thousand times the floor (an ill-conditioned tall
//!    tower, whose rounding noise keeps the steps from shrinking further).
//!    Both tests are relative, so scaling every length error by `c` scales the answer by
//!    `c` (no length scale enters). With the defaults the displacements, and with them θ_P,
//!    are resolved to about 1e-12 relative (tested to be better than 1e-9).
//!
//! ## Which equilibrium
//!
//! A few samples have two stable equilibria: about 1.5 % of the §3.4 samples at 10 stages
//! (6 of 400; 4 of 400 at 20 and at 30 stages), with the same number of slack cables,
//! energies a ridge apart, and θ_P differing by up to 5e-4 relative. The answer is the one
//! this algorithm reaches: a function of the model and the sample only (never of threads,
//! shards or machine), pinned with the algorithm by the numerics version. We do not claim it
//! is *the* physical one, and no rule built on the model alone would be: which state a
//! built truss takes depends on its assembly history, which the model does not represent;
//! "the lowest energy" needs every equilibrium found, and "the one energy descent from the
//! linearised solution reaches" is not well defined (two slow descents from it end in
//! different states; see the solver tests `a_sample_with_two_stable_equilibria` and
//! `descents_from_the_linearised_solution_end_in_different_equilibria`). The effect on the
//! statistics is below what they resolve: the paper-3.4 report is identical to four
//! significant digits whichever state those samples take (numerics 2 and 3 differ on three
//! such samples), while θ_P95's 95 % interval is about ±3 %.
//!
//! ## Allocation
//!
//! A [`Solver`] owns all its buffers; [`Solver::solve`] allocates nothing unless iteration
//! records are requested.

use crate::block::BlockBandMatrix;
use crate::element::{AxialMember, AxialState};
use crate::joint::{BandState, JointEnd, JointState, JointSummary, joint_state};
use crate::linearised::ActiveSet;
use crate::measure::{Distortion, distortion};
use crate::structure::Structure;
use crate::{ModelError, SolveError};
use evaluate::{Evaluation, dot_n};
pub use held::{HOLDING_FRACTION, Holding, HoldingLimit};
use lanes::{Kernels, finish};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

mod evaluate;
mod floating;
mod held;
mod holding;
mod kept;
pub mod lanes;
mod limit;
mod line_search;
mod newton;
mod step;

/// Options of the Newton solver.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    /// Most linear solves before giving up.
    pub max_iterations: u32,
    /// Converged when the last step is at most this fraction of the largest displacement.
    pub step_tolerance: f64,
    /// Converged when the largest out-of-balance force is at most this fraction of the
    /// largest member force (about 500 times the rounding error of summing the forces).
    pub residual_floor: f64,
    /// Reuse a factorisation while the slack set is unchanged and steps shrink fast enough.
    pub reuse_factorisation: bool,
    /// Refactorise when a chord step is more than this fraction of the one before it.
    pub reuse_contraction: f64,
    /// Start the line search of a chord step at the last chord step's secant minimiser
    /// instead of the full step (step 4 of the module doc).
    pub chord_secant: bool,
    /// Record every iteration (residual, step, slack cables) for debugging.
    pub record_iterations: bool,
    /// After a solve whose tilt the bars do not frame (pin joints), compute whether a stage
    /// floats and how firmly the top surface is held ([`SolveReport::floating`],
    /// [`SolveReport::holding_force`]); at the limit of one-sided members, a factorisation
    /// of the true tangent and nine solves with it, about a quarter of a sample with taut
    /// diagonals (the default: true). Off for callers that read only the displacements (the
    /// diagnosis's simulations); the displacements are the same bits either way, and the
    /// report then says `floating: false` and `holding_force: None`, as for a model whose
    /// bars frame the tilt.
    pub holding: bool,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            max_iterations: 120,
            step_tolerance: 1e-12,
            residual_floor: 1e-13,
            reuse_factorisation: true,
            reuse_contraction: 0.05,
            chord_secant: true,
            record_iterations: false,
            holding: true,
        }
    }
}

/// What a sample changes in the model: per-member length errors, extra nodal loads, and
/// per-joint clearances.
#[derive(Debug, Clone, Copy, Default)]
pub struct Perturbation<'a> {
    /// Length error per member, in model order \[mm\] (natural length = model's + error);
    /// empty for none.
    pub length_errors: &'a [f64],
    /// Extra nodal force per node, in model order \[N\]; empty for none.
    pub extra_loads: &'a [[f64; 3]],
    /// Clearance per joint, in model order \[mm\] (≥ 0); empty for the model's own.
    pub clearances: &'a [f64],
}

/// How a solve went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// Linear solves (the first guess counts as one).
    pub iterations: u32,
    /// Tangent factorisations (the shared nominal one not counted).
    pub factorisations: u32,
    /// Final out-of-balance force, max over free DOFs \[N\].
    pub residual: f64,
    /// Size of the last step, max over free DOFs \[mm\].
    pub step: f64,
    /// Number of tension-only members that ended slack.
    pub slack_cables: u32,
    /// Evaluations of the out-of-balance force (line-search trials included).
    pub evaluations: u32,
    /// Number of joints whose shaft does not bear on its hole's edge: they carry no force
    /// (see [`crate::joint`]).
    pub loose_joints: u32,
    /// Soft directions of the linearised start's slack set, counted by the capacitance
    /// matrix's soft pivots (in the paper's prism, one per panel whose bracing is all
    /// slack: held only by the slack cables' compression stiffness and the geometric
    /// stiffness of the member forces, which the linearised problem lacks; each costs
    /// Newton iterations). 0 where the start was not solved by the capacitance matrix (a
    /// model with more than 96 cables, or a large slack set).
    pub soft_directions: u32,
    /// Whether some stage is held by nothing at the limit: the tangent of the members that
    /// bear (and the geometric stiffness of their forces) is not positive definite, so a
    /// stage moves under an arbitrarily small load (a *floating* stage; see
    /// [`crate::limit`]): the answer then rests on effects the model leaves out. Never where
    /// the model's bars frame the tilt, nor where [`SolveOptions::holding`] is off (not
    /// computed).
    pub floating: bool,
    /// The holding force \[N\]: the largest force on one node of the top surface that, to
    /// first order, moves θ_P by at most 1 % and makes no bearing one-sided member let go
    /// (0 where the equilibrium is not stable against some small load; see
    /// [`Solver::holding`]). Computed, like [`SolveReport::floating`], only where the
    /// model's bars do not frame the tilt, and [`SolveOptions::holding`] is on.
    pub holding_force: Option<f64>,
    /// Where the limit solver's last attempt at `ρ = 0` did not converge, the compression
    /// ratio `ρ` of the one-sided members at the equilibrium reported instead: the last
    /// stage the continuation reached, which stands for the limit (see [`crate::limit`] and
    /// the `limit` module of the solver). `None` where the equilibrium is the limit's own
    /// (`ρ = 0`) or the model is solved at its own ratios.
    pub limit_ratio: Option<f64>,
}

/// One Newton iteration, recorded when [`SolveOptions::record_iterations`] is set.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationRecord {
    /// Iteration number, from 1.
    pub iteration: u32,
    /// Out-of-balance force before the step, max over free DOFs \[N\].
    pub residual: f64,
    /// Size of the step taken, max over free DOFs \[mm\].
    pub step: f64,
    /// Line-search step length α.
    pub alpha: f64,
    /// Whether the tangent was factorised afresh for this step.
    pub refactorised: bool,
    /// Levenberg shift μ used (0 when the tangent was positive definite).
    pub shift: f64,
    /// Indices of the cables slack before the step.
    pub slack: Vec<usize>,
    /// Evaluations of the out-of-balance force so far in this solve.
    pub evaluations: u32,
}

/// The equilibrium of one sample, collected for output.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// How the solve went.
    pub report: SolveReport,
    /// Displacement of every node, model order \[mm\].
    pub displacements: Vec<[f64; 3]>,
    /// Axial force of every member, model order, tension positive \[N\].
    pub forces: Vec<f64>,
    /// Indices of the slack cables.
    pub slack: Vec<usize>,
    /// The top surface's tilt, if the model names a top surface.
    pub distortion: Option<Distortion>,
    /// Each joint's hole-centre offset from its shaft centre, model order \[mm\].
    pub joint_offsets: Vec<[f64; 3]>,
    /// Each joint's contact force (zero when loose), model order \[N\].
    pub joint_contacts: Vec<f64>,
    /// Indices of the loose joints.
    pub loose_joints: Vec<usize>,
}

/// Which operator approximates `K⁻¹` for the next step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// The linearised stiffness of the current slack set, by Woodbury from `K₀`.
    Chord,
    /// A factorisation in `Solver::k`: the true tangent, or the linearised stiffness.
    Tangent,
}

/// A Newton solver for one model, with all its buffers. Cheap to create from a shared
/// [`Structure`]; use one per thread.
#[derive(Debug, Clone)]
pub struct Solver {
    structure: Arc<Structure>,
    options: SolveOptions,
    /// Nominal length of the shortest member \[mm\] (caps a line search's steps).
    shortest: f64,
    /// The current sample's constants.
    sample: SampleConstants,
    /// The point, its states and the vectors the iteration works in.
    work: Workspace,
    /// The factorised stiffness and the slack set it belongs to.
    factor: FactorCache,
    /// What the next step carries over from the last one.
    step: StepState,
    log: Vec<IterationRecord>,
    last: Option<SolveReport>,
    /// The last converged sample's holding force and the load that reaches it.
    holding: Option<Holding>,
    /// The buffers of the solver for cables at their limit (see [`limit`]).
    limit: limit::work::LimitWork,
    evaluations: u32,
    /// The last chord step's secant minimiser along its line, relative to that step
    /// (NaN when the last step was not a chord step, or switched a one-sided member):
    /// the next chord step's first trial (see `line_search`).
    chord_secant: f64,
    /// Which sample the solver holds, for the batched kernels' buffers: a number unique to
    /// this solver in the process, and its count of samples set.
    sample_key: (usize, u64),
}

/// The next solver's number (see `Solver::sample_key`).
static SOLVERS: AtomicU64 = AtomicU64::new(0);

/// What a sample sets: members, loads and clearances, and its scales.
#[derive(Debug, Clone)]
struct SampleConstants {
    members: Vec<AxialMember>,
    /// Each member's `k = E·A/L₀` for the current sample \[N/mm\].
    tension: Vec<f64>,
    /// Each joint's clearance for the current sample \[mm\].
    clearances: Vec<f64>,
    loads: Vec<f64>,
    /// The sample's largest |initial stretch| \[mm\]: the scale of its displacements
    /// (with the shortest member's 1e-6, for samples driven by loads alone).
    scale: f64,
    /// The sample's force scale \[N\]: the largest `k·|s₀|` of its members and of its
    /// loads, so that a solution whose forces all vanish still has a rounding floor.
    force_ref: f64,
    /// The stiffest member's `k = E·A/L₀` \[N/mm\] (scales the rounding floor that the
    /// displacements set on the force).
    stiffest: f64,
}

/// The current point `u`, its out-of-balance force `r` and member states, the step `d`,
/// a trial point's, and scratch.
#[derive(Debug, Clone)]
struct Workspace {
    states: Vec<AxialState>,
    trial_states: Vec<AxialState>,
    slack: Vec<bool>,
    u: Vec<f64>,
    r: Vec<f64>,
    d: Vec<f64>,
    trial_u: Vec<f64>,
    trial_r: Vec<f64>,
    scratch: Vec<f64>,
    /// `∂θ_P/∂u` for the holding force (see the `holding` module).
    holding_gradient: Vec<f64>,
    /// Each member's rates of axial force per unit load along x, y, z at one top node
    /// \[N/N\] (see the `holding` module).
    holding_rates: Vec<[f64; 3]>,
    stretch: Vec<f64>,
    breakpoints: Vec<(f64, f64)>,
    failures: Vec<crate::block::PivotFailure>,
}

/// The factorised model stiffness in `k` and the slack set it was assembled for; the
/// linearised problem's active set and its capacitance factor.
#[derive(Debug, Clone)]
struct FactorCache {
    k: BlockBandMatrix,
    factor_slack: Vec<bool>,
    /// Cables a model step engaged (made to bear along a direction in which its model fell)
    /// and kept bearing through its pieces; kept until the next model step, which starts
    /// with them bearing at the limit of one-sided members (see `Solver::model_step`).
    locked: Vec<bool>,
    active: ActiveSet,
    /// The model stiffness of the current model step's point, unfactorised.
    kept: kept::KeptAssembly,
}

/// What the next step carries over from the last one.
#[derive(Debug, Clone)]
struct StepState {
    /// Levenberg damping μ of model steps (`K + μ·diag(K)`): 0, until steps stall.
    damping: f64,
    /// The next model step keeps the current slack set (the last one's switching did not
    /// come true).
    plain_step: bool,
    /// The slack set when the current step was chosen.
    step_slack: Vec<bool>,
    /// Cables pinned at their kink for the next model step.
    pinned: Vec<bool>,
}

impl Solver {
    /// A solver for `model` (compiles it; use [`Solver::with_structure`] to share).
    pub fn new(model: &crate::Model, options: SolveOptions) -> Result<Self, ModelError> {
        Ok(Self::with_structure(
            Arc::new(Structure::new(model)?),
            options,
        ))
    }

    /// A solver over a shared compiled structure.
    pub fn with_structure(structure: Arc<Structure>, options: SolveOptions) -> Self {
        let n = structure.free;
        let m = structure.members.len();
        let members: Vec<AxialMember> = structure
            .members
            .iter()
            .map(|c| structure.nominal_member(c, 0.0, structure.band_clearance(c, &[])))
            .collect();
        let cables = structure.members.iter().filter(|c| c.is_cable).count();
        let zero_state = members[0].state([0.0; 3]);
        Self {
            options,
            shortest: structure.shortest_member(),
            sample: SampleConstants {
                tension: members.iter().map(AxialMember::tension_stiffness).collect(),
                members,
                clearances: structure.joints.iter().map(|j| j.clearance).collect(),
                loads: vec![0.0; n + 1],
                scale: 0.0,
                force_ref: 0.0,
                stiffest: 0.0,
            },
            work: Workspace {
                states: vec![zero_state; m],
                trial_states: vec![zero_state; m],
                slack: vec![false; m],
                u: vec![0.0; n + 1],
                r: vec![0.0; n + 1],
                d: vec![0.0; n + 1],
                trial_u: vec![0.0; n + 1],
                trial_r: vec![0.0; n + 1],
                scratch: vec![0.0; n + 1],
                holding_gradient: vec![0.0; n + 1],
                holding_rates: vec![[0.0; 3]; m],
                stretch: vec![0.0; m],
                breakpoints: Vec::with_capacity(m),
                failures: Vec::with_capacity(64),
            },
            factor: FactorCache {
                k: BlockBandMatrix::new(structure.nominal.blocks(), structure.bandwidth()),
                factor_slack: vec![false; m],
                locked: vec![false; m],
                active: ActiveSet::new(cables),
                kept: kept::KeptAssembly::new(&structure),
            },
            step: StepState {
                damping: 0.0,
                plain_step: false,
                step_slack: vec![false; m],
                pinned: vec![false; m],
            },
            log: Vec::new(),
            last: None,
            holding: None,
            limit: limit::work::LimitWork::new(n),
            evaluations: 0,
            chord_secant: f64::NAN,
            sample_key: (SOLVERS.fetch_add(1, Ordering::Relaxed) as usize, 0),
            structure,
        }
    }

    /// The compiled structure.
    pub fn structure(&self) -> &Arc<Structure> {
        &self.structure
    }

    /// The options.
    pub fn options(&self) -> &SolveOptions {
        &self.options
    }

    /// Solves with per-member length errors \[mm\] (model order) and no extra loads.
    pub fn solve(&mut self, length_errors: &[f64]) -> Result<SolveReport, SolveError> {
        self.solve_perturbed(Perturbation {
            length_errors,
            ..Perturbation::default()
        })
    }

    /// Solves one sample. On success the solver holds its equilibrium (see
    /// [`Solver::displacement`], [`Solver::distortion`], [`Solver::equilibrium`]).
    pub fn solve_perturbed(&mut self, p: Perturbation<'_>) -> Result<SolveReport, SolveError> {
        finish(self.solve_perturbed_in(p, Kernels::OneSample))
    }

    /// [`Solver::solve_perturbed`], its kernels run by `kernels`: at once, or in a lane of
    /// a batch (see [`lanes`]). The same operations either way, so the same bits.
    pub async fn solve_perturbed_in(
        &mut self,
        p: Perturbation<'_>,
        kernels: Kernels<'_>,
    ) -> Result<SolveReport, SolveError> {
        self.last = None;
        self.holding = None;
        self.log.clear();
        self.evaluations = 0;
        self.sample_key.1 += 1;
        self.set_sample(p)?;
        let report = if self.structure.near_the_limit() {
            self.solve_limit(kernels).await?
        } else {
            self.newton(kernels).await?
        };
        self.last = Some(report);
        Ok(report)
    }

    /// Sets the per-sample member constants and loads, checking the input.
    fn set_sample(&mut self, p: Perturbation<'_>) -> Result<(), SolveError> {
        let s = &*self.structure;
        let m = s.model_members;
        if !p.length_errors.is_empty() && p.length_errors.len() != m {
            return Err(SolveError::Input(format!(
                "{} length errors for {m} members",
                p.length_errors.len()
            )));
        }
        if !p.extra_loads.is_empty() && p.extra_loads.len() != s.node_ids.len() {
            return Err(SolveError::Input(format!(
                "{} nodal loads for {} nodes",
                p.extra_loads.len(),
                s.node_ids.len()
            )));
        }
        if !p.clearances.is_empty() && p.clearances.len() != s.joints.len() {
            return Err(SolveError::Input(format!(
                "{} clearances for {} joints",
                p.clearances.len(),
                s.joints.len()
            )));
        }
        for (i, (g, c)) in self.sample.clearances.iter_mut().zip(&s.joints).enumerate() {
            let v = p.clearances.get(i).copied().unwrap_or(c.clearance);
            if !(v.is_finite() && v >= 0.0) {
                return Err(SolveError::Input(format!(
                    "joint {:?} (index {i}): clearance {v} mm is not a finite number ≥ 0",
                    c.id
                )));
            }
            *g = v;
        }
        for (i, c) in s.members.iter().enumerate() {
            let e = p.length_errors.get(c.model_member).copied().unwrap_or(0.0);
            if !e.is_finite() || c.natural_length + e <= 0.0 {
                return Err(SolveError::Input(format!(
                    "member {}: length error {e} mm leaves no positive natural length",
                    c.model_member
                )));
            }
            let gap = s.band_clearance(c, &self.sample.clearances);
            self.sample.members[i] = s.nominal_member(c, e, gap);
            self.sample.tension[i] = self.sample.members[i].tension_stiffness();
        }
        self.sample.scale = self
            .sample
            .members
            .iter()
            .map(|m| m.initial_stretch.abs())
            .fold(1e-6 * self.shortest, f64::max);
        self.sample.force_ref = self
            .sample
            .members
            .iter()
            .zip(&self.sample.tension)
            .map(|(m, k)| k * m.initial_stretch.abs())
            .chain(self.sample.loads.iter().map(|f| f.abs()))
            .fold(0.0, f64::max);
        self.sample.stiffest = self.sample.tension.iter().copied().fold(0.0, f64::max);
        self.chord_secant = f64::NAN;
        self.step.damping = 0.0;
        self.step.plain_step = false;
        self.step.pinned.fill(false);
        self.factor.locked.fill(false);
        self.sample.loads.copy_from_slice(&s.loads);
        for (node, f) in p.extra_loads.iter().enumerate() {
            if f.iter().any(|x| !x.is_finite()) {
                return Err(SolveError::Input(format!(
                    "extra load on node {:?} is not finite",
                    s.node_ids[node]
                )));
            }
            for (dir, &fd) in f.iter().enumerate() {
                let dof = s.node_dofs[node][dir];
                if dof != crate::structure::FIXED {
                    self.sample.loads[dof as usize] += fd;
                }
            }
        }
        Ok(())
    }

    /// The last successful solve's report.
    pub fn last_report(&self) -> Option<SolveReport> {
        self.last
    }

    /// The last successful solve's holding force, with the load on the top surface that
    /// reaches it and what it reaches (see [`SolveReport::holding_force`]).
    pub fn holding(&self) -> Option<Holding> {
        self.holding
    }

    /// Displacement of node `node` at the last equilibrium \[mm\]: a hole node's is its
    /// shaft's plus its joint's offset.
    pub fn displacement(&self, node: usize) -> [f64; 3] {
        let s = &self.structure;
        if let Some(j) = s.hole_joint[node] {
            let shaft = self.displacement(s.joints[j].shaft);
            let o = self.joint_state(j).offset;
            return [shaft[0] + o[0], shaft[1] + o[1], shaft[2] + o[2]];
        }
        s.node_dofs[node].map(|d| {
            if d == crate::structure::FIXED {
                0.0
            } else {
                self.work.u[d as usize]
            }
        })
    }

    /// Axial force of model member `m` at the last equilibrium, tension positive \[N\]: for
    /// a member in clearance holes, the sum of its two halves.
    pub fn member_force(&self, m: usize) -> f64 {
        match &self.structure.members[m].band {
            Some(b) => self.work.states[m].force + self.work.states[b.partner].force,
            None => self.work.states[m].force,
        }
    }

    /// The state of joint `j` at the last equilibrium, from its member's (see
    /// [`crate::joint`]).
    pub fn joint_state(&self, j: usize) -> JointState {
        let s = &self.structure;
        let c = &s.joints[j];
        let half = &s.members[c.member];
        let partner = half.band.as_ref().map_or(c.member, |b| b.partner);
        let (t, p) = (&self.work.states[c.member], &self.work.states[partner]);
        let gap = s.band_clearance(half, &self.sample.clearances);
        joint_state(
            JointEnd {
                at_start: c.at_start,
                clearance: self.sample.clearances[j],
                tension_stiffness: c.tension_stiffness,
            },
            BandState {
                direction: t.direction,
                force: t.force + p.force,
                elongation: t.elongation + gap,
                total_clearance: gap,
                bearing: !(t.slack && p.slack),
            },
        )
    }

    /// Each joint's id and summary at the last equilibrium, model order.
    pub fn joint_summaries(&self) -> Vec<(String, JointSummary)> {
        (0..self.structure.joints.len())
            .map(|j| {
                let id = self.structure.joints[j].id.clone();
                (id, self.joint_state(j).into())
            })
            .collect()
    }

    /// Whether model member `m` is a slack cable at the last equilibrium.
    pub fn is_slack(&self, m: usize) -> bool {
        self.structure.members[m].band.is_none() && self.work.states[m].slack
    }

    /// Whether compiled member `m` (a model member, or the compression-only half of a
    /// member in clearance holes, numbered after the model's members, as in
    /// [`HoldingLimit::Release`]) is slack at the last equilibrium.
    pub fn compiled_member_slack(&self, m: usize) -> bool {
        self.work.states[m].slack
    }

    /// Number of the model's cables that are slack at the current point.
    fn slack_cable_count(&self) -> u32 {
        (0..self.structure.model_members)
            .filter(|&m| self.is_slack(m))
            .count() as u32
    }

    /// Number of joints whose member bears on neither side (both halves slack).
    fn loose_joint_count(&self) -> u32 {
        self.structure
            .joints
            .iter()
            .filter(|c| {
                let b = self.structure.members[c.member].band.as_ref();
                b.is_some_and(|b| {
                    self.work.states[c.member].slack && self.work.states[b.partner].slack
                })
            })
            .count() as u32
    }

    /// The top surface's tilt at the last equilibrium, if the model names a top surface.
    pub fn distortion(&self) -> Option<Distortion> {
        let t = self.structure.top_surface.as_ref()?;
        let x = t.nodes.map(|i| self.structure.node_xyz[i]);
        let u = t.nodes.map(|i| self.displacement(i));
        Some(distortion(x, u, t.reference_normal))
    }

    /// Iteration records of the last solve (empty unless requested in the options).
    pub fn iteration_log(&self) -> &[IterationRecord] {
        &self.log
    }

    /// Collects the last equilibrium; `None` before a successful solve.
    pub fn equilibrium(&self) -> Option<Equilibrium> {
        let report = self.last?;
        let joints: Vec<JointState> = (0..self.structure.joints.len())
            .map(|j| self.joint_state(j))
            .collect();
        let members = 0..self.structure.model_members;
        Some(Equilibrium {
            report,
            displacements: (0..self.structure.node_ids.len())
                .map(|i| self.displacement(i))
                .collect(),
            forces: members.clone().map(|m| self.member_force(m)).collect(),
            slack: members.filter(|&m| self.is_slack(m)).collect(),
            distortion: self.distortion(),
            joint_offsets: joints.iter().map(|s| s.offset).collect(),
            joint_contacts: joints.iter().map(|s| s.contact).collect(),
            loose_joints: (0..joints.len()).filter(|&j| !joints[j].engaged).collect(),
        })
    }

    /// Total potential energy `Π(u) = Σ W − fᵀu` at the last point evaluated \[N·mm\] (for
    /// tests: Π is minimal at a stable equilibrium).
    pub fn potential_energy(&self) -> f64 {
        let strain: f64 = self
            .work
            .states
            .iter()
            .map(|s| 0.5 * s.stiffness * s.elongation * s.elongation)
            .sum();
        strain
            - dot_n(
                &self.sample.loads[..self.structure.free],
                &self.work.u[..self.structure.free],
            )
    }
}

#[cfg(test)]
mod tests;
