//! Backward elimination's test: an effect added in an earlier step, tested given the
//! others, and which of the others took over what it explained
//! ([`crate::selection::update`] says when it is removed).

use crate::candidates::parameter::Parameter;
use crate::likelihood::fit::adjustments;
use crate::likelihood::joint::JointFit;
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// An effect taken out of the model by backward elimination, or replaced by a swap.
#[derive(Debug, Clone, Serialize)]
pub struct Removal {
    /// The effect removed.
    pub name: String,
    /// The candidate put in its place by a swap (module doc), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replaced_by: Option<String>,
    /// The step that added it.
    pub added_in_step: usize,
    /// Λₑ = 2(ℓ̂ − ℓ̂₋ₑ)/(c·λₑ) of the effect given the others (module doc); for a swap,
    /// 2(ℓ̂_swap − ℓ̂)/c.
    pub lr_statistic: f64,
    /// P(χ²_{kₑ} ≥ Λₑ); for a swap, none.
    pub p_value: Option<f64>,
    /// ΔBICₑ = λₑ·(kₑ ln n − Λₑ): above −2, or p ≥ α/2, and it is removed; for a swap,
    /// the swapped model's BIC less the model's (≤ −2).
    pub delta_bic: f64,
    /// The effect that took over what it explained (its parameters moved furthest), if any.
    pub explained_by: Option<String>,
    /// The measurement that would tell the two apart.
    pub separate_by: String,
}

/// The test of one earlier effect given the others, for `n` specimens and the inflation
/// `c`: Λₑ, p, ΔBICₑ.
pub(crate) fn removal_test(
    (n, c): (usize, f64),
    full: &JointFit,
    reduced: &JointFit,
    (index, k): (usize, usize),
) -> (f64, f64, f64) {
    let n = n as f64;
    let offset: usize = full.values[..index].iter().map(Vec::len).sum();
    let lambda = adjustments(&full.fit)
        .map_or(1.0, |(_, per)| {
            per[offset..offset + k].iter().sum::<f64>() / k as f64
        })
        .max(1.0);
    let lr = (2.0 * (full.log_likelihood - reduced.log_likelihood) / (c * lambda)).max(0.0);
    let p = 1.0 - ChiSquared::new(k as f64).expect("k ≥ 1").cdf(lr);
    (lr, p, lambda * (k as f64 * n.ln() - lr))
}

/// Of the effects left after removing one, the one whose parameters moved furthest on their
/// ranges between the full fit (`before`, the removed one's entry taken out) and the
/// reduced fit (`after`), with how far (largest change of an internal coordinate); `None`
/// when nothing moved.
pub(crate) fn furthest_moved(
    parameters: &[Vec<Parameter>],
    before: &[Vec<f64>],
    after: &[Vec<f64>],
) -> Option<(usize, f64)> {
    (0..after.len())
        .map(|e| {
            let moved = parameters[e]
                .iter()
                .zip(before[e].iter().zip(&after[e]))
                .map(|(p, (&a, &b))| (p.internal(a) - p.internal(b)).abs())
                .fold(0.0, f64::max);
            (e, moved)
        })
        .filter(|&(_, m)| m > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parameter(low: f64, high: f64) -> Parameter {
        Parameter {
            name: "p".into(),
            unit: "mm",
            low,
            high,
            null: 0.0,
            log: false,
        }
    }

    /// The effect that moved furthest on its own range is the one that took over: a move of
    /// 2 in a range of 40 (0.05) beats a move of 0.001 in a range of 0.2 (0.005); nothing
    /// moved, nothing took over.
    #[test]
    fn the_furthest_moved_took_over() {
        let params = vec![
            vec![parameter(-0.1, 0.1)],
            vec![parameter(-20.0, 20.0), parameter(-0.01, 0.01)],
        ];
        let before = vec![vec![0.0], vec![-0.1, 0.002]];
        let after = vec![vec![0.001], vec![1.9, 0.002]];
        let (e, moved) = furthest_moved(&params, &before, &after).unwrap();
        assert_eq!(e, 1);
        assert!((moved - 0.05).abs() < 1e-12, "{moved}");
        assert_eq!(furthest_moved(&params, &before, &before), None);
    }
}
