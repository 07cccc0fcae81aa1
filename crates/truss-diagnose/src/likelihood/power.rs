//! The power of a candidate's likelihood-ratio test, and the smallest effect it detects
//! (the detection limit of a candidate the diagnosis did not name).
//!
//! ## The test under a local alternative
//!
//! A candidate's test compares Λ = 2(ℓ̂ − ℓ₀)/(c·λ̄) with q = χ²_k's (1 − α_K) quantile
//! (α_K its Bonferroni-adjusted level, c = 1 + n/N, λ̄ the misspecification adjustment;
//! [`crate::likelihood::score`]). With the candidate's parameters at t = t₀ + δ (internal
//! coordinates, [`crate::candidates::parameter::Parameter::internal`]), the score at t₀ is
//! about N(Aδ, c·B) and 2(ℓ̂ − ℓ₀) ≈ sᵀA⁻¹s, so that, with A⁻¹B ≈ λ̄·I,
//!
//! ```text
//! Λ ~ χ²_k(λ),   λ = δᵀAδ / (c·λ̄) = n·δᵀIδ / (c·λ̄)
//! ```
//!
//! non-central χ² with k degrees of freedom, A = −∂²ℓ/∂t² the observed information of the
//! n specimens (I = A/n per specimen). Its power is P(χ²_k(λ) > q) ([`power`]); the
//! non-centrality λ₈₀ at which it is 80 % ([`noncentrality_for_power`]) gives the smallest
//! detected shift along a direction d: δ = √(λ₈₀·c·λ̄ / dᵀAd).
//!
//! ## Directions
//!
//! A candidate's parameters have different units (a temperature field's K/mm and K), so
//! each is taken one at a time (d = eⱼ, the others at their null), its limit in its own
//! unit; the candidate's *most visible* parameter is the one whose limit is the smallest
//! share of its plausible range (the internal coordinates: every range mapped onto
//! [0, 1], so the plausible range is each parameter's natural scale).
//!
//! ## One-sided parameters
//!
//! A parameter whose null is an end of its range (a clearance ≥ 0, a diagonal shortening
//! ≤ 0) moves one way only. Its null distribution is the χ̄² mixture ½χ²₀ + ½χ²₁ and the
//! test's χ²_k reference is conservative there; the limit uses the same q the test uses,
//! so "detected" means what the selection's test would say. Under the alternative, a
//! single one-sided parameter's statistic is max(0, Z)², Z ~ N(√λ, 1), whose power
//! Φ(√λ − √q) differs from χ²₁(λ)'s by Φ(−√λ − √q) (below 1e-6 at 80 % power); with
//! several constrained parameters the constrained statistic is never larger than the
//! unconstrained one, so χ²_k(λ) overstates the power and the stated limit is, if
//! anything, too small: an effect below it is still not detected with 80 % power.

//!
//! ## Naming
//!
//! Significance is not all a step asks: it names a candidate only where its BIC is also
//! clearly better, ΔBIC = λ̄·(k·ln n − Λ) ≤ −Δ (Δ = 2, `selection::decide`), i.e.
//! Λ ≥ k·ln n + Δ/λ̄. Where that bound is above q (k ≥ 2, or many specimens), an effect at
//! the detection limit is significant but not named. The *naming limit*
//! ([`DetectionLimit::with_naming`]) is the same computation with q replaced by
//! q_name = max(q, k·ln n + Δ/λ̄): the smallest effect the step would name with 80 % power
//! (as the candidate tested alone; among rivals it must also be the best by BIC).
//! Since δ ∝ √λ, it is the detection limit scaled by √(λ_name/λ₈₀).

use crate::candidates::parameter::Parameter;
use nalgebra::DMatrix;
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use statrs::function::gamma::{gamma_lr, ln_gamma};

/// The power the detection limits are stated at.
pub const POWER: f64 = 0.8;

/// P(χ²_k(λ) ≤ x): the non-central χ² distribution function as the Poisson mixture of
/// central ones, `Σ_j e^(−λ/2)(λ/2)^j/j! · P(k/2 + j, x/2)` (P the regularised lower
/// incomplete gamma function), summed over j from the Poisson's mode outwards until the
/// Poisson weights fall below 1e-17 on either side.
pub fn noncentral_cdf(x: f64, k: usize, lambda: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let half = k as f64 / 2.0;
    if lambda <= 0.0 {
        return gamma_lr(half, x / 2.0);
    }
    let m = lambda / 2.0;
    let weight = |j: usize| (-m + j as f64 * m.ln() - ln_gamma(j as f64 + 1.0)).exp();
    let term = |j: usize| weight(j) * gamma_lr(half + j as f64, x / 2.0);
    let mode = m.floor() as usize;
    let mut sum = term(mode);
    // Upwards from the mode the weights fall faster than geometrically; so do they
    // downwards. Each side stops once its weights drop below 1e-17.
    for j in mode + 1.. {
        let w = weight(j);
        sum += w * gamma_lr(half + j as f64, x / 2.0);
        if w < 1e-17 {
            break;
        }
    }
    for j in (0..mode).rev() {
        let w = weight(j);
        sum += w * gamma_lr(half + j as f64, x / 2.0);
        if w < 1e-17 {
            break;
        }
    }
    sum.clamp(0.0, 1.0)
}

/// The critical value of a k-parameter test at level `level`: χ²_k's (1 − level) quantile.
pub fn critical_value(k: usize, level: f64) -> f64 {
    ChiSquared::new(k as f64)
        .expect("k ≥ 1")
        .inverse_cdf(1.0 - level)
}

/// The power P(χ²_k(λ) > q) of a test with critical value `q`.
pub fn power(q: f64, k: usize, lambda: f64) -> f64 {
    1.0 - noncentral_cdf(q, k, lambda)
}

/// The non-centrality λ at which the test with critical value `q` and `k` degrees of
/// freedom has power `target` (bisection on the power, which grows with λ).
pub fn noncentrality_for_power(q: f64, k: usize, target: f64) -> f64 {
    let f = |l: f64| power(q, k, l);
    let bracket = truss_stats::bisect::bracket_from_zero(f, target);
    truss_stats::bisect::bisect(f, target, bracket)
}

/// The smallest effect of one parameter that a candidate's test detects with 80 % power.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParameterLimit {
    /// The parameter's name.
    pub name: String,
    /// Its unit.
    pub unit: &'static str,
    /// Its value at the limit (its null moved by δ, upwards where the range allows);
    /// `None`: not detectable at any size within the plausible range.
    pub value: Option<f64>,
    /// \|value − null\| in the parameter's unit; `None` as for `value`.
    pub size: Option<f64>,
    /// δ as a share of the plausible range (the internal coordinate's shift).
    pub share_of_range: Option<f64>,
    /// The ways the range lets it move from its null: `"±"`, `"+"` or `"-"`.
    pub direction: &'static str,
    /// The observed information per specimen along it at the fit, Aⱼⱼ/(n·(dv/dt)²)
    /// \[1/unit²\] (dv/dt the map from the internal coordinate at the null).
    pub information_per_specimen: f64,
    /// The naming limit's value and size ([`DetectionLimit::with_naming`]), where computed;
    /// `None` inside the `Some` where not reachable within the plausible range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub naming_value: Option<Option<f64>>,
    /// \|naming_value − null\|.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub naming_size: Option<Option<f64>>,
}

/// The parameter `p` moved from its null by `delta` (internal coordinates), upwards where
/// the range allows, else downwards; `None` where neither fits in the range.
fn shifted(p: &Parameter, delta: Option<f64>) -> Option<f64> {
    let t0 = p.internal(p.null);
    let (up, down) = (t0 < 1.0 - 1e-12, t0 > 1e-12);
    delta.and_then(|d| {
        if up && t0 + d <= 1.0 {
            Some(t0 + d)
        } else if down && t0 - d >= 0.0 {
            Some(t0 - d)
        } else {
            None
        }
    })
}

/// The smallest effects a candidate's test detects with 80 % power, one parameter at a time
/// (module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DetectionLimit {
    /// The power, [`POWER`].
    pub power: f64,
    /// The test's level α_K (Bonferroni-adjusted).
    pub level: f64,
    /// Its critical value q, χ²_k's (1 − α_K) quantile.
    pub critical_value: f64,
    /// λ₈₀: the non-centrality at which P(χ²_k(λ) > q) = 0.8.
    pub noncentrality: f64,
    /// c = 1 + n/N.
    pub inflation: f64,
    /// λ̄, the misspecification adjustment of the test.
    pub adjustment: f64,
    /// Each parameter's limit.
    pub parameters: Vec<ParameterLimit>,
    /// The parameter whose limit is the smallest share of its range, if any is detectable.
    pub most_visible: Option<usize>,
    /// For the naming limit (module doc), where computed: q_name = max(q, k·ln n + Δ/λ̄).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub naming_critical_value: Option<f64>,
    /// λ at which P(χ²_k(λ) > q_name) = 0.8.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub naming_noncentrality: Option<f64>,
}

impl DetectionLimit {
    /// Adds the naming limit (module doc) of a candidate with `parameters` tested on `n`
    /// specimens, where a step names only at ΔBIC ≤ −`delta_bic`: each parameter's limit
    /// scaled by √(λ_name/λ₈₀).
    pub fn with_naming(&mut self, parameters: &[Parameter], n: usize, delta_bic: f64) {
        let k = self.parameters.len();
        if k != parameters.len() || n < 2 {
            return;
        }
        let bic = k as f64 * (n as f64).ln() + delta_bic / self.adjustment;
        let q = self.critical_value.max(bic);
        let lambda = if q > self.critical_value {
            noncentrality_for_power(q, k, POWER)
        } else {
            self.noncentrality
        };
        let scale = (lambda / self.noncentrality).sqrt();
        for (l, p) in self.parameters.iter_mut().zip(parameters) {
            // δ of the detection limit (its share of the range), where found within it.
            let t = shifted(p, l.share_of_range.map(|d| d * scale));
            let value = t.map(|t| p.value(t));
            l.naming_value = Some(value);
            l.naming_size = Some(value.map(|v| (v - p.null).abs()));
        }
        self.naming_critical_value = Some(q);
        self.naming_noncentrality = Some(lambda);
    }
}

/// A candidate not in the final model and the smallest effect of it these data detect.
#[derive(Debug, Clone, Serialize)]
pub struct Unseen {
    /// The candidate's name.
    pub name: String,
    /// The step whose test (against the final model) the limit is of.
    pub step: usize,
    /// Whether that test was significant (the candidate improved the fit, but was not
    /// named or not kept): its limit is then no statement that nothing is there.
    pub significant: bool,
    /// Its p-value there.
    pub p_value: f64,
    /// Specimens n.
    pub specimens: usize,
    /// The limits, one parameter at a time; `None` where the fit failed or had no
    /// curvature.
    pub limit: Option<DetectionLimit>,
}

/// The detection limits of a candidate with `parameters`, from the observed information
/// `curvature` = A = −∂²ℓ/∂t² of `n` specimens (internal coordinates), for its test at
/// `level` with `c` = `inflation` and λ̄ = `adjustment` (module doc):
/// δⱼ = √(λ₈₀·c·λ̄/Aⱼⱼ) in internal coordinates. A parameter with Aⱼⱼ ≤ 0, or whose δⱼ
/// leaves the plausible range in every direction it may move, is not detectable there.
pub fn detection_limit(
    parameters: &[Parameter],
    curvature: &DMatrix<f64>,
    n: usize,
    level: f64,
    inflation: f64,
    adjustment: f64,
) -> Option<DetectionLimit> {
    let k = parameters.len();
    if k == 0 || curvature.nrows() != k || curvature.ncols() != k || n == 0 {
        return None;
    }
    let q = critical_value(k, level);
    let lambda = noncentrality_for_power(q, k, POWER);
    let limits: Vec<ParameterLimit> = parameters
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let t0 = p.internal(p.null);
            let (up, down) = (t0 < 1.0 - 1e-12, t0 > 1e-12);
            let slope = if p.log {
                p.null * (p.high / p.low).ln()
            } else {
                p.high - p.low
            };
            let a = curvature[(j, j)];
            let delta = (a > 0.0 && a.is_finite())
                .then(|| (lambda * inflation * adjustment / a).sqrt())
                .filter(|d| d.is_finite());
            let t = shifted(p, delta);
            let value = t.map(|t| p.value(t));
            ParameterLimit {
                name: p.name.clone(),
                unit: p.unit,
                value,
                size: value.map(|v| (v - p.null).abs()),
                share_of_range: t.and(delta),
                direction: match (up, down) {
                    (true, true) => "±",
                    (true, false) => "+",
                    _ => "-",
                },
                information_per_specimen: a / (n as f64 * slope * slope),
                naming_value: None,
                naming_size: None,
            }
        })
        .collect();
    let most_visible = limits
        .iter()
        .enumerate()
        .filter_map(|(j, l)| l.share_of_range.map(|s| (j, s)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(j, _)| j);
    Some(DetectionLimit {
        power: POWER,
        level,
        critical_value: q,
        noncentrality: lambda,
        inflation,
        adjustment,
        parameters: limits,
        most_visible,
        naming_critical_value: None,
        naming_noncentrality: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use statrs::distribution::Normal;

    /// χ²₁(λ) is the square of N(√λ, 1): P(χ²₁(λ) ≤ x) = Φ(√x − √λ) − Φ(−√x − √λ), a
    /// closed form independent of the series; and λ = 0 is the central χ²_k.
    #[test]
    fn one_degree_of_freedom_matches_the_normal() {
        let phi = |z: f64| Normal::standard().cdf(z);
        for &(x, l) in &[
            (0.5f64, 0.3f64),
            (3.84, 7.85),
            (9.0, 1.0),
            (20.0, 40.0),
            (2.0, 150.0),
        ] {
            let exact = phi(x.sqrt() - l.sqrt()) - phi(-x.sqrt() - l.sqrt());
            let series = noncentral_cdf(x, 1, l);
            assert!(
                (series - exact).abs() < 1e-10,
                "x {x} λ {l}: {series} vs {exact}"
            );
        }
        for k in [1, 2, 5] {
            let c = ChiSquared::new(k as f64).unwrap().cdf(4.2);
            assert!((noncentral_cdf(4.2, k, 0.0) - c).abs() < 1e-14);
            assert!((noncentral_cdf(4.2, k, 1e-12) - c).abs() < 1e-10);
        }
    }

    /// χ²_k(λ) = χ²₁(λ) + χ²_{k−1}: its distribution function is the convolution
    /// ∫ f_{χ²_{k−1}}(y)·P(χ²₁(λ) ≤ x − y) dy, integrated here numerically (Simpson, the
    /// χ²₁ part in its closed form), for k = 3 and 5.
    #[test]
    fn more_degrees_of_freedom_match_the_convolution() {
        let phi = |z: f64| Normal::standard().cdf(z);
        let f1 = |x: f64, l: f64| {
            if x <= 0.0 {
                0.0
            } else {
                phi(x.sqrt() - l.sqrt()) - phi(-x.sqrt() - l.sqrt())
            }
        };
        for &(k, x, l) in &[(3usize, 6.0, 4.0), (5, 15.0, 10.0), (3, 2.0, 0.7)] {
            let d = statrs::distribution::ChiSquared::new((k - 1) as f64).unwrap();
            use statrs::distribution::Continuous;
            let m = 20_000;
            let h = x / m as f64;
            let g = |y: f64| d.pdf(y) * f1(x - y, l);
            let mut s = g(0.0) + g(x);
            for i in 1..m {
                s += g(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            let reference = s * h / 3.0;
            let series = noncentral_cdf(x, k, l);
            assert!(
                (series - reference).abs() < 1e-6,
                "k {k} x {x} λ {l}: {series} vs {reference}"
            );
        }
    }

    /// Cohen's (1988, table 9.4.2) non-centralities for 80 % power at α = 0.05: 7.85 for
    /// one degree of freedom ((1.96 + 0.8416)² = 7.849 by hand), 9.64 for two, 10.90 for
    /// three, 11.94 for four.
    #[test]
    fn eighty_percent_power_matches_cohens_table() {
        for (k, table) in [(1, 7.85), (2, 9.64), (3, 10.90), (4, 11.94)] {
            let l = noncentrality_for_power(critical_value(k, 0.05), k, POWER);
            assert!((l - table).abs() < 0.01, "k {k}: {l} vs {table}");
        }
        let by_hand = (1.959_964f64 + 0.841_621).powi(2);
        let l = noncentrality_for_power(critical_value(1, 0.05), 1, POWER);
        assert!((l - by_hand).abs() < 1e-4, "{l} vs {by_hand}");
    }

    /// The limit by hand: one parameter in ±0.1 mm (null 0, internal ½), A = 4·10⁴ on the
    /// internal scale from 100 specimens, c = 1.05, λ̄ = 1.2, α = 0.05: alone, λ₈₀ = 7.849,
    /// δ = √(7.849·1.05·1.2/4e4) = 0.01572, i.e. 3.14 µm; among four parameters λ₈₀ is χ²₄'s; a clearance (null at its
    /// range's low end) moves up only; a parameter with no curvature, or one whose δ leaves
    /// the range, is not detectable; the most visible is the smallest share of its range.
    #[test]
    fn limits_by_hand() {
        let params = [
            Parameter::linear("bias", "mm", -0.1, 0.1, 0.0),
            Parameter::linear("clearance", "mm", 0.0, 0.05, 0.0),
            Parameter::linear("flat", "K", -20.0, 20.0, 0.0),
            Parameter::linear("weak", "K", -20.0, 20.0, 0.0),
        ];
        let a = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![4e4, 1e4, 0.0, 1.0]));
        let l = detection_limit(&params, &a, 100, 0.05, 1.05, 1.2).unwrap();
        let lambda = noncentrality_for_power(critical_value(4, 0.05), 4, POWER);
        assert!((l.noncentrality - lambda).abs() < 1e-9);
        let d = (lambda * 1.05 * 1.2 / 4e4f64).sqrt();
        let b = &l.parameters[0];
        assert!((b.size.unwrap() - d * 0.2).abs() < 1e-12, "{b:?}");
        assert_eq!(b.direction, "±");
        assert!((b.information_per_specimen - 4e4 / (100.0 * 0.04)).abs() < 1e-9);
        let c = &l.parameters[1];
        assert_eq!(c.direction, "+");
        assert!((c.value.unwrap() - 2.0 * d * 0.05).abs() < 1e-12, "{c:?}");
        assert_eq!(l.parameters[2].size, None);
        assert_eq!(l.parameters[3].size, None, "{:?}", l.parameters[3]);
        assert_eq!(l.most_visible, Some(0));
        // One parameter at α = 0.05: Cohen's 7.85, by hand.
        let one = detection_limit(
            &params[..1],
            &DMatrix::from_element(1, 1, 4e4),
            100,
            0.05,
            1.05,
            1.2,
        )
        .unwrap();
        let by_hand = ((1.959_964f64 + 0.841_621).powi(2) * 1.05 * 1.2 / 4e4).sqrt() * 0.2;
        assert!((one.parameters[0].size.unwrap() - by_hand).abs() < 1e-5 * by_hand);
    }

    /// The naming limit by hand: one parameter, n = 100, λ̄ = 1.2: naming needs
    /// Λ ≥ ln 100 + 2/1.2 = 6.272 > q = 3.841, so λ_name solves Φ(√λ − √6.272) = 0.8 (the
    /// other tail is below 1e-8): √λ = 2.5044 + 0.8416, λ = 11.196, and the size is
    /// √(11.196·1.05·1.2/4e4)·0.2 mm. With 3 specimens ln 3 + 2/1.2 = 2.77 < q: naming asks
    /// nothing more. A clearance (one-sided) whose naming shift leaves the
    /// range (its detection shift inside it) is not named at any size within it.
    #[test]
    fn naming_limits_by_hand() {
        let bias = [Parameter::linear("bias", "mm", -0.1, 0.1, 0.0)];
        let a = DMatrix::from_element(1, 1, 4e4);
        let mut l = detection_limit(&bias, &a, 100, 0.05, 1.05, 1.2).unwrap();
        l.with_naming(&bias, 100, 2.0);
        let q = 100f64.ln() + 2.0 / 1.2;
        assert!((l.naming_critical_value.unwrap() - q).abs() < 1e-12);
        let by_hand = (q.sqrt() + 0.841_621).powi(2);
        assert!(
            (l.naming_noncentrality.unwrap() - by_hand).abs() < 1e-4,
            "{l:?}"
        );
        let size = (by_hand * 1.05 * 1.2 / 4e4).sqrt() * 0.2;
        let named = l.parameters[0].naming_size.unwrap().unwrap();
        assert!((named - size).abs() < 1e-5 * size, "{named} vs {size}");
        // √(11.196/7.849) = 1.194 times the detection limit.
        let ratio = named / l.parameters[0].size.unwrap();
        let exact = (l.naming_noncentrality.unwrap() / l.noncentrality).sqrt();
        assert!(
            (ratio - exact).abs() < 1e-9 && ratio > 1.19,
            "{ratio} vs {exact}"
        );
        let mut few = detection_limit(&bias, &a, 3, 0.05, 1.05, 1.2).unwrap();
        few.with_naming(&bias, 3, 2.0);
        assert_eq!(few.naming_critical_value, Some(few.critical_value));
        assert_eq!(few.parameters[0].naming_size, Some(few.parameters[0].size));
        // With A = 12.2 the detection shift √(7.849·1.26/12.2) = 0.900 of the range fits,
        // the naming one 1.194 times that does not.
        let clearance = [Parameter::linear("clearance", "mm", 0.0, 0.05, 0.0)];
        let soft = DMatrix::from_element(1, 1, 12.2);
        let mut c = detection_limit(&clearance, &soft, 100, 0.05, 1.05, 1.2).unwrap();
        c.with_naming(&clearance, 100, 2.0);
        let p = &c.parameters[0];
        assert!(p.size.is_some(), "{p:?}");
        assert_eq!(p.naming_value, Some(None), "{p:?}");
    }
}
