//! The allocation against its closed form (two groups of known sensitivities), brute-force
//! optimality along the budget, fixed groups, and Hoyt's law against Rayleigh's and a
//! Monte Carlo of a 2-D Gaussian.

use truss_stats::rng::SplitMix64;
use truss_tolerance::allocate::{GroupModel, allocate, cost, model_theta, uniform};
use truss_tolerance::percentile::{norm_cdf, norm_quantile, rayleigh_factor};

fn iso(s: f64, members: usize, weight: f64) -> GroupModel {
    GroupModel {
        covariance: [s, 0.0, s],
        members,
        weight,
        fixed: None,
        shared: false,
    }
}

/// Two groups, S₁ = 4e-6 and S₂ = 1e-4 mm⁻², n = 18 and 15, weights 1 and 3: Lagrange gives
/// σ_g = k (w_g n_g / S_g)^{1/3} with k² = V* / Σ S_g (w_g n_g/S_g)^{2/3} and
/// V* = (tan θ* / √(−2 ln 0.05))².
#[test]
fn two_groups_match_the_closed_form() {
    let groups = [iso(4e-6, 18, 1.0), iso(1e-4, 15, 3.0)];
    let target = 20.0 / truss_units::ARCSEC_PER_RAD;
    let q = 0.95;
    let sigmas = allocate(&groups, target, q).unwrap();
    let v = (target.tan() / rayleigh_factor(q)).powi(2);
    let d = |s: f64, n: f64, w: f64| (w * n / s).cbrt();
    let (d1, d2) = (d(4e-6, 18.0, 1.0), d(1e-4, 15.0, 3.0));
    let k = (v / (4e-6 * d1 * d1 + 1e-4 * d2 * d2)).sqrt();
    for (got, want) in sigmas.iter().zip([k * d1, k * d2]) {
        assert!(
            (got / want - 1.0).abs() < 1e-9,
            "σ {got} vs closed form {want}"
        );
    }
    // The budget is met exactly by the model.
    assert!((model_theta(&groups, &sigmas, q) / target - 1.0).abs() < 1e-12);
}

/// Every other point on the budget's boundary costs more: σ₁ scanned over a decade either
/// side, σ₂ from S₁σ₁² + S₂σ₂² = V*.
#[test]
fn the_allocation_is_the_cheapest_on_the_budget() {
    let groups = [iso(4e-6, 18, 1.0), iso(1e-4, 15, 1.0)];
    let target = 1e-4;
    let q = 0.9;
    let best = allocate(&groups, target, q).unwrap();
    let best_cost = cost(&groups, &best);
    let v = 4e-6 * best[0].powi(2) + 1e-4 * best[1].powi(2);
    let mut scanned = 0;
    for i in -40..=40 {
        let s1 = best[0] * 10f64.powf(i as f64 / 40.0);
        let rest = v - 4e-6 * s1 * s1;
        if rest <= 0.0 || i == 0 {
            continue;
        }
        let s2 = (rest / 1e-4).sqrt();
        assert!(
            cost(&groups, &[s1, s2]) > best_cost,
            "σ = ({s1}, {s2}) costs less than the allocation {best:?}"
        );
        scanned += 1;
    }
    assert!(scanned > 30);
    // The uniform σ meets the same budget and costs more.
    let u = uniform(&groups, target, q);
    assert!((model_theta(&groups, &[u, u], q) / target - 1.0).abs() < 1e-9);
    assert!(cost(&groups, &[u, u]) > best_cost);
}

/// A fixed group takes its share of the budget first; the rest follows the closed form with
/// the budget left; a fix that alone exceeds the target is unreachable.
#[test]
fn fixed_groups_use_their_budget_first() {
    let mut groups = [iso(4e-6, 18, 1.0), iso(1e-4, 15, 1.0)];
    let q = 0.95;
    let target = 20.0 / truss_units::ARCSEC_PER_RAD;
    let v = (target.tan() / rayleigh_factor(q)).powi(2);
    groups[0].fixed = Some(0.5 * (v / 4e-6).sqrt());
    let sigmas = allocate(&groups, target, q).unwrap();
    assert_eq!(sigmas[0], groups[0].fixed.unwrap());
    let left = v - 4e-6 * sigmas[0].powi(2);
    assert!((sigmas[1] / (left / 1e-4).sqrt() - 1.0).abs() < 1e-9);
    groups[0].fixed = Some(1.01 * (v / 4e-6).sqrt());
    assert!(allocate(&groups, target, q).is_err());
}

/// Isotropic: Hoyt's law is Rayleigh's, r_q = σ_t √(−2 ln(1 − q)). Anisotropic and
/// correlated: the quantile matches the empirical one of 200,000 Gaussian draws.
#[test]
fn hoyt_law_against_rayleigh_and_monte_carlo() {
    for q in [0.5, 0.9, 0.95, 0.99] {
        let r = norm_quantile(&[4e-10, 0.0, 4e-10], q);
        assert!((r / (2e-5 * rayleigh_factor(q)) - 1.0).abs() < 1e-9);
    }
    // Σ = [[4, 1.5], [1.5, 1]]·1e-10: draw t = L·u with L the Cholesky factor.
    let c: [f64; 3] = [4e-10, 1.5e-10, 1e-10];
    let (l11, l21) = (c[0].sqrt(), c[1] / c[0].sqrt());
    let l22 = (c[2] - l21 * l21).sqrt();
    let mut rng = SplitMix64::new(7);
    let mut norms: Vec<f64> = (0..200_000)
        .map(|_| {
            let (u, v) = (rng.normal(), rng.normal());
            let (x, y) = (l11 * u, l21 * u + l22 * v);
            (x * x + y * y).sqrt()
        })
        .collect();
    norms.sort_by(f64::total_cmp);
    for q in [0.5, 0.95] {
        let empirical = norms[(q * norms.len() as f64) as usize];
        let r = norm_quantile(&c, q);
        assert!(
            (r / empirical - 1.0).abs() < 0.01,
            "q = {q}: Hoyt {r} vs Monte Carlo {empirical}"
        );
        assert!((norm_cdf(&c, r) - q).abs() < 1e-9);
    }
}
