//! Percentiles: the inverse empirical CDF, its weighted form, and the distribution-free
//! order-statistic confidence interval.
//!
//! ## Definition (Hyndman & Fan 1996, definition 1)
//!
//! The `p`-quantile of a sample is the smallest sample value `x` with `F_n(x) ≥ p`, where
//! `F_n` is the empirical CDF. For values sorted ascending `x₍₁₎ ≤ … ≤ x₍ₙ₎` it is `x₍ₖ₎`
//! with `k` the smallest rank such that `k ≥ p·n`. With integer weights `wᵢ` (the Poisson
//! bootstrap) the same definition reads: the first sorted value whose cumulative weight
//! `Σ_{j ≤ k} w₍ⱼ₎` reaches `p·W`, `W = Σ wᵢ`; with all weights 1 the two coincide, and with
//! weight `w` a value counts as `w` copies of itself. Ties in value are ordered by global
//! sample index, so the sorted order, and with it every weighted quantile, is unique.
//! `p·n` and `p·W` are evaluated in IEEE double precision; `0 < p < 1`.

use statrs::distribution::{Binomial, DiscreteCDF};

/// Weights summed at once when the walk skips ahead (a multiple of the vector width).
const WALK_BLOCK: usize = 64;

/// The 1-based rank `k` of the Hyndman–Fan definition-1 `p`-quantile of `n` values: the smallest
/// `k ≥ 1` with `k ≥ p·n`. `None` if `n = 0` or `p` is not in (0, 1).
pub fn hf1_rank(n: usize, p: f64) -> Option<usize> {
    if n == 0 || !(p > 0.0 && p < 1.0) {
        return None;
    }
    let target = p * n as f64;
    // The smallest integer k with k >= target, at least 1 and at most n.
    Some((target.ceil() as usize).clamp(1, n))
}

/// The definition-1 `p`-quantile of values sorted ascending. `None` if empty or `p ∉ (0, 1)`.
pub fn quantile_sorted(sorted: &[f64], p: f64) -> Option<f64> {
    hf1_rank(sorted.len(), p).map(|k| sorted[k - 1])
}

/// The definition-1 `p`-quantile of a sample (sorted internally). `None` if empty, if a value
/// is NaN, or if `p ∉ (0, 1)`.
pub fn quantile(values: &[f64], p: f64) -> Option<f64> {
    if values.iter().any(|x| x.is_nan()) {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    quantile_sorted(&sorted, p)
}

/// The position (0-based, in sorted order) of the weighted definition-1 quantiles for the
/// levels `ps` (ascending), given the weights in sorted order. Writes `positions[j]` for
/// `ps[j]`; returns `false` (and writes nothing meaningful) when all weights are zero.
pub fn weighted_positions(weights_sorted: &[u8], ps: &[f64], positions: &mut [usize]) -> bool {
    let total: u64 = weights_sorted.iter().map(|&w| u64::from(w)).sum();
    weighted_positions_with_total(weights_sorted, total, ps, positions)
}

/// [`weighted_positions`] with the total weight already known.
pub fn weighted_positions_with_total(
    weights_sorted: &[u8],
    total: u64,
    ps: &[f64],
    positions: &mut [usize],
) -> bool {
    debug_assert!(ps.windows(2).all(|w| w[0] <= w[1]));
    if total == 0 || ps.is_empty() {
        return total != 0;
    }
    let w_total = total as f64;
    // cum ≥ p·W (a real comparison with the double p·W) ⟺ cum ≥ ⌈p·W⌉ for integer cum < 2⁵³.
    let need = |p: f64| (p * w_total).ceil().max(1.0) as u64;
    let n = weights_sorted.len();
    // `i` is the number of weights summed into `cum`. Whole blocks are skipped by their
    // (vectorised) sum while the target is beyond them; then the walk goes one by one.
    let (mut i, mut cum) = (0usize, 0u64);
    for (j, &p) in ps.iter().enumerate() {
        let target = need(p);
        if cum < target {
            while i + WALK_BLOCK <= n {
                let block: u32 = weights_sorted[i..i + WALK_BLOCK]
                    .iter()
                    .map(|&w| u32::from(w))
                    .sum();
                if cum + u64::from(block) >= target {
                    break;
                }
                cum += u64::from(block);
                i += WALK_BLOCK;
            }
            while i < n && cum < target {
                cum += u64::from(weights_sorted[i]);
                i += 1;
            }
        }
        if cum < target {
            break;
        }
        // The weight that made `cum` reach the target is at i − 1, and it is positive.
        positions[j] = i - 1;
        if j + 1 == ps.len() {
            return true;
        }
    }
    // Unreachable for p < 1 (⌈p·W⌉ ≤ W); be total anyway: the last weighted value.
    let last = weights_sorted.iter().rposition(|&w| w > 0).unwrap_or(0);
    for (j, &p) in ps.iter().enumerate() {
        if need(p) > total {
            positions[j] = last;
        }
    }
    true
}

/// A distribution-free confidence interval `[x₍ₗ₎, x₍ᵤ₎]` for the `p`-quantile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderStatisticInterval {
    /// 1-based rank of the lower end.
    pub lower_rank: usize,
    /// 1-based rank of the upper end.
    pub upper_rank: usize,
    /// `x₍ₗ₎`.
    pub lower: f64,
    /// `x₍ᵤ₎`.
    pub upper: f64,
    /// The exact coverage `P(l ≤ K ≤ u − 1)`, `K ~ Binomial(n, p)`, at least the confidence asked.
    pub coverage: f64,
}

/// The equal-tailed distribution-free interval for the `p`-quantile from the order statistics
/// of `sorted` (ascending), with `K ~ Binomial(n, p)` the number of values below the true
/// quantile ξ_p (e.g. Conover, *Practical Nonparametric Statistics*, 3rd ed., §3.2; David &
/// Nagaraja, *Order Statistics*, §7.1): `P(x₍ₗ₎ ≤ ξ_p ≤ x₍ᵤ₎) ≥ P(l ≤ K ≤ u − 1)`.
///
/// `l` is the largest rank with `P(K ≤ l − 1) ≤ (1 − c)/2` and `u` the smallest with
/// `P(K ≤ u − 1) ≥ 1 − (1 − c)/2`; binomial probabilities from `statrs` (regularised incomplete
/// beta). Fails with a reason if `n` is too small for an interval at this confidence.
pub fn order_statistic_interval(
    sorted: &[f64],
    p: f64,
    confidence: f64,
) -> Result<OrderStatisticInterval, String> {
    let n = sorted.len();
    if n == 0 {
        return Err("no samples".into());
    }
    let binom = Binomial::new(p, n as u64).map_err(|e| format!("binomial({n}, {p}): {e}"))?;
    let tail = (1.0 - confidence) / 2.0;
    // Smallest m in 0..=n with cdf(m) > tail; then l - 1 = m - 1, i.e. l = m.
    let first_above = |level: f64, strict: bool| -> u64 {
        let (mut lo, mut hi) = (0u64, n as u64);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            let c = binom.cdf(mid);
            let ok = if strict { c > level } else { c >= level };
            if ok {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    };
    // l: largest with cdf(l-1) <= tail  <=>  l = min{m : cdf(m) > tail}.
    let l = first_above(tail, true) as usize;
    // u: smallest with cdf(u-1) >= 1 - tail  <=>  u - 1 = min{m : cdf(m) >= 1 - tail}.
    let u = first_above(1.0 - tail, false) as usize + 1;
    if l < 1 || u > n {
        return Err(format!(
            "n = {n} is too small for a distribution-free {:.0} % interval of the {} % quantile (it would need order statistics {l} and {u} of {n})",
            confidence * 100.0,
            p * 100.0
        ));
    }
    let cdf = |k: usize| if k == 0 { 0.0 } else { binom.cdf(k as u64 - 1) };
    let coverage = cdf(u) - cdf(l);
    Ok(OrderStatisticInterval {
        lower_rank: l,
        upper_rank: u,
        lower: sorted[l - 1],
        upper: sorted[u - 1],
        coverage,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Hyndman & Fan (1996), definition 1, by hand: for 1..=10, the 0.95-quantile is the
    /// 10th value (9.5 → 10), the 0.5-quantile the 5th (5.0 → 5), 0.51 the 6th.
    #[test]
    fn hf1_by_hand() {
        let x: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(quantile_sorted(&x, 0.95), Some(10.0));
        assert_eq!(quantile_sorted(&x, 0.5), Some(5.0));
        assert_eq!(quantile_sorted(&x, 0.51), Some(6.0));
        assert_eq!(quantile_sorted(&x, 0.01), Some(1.0));
        assert_eq!(quantile_sorted(&x, 0.0), None);
        assert_eq!(quantile_sorted(&[], 0.5), None);
        assert_eq!(quantile(&[3.0, 1.0, 2.0], 0.5), Some(2.0));
    }

    /// Conover (1999, §3.2, example of the median with n = 20): the 95 % interval for the
    /// median is (x₍₆₎, x₍₁₅₎) with coverage 1 − 2·P(K ≤ 5) = 1 − 2·21700/2²⁰ = 0.958611.
    #[test]
    fn order_statistic_median_n20_by_hand() {
        let x: Vec<f64> = (1..=20).map(f64::from).collect();
        let ci = order_statistic_interval(&x, 0.5, 0.95).unwrap();
        assert_eq!((ci.lower_rank, ci.upper_rank), (6, 15));
        assert_eq!((ci.lower, ci.upper), (6.0, 15.0));
        let by_hand = 1.0 - 2.0 * 21700.0 / 1_048_576.0;
        assert!((ci.coverage - by_hand).abs() < 1e-12, "{}", ci.coverage);
    }

    /// The 95th percentile with n = 1000: K ~ Bin(1000, 0.95), mean 950, sd 6.89; the
    /// normal approximation gives ranks ≈ 950 ∓ 1.96·6.89 = 936.5 and 963.5.
    #[test]
    fn order_statistic_p95_near_normal_approximation() {
        let x: Vec<f64> = (1..=1000).map(f64::from).collect();
        let ci = order_statistic_interval(&x, 0.95, 0.95).unwrap();
        assert!((935..=939).contains(&ci.lower_rank), "{ci:?}");
        assert!((962..=966).contains(&ci.upper_rank), "{ci:?}");
        assert!(ci.coverage >= 0.95 && ci.coverage < 0.97, "{ci:?}");
    }

    #[test]
    fn order_statistic_too_few_samples_is_a_reason() {
        let x: Vec<f64> = (1..=20).map(f64::from).collect();
        let err = order_statistic_interval(&x, 0.99, 0.95).unwrap_err();
        assert!(err.contains("too small"), "{err}");
    }

    #[test]
    fn weighted_all_zero_is_none() {
        let mut pos = [0usize; 1];
        assert!(!weighted_positions(&[0, 0, 0], &[0.5], &mut pos));
    }

    proptest! {
        /// With all weights 1 the weighted quantile is definition 1.
        #[test]
        fn unit_weights_give_hf1(n in 1usize..300, p in 0.001f64..0.999) {
            let w = vec![1u8; n];
            let mut pos = [0usize; 1];
            prop_assert!(weighted_positions(&w, &[p], &mut pos));
            prop_assert_eq!(pos[0] + 1, hf1_rank(n, p).unwrap());
        }

        /// Integer weights act as copies: the weighted quantile equals definition 1 on the
        /// sample with each value repeated by its weight.
        #[test]
        fn integer_weights_are_copies(w in proptest::collection::vec(0u8..4, 1..100), p in 0.01f64..0.99) {
            let values: Vec<f64> = (0..w.len()).map(|i| i as f64).collect();
            let expanded: Vec<f64> = values.iter().zip(&w).flat_map(|(&v, &k)| std::iter::repeat_n(v, k as usize)).collect();
            let mut pos = [0usize; 1];
            let ok = weighted_positions(&w, &[p], &mut pos);
            prop_assert_eq!(ok, !expanded.is_empty());
            if ok {
                prop_assert_eq!(Some(values[pos[0]]), quantile_sorted(&expanded, p));
            }
        }
    }
}
