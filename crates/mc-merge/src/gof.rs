//! Goodness of fit of the Rayleigh law with an estimated scale.
//!
//! ## The tests
//!
//! θ is Rayleigh(σ) exactly when y = θ² is exponential with mean 2σ², and the ML Rayleigh fit
//! (σ̂² = Σθ²/2n) is the ML exponential fit (m̂ = ȳ); so testing the Rayleigh law with the scale
//! estimated is testing exponentiality with the mean estimated ("case 3" of D'Agostino & Stephens,
//! *Goodness-of-Fit Techniques*, 1986, §4.9). With `Fᵢ = 1 − exp(−y₍ᵢ₎/ȳ)` for y sorted ascending:
//!
//! - Kolmogorov–Smirnov `D = maxᵢ max(i/n − Fᵢ, Fᵢ − (i−1)/n)`, the largest gap between the
//!   empirical CDF of θ and the fitted Rayleigh CDF; Stephens' modified form
//!   `D* = (D − 0.2/n)(√n + 0.26 + 0.5/√n)`.
//! - Anderson–Darling `A² = −n − (1/n) Σ (2i−1)[ln Fᵢ + ln(1 − F₍ₙ₊₁₋ᵢ₎)]`; modified
//!   `A* = A²(1 + 0.6/n)`.
//!
//! ## p-values: Monte Carlo null calibration
//!
//! Because the scale is estimated, the textbook KS/AD p-values (known parameters) would be far
//! too large. The null distribution of these statistics does not depend on the true scale (they
//! are scale invariant: the statistic is pivotal), only on `n`, so it is simulated: `M` samples of
//! `n` standard exponentials, generated already sorted by Rényi's representation
//! `E₍ᵢ₎ = Σ_{j ≤ i} Zⱼ/(n − j + 1)`, `Zⱼ ~ Exp(1)` from the counter-based generator
//! ([`crate::rng`], stream `GofNull`), give `M` values of D* and A*, and
//! `p = (1 + #{T_sim ≥ T_obs}) / (M + 1)` (Davison & Hinkley 1997, eq. 4.11), with Monte Carlo
//! standard error `√(p(1−p)/M)`.
//!
//! ## The normal law (despace)
//!
//! [`normal_gof`] tests a sample against the normal law with mean and standard deviation
//! estimated (`x̄`, `s` with divisor n − 1: "case 3" of D'Agostino & Stephens §4.8,
//! Lilliefors' test for KS), with `Fᵢ = Φ((x₍ᵢ₎ − x̄)/s)` in the same D and A² and Stephens'
//! modified forms for this case, `D* = D(√n − 0.01 + 0.85/√n)`, `A* = A²(1 + 0.75/n + 2.25/n²)`.
//! The statistics are invariant under a change of location and scale, so the null is
//! simulated from standard normals (Box–Muller of two uniforms of the counter-based
//! generator, stream `GofNormalNull`), sorted, in the same way as the exponential one.
//!
//! For `n` above [`MAX_CALIBRATION_N`] the null of the *modified* statistics is simulated at
//! `n = MAX_CALIBRATION_N`: Stephens' modifications make their percentage points independent of
//! `n` (the corrections are of order 0.26/√n and 0.6/n, below 0.6 % there), which keeps the cost
//! bounded. The calibration depends only on (n, M, seed), so cases of equal size share it.

use crate::bootstrap::for_each_replicate;
use crate::rng::{self, Stream};

/// Above this sample size the null is simulated at this size (see the module doc).
pub const MAX_CALIBRATION_N: usize = 2_000;

/// The statistics of one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpStatistics {
    /// Sample size.
    pub n: usize,
    /// Kolmogorov–Smirnov D: max gap between empirical and fitted CDF.
    pub ks: f64,
    /// Stephens' modified D*.
    pub ks_modified: f64,
    /// Anderson–Darling A².
    pub ad: f64,
    /// Stephens' modified A*.
    pub ad_modified: f64,
}

/// KS and AD statistics of exponentiality with the mean estimated, for `y` sorted ascending
/// (y ≥ 0). Fails with a reason if n < 2 or the mean is zero.
pub fn exp_statistics(y_sorted: &[f64]) -> Result<ExpStatistics, String> {
    let n = y_sorted.len();
    if n < 2 {
        return Err(format!(
            "n = {n}: a goodness-of-fit test needs at least 2 samples"
        ));
    }
    let nf = n as f64;
    let mean = y_sorted.iter().sum::<f64>() / nf;
    if !(mean > 0.0 && mean.is_finite()) {
        return Err("every θ_P is zero: no Rayleigh scale to test".into());
    }
    let inv = 1.0 / mean;
    let mut d = 0.0f64;
    let mut s = 0.0f64;
    for (i, &y) in y_sorted.iter().enumerate() {
        let f = -(-y * inv).exp_m1();
        let k = i as f64;
        d = d.max((k + 1.0) / nf - f).max(f - k / nf);
        // ln(1 − F(y₍ₙ₊₁₋ᵢ₎)) = −y₍ₙ₊₁₋ᵢ₎/ȳ exactly.
        let upper = y_sorted[n - 1 - i];
        s += (2.0 * k + 1.0) * (f.max(f64::MIN_POSITIVE).ln() - upper * inv);
    }
    let ad = -nf - s / nf;
    let sq = nf.sqrt();
    Ok(ExpStatistics {
        n,
        ks: d,
        ks_modified: (d - 0.2 / nf) * (sq + 0.26 + 0.5 / sq),
        ad,
        ad_modified: ad * (1.0 + 0.6 / nf),
    })
}

/// `Φ(z)`, the standard normal CDF, and `1 − Φ(z)`, each accurate in its own tail.
fn normal_cdf_pair(z: f64) -> (f64, f64) {
    use statrs::function::erf::erfc;
    let r = std::f64::consts::FRAC_1_SQRT_2;
    (0.5 * erfc(-z * r), 0.5 * erfc(z * r))
}

/// KS and AD statistics of normality with mean and standard deviation estimated, for `x`
/// sorted ascending (see the module doc). Fails with a reason if n < 3 or every value is the
/// same.
pub fn normal_statistics(x_sorted: &[f64]) -> Result<ExpStatistics, String> {
    let n = x_sorted.len();
    if n < 3 {
        return Err(format!(
            "n = {n}: a test of normality needs at least 3 samples"
        ));
    }
    let nf = n as f64;
    let mean = x_sorted.iter().sum::<f64>() / nf;
    let ss: f64 = x_sorted.iter().map(|x| (x - mean) * (x - mean)).sum();
    let sd = (ss / (nf - 1.0)).sqrt();
    if !(sd > 0.0 && sd.is_finite()) {
        return Err("every value is the same: no normal spread to test".into());
    }
    let z: Vec<f64> = x_sorted.iter().map(|x| (x - mean) / sd).collect();
    let mut d = 0.0f64;
    let mut s = 0.0f64;
    for i in 0..n {
        let (f, _) = normal_cdf_pair(z[i]);
        let (_, upper) = normal_cdf_pair(z[n - 1 - i]);
        let k = i as f64;
        d = d.max((k + 1.0) / nf - f).max(f - k / nf);
        s += (2.0 * k + 1.0) * (f.max(f64::MIN_POSITIVE).ln() + upper.max(f64::MIN_POSITIVE).ln());
    }
    let ad = -nf - s / nf;
    let sq = nf.sqrt();
    Ok(ExpStatistics {
        n,
        ks: d,
        ks_modified: d * (sq - 0.01 + 0.85 / sq),
        ad,
        ad_modified: ad * (1.0 + 0.75 / nf + 2.25 / (nf * nf)),
    })
}

/// The law a null calibration is simulated under.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Law {
    /// The exponential (θ² and decenter² under the Rayleigh law).
    Exponential,
    /// The normal (despace).
    Normal,
}

/// A simulated null distribution of D* and A* at one sample size.
#[derive(Debug, Clone)]
pub struct NullCalibration {
    /// Sample size simulated.
    pub sample_size: usize,
    /// D* of each simulated sample, sorted ascending.
    pub ks_modified: Vec<f64>,
    /// A* of each simulated sample, sorted ascending.
    pub ad_modified: Vec<f64>,
}

impl NullCalibration {
    /// Simulates `replicates` standard normal samples of size `sample_size` (≥ 3), for
    /// [`normal_statistics`].
    pub fn simulate_normal(sample_size: usize, replicates: u32, seed: u64, threads: usize) -> Self {
        let n = sample_size.max(3);
        let pairs: Vec<(f64, f64)> = for_each_replicate(
            replicates as usize,
            threads,
            || vec![0.0f64; n],
            |r, x| {
                let key = rng::replicate_key(seed ^ n as u64, Stream::GofNormalNull, r as u64);
                for (j, slot) in x.iter_mut().enumerate() {
                    let j = 2 * j as u64;
                    *slot = rng::box_muller(
                        rng::open01(rng::bits(key, j)),
                        rng::open01(rng::bits(key, j + 1)),
                    );
                }
                x.sort_by(f64::total_cmp);
                let s = normal_statistics(x).expect("simulated normals differ");
                (s.ks_modified, s.ad_modified)
            },
        );
        Self::from_pairs(n, pairs)
    }

    fn from_pairs(n: usize, pairs: Vec<(f64, f64)>) -> Self {
        let mut ks: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let mut ad: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        ks.sort_by(f64::total_cmp);
        ad.sort_by(f64::total_cmp);
        Self {
            sample_size: n,
            ks_modified: ks,
            ad_modified: ad,
        }
    }

    /// Simulates `replicates` exponential samples of size `sample_size` (≥ 2).
    pub fn simulate(sample_size: usize, replicates: u32, seed: u64, threads: usize) -> Self {
        let n = sample_size.max(2);
        let pairs: Vec<(f64, f64)> = for_each_replicate(
            replicates as usize,
            threads,
            || vec![0.0f64; n],
            |r, y| {
                let key = rng::replicate_key(seed ^ n as u64, Stream::GofNull, r as u64);
                let mut acc = 0.0;
                for (j, slot) in y.iter_mut().enumerate() {
                    acc += rng::exp1(rng::bits(key, j as u64)) / (n - j) as f64;
                    *slot = acc;
                }
                let s = exp_statistics(y).expect("simulated exponentials are positive");
                (s.ks_modified, s.ad_modified)
            },
        );
        Self::from_pairs(n, pairs)
    }

    /// `(1 + #{T_sim ≥ t}) / (M + 1)` over `sorted`.
    fn p_value(sorted: &[f64], t: f64) -> f64 {
        let at_least = sorted.len() - sorted.partition_point(|&x| x < t);
        (1.0 + at_least as f64) / (sorted.len() as f64 + 1.0)
    }

    /// The KS p-value of an observed D*.
    pub fn ks_p_value(&self, ks_modified: f64) -> f64 {
        Self::p_value(&self.ks_modified, ks_modified)
    }

    /// The AD p-value of an observed A*.
    pub fn ad_p_value(&self, ad_modified: f64) -> f64 {
        Self::p_value(&self.ad_modified, ad_modified)
    }

    /// Number of simulated samples.
    pub fn replicates(&self) -> usize {
        self.ks_modified.len()
    }
}

/// Null calibrations already simulated in this run, by law and sample size.
#[derive(Debug, Default)]
pub struct CalibrationCache {
    by_size: std::collections::BTreeMap<(Law, usize), NullCalibration>,
}

/// Settings of the goodness-of-fit test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GofConfig {
    /// Simulated null samples `M`.
    pub replicates: u32,
    /// Seed of the null simulation.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
}

impl CalibrationCache {
    /// The exponential calibration for samples of size `n` (simulated at
    /// `min(n, MAX_CALIBRATION_N)`).
    pub fn get(&mut self, n: usize, config: &GofConfig) -> &NullCalibration {
        self.of(Law::Exponential, n, config)
    }

    /// The calibration of `law` for samples of size `n` (simulated at
    /// `min(n, MAX_CALIBRATION_N)`).
    pub fn of(&mut self, law: Law, n: usize, config: &GofConfig) -> &NullCalibration {
        let size = n.min(MAX_CALIBRATION_N);
        self.by_size
            .entry((law, size))
            .or_insert_with(|| match law {
                Law::Exponential => {
                    NullCalibration::simulate(size, config.replicates, config.seed, config.threads)
                }
                Law::Normal => NullCalibration::simulate_normal(
                    size,
                    config.replicates,
                    config.seed,
                    config.threads,
                ),
            })
    }
}

/// The outcome of the Rayleigh goodness-of-fit tests for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayleighGof {
    /// The statistics.
    pub statistics: ExpStatistics,
    /// KS p-value (estimated scale, Monte Carlo calibrated).
    pub ks_p: f64,
    /// AD p-value.
    pub ad_p: f64,
    /// Monte Carlo standard error of the KS p-value.
    pub ks_p_se: f64,
    /// Monte Carlo standard error of the AD p-value.
    pub ad_p_se: f64,
    /// The sample size of the null simulation.
    pub calibration_n: usize,
    /// The number of null samples.
    pub calibration_replicates: usize,
}

/// Tests θ_P (sorted ascending) against the Rayleigh law with the scale estimated (also
/// decenter, which follows the same law under small errors).
pub fn rayleigh_gof(
    theta_sorted: &[f64],
    cache: &mut CalibrationCache,
    config: &GofConfig,
) -> Result<RayleighGof, String> {
    let y: Vec<f64> = theta_sorted.iter().map(|t| t * t).collect();
    let statistics = exp_statistics(&y)?;
    calibrated(statistics, cache.get(y.len(), config))
}

/// Tests a sample (sorted ascending) against the normal law with mean and standard deviation
/// estimated (despace); the outcome has [`RayleighGof`]'s form.
pub fn normal_gof(
    sorted: &[f64],
    cache: &mut CalibrationCache,
    config: &GofConfig,
) -> Result<RayleighGof, String> {
    let statistics = normal_statistics(sorted)?;
    calibrated(statistics, cache.of(Law::Normal, sorted.len(), config))
}

/// The p-values of `statistics` under the null `cal`.
fn calibrated(statistics: ExpStatistics, cal: &NullCalibration) -> Result<RayleighGof, String> {
    let m = cal.replicates() as f64;
    let ks_p = cal.ks_p_value(statistics.ks_modified);
    let ad_p = cal.ad_p_value(statistics.ad_modified);
    Ok(RayleighGof {
        statistics,
        ks_p,
        ad_p,
        ks_p_se: (ks_p * (1.0 - ks_p) / m).sqrt(),
        ad_p_se: (ad_p * (1.0 - ad_p) / m).sqrt(),
        calibration_n: cal.sample_size,
        calibration_replicates: cal.replicates(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AD statistic by hand for y = (1, 2, 3): ȳ = 2, Fᵢ = 1 − e^{−yᵢ/2}.
    #[test]
    fn statistics_by_hand() {
        let y = [1.0, 2.0, 3.0];
        let f: Vec<f64> = y.iter().map(|v: &f64| 1.0 - (-v / 2.0).exp()).collect();
        let mut s = 0.0;
        for i in 0..3 {
            s += (2.0 * i as f64 + 1.0) * (f[i].ln() + (1.0 - f[2 - i]).ln());
        }
        let ad = -3.0 - s / 3.0;
        let d = (0..3)
            .map(|i| ((i + 1) as f64 / 3.0 - f[i]).max(f[i] - i as f64 / 3.0))
            .fold(0.0, f64::max);
        let st = exp_statistics(&y).unwrap();
        assert!((st.ad - ad).abs() < 1e-12);
        assert!((st.ks - d).abs() < 1e-15);
        // Scale invariance: the statistic is pivotal.
        let st10 = exp_statistics(&[10.0, 20.0, 30.0]).unwrap();
        assert!((st10.ad - st.ad).abs() < 1e-12 && (st10.ks - st.ks).abs() < 1e-15);
    }

    /// Stephens' tables (D'Agostino & Stephens 1986, Table 4.14; Stephens 1974, JASA 69:730,
    /// Table 1A: exponential, mean estimated) give upper 5 % points D* ≈ 1.094 and A* ≈ 1.32–1.34
    /// (printings differ in the last digits); our simulated null must be close.
    #[test]
    fn simulated_null_matches_stephens_five_percent_points() {
        let cal = NullCalibration::simulate(100, 4000, 3, 2);
        let q = |v: &[f64]| crate::quantile::quantile_sorted(v, 0.95).unwrap();
        let (d95, a95) = (q(&cal.ks_modified), q(&cal.ad_modified));
        assert!((d95 - 1.094).abs() < 0.05, "D* 95 % point {d95}");
        assert!((a95 - 1.33).abs() < 0.08, "A* 95 % point {a95}");
    }

    /// Stephens' upper 5 % points for the normal with mean and variance estimated
    /// (D'Agostino & Stephens 1986, Table 4.7): D* = 0.895, A* = 0.752; our simulated null
    /// must be close. And the statistics by hand for (−1, 0, 1): x̄ = 0, s = 1.
    #[test]
    fn normal_null_matches_stephens_five_percent_points() {
        let cal = NullCalibration::simulate_normal(100, 4000, 3, 2);
        let q = |v: &[f64]| crate::quantile::quantile_sorted(v, 0.95).unwrap();
        let (d95, a95) = (q(&cal.ks_modified), q(&cal.ad_modified));
        assert!((d95 - 0.895).abs() < 0.04, "D* 95 % point {d95}");
        assert!((a95 - 0.752).abs() < 0.05, "A* 95 % point {a95}");
        let st = normal_statistics(&[-1.0, 0.0, 1.0]).unwrap();
        let phi = |z: f64| 0.5 * statrs::function::erf::erfc(-z / 2f64.sqrt());
        let f = [phi(-1.0), 0.5, phi(1.0)];
        let d = (0..3)
            .map(|i| ((i + 1) as f64 / 3.0 - f[i]).max(f[i] - i as f64 / 3.0))
            .fold(0.0, f64::max);
        let mut s = 0.0;
        for i in 0..3 {
            s += (2.0 * i as f64 + 1.0) * (f[i].ln() + (1.0 - f[2 - i]).ln());
        }
        assert!((st.ks - d).abs() < 1e-15 && (st.ad - (-3.0 - s / 3.0)).abs() < 1e-12);
        // Location and scale invariance.
        let moved = normal_statistics(&[9.0, 10.0, 11.0]).unwrap();
        assert!((moved.ad - st.ad).abs() < 1e-12);
        assert!(normal_statistics(&[2.0, 2.0, 2.0]).is_err());
    }

    #[test]
    fn degenerate_inputs_are_reasons() {
        assert!(exp_statistics(&[1.0]).is_err());
        assert!(exp_statistics(&[0.0, 0.0, 0.0]).is_err());
    }
}
