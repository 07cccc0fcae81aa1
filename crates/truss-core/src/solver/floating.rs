//! Whether a converged sample floats: some stage's tilt held by pretension or
//! regularisation alone, not by the members that bear (see [`crate::limit`]).

use super::Solver;
use crate::structure::tilt_loads;

/// A sample floats when the members that bear take less than this share of the work of a
/// tilting load.
const BEARING_SHARE: f64 = 0.5;

impl Solver {
    /// Whether the converged point floats. For each tilting load `g` (see
    /// [`crate::structure::tilt_loads`]), `x = K_S⁻¹·g` with the linearised stiffness of the
    /// current slack set (the material stiffness of the members that bear, and the slack
    /// members' `r·k`: the geometric stiffness of the pretension is left out, so what it
    /// holds counts as not held by members), and the work `gᵀx = Σ_m k_e,m·(b_mᵀx)²` is
    /// split between the members that bear and the slack ones. Floating when the bearing
    /// share is below one half for either load, or `K_S` is not positive definite.
    ///
    /// Never for a model whose bars frame the tilt, or without a top surface (nothing to
    /// hold). Uses the Woodbury data where the model has a cable basis, else factorises
    /// `K_S`; changes only scratch state (the solve is over).
    pub(super) fn floating(&mut self) -> bool {
        let s = std::sync::Arc::clone(&self.structure);
        if s.tilt_framed {
            return false;
        }
        let n = s.free;
        let mut loads = [vec![0.0; n + 1], vec![0.0; n + 1]];
        if tilt_loads(&s, &self.work.u, &mut loads).is_none() {
            return false;
        }
        let ratio = |m: usize| {
            let st = &self.work.states[m];
            if st.slack {
                st.stiffness / self.sample.tension[m]
            } else {
                1.0
            }
        };
        match &s.basis {
            Some(basis) => {
                let states = &self.work.states;
                let nc = basis.cables.len();
                self.factor
                    .active
                    .set_slack_from(|c| states[basis.cables[c]].slack, nc);
                if self.factor.active.factor(basis).is_err() {
                    return true;
                }
            }
            None => {
                s.assemble_material(&mut self.factor.k, ratio);
                if self.factor.k.factor().is_err() {
                    return true;
                }
            }
        }
        for mut x in loads {
            let g = x.clone();
            match &s.basis {
                Some(basis) => self.factor.active.apply_inverse(&s, basis, &mut x),
                None => self.factor.k.solve_in_place(&mut x[..n]),
            }
            x[n] = 0.0;
            let total: f64 = g[..n].iter().zip(&x[..n]).map(|(a, b)| a * b).sum();
            if !(total.is_finite() && total > 0.0) {
                return true;
            }
            let bearing: f64 = s
                .members
                .iter()
                .enumerate()
                .filter(|&(m, _)| !self.work.states[m].slack)
                .map(|(m, c)| {
                    let e = crate::linearised::gather_b(&s, m, &x);
                    c.stiffness * e * e
                })
                .sum();
            if bearing < BEARING_SHARE * total {
                return true;
            }
        }
        false
    }
}
