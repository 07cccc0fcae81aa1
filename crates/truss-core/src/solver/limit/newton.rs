//! The Newton iteration at `ρ = 0` itself: the continuation's attempts to reach the limit
//! from a converged stage (the stages at `ρ > 0` are [`Solver::newton_warm`]).
//!
//! Each iteration:
//! 1. **The model's bearing set**: the members' current states, but a one-sided member
//!    within the noise of its kink bears (at `ρ = 0` a slack cable carries nothing, and a
//!    kink is where a floating stage's cables sit).
//! 2. **Engagement**: the tangent of that set is factorised; each pivot below
//!    `−SOFT_PIVOT` of its diagonal is a direction in which the truss falls (a panel whose
//!    frame is compressed and whose bracing is slack): the first slack one-sided member that
//!    engages along it, on the side that lowers the energy, is made to bear in the model,
//!    and the tangent factorised again, until none falls (at most [`MAX_ENGAGEMENTS`]).
//! 3. **The step** `δ = δ_p + W·a` of the [`reduced`](super::reduced) problem over the
//!    soft pivots' directions, with the right-hand side `−r` corrected by the linearised
//!    force of each member whose model state differs from its current one.
//! 4. **Line search** on the energy ([`Solver::line_search`]); along an unstable reduced
//!    direction, a search that expands until the energy stops falling.
//!
//! Converged when the out-of-balance force is at its floor (as [`Solver::newton`]'s force
//! test) and, where the last step selected free directions, that step is below the step
//! tolerance.

use super::super::evaluate::{dot_n, max_abs};
use super::super::lanes::Kernels;
use super::super::{Evaluation, Solver};
use super::reduced::Finding;
use super::{KINK, SOFT_PIVOT};
use crate::SolveError;
use crate::block::PIVOT_TOLERANCE;
use std::sync::Arc;

/// Most engagement rounds (refactorisations) of one iteration.
const MAX_ENGAGEMENTS: u32 = 8;

/// Most pieces (model bearing sets) of one iteration.
const MAX_PIECES: u32 = 8;

/// Most soft pivots (directions of the [`reduced`](super::reduced) problem) of one step.
/// The reduced problem is dense and its eigen-decomposition costs about `9p³` flops (see
/// the `eigen` module): 9 directions at most in 2,000 samples of the paper's Fig. 16 case,
/// up to 198 in a 300-stage prism with free play that solves in 303 iterations, and 1,653
/// in another's last attempt at `ρ = 0` (that sample had not finished after 20 minutes,
/// when the decomposition was all cyclic Jacobi).
/// An attempt that meets more is abandoned as one that does not converge: a watched one
/// as an event, the last one leaving the last stage to stand for the limit (see the
/// module doc of `limit`).
const MAX_REDUCED: usize = 256;

/// How a stage of the continuation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum StageEnd {
    /// Converged at the stage's ratio.
    Converged,
    /// (Only when asked to watch for it) the solve at this ratio left the bearing set it
    /// started from: a member engaged, or one crossed its kink.
    Event,
}

/// Counters of a solve across its stages.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Counts {
    pub iterations: u32,
    pub factorisations: u32,
    pub step: f64,
    pub residual: f64,
}

impl Solver {
    /// Sets the compression ratio of the cables of ratio 0 for the current sample.
    pub(super) fn set_limit_ratio(&mut self, ratio: f64) {
        let s = Arc::clone(&self.structure);
        for (m, c) in s.members.iter().enumerate() {
            if c.limit {
                self.sample.members[m].compression_ratio = ratio;
            }
        }
        // The batched evaluation caches a sample's members by this key.
        self.sample_key.1 += 1;
    }

    /// Whether member `m` is one-sided with nothing on its slack side at the current ratio.
    fn exactly_one_sided(&self, m: usize) -> bool {
        self.structure.members[m].is_cable && self.sample.members[m].compression_ratio == 0.0
    }

    /// The iteration of the module doc at `ρ = 0`, from the current point. With `watch`,
    /// returns [`StageEnd::Event`] as soon as the solve leaves the bearing set it started
    /// from (by more than the kink noise), leaving the point where it is.
    pub(super) async fn relax(
        &mut self,
        watch: bool,
        counts: &mut Counts,
        kernels: Kernels<'_>,
    ) -> Result<StageEnd, SolveError> {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        let mm = s.members.len();
        self.set_limit_ratio(0.0);
        let mut eval = self.evaluate_current(kernels).await;
        let kink = KINK * self.sample.scale;
        let start: Vec<i8> = (0..mm).map(|m| self.side(m, kink)).collect();
        let mut last_step = f64::INFINITY;
        let mut selected = false;
        let first_iteration = counts.iterations;
        loop {
            counts.residual = eval.residual;
            counts.step = last_step;
            if !eval.residual.is_finite() {
                return Err(SolveError::NonFinite {
                    iteration: counts.iterations,
                    what: "out-of-balance force (a member may have collapsed to zero length)"
                        .into(),
                });
            }
            let floor = self.force_floor(&eval);
            let u_max = max_abs(&self.work.u[..n]);
            let force_ok = eval.residual <= floor.max(self.rounding_floor(u_max));
            let step_ok = last_step <= self.options.step_tolerance * u_max.max(self.sample.scale);
            if force_ok && (!selected || step_ok) {
                return Ok(StageEnd::Converged);
            }
            if watch && (0..mm).any(|m| self.side(m, kink) * start[m] < 0) {
                return Ok(StageEnd::Event);
            }
            if counts.iterations - first_iteration >= self.options.max_iterations {
                return Err(SolveError::NotConverged {
                    iterations: counts.iterations,
                    residual: eval.residual,
                    step: last_step,
                });
            }
            counts.iterations += 1;
            // 1. The model's bearing set.
            for m in 0..mm {
                let st = &self.work.states[m];
                self.factor.factor_slack[m] = st.slack
                    && !(self.exactly_one_sided(m) && s.members[m].sense * st.elongation > -kink);
            }
            self.step.pinned.fill(false);
            // 2.–3. Engagement and the step, over the pieces the steps predict (a member
            // predicted past its kink changes state in the model; an engaged one stays).
            let mut engaged = false;
            let mut locked = std::mem::take(&mut self.factor.locked);
            locked.fill(false);
            let mut finding = Finding::Step { selected: false };
            for _piece in 0..MAX_PIECES {
                for round in 0..=MAX_ENGAGEMENTS {
                    self.factor_soft(counts, kernels).await;
                    if round == MAX_ENGAGEMENTS {
                        break;
                    }
                    let mut any = false;
                    for f in 0..self.work.failures.len() {
                        let failure = self.work.failures[f];
                        if failure.pivot >= -SOFT_PIVOT * self.limit.diag[failure.index] {
                            continue;
                        }
                        if watch {
                            // A direction in which the truss falls: a member will engage.
                            self.factor.locked = locked;
                            return Ok(StageEnd::Event);
                        }
                        self.factor
                            .k
                            .failed_pivot_direction(failure.index, &mut self.work.scratch);
                        self.work.scratch[n] = 0.0;
                        if let Some(m) = self.first_to_engage(f64::INFINITY, failure.index) {
                            self.factor.factor_slack[m] = false;
                            locked[m] = true;
                            any = true;
                        }
                    }
                    if !any {
                        break;
                    }
                    engaged = true;
                }
                if watch && engaged {
                    self.factor.locked = locked;
                    return Ok(StageEnd::Event);
                }
                if self.work.failures.len() > MAX_REDUCED {
                    // Too many free directions for the dense reduced problem: the attempt
                    // is abandoned (see `MAX_REDUCED`).
                    self.factor.locked = locked;
                    return Err(self.stalled(counts, &eval, last_step));
                }
                finding = self.reduced_step(floor, kernels).await;
                if matches!(finding, Finding::Unstable { .. }) {
                    break;
                }
                let mut switched = false;
                for (m, c) in s.members.iter().enumerate() {
                    if !c.is_cable || locked[m] {
                        continue;
                    }
                    let se = c.sense * self.predicted_elongation(m, &self.work.d);
                    let bearing = !self.factor.factor_slack[m];
                    if (se > kink && !bearing) || (se < -kink && bearing) {
                        self.factor.factor_slack[m] = bearing;
                        switched = true;
                    }
                }
                if !switched {
                    break;
                }
            }
            self.factor.locked = locked;
            selected = matches!(finding, Finding::Step { selected: true });
            if let Finding::Unstable { index } = finding {
                if watch {
                    return Ok(StageEnd::Event);
                }
                // Along the unstable direction until the energy stops falling.
                self.work.d.fill(0.0);
                let p = self.limit.reduced.p;
                for (k, c) in self.limit.reduced.direction(index).enumerate().take(p) {
                    let w = &self.limit.w[k];
                    for (d, x) in self.work.d[..n].iter_mut().zip(&w[..n]) {
                        *d += c * x;
                    }
                }
                if !self.negative_curvature() {
                    return Err(self.stalled(counts, &eval, last_step));
                }
                let (alpha, e, d_max) = self
                    .line_search(counts.iterations, eval, true, false, kernels)
                    .await
                    .map_err(|_| self.stalled(counts, &eval, last_step))?;
                (eval, last_step) = (e, alpha * d_max);
                self.update_slack();
                continue;
            }
            if watch {
                // The step's predicted states.
                let crosses = (0..mm).any(|m| {
                    let c = &s.members[m];
                    if !c.is_cable || start[m] == 0 {
                        return false;
                    }
                    let se = c.sense * self.predicted_elongation(m, &self.work.d);
                    se.abs() > kink && (se > 0.0) != (start[m] > 0)
                });
                if crosses {
                    return Ok(StageEnd::Event);
                }
            }
            // 4. Line search (a converged force with a selection step: the step as it is).
            if force_ok || dot_n(&self.work.r[..n], &self.work.d[..n]) >= 0.0 {
                for i in 0..n {
                    self.work.u[i] += self.work.d[i];
                }
                last_step = max_abs(&self.work.d[..n]);
                eval = self.evaluate_current(kernels).await;
                continue;
            }
            let (alpha, e, d_max) = self
                .line_search(counts.iterations, eval, false, false, kernels)
                .await
                .map_err(|_| self.stalled(counts, &eval, last_step))?;
            (eval, last_step) = (e, alpha * d_max);
            self.update_slack();
        }
    }

    /// A one-sided member's side: +1 bearing, −1 slack, 0 within `kink` of its kink (or
    /// not one-sided).
    fn side(&self, m: usize, kink: f64) -> i8 {
        let c = &self.structure.members[m];
        if !c.is_cable {
            return 0;
        }
        let se = c.sense * self.work.states[m].elongation;
        if se > kink {
            1
        } else if se < -kink {
            -1
        } else {
            0
        }
    }

    fn stalled(&self, counts: &Counts, eval: &Evaluation, step: f64) -> SolveError {
        SolveError::NotConverged {
            iterations: counts.iterations,
            residual: eval.residual,
            step,
        }
    }

    /// Assembles the model tangent of `self.factor.factor_slack` and factorises it with
    /// every pivot below [`SOFT_PIVOT`] of its row's diagonal replaced by that diagonal
    /// (the failures in `self.work.failures`); keeps the original diagonal.
    async fn factor_soft(&mut self, counts: &mut Counts, kernels: Kernels<'_>) {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        self.assemble_model();
        for i in 0..n {
            self.limit.diag[i] = self.factor.k.get(i, i);
        }
        self.factor.k.set_pivot_tolerance(SOFT_PIVOT);
        counts.factorisations += 1;
        self.factor_tangent(kernels, n + 1).await;
        self.factor.k.set_pivot_tolerance(PIVOT_TOLERANCE);
    }

    /// Step 3 of the module doc into `self.work.d`, with the factorisation of
    /// [`Solver::factor_soft`] (its failures the reduced space); returns the reduced
    /// problem's finding.
    async fn reduced_step(&mut self, floor: f64, kernels: Kernels<'_>) -> Finding {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        let mm = s.members.len();
        // F = −r − Σ (k_model − k_now)·e·b over members whose model state differs.
        let mut rhs = std::mem::take(&mut self.limit.rhs);
        for (f, r) in rhs[..n].iter_mut().zip(&self.work.r[..n]) {
            *f = -r;
        }
        rhs[n] = 0.0;
        for (m, c) in s.members.iter().enumerate() {
            if let Some(k_model) = self.model_stiffness(m) {
                let st = &self.work.states[m];
                let extra = (k_model - st.stiffness) * st.elongation;
                for d in 0..3 {
                    let f = extra * st.direction[d];
                    rhs[c.link.dofs[d]] += f;
                    rhs[c.link.dofs[3 + d]] -= f;
                }
            }
        }
        rhs[n] = 0.0;
        self.limit.rhs = rhs;
        // The factor of K' (each failed pivot raised to its diagonal) solves.
        self.factor.k.force_factored();
        self.work.d.copy_from_slice(&self.limit.rhs);
        kernels
            .solve(&s, self.sample_key, &mut self.factor.k, &mut self.work.d)
            .await;
        self.work.d[n] = 0.0;
        let p = self.work.failures.len();
        if p == 0 {
            return Finding::Step { selected: false };
        }
        if self.limit.w.len() < p {
            self.limit.w.resize_with(p, || vec![0.0; n + 1]);
        }
        for k in 0..p {
            let f = self.work.failures[k];
            let spring = self.limit.diag[f.index].abs().max(f64::MIN_POSITIVE) - f.pivot;
            let w = &mut self.limit.w[k];
            w.fill(0.0);
            w[f.index] = spring;
            kernels
                .solve(&s, self.sample_key, &mut self.factor.k, w)
                .await;
            w[n] = 0.0;
            let scale = max_abs(&w[..n]);
            if scale > 0.0 {
                for x in w.iter_mut() {
                    *x /= scale;
                }
            }
        }
        let mut red = std::mem::take(&mut self.limit.reduced);
        red.reset(p);
        for (k, w) in self.limit.w[..p].iter().enumerate() {
            red.force[k] = dot_n(&w[..n], &self.limit.rhs[..n]);
        }
        let mut along = vec![0.0; p + 1];
        let mut delta: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; p + 1]);
        for m in 0..mm {
            let c = &s.members[m];
            let st = &self.work.states[m];
            let k = self.model_stiffness(m).unwrap_or(st.stiffness);
            let n_over_l = st.force / st.length;
            let model_slack = self.factor.factor_slack[m];
            let kq = if c.limit && model_slack && self.exactly_one_sided(m) {
                self.sample.tension[m]
            } else {
                0.0
            };
            if k == 0.0 && n_over_l == 0.0 && kq == 0.0 {
                continue;
            }
            let dofs = &c.link.dofs;
            for (j, v) in self.limit.w[..p]
                .iter()
                .map(|w| w.as_slice())
                .chain(std::iter::once(self.work.d.as_slice()))
                .enumerate()
            {
                let dv = [
                    v[dofs[3]] - v[dofs[0]],
                    v[dofs[4]] - v[dofs[1]],
                    v[dofs[5]] - v[dofs[2]],
                ];
                along[j] =
                    st.direction[0] * dv[0] + st.direction[1] * dv[1] + st.direction[2] * dv[2];
                for (d, x) in delta.iter_mut().zip(dv) {
                    d[j] = x;
                }
            }
            red.add_member(k, n_over_l, &along, &delta, kq, st.elongation);
        }
        red.symmetrise();
        let tau = 1e3 * floor / self.shortest_member();
        let finding = red.classify(tau, 10.0 * floor);
        if let Finding::Step { .. } = finding {
            for (k, w) in self.limit.w[..p].iter().enumerate() {
                let a = red.a[k];
                for (d, x) in self.work.d[..n].iter_mut().zip(&w[..n]) {
                    *d += a * x;
                }
            }
        }
        self.limit.reduced = red;
        finding
    }
}
