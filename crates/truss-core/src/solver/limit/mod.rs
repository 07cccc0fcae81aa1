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
//! At `ρ = 0` itself nothing is regularised: a slack cable's compression stiffness is
//! exactly zero. A watched attempt that does not converge is abandoned as an event is.
//! Where even the last attempt does not converge (a loaded stage coming to rest against
//! its joints' contacts, in about 1 of 40 Fig. 16 samples under a top load of 1 nN), the
//! last stage's equilibrium stands for the limit: at [`LAST_RATIO`] the slack diagonals'
//! compression stiffness is 4e-10 N/mm, and what it holds moves by that fraction of what a
//! member that bears would.

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

/// The last positive ratio of the continuation.
const LAST_RATIO: f64 = 1e-12;

impl Solver {
    /// The continuation of the module doc, from the linearised start at `ρ₀`.
    pub(super) async fn solve_limit(
        &mut self,
        kernels: Kernels<'_>,
    ) -> Result<SolveReport, SolveError> {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        let mut counts = Counts::default();
        self.set_limit_ratio(FIRST_RATIO);
        self.work.u.fill(0.0);
        let mut start_factorisations = 0;
        self.linearised_from_rest(&mut start_factorisations);
        let first = self.newton_warm(kernels).await?;
        counts.factorisations += start_factorisations;
        counts.iterations = first.iterations + 1;
        counts.factorisations += first.factorisations;
        let stages = (FIRST_RATIO / LAST_RATIO).log10().round() as i32;
        for stage in 1..=stages + 1 {
            self.limit.saved.copy_from_slice(&self.work.u);
            let last = stage > stages;
            // A watched attempt is speculative: one that does not converge is abandoned as
            // an event is. Where the last does not converge, the last stage stands for the
            // limit (see the module doc).
            let end = match self.relax(!last, &mut counts, kernels).await {
                Ok(end) => end,
                Err(_) if !last => StageEnd::Event,
                Err(_) => {
                    self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
                    self.set_limit_ratio(LAST_RATIO);
                    break;
                }
            };
            if end == StageEnd::Converged {
                break;
            }
            self.work.u[..n].copy_from_slice(&self.limit.saved[..n]);
            let ratio = FIRST_RATIO * 10f64.powi(-stage);
            self.set_limit_ratio(ratio);
            let r = self.newton_warm(kernels).await?;
            counts.iterations += r.iterations;
            counts.factorisations += r.factorisations;
        }
        let eval = self.evaluate_current(kernels).await;
        let floor = self.force_floor(&eval);
        self.holding = self.compute_holding(floor, kernels).await;
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
        })
    }
}
