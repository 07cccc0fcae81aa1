//! The stepwise half of the selection: after a step adds an effect, every effect of the model
//! is re-fitted jointly, and each effect added in an earlier step is tested for removal given
//! the others (backward elimination).
//!
//! ## Joint re-fit
//!
//! The model's effects are one candidate of k = Σ kₑ parameters ([`Combined`]), maximised
//! together by the same trust-region Newton method as a single candidate ([`crate::fit`]),
//! from their current values (no scan: each is already near its maximum given the others).
//! Effects interact: a scatter fitted before a mean shift was found has absorbed part of it
//! and gives it back only when both move at once.
//!
//! ## Backward elimination
//!
//! For each effect e added in an earlier step (not the one just added, which its own step
//! has just tested given all the others), the model without e is re-fitted jointly, and e
//! is tested as a candidate is, against that reduced model: Λₑ = 2(ℓ̂ − ℓ̂₋ₑ)/(c·λₑ),
//! p = P(χ²_{kₑ} ≥ Λₑ), ΔBICₑ = λₑ·(kₑ ln n − Λₑ), with c = 1 + n/N and λₑ = max(1, the mean
//! over e's parameters of the one-parameter misspecification factor (A⁻¹BA⁻¹)ⱼⱼ/(A⁻¹)ⱼⱼ of
//! the joint fit). The effect least needed (largest ΔBICₑ) is removed when it is not both
//! significant at α/2 and better by ΔBIC ≤ −2 — what it explained, the others explain as
//! well; then the remaining earlier effects are tested again, until every one is needed.
//! Keeping needs p < α/2, entering needed p < α/(2K): removing is the harder of the two, as
//! stepwise selection needs to avoid cycling; a removed effect is not tried again.
//!
//! A removed effect is reported as indistinguishable from the effect that took over what
//! it explained: the one whose parameters move furthest, on their plausible ranges (the unit
//! cube of [`crate::candidates::Parameter::internal`]), when it is removed (a uniform
//! temperature change takes over a length bias of every member by moving its `offset`),
//! with the measurement that would separate the two ([`separating_measurement`]).
//!
//! ## Swap
//!
//! Forward selection can add first an effect that mimics two true ones at once (a longeron
//! length bias standing in for a diagonal pretension and part of a larger scatter), and
//! once the second true effect is in, the first true one may fit no better than the
//! stand-in given the others, so neither elimination nor a later step corrects it. So, once
//! no earlier effect can be removed, each earlier effect e is tried replaced by each
//! remaining candidate r that competed with it when e was named (r significant then, and
//! explaining at least half as much: ΔBIC_r ≤ ½·ΔBIC_e; a pruning of the search, to spare
//! joint fits of candidates that explained something else), the new model fitted jointly
//! from the current values and r's fit of that step. The best swap is made when the new
//! model's BIC, −2ℓ̂/c + tr(A⁻¹B)·ln n (tr(A⁻¹B) ≥ k the joint fit's effective number of
//! parameters), is lower by at least 2: r explains jointly what e explained, better. A
//! swap keeps the number of effects. At most one swap per step.
//!
//! ## The false discovery rate
//!
//! ForwardStop ([`crate::diagnose::forward_stop`]) runs on the adjusted p-values of the
//! steps in the order they named effects, whatever was removed later: the number of steps
//! it keeps is decided as without removals, and the final model is that after the last kept
//! step, with the removals of the kept steps. Removal only takes effects out of the model,
//! so the effects finally named are a subset of those ForwardStop accepts: the number of
//! false discoveries among them is never larger, and the probability of any false discovery
//! is at most that of forward selection alone.

use crate::candidates::{Candidate, Parameter};
use crate::errors::DiagnoseError;
use crate::fit::{Fit, Options, adjustments, maximise};
use crate::score::{FittedParameter, Test, projection, score_of};
use crate::step::Context;
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Several effects as one candidate: their parameters one after the other, applied in turn.
pub struct Combined<'a> {
    parts: Vec<&'a dyn Candidate>,
    parameters: Vec<Parameter>,
}

impl<'a> Combined<'a> {
    /// The effects `parts`, applied in this order.
    pub fn new(parts: Vec<&'a dyn Candidate>) -> Self {
        let parameters = parts
            .iter()
            .flat_map(|c| c.parameters().iter().cloned())
            .collect();
        Self { parts, parameters }
    }

    /// The index range of each part's parameters.
    fn ranges(&self) -> Vec<std::ops::Range<usize>> {
        let mut start = 0;
        self.parts
            .iter()
            .map(|c| {
                let k = c.parameters().len();
                start += k;
                start - k..start
            })
            .collect()
    }

    /// `values` cut into each part's.
    pub fn split<T: Clone>(&self, values: &[T]) -> Vec<Vec<T>> {
        self.ranges()
            .into_iter()
            .map(|r| values[r].to_vec())
            .collect()
    }
}

impl Candidate for Combined<'_> {
    fn name(&self) -> &'static str {
        "the model's effects"
    }
    fn mechanism(&self) -> &'static str {
        "every effect of the model, fitted jointly"
    }
    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }
    fn apply(
        &self,
        values: &[f64],
        edit: &mut crate::baseline::CaseEdit,
    ) -> Result<(), DiagnoseError> {
        for (c, r) in self.parts.iter().zip(self.ranges()) {
            c.apply(&values[r], edit)?;
        }
        Ok(())
    }
    fn project(&self, values: &mut [f64], fixed: Option<usize>) {
        for (c, r) in self.parts.iter().zip(self.ranges()) {
            let inner = fixed.filter(|f| r.contains(f)).map(|f| f - r.start);
            c.project(&mut values[r], inner);
        }
    }
}

/// A joint fit of a model's effects.
pub(crate) struct JointFit {
    /// Each effect's values, in the order given.
    pub values: Vec<Vec<f64>>,
    /// Each effect's fitted parameters with their 95 % Wald intervals (the joint sandwich).
    pub parameters: Vec<Vec<FittedParameter>>,
    /// ℓ̂.
    pub log_likelihood: f64,
    /// The optimiser's result (internal coordinates, A, B, steps).
    pub fit: Fit,
}

/// Fits `effects` (each a candidate and its current values) jointly, from their current
/// values; `steps`: the finite-difference steps to start from (internal coordinates, all
/// parameters in order), if known.
pub(crate) fn joint_fit(
    ctx: &Context,
    effects: &[(&dyn Candidate, &[f64])],
    steps: Option<&[f64]>,
) -> Result<JointFit, DiagnoseError> {
    let combined = Combined::new(effects.iter().map(|e| e.0).collect());
    let params = combined.parameters().to_vec();
    let start: Vec<f64> = params
        .iter()
        .zip(effects.iter().flat_map(|e| e.1.iter()))
        .map(|(p, &v)| p.internal(v).clamp(0.0, 1.0))
        .collect();
    let ev = ctx.evaluator(&ctx.baseline.derived_case());
    let project = projection(&combined);
    let clusters = ctx.measured.clusters();
    let mut objective = |t: &[f64]| {
        let v: Vec<f64> = params.iter().zip(t).map(|(p, &x)| p.value(x)).collect();
        ev.terms_at(&combined, &v)
    };
    let options = Options {
        steps,
        curvature: true,
        clusters: Some(&clusters),
    };
    let fit = maximise(&start, options, &|t| project(t, None), &mut objective);
    ctx.simulations
        .set(ctx.simulations.get() + ev.simulations.get());
    let fit = fit?;
    let n = ctx.measured.n();
    let test = Test {
        l0: fit.log_likelihood,
        n,
        inflation: 1.0 + n as f64 / ctx.samples as f64,
        level: ctx.settings.candidate_level(),
    };
    let score = score_of(&combined, &fit, &test);
    let values: Vec<f64> = score.parameters.iter().map(|p| p.value).collect();
    Ok(JointFit {
        values: combined.split(&values),
        parameters: combined.split(&score.parameters),
        log_likelihood: fit.log_likelihood,
        fit,
    })
}

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

/// A joint fit's BIC, −2ℓ̂/c + tr(A⁻¹B)·ln n with tr(A⁻¹B) = k·max(1, λ̄) (module doc).
pub(crate) fn bic(ctx: &Context, fit: &JointFit) -> f64 {
    let n = ctx.measured.n() as f64;
    let c = 1.0 + n / ctx.samples as f64;
    let k = fit.fit.internal.len() as f64;
    let lambda = adjustments(&fit.fit).map_or(1.0, |(m, _)| m).max(1.0);
    -2.0 * fit.log_likelihood / c + k * lambda * n.ln()
}

/// The test of one earlier effect given the others: Λₑ, p, ΔBICₑ.
pub(crate) fn removal_test(
    ctx: &Context,
    full: &JointFit,
    reduced: &JointFit,
    (index, k): (usize, usize),
) -> (f64, f64, f64) {
    let n = ctx.measured.n() as f64;
    let c = 1.0 + n / ctx.samples as f64;
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

/// The measurement that tells effect `a` from effect `b` when node positions cannot.
pub fn separating_measurement(a: &str, b: &str) -> &'static str {
    let pair = |x: &str, y: &str| (a == x && b == y) || (a == y && b == x);
    if pair("length_bias", "thermal_gradient") {
        "the truss's temperature during the measurements (a uniform temperature change lengthens every member as a length bias does), or the member lengths measured one by one at a known temperature (`--measured-members`)"
    } else if pair("length_bias", "diagonal_pretension")
        || pair("backlash", "length_bias")
        || pair("backlash", "diagonal_pretension")
    {
        "the member lengths measured one by one, longerons and diagonals to a few µm (`--measured-members`)"
    } else if pair("diagonal_pretension", "thermal_gradient") {
        "the diagonals' lengths measured one by one (`--measured-members`), or the truss's temperature"
    } else if a == "gravity" || b == "gravity" {
        "a test in another orientation (self-weight turns with it; the other effect does not)"
    } else if a == "length_sigma" || b == "length_sigma" {
        "the member lengths measured one by one (`--measured-members`): their scatter is measured directly"
    } else {
        "a measurement that only one of them affects (member lengths for length effects, temperatures for a thermal field, a test in another orientation for self-weight)"
    }
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

    /// Several effects as one: their parameters in order, cut back by `split`; applying the
    /// combination is applying each in turn; each part projects its own slice (gravity's
    /// |g| ≤ 1 on its three, the temperature field's left alone), a held parameter indexed
    /// within the whole.
    #[test]
    fn combined_effects_apply_in_turn() {
        let job = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../jobs/diagnose-baseline.json");
        let baseline = crate::baseline::Baseline::read(&job, "as-built").unwrap();
        let (candidates, _) = crate::candidates::library(&baseline);
        let pick = |n: &str| {
            candidates
                .iter()
                .find(|c| c.name() == n)
                .map(|c| c.as_ref())
                .unwrap()
        };
        let (gravity, thermal) = (pick("gravity"), pick("thermal_gradient"));
        let combined = Combined::new(vec![gravity, thermal]);
        assert_eq!(combined.parameters().len(), 3 + 4);
        assert_eq!(combined.parameters()[3].name, "gradient_x");
        let values = [0.0, 0.6, 0.8, 0.001, 0.0, 0.0, 2.0];
        let parts = combined.split(&values);
        assert_eq!(parts, vec![vec![0.0, 0.6, 0.8], vec![0.001, 0.0, 0.0, 2.0]]);
        let mut one = baseline.derived_case();
        combined.apply(&values, &mut one).unwrap();
        let mut each = baseline.derived_case();
        gravity.apply(&parts[0], &mut each).unwrap();
        thermal.apply(&parts[1], &mut each).unwrap();
        assert_eq!(one, each);
        assert_ne!(one, baseline.derived_case());
        // |g|² = 0.36 + 2.56 with g_y held at 0.6: g_z scaled to √(1 − 0.36) = 0.8.
        let mut v = [0.0, 0.6, 1.6, 0.001, 0.0, 0.0, 2.0];
        combined.project(&mut v, Some(1));
        assert_eq!(v[1], 0.6, "held");
        assert!((v[2] - 0.8).abs() < 1e-12, "{v:?}");
        assert_eq!(v[3..], values[3..]);
    }

    /// The pairs the crate doc names get their own measurement, either way round.
    #[test]
    fn each_confusable_pair_names_its_measurement() {
        let m = separating_measurement("thermal_gradient", "length_bias");
        assert!(m.contains("temperature"), "{m}");
        assert_eq!(m, separating_measurement("length_bias", "thermal_gradient"));
        assert!(
            separating_measurement("diagonal_pretension", "length_bias")
                .contains("--measured-members")
        );
        assert!(separating_measurement("backlash", "length_bias").contains("--measured-members"));
    }
}
