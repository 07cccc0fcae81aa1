//! The percentile of θ_P when the tilt (tan θ_x, tan θ_y) is a zero-mean 2-D Gaussian.
//!
//! The top surface's normal makes the angle θ_P with the bottom's, and
//! `tan θ_P = √(tan²θ_x + tan²θ_y) = |t|` (paper eqs. 2, 8, 9: the bottom is fixed, so its normal
//! is the z axis). Let `t ~ N(0, Σ)` with eigenvalues `λ₁, λ₂` of Σ. Whitening, `t = Q·diag(√λ)·u`
//! with `u ~ N(0, I)`, and in polar coordinates `u = ρ(cos φ, sin φ)`: `ρ` is Rayleigh,
//! `P(ρ ≤ a) = 1 − exp(−a²/2)`, independent of `φ ~ U(0, 2π)`, and
//! `|t|² = ρ²·g(φ)` with `g(φ) = λ₁cos²φ + λ₂sin²φ`. So
//!
//! ```text
//! P(|t| ≤ r) = (1/2π) ∫₀^{2π} [1 − exp(−r² / (2 g(φ)))] dφ           (Hoyt's law)
//! ```
//!
//! evaluated with the trapezoidal rule on 256 points (the integrand is smooth and periodic, so
//! the rule converges geometrically), and inverted for `r` by bisection. In the isotropic case
//! `λ₁ = λ₂ = σ_t²` this is Rayleigh's law (paper eq. 28): `r_q = σ_t·√(−2 ln(1 − q))`.
//! Then `θ_Pq = atan(r_q)`. `r_q` is positively homogeneous of degree 1 in the scale of `t`:
//! `r_q(c²Σ) = c·r_q(Σ)`.

use truss_stats::bisect::bisect;

/// A symmetric 2×2 covariance `[[xx, xy], [xy, yy]]` of (tan θ_x, tan θ_y), stored
/// `[xx, xy, yy]` \[-\].
pub type Covariance = [f64; 3];

/// Trapezoidal points over the angle.
const POINTS: usize = 256;

/// The eigenvalues (λ₁ ≥ λ₂) of a covariance.
pub fn eigenvalues(c: &Covariance) -> (f64, f64) {
    let mean = 0.5 * (c[0] + c[2]);
    let half = 0.5 * (c[0] - c[2]);
    let radius = (half * half + c[1] * c[1]).sqrt();
    (mean + radius, (mean - radius).max(0.0))
}

/// `P(|t| ≤ r)` for `t ~ N(0, Σ)` (Hoyt's law, see the module doc).
pub fn norm_cdf(c: &Covariance, r: f64) -> f64 {
    let (l1, l2) = eigenvalues(c);
    let mut sum = 0.0;
    for i in 0..POINTS {
        let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.5) / POINTS as f64;
        let g = l1 * phi.cos().powi(2) + l2 * phi.sin().powi(2);
        sum += if g > 0.0 {
            1.0 - (-r * r / (2.0 * g)).exp()
        } else {
            1.0
        };
    }
    sum / POINTS as f64
}

/// Rayleigh's factor `√(−2 ln(1 − q))`: θ_Pq = factor · σ_t for an isotropic tilt.
pub fn rayleigh_factor(q: f64) -> f64 {
    (-2.0 * (1.0 - q).ln()).sqrt()
}

/// The `q`-quantile of `|t|` for `t ~ N(0, Σ)` \[-\]; 0 when Σ = 0.
pub fn norm_quantile(c: &Covariance, q: f64) -> f64 {
    let (l1, l2) = eigenvalues(c);
    let k = rayleigh_factor(q);
    // The quantile lies between the isotropic ones of the smaller and larger eigenvalue.
    let (lo, hi) = (l2.sqrt() * k, l1.sqrt() * k);
    if hi <= 0.0 {
        return 0.0;
    }
    bisect(|r| norm_cdf(c, r), q, (lo, hi))
}

/// The `q`-quantile of θ_P \[rad\] for a Gaussian tilt of covariance Σ.
pub fn theta_quantile(c: &Covariance, q: f64) -> f64 {
    norm_quantile(c, q).atan()
}
