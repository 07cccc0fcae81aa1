//! The paper's Rayleigh law (section 3.2): tan θ_x and tan θ_y are N(0, σ_t²) (eqs. 19–20),
//! so θ_P ≈ √(tan²θ_x + tan²θ_y) is Rayleigh(σ_t) (eq. 26) with percentiles
//! θ_P^α = √(−2σ² ln(1 − α)) (eq. 28).
//!
//! ## Estimators (all sums in global index order, so they do not depend on the split)
//!
//! - Mean and sample standard deviation (divisor n − 1) of tan θ_x and of tan θ_y, with the
//!   normal-theory intervals: Student t for the mean, `(n−1)s²/σ² ~ χ²(n−1)` for the standard
//!   deviation.
//! - `σ_t` pooled, the zero-mean maximum-likelihood estimate from both components:
//!   `σ̂_t² = Σ (tan²θ_x + tan²θ_y) / (2n)`, with `2n σ̂_t²/σ_t² ~ χ²(2n)`; and each component
//!   alone, `σ̂² = Σ tan²θ / n` with `χ²(n)`.
//! - The maximum-likelihood Rayleigh fit of θ_P: `σ̂² = Σ θ² / (2n)`; since θ²/σ² ~ χ²(2), the
//!   exact interval is from `2n σ̂²/σ² ~ χ²(2n)`:
//!   `σ ∈ [√(Σθ²/χ²_{(1+c)/2}(2n)), √(Σθ²/χ²_{(1−c)/2}(2n))]`.
//! - Rayleigh percentiles by eq. 28 at σ̂, with the interval mapped from σ's interval
//!   (eq. 28 is increasing in σ).
//!
//! χ² quantiles come from `statrs` (`ChiSquared::inverse_cdf`).

use statrs::distribution::{ChiSquared, ContinuousCDF, StudentsT};

/// A confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Lower end.
    pub lower: f64,
    /// Upper end.
    pub upper: f64,
}

/// The interval of a scale σ from a sum of squares `S = Σ xᵢ²` with `S/σ² ~ χ²(dof)`.
pub fn chi2_scale_interval(sum_sq: f64, dof: f64, confidence: f64) -> Result<Bounds, String> {
    let chi2 = ChiSquared::new(dof).map_err(|e| format!("chi-square({dof}): {e}"))?;
    let tail = (1.0 - confidence) / 2.0;
    let hi_q = chi2.inverse_cdf(1.0 - tail);
    let lo_q = chi2.inverse_cdf(tail);
    if !(hi_q.is_finite() && lo_q.is_finite() && lo_q > 0.0) {
        return Err(format!("chi-square({dof}) quantiles not finite"));
    }
    Ok(Bounds {
        lower: (sum_sq / hi_q).sqrt(),
        upper: (sum_sq / lo_q).sqrt(),
    })
}

/// Summary of one slope component (tan θ_x or tan θ_y).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComponentStats {
    /// Number of values.
    pub n: usize,
    /// Sample mean.
    pub mean: f64,
    /// Student-t interval of the mean (`None` if n < 2).
    pub mean_interval: Option<Bounds>,
    /// Sample standard deviation, divisor n − 1 (`None` if n < 2).
    pub std: Option<f64>,
    /// χ²(n−1) interval of the standard deviation.
    pub std_interval: Option<Bounds>,
    /// Zero-mean ML scale `√(Σx²/n)`.
    pub rms: f64,
    /// χ²(n) interval of the zero-mean scale.
    pub rms_interval: Option<Bounds>,
    /// `Σ x²`.
    pub sum_sq: f64,
}

/// Mean, standard deviation and zero-mean scale of `values` (in index order; iterated three
/// times, so nothing is copied). `None` if empty.
pub fn component_stats(
    values: impl Iterator<Item = f64> + Clone,
    confidence: f64,
) -> Option<ComponentStats> {
    let n = values.clone().count();
    if n == 0 {
        return None;
    }
    let nf = n as f64;
    let mean = values.clone().sum::<f64>() / nf;
    let sum_sq: f64 = values.clone().map(|x| x * x).sum();
    let ss_dev: f64 = values.map(|x| (x - mean) * (x - mean)).sum();
    let tail = (1.0 - confidence) / 2.0;
    let (std, std_interval, mean_interval) = if n >= 2 {
        let s = (ss_dev / (nf - 1.0)).sqrt();
        let t = StudentsT::new(0.0, 1.0, nf - 1.0)
            .ok()
            .map(|t| t.inverse_cdf(1.0 - tail));
        let mean_iv = t.filter(|t| t.is_finite()).map(|t| Bounds {
            lower: mean - t * s / nf.sqrt(),
            upper: mean + t * s / nf.sqrt(),
        });
        (
            Some(s),
            chi2_scale_interval(ss_dev, nf - 1.0, confidence).ok(),
            mean_iv,
        )
    } else {
        (None, None, None)
    };
    Some(ComponentStats {
        n,
        mean,
        mean_interval,
        std,
        std_interval,
        rms: (sum_sq / nf).sqrt(),
        rms_interval: chi2_scale_interval(sum_sq, nf, confidence).ok(),
        sum_sq,
    })
}

/// The maximum-likelihood Rayleigh fit of θ_P.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayleighFit {
    /// Number of values.
    pub n: usize,
    /// `Σ θ²`.
    pub sum_sq: f64,
    /// `σ̂ = √(Σθ²/(2n))` (rad).
    pub sigma: f64,
    /// Exact χ²(2n) interval of σ (rad).
    pub sigma_interval: Bounds,
}

/// Fits a Rayleigh distribution to `thetas` by maximum likelihood. `None` if empty.
pub fn fit(thetas: &[f64], confidence: f64) -> Option<RayleighFit> {
    let n = thetas.len();
    if n == 0 {
        return None;
    }
    let sum_sq: f64 = thetas.iter().map(|x| x * x).sum();
    Some(fit_from_sum_sq(n, sum_sq, confidence))
}

/// The fit from `n` and `Σθ²`.
pub fn fit_from_sum_sq(n: usize, sum_sq: f64, confidence: f64) -> RayleighFit {
    let dof = 2.0 * n as f64;
    let sigma_interval = chi2_scale_interval(sum_sq, dof, confidence).unwrap_or(Bounds {
        lower: 0.0,
        upper: 0.0,
    });
    RayleighFit {
        n,
        sum_sq,
        sigma: (sum_sq / dof).sqrt(),
        sigma_interval,
    }
}

/// The Rayleigh `alpha`-percentile `√(−2σ² ln(1 − α))` (paper eq. 28).
pub fn percentile(sigma: f64, alpha: f64) -> f64 {
    sigma * (-2.0 * (-alpha).ln_1p()).sqrt()
}

/// The Rayleigh CDF `1 − exp(−θ²/(2σ²))` (paper eq. 27).
pub fn cdf(sigma: f64, theta: f64) -> f64 {
    -(-(theta * theta) / (2.0 * sigma * sigma)).exp_m1()
}

/// The Rayleigh density `θ/σ² exp(−θ²/(2σ²))` (paper eq. 26).
pub fn density(sigma: f64, theta: f64) -> f64 {
    theta / (sigma * sigma) * (-(theta * theta) / (2.0 * sigma * sigma)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Paper section 3.2: σ_t = 3.96e-5 and α = 0.95 give θ_P^α = 9.69e-5 rad (eq. 28).
    #[test]
    fn eq28_reproduces_the_papers_number() {
        let q = percentile(3.96e-5, 0.95);
        assert!((q - 9.69e-5).abs() < 0.005e-5, "{q}");
        assert!((cdf(3.96e-5, q) - 0.95).abs() < 1e-12);
    }

    /// The density integrates to the CDF (trapezoid rule on a fine grid).
    #[test]
    fn density_integrates_to_cdf() {
        let s = 2.0;
        let m = 20_000;
        let h = 8.0 / m as f64;
        let integral: f64 = (0..m)
            .map(|i| 0.5 * h * (density(s, i as f64 * h) + density(s, (i + 1) as f64 * h)))
            .sum();
        assert!((integral - cdf(s, 8.0)).abs() < 1e-7);
    }

    /// χ² interval by hand for dof = 2 (exponential): χ²₀.₀₂₅(2) = −2 ln 0.975,
    /// χ²₀.₉₇₅(2) = −2 ln 0.025.
    #[test]
    fn chi2_interval_dof2_by_hand() {
        let b = chi2_scale_interval(1.0, 2.0, 0.95).unwrap();
        assert!((b.lower - (1.0 / (-2.0 * 0.025f64.ln())).sqrt()).abs() < 1e-9);
        assert!((b.upper - (1.0 / (-2.0 * 0.975f64.ln())).sqrt()).abs() < 1e-9);
    }

    /// For large dof the χ² interval matches the Wilson–Hilferty approximation
    /// χ²_q(k) ≈ k (1 − 2/(9k) + z_q √(2/(9k)))³ (Johnson, Kotz & Balakrishnan, vol. 1, 18.24).
    #[test]
    fn chi2_interval_large_dof_matches_wilson_hilferty() {
        let k = 100_000.0;
        let b = chi2_scale_interval(k, k, 0.95).unwrap();
        let wh = |z: f64| k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
        let z = 1.959_963_984_540_054;
        assert!((b.lower - (k / wh(z)).sqrt()).abs() < 1e-6, "{b:?}");
        assert!((b.upper - (k / wh(-z)).sqrt()).abs() < 1e-6, "{b:?}");
    }

    #[test]
    fn component_stats_by_hand() {
        let s = component_stats([1.0, -1.0, 3.0].into_iter(), 0.95).unwrap();
        assert_eq!(s.mean, 1.0);
        assert!((s.std.unwrap() - 2.0).abs() < 1e-15);
        assert!((s.rms - (11.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!(
            component_stats([2.0].into_iter(), 0.95)
                .unwrap()
                .std
                .is_none()
        );
        assert!(component_stats(std::iter::empty(), 0.95).is_none());
    }
}
