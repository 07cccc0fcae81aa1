//! Statistical verification: do the intervals cover, do the tests hold their level, do the fits
//! recover known values? Each test names its source; sample sizes and repeat counts are chosen so
//! that the whole file runs in a few seconds in the test profile (opt-level 2), with acceptance
//! bands of about ±3 binomial standard deviations around the nominal rate.
//!
//! Data are simulated from the crate's counter-based generator (stream `Synthetic`), one key per
//! repeat, so every run sees the same numbers.

use mc_merge::bootstrap::{self, BootstrapConfig, SortedSample, bootstrap_quantiles};
use mc_merge::gof::{CalibrationCache, GofConfig, MAX_CALIBRATION_N, rayleigh_gof};
use mc_merge::quantile::{order_statistic_interval, quantile_sorted};
use mc_merge::rayleigh;
use mc_merge::rng::{self, Stream};

fn key(repeat: u64, salt: u64) -> u64 {
    rng::replicate_key(0x5eed ^ salt, Stream::Synthetic, repeat)
}

/// Rayleigh(σ) by inversion: σ √(−2 ln U) (paper eq. 27 inverted).
fn rayleigh_sample(n: usize, sigma: f64, k: u64) -> Vec<f64> {
    (0..n as u64)
        .map(|i| sigma * (2.0 * rng::exp1(rng::bits(k, i))).sqrt())
        .collect()
}

fn exponential_sample(n: usize, k: u64) -> Vec<f64> {
    (0..n as u64).map(|i| rng::exp1(rng::bits(k, i))).collect()
}

fn sorted(v: Vec<f64>) -> SortedSample {
    SortedSample::new(v.into_iter().zip(0u64..).collect())
}

/// The ML Rayleigh fit and its exact χ²(2n) interval (2nσ̂²/σ² ~ χ²(2n), since θ²/σ² ~ χ²(2)):
/// recovers the paper's σ_t = 3.96e-5 and covers it in 95 % ± 2.1 % (3 sd) of 1000 repeats.
#[test]
fn rayleigh_fit_interval_covers_95_percent() {
    let sigma = 3.96e-5;
    let big = rayleigh_sample(50_000, sigma, key(0, 1));
    let fit = rayleigh::fit(&big, 0.95).unwrap();
    assert!((fit.sigma / sigma - 1.0).abs() < 0.01, "{fit:?}");
    assert!(fit.sigma_interval.lower < sigma && sigma < fit.sigma_interval.upper);
    let repeats = 1000;
    let covered = (0..repeats)
        .filter(|&r| {
            let f = rayleigh::fit(&rayleigh_sample(200, sigma, key(r, 2)), 0.95).unwrap();
            f.sigma_interval.lower <= sigma && sigma <= f.sigma_interval.upper
        })
        .count();
    let rate = covered as f64 / repeats as f64;
    assert!((0.929..=0.971).contains(&rate), "coverage {rate}");
}

/// Poisson-bootstrap percentile and BCa intervals, and the order-statistic interval, of the
/// 95th percentile of Exp(1) (true value ln 20) cover it in about 95 % of 200 repeats of
/// n = 400 (percentile bootstrap: Efron & Tibshirani 1993, ch. 13; the Poisson bootstrap:
/// Hanley & MacGibbon 2006). The band [0.88, 0.995] allows the known slight undercoverage of
/// bootstrap intervals for tail quantiles at this n.
#[test]
fn bootstrap_intervals_cover_the_true_quantile() {
    let truth = 20f64.ln();
    let (repeats, n) = (200u64, 400);
    let (mut pct, mut bca, mut os) = (0, 0, 0);
    for r in 0..repeats {
        let s = sorted(exponential_sample(n, key(r, 3)));
        let c = BootstrapConfig {
            replicates: 500,
            seed: 1000 + r,
            threads: 2,
        };
        let reps = bootstrap_quantiles(&s, &[0.95], &c).sorted_level(0);
        let q = quantile_sorted(&s.values, 0.95).unwrap();
        let (lo, hi) = bootstrap::percentile_interval(&reps, 0.95).unwrap();
        pct += usize::from(lo <= truth && truth <= hi);
        let a = bootstrap::quantile_acceleration(&s.values, 0.95, q).unwrap();
        let b = bootstrap::bca_interval(&reps, q, a, 0.95).unwrap();
        bca += usize::from(b.lower <= truth && truth <= b.upper);
        let o = order_statistic_interval(&s.values, 0.95, 0.95).unwrap();
        os += usize::from(o.lower <= truth && truth <= o.upper);
    }
    let rate = |k: usize| k as f64 / repeats as f64;
    assert!(
        (0.88..=0.995).contains(&rate(pct)),
        "percentile {}",
        rate(pct)
    );
    assert!((0.88..=0.995).contains(&rate(bca)), "BCa {}", rate(bca));
    // The order-statistic interval is exact and conservative (coverage ≥ 95 %).
    assert!(rate(os) >= 0.9, "order statistic {}", rate(os));
}

/// On a large, nearly symmetric problem (the median of N(0,1), n = 20000) BCa's corrections
/// vanish (z₀ ≈ 0, a = 0 for the median) and BCa agrees with the percentile interval (Efron
/// 1987, §2).
#[test]
fn bca_agrees_with_percentile_on_large_symmetric_sample() {
    let k = key(0, 4);
    let n = 20_000u64;
    let normal: Vec<f64> = (0..n)
        .map(|i| {
            let u1 = rng::open01(rng::bits(k, 2 * i));
            let u2 = rng::open01(rng::bits(k, 2 * i + 1));
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        })
        .collect();
    let s = sorted(normal);
    let c = BootstrapConfig {
        replicates: 2000,
        seed: 9,
        threads: 2,
    };
    let reps = bootstrap_quantiles(&s, &[0.5], &c).sorted_level(0);
    let q = quantile_sorted(&s.values, 0.5).unwrap();
    let (lo, hi) = bootstrap::percentile_interval(&reps, 0.95).unwrap();
    let a = bootstrap::quantile_acceleration(&s.values, 0.5, q).unwrap();
    let b = bootstrap::bca_interval(&reps, q, a, 0.95).unwrap();
    let width = hi - lo;
    assert!(a.abs() < 1e-3, "a = {a}");
    assert!(b.z0.abs() < 0.1, "z0 = {}", b.z0);
    assert!((b.lower - lo).abs() < 0.1 * width, "{b:?} vs [{lo}, {hi}]");
    assert!((b.upper - hi).abs() < 0.1 * width, "{b:?} vs [{lo}, {hi}]");
    // Asymptotic width of the median's interval: 2·1.96·√(π/2)/√n (Stuart & Ord, 10.10).
    let asymptotic = 2.0 * 1.96 * (std::f64::consts::PI / 2.0).sqrt() / (n as f64).sqrt();
    assert!(
        (width / asymptotic - 1.0).abs() < 0.15,
        "{width} vs {asymptotic}"
    );
}

/// Under the Rayleigh law with estimated scale the KS and AD p-values are uniform: of 300
/// samples (n = 200), about 5 % fall below 0.05 (band 1.2 %–9.5 %, ±3.4 sd) and about half
/// below 0.5 (D'Agostino & Stephens 1986, §4.9: the null of the estimated-scale tests).
#[test]
fn gof_p_values_are_uniform_under_the_null() {
    let config = GofConfig {
        replicates: 999,
        seed: 4,
        threads: 2,
    };
    let mut cache = CalibrationCache::default();
    let repeats = 300u64;
    let (mut ks05, mut ad05, mut ks50, mut ad50) = (0, 0, 0, 0);
    for r in 0..repeats {
        let mut x = rayleigh_sample(200, 2.5e-5, key(r, 5));
        x.sort_by(f64::total_cmp);
        let g = rayleigh_gof(&x, &mut cache, &config).unwrap();
        ks05 += usize::from(g.ks_p < 0.05);
        ad05 += usize::from(g.ad_p < 0.05);
        ks50 += usize::from(g.ks_p < 0.5);
        ad50 += usize::from(g.ad_p < 0.5);
    }
    let f = |k: usize| k as f64 / repeats as f64;
    for (name, v) in [("KS", f(ks05)), ("AD", f(ad05))] {
        assert!((0.012..=0.095).contains(&v), "{name} rejects {v} at 5 %");
    }
    for (name, v) in [("KS", f(ks50)), ("AD", f(ad50))] {
        assert!((0.41..=0.59).contains(&v), "{name}: P(p < 0.5) = {v}");
    }
}

/// Above the calibration size the modified statistics' null is simulated at
/// `MAX_CALIBRATION_N`; the p-values must still hold their level at the paper's sample size
/// (60 samples of n = 50,000).
#[test]
fn gof_level_holds_above_the_calibration_size() {
    let config = GofConfig {
        replicates: 999,
        seed: 6,
        threads: 2,
    };
    let mut cache = CalibrationCache::default();
    let repeats = 60u64;
    let mut small = 0;
    let mut half = 0;
    for r in 0..repeats {
        let mut x = rayleigh_sample(50_000, 1.0, key(r, 6));
        x.sort_by(f64::total_cmp);
        let g = rayleigh_gof(&x, &mut cache, &config).unwrap();
        assert_eq!(g.calibration_n, MAX_CALIBRATION_N);
        small += usize::from(g.ad_p < 0.05 || g.ks_p < 0.05);
        half += usize::from(g.ad_p < 0.5);
    }
    // Either test below 5 %: about 5–10 % expected (two correlated tests), so ~3–6 of 60.
    assert!(small <= 13, "{small} of {repeats} rejected");
    // AD p below 0.5 in half of the samples: 30 ± 3 sd.
    assert!((18..=42).contains(&half), "{half} of {repeats} below 0.5");
}

/// Clearly non-Rayleigh data are rejected: θ uniform on [0, 1] (so θ² has density ∝ 1/√y, far
/// from exponential), n = 200, in at least 45 of 50 repeats by AD; and θ from a Rayleigh
/// mixture of two scales (1 and 3) at n = 2000.
#[test]
fn gof_rejects_clearly_non_rayleigh_data() {
    let config = GofConfig {
        replicates: 999,
        seed: 7,
        threads: 2,
    };
    let mut cache = CalibrationCache::default();
    let mut rejected = 0;
    for r in 0..50u64 {
        let k = key(r, 7);
        let mut x: Vec<f64> = (0..200u64).map(|i| rng::open01(rng::bits(k, i))).collect();
        x.sort_by(f64::total_cmp);
        let g = rayleigh_gof(&x, &mut cache, &config).unwrap();
        rejected += usize::from(g.ad_p < 0.05);
    }
    assert!(
        rejected >= 45,
        "AD rejected uniform data only {rejected} of 50 times"
    );
    let mut mix = rayleigh_sample(1000, 1.0, key(0, 8));
    mix.extend(rayleigh_sample(1000, 3.0, key(1, 8)));
    mix.sort_by(f64::total_cmp);
    let g = rayleigh_gof(&mix, &mut cache, &config).unwrap();
    assert!(g.ad_p < 0.01 && g.ks_p < 0.01, "{g:?}");
}
