//! One-sided members at their limit: cables of compression ratio 0 solved exactly at
//! `r = 0`, by continuation in `r` with exact steps where the tangent is soft.
//!
//! ## The answer
//!
//! A cable of model ratio 0 carries nothing in compression (the paper's Table 1); a pin joint
//! in free play carries nothing across its clearance. Where such members carry nothing, the
//! equilibrium of `r = 0` is not always a point (a stage whose members all carry nothing can
//! sit anywhere in a region), so the answer is defined as a limit: with the cables of ratio
//! 0 given a compression ratio `ρ`, the equilibrium `u(ρ)` is continued from `ρ₀ =`
//! [`FIRST_RATIO`] down to `ρ → 0`, and the answer is `lim_{ρ→0} u(ρ)`. That
//! limit is an equilibrium of `r = 0` itself, and it is:
//! - where a stage is held by members that bear, that equilibrium (their axial stiffness, or
//!   the geometric stiffness `N/L` of whatever force they carry, however small);
//! - where a panel's frame is compressed and its bracing slack, the state after the panel has
//!   racked until a diagonal engages (at `ρ` below `N/(L·k)` such a panel is unstable);
//! - where members carry nothing at all (a stage floating in its joints' clearances), the
//!   position of least compression energy `Q = Σ ½·k·e²` of the slack cables among the
//!   equilibria (the leading order of `ρ·Q`), which puts a floating stage's diagonals at
//!   their natural length where they can be.
//!
//! ## The method
//!
//! 1. **The anchor** at `ρ₀`: the linearised problem's one-sided solution from the rest
//!    state ([`start`]: the bearing set found by primal–dual active-set rounds on the
//!    linear problem), then the ordinary Newton iteration ([`Solver::newton_warm`]) at
//!    `ρ₀`.
//! 2. **An attempt at `ρ = 0`** from the converged point ([`newton`]: a Newton iteration
//!    whose steps are exact where the tangent is soft, [`reduced`]), watching the bearing
//!    set: if no member changes side and nothing falls on the way, the branch reaches the
//!    limit with the set it has, and the attempt's end is the answer.
//! 3. Otherwise the attempt is abandoned, the point restored, and the next stage solved at
//!    a tenfold smaller ratio (ordinary Newton, warm-started), then step 2 again; after
//!    [`LAST_RATIO`], the last attempt at 0 runs to convergence without watching.
//!
//! 4. **Where a stage does not converge** (Newton at `ρ₀` from the linearised start, or at a
//!    tenfold smaller ratio from the last stage: a tall truss whose many panels rack at
//!    once, such as the 300-stage prism with pin joints), the stage's ratio is reached by
//!    [`Solver::continue_down`] instead: from [`FALLBACK_RATIO`] (for the anchor) or from
//!    the last converged stage, in steps of `log₁₀ ρ` that halve where Newton fails. A
//!    sample whose tenfold stages all converge runs exactly the operations it ran before.
//!    Where even those steps fail down to [`MIN_LOG_STEP`] below the first ratio (a tall
//!    truss whose stages below `ρ ≈ 1e-7` stall at out-of-balance forces of 1e-7 to 1e-5 N),
//!    the continuation ends at the stage it reached: that stage is the last, and the last
//!    attempt at 0 starts from it.
//!
//! At `ρ = 0` itself nothing is regularised: a slack cable's compression stiffness is
//! exactly zero. A watched attempt that does not converge is abandoned as an event is.
//! An attempt whose step meets more free directions than its dense reduced problem takes
//! (`MAX_REDUCED` of the `newton` module: a tall truss with many stages floating at once)
//! does not converge either.
//! Where even the last attempt does not converge (a loaded stage coming to rest against
//! its joints' contacts, in about 1 of 40 Fig. 16 samples under a top load of 1 nN; or a
//! 300-stage prism with free play whose last attempt meets 1,653 free directions), the
//! last stage's equilibrium stands for the limit: at [`LAST_RATIO`] the slack diagonals'
//! compression stiffness is 4e-10 N/mm, and what it holds moves by that fraction of what a
//! member that bears would. A stalled continuation's last stage is at a larger ratio
//! (4e-9 to 2e-7 in the 300-stage samples measured), and holds more. Either way the solve
//! reports the ratio ([`SolveReport::limit_ratio`]), and the shard line with it.

mod eigen;
mod newton;
mod reduced;
mod start;
pub(super) mod work;

use super::lanes::Kernels;
use super::{SolveReport, Solver};
use crate::SolveError;
use newton::{Counts, StageEnd};
use std::sync::Arc;
use work::{KINK, SOFT_PIVOT};

/// The first ratio of the continuation: the one the cables of ratio 0 are compiled with.
const FIRST_RATIO: f64 = crate::structure::LIMIT_RATIO;

/// The anchor where Newton at [`FIRST_RATIO`] does not converge from the linearised start:
/// stiff enough that no panel racks (its slack members a hundredth of their bearing
/// stiffness).
const FALLBACK_RATIO: f64 = 1e-2;

/// The smallest step of [`Solver::continue_down`], in decades of the ratio.
const MIN_LOG_STEP: f64 = 1.0 / 128.0;

/// The last positive ratio of the continuation.
const LAST_RATIO: f64 = 1e-12;

impl Solver {
    /// Step 1 of the module doc at `ratio`: the linearised start from rest, then Newton
    /// there. Where Newton fails, the work it did is counted all the same (the start's
    /// factorisations, and the iterations of a Newton that did not converge), as
    /// [`Solver::continue_down`] counts its failed steps: a sample's iterations are all the
    /// linear solves it took, on the path it ended on or not.
    async fn anchor_at(
        &mut self,
        ratio: f64,
        counts: &mut Counts,
        kernels: Kernels<'_>,
    ) -> Result<(), SolveError> {
        self.set_limit_ratio(ratio);
        self.work.u.fill(0.0);
        let mut start_factorisations = 0;
        self.linearised_from_rest(&mut start_factorisations, kernels)
            .await;
        counts.factorisations += start_factorisations;
        let r = match self.newton_warm(kernels).await {
            Ok(r) => r,
            Err(e) => {
                if let SolveError::NotConverged { iterations, .. } = e {
                    counts.iterations += iterations;
                }
                return Err(e);
            }
        };
        counts.iterations += r.iterations;
        counts.factorisations += r.factorisations;
        Ok(())
    }

    /// Continues the converged equilibrium at ratio `from` (the current point) down to
    /// `to < from`, where the tenfold steps of the module doc do not converge: steps of
    /// `log₁₀ ρ` that halve where Newton at the next ratio does not converge from the last
    /// converged point (restored), and grow by half again after a success, down to
    /// [`MIN_LOG_STEP`] decades. Each stage is [`Solver::newton_warm`], so the equilibrium
    /// reached at `to` is that of the tenfold path wherever both converge. Where the steps
    /// fail down to [`MIN_LOG_STEP`], the point and the ratio are the last converged
    /// stage's, and the error carries that ratio.
    async fn continue_down(
        &mut self,
        from: f64,
        to: f64,
        counts: &mut Counts,
        kernels: Kernels<'_>,
    ) -> Result<(), (SolveError, f64)> {
        let n = self.structure.free;
        // The last converged point and its ratio, restored where a step fails.
        self.limit.saved[..n].copy_from_slice(&self.work.u[..n]);
        let (mut at, end) = (from.log10(), to.log10());
        let mut reached = from;
        let mut step: f64 = 0.5;
        loop {
            let next = (at - step).max(end);
            self.set_limit_ratio(if next <= end { to } else { 10f64.powf(next) });
            match self.newton_warm(kernels).await {
                Ok(r) => {
                    counts.iterations += r.iterations;
                    counts.factorisations += r.factorisations;
                    if next <= end {
                        return Ok(());
                    }
                    at = next;
                    reached = 10f64.powf(next);
                    self.limit.saved[..n].copy_from_slice(&self.work.u[..n]);
                    step = (step * 1.5).min(1.0);
                }
                Err(e) => {
                    if let SolveError::NotConverged { iterations, .. } = e {
                        counts.iterations += iterations;
                    }
                    self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
                    step *= 0.5;
                    if step < MIN_LOG_STEP {
                        self.set_limit_ratio(reached);
                        return Err((e, reached));
                    }
                }
            }
        }
    }

    /// The continuation of the module doc, from the linearised start at `ρ₀`.
    pub(super) async fn solve_limit(
        &mut self,
        kernels: Kernels<'_>,
    ) -> Result<SolveReport, SolveError> {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        // The linearised start counts as an iteration.
        let mut counts = Counts {
            iterations: 1,
            ..Counts::default()
        };
        if self
            .anchor_at(FIRST_RATIO, &mut counts, kernels)
            .await
            .is_err()
        {
            // A tall truss whose many panels rack at once: reach `ρ₀` from a stiffer
            // anchor instead (see `continue_down`).
            self.anchor_at(FALLBACK_RATIO, &mut counts, kernels).await?;
            self.continue_down(FALLBACK_RATIO, FIRST_RATIO, &mut counts, kernels)
                .await
                .map_err(|(e, _)| e)?;
        }
        let stages = (FIRST_RATIO / LAST_RATIO).log10().round() as i32;
        let mut limit_ratio = None;
        // The ratio of the last converged stage, which stands for the limit where the last
        // attempt at 0 does not converge: `LAST_RATIO`, or where the continuation stalls
        // above it, the stage it reached.
        let mut standing = LAST_RATIO;
        for stage in 1..=stages + 1 {
            self.limit.saved.copy_from_slice(&self.work.u);
            let last = stage > stages || standing > LAST_RATIO;
            // A watched attempt is speculative: one that does not converge is abandoned as
            // an event is. Where the last does not converge, the last stage stands for the
            // limit (see the module doc).
            let end = match self.relax(!last, &mut counts, kernels).await {
                Ok(end) => end,
                Err(_) if !last => StageEnd::Event,
                Err(_) => {
                    self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
                    self.set_limit_ratio(standing);
                    limit_ratio = Some(standing);
                    break;
                }
            };
            if end == StageEnd::Converged {
                break;
            }
            self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
            let ratio = FIRST_RATIO * 10f64.powi(-stage);
            self.set_limit_ratio(ratio);
            match self.newton_warm(kernels).await {
                Ok(r) => {
                    counts.iterations += r.iterations;
                    counts.factorisations += r.factorisations;
                }
                Err(_) => {
                    self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
                    let from = ratio * 10.0;
                    if let Err((_, reached)) =
                        self.continue_down(from, ratio, &mut counts, kernels).await
                    {
                        // Stalled between two stages: the stage reached is the last, and
                        // the last attempt at 0 starts from it.
                        standing = reached;
                    }
                }
            }
        }
        let eval = self.evaluate_current(kernels).await;
        let floor = self.force_floor(&eval);
        if limit_ratio.is_some() {
            // Whether the stage that stands for the limit floats, and how firmly it is held,
            // are the limit's: there its slack members carry nothing (at the stage's ratio
            // they would hold a floating stage by that ratio's stiffness, piconewtons).
            self.set_limit_ratio(0.0);
            self.evaluate_current(kernels).await;
        }
        self.holding = if self.options.holding {
            self.compute_holding(floor, kernels).await
        } else {
            None
        };
        // Floating: the members that carry force do not hold the top surface.
        let floating = self
            .holding
            .is_some_and(|h| h.limit == super::HoldingLimit::Unstable);
        Ok(SolveReport {
            iterations: counts.iterations,
            factorisations: counts.factorisations,
            residual: eval.residual,
            step: counts.step,
            slack_cables: self.slack_cable_count(),
            evaluations: self.evaluations,
            loose_joints: self.loose_joint_count(),
            soft_directions: 0,
            floating,
            holding_force: self.holding.map(|h| h.force),
            limit_ratio,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Model;
    use crate::SolveOptions;
    use crate::prism::{BacklashOptions, PrismOptions};
    use crate::solver::Perturbation;
    use crate::solver::lanes::finish;

    /// The paper's 5-stage truss with pin joints in free play (clearance 10.5 µm).
    fn pin_jointed_prism() -> Model {
        PrismOptions {
            backlash: Some(BacklashOptions {
                clearance: 0.0105,
                ..BacklashOptions::default()
            }),
            ..PrismOptions::with_stages(5)
        }
        .model()
        .unwrap()
    }

    /// Length errors \[mm\] spread over ±6.7 µm by `pick(m) mod 13` for member `m`, the
    /// diagonals shortened by 10 µm and half an error more (so that they are pretensioned).
    fn length_errors(model: &Model, pick: impl Fn(usize) -> usize) -> Vec<f64> {
        model
            .members()
            .iter()
            .enumerate()
            .map(|(m, member)| {
                let e = 0.0067 * ((pick(m) % 13) as f64 / 6.0 - 1.0);
                if member.id.starts_with("diagonal") {
                    -0.01 - 0.5 * e.abs()
                } else {
                    e
                }
            })
            .collect()
    }

    /// An anchor whose Newton does not converge (here: allowed one iteration, from the
    /// linearised start of the paper's 5-stage truss with pin joints in free play and
    /// shortened diagonals) counts its iterations in the solve's all the same, as a failed
    /// step of `continue_down` does: before, the 300-stage prism with free play fell back
    /// from such an anchor after 120 iterations that its line did not count.
    #[test]
    fn a_failed_anchor_counts_its_iterations() {
        let model = pin_jointed_prism();
        let options = SolveOptions {
            max_iterations: 1,
            ..SolveOptions::default()
        };
        let mut solver = Solver::new(&model, options).unwrap();
        assert!(solver.structure.near_the_limit());
        let errors = length_errors(&model, |m| m * 7919);
        solver
            .set_sample(Perturbation {
                length_errors: &errors,
                ..Perturbation::default()
            })
            .unwrap();
        let mut counts = Counts::default();
        let result = finish(solver.anchor_at(FIRST_RATIO, &mut counts, Kernels::OneSample));
        let Err(SolveError::NotConverged { iterations, .. }) = result else {
            panic!("one iteration should not converge: {result:?}");
        };
        assert!(iterations >= 1);
        assert_eq!(counts.iterations, iterations);
        assert!(counts.factorisations >= 1);
    }

    /// A cable that a model step engaged (its model fell along a failed pivot's direction
    /// until that cable bore) and that is still slack bears from the start of the next model
    /// step. Taken again at the same point (as where the line search stops short of the
    /// cable's kink), the step then does not fail at that pivot again: it takes fewer
    /// factorisations. Here: the first model step from the linearised start at the first
    /// ratio, on the first of the paper's Fig. 16 truss's samples (pin joints in free play,
    /// shortened diagonals) whose first step engages a cable.
    #[test]
    fn a_model_step_starts_with_the_cables_the_last_one_engaged() {
        let model = pin_jointed_prism();
        for sample in 0..40 {
            let mut solver = Solver::new(&model, SolveOptions::default()).unwrap();
            let errors = length_errors(&model, |m| (m + 1) * (sample + 7) * 7919);
            solver
                .set_sample(Perturbation {
                    length_errors: &errors,
                    ..Perturbation::default()
                })
                .unwrap();
            solver.set_limit_ratio(FIRST_RATIO);
            solver.work.u.fill(0.0);
            let mut start = 0;
            finish(solver.linearised_from_rest(&mut start, Kernels::OneSample));
            finish(solver.evaluate_current(Kernels::OneSample));
            let mut first = 0;
            finish(solver.model_step(1, &mut first, Kernels::OneSample)).unwrap();
            let engaged: Vec<usize> = (0..solver.factor.locked.len())
                .filter(|&m| solver.factor.locked[m])
                .collect();
            if engaged.is_empty() {
                continue;
            }
            assert!(engaged.iter().all(|&m| solver.work.slack[m]));
            let mut second = 0;
            finish(solver.model_step(2, &mut second, Kernels::OneSample)).unwrap();
            assert!(
                second < first,
                "sample {sample}: {second} factorisations again after engaging {engaged:?} in {first}"
            );
            return;
        }
        panic!("no sample's first model step engaged a cable");
    }
}
