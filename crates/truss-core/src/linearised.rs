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
use crate::structure::Structure;

/// Woodbury data for one model: `Z = K₀⁻¹B` and `G = BᵀK₀⁻¹B` over its cables.
#[derive(Debug, Clone)]
pub(crate) struct CableBasis {
    /// Member index of each cable.
    pub cables: Vec<usize>,
    /// `Z`, column per cable, each of length `free`.
    pub z: Vec<f64>,
    /// `G`, row-major `n_c × n_c`.
    pub g: Vec<f64>,
    /// `Gᵀ`, row-major (the columns of `G`, which rounding leaves not quite symmetric).
    pub g_t: Vec<f64>,
    /// `1/((1 − r_c)·k_c)` per cable, with nominal `k_c` \[mm/N\].
    pub w_inv: Vec<f64>,
    /// `σ_c` per cable: +1 tension-only (slack when `e < 0`), −1 compression-only (slack
    /// when `e > 0`).
    pub sense: Vec<f64>,
    /// The largest slack set solved by the capacitance matrix: `⌊∛(3·n·b²)⌋`, where its
    /// Cholesky (`|S|³/6` multiply–adds) costs as much as the banded one of `K_S` (`n·b²/2`,
    /// `n` unknowns, `b = 3·(q + 1)` rows of band for `q` block off-diagonals).
    pub max_slack: usize,
}

/// A slack set whose capacitance matrix has a pivot below this fraction of its diagonal
/// leaves a soft direction in `K_S` (a panel held only by slack cables), where the geometric
/// stiffness of the member forces, absent from `K_S`, matters: chord steps with `K_S` do not
/// converge there, so the solver goes straight to the true tangent.
pub(crate) const SOFT_PIVOT_RATIO: f64 = 1e-3;

/// Models with more cables than this solve each piece by factorising `K_S` instead: the
/// capacitance matrix would cost more than the banded factorisation.
pub(crate) const MAX_WOODBURY_CABLES: usize = 96;

impl CableBasis {
    /// Precomputes `Z` and `G` with the factorised `K₀` of `s`.
    pub fn new(s: &Structure) -> Self {
        let n = s.free;
        let cables: Vec<usize> = (0..s.members.len())
            .filter(|&m| s.members[m].is_cable)
            .collect();
        let nc = cables.len();
        let mut z = vec![0.0; n * nc];
        let mut w_inv = vec![0.0; nc];
        let mut col = vec![0.0; n + 1];
        for (k, &m) in cables.iter().enumerate() {
            col.fill(0.0);
            scatter_b(s, m, 1.0, &mut col);
            s.nominal.solve_in_place(&mut col[..n]);
            z[k * n..(k + 1) * n].copy_from_slice(&col[..n]);
            let c = &s.members[m];
            w_inv[k] = c.natural_length / ((1.0 - c.compression_ratio) * c.rigidity);
        }
        let mut g = vec![0.0; nc * nc];
        for (a, &ma) in cables.iter().enumerate() {
            for b in 0..nc {
                g[a * nc + b] = gather_b(s, ma, &z[b * n..(b + 1) * n]);
            }
        }
        let mut g_t = vec![0.0; nc * nc];
        for a in 0..nc {
            for b in 0..nc {
                g_t[b * nc + a] = g[a * nc + b];
            }
        }
        let sense = cables.iter().map(|&m| s.members[m].sense).collect();
        let band = 3.0 * (s.bandwidth() as f64 + 1.0);
        let max_slack = (3.0 * n as f64 * band * band).cbrt().floor() as usize;
        Self {
            cables,
            z,
            g,
            g_t,
            w_inv,
            sense,
            max_slack,
        }
    }
}

/// Adds `scale·b_m` to `v` (`v` has the zero slot at index `free`).
#[inline(always)]
pub(crate) fn scatter_b(s: &Structure, m: usize, scale: f64, v: &mut [f64]) {
    let c = &s.members[m];
    let n = &c.unit;
    if c.link.masked {
        for k in 0..3 {
            v[c.link.dofs[k]] -= scale * n[k];
            v[c.link.dofs[3 + k]] += scale * n[k];
        }
        v[s.free] = 0.0;
        return;
    }
    let f = [scale * n[0], scale * n[1], scale * n[2]];
    let (blocks, _) = v[..s.free].as_chunks_mut::<3>();
    if let Some(x) = blocks.get_mut(c.link.ends[0]) {
        for (x, f) in x.iter_mut().zip(&f) {
            *x -= f;
        }
    }
    if let Some(x) = blocks.get_mut(c.link.ends[1]) {
        for (x, f) in x.iter_mut().zip(&f) {
            *x += f;
        }
    }
}

/// `b_mᵀ v` (`v` may omit the zero slot).
#[inline(always)]
pub(crate) fn gather_b(s: &Structure, m: usize, v: &[f64]) -> f64 {
    let c = &s.members[m];
    let mut sum = 0.0;
    if c.link.masked {
        let at = |d: usize| if d < s.free { v[d] } else { 0.0 };
        for k in 0..3 {
            sum += c.unit[k] * (at(c.link.dofs[3 + k]) - at(c.link.dofs[k]));
        }
        return sum;
    }
    let (blocks, _) = v[..s.free].as_chunks::<3>();
    let vi = blocks.get(c.link.ends[0]).copied().unwrap_or([0.0; 3]);
    let vj = blocks.get(c.link.ends[1]).copied().unwrap_or([0.0; 3]);
    for k in 0..3 {
        sum += c.unit[k] * (vj[k] - vi[k]);
    }
    sum
}

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
