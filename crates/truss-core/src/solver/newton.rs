//! The iteration of the module doc: the linearised problem, then chord steps or model
//! steps, each followed by a line search, until converged.

use super::evaluate::{evaluate_with, max_abs};
use super::step::Step;
use super::{IterationRecord, Mode, SolveReport, Solver};
use crate::SolveError;
use crate::linearised::{ActiveSetFailure, gather_b, scatter_b};
use crate::structure::Structure;
use std::sync::Arc;

/// The force "has stopped falling" when it has not halved in this many iterations.
const STALL_ITERATIONS: u32 = 3;

/// A stalled force is accepted within this factor of the rounding floor (1e-10 of the
/// largest member force with the default floor): an ill-conditioned tall tower's rounding
/// noise keeps the steps from shrinking further.
const STALL_FLOOR_FACTOR: f64 = 1e3;

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

impl Solver {
    /// Steps 1–5 of the module doc.
    pub(super) fn newton(&mut self) -> Result<SolveReport, SolveError> {
        let n = self.structure.free;
        let opts = self.options.clone();
        let structure = Arc::clone(&self.structure);
        let mut iterations = 0u32;
        let mut factorisations = 0u32;

        // Step 1: the linearised problem.
        let mut mode = match self.linearised(&structure, &mut factorisations) {
            Ok(mode) => {
                iterations += 1;
                mode
            }
            Err(_) => {
                self.work.u.fill(0.0);
                Mode::Tangent
            }
        };
        let mut eval = evaluate_with(
            &structure,
            &self.sample.members,
            self.sample.tension.iter().copied(),
            &self.sample.loads,
            &self.work.u,
            &mut self.work.r,
            &mut self.work.states,
        );
        self.update_slack();
        // Whether `self.factor.k` holds the factorised model stiffness of `self.factor.factor_slack`.
        let mut k_valid = false;
        let mut prev_step = f64::INFINITY;
        let mut step = 0.0;
        let mut poor = false;
        // Iterations since the out-of-balance force last halved, and its lowest value.
        let (mut stalled, mut lowest) = (0u32, f64::INFINITY);
        loop {
            if !eval.residual.is_finite() {
                return Err(SolveError::NonFinite {
                    iteration: iterations,
                    what: "out-of-balance force (a member may have collapsed to zero length)"
                        .into(),
                });
            }
            // The force test's floor: relative to the largest force.
            let floor = opts.residual_floor * eval.force_scale.max(self.sample.force_ref);
            if eval.residual == 0.0 || eval.residual <= floor {
                break;
            }
            // At the rounding floor of an ill-conditioned structure (a tall tower, whose
            // bending is far softer than its members) the steps stop shrinking before the
            // step test is met: accept when the force has not halved in three iterations and
            // is within a thousand times the floor (1e-10 of the largest member force).
            if eval.residual <= 0.5 * lowest {
                (stalled, lowest) = (0, eval.residual);
            } else {
                stalled += 1;
            }
            if stalled >= STALL_ITERATIONS && eval.residual <= STALL_FLOOR_FACTOR * floor {
                break;
            }
            if iterations >= opts.max_iterations {
                return Err(SolveError::NotConverged {
                    iterations,
                    residual: eval.residual,
                    step,
                });
            }
            iterations += 1;

            // Choose the step.
            self.step.step_slack.copy_from_slice(&self.work.slack);
            let mut fresh = false;
            let mut shift = 0.0;
            let mut curved = false;
            if mode == Mode::Chord && poor {
                mode = Mode::Tangent;
                poor = false;
            }
            if mode == Mode::Chord {
                let basis = structure.basis.as_ref().expect("chord mode needs a basis");
                let states = &self.work.states;
                let nc = basis.cables.len();
                if self
                    .factor
                    .active
                    .set_slack_from(|c| states[basis.cables[c]].slack, nc)
                    && self.factor.active.factor(basis).is_err()
                {
                    mode = Mode::Tangent;
                }
            }
            match mode {
                Mode::Chord => {
                    let basis = structure.basis.as_ref().expect("chord mode needs a basis");
                    self.negate_residual_into_step();
                    self.factor
                        .active
                        .apply_inverse(&structure, basis, &mut self.work.d);
                }
                Mode::Tangent => {
                    let reuse = k_valid
                        && opts.reuse_factorisation
                        && !poor
                        && self.work.slack == self.factor.factor_slack;
                    if reuse {
                        self.negate_residual_into_step();
                        self.factor.k.solve_in_place(&mut self.work.d[..n]);
                    } else {
                        match self.model_step(iterations, &mut factorisations)? {
                            Step::Newton { shift: mu } => {
                                shift = mu;
                                fresh = true;
                                k_valid = true;
                                prev_step = f64::INFINITY;
                            }
                            Step::Curvature => {
                                curved = true;
                                k_valid = false;
                            }
                        }
                    }
                }
            }

            let residual_before = eval.residual;
            let (alpha, new_eval, d_max) = match self.line_search(iterations, eval, curved) {
                Ok(found) => found,
                Err(e) => {
                    // No step along this direction lowers the energy: damp the model steps
                    // (towards steepest descent) and try again from the same point.
                    if !self.raise_damping() {
                        return Err(e);
                    }
                    mode = Mode::Tangent;
                    k_valid = false;
                    prev_step = f64::INFINITY;
                    continue;
                }
            };
            eval = new_eval;
            step = alpha * d_max;
            let u_max = max_abs(&self.work.u[..n]);
            let far_from_floor = eval.residual
                > STALL_FLOOR_FACTOR
                    * opts.residual_floor
                    * eval.force_scale.max(self.sample.force_ref);
            if far_from_floor && step <= STUCK_STEP * u_max.max(self.sample.scale) {
                // A step that no longer moves while the force is far from balanced: damp.
                if !self.raise_damping() {
                    return Err(SolveError::NotConverged {
                        iterations,
                        residual: eval.residual,
                        step,
                    });
                }
                mode = Mode::Tangent;
                k_valid = false;
            } else if self.step.damping > 0.0 && alpha >= FULL_STEP {
                // Full steps again: relax the damping back towards Newton's method.
                self.step.damping = if self.step.damping < DAMPING_OFF {
                    0.0
                } else {
                    self.step.damping * DAMPING_RELAX
                };
                k_valid = false;
            }
            if opts.record_iterations {
                let slack = self.slack_indices();
                self.log.push(IterationRecord {
                    iteration: iterations,
                    residual: residual_before,
                    step,
                    alpha,
                    refactorised: fresh,
                    shift,
                    slack,
                    evaluations: self.evaluations,
                });
            }
            // A model step that switched cables but whose switch did not come true (the line
            // search stopped short and the slack set is unchanged) is followed by a plain
            // step on the current piece.
            self.update_slack();
            let switched = fresh && self.factor.factor_slack != self.step.step_slack;
            self.step.plain_step =
                switched && alpha < FULL_STEP && self.work.slack == self.step.step_slack;
            // Pin the cables whose switch failed for the next (plain) step, release the rest.
            for ((p, f), s) in self
                .step
                .pinned
                .iter_mut()
                .zip(&self.factor.factor_slack)
                .zip(&self.step.step_slack)
            {
                *p = self.step.plain_step && f != s;
            }

            // Convergence on the step.
            let contraction = step / prev_step;
            let small = step <= opts.step_tolerance * u_max;
            let undamped = self.step.damping == 0.0;
            if small && !curved && undamped && (fresh || contraction <= CONVERGED_CONTRACTION) {
                break;
            }
            poor = !fresh && !curved && contraction > opts.reuse_contraction;
            prev_step = if curved { f64::INFINITY } else { step };
        }
        Ok(SolveReport {
            iterations,
            factorisations,
            residual: eval.residual,
            step,
            slack_cables: self.slack_cable_count(),
            evaluations: self.evaluations,
            loose_joints: self.loose_joint_count(),
        })
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
    /// the final slack set leaves no soft direction, model steps otherwise.
    fn linearised(
        &mut self,
        structure: &Structure,
        factorisations: &mut u32,
    ) -> Result<Mode, ActiveSetFailure> {
        for (st, m) in self.work.stretch.iter_mut().zip(&self.sample.members) {
            *st = m.initial_stretch;
        }
        match &structure.basis {
            Some(basis) => {
                self.factor.active.solve_linearised(
                    structure,
                    basis,
                    &self.work.stretch,
                    &self.sample.loads,
                    &mut self.work.u,
                )?;
                Ok(if self.factor.active.is_soft() {
                    Mode::Tangent
                } else {
                    Mode::Chord
                })
            }
            None => {
                self.linearised_banded(structure, factorisations)?;
                Ok(Mode::Tangent)
            }
        }
    }

    /// Step 1 without a cable basis: the active-set iteration with a block-banded
    /// factorisation of the linearised stiffness of each slack set tried.
    fn linearised_banded(
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
        for _ in 0..50 {
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
            for (m, c) in s.members.iter().enumerate() {
                let slack = c.is_cable
                    && c.sense * (gather_b(s, m, &self.work.u) + self.work.stretch[m]) < 0.0;
                if slack != self.factor.factor_slack[m] {
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
