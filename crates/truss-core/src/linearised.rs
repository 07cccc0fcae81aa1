//! The linearised problem, solved exactly: the starting point and chord operator of Newton.
//!
//! With the kinematics linearised about the nominal geometry, a member's elongation is
//! `e_m = b_mᵀu + s_m` (`b_m` holds `∓n_m` at its two nodes' DOFs, `n_m` its nominal unit
//! direction, `s_m = L_r − L₀` its initial stretch), its force `t_m = k_m·e_m`, or `r·k_m·e_m`
//! for a slack cable, and equilibrium `Σ t_m·b_m = f` is a piecewise linear system whose
//! pieces are the slack sets `S`. Its energy is convex, so it has one solution, found by
//! the primal–dual active-set method: guess `S`, solve the linear system of that piece,
//! take as the next `S` the cables with `e < 0`, until `S` repeats.
//!
//! Each piece is solved from the shared factorisation of the all-taut material stiffness
//! `K₀ = Σ k_m b_m b_mᵀ` (factorised once per model) by the Woodbury identity: with
//! `Z = K₀⁻¹B` and `G = BᵀK₀⁻¹B` over the cables `B = [b_c]`, precomputed once, and
//! `u_lin = K₀⁻¹(f − Σ k_m s_m b_m)` (one banded solve per sample),
//!
//! ```text
//! K_S = K₀ − B_S W B_Sᵀ,   W = diag((1 − r_c)·k_c)
//! u   = u_lin + Z_S z_S,   (W⁻¹ − G_SS)·z_S = e_lin,S,   e_lin = Bᵀu_lin + s
//! ```
//!
//! where `z_c = (1 − r_c)·k_c·e_c` is the force a slack cable does *not* carry. A piece costs
//! one Cholesky of the `|S|×|S|` capacitance matrix `W⁻¹ − G_SS`, which is positive definite
//! exactly when `K_S` is; the same factor then applies `K_S⁻¹` to any vector at the cost of a
//! banded solve, which is the chord operator of the Newton iterations that follow.
//!
//! The dense Cholesky of the capacitance matrix costs `|S|³/6` multiply–adds, the banded
//! one of `K_S` about `n·b²/2` (`n` unknowns, `b` the band's width in rows); where a piece's
//! slack set is larger than [`CableBasis::max_slack`], the size at which the two are equal
//! (pin joints in free play, whose two one-sided halves are both slack), the method gives
//! way to the same iteration with a banded factorisation of `K_S` per piece
//! ([`ActiveSetFailure::LargeSlackSet`]).

use crate::capacitance::Capacitance;
use crate::structure::{CableBasis, Structure};

/// Adds `scale·b_m` to `v` (`v` has the zero slot at index `free`).
#[inline(always)]
pub(crate) fn scatter_b(s: &Structure, m: usize, scale: f64, v: &mut [f64]) {
    s.members[m].scatter_b(s.free, scale, v);
}

/// `b_mᵀ v` (`v` may omit the zero slot).
#[inline(always)]
pub(crate) fn gather_b(s: &Structure, m: usize, v: &[f64]) -> f64 {
    s.members[m].gather_b(s.free, v)
}

/// A slack set whose capacitance matrix has a pivot below this fraction of its diagonal
/// leaves a soft direction in `K_S` (a panel held only by slack cables), where the geometric
/// stiffness of the member forces, absent from `K_S`, matters: chord steps with `K_S` do not
/// converge there, so the solver goes straight to the true tangent.
pub(crate) const SOFT_PIVOT_RATIO: f64 = 1e-3;

/// The per-sample state of the active-set method: the slack set and its factorised
/// capacitance matrix, which together apply `K_S⁻¹`.
#[derive(Debug, Clone)]
pub(crate) struct ActiveSet {
    /// Positions (into `CableBasis::cables`) of the slack cables, increasing.
    pub slack: Vec<usize>,
    /// Cholesky factor of `W⁻¹ − G_SS`.
    capacitance: Capacitance,
    /// The slack positions of the capacitance factor's valid leading rows (the matrix
    /// depends only on them: `W` and `G` are the model's).
    factored: Vec<usize>,
    /// Scratch: a right-hand side over the slack set, solved in place.
    z: Vec<f64>,
    /// Scratch: linearised elongations of the cables without slack corrections.
    e_lin: Vec<f64>,
    /// Scratch: linearised elongations of the cables of the current piece.
    e: Vec<f64>,
}

/// The active-set method met a piece whose stiffness is not positive definite (a mechanism
/// with some compression ratio of zero), or did not settle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ActiveSetFailure {
    /// `K_S` is singular or indefinite.
    NotPositiveDefinite,
    /// The slack set cycled or did not settle within the iteration limit.
    NoFixedPoint,
    /// A piece's slack set is larger than [`CableBasis::max_slack`]: factorise `K_S`
    /// instead.
    LargeSlackSet,
}

impl ActiveSet {
    /// An empty active set with room for `nc` cables.
    pub fn new(nc: usize) -> Self {
        Self {
            slack: Vec::with_capacity(nc),
            capacitance: Capacitance::new(nc),
            factored: Vec::with_capacity(nc),
            z: Vec::with_capacity(nc),
            e_lin: Vec::with_capacity(nc),
            e: Vec::with_capacity(nc),
        }
    }

    /// Factorises `W⁻¹ − G_SS` for the current `slack`, keeping the rows of the last factor
    /// whose leading slack cables are the same (the factor is the same, bit for bit).
    pub fn factor(&mut self, basis: &CableBasis) -> Result<(), ActiveSetFailure> {
        let nc = basis.cables.len();
        let slack = &self.slack;
        let valid = self.capacitance.valid_rows().min(self.factored.len());
        let keep = slack
            .iter()
            .zip(&self.factored[..valid])
            .take_while(|(a, b)| a == b)
            .count();
        self.capacitance.set_from(keep, slack.len(), |i, row| {
            let a = slack[i];
            let g = &basis.g[a * nc..(a + 1) * nc];
            for (x, &b) in row.iter_mut().zip(slack) {
                *x = -g[b];
            }
            row[i] += basis.w_inv[a];
        });
        self.factored.clear();
        self.factored.extend_from_slice(slack);
        if slack.is_empty() {
            return Ok(());
        }
        self.capacitance
            .factor_from(keep)
            .map_err(|_| ActiveSetFailure::NotPositiveDefinite)
    }

    /// The number of soft directions the factorised slack set leaves: one per panel whose
    /// bracing is all slack (its capacitance pivots below [`SOFT_PIVOT_RATIO`]).
    pub fn soft_directions(&self) -> usize {
        if self.slack.is_empty() {
            0
        } else {
            self.capacitance.soft_rows(SOFT_PIVOT_RATIO)
        }
    }

    /// Sets the slack set to the cables (by position) whose `e` is negative; returns whether
    /// it changed.
    pub fn set_slack_from(&mut self, e: impl Fn(usize) -> bool, nc: usize) -> bool {
        let changed = !(0..nc).filter(|&c| e(c)).eq(self.slack.iter().copied());
        if changed {
            self.slack.clear();
            self.slack.extend((0..nc).filter(|&c| e(c)));
        }
        changed
    }

    /// Applies `K_S⁻¹` in place to `v` (length `free + 1`, zero slot last), with the slack set
    /// factorised: `K_S⁻¹v = K₀⁻¹v + Z_S·(W⁻¹ − G_SS)⁻¹·Z_Sᵀ·v`.
    pub fn apply_inverse(&mut self, s: &Structure, basis: &CableBasis, v: &mut [f64]) {
        let n = s.free;
        self.z.clear();
        for &c in &self.slack {
            let zc = &basis.z[c * n..(c + 1) * n];
            self.z
                .push(zc.iter().zip(&v[..n]).map(|(a, b)| a * b).sum());
        }
        if !self.z.is_empty() {
            self.capacitance.solve_in_place(&mut self.z);
        }
        s.nominal.solve_in_place(&mut v[..n]);
        for (&c, zc) in self.slack.iter().zip(&self.z) {
            for (vi, zi) in v[..n].iter_mut().zip(&basis.z[c * n..(c + 1) * n]) {
                *vi += zc * zi;
            }
        }
        v[n] = 0.0;
    }

    /// Solves the linearised problem (module doc) for a sample whose initial stretches are
    /// `stretch` (per member) and loads `loads`; writes `u` (length `free + 1`) and leaves
    /// the final slack set factorised. Returns the number of pieces tried; gives way
    /// ([`ActiveSetFailure::LargeSlackSet`]) at a piece with more than
    /// [`CableBasis::max_slack`] slack cables, before factorising it.
    pub fn solve_linearised(
        &mut self,
        s: &Structure,
        basis: &CableBasis,
        stretch: &[f64],
        loads: &[f64],
        u: &mut [f64],
    ) -> Result<u32, ActiveSetFailure> {
        let n = s.free;
        let nc = basis.cables.len();
        // u_lin = K₀⁻¹ (f − Σ k_m s_m b_m), with nominal k_m.
        u.copy_from_slice(loads);
        for (m, (c, st)) in s.members.iter().zip(stretch).enumerate() {
            scatter_b(s, m, -c.stiffness * st, u);
        }
        s.nominal.solve_in_place(&mut u[..n]);
        self.e_lin.clear();
        self.e_lin
            .extend(basis.cables.iter().map(|&m| gather_b(s, m, u) + stretch[m]));
        let e_lin = &self.e_lin;
        self.slack.clear();
        let sense = &basis.sense;
        self.slack
            .extend((0..nc).filter(|&c| sense[c] * e_lin[c] < 0.0));
        let mut pieces = 0;
        loop {
            pieces += 1;
            if self.slack.len() > basis.max_slack {
                return Err(ActiveSetFailure::LargeSlackSet);
            }
            self.factor(basis)?;
            self.z.clear();
            self.z.extend(self.slack.iter().map(|&c| self.e_lin[c]));
            if !self.z.is_empty() {
                self.capacitance.solve_in_place(&mut self.z);
            }
            // e = e_lin + G_{:,S} z_S; the slack set of this solution.
            // Column by column (rows of Gᵀ), each sum in the order of the slack set.
            let (slack, z, e_lin) = (&self.slack, &self.z, &self.e_lin);
            self.e.clear();
            self.e.resize(nc, -0.0);
            for (&b, zb) in slack.iter().zip(z) {
                for (e, g) in self.e.iter_mut().zip(&basis.g_t[b * nc..(b + 1) * nc]) {
                    *e += g * zb;
                }
            }
            for (e, el) in self.e.iter_mut().zip(e_lin) {
                *e += el;
            }
            let e = &self.e;
            let settled = (0..nc)
                .filter(|&c| sense[c] * e[c] < 0.0)
                .eq(slack.iter().copied());
            if settled {
                for (&c, zc) in self.slack.iter().zip(&self.z) {
                    for (ui, zi) in u[..n].iter_mut().zip(&basis.z[c * n..(c + 1) * n]) {
                        *ui += zc * zi;
                    }
                }
                u[n] = 0.0;
                return Ok(pieces);
            }
            if pieces >= 50 {
                return Err(ActiveSetFailure::NoFixedPoint);
            }
            self.slack.clear();
            self.slack
                .extend((0..nc).filter(|&c| sense[c] * self.e[c] < 0.0));
        }
    }
}
