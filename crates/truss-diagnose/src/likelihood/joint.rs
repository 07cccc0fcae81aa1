//! Several effects fitted as one: the joint re-fit of a model's effects.
//!
//! The model's effects are one candidate of k = Σ kₑ parameters ([`Combined`]), maximised
//! together by the same trust-region Newton method as a single candidate
//! ([`crate::likelihood::fit`]), from their current values (no scan: each is already near its
//! maximum given the others). Effects interact: a scatter fitted before a mean shift was
//! found has absorbed part of it and gives it back only when both move at once. The joint
//! fit's BIC, −2ℓ̂/c + tr(A⁻¹B)·ln n (`bic`), compares models of different effects.

use crate::candidates::candidate::{Candidate, Trace};
use crate::candidates::parameter::Parameter;
use crate::errors::DiagnoseError;
use crate::likelihood::fit::{Fit, Options, adjustments, maximise};
use crate::likelihood::score::{Evaluator, FittedParameter, Test, projection, score_of};

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

    /// The part parameter `j` belongs to, and its parameters' index range.
    fn part_of(&self, j: usize) -> (&'a dyn Candidate, std::ops::Range<usize>) {
        self.parts
            .iter()
            .zip(self.ranges())
            .find(|(_, r)| r.contains(&j))
            .map(|(c, r)| (*c, r))
            .expect("a parameter of the combination")
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
        edit: &mut crate::comparison::baseline::CaseEdit,
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
    /// The reading of the part parameter `j` belongs to.
    fn reading(&self, j: usize, value: f64, span: [f64; 3]) -> String {
        let (c, r) = self.part_of(j);
        c.reading(j - r.start, value, span)
    }
    /// The first part's (a combination is never compared with a rival).
    fn trace(&self) -> Trace {
        self.parts[0].trace()
    }
    /// Whether any part puts the joints in free play.
    fn free_play(&self) -> bool {
        self.parts.iter().any(|c| c.free_play())
    }
}

/// A joint fit of a model's effects.
#[derive(Debug, Clone)]
pub struct JointFit {
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
/// values, with `ev` (an evaluator of the baseline's case, whose simulation count it adds
/// to); `steps`: the finite-difference steps to start from (internal coordinates, all
/// parameters in order), if known; `level`: the level the joint fit's own test is scored at.
pub(crate) fn joint_fit(
    ev: &Evaluator,
    effects: &[(&dyn Candidate, &[f64])],
    steps: Option<&[f64]>,
    level: f64,
) -> Result<JointFit, DiagnoseError> {
    let combined = Combined::new(effects.iter().map(|e| e.0).collect());
    let params = combined.parameters().to_vec();
    let start: Vec<f64> = params
        .iter()
        .zip(effects.iter().flat_map(|e| e.1.iter()))
        .map(|(p, &v)| p.internal(v).clamp(0.0, 1.0))
        .collect();
    let project = projection(&combined);
    let clusters = ev.measured.clusters();
    let mut objective = |t: &[f64]| {
        let v: Vec<f64> = params.iter().zip(t).map(|(p, &x)| p.value(x)).collect();
        ev.terms_at(&combined, &v)
    };
    let options = Options {
        steps,
        curvature: true,
        clusters: Some(&clusters),
        rough: ev.rough(&combined),
    };
    let fit = maximise(&start, options, &|t| project(t, None), &mut objective)?;
    let n = ev.measured.n();
    let test = Test {
        l0: fit.log_likelihood,
        n,
        inflation: 1.0 + n as f64 / ev.samples as f64,
        level,
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

/// A joint fit's BIC, −2ℓ̂/c + tr(A⁻¹B)·ln n with tr(A⁻¹B) = k·max(1, λ̄), for `n`
/// specimens and `samples` simulated samples (c = 1 + n/N).
pub(crate) fn bic(fit: &JointFit, n: usize, samples: usize) -> f64 {
    let n = n as f64;
    let c = 1.0 + n / samples as f64;
    let k = fit.fit.internal.len() as f64;
    let lambda = adjustments(&fit.fit).map_or(1.0, |(m, _)| m).max(1.0);
    -2.0 * fit.log_likelihood / c + k * lambda * n.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Several effects as one: their parameters in order, cut back by `split`; applying the
    /// combination is applying each in turn; each part projects its own slice (backlash's
    /// spread held to its mean clearance, the temperature field's left alone), a held
    /// parameter indexed within the whole.
    #[test]
    fn combined_effects_apply_in_turn() {
        let baseline = crate::comparison::baseline::Baseline::of_test();
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
        // Backlash after the field: its spread 0.006 above its mean 0.004 is held to the
        // mean, or with the spread held (index 5 of the whole) the mean raised to it.
        let combined = Combined::new(vec![thermal, pick("backlash")]);
        let mut v = [0.001, 0.0, 0.0, 2.0, 0.004, 0.006];
        combined.project(&mut v, None);
        assert_eq!(v, [0.001, 0.0, 0.0, 2.0, 0.004, 0.004]);
        let mut v = [0.001, 0.0, 0.0, 2.0, 0.004, 0.006];
        combined.project(&mut v, Some(5));
        assert_eq!(v, [0.001, 0.0, 0.0, 2.0, 0.006, 0.006]);
    }
}
