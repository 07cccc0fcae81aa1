//! The iteration of the module doc: the linearised problem, then chord steps or model
//! steps, each followed by a line search, until converged.

use super::evaluate::max_abs;
use super::lanes::{Evaluate, Kernels};
use super::step::Step;
use super::{Evaluation, IterationRecord, Mode, SolveReport, Solver};
use crate::SolveError;
use crate::linearised::{ActiveSetFailure, gather_b, scatter_b};
use crate::structure::Structure;
use std::sync::Arc;

/// The force "has stopped falling" when it has not halved in this many iterations.
const STALL_ITERATIONS: u32 = 3;

/// A stalled force is accepted within this factor of the floor the force test uses: the
/// larger of `residual_floor·F` (1e-10 of the largest member force with the default floor)
/// and the displacements' rounding floor ([`Solver::rounding_floor`]). An ill-conditioned
/// tall tower's rounding noise keeps the steps from shrinking further. Both floors, as the
/// force test has them: with the first alone, a stage of the limit solver on the 300-stage
/// prism with free play (tops 40–80 mm out, a rounding floor of 2e-10 N against a force
/// floor of 1.4e-11 N) stalled at 1.5e-8 to 1.3e-7 N, its line search unable to see a
/// descent in that noise, and was abandoned; with both, such stages end.
const STALL_FLOOR_FACTOR: f64 = 1e3;

/// The rounding floor of the out-of-balance force from the displacements, in units of
/// `ε·k_max·‖u‖∞` (see [`Solver::rounding_floor`]).
const DISPLACEMENT_ROUNDING: f64 = 4.0;

/// A step that no longer moves (at most this fraction of the displacements) while the
/// force is more than [`STALL_FLOOR_FACTOR`] times its floor raises the damping.
const STUCK_STEP: f64 = 1e-10;

/// A line search that takes at least this fraction of the step counts as a full step: the
/// damping is relaxed, and a switching step that came this far is not followed by a plain
/// one.
const FULL_STEP: f64 = 0.5;

/// Relaxing damping multiplies it by this, until it drops below [`DAMPING_OFF`].
const DAMPING_RELAX: f64 = 0.1;

/// Damping below this is switched off (Newton's method again).
const DAMPING_OFF: f64 = 1e-8;

/// Raising damping multiplies it by this, starting from [`DAMPING_START`].
const DAMPING_RAISE: f64 = 10.0;

/// The first damping μ of model steps that stall.
const DAMPING_START: f64 = 1e-6;

/// Beyond this damping a model step is a scaled steepest descent; if that does not move,
/// the solve fails.
const DAMPING_MAX: f64 = 1e8;

/// Converged on the step when it is small and the error it leaves is no larger than it:
/// a fresh tangent's step, or one whose measured contraction is at most this.
const CONVERGED_CONTRACTION: f64 = 0.5;

/// Most slack sets the banded active-set iteration of step 1 tries (models without a
/// cable basis) before it gives up and Newton starts from zero.
const MAX_LINEARISED_PIECES: u32 = 50;

/// In the banded active-set iteration of step 1, a cable whose linearised elongation is
/// within this fraction of the sample's largest initial stretch of its kink keeps its
/// state: near a mechanism (pin joints in free play) the rounding of `K_S⁻¹` is that large,
/// and such a cable would otherwise flip at every piece.
const KINK_NOISE: f64 = 1e-8;

/// The state of one solve's iteration that the parts of [`Solver::newton`] share.
#[derive(Debug, Clone, Copy)]
pub(super) struct Progress {
    /// Linear solves so far (the linearised problem counts as one).
    iterations: u32,
    /// Factorisations so far (the shared nominal one not counted).
    factorisations: u32,
    /// The operator of the next step.
    mode: Mode,
    /// The current point's evaluation.
    eval: Evaluation,
    /// Whether `Solver::factor.k` holds the factorised model stiffness of
    /// `Solver::factor.factor_slack`.
    k_valid: bool,
    /// The last step's size \[mm\] (infinite after a fresh operator: no contraction known).
    prev_step: f64,
    /// The last step's size `α·max |d|` \[mm\].
    step: f64,
    /// The last reused operator's step contracted by less than
    /// [`super::SolveOptions::reuse_contraction`]: use a fresh one.
    poor: bool,
    /// Iterations since the out-of-balance force last halved.
    stalled: u32,
    /// The lowest out-of-balance force so far \[N\].
    lowest: f64,
    /// The current point's largest displacement `‖u‖∞` \[mm\].
    u_max: f64,
    /// Soft directions of the linearised start (see [`SolveReport::soft_directions`]).
    soft_directions: u32,
}

/// How the step of one iteration was chosen.
#[derive(Debug, Clone, Copy)]
struct StepChoice {
    /// The tangent was factorised afresh for it.
    fresh: bool,
    /// The Levenberg shift μ of that factorisation.
    shift: f64,
    /// It is a direction of negative curvature (the line search may expand).
    curved: bool,
}

/// Whether the iteration goes on.
enum Next {
    /// Take another step.
    Step,
    /// Converged.
    Done,
}

impl Solver {
    /// Steps 1–5 of the module doc: the linearised start, then steps (chosen by
    /// [`Solver::choose_step`], taken by the line search) until the force test
    /// ([`Solver::force_converged`]) or the step test ([`Solver::step_converged`]) holds.
    pub(super) async fn newton(&mut self, kernels: Kernels<'_>) -> Result<SolveReport, SolveError> {
        let p = self.start(kernels).await;
        self.iterate(p, true, kernels).await
    }

    /// Factorises the tangent in `self.factor.k` (in the batch where the solve runs in
    /// lanes: the same bits), stopping at its `max`-th pivot that is not safely positive
    /// (see [`crate::block::BlockBandMatrix::factor_collecting`]); returns whether there
    /// was none (the failures, if any, in `self.work.failures`).
    pub(super) async fn factor_tangent(&mut self, kernels: Kernels<'_>, max: usize) -> bool {
        let s = Arc::clone(&self.structure);
        kernels
            .refactor(
                &s,
                self.sample_key,
                &mut self.factor.k,
                &mut self.work.failures,
                max,
                0,
            )
            .await;
        self.work.failures.is_empty()
    }

    /// Evaluates the current point `u` into the solver's state: the residual, the members'
    /// states and the slack set.
    pub(super) async fn evaluate_current(&mut self, kernels: Kernels<'_>) -> Evaluation {
        let structure = Arc::clone(&self.structure);
        let eval = kernels
            .evaluate(Evaluate {
                structure: &structure,
                key: self.sample_key,
                members: &mut self.sample.members,
                tension: &mut self.sample.tension,
                loads: &mut self.sample.loads,
                u: &mut self.work.u,
                r: &mut self.work.r,
                states: &mut self.work.states,
            })
            .await;
        self.update_slack();
        eval
    }

    /// Steps 2–5 of the module doc from the current point (a warm start): `u` as it is,
    /// evaluated, and model steps from there.
    pub(super) async fn newton_warm(
        &mut self,
        kernels: Kernels<'_>,
    ) -> Result<SolveReport, SolveError> {
        let structure = Arc::clone(&self.structure);
        let eval = self.evaluate_current(kernels).await;
        self.chord_secant = f64::NAN;
        self.step.damping = 0.0;
        self.step.plain_step = false;
        self.step.pinned.fill(false);
        self.factor.locked.fill(false);
        let p = Progress {
            iterations: 0,
            factorisations: 0,
            mode: Mode::Tangent,
            eval,
            k_valid: false,
            prev_step: f64::INFINITY,
            step: 0.0,
            poor: false,
            stalled: 0,
            lowest: f64::INFINITY,
            u_max: max_abs(&self.work.u[..structure.free]),
            soft_directions: 0,
        };
        self.iterate(p, false, kernels).await
    }

    /// The iteration of [`Solver::newton`] from `p`; with `assess`, the converged point's
    /// floating flag and holding force (else left out: a stage of the limit solver).
    async fn iterate(
        &mut self,
        mut p: Progress,
        assess: bool,
        kernels: Kernels<'_>,
    ) -> Result<SolveReport, SolveError> {
        loop {
            if let Next::Done = self.force_converged(&mut p)? {
                break;
            }
            p.iterations += 1;
            let choice = self.choose_step(&mut p, kernels).await?;
            let residual_before = p.eval.residual;
            let alpha = match self
                .line_search(
                    p.iterations,
                    p.eval,
                    choice.curved,
                    !choice.fresh && !choice.curved,
                    kernels,
                )
                .await
            {
                Ok((alpha, eval, d_max)) => {
                    p.eval = eval;
                    p.step = alpha * d_max;
                    alpha
                }
                Err(e) => {
                    // No step along this direction lowers the energy: damp the model steps
                    // (towards steepest descent) and try again from the same point.
                    if !self.raise_damping() {
                        return Err(e);
                    }
                    p.mode = Mode::Tangent;
                    p.k_valid = false;
                    p.prev_step = f64::INFINITY;
                    continue;
                }
            };
            p.u_max = max_abs(&self.work.u[..self.structure.free]);
            self.adapt_damping(&mut p, alpha)?;
            if self.options.record_iterations {
                self.record(&p, &choice, residual_before, alpha);
            }
            self.update_slack();
            if self.work.slack != self.step.step_slack {
                // A kink crossed: the secant along this step says little about the next.
                self.chord_secant = f64::NAN;
            }
            self.pin_failed_switches(choice.fresh, alpha);
            if let Next::Done = self.step_converged(&mut p, &choice) {
                break;
            }
        }
        let mut floating = false;
        if assess && self.options.holding {
            floating = self.floating();
            let floor = self.force_floor(&p.eval);
            self.holding = self.compute_holding(floor, kernels).await;
        }
        Ok(SolveReport {
            iterations: p.iterations,
            factorisations: p.factorisations,
            residual: p.eval.residual,
            step: p.step,
            slack_cables: self.slack_cable_count(),
            evaluations: self.evaluations,
            loose_joints: self.loose_joint_count(),
            soft_directions: p.soft_directions,
            floating,
            holding_force: self.holding.map(|h| h.force),
            limit_ratio: None,
        })
    }

    /// Step 1: the linearised problem (or zero, if it fails), evaluated.
    pub(super) async fn start(&mut self, kernels: Kernels<'_>) -> Progress {
        let structure = Arc::clone(&self.structure);
        let mut factorisations = 0;
        let mut iterations = 0;
        let mut soft_directions = 0;
        let mode = match self.linearised(&structure, &mut factorisations) {
            Ok((mode, soft)) => {
                iterations += 1;
                soft_directions = soft;
                mode
            }
            Err(_) => {
                self.work.u.fill(0.0);
                Mode::Tangent
            }
        };
        let eval = self.evaluate_current(kernels).await;
        Progress {
            iterations,
            factorisations,
            mode,
            eval,
            k_valid: false,
            prev_step: f64::INFINITY,
            step: 0.0,
            poor: false,
            stalled: 0,
            lowest: f64::INFINITY,
            u_max: max_abs(&self.work.u[..structure.free]),
            soft_directions,
        }
    }

    /// The force test of step 5 at the current point: done when the out-of-balance force
    /// is at its floor, the larger of `residual_floor·F` (`F` the largest member force, or
    /// the sample's force scale) and the rounding floor, or has stopped falling
    /// ([`STALL_ITERATIONS`]) within [`STALL_FLOOR_FACTOR`] times it (an ill-conditioned
    /// tall tower, whose bending is far softer than its members: the steps stop shrinking
    /// before the step test is met). Errors on a non-finite force or too many iterations.
    fn force_converged(&self, p: &mut Progress) -> Result<Next, SolveError> {
        let eval = &p.eval;
        if !eval.residual.is_finite() {
            return Err(SolveError::NonFinite {
                iteration: p.iterations,
                what: "out-of-balance force (a member may have collapsed to zero length)".into(),
            });
        }
        let floor = self.force_floor(eval).max(self.rounding_floor(p.u_max));
        if eval.residual == 0.0 || eval.residual <= floor {
            return Ok(Next::Done);
        }
        if eval.residual <= 0.5 * p.lowest {
            (p.stalled, p.lowest) = (0, eval.residual);
        } else {
            p.stalled += 1;
        }
        if p.stalled >= STALL_ITERATIONS && eval.residual <= STALL_FLOOR_FACTOR * floor {
            return Ok(Next::Done);
        }
        if p.iterations >= self.options.max_iterations {
            return Err(SolveError::NotConverged {
                iterations: p.iterations,
                residual: eval.residual,
                step: p.step,
            });
        }
        Ok(Next::Step)
    }

    /// The force test's floor \[N\]: `residual_floor` times the largest member force (or
    /// the sample's force scale, if larger).
    pub(super) fn force_floor(&self, eval: &Evaluation) -> f64 {
        self.options.residual_floor * eval.force_scale.max(self.sample.force_ref)
    }

    /// The rounding floor of the out-of-balance force that the displacements set \[N\]:
    ///
    /// ```text
    /// ρ_u = c·ε·k_max·‖u‖∞,    c = 4,  k_max = max_m E·A/L₀
    /// ```
    ///
    /// Each member's `d = u_j − u_i` is rounded by about `ε·‖u‖∞`, so its force by
    /// `k·ε·‖u‖∞`, and a node sums a few members' forces. Below `ρ_u` the force is noise,
    /// and further steps only move the answer by that noise (on 300-stage towers, whose
    /// tops move 20–45 mm, the force stops falling at 0.6 to 1.2 `ε·k_max·‖u‖∞`, about
    /// 1e-11 N, while the force floor is a few 1e-12 N). It matters only where the
    /// displacements are that large: for the paper's 5-stage prism it is a tenth of the
    /// force floor or less (tested). Without it such a solve goes on until the stall rule
    /// accepts it, three iterations later. Like the force floor it scales with the length
    /// errors, so the answer stays homogeneous in them.
    pub(super) fn rounding_floor(&self, u_max: f64) -> f64 {
        DISPLACEMENT_ROUNDING * f64::EPSILON * self.sample.stiffest * u_max
    }

    /// Steps 2–3: puts the next step into `self.work.d`, a chord step with the current
    /// slack set's Woodbury inverse while those contract, else a model step with the true
    /// tangent (reusing its factorisation while the slack set is unchanged and steps
    /// contract).
    async fn choose_step(
        &mut self,
        p: &mut Progress,
        kernels: Kernels<'_>,
    ) -> Result<StepChoice, SolveError> {
        let structure = Arc::clone(&self.structure);
        self.step.step_slack.copy_from_slice(&self.work.slack);
        let mut choice = StepChoice {
            fresh: false,
            shift: 0.0,
            curved: false,
        };
        if p.mode == Mode::Chord && p.poor {
            p.mode = Mode::Tangent;
            p.poor = false;
        }
        if p.mode == Mode::Chord {
            let basis = structure.basis.as_ref().expect("chord mode needs a basis");
            let states = &self.work.states;
            let nc = basis.cables.len();
            if self
                .factor
                .active
                .set_slack_from(|c| states[basis.cables[c]].slack, nc)
                && self.factor.active.factor(basis).is_err()
            {
                p.mode = Mode::Tangent;
            }
        }
        match p.mode {
            Mode::Chord => {
                let basis = structure.basis.as_ref().expect("chord mode needs a basis");
                self.negate_residual_into_step();
                self.factor
                    .active
                    .apply_inverse(&structure, basis, &mut self.work.d);
            }
            Mode::Tangent => {
                let reuse = p.k_valid
                    && self.options.reuse_factorisation
                    && !p.poor
                    && self.work.slack == self.factor.factor_slack;
                if reuse {
                    self.negate_residual_into_step();
                    kernels
                        .solve(
                            &structure,
                            self.sample_key,
                            &mut self.factor.k,
                            &mut self.work.d,
                        )
                        .await;
                } else {
                    match self
                        .model_step(p.iterations, &mut p.factorisations, kernels)
                        .await?
                    {
                        Step::Newton { shift } => {
                            choice.shift = shift;
                            choice.fresh = true;
                            p.k_valid = true;
                            p.prev_step = f64::INFINITY;
                        }
                        Step::Curvature => {
                            choice.curved = true;
                            p.k_valid = false;
                        }
                    }
                }
            }
        }
        Ok(choice)
    }

    /// After a line search: a step that no longer moves ([`STUCK_STEP`]) while the force
    /// is far from its floor (beyond [`STALL_FLOOR_FACTOR`] times the force test's floor)
    /// raises the damping (an error once it is beyond [`DAMPING_MAX`]); full steps again
    /// relax it back towards Newton's method.
    fn adapt_damping(&mut self, p: &mut Progress, alpha: f64) -> Result<(), SolveError> {
        // (Multiplied in this order, as ever: the comparison's rounding is part of the
        // results.)
        let far_from_floor = p.eval.residual
            > (STALL_FLOOR_FACTOR
                * self.options.residual_floor
                * p.eval.force_scale.max(self.sample.force_ref))
            .max(STALL_FLOOR_FACTOR * self.rounding_floor(p.u_max));
        if far_from_floor && p.step <= STUCK_STEP * p.u_max.max(self.sample.scale) {
            if !self.raise_damping() {
                return Err(SolveError::NotConverged {
                    iterations: p.iterations,
                    residual: p.eval.residual,
                    step: p.step,
                });
            }
            p.mode = Mode::Tangent;
            p.k_valid = false;
        } else if self.step.damping > 0.0 && alpha >= FULL_STEP {
            self.step.damping = if self.step.damping < DAMPING_OFF {
                0.0
            } else {
                self.step.damping * DAMPING_RELAX
            };
            p.k_valid = false;
        }
        Ok(())
    }

    /// Appends the iteration's record to the log.
    fn record(&mut self, p: &Progress, choice: &StepChoice, residual_before: f64, alpha: f64) {
        let slack = self.slack_indices();
        self.log.push(IterationRecord {
            iteration: p.iterations,
            residual: residual_before,
            step: p.step,
            alpha,
            refactorised: choice.fresh,
            shift: choice.shift,
            slack,
            evaluations: self.evaluations,
        });
    }

    /// A model step that switched cables but whose switch did not come true (the line
    /// search stopped short of [`FULL_STEP`] and the slack set is unchanged) is followed
    /// by a plain step on the current piece, with the cables whose switch failed pinned;
    /// the others are released.
    fn pin_failed_switches(&mut self, fresh: bool, alpha: f64) {
        let switched = fresh && self.factor.factor_slack != self.step.step_slack;
        self.step.plain_step =
            switched && alpha < FULL_STEP && self.work.slack == self.step.step_slack;
        for ((p, f), s) in self
            .step
            .pinned
            .iter_mut()
            .zip(&self.factor.factor_slack)
            .zip(&self.step.step_slack)
        {
            *p = self.step.plain_step && f != s;
        }
    }

    /// The step test of step 5: done when the step is at most `step_tolerance` of the
    /// largest displacement, undamped and not along a curvature, and the error it leaves
    /// is no larger than it (a fresh tangent's, or a contraction of at most
    /// [`CONVERGED_CONTRACTION`]). Otherwise notes whether a reused operator's step
    /// contracted too little to keep it.
    fn step_converged(&self, p: &mut Progress, choice: &StepChoice) -> Next {
        let contraction = p.step / p.prev_step;
        let small = p.step <= self.options.step_tolerance * p.u_max;
        let undamped = self.step.damping == 0.0;
        if small
            && !choice.curved
            && undamped
            && (choice.fresh || contraction <= CONVERGED_CONTRACTION)
        {
            return Next::Done;
        }
        p.poor = !choice.fresh && !choice.curved && contraction > self.options.reuse_contraction;
        p.prev_step = if choice.curved { f64::INFINITY } else { p.step };
        Next::Step
    }

    /// Raises the Levenberg damping of model steps by [`DAMPING_RAISE`] (from
    /// [`DAMPING_START`]); false once it is beyond [`DAMPING_MAX`], where a model step is a
    /// scaled steepest descent and still does not move.
    fn raise_damping(&mut self) -> bool {
        self.step.damping = (self.step.damping * DAMPING_RAISE).max(DAMPING_START);
        // A damped step is a plain descent step: no cable pinned or switched.
        self.step.pinned.fill(false);
        self.step.plain_step = false;
        self.step.damping <= DAMPING_MAX
    }

    /// `d = −r` (the zero slot kept zero).
    fn negate_residual_into_step(&mut self) {
        let n = self.structure.free;
        for (d, r) in self.work.d[..n].iter_mut().zip(&self.work.r[..n]) {
            *d = -r;
        }
        self.work.d[n] = 0.0;
    }

    /// Step 1: solves the linearised problem into `self.work.u`, and says how to go on: chord
    /// steps with the active set's Woodbury inverse when the model has a cable basis and
    /// the final slack set leaves no soft direction, model steps otherwise; and how many
    /// soft directions it leaves (0 when not solved by the capacitance matrix). A piece with a
    /// slack set too large for the capacitance matrix (see the `linearised` module) hands
    /// the iteration to [`Solver::linearised_banded`].
    fn linearised(
        &mut self,
        structure: &Structure,
        factorisations: &mut u32,
    ) -> Result<(Mode, u32), ActiveSetFailure> {
        for (st, m) in self.work.stretch.iter_mut().zip(&self.sample.members) {
            *st = m.initial_stretch;
        }
        match &structure.basis {
            Some(basis) => {
                match self.factor.active.solve_linearised(
                    structure,
                    basis,
                    &self.work.stretch,
                    &self.sample.loads,
                    &mut self.work.u,
                ) {
                    Ok(_) => {
                        let soft = self.factor.active.soft_directions() as u32;
                        Ok((if soft > 0 { Mode::Tangent } else { Mode::Chord }, soft))
                    }
                    Err(ActiveSetFailure::LargeSlackSet) => {
                        self.linearised_banded(structure, factorisations)?;
                        Ok((Mode::Tangent, 0))
                    }
                    Err(e) => Err(e),
                }
            }
            None => {
                self.linearised_banded(structure, factorisations)?;
                Ok((Mode::Tangent, 0))
            }
        }
    }

    /// Step 1 without a cable basis, or with a large slack set: the active-set iteration
    /// with a block-banded factorisation of the linearised stiffness of each slack set
    /// tried, from the all-taut solution's slack set.
    pub(super) fn linearised_banded(
        &mut self,
        s: &Structure,
        factorisations: &mut u32,
    ) -> Result<(), ActiveSetFailure> {
        let n = s.free;
        // Start from the all-taut solution's slack set.
        self.work.u.copy_from_slice(&self.sample.loads);
        for (m, c) in s.members.iter().enumerate() {
            scatter_b(
                s,
                m,
                -c.rigidity / c.natural_length * self.work.stretch[m],
                &mut self.work.u,
            );
        }
        s.nominal.solve_in_place(&mut self.work.u[..n]);
        for (m, c) in s.members.iter().enumerate() {
            self.factor.factor_slack[m] =
                c.is_cable && c.sense * (gather_b(s, m, &self.work.u) + self.work.stretch[m]) < 0.0;
        }
        for _ in 0..MAX_LINEARISED_PIECES {
            let slack = &self.factor.factor_slack;
            s.assemble_material(&mut self.factor.k, |m| {
                if slack[m] {
                    s.members[m].compression_ratio
                } else {
                    1.0
                }
            });
            self.work.u.copy_from_slice(&self.sample.loads);
            for (m, c) in s.members.iter().enumerate() {
                let mut k = c.rigidity / c.natural_length;
                if self.factor.factor_slack[m] {
                    k *= c.compression_ratio;
                }
                scatter_b(s, m, -k * self.work.stretch[m], &mut self.work.u);
            }
            *factorisations += 1;
            self.factor
                .k
                .factor()
                .map_err(|_| ActiveSetFailure::NotPositiveDefinite)?;
            self.factor.k.solve_in_place(&mut self.work.u[..n]);
            let mut settled = true;
            let noise = KINK_NOISE * self.sample.scale;
            for (m, c) in s.members.iter().enumerate() {
                let e = c.sense * (gather_b(s, m, &self.work.u) + self.work.stretch[m]);
                let slack = c.is_cable && e < 0.0;
                if slack != self.factor.factor_slack[m] && e.abs() > noise {
                    settled = false;
                    self.factor.factor_slack[m] = slack;
                }
            }
            if settled {
                return Ok(());
            }
        }
        Err(ActiveSetFailure::NoFixedPoint)
    }
}
