//! θ_P's percentile of a Monte Carlo run with its bootstrap interval, and the check an
//! allocation must pass.
//!
//! The estimate is the Hyndman–Fan definition-1 quantile of the run's θ_P; the interval is the
//! 95 % BCa interval of the Poisson bootstrap (`truss_stats::bootstrap`, B = 2000, seed the
//! job's, weights keyed by the sample index: the interval depends on neither the thread count
//! nor the order of the samples). An allocation **verifies** when the interval's upper end is
//! at most the target and the estimate at least 0.9 × the target: the budget is met with 95 %
//! confidence, and not needlessly.

use crate::errors::ToleranceError;
use truss_stats::bootstrap::{
    BootstrapConfig, SortedSample, bca_interval, bootstrap_quantiles, quantile_acceleration,
};
use truss_stats::quantile::quantile_sorted;

/// Bootstrap replicates of the percentile.
pub const REPLICATES: u32 = 2000;

/// The least estimate, as a fraction of the target, that is not needlessly conservative.
pub const LEAST_FRACTION: f64 = 0.9;

/// A percentile of θ_P with its interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percentile {
    /// The estimate \[rad\].
    pub theta: f64,
    /// The 95 % BCa interval \[rad\].
    pub interval: (f64, f64),
    /// Samples.
    pub samples: usize,
}

impl Percentile {
    /// Whether it meets `target` \[rad\] at the interval's upper end, and is within
    /// 1 − [`LEAST_FRACTION`] of it.
    pub fn verifies(&self, target: f64) -> bool {
        self.interval.1 <= target && self.theta >= LEAST_FRACTION * target
    }
}

/// The `q`-percentile of `theta_p` (sample `k` at position `k`) with its interval.
pub fn percentile(
    theta_p: &[f64],
    q: f64,
    seed: u64,
    threads: usize,
) -> Result<Percentile, ToleranceError> {
    let sample = SortedSample::new(
        theta_p
            .iter()
            .enumerate()
            .map(|(k, &t)| (t, k as u64))
            .collect(),
    );
    let theta = quantile_sorted(&sample.values, q)
        .ok_or_else(|| ToleranceError::Statistics("no samples for the percentile".into()))?;
    let config = BootstrapConfig {
        replicates: REPLICATES,
        seed,
        threads,
    };
    let reps = bootstrap_quantiles(&sample, &[q], &config);
    let sorted = reps.sorted_level(0);
    let a = quantile_acceleration(&sample.values, q, theta).unwrap_or(0.0);
    let bca = bca_interval(&sorted, theta, a, 0.95).map_err(|e| {
        ToleranceError::Statistics(format!(
            "the interval of θ_P{} over {} samples: {e}",
            q * 100.0,
            theta_p.len()
        ))
    })?;
    Ok(Percentile {
        theta,
        interval: (bca.lower, bca.upper),
        samples: theta_p.len(),
    })
}
