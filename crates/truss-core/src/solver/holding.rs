//! How firmly a converged sample is held: its *holding force*, the largest force on one node
//! of the top surface that, to first order, moves θ_P by at most 1 % and makes no bearing
//! one-sided member let go.
//!
//! At the equilibrium `u` with tangent stiffness `K(u)` \[N/mm\] (the true tangent: the
//! members that bear, the slack members at their working ratio (at the limit `r → 0`: none,
//! and a one-sided member at its kink counts as slack), and the geometric stiffness of the
//! member forces), a small load `F·t` on top node `j` (`t` a unit vector, `F` in N)
//! moves the nodes by `Δu = F·K⁻¹·e_{j,t}`, and with it
//!
//! ```text
//! θ_P   by  F·gᵀz_t,            g = ∂θ_P/∂u [rad/mm] (measure::theta_gradient), z_t = K⁻¹e_{j,t}
//! N_m   by  F·k_e,m·n_mᵀΔz_t    (Δz = z at member m's second node − at its first)
//! ```
//!
//! With the three unit loads along the axes at node `j` solved (`z_x, z_y, z_z`), the
//! worst direction for each effect is along its vector of three rates, so the loads that
//! first reach each limit are
//!
//! ```text
//! F_tilt,j = 0.01·θ_P / |s_j|,           s_j = (gᵀz_x, gᵀz_y, gᵀz_z)             [N]
//! F_m,j    = σ_m·N_m / |ρ_m,j|,           ρ_m,j = k_e,m·(n_mᵀΔz_x, n_mᵀΔz_y, n_mᵀΔz_z)
//! F_hold   = min over top nodes j of min(F_tilt,j, min over bearing one-sided m of F_m,j)
//! ```
//!
//! (`σ_m` +1 for a tension-only member, −1 for a compression-only one, so `σ_m·N_m ≥ 0`
//! while it bears). Below `F_hold` the sample stays the state it was solved in and θ_P moves
//! by less than 1 %; at `F_hold` either θ_P has moved by 1 %, or a bearing member (a cable,
//! a joint on its hole's edge) lets go, after which what holds the top is what is left.
//!
//! A sample whose top is framed by bearing members has a holding force of millinewtons to
//! newtons; a stage held only by a pretension of a few millinewtons, of micronewtons; a
//! stage held by nothing at the limit (a floating stage), 0: there θ_P
//! rests on effects the model leaves out (friction in the joints, the diagonals' bending
//! stiffness, the assembly's history), and a touch, a draught or gravity in a test moves
//! it.
//!
//! A member that bears less than the solve resolves (`σ·N` within a thousand times the
//! force floor) sits at its kink, as slack as it is taut, and is not counted: it lets go
//! under any load, and that changes nothing. The holding force is `0` where `K(u)` is not
//! positive definite at the equilibrium (the state is not stable against some small load),
//! and it is not computed where the model's bars frame the tilt (the prism without pin joints, as for
//! [`crate::SolveReport::floating`]), without a top surface, or where a top node is a
//! joint's hole node (its position is its joint's, not an unknown to load).

use super::Solver;
use super::held::{HOLDING_FRACTION, Holding, HoldingLimit};
use super::lanes::Kernels;
use crate::measure::theta_gradient;
use crate::structure::FIXED;
use std::sync::Arc;

/// A one-sided member counts as bearing when `σ·N` is above this many times the solve's
/// force floor (`residual_floor` times the largest member force): below, its force is
/// within what the solve resolves, and it sits at its kink.
const GRAZING_FACTOR: f64 = 1e3;

impl Solver {
    /// The holding force of the converged point (module doc), whose force test's floor is
    /// `force_floor` \[N\]; `None` where it is not computed. Changes only scratch state (the
    /// solve is over): the factorisation, its slack set, the pinned cables and the scratch
    /// vectors.
    pub(super) async fn compute_holding(
        &mut self,
        force_floor: f64,
        kernels: Kernels<'_>,
    ) -> Option<Holding> {
        let s = Arc::clone(&self.structure);
        if s.tilt_framed {
            return None;
        }
        let top = s.top_surface.as_ref()?;
        if top.nodes.iter().any(|&i| s.hole_joint[i].is_some()) {
            return None;
        }
        let theta = self.distortion()?.theta_p;
        let x = top.nodes.map(|i| s.node_xyz[i]);
        let u = top.nodes.map(|i| self.displacement(i));
        let gradient = theta_gradient(x, u, top.reference_normal)?;
        let g = &mut self.work.holding_gradient;
        g.fill(0.0);
        for (k, &node) in top.nodes.iter().enumerate() {
            for (dir, &dof) in s.node_dofs[node].iter().enumerate() {
                if dof != FIXED {
                    g[dof as usize] += gradient[k][dir];
                }
            }
        }
        // The true tangent at the equilibrium: no cable switched or pinned, no shift; at the
        // limit, a one-sided member with nothing on its slack side that carries no more than
        // the solve resolves sits at its kink and resists nothing a load compresses it by: it
        // counts as slack (a floating stage's cables).
        let grazing = GRAZING_FACTOR * force_floor;
        for (m, c) in s.members.iter().enumerate() {
            let st = &self.work.states[m];
            self.factor.factor_slack[m] = st.slack
                || (c.is_cable
                    && self.sample.members[m].compression_ratio == 0.0
                    && c.sense * st.force <= grazing);
        }
        self.step.pinned.fill(false);
        self.assemble_model();
        if !self.factor_tangent(kernels, 1).await {
            return Some(Holding {
                force: 0.0,
                node: top.nodes[0],
                direction: [0.0; 3],
                limit: HoldingLimit::Unstable,
            });
        }
        let n = s.free;
        let mut best: Option<Holding> = None;
        for &node in &top.nodes {
            let mut tilt = [0.0; 3];
            for (dir, &dof) in s.node_dofs[node].iter().enumerate() {
                if dof == FIXED {
                    self.work
                        .holding_rates
                        .iter_mut()
                        .for_each(|r| r[dir] = 0.0);
                    continue;
                }
                let z = &mut self.work.scratch;
                z.fill(0.0);
                z[dof as usize] = 1.0;
                kernels
                    .solve(
                        &s,
                        self.sample_key,
                        &mut self.factor.k,
                        &mut self.work.scratch,
                    )
                    .await;
                let z = &mut self.work.scratch;
                z[n] = 0.0;
                tilt[dir] = self.work.holding_gradient[..n]
                    .iter()
                    .zip(&z[..n])
                    .map(|(a, b)| a * b)
                    .sum();
                for ((c, st), rate) in s
                    .members
                    .iter()
                    .zip(&self.work.states)
                    .zip(self.work.holding_rates.iter_mut())
                {
                    let dofs = &c.link.dofs;
                    let along = st.direction[0] * (z[dofs[3]] - z[dofs[0]])
                        + st.direction[1] * (z[dofs[4]] - z[dofs[1]])
                        + st.direction[2] * (z[dofs[5]] - z[dofs[2]]);
                    rate[dir] = st.stiffness * along;
                }
            }
            let mut consider = |force: f64, rates: [f64; 3], sign: f64, limit: HoldingLimit| {
                let size = (rates[0] * rates[0] + rates[1] * rates[1] + rates[2] * rates[2]).sqrt();
                if !(size > 0.0 && size.is_finite()) {
                    return;
                }
                let f = force / size;
                if best.is_none_or(|b| f < b.force) {
                    best = Some(Holding {
                        force: f,
                        node,
                        direction: rates.map(|r| sign * r / size),
                        limit,
                    });
                }
            };
            consider(HOLDING_FRACTION * theta, tilt, 1.0, HoldingLimit::Tilt);
            for (m, (c, st)) in s.members.iter().zip(&self.work.states).enumerate() {
                let one_sided = c.is_cable && c.compression_ratio < 1.0;
                // A member that bears less than the solve resolves sits at its kink: slack
                // as much as taut (it lets go under any load, and that changes nothing).
                let bearing = c.sense * st.force;
                if one_sided && !st.slack && bearing > grazing {
                    // The load that lowers σ·N fastest: against σ·ρ.
                    let rates = self.work.holding_rates[m];
                    consider(
                        bearing,
                        rates,
                        -c.sense,
                        HoldingLimit::Release { member: m },
                    );
                }
            }
        }
        best
    }
}
