//! One Newton step with the true tangent: the piecewise model of the energy at the current
//! point, minimised exactly over slack sets, or a direction of negative curvature.
//!
//! At the current point `u`, each member's elongation is linearised, `e(δ) = e + nᵀΔδ`,
//! keeping its exact piecewise axial energy `½·k_e(e)·e²`, and the geometric stiffness of
//! the current forces `(N/L)(I − n nᵀ)` is added. For a slack set `S` the model's minimiser
//! solves
//!
//! ```text
//! K(S)·δ = −r(u) − Σ_{m switched} (k_e,S − k_e,now)·e_m·b_m
//! K(S)   = Σ_m k_e,S·n nᵀ + (N_m/L_m)(I − n nᵀ)        (blocks of each member)
//! ```
//!
//! where "switched" are the cables whose state in `S` differs from now. The set is found by
//! the active-set iteration (take as the next `S` the cables with `e + nᵀΔδ < 0` until it
//! repeats), so a step changes the state of any number of cables at once, instead of one
//! line search per change.
//!
//! When such a switch does not come true (the line search stops at the cable's kink,
//! `e = 0`, and no cable changes state), the equilibrium lies on that kink, where neither
//! piece's own minimiser is: the next step is *plain* (the current set, no switching) with
//! the cables that failed to switch *pinned*, stiffened a thousandfold in the model, so the
//! step keeps their elongations at zero (the Newton step of the equality-constrained
//! problem `e_c = 0`). The line search still judges every step on the true energy.

use super::Solver;
use super::evaluate::{dot_n, max_abs};
use super::lanes::Kernels;
use crate::SolveError;

/// Most negative pivots of one factorisation whose directions engage a cable each.
const ENGAGE_AT_ONCE: usize = 32;

/// Most slack sets tried for one model step; the last step is used if none settles.
const MAX_MODEL_PIECES: u32 = 8;

/// A cable pinned at its kink gets this many times its tension stiffness in the model: the
/// step then keeps its elongation at zero, where an equilibrium on the kink lies.
const PIN_FACTOR: f64 = 1e3;

/// The first Levenberg shift μ tried where `K(S)` is not positive definite (undamped).
const SHIFT_START: f64 = 1e-9;

/// Each retry multiplies the shift by this.
const SHIFT_RAISE: f64 = 100.0;

/// Shifts are tried up to this many times the solver's damping (and at least up to
/// [`SHIFT_LIMIT_MIN`]); beyond, the structure is a mechanism.
const SHIFT_LIMIT_FACTOR: f64 = 1e3;

/// The least limit of the shift μ. It must exceed 1: a node held only by slack cables (in a
/// truss with backlash joints whose longerons float) has a diagonal of about `r·E·A/L₀`,
/// which the negative geometric stiffness `−N/L` of compressed members at it can outweigh,
/// and then `K + μ·diag(K)` is positive definite only for some μ > 1. Measured: in the
/// Fig. 16 study at σ = 6.7 µm, 1 sample in 10,000 with the diagonals' ratio 1e-6 and 2 with
/// 1e-10 failed as mechanisms with a limit of 1; with this limit they converge (the first to
/// the same θ_P as at 1e-7, within 3e-9). A true mechanism has a zero pivot whatever μ, and
/// is still refused, after two more factorisations.
const SHIFT_LIMIT_MIN: f64 = 1e4;

/// What a model step produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Step {
    /// `self.work.d` is the model's step, and `self.factor.k` the factorised `K(S)` of the slack set in
    /// `self.factor.factor_slack` (plus a Levenberg shift `μ`, usually 0).
    Newton {
        /// The shift μ.
        shift: f64,
    },
    /// `self.work.d` is a direction of negative curvature of `K(S)`; `self.factor.k` is not usable.
    Curvature,
}

impl Solver {
    /// Records which cables are slack at the current point.
    pub(super) fn update_slack(&mut self) {
        for (s, st) in self.work.slack.iter_mut().zip(&self.work.states) {
            *s = st.slack;
        }
    }

    /// Indices of the model's currently slack cables (a member in clearance holes is never
    /// listed: its halves' state is its joints').
    pub(super) fn slack_indices(&self) -> Vec<usize> {
        let s = &self.structure;
        (0..s.model_members)
            .filter(|&m| self.work.slack[m] && s.members[m].band.is_none())
            .collect()
    }

    /// The model step of the module doc, starting from the current slack set. Counts
    /// factorisations.
    ///
    /// Where `K(S)` is indefinite (a panel whose bracing is slack, compressed past the
    /// stiffness of its slack cables), the piece's minimum along the direction of negative
    /// curvature that the failed pivot gives is where the first slack cable engages: that
    /// cable is made taut (and kept so for this step) and `K(S)` factorised again. Only when
    /// no cable bounds the direction does the step become a search along it. At the limit of
    /// one-sided members, the cables one model step engaged start the next one bearing, where
    /// they are still slack (`locked` of the step's factor cache, kept until the next step).
    pub(super) async fn model_step(
        &mut self,
        iteration: u32,
        factorisations: &mut u32,
        kernels: Kernels<'_>,
    ) -> Result<Step, SolveError> {
        let n = self.structure.free;
        // The model's slack set: the current one; in a stage of the limit solver (see
        // `limit`), a one-sided member within the rounding noise of its kink bears (a
        // floating stage's cables sit at their kinks), except in a plain step, which switches
        // nothing. Elsewhere the kink band is empty and one cable engages per factorisation.
        let at_limit = self.structure.near_the_limit();
        let kink = if at_limit {
            super::limit::work::KINK * self.sample.scale
        } else {
            -1.0
        };
        let at_once = if at_limit { ENGAGE_AT_ONCE } else { 1 };
        let plain = self.step.damping > 0.0 || self.step.plain_step;
        for (m, c) in self.structure.members.iter().enumerate() {
            let se = c.sense * self.work.states[m].elongation;
            self.factor.factor_slack[m] =
                self.work.slack[m] && (plain || !c.is_cable || se.abs() > kink);
        }
        // At the limit, a cable the last model step engaged (locked) that is still slack (the
        // line search stopped short of its kink) bears from the start: the part of the truss
        // that fell onto it still rests on it, and finding that again would cost a
        // factorisation that fails at the same pivot (a third of the engagements in the
        // paper's Fig. 16 case). It is not locked in this step: the pieces may free it.
        if at_limit && !plain {
            for (slack, &engaged) in self.factor.factor_slack.iter_mut().zip(&self.factor.locked) {
                *slack &= !engaged;
            }
        }
        self.factor.locked.fill(false);
        let mut pieces = 0;
        let mut engagements = 0;
        // Whether `self.factor.kept` holds this point's assembly (kept only at the limit,
        // where a model step's pieces and engagement rounds are many: 3.1 assemblies per
        // step in the paper's Fig. 16 case, against 1.0 for the rigid prism).
        let mut kept = false;
        // The identity of `self.factor.k` as this step's last factorisation left it: while
        // it is unchanged, `k` holds the factor of the kept matrix before the switches since,
        // and (where that saves work) a factorisation starts again at the first block row
        // they change. On the 300-stage prism with free play, 61 % of the rows on average.
        let mut factored: Option<(u64, u64)> = None;
        let restart = kernels.refactors_from_a_row(&self.structure);
        while pieces < MAX_MODEL_PIECES {
            let from = if kept {
                self.reassemble_model(restart && factored == Some(self.factor.k.identity()))
            } else {
                self.assemble_model_keeping(at_limit);
                kept = at_limit;
                0
            };
            if self.step.damping > 0.0 {
                self.factor
                    .k
                    .scale_diagonal_from(from, 1.0 + self.step.damping);
            }
            *factorisations += 1;
            kernels
                .refactor(
                    &self.structure,
                    self.sample_key,
                    &mut self.factor.k,
                    &mut self.work.failures,
                    at_once,
                    from,
                )
                .await;
            factored = Some(self.factor.k.identity());
            let mut shift = self.step.damping;
            // Plain steps (the current slack set, no switching): while damped, and after a
            // switching step that did not come true.
            let damped = self.step.damping > 0.0 || self.step.plain_step;
            if let Some(&first) = self.work.failures.first() {
                if !damped && first.pivot < 0.0 && engagements < self.structure.members.len() {
                    // The first negative pivot's direction engages its first cable, and so
                    // does each later one that lies more than twice the band's reach from
                    // every pivot engaged before it (another part of the truss: its
                    // direction is its own).
                    let reach = 6 * (self.structure.bandwidth() + 1);
                    let mut engaged_at: [usize; ENGAGE_AT_ONCE] = [0; ENGAGE_AT_ONCE];
                    let mut count = 0;
                    for f in 0..self.work.failures.len() {
                        let failure = self.work.failures[f];
                        if failure.pivot >= 0.0
                            || engaged_at[..count]
                                .iter()
                                .any(|&j| failure.index < j + reach)
                        {
                            if f == 0 {
                                break;
                            }
                            continue;
                        }
                        self.factor
                            .k
                            .failed_pivot_direction(failure.index, &mut self.work.scratch);
                        let curvature = if at_limit {
                            failure.pivot
                        } else {
                            f64::INFINITY
                        };
                        if self.engage_first_cable(curvature, failure.index) {
                            engagements += 1;
                            engaged_at[count] = failure.index;
                            count += 1;
                        } else if f == 0 {
                            break;
                        }
                    }
                    if count > 0 {
                        continue;
                    }
                    self.factor
                        .k
                        .failed_pivot_direction(first.index, &mut self.work.scratch);
                    self.work.d.copy_from_slice(&self.work.scratch);
                    self.work.d[n] = 0.0;
                    if self.negative_curvature() {
                        return Ok(Step::Curvature);
                    }
                }
                shift = self
                    .factor_model(iteration, factorisations, false)?
                    .expect("a shifted factorisation never stops at a curvature");
            }
            pieces += 1;
            // Right-hand side: −r, corrected for the cables switched in the model.
            for i in 0..n {
                self.work.d[i] = -self.work.r[i];
            }
            self.work.d[n] = 0.0;
            let s = &*self.structure;
            for (m, c) in s.members.iter().enumerate() {
                if let Some(k_model) = self.model_stiffness(m) {
                    let st = &self.work.states[m];
                    let extra = (k_model - st.stiffness) * st.elongation;
                    for d in 0..3 {
                        let f = extra * st.direction[d];
                        self.work.d[c.link.dofs[d]] += f;
                        self.work.d[c.link.dofs[3 + d]] -= f;
                    }
                }
            }
            self.work.d[n] = 0.0;
            kernels
                .solve(
                    &self.structure,
                    self.sample_key,
                    &mut self.factor.k,
                    &mut self.work.d,
                )
                .await;
            if damped {
                // Plain steps keep the current slack set: with no switched cables the
                // direction −(K + μ·diag K)⁻¹·r descends, whatever the model says, and
                // converges to the minimum of the current piece (or the line search takes it
                // to the piece's edge).
                return Ok(Step::Newton { shift });
            }
            // The slack set the model predicts at the step.
            let mut settled = true;
            for (m, c) in s.members.iter().enumerate() {
                if !c.is_cable {
                    continue;
                }
                let e = self.predicted_elongation(m, &self.work.d);
                let slack =
                    c.sense * e < 0.0 && c.compression_ratio < 1.0 && !self.factor.locked[m];
                // A member predicted within the noise of its kink keeps its state: a floating
                // stage's cables sit at their kinks, and would flip at every piece.
                if (c.sense * e).abs() <= kink {
                    continue;
                }
                if slack != self.factor.factor_slack[m] {
                    settled = false;
                    self.factor.factor_slack[m] = slack;
                }
            }
            if settled {
                return Ok(Step::Newton { shift });
            }
        }
        // No settled set: refactorise for the last set so that `self.factor.k` matches
        // `self.factor.factor_slack`, and keep the step computed before (the line search copes).
        self.work.scratch.copy_from_slice(&self.work.d);
        let shift = self
            .factor_model(iteration, factorisations, false)?
            .expect("a shifted factorisation never stops at a curvature");
        self.work.d.copy_from_slice(&self.work.scratch);
        Ok(Step::Newton { shift })
    }

    /// Assembles the model's `K(S)` for `S = self.factor.factor_slack` and factorises it (with
    /// the solver's current damping μ₀ as a Levenberg shift `K + μ·diag(K)`); where it is not
    /// positive definite, retries with μ = 1e-9 (or 100·μ₀), ×100 each time, up to
    /// max([`SHIFT_LIMIT_MIN`], 1000·μ₀). Returns `Some(μ)` (the `Option` is for callers that
    /// stop at a curvature; this one never does unless `allow_curvature`, which leaves the
    /// direction of the first negative pivot in `self.work.d` and returns `None`).
    pub(super) fn factor_model(
        &mut self,
        iteration: u32,
        factorisations: &mut u32,
        allow_curvature: bool,
    ) -> Result<Option<f64>, SolveError> {
        let mut shift = self.step.damping;
        let limit = (SHIFT_LIMIT_FACTOR * self.step.damping).max(SHIFT_LIMIT_MIN);
        loop {
            self.assemble_model();
            let s = &*self.structure;
            if shift > 0.0 {
                self.factor.k.scale_diagonal(1.0 + shift);
            }
            *factorisations += 1;
            match self.factor.k.factor() {
                Ok(()) => return Ok(Some(shift)),
                Err(e) => {
                    if allow_curvature && shift == 0.0 && e.pivot < 0.0 {
                        self.factor
                            .k
                            .failed_pivot_direction(e.index, &mut self.work.d);
                        self.work.d[s.free] = 0.0;
                        return Ok(None);
                    }
                    shift = if shift == 0.0 {
                        SHIFT_START
                    } else {
                        shift * SHIFT_RAISE
                    };
                    if shift > limit {
                        let (node, dof) = s.describe_dof(e.index);
                        return Err(SolveError::Mechanism {
                            iteration,
                            node,
                            dof,
                        });
                    }
                }
            }
        }
    }

    /// With `self.work.scratch` a direction of negative curvature `v` of `K(S)`, finds the slack
    /// cable of `S` that engages first along `±v` (the sign that lowers the energy first,
    /// else the other), makes it taut and locked in `S`, and returns true; false if no slack
    /// cable engages. See [`Solver::first_to_engage`] for `curvature` and `last_row`.
    fn engage_first_cable(&mut self, curvature: f64, last_row: usize) -> bool {
        let Some(m) = self.first_to_engage(curvature, last_row) else {
            return false;
        };
        self.factor.factor_slack[m] = false;
        self.factor.locked[m] = true;
        true
    }

    /// With `self.work.scratch` a direction `v` in which the model falls, zero above row
    /// `last_row` (a failed pivot's, whose row it is), the slack cable of the model's set `S`
    /// that engages first along `±v` (the sign that lowers the energy first, else the other).
    /// Only a cable whose stiffness once taut outweighs the direction's negative curvature
    /// (`k·rate² > −curvature`, N/mm per unit of `v`) counts: pass infinity to count every
    /// cable. Of cables that engage at the same point, the first in model order.
    ///
    /// Only the cables that reach a row up to `last_row` are looked at
    /// ([`Structure::one_sided_by_row`](crate::structure::Structure)): every other one's rate
    /// along `v` is zero, so it cannot engage. On a 300-stage prism with free play, whose
    /// engagement rounds look for a cable along some thirty directions each, the scan over
    /// every member was a fifth of a sample's instructions.
    pub(super) fn first_to_engage(&self, curvature: f64, last_row: usize) -> Option<usize> {
        let n = self.structure.free;
        let v = &self.work.scratch;
        let descent = if dot_n(&self.work.r[..n], &v[..n]) > 0.0 {
            -1.0
        } else {
            1.0
        };
        let reached = self
            .structure
            .one_sided_by_row
            .partition_point(|&(row, _)| row <= last_row);
        let candidates = &self.structure.one_sided_by_row[..reached];
        for sign in [descent, -descent] {
            let mut first: Option<(f64, usize)> = None;
            for &(_, m) in candidates {
                if !self.factor.factor_slack[m] {
                    continue;
                }
                let c = &self.structure.members[m];
                let st = &self.work.states[m];
                let rate = sign * c.sense * self.elongation_rate(m, v);
                let k = self.sample.tension[m] * (1.0 - self.sample.members[m].compression_ratio);
                if rate > 0.0 && k * rate * rate > -curvature {
                    let at = (-c.sense * st.elongation).max(0.0) / rate;
                    if first.is_none_or(|(best, b)| at < best || (at == best && m < b)) {
                        first = Some((at, m));
                    }
                }
            }
            if first.is_some() {
                return first.map(|(_, m)| m);
            }
        }
        None
    }

    /// Member `m`'s elongation after the step `d` to first order \[mm\]: the current one plus
    /// its direction dotted with its ends' relative step (summed in that order).
    #[inline]
    pub(super) fn predicted_elongation(&self, m: usize, d: &[f64]) -> f64 {
        let (dofs, st) = (&self.structure.members[m].link.dofs, &self.work.states[m]);
        st.elongation
            + st.direction[0] * (d[dofs[3]] - d[dofs[0]])
            + st.direction[1] * (d[dofs[4]] - d[dofs[1]])
            + st.direction[2] * (d[dofs[5]] - d[dofs[2]])
    }

    /// The first-order change of member `m`'s elongation along the displacement `v` \[mm per
    /// unit of `v`\]: its direction dotted with its ends' relative displacement.
    #[inline]
    pub(super) fn elongation_rate(&self, m: usize, v: &[f64]) -> f64 {
        let (dofs, n) = (
            &self.structure.members[m].link.dofs,
            &self.work.states[m].direction,
        );
        n[0] * (v[dofs[3]] - v[dofs[0]])
            + n[1] * (v[dofs[4]] - v[dofs[1]])
            + n[2] * (v[dofs[5]] - v[dofs[2]])
    }

    /// Assembles into `self.factor.k` the model stiffness `K(S)` of the module doc at the current
    /// point, for `S = self.factor.factor_slack`: the true tangent when `S` is the current slack set.
    pub(super) fn assemble_model(&mut self) {
        self.assemble_model_keeping(false);
    }

    /// [`Solver::assemble_model`]; with `keep`, also keeps the assembly for
    /// [`Solver::reassemble_model`] at the same point.
    pub(super) fn assemble_model_keeping(&mut self, keep: bool) {
        let s = &*self.structure;
        s.begin_assembly(&mut self.factor.k);
        for (m, c) in s.members.iter().enumerate() {
            let block = self.model_block(m);
            s.add_block(&mut self.factor.k, &c.link, &block);
        }
        s.set_identity_rows(&mut self.factor.k);
        if keep {
            self.factor
                .kept
                .keep(&mut self.factor.k, &self.factor.factor_slack);
        }
    }

    /// Member `m`'s tangent block in the model `K(S)` (its model stiffness, see
    /// [`Solver::model_stiffness`]), as [`Structure::add_block`] takes it.
    #[inline]
    fn model_block(&self, m: usize) -> [f64; 6] {
        let st = &self.work.states[m];
        st.tangent_block_with(self.model_stiffness(m).unwrap_or(st.stiffness))
    }

    /// [`Solver::assemble_model`] at the point of the last whole assembly that was kept
    /// (the members' states and the pinned cables unchanged since), where only cables'
    /// places in `S` changed: the slots those cables reach are summed again over all their
    /// members, in order ([`Structure::reassemble_slots`]), and the kept matrix is copied
    /// into `self.factor.k`. The same bits as a whole assembly: every slot is the same sum,
    /// in the same order, of the same blocks.
    ///
    /// Where `factored` (`self.factor.k` holds the factorisation of the kept matrix before
    /// these switches), only the block rows from the first that changed are copied: the
    /// earlier ones keep that factor, for
    /// [`BlockBandMatrix::refactor_collecting`](crate::block::BlockBandMatrix::refactor_collecting).
    /// Returns the first row copied (0 unless `factored`).
    pub(super) fn reassemble_model(&mut self, factored: bool) -> usize {
        let mut kept = std::mem::take(&mut self.factor.kept);
        let first = kept.reassemble(&self.structure, &self.factor.factor_slack, |m| {
            self.model_block(m)
        });
        let from = if factored { first } else { 0 };
        kept.copy_rows_into(&mut self.factor.k, from);
        self.factor.kept = kept;
        from
    }

    /// A cable's axial stiffness in the model when it differs from its present one: pinned
    /// at its kink ([`PIN_FACTOR`] times its tension stiffness), or switched in `S`; `None`
    /// otherwise.
    #[inline]
    pub(super) fn model_stiffness(&self, m: usize) -> Option<f64> {
        let c = &self.structure.members[m];
        if !c.is_cable {
            return None;
        }
        let k = self.sample.tension[m];
        if self.step.pinned[m] {
            Some(PIN_FACTOR * k)
        } else if self.factor.factor_slack[m] != self.work.states[m].slack {
            Some(if self.factor.factor_slack[m] {
                self.sample.members[m].compression_ratio * k
            } else {
                k
            })
        } else {
            None
        }
    }

    /// Turns the direction left in `self.work.d` by a failed factorisation (whose curvature
    /// `dᵀK d` is the negative pivot) into a step direction: scaled to max |d| = 1 mm and
    /// signed so that the energy decreases along it. Returns false if it is unusable.
    pub(super) fn negative_curvature(&mut self) -> bool {
        let n = self.structure.free;
        let scale = max_abs(&self.work.d[..n]);
        if !(scale.is_finite() && scale > 0.0) {
            return false;
        }
        let sign = if dot_n(&self.work.r[..n], &self.work.d[..n]) > 0.0 {
            -1.0
        } else {
            1.0
        };
        for x in &mut self.work.d[..n] {
            *x *= sign / scale;
        }
        true
    }
}
