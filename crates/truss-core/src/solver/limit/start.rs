//! The continuation's starting point: the linearised problem at the first ratio, solved
//! by the primal–dual active-set iteration from the state at rest.
//!
//! With the kinematics linearised about the nominal geometry (`e_m = b_mᵀu + s_m`, see the
//! `linearised` module), the energy is convex and piecewise quadratic in the set of slack
//! one-sided members; its minimiser is found by taking as the first set the members slack
//! at rest (`σ·s_m < 0`: a pin joint in its clearance, a cable made longer than its span),
//! solving that piece, and taking as the next set the members whose linearised elongation
//! is below their kink, until the set repeats. From rest that takes a few pieces in the
//! paper's truss with backlash (the joints loose, the shortened diagonals taut: each stage
//! an octahedron of battens and diagonals; then the longerons that the diagonals pull onto
//! their holes' edges). Each piece is one banded factorisation of the material stiffness of
//! its set, with the sample's own member stiffnesses.

use super::super::Solver;
use super::super::lanes::Kernels;
use crate::linearised::{gather_b, scatter_b};
use std::sync::Arc;

/// Most pieces; the last one's solution is the start if none repeats.
const MAX_PIECES: u32 = 30;

/// A member whose linearised elongation is within this fraction of the sample's largest
/// initial stretch of its kink keeps its state (the kinks of a floating stage's cables).
const KINK_NOISE: f64 = 1e-8;

impl Solver {
    /// The linearised start of the module doc into `self.work.u`; counts factorisations.
    /// Returns false (leaving `u = 0`) where a piece's stiffness is not positive definite
    /// (a mechanism of that set).
    pub(super) async fn linearised_from_rest(
        &mut self,
        factorisations: &mut u32,
        kernels: Kernels<'_>,
    ) -> bool {
        let s = Arc::clone(&self.structure);
        let n = s.free;
        for (m, c) in s.members.iter().enumerate() {
            let s0 = self.sample.members[m].initial_stretch;
            self.factor.factor_slack[m] = c.is_cable && c.sense * s0 < 0.0;
        }
        let noise = KINK_NOISE * self.sample.scale;
        for _ in 0..MAX_PIECES {
            let slack = &self.factor.factor_slack;
            let members = &self.sample.members;
            let tension = &self.sample.tension;
            // `assemble_material` scales each member's nominal `E·A/L₀`; the sample's is
            // `tension[m]`.
            s.assemble_material(&mut self.factor.k, |m| {
                let own = tension[m] * s.members[m].natural_length / s.members[m].rigidity;
                if slack[m] {
                    own * members[m].compression_ratio
                } else {
                    own
                }
            });
            self.work.u.copy_from_slice(&self.sample.loads);
            for m in 0..s.members.len() {
                let mut k = self.sample.tension[m];
                if self.factor.factor_slack[m] {
                    k *= self.sample.members[m].compression_ratio;
                }
                scatter_b(
                    &s,
                    m,
                    -k * self.sample.members[m].initial_stretch,
                    &mut self.work.u,
                );
            }
            *factorisations += 1;
            if !self.factor_tangent(kernels, 1).await {
                self.work.u.fill(0.0);
                return false;
            }
            kernels
                .solve(&s, self.sample_key, &mut self.factor.k, &mut self.work.u)
                .await;
            self.work.u[n] = 0.0;
            let mut settled = true;
            for (m, c) in s.members.iter().enumerate() {
                if !c.is_cable {
                    continue;
                }
                let e = c.sense
                    * (gather_b(&s, m, &self.work.u) + self.sample.members[m].initial_stretch);
                let slack = e < 0.0;
                if slack != self.factor.factor_slack[m] && e.abs() > noise {
                    settled = false;
                    self.factor.factor_slack[m] = slack;
                }
            }
            if settled {
                return true;
            }
        }
        true
    }
}
