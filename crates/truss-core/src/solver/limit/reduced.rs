//! The reduced problem of a Newton step: the directions in which the tangent's
//! factorisation met a soft, singular or negative pivot, solved exactly in the small space
//! they span.
//!
//! ## Why
//!
//! Where one-sided members carry nothing, the tangent `K` of the members that bear has
//! directions of tiny stiffness: a stage held only by the geometric stiffness `N/L` of a
//! pretension of micronewtons, a panel whose frame is compressed and whose bracing is slack
//! (negative), a stage whose members all carry nothing (none at all). In the factorisation
//! those directions appear as pivots at the rounding noise of the material stiffness
//! (`ε·E·A/L`, ten orders above `N/L` for a micronewton): the banded solve cannot resolve
//! them. The factorisation therefore replaces every pivot below [`super::SOFT_PIVOT`] of its
//! row's diagonal by that diagonal, a spring `c_j` on row `j`, and the step is sought in
//!
//! ```text
//! δ = δ_p + W·a,    δ_p = K'⁻¹F,    w_j = K'⁻¹(c_j·e_j),    K' = K + Σ_j c_j e_j e_jᵀ
//! ```
//!
//! (`F` the step's right-hand side), which contains the exact Newton step `K⁻¹F` whenever it
//! exists. The coefficients `a` minimise the step's quadratic model over that space
//! (Rayleigh–Ritz): `(WᵀKW)·a = Wᵀ(F − K·δ_p)`. `WᵀKW` is summed member by member,
//!
//! ```text
//! w_iᵀK w_j = Σ_m k_e,m (n_m·Δw_i)(n_m·Δw_j) + (N_m/L_m)(Δw_i·Δw_j − (n_m·Δw_i)(n_m·Δw_j))
//! ```
//!
//! which resolves the geometric stiffness of any force above the solve's force floor, where
//! `w_iᵀ(K'w_j) − …` would cancel. [`Reduced::classify`] then sorts the eigen-directions of
//! `WᵀKW` into held (positive: the Newton step), unstable (negative: the stage falls until a
//! one-sided member engages) and free (zero: at ratio 0, the limit `ρ → 0` of the step with
//! the slack cables at ratio ρ, which minimises their compression energy
//! `Q = Σ ½·k·e²` over the free directions).
//!
//! Units: displacements \[mm\], forces \[N\], stiffnesses \[N/mm\].

/// The reduced problem of one step, its buffers kept between steps.
#[derive(Debug, Clone, Default)]
pub(crate) struct Reduced {
    /// Number of directions `p`.
    pub p: usize,
    /// `WᵀKW`, row-major `p×p`; overwritten by its eigen-decomposition.
    pub stiffness: Vec<f64>,
    /// `Wᵀ(F − K·δ_p)`.
    pub force: Vec<f64>,
    /// `WᵀHW` with `H = Σ k·n nᵀ` over the slack cables of ratio 0 (at unit ratio).
    pub selection: Vec<f64>,
    /// `Wᵀ(H·δ_p + ∇Q)`, `∇Q = Σ k·e·b` over the same cables.
    pub selection_force: Vec<f64>,
    /// Eigenvalues of `WᵀKW`.
    pub values: Vec<f64>,
    /// Eigenvectors of `WᵀKW` (columns).
    pub vectors: Vec<f64>,
    /// The solution `a`.
    pub a: Vec<f64>,
    /// Scratch of length `p`.
    scratch: Vec<f64>,
    /// Scratch of length `p*p`.
    scratch_pp: Vec<f64>,
    /// Scratch of length `p*p`.
    scratch_pp2: Vec<f64>,
}

/// What the reduced problem found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Finding {
    /// Every direction is held, or free and selected: `a` is the step's part in `W`.
    Step {
        /// Whether some direction was free and selected by the slack cables' energy (the
        /// step must then also be small for the solve to be converged).
        selected: bool,
    },
    /// Eigen-direction `i` is unstable (negative stiffness), or free and pushed by an
    /// unbalanced force: the step is along it, until a member engages.
    Unstable {
        /// Its index among the eigenvalues.
        index: usize,
    },
}

impl Reduced {
    /// Clears the problem for `p` directions.
    pub fn reset(&mut self, p: usize) {
        self.p = p;
        for v in [
            &mut self.stiffness,
            &mut self.selection,
            &mut self.vectors,
            &mut self.scratch_pp,
            &mut self.scratch_pp2,
        ] {
            v.clear();
            v.resize(p * p, 0.0);
        }
        for v in [
            &mut self.force,
            &mut self.selection_force,
            &mut self.values,
            &mut self.a,
            &mut self.scratch,
        ] {
            v.clear();
            v.resize(p, 0.0);
        }
    }

    /// Adds one member's part: its effective axial stiffness `k` \[N/mm\], `N/L` \[N/mm\], its
    /// elongation rates along the `p` directions and along `δ_p` (`along[p]`) with the
    /// relative displacements `delta` (same order), and, for a slack cable of ratio 0, its
    /// unit-ratio stiffness `kq` and elongation `e` (else `kq = 0`).
    #[allow(clippy::too_many_arguments)]
    pub fn add_member(
        &mut self,
        k: f64,
        n_over_l: f64,
        along: &[f64],
        delta: &[Vec<f64>; 3],
        kq: f64,
        e: f64,
    ) {
        let p = self.p;
        let [dx, dy, dz] = delta;
        let (along, dx, dy, dz) = (&along[..=p], &dx[..=p], &dy[..=p], &dz[..=p]);
        for i in 0..p {
            let dot_p = dx[i] * dx[p] + dy[i] * dy[p] + dz[i] * dz[p];
            let kid = k * along[i] * along[p] + n_over_l * (dot_p - along[i] * along[p]);
            self.force[i] -= kid;
            if kq != 0.0 {
                self.selection_force[i] += kq * along[i] * (e + along[p]);
            }
            // Row i's lower triangle, j = 0..=i: the same expressions, in the same order, as
            // one entry at a time, over columns the compiler can run side by side.
            let (ka, a) = (k * along[i], along[i]);
            let (xi, yi, zi) = (dx[i], dy[i], dz[i]);
            let row = &mut self.stiffness[i * p..=i * p + i];
            for ((((s, &aj), &xj), &yj), &zj) in row
                .iter_mut()
                .zip(&along[..=i])
                .zip(&dx[..=i])
                .zip(&dy[..=i])
                .zip(&dz[..=i])
            {
                *s += ka * aj + n_over_l * ((xi * xj + yi * yj + zi * zj) - a * aj);
            }
            if kq != 0.0 {
                let kqa = kq * along[i];
                let row = &mut self.selection[i * p..=i * p + i];
                for (s, &aj) in row.iter_mut().zip(&along[..=i]) {
                    *s += kqa * aj;
                }
            }
        }
    }

    /// Completes the symmetric matrices from their lower triangles.
    pub fn symmetrise(&mut self) {
        let p = self.p;
        for i in 0..p {
            for j in 0..i {
                self.stiffness[j * p + i] = self.stiffness[i * p + j];
                self.selection[j * p + i] = self.selection[i * p + j];
            }
        }
    }

    /// Solves the reduced problem: eigen-decomposes `WᵀKW`; an eigenvalue above `tau`
    /// \[N/mm\] is held (`a` along it is the Newton step), one below `−tau` unstable, one
    /// within `±tau` free. A free direction whose force is above `force_noise` \[N\] is
    /// unstable too (nothing holds it against that force). Otherwise the free directions'
    /// coefficients minimise the slack cables' energy `Q` given the held part
    /// (`(VᵀHV)·c = −Vᵀ(H·a_held + g)` over the free eigenvectors `V`, with a direction that
    /// moves no slack cable left where it is).
    pub fn classify(&mut self, tau: f64, force_noise: f64) -> Finding {
        let p = self.p;
        super::eigen::symmetric_eigen(&mut self.stiffness, &mut self.vectors, &mut self.values, p);
        // Components of the force along the eigenvectors.
        for i in 0..p {
            self.scratch[i] = (0..p)
                .map(|k| self.vectors[k * p + i] * self.force[k])
                .sum();
        }
        let mut worst: Option<usize> = None;
        for i in 0..p {
            let mu = self.values[i];
            let unstable = mu < -tau || (mu.abs() <= tau && self.scratch[i].abs() > force_noise);
            if unstable && worst.is_none_or(|w| mu < self.values[w]) {
                worst = Some(i);
            }
        }
        if let Some(index) = worst {
            return Finding::Unstable { index };
        }
        // Held part.
        let mut coefficients = vec![0.0; p];
        let free: Vec<usize> = (0..p).filter(|&i| self.values[i].abs() <= tau).collect();
        for ((c, &mu), &f) in coefficients
            .iter_mut()
            .zip(&self.values[..p])
            .zip(&self.scratch)
        {
            if mu > tau {
                *c = f / mu;
            }
        }
        let selected = !free.is_empty();
        if selected {
            let q = free.len();
            // a_held in the W basis.
            let held: Vec<f64> = (0..p)
                .map(|k| {
                    (0..p)
                        .map(|i| self.vectors[k * p + i] * coefficients[i])
                        .sum()
                })
                .collect();
            // VᵀHV and −Vᵀ(H·a_held + g).
            let h_held: Vec<f64> = (0..p)
                .map(|k| (0..p).map(|l| self.selection[k * p + l] * held[l]).sum())
                .collect();
            // (H·V)[k][jj] over the free columns first: p²·q products, not p²·q² (each
            // entry summed in the same order as in the product below, so the same bits).
            let mut hv_free = vec![0.0; p * q];
            for k in 0..p {
                for (jj, &j) in free.iter().enumerate() {
                    hv_free[k * q + jj] = (0..p)
                        .map(|l| self.selection[k * p + l] * self.vectors[l * p + j])
                        .sum::<f64>();
                }
            }
            let vhv = &mut self.scratch_pp;
            let mut rhs = vec![0.0; q];
            for (ii, &i) in free.iter().enumerate() {
                rhs[ii] = -(0..p)
                    .map(|k| self.vectors[k * p + i] * (h_held[k] + self.selection_force[k]))
                    .sum::<f64>();
                for jj in 0..q {
                    vhv[ii * q + jj] = (0..p)
                        .map(|k| self.vectors[k * p + i] * hv_free[k * q + jj])
                        .sum();
                }
            }
            let (hv, hval) = (&mut self.scratch_pp2, &mut vec![0.0; q]);
            super::eigen::symmetric_eigen(vhv, hv, hval, q);
            let largest = hval.iter().fold(0.0f64, |x, y| x.max(y.abs()));
            for i in 0..q {
                if hval[i] > 1e-10 * largest && hval[i] > 0.0 {
                    let proj: f64 = (0..q).map(|k| hv[k * q + i] * rhs[k]).sum();
                    for k in 0..q {
                        coefficients[free[k]] += hv[k * q + i] * proj / hval[i];
                    }
                }
            }
        }
        for k in 0..p {
            self.a[k] = (0..p)
                .map(|i| self.vectors[k * p + i] * coefficients[i])
                .sum();
        }
        Finding::Step { selected }
    }

    /// The unit eigen-direction `i` in the `W` basis.
    pub fn direction(&self, i: usize) -> impl Iterator<Item = f64> + '_ {
        let p = self.p;
        (0..p).map(move |k| self.vectors[k * p + i])
    }
}
