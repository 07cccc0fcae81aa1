//! The cheapest per-group σ meeting a θ_P percentile budget, from the tilt's linear model.
//!
//! ## The model
//!
//! Each group `g` contributes `C_g = Σ_{i∈g} β_i β_iᵀ` \[mm⁻²\] per unit σ_g² to the covariance of
//! the tilt `t = (tan θ_x, tan θ_y)`, where `β_i` \[mm⁻¹\] are member `i`'s regression
//! coefficients ([`crate::sensitivity`]); with independent errors
//! `Σ(σ) = Σ_g σ_g² C_g`, and its half-trace `σ_t² = Σ_g σ_g² S_g` with `S_g = tr C_g / 2`.
//! The budget is `θ_Pq(Σ(σ)) ≤ θ*` ([`crate::percentile`]); for an isotropic tilt that is
//! `σ_t ≤ V*^{1/2} = tan θ* / √(−2 ln(1 − q))`.
//!
//! ## The optimum
//!
//! Minimise the cost `K(σ) = Σ_g w_g n_g / σ_g` (n_g members, weight w_g) subject to
//! `Σ_g S_g σ_g² = V*`. Stationarity of `K + λ(Σ S_g σ_g² − V*)`:
//! `−w_g n_g / σ_g² + 2λ S_g σ_g = 0`, so
//!
//! ```text
//! σ_g = k · (w_g n_g / S_g)^{1/3},      k² = V*_free / Σ_g S_g (w_g n_g / S_g)^{2/3}
//! ```
//!
//! with `V*_free = V* − Σ_{fixed} S_g σ_g²` the budget left by the `--fix`ed groups. `K` is
//! convex and decreasing in each σ_g on σ > 0 and the feasible set `{Σ S_g σ_g² ≤ V*}` is
//! convex, so this stationary point on its boundary is the global minimum. Tighter groups are
//! the sensitive, cheap-to-tighten ones: halving `S_g` widens σ_g by 2^{1/3}.
//!
//! When the tilt is not isotropic (Σ's eigenvalues differ), the trace constraint is replaced
//! by the exact Hoyt percentile in the last step: the direction `(w_g n_g / S_g)^{1/3}` is kept
//! and `k` is found by bisection so that `θ_Pq(Σ_fixed + k² Σ_free) = θ*` (`θ_Pq` increases with
//! `k`). For the prism, whose groups are invariant under its 120° rotation, Σ is isotropic
//! and the two coincide.
//!
//! ## Production lots
//!
//! A group's lot part is a group of the model too (`C_lot = Σ_L B_L B_Lᵀ`,
//! [`crate::sensitivity`]), held at its σ like a fixed group, so it uses up its part of the
//! budget first; it costs nothing here (`shared`: the cost counts the groups one machines),
//! and the uniform σ's comparison keeps it at its σ too.

use crate::percentile::{Covariance, theta_quantile};
use truss_stats::bisect::{bisect, bracket_from_zero};

/// One group as the allocation sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupModel {
    /// Covariance of the tilt per unit σ² `C_g` \[mm⁻²\].
    pub covariance: Covariance,
    /// Number of members `n_g`.
    pub members: usize,
    /// Cost weight `w_g`.
    pub weight: f64,
    /// Pinned σ \[mm\], if fixed.
    pub fixed: Option<f64>,
    /// A production lot's shared part (fixed at its σ, no cost, kept in the uniform σ's
    /// comparison).
    pub shared: bool,
}

impl GroupModel {
    /// `S_g = tr C_g / 2` \[mm⁻²\].
    pub fn sensitivity(&self) -> f64 {
        0.5 * (self.covariance[0] + self.covariance[2])
    }
}

/// Why no allocation exists.
#[derive(Debug, Clone, PartialEq)]
pub enum AllocationError {
    /// The fixed groups alone give this θ_Pq \[rad\], at or above the target.
    Unreachable {
        /// Their θ_Pq \[rad\].
        theta_fixed: f64,
    },
}

/// The tilt's covariance `Σ_g σ_g² C_g` at σ values `sigmas` \[mm\].
pub fn covariance(groups: &[GroupModel], sigmas: &[f64]) -> Covariance {
    let mut c = [0.0; 3];
    for (g, s) in groups.iter().zip(sigmas) {
        for (cj, gj) in c.iter_mut().zip(&g.covariance) {
            *cj += s * s * gj;
        }
    }
    c
}

/// The model's θ_Pq \[rad\] at σ values `sigmas` \[mm\].
pub fn model_theta(groups: &[GroupModel], sigmas: &[f64], q: f64) -> f64 {
    theta_quantile(&covariance(groups, sigmas), q)
}

/// The cost `Σ_g w_g n_g / σ_g` over the groups not `shared` (infinite if a σ is 0).
pub fn cost(groups: &[GroupModel], sigmas: &[f64]) -> f64 {
    groups
        .iter()
        .zip(sigmas)
        .filter(|(g, _)| !g.shared)
        .map(|(g, s)| g.weight * g.members as f64 / s)
        .sum()
}

/// The cheapest σ per group \[mm\] with model θ_Pq = `target` \[rad\] (see the module doc).
/// Every free group must have `S_g > 0` (the caller checks).
pub fn allocate(groups: &[GroupModel], target: f64, q: f64) -> Result<Vec<f64>, AllocationError> {
    let fixed: Vec<f64> = groups.iter().map(|g| g.fixed.unwrap_or(0.0)).collect();
    let theta_fixed = model_theta(groups, &fixed, q);
    if theta_fixed >= target {
        return Err(AllocationError::Unreachable { theta_fixed });
    }
    let direction: Vec<f64> = groups
        .iter()
        .map(|g| match g.fixed {
            Some(_) => 0.0,
            None => (g.weight * g.members as f64 / g.sensitivity()).cbrt(),
        })
        .collect();
    let at = |k: f64| -> Vec<f64> {
        groups
            .iter()
            .zip(&direction)
            .map(|(g, d)| g.fixed.unwrap_or(k * d))
            .collect()
    };
    // Bracket k, then bisect: θ_Pq grows with k.
    let theta = |k: f64| model_theta(groups, &at(k), q);
    let k = bisect(theta, target, bracket_from_zero(theta, target));
    Ok(at(k))
}

/// The common σ \[mm\] of every group not `shared` with model θ_Pq = `target` \[rad\]
/// (fixes ignored; the shared lot parts at their σ): `θ_Pq` is homogeneous in σ, so
/// σ_u = tan θ* / r_q(Σ_g C_g) where the lot parts add nothing, else by bisection on
/// `θ_Pq(Σ_lots + σ_u² Σ_g C_g) = θ*` (0 where the lots alone reach the target).
pub fn uniform(groups: &[GroupModel], target: f64, q: f64) -> f64 {
    // Each sum over its own groups only (a 0 · ∞ of an extreme C_g would be NaN).
    let sum = |shared: bool| {
        let (g, s): (Vec<GroupModel>, Vec<f64>) = groups
            .iter()
            .filter(|g| g.shared == shared)
            .map(|g| (*g, if shared { g.fixed.unwrap_or(0.0) } else { 1.0 }))
            .unzip();
        covariance(&g, &s)
    };
    let free = sum(false);
    if !groups
        .iter()
        .any(|g| g.shared && g.fixed.is_some_and(|s| s > 0.0))
    {
        let r = crate::percentile::norm_quantile(&free, q);
        return target.tan() / r;
    }
    let fixed = sum(true);
    let at = |k: f64| {
        let c: Covariance = std::array::from_fn(|j| fixed[j] + k * k * free[j]);
        theta_quantile(&c, q)
    };
    bisect(at, target, bracket_from_zero(at, target))
}
