//! The Poisson bootstrap of percentiles, and its percentile and BCa confidence intervals.
//!
//! ## Why Poisson, and why it is split-invariant
//!
//! In replicate `r` every sample `i` gets an integer weight `wᵢ ~ Poisson(1)` instead of the
//! multinomial counts of Efron's bootstrap (Hanley & MacGibbon 2006; Chamandy et al., "Estimating
//! uncertainty for massive data streams", Google 2012). The weight is a pure function
//! `w(seed, r, global index)` of the counter-based generator of [`crate::rng`], so a sample's
//! weight never depends on which shard held it or in which order the files were read: the
//! replicates, and every interval below, are identical however the job was split. For large `n`
//! the Poisson and multinomial bootstraps agree (the total weight `W = Σ wᵢ` is `n ± √n`).
//!
//! ## The hot loop
//!
//! The sample is sorted once by (value, global index). For each replicate the weights are
//! generated in that sorted order into a byte buffer, summed, and the cumulative weight is walked
//! once to find every requested weighted quantile ([`crate::quantile`]). The replicates are
//! split into contiguous blocks over `threads` scoped threads; each replicate's result depends
//! only on (seed, r), so the results do not depend on the thread count.
//!
//! ## Intervals
//!
//! - **Percentile**: `[q*_{(1−c)/2}, q*_{(1+c)/2}]`, definition-1 quantiles of the replicates.
//! - **BCa** (Efron 1987, "Better bootstrap confidence intervals", JASA 82:171): the percentile
//!   levels are moved to `α₁,₂ = Φ(z₀ + (z₀ + z_{α})/(1 − a(z₀ + z_{α})))` with the bias correction
//!   `z₀ = Φ⁻¹((#{q* < q̂} + ½·#{q* = q̂}) / B)` (ties, frequent for a quantile, count half) and the
//!   acceleration from the empirical influence function of the quantile,
//!   `Uᵢ = p − 1{xᵢ ≤ q̂}`, `a = Σ Uᵢ³ / (6 (Σ Uᵢ²)^{3/2})` (the density factor `1/f(q̂)` of the
//!   influence function cancels in `a`).

use crate::quantile::{quantile_sorted, weighted_positions_with_total};
use crate::rng::{self, PoissonTable, Stream};
use statrs::distribution::{ContinuousCDF, Normal};

const LANES: usize = 4;

/// How to bootstrap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BootstrapConfig {
    /// Number of replicates `B`.
    pub replicates: u32,
    /// Seed of the counter-based generator.
    pub seed: u64,
    /// Worker threads (results do not depend on it).
    pub threads: usize,
}

/// A sample sorted ascending by value, ties by global index, with each value's global index.
#[derive(Debug, Clone, Default)]
pub struct SortedSample {
    /// The values, ascending.
    pub values: Vec<f64>,
    /// The global sample index of each value.
    pub indices: Vec<u64>,
}

impl SortedSample {
    /// Sorts `(value, global index)` pairs. Values must not be NaN (they are compared with
    /// `f64::total_cmp`).
    pub fn new(mut pairs: Vec<(f64, u64)>) -> Self {
        pairs.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let values = pairs.iter().map(|p| p.0).collect();
        let indices = pairs.iter().map(|p| p.1).collect();
        Self { values, indices }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// The result of one bootstrap replicate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Replicate {
    /// Total weight `W` (0 if every weight was zero: the replicate is empty).
    pub total_weight: u64,
    /// Weighted sum of squares `Σ wᵢ xᵢ²` (for the Rayleigh scale `σ*² = Σ w x² / (2W)`).
    pub weighted_sum_sq: f64,
}

/// All replicates of one sample: for each requested level, the replicate quantiles.
#[derive(Debug, Clone)]
pub struct QuantileReplicates {
    /// The levels, in the order asked.
    pub levels: Vec<f64>,
    /// `quantiles[j][r]`: the level-`j` quantile of replicate `r`; `None` if the replicate is
    /// empty (all weights zero, probability `e⁻ⁿ`).
    pub quantiles: Vec<Vec<Option<f64>>>,
    /// Per replicate totals.
    pub replicates: Vec<Replicate>,
}

impl QuantileReplicates {
    /// The number of empty replicates.
    pub fn empty(&self) -> usize {
        self.replicates
            .iter()
            .filter(|r| r.total_weight == 0)
            .count()
    }

    /// The valid replicate values of level `j`, sorted ascending.
    pub fn sorted_level(&self, j: usize) -> Vec<f64> {
        let mut v: Vec<f64> = self.quantiles[j].iter().flatten().copied().collect();
        v.sort_by(f64::total_cmp);
        v
    }
}

/// Runs `f(r, out)` for every replicate `r` in `0..replicates`, writing one result per
/// replicate, over `threads` scoped threads in contiguous blocks. Deterministic: each result
/// depends only on `r`.
/// `make_scratch` builds one scratch value per thread, reused across its replicates.
pub fn for_each_replicate<T, Sc, S, F>(
    replicates: usize,
    threads: usize,
    make_scratch: S,
    f: F,
) -> Vec<T>
where
    T: Default + Clone + Send,
    S: Fn() -> Sc + Sync,
    F: Fn(usize, &mut Sc) -> T + Sync,
{
    let mut out = vec![T::default(); replicates];
    let threads = threads.clamp(1, replicates.max(1));
    let chunk = replicates.div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for (block, slot) in out.chunks_mut(chunk).enumerate() {
            let f = &f;
            let make_scratch = &make_scratch;
            scope.spawn(move || {
                let mut scratch = make_scratch();
                for (k, o) in slot.iter_mut().enumerate() {
                    *o = f(block * chunk + k, &mut scratch);
                }
            });
        }
    });
    out
}

/// The hot loop: the weights of one replicate in sorted order, their total `W` and `Σ w x²`.
/// Four partial sums of `w x²` break the floating-point dependency chain; the order of
/// summation is fixed, so the result is still a function of (seed, replicate) only.
#[inline(never)]
fn generate_weights(
    table: &PoissonTable,
    key: u64,
    offsets: &[u64],
    values: &[f64],
    weights: &mut [u8],
) -> (u64, f64) {
    let mut total = 0u64;
    let mut sum_sq = [0.0f64; LANES];
    let chunks = weights
        .chunks_exact_mut(LANES)
        .zip(offsets.chunks_exact(LANES))
        .zip(values.chunks_exact(LANES));
    for ((w, o), x) in chunks {
        for l in 0..LANES {
            let k = table.weight(rng::bits_at(key, o[l]));
            w[l] = k;
            total += u64::from(k);
            sum_sq[l] += f64::from(k) * x[l] * x[l];
        }
    }
    let done = weights.len() - weights.len() % LANES;
    for (l, i) in (done..weights.len()).enumerate() {
        let k = table.weight(rng::bits_at(key, offsets[i]));
        weights[i] = k;
        total += u64::from(k);
        sum_sq[l] += f64::from(k) * values[i] * values[i];
    }
    (total, (sum_sq[0] + sum_sq[1]) + (sum_sq[2] + sum_sq[3]))
}

/// The Poisson bootstrap of the definition-1 quantiles at `levels` (each in (0, 1)) of `sample`.
pub fn bootstrap_quantiles(
    sample: &SortedSample,
    levels: &[f64],
    config: &BootstrapConfig,
) -> QuantileReplicates {
    let n = sample.len();
    // Walk the levels in ascending order, remember where each goes.
    let mut order: Vec<usize> = (0..levels.len()).collect();
    order.sort_by(|&a, &b| levels[a].total_cmp(&levels[b]));
    let sorted_levels: Vec<f64> = order.iter().map(|&j| levels[j]).collect();
    let table = PoissonTable::new();
    let offsets: Vec<u64> = sample
        .indices
        .iter()
        .map(|&i| rng::counter_offset(i))
        .collect();
    type Row = (Replicate, Vec<Option<f64>>);
    let rows: Vec<Row> = for_each_replicate(
        config.replicates as usize,
        config.threads,
        || (vec![0u8; n], vec![0usize; levels.len()]),
        |r, (weights, positions)| {
            let key = rng::replicate_key(config.seed, Stream::Bootstrap, r as u64);
            let (total, sum_sq) = generate_weights(&table, key, &offsets, &sample.values, weights);
            let rep = Replicate {
                total_weight: total,
                weighted_sum_sq: sum_sq,
            };
            let mut q = vec![None; levels.len()];
            if weighted_positions_with_total(weights, total, &sorted_levels, positions) {
                for (s, &j) in order.iter().enumerate() {
                    q[j] = Some(sample.values[positions[s]]);
                }
            }
            (rep, q)
        },
    );
    let mut quantiles = vec![Vec::with_capacity(rows.len()); levels.len()];
    let mut replicates = Vec::with_capacity(rows.len());
    for (rep, q) in rows {
        replicates.push(rep);
        for (j, v) in q.into_iter().enumerate() {
            quantiles[j].push(v);
        }
    }
    QuantileReplicates {
        levels: levels.to_vec(),
        quantiles,
        replicates,
    }
}

/// The Poisson weights of replicate `replicate` for the samples with global indices `indices`
/// (in any order), written into `weights`; returns their total `W`. The building block for
/// bootstraps of other statistics (for example two-sample comparisons): give each sample its
/// global index and the weights stay split-invariant.
pub fn poisson_weights(seed: u64, replicate: u64, indices: &[u64], weights: &mut [u8]) -> u64 {
    let table = PoissonTable::new();
    let key = rng::replicate_key(seed, Stream::Bootstrap, replicate);
    let mut total = 0u64;
    for (w, &i) in weights.iter_mut().zip(indices) {
        *w = table.weight(rng::bits(key, i));
        total += u64::from(*w);
    }
    total
}

/// A Poisson bootstrap of any statistic: for each replicate, the weights of the samples with
/// global indices `indices` (in the order given) are generated and passed to `statistic` with
/// their total. Results depend only on (seed, replicate), never on the thread count.
pub fn bootstrap_statistic<T, F>(indices: &[u64], config: &BootstrapConfig, statistic: F) -> Vec<T>
where
    T: Default + Clone + Send,
    F: Fn(&[u8], u64) -> T + Sync,
{
    for_each_replicate(
        config.replicates as usize,
        config.threads,
        || vec![0u8; indices.len()],
        |r, weights| {
            let total = poisson_weights(config.seed, r as u64, indices, weights);
            statistic(weights, total)
        },
    )
}

/// The percentile-method interval from replicate values sorted ascending.
pub fn percentile_interval(sorted_replicates: &[f64], confidence: f64) -> Option<(f64, f64)> {
    let tail = (1.0 - confidence) / 2.0;
    Some((
        quantile_sorted(sorted_replicates, tail)?,
        quantile_sorted(sorted_replicates, 1.0 - tail)?,
    ))
}

/// A BCa interval with its bias correction and acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BcaInterval {
    /// Lower end.
    pub lower: f64,
    /// Upper end.
    pub upper: f64,
    /// Bias correction `z₀`.
    pub z0: f64,
    /// Acceleration `a`.
    pub acceleration: f64,
    /// The adjusted percentile levels (α₁, α₂) of the replicate distribution.
    pub levels: (f64, f64),
}

/// The acceleration of the BCa interval of the `p`-quantile `q` of `sorted` (ascending), from
/// the empirical influence function `Uᵢ = p − 1{xᵢ ≤ q}` (Efron 1987, eq. 6.6):
/// `a = Σ Uᵢ³ / (6 (Σ Uᵢ²)^{3/2})`. `None` if `Σ Uᵢ² = 0`.
pub fn quantile_acceleration(sorted: &[f64], p: f64, q: f64) -> Option<f64> {
    let n = sorted.len() as f64;
    let below = sorted.partition_point(|&x| x <= q) as f64;
    let (u_in, u_out) = (p - 1.0, p);
    let s2 = below * u_in * u_in + (n - below) * u_out * u_out;
    let s3 = below * u_in.powi(3) + (n - below) * u_out.powi(3);
    (s2 > 0.0).then(|| s3 / (6.0 * s2.powf(1.5)))
}

/// The BCa interval (Efron 1987) from replicate values sorted ascending, the estimate and the
/// acceleration. Fails with a reason when the bias correction is infinite (every replicate on
/// one side of the estimate) or the adjustment leaves (0, 1).
pub fn bca_interval(
    sorted_replicates: &[f64],
    estimate: f64,
    acceleration: f64,
    confidence: f64,
) -> Result<BcaInterval, String> {
    let b = sorted_replicates.len();
    if b == 0 {
        return Err("no bootstrap replicates".into());
    }
    let below = sorted_replicates.partition_point(|&x| x < estimate);
    let equal = sorted_replicates.partition_point(|&x| x <= estimate) - below;
    let frac = (below as f64 + 0.5 * equal as f64) / b as f64;
    if frac <= 0.0 || frac >= 1.0 {
        return Err(format!(
            "bias correction undefined: all {b} replicates lie on one side of the estimate"
        ));
    }
    let normal = Normal::standard();
    let z0 = normal.inverse_cdf(frac);
    let tail = (1.0 - confidence) / 2.0;
    let adjust = |alpha: f64| -> Option<f64> {
        let z = z0 + normal.inverse_cdf(alpha);
        let denom = 1.0 - acceleration * z;
        (denom > 0.0).then(|| normal.cdf(z0 + z / denom))
    };
    let (Some(a1), Some(a2)) = (adjust(tail), adjust(1.0 - tail)) else {
        return Err(format!(
            "acceleration a = {acceleration:.3} too large for the BCa adjustment"
        ));
    };
    if !(a1 > 0.0 && a2 < 1.0 && a1 < a2) {
        return Err(format!(
            "BCa levels ({a1:.4}, {a2:.4}) degenerate (z0 = {z0:.3}, a = {acceleration:.4})"
        ));
    }
    Ok(BcaInterval {
        lower: quantile_sorted(sorted_replicates, a1).ok_or("no replicates")?,
        upper: quantile_sorted(sorted_replicates, a2).ok_or("no replicates")?,
        z0,
        acceleration,
        levels: (a1, a2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(n: usize) -> SortedSample {
        let key = rng::replicate_key(99, Stream::Synthetic, 0);
        SortedSample::new(
            (0..n as u64)
                .map(|i| (rng::exp1(rng::bits(key, i)), i))
                .collect(),
        )
    }

    #[test]
    fn thread_count_does_not_change_replicates() {
        let s = sample(2000);
        let run = |threads| {
            let c = BootstrapConfig {
                replicates: 101,
                seed: 5,
                threads,
            };
            bootstrap_quantiles(&s, &[0.95, 0.5], &c).quantiles
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
        assert_eq!(one, run(64));
    }

    /// Replicate quantiles agree with a direct evaluation from the weights' definition.
    #[test]
    fn replicate_matches_direct_weighted_quantile() {
        let s = sample(300);
        let c = BootstrapConfig {
            replicates: 5,
            seed: 11,
            threads: 2,
        };
        let reps = bootstrap_quantiles(&s, &[0.9], &c);
        let table = PoissonTable::new();
        for r in 0..5u64 {
            // Expand each value by its weight in index order, then take definition 1.
            let mut expanded = vec![];
            for (x, &i) in s.values.iter().zip(&s.indices) {
                let w = rng::poisson_weight(&table, 11, r, i);
                expanded.extend(std::iter::repeat_n(*x, w as usize));
            }
            expanded.sort_by(f64::total_cmp);
            assert_eq!(
                reps.quantiles[0][r as usize],
                quantile_sorted(&expanded, 0.9)
            );
        }
    }

    /// The generic bootstrap with a weighted-quantile statistic reproduces the specialised one.
    #[test]
    fn generic_bootstrap_matches_quantile_bootstrap() {
        let s = sample(500);
        let c = BootstrapConfig {
            replicates: 50,
            seed: 3,
            threads: 2,
        };
        let fast = bootstrap_quantiles(&s, &[0.9], &c);
        let generic = bootstrap_statistic(&s.indices, &c, |w, total| {
            let mut pos = [0usize];
            crate::quantile::weighted_positions_with_total(w, total, &[0.9], &mut pos)
                .then(|| s.values[pos[0]])
        });
        assert_eq!(fast.quantiles[0], generic);
        let one = BootstrapConfig { threads: 1, ..c };
        assert_eq!(
            generic,
            bootstrap_statistic(&s.indices, &one, |w, t| {
                let mut pos = [0usize];
                crate::quantile::weighted_positions_with_total(w, t, &[0.9], &mut pos)
                    .then(|| s.values[pos[0]])
            })
        );
    }

    /// Ties in value are ordered by global index, whatever order the pairs came in.
    #[test]
    fn ties_sort_by_index() {
        let s = SortedSample::new(vec![(1.0, 5), (1.0, 2), (0.5, 9)]);
        assert_eq!(s.indices, vec![9, 2, 5]);
    }

    #[test]
    fn acceleration_of_median_is_zero_and_sign_follows_tail() {
        let x: Vec<f64> = (1..=100).map(f64::from).collect();
        assert!(quantile_acceleration(&x, 0.5, 50.0).unwrap().abs() < 1e-12);
        // Upper quantile: few U = p > 0, many U = p - 1 < 0 → negative skewness sum.
        let a = quantile_acceleration(&x, 0.95, 95.0).unwrap();
        // By hand: 95 values U = -0.05, 5 values U = 0.95.
        let s2 = 95.0 * 0.05f64.powi(2) + 5.0 * 0.95f64.powi(2);
        let s3 = -95.0 * 0.05f64.powi(3) + 5.0 * 0.95f64.powi(3);
        assert!((a - s3 / (6.0 * s2.powf(1.5))).abs() < 1e-15);
    }

    #[test]
    fn bca_one_sided_replicates_is_a_reason() {
        let reps = vec![2.0, 3.0, 4.0];
        assert!(bca_interval(&reps, 1.0, 0.0, 0.95).is_err());
    }

    /// With z₀ = 0 and a = 0 BCa is the percentile interval.
    #[test]
    fn bca_reduces_to_percentile_without_bias_or_acceleration() {
        let reps: Vec<f64> = (0..1001).map(f64::from).collect();
        let bca = bca_interval(&reps, 500.0, 0.0, 0.9).unwrap();
        assert!(bca.z0.abs() < 1e-12);
        assert_eq!(
            (bca.lower, bca.upper),
            percentile_interval(&reps, 0.9).unwrap()
        );
    }
}
