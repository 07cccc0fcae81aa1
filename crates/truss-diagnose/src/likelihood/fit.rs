//! Maximising a candidate's likelihood over its parameters, and Wald intervals.
//!
//! ## Method
//!
//! The parameters are mapped onto the unit cube ([`Parameter::internal`]: linear, or
//! logarithmic for a scale), where the log-likelihood is smooth because every evaluation uses
//! the same random numbers. From the best of the null point (the baseline) and a scan along
//! each axis ([`crate::likelihood::score::SCAN`]; an axis the null holds scanned again from
//! the best point of the others), a trust-region Newton method: gradient and Hessian by finite
//! differences with steps adapted to the likelihood's scale ([`crate::likelihood::derivatives`]), the step
//! `s = (A + μI)⁻¹g` with `A = −H` and the smallest `μ ≥ 0` that makes `A + μI` positive
//! definite and `|s|` at most the trust radius (0.3 at first, doubled after a good step,
//! quartered after a failed one), clipped to the cube (and projected where the box is not the
//! whole constraint). It stops when the quadratic model promises, or a step gains, less than
//! [`TOLERANCE`] in ℓ, when the radius falls below 1e-4, or after [`MAX_ITERATIONS`].
//!
//! The full Hessian costs `k(k−1)/2` mixed differences on top of the `1 + 2k` evaluations of
//! the central stencil, which give the gradient and the diagonal. So after a successful step
//! only the central stencil is evaluated ([`derivatives_along_axes`]) and the mixed entries
//! are updated from the change of gradient across the step (symmetric rank one, `sr1_mixed`).
//! The full Hessian is measured again where the updated model fails (a step that loses ℓ)
//! and, when `A` is wanted, where the updated model promises no progress (only the measured
//! model decides that maximum) and at the maximum: for such fits the stopping rule and `A`
//! are those of the measured model. An inner maximisation of a profile, which wants only ℓ,
//! may stop on the updated model.
//!
//! ## A rough likelihood
//!
//! The steps make each central second difference about one unit of ℓ. Where ℓ is rough
//! on that scale, the mixed differences are not the curvature but the roughness over
//! `hᵢhⱼ`: with pin joints in free play and solved at the cables' limit, each sample's
//! contact state changes at its own value of a clearance or a diagonal pretension, and ℓ
//! has a kink for each. On the three-effect benchmark's data (`scripts/bench-diagnose.sh`:
//! backlash, the diagonals' scatter and a pretension fitted jointly, 200 specimens) the
//! mixed entries of the pretension's row read as correlations of 0.72, 1.17, 0.75 and 2.06
//! at those steps (no positive definite matrix has one above 1), and 0.05 to 0.24 at steps
//! twice and three times as long, which agree. So where `A` at the maximum is not positive
//! definite *and* a mixed entry exceeds what its two diagonal entries allow any curvature
//! (`A_ij² > A_ii·A_jj`: a 2 × 2 principal minor below zero, which only the noise of the
//! mixed differences makes), it is measured again with every step [`LONGER_STEPS`] times
//! as long, without adapting them, and the first positive definite one is kept (else the
//! first: the Wald intervals are then not found). An `A` that is merely indefinite, every
//! pair consistent, is what a flat ridge measures (two effects explaining the same signal,
//! a temperature offset and a batten length bias: eigenvalues −0.7 and −0.03 against 9e6,
//! the largest correlation 0.97), and it is kept: the confounding tests read such a
//! ridge from it ([`crate::selection::confound`]). A fit whose `A` is positive definite
//! at the likelihood's own scale is untouched.
//!
//! That rule catches only the roughness that makes `A` inconsistent. Where the model has
//! joints in free play ([`Options::rough`]: the current model has clearances, or the fitted
//! effect gives it some), the roughness is everywhere, and a positive definite `A` measured
//! at the likelihood's own scale is as much its kinks as its curvature. On the three-effect
//! benchmark's data the final joint fit (backlash, the scatter of each member group, a
//! pretension) ended three times at the same maximum (every value within 0.8 %, ℓ̂ within
//! 0.1) by three optimiser paths, and its Wald intervals' widths differed by factors of 0.3
//! to 5 (the battens' scatter 3.7, 4.3 and 18.5 µm wide). Measured again at those three
//! points, each with steps adapted from a different start (0.02, 0.004, 0.0005), `A` was
//! not positive definite at two of them; at four standard errors along each axis the widths
//! agreed within 8 % (the clearance's 0.200, 0.201 and 0.204 µm, the battens' scatter 1.82,
//! 1.78 and 1.85 µm). So in a rough fit the model that decides the maximum (each full
//! measurement of the quasi-Newton scheme above) and `A` there are measured at
//! [`SMOOTHING`] = 4 standard errors along each axis, `4/√(−Hᵢᵢ)` from the latest model
//! (`smoothing_steps`): second differences of about 16 units of ℓ, against which the
//! kinks of single samples average out, taken over ±4 standard errors (twice the 95 %
//! interval's half-width: the secant curvature on the interval's own scale). Not simply
//! four times the adapted steps: those lie anywhere within a factor 4 of one standard error
//! (their second differences within a factor 16 of one unit), and so would the widths. The
//! search between them keeps the adapted steps, and the steps a fit reports (and later
//! fits start from) are the adapted ones. A fit without free play runs exactly as before.
//!
//! ## Wald intervals
//!
//! ℓ is a sum of per-unit terms ℓ_u (one per specimen, one per member observation). With
//! `A = −∂²ℓ/∂t²` at the optimum and `B = Σ_u (g_u − ḡ)(g_u − ḡ)ᵀ` the variability of the
//! per-unit scores `g_u = ∂ℓ_u/∂t`, the covariance of the internal coordinates is the
//! sandwich `c·A⁻¹BA⁻¹` (Huber 1967; White 1982), valid when the Gaussian approximation is
//! not the true distribution of a specimen, with `c = 1 + n/N` for the simulation's own noise
//! in μ and Σ (it adds to the data's in proportion to the sample sizes). The 95 % Wald
//! interval of each is `t̂ ± 1.96·√covᵢᵢ` mapped back to the parameter (so a scale's interval
//! is symmetric in its logarithm). Where `A` is not positive definite the interval is
//! undetermined. These rest on ℓ being quadratic over the interval; the diagnosis reports
//! them next to the profile-likelihood intervals of [`crate::likelihood::profile`], which do not, and
//! uses the latter for the named effect.

use crate::candidates::parameter::Parameter;
use crate::errors::DiagnoseError;
use crate::likelihood::derivatives::{
    Derivatives, INITIAL_STEP, Objective, Terms, derivatives, derivatives_along_axes,
    derivatives_at_steps, total,
};
use nalgebra::{DMatrix, DVector};

/// Smallest gain in ℓ that counts as progress.
pub const TOLERANCE: f64 = 0.02;
/// Most Newton iterations.
pub const MAX_ITERATIONS: usize = 12;
/// The factors by which the steps grow where the curvature at the maximum, measured at the
/// likelihood's own standard error, is not positive definite and a pair of its entries is
/// inconsistent (module doc).
pub const LONGER_STEPS: [f64; 2] = [2.0, 4.0];
/// Where ℓ is rough ([`Options::rough`]), the steps of the model that decides the maximum,
/// and of `A` there, in standard errors of each parameter (module doc).
pub const SMOOTHING: f64 = 4.0;

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The maximum in internal coordinates.
    pub internal: Vec<f64>,
    /// ℓ there.
    pub log_likelihood: f64,
    /// A = −∂²ℓ/∂t² there (internal coordinates); empty (0 × 0) when not asked for.
    pub curvature: DMatrix<f64>,
    /// B, the variability of the per-unit scores there ([`crate::likelihood::derivatives`]); empty when
    /// not asked for.
    pub variability: DMatrix<f64>,
    /// The finite-difference steps last used, per parameter (internal coordinates).
    pub steps: Vec<f64>,
    /// Evaluations of ℓ.
    pub evaluations: usize,
    /// Newton iterations.
    pub iterations: usize,
}

/// How to maximise.
#[derive(Debug, Clone, Copy)]
pub struct Options<'a> {
    /// Initial finite-difference steps; `None`: [`INITIAL_STEP`] on every axis.
    pub steps: Option<&'a [f64]>,
    /// Whether `A` and `B` are wanted at the maximum (an inner maximisation of a profile
    /// needs only ℓ).
    pub curvature: bool,
    /// The cluster of each unit term of ℓ for `B` ([`crate::likelihood::derivatives`]); `None`: every
    /// unit its own.
    pub clusters: Option<&'a [usize]>,
    /// ℓ is rough on the scale of its standard error (joints in free play,
    /// [`crate::candidates::candidate::Candidate::free_play`]): the model that decides the
    /// maximum, and `A` there, are measured at [`SMOOTHING`] standard errors along each
    /// axis (module doc).
    pub rough: bool,
}

impl Default for Options<'_> {
    fn default() -> Self {
        Self {
            steps: None,
            curvature: true,
            clusters: None,
            rough: false,
        }
    }
}

/// A 95 % interval, or why there is none.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Interval {
    /// Lower end, if determined.
    pub lower: Option<f64>,
    /// Upper end, if determined.
    pub upper: Option<f64>,
    /// Whether the lower end is the plausible range's (the interval is cut there).
    pub lower_at_range_end: bool,
    /// Whether the upper end is the plausible range's.
    pub upper_at_range_end: bool,
    /// `profile` ([`crate::likelihood::profile`]) or `wald` (this module).
    pub method: &'static str,
    /// For a profile interval, the threshold `q` of `2(ℓ̂ − ℓ_p) ≤ q`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
}

impl Interval {
    /// An interval whose ends could not be found.
    pub fn undetermined(method: &'static str) -> Self {
        Self {
            lower: None,
            upper: None,
            lower_at_range_end: false,
            upper_at_range_end: false,
            method,
            threshold: None,
        }
    }

    /// Whether an end is cut at the plausible range.
    pub fn at_range_end(&self) -> bool {
        self.lower_at_range_end || self.upper_at_range_end
    }
}

/// The step `(A + μI)⁻¹g` within `radius` (module doc).
fn trust_step(g: &DVector<f64>, a: &DMatrix<f64>, radius: f64) -> DVector<f64> {
    let k = g.len();
    let eig = nalgebra::SymmetricEigen::new(a.clone());
    let lmin = eig
        .eigenvalues
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let scale = eig
        .eigenvalues
        .iter()
        .map(|v| v.abs())
        .fold(1e-12, f64::max);
    let solve = |mu: f64| -> DVector<f64> {
        let qg = eig.eigenvectors.transpose() * g;
        let mut y = DVector::zeros(k);
        for i in 0..k {
            y[i] = qg[i] / (eig.eigenvalues[i] + mu);
        }
        &eig.eigenvectors * y
    };
    let mut mu = if lmin > 1e-9 * scale {
        0.0
    } else {
        -lmin + 1e-6 * scale
    };
    let mut s = solve(mu);
    if s.norm() <= radius {
        return s;
    }
    // Bisection on μ for |s| = radius.
    let (mut lo, mut hi) = (mu, mu.max(1e-12) + g.norm() / radius + scale);
    for _ in 0..100 {
        mu = 0.5 * (lo + hi);
        s = solve(mu);
        if s.norm() > radius {
            lo = mu;
        } else {
            hi = mu;
        }
        if hi - lo < 1e-12 * hi {
            break;
        }
    }
    solve(hi)
}

/// The trust step restricted to the subspace orthogonal to the orthonormal `blocked`.
fn restricted_step(
    g: &DVector<f64>,
    a: &DMatrix<f64>,
    radius: f64,
    blocked: &[DVector<f64>],
) -> DVector<f64> {
    let k = g.len();
    if blocked.is_empty() {
        return trust_step(g, a, radius);
    }
    let mut p = DMatrix::identity(k, k);
    for b in blocked {
        p -= b * b.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(p);
    let basis: Vec<DVector<f64>> = (0..k)
        .filter(|&i| eig.eigenvalues[i] > 0.5)
        .map(|i| eig.eigenvectors.column(i).into_owned())
        .collect();
    if basis.is_empty() {
        return DVector::zeros(k);
    }
    let z = DMatrix::from_columns(&basis);
    let zt = z.transpose();
    let s = trust_step(&(&zt * g), &(&zt * a * &z), radius);
    z * s
}

/// The trust step from `t`, restricted away from the constraints active at `t` that it
/// pushes against, and the next point: `t` plus the step, clipped to the cube and projected
/// (module doc).
fn constrained_step(
    t: &[f64],
    g: &DVector<f64>,
    a: &DMatrix<f64>,
    radius: f64,
    project: &dyn Fn(&mut [f64]),
) -> (DVector<f64>, Vec<f64>) {
    let k = t.len();
    let onto = |s: &DVector<f64>| -> Vec<f64> {
        let mut p: Vec<f64> = t
            .iter()
            .zip(s.iter())
            .map(|(x, d)| (x + d).clamp(0.0, 1.0))
            .collect();
        project(&mut p);
        p
    };
    let mut blocked: Vec<DVector<f64>> = Vec::new();
    loop {
        let s = restricted_step(g, a, radius, &blocked);
        let norm = s.norm();
        if blocked.len() + 1 >= k || norm == 0.0 {
            return (s.clone(), onto(&s));
        }
        // Is a constraint active at t against this step? Move 1e-6 along it and see what
        // the projection takes away.
        let eps = 1e-6;
        let small = &s * (eps / norm);
        let moved = onto(&small);
        let mut n = DVector::from_iterator(k, (0..k).map(|i| t[i] + small[i] - moved[i]));
        if n.norm() <= 1e-3 * eps {
            return (s.clone(), onto(&s));
        }
        for b in &blocked {
            n -= b * b.dot(&n);
        }
        if n.norm() <= 1e-6 * eps {
            return (s.clone(), onto(&s));
        }
        blocked.push(n.normalize());
    }
}

/// The symmetric rank-one (SR1) update of the Hessian `h` for the step `s` and the change
/// of gradient `y` across it (Nocedal & Wright, *Numerical Optimization*, 2nd ed., eq. 6.24:
/// `h + r rᵀ/(rᵀs)`, `r = y − h s`, skipped where `|rᵀs| < 1e-8·|s|·|r|`), keeping `h`'s
/// diagonal, which the central differences measure.
fn sr1_mixed(h: &DMatrix<f64>, s: &DVector<f64>, y: &DVector<f64>) -> DMatrix<f64> {
    let r = y - h * s;
    let denom = r.dot(s);
    if denom.abs() < 1e-8 * s.norm() * r.norm() || denom == 0.0 {
        return h.clone();
    }
    let mut next = h + &r * r.transpose() / denom;
    for i in 0..h.nrows() {
        next[(i, i)] = h[(i, i)];
    }
    next
}

/// The steps of a rough fit's deciding model ([`Options::rough`]): [`SMOOTHING`] standard
/// errors along each axis, `SMOOTHING/√(−Hᵢᵢ)` from the latest model's `h` (the second
/// differences of the adapted steps lie anywhere within a factor 16 of one unit of ℓ, so
/// their steps would set the scale only within a factor 4), or `SMOOTHING` times the adapted
/// step where `h` has no curvature along the axis.
fn smoothing_steps(steps: &[f64], h: &DMatrix<f64>) -> Vec<f64> {
    steps
        .iter()
        .enumerate()
        .map(|(i, &step)| {
            let a = -h[(i, i)];
            if a > 0.0 && a.is_finite() {
                SMOOTHING / a.sqrt()
            } else {
                SMOOTHING * step
            }
        })
        .collect()
}

/// Whether a mixed entry of `a` is larger than its two diagonal entries allow any curvature
/// (`a_ij² > a_ii·a_jj`, both positive): a 2 × 2 principal minor that is negative, which
/// only noise in the mixed differences makes (module doc).
fn pairwise_inconsistent(a: &DMatrix<f64>) -> bool {
    let k = a.nrows();
    (0..k).any(|i| {
        (0..i).any(|j| {
            a[(i, i)] > 0.0 && a[(j, j)] > 0.0 && a[(i, j)] * a[(i, j)] > a[(i, i)] * a[(j, j)]
        })
    })
}

/// `A = −H` and `B` at the maximum `t` from the derivatives `d` measured there; where that
/// `A` is not positive definite and a pair of its entries is inconsistent
/// ([`pairwise_inconsistent`]), measured again at steps [`LONGER_STEPS`] times longer, the
/// first positive definite one kept (module doc), else `d`'s. `measured_at`: the steps `d`
/// was measured at where they are not `d.steps` (a rough fit's, [`smoothing_steps`]).
fn curvature_at_maximum(
    t: &[f64],
    terms: &Terms,
    d: Derivatives,
    measured_at: Option<&[f64]>,
    clusters: Option<&[usize]>,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DiagnoseError> {
    let a = -&d.hessian;
    if nalgebra::Cholesky::new(a.clone()).is_some() || !pairwise_inconsistent(&a) {
        return Ok((a, d.variability));
    }
    for factor in LONGER_STEPS {
        let longer: Vec<f64> = measured_at
            .unwrap_or(&d.steps)
            .iter()
            .map(|h| h * factor)
            .collect();
        let again = derivatives_at_steps(t, terms, &longer, clusters, f, evaluations)?;
        let a_again = -&again.hessian;
        if nalgebra::Cholesky::new(a_again.clone()).is_some() {
            return Ok((a_again, again.variability));
        }
    }
    Ok((a, d.variability))
}

/// Maximises `f` (ℓ as a function of internal coordinates) over the unit cube from `start`;
/// `project` maps internal coordinates onto the feasible set.
pub fn maximise(
    start: &[f64],
    options: Options,
    project: &dyn Fn(&mut [f64]),
    f: &mut Objective,
) -> Result<Fit, DiagnoseError> {
    let k = start.len();
    let mut t = start.to_vec();
    let mut evaluations = 1;
    let mut terms = f(&t)?;
    let mut f0 = total(&terms);
    let mut steps = options
        .steps
        .map_or_else(|| vec![INITIAL_STEP; k], <[f64]>::to_vec);
    let mut radius = 0.3;
    let mut iterations = 0;
    // The model that decides the maximum: all finite differences, at `SMOOTHING` standard
    // errors where ℓ is rough (its steps are reported as the adapted ones); `measured_at`:
    // the steps a rough fit's was last measured at.
    let mut measured_at: Vec<f64> = Vec::new();
    let mut measure = |t: &[f64],
                       terms: &Terms,
                       steps: &[f64],
                       h: &DMatrix<f64>,
                       f: &mut Objective,
                       evaluations: &mut usize|
     -> Result<Derivatives, DiagnoseError> {
        if !options.rough {
            return derivatives(t, terms, steps, options.clusters, f, evaluations);
        }
        measured_at = smoothing_steps(steps, h);
        let mut d = derivatives_at_steps(t, terms, &measured_at, options.clusters, f, evaluations)?;
        d.steps = steps.to_vec();
        Ok(d)
    };
    let mut d = derivatives(&t, &terms, &steps, options.clusters, f, &mut evaluations)?;
    // `fresh`: `d` is at `t`; `exact`: its Hessian is the deciding model's (all finite
    // differences at its scale), not the quasi-Newton update's nor, where ℓ is rough, the
    // adapted steps' (module doc).
    let (mut fresh, mut exact) = (true, !options.rough);
    // The gradient before the last successful step and that step, for the secant.
    let mut secant: Option<(DVector<f64>, DVector<f64>)> = None;
    while iterations < MAX_ITERATIONS && radius > 1e-4 {
        iterations += 1;
        if !fresh {
            let (g_old, s) = secant.take().expect("a successful step came before");
            d = derivatives_along_axes(
                &t,
                &terms,
                &steps,
                options.clusters,
                &d.hessian,
                f,
                &mut evaluations,
            )?;
            d.hessian = sr1_mixed(&d.hessian, &s, &(&d.gradient - g_old));
            (fresh, exact) = (true, false);
        }
        steps.clone_from(&d.steps);
        let a = -&d.hessian;
        let (wanted, next) = constrained_step(&t, &d.gradient, &a, radius, project);
        let step = DVector::from_iterator(k, next.iter().zip(&t).map(|(a, b)| a - b));
        let model = |s: &DVector<f64>| d.gradient.dot(s) - 0.5 * s.dot(&(&a * s));
        // The gain the quadratic model predicts for the step taken, and for the step it
        // wanted (before clipping and projection: on a curved boundary the projection can
        // spoil a long step that a shorter one would not).
        let (predicted, promised) = (model(&step), model(&wanted));
        if promised.max(predicted) < TOLERANCE {
            if !exact && options.curvature {
                // Only the exact model decides that t is the maximum.
                d = measure(&t, &terms, &steps, &d.hessian, f, &mut evaluations)?;
                exact = true;
                iterations -= 1;
                continue;
            }
            // The model promises no progress worth an evaluation: t is the maximum.
            break;
        }
        evaluations += 1;
        let next_terms = f(&next)?;
        let f1 = total(&next_terms);
        let gain = f1 - f0;
        if gain > 0.0 {
            let ratio = gain / predicted.max(1e-300);
            secant = Some((d.gradient.clone(), step.clone()));
            t = next;
            f0 = f1;
            terms = next_terms;
            fresh = false;
            if ratio > 0.75 && step.norm() > 0.9 * radius {
                radius *= 2.0;
            } else if ratio < 0.25 {
                radius *= 0.25;
            }
            if gain < TOLERANCE {
                break;
            }
        } else {
            radius = 0.25 * step.norm().max(wanted.norm()).min(radius);
            if !exact {
                // The updated model failed: measure it again where it is.
                d = measure(&t, &terms, &steps, &d.hessian, f, &mut evaluations)?;
                exact = true;
            } else if promised < TOLERANCE {
                break;
            }
        }
    }
    if (!fresh || !exact) && options.curvature {
        d = measure(&t, &terms, &steps, &d.hessian, f, &mut evaluations)?;
    }
    let (curvature, variability) = if options.curvature {
        steps.clone_from(&d.steps);
        let smoothed = options.rough.then_some(measured_at.as_slice());
        curvature_at_maximum(
            &t,
            &terms,
            d,
            smoothed,
            options.clusters,
            f,
            &mut evaluations,
        )?
    } else {
        (DMatrix::zeros(0, 0), DMatrix::zeros(0, 0))
    };
    Ok(Fit {
        internal: t,
        log_likelihood: f0,
        curvature,
        variability,
        steps,
        evaluations,
        iterations,
    })
}

/// The robust (sandwich) covariance `c·A⁻¹BA⁻¹` of the internal coordinates, `c = 1 + n/N`;
/// `None` when `A` is not positive definite.
pub fn sandwich(fit: &Fit, inflation: f64) -> Option<DMatrix<f64>> {
    let a_inv = nalgebra::Cholesky::new(fit.curvature.clone())?.inverse();
    Some(&a_inv * &fit.variability * &a_inv * inflation)
}

/// The misspecification adjustments at a fit: `λ̄ = tr(A⁻¹B)/k`, the mean eigenvalue of
/// `A⁻¹B` (that of the k-parameter likelihood-ratio test), and per parameter
/// `λⱼ = (A⁻¹BA⁻¹)ⱼⱼ/(A⁻¹)ⱼⱼ` (that of parameter j's profile: the ratio of its sandwich
/// variance to its model-based one); both 1 when the Gaussian model is right, and `None`
/// when `A` is not positive definite.
pub fn adjustments(fit: &Fit) -> Option<(f64, Vec<f64>)> {
    let k = fit.internal.len();
    let a_inv = nalgebra::Cholesky::new(fit.curvature.clone())?.inverse();
    let ab = &a_inv * &fit.variability;
    let cov = &ab * &a_inv;
    let per = (0..k).map(|j| cov[(j, j)] / a_inv[(j, j)]).collect();
    Some((ab.trace() / k as f64, per))
}

/// Wald intervals of the parameters from the sandwich covariance (module doc); `inflation`
/// is `c = 1 + n/N`.
pub fn wald_intervals(fit: &Fit, parameters: &[Parameter], inflation: f64) -> Vec<Interval> {
    let k = parameters.len();
    let Some(cov) = sandwich(fit, inflation) else {
        return vec![Interval::undetermined("wald"); k];
    };
    (0..k)
        .map(|i| {
            let half = 1.959_963_984_540_054 * cov[(i, i)].sqrt();
            let (lo, hi) = (fit.internal[i] - half, fit.internal[i] + half);
            let p = &parameters[i];
            Interval {
                lower: Some(p.value(lo.max(0.0))),
                upper: Some(p.value(hi.min(1.0))),
                lower_at_range_end: lo <= 0.0,
                upper_at_range_end: hi >= 1.0,
                method: "wald",
                threshold: None,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::likelihood::derivatives::Terms;

    /// A likelihood rough on the scale of its own standard error: a quadratic of standard
    /// error 0.002 along each axis and correlation 0.9, rounded to whole units of ℓ (as a
    /// sum over samples whose contact states change at their own parameter values makes it
    /// step). At t − m = (−0.0005, 0.0004) the stencil keeps steps of one standard error
    /// (the second differences are 1 unit), and there the rounded mixed difference reads a
    /// correlation of 2, so A is indefinite; measured again at twice the steps it reads
    /// 0.75, the diagonal exact (the same stencil worked in NumPy gives 2 and 0.75). The
    /// rule of the module doc keeps that one. Without the rule the first A comes back and
    /// Cholesky fails.
    #[test]
    fn a_rough_likelihood_has_its_curvature_measured_at_longer_steps() {
        let (se, rho, m) = (0.002, 0.9, [0.5, 0.5]);
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            let (x, y) = ((t[0] - m[0]) / se, (t[1] - m[1]) / se);
            Ok(vec![(-0.5 * (x * x + 2.0 * rho * x * y + y * y)).round()])
        };
        let t = [m[0] - 0.0005, m[1] + 0.0004];
        let terms = f(&t).unwrap();
        let mut evaluations = 0;
        let d = derivatives(&t, &terms, &[se, se], None, &mut f, &mut evaluations).unwrap();
        let a = -&d.hessian;
        assert!(
            nalgebra::Cholesky::new(a.clone()).is_none(),
            "the premise: A at the adapted steps {:?} is indefinite, {a}",
            d.steps
        );
        assert_eq!(d.steps, [se, se]);
        let correlation = |a: &DMatrix<f64>| a[(0, 1)] / (a[(0, 0)] * a[(1, 1)]).sqrt();
        assert!((correlation(&a) - 2.0).abs() < 1e-9, "{a}");
        let (a, _) =
            curvature_at_maximum(&t, &terms, d, None, None, &mut f, &mut evaluations).unwrap();
        assert!(nalgebra::Cholesky::new(a.clone()).is_some(), "{a}");
        for i in 0..2 {
            assert!((a[(i, i)] * se * se - 1.0).abs() < 1e-9, "{a}");
        }
        assert!((correlation(&a) - 0.75).abs() < 1e-9, "{a}");
    }

    /// A flat ridge is not noise: an exact quadratic whose curvature is indefinite though
    /// every pair of parameters is consistent (correlations ±0.99; vᵀCv = 3 − 6·0.99 < 0 for
    /// v = (1, −1, 1)) keeps the A measured at its own steps, with no further evaluation:
    /// only a 2 × 2 minor below zero is read as noise.
    #[test]
    fn an_indefinite_but_consistent_curvature_is_kept() {
        let c = [[1.0, 0.99, -0.99], [0.99, 1.0, 0.99], [-0.99, 0.99, 1.0]];
        let se = 0.01;
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            let x: Vec<f64> = t.iter().map(|v| (v - 0.5) / se).collect();
            let q: f64 = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| c[i][j] * x[i] * x[j])
                .sum();
            Ok(vec![-0.5 * q])
        };
        let t = [0.5; 3];
        let terms = f(&t).unwrap();
        let mut evaluations = 0;
        let d = derivatives(&t, &terms, &[se; 3], None, &mut f, &mut evaluations).unwrap();
        let measured = -&d.hessian;
        assert!(nalgebra::Cholesky::new(measured.clone()).is_none());
        assert!(!pairwise_inconsistent(&measured), "{measured}");
        let before = evaluations;
        let (a, _) =
            curvature_at_maximum(&t, &terms, d, None, None, &mut f, &mut evaluations).unwrap();
        assert_eq!(a, measured);
        assert_eq!(evaluations, before);
    }

    /// A concave quadratic with its maximum inside the cube is found in a few iterations, and
    /// the Wald interval is the exact one of a normal likelihood: for ℓ = −(t − m)²/(2s²),
    /// t̂ ± 1.96·s.
    #[test]
    fn quadratic_maximum_and_its_interval() {
        let (m, s) = ([0.31, 0.72], 0.05);
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(vec![
                -((t[0] - m[0]).powi(2)
                    + (t[1] - m[1]).powi(2)
                    + 0.5 * (t[0] - m[0]) * (t[1] - m[1]))
                    / (2.0 * s * s),
            ])
        };
        let fit = maximise(&[0.5, 0.5], Options::default(), &|_| {}, &mut f).unwrap();
        assert!((fit.internal[0] - m[0]).abs() < 1e-6, "{:?}", fit.internal);
        assert!((fit.internal[1] - m[1]).abs() < 1e-6, "{:?}", fit.internal);
        let p = Parameter {
            name: "a".into(),
            unit: "-",
            low: 0.0,
            high: 1.0,
            null: 0.5,
            log: false,
        };
        // Normal data x₁…x₄ with known SD 2s: ℓ_u = −(x_u − t)²/(2·4s²), whose scores
        // vary as the likelihood says (B = A), so the sandwich is the model-based interval.
        let xs = [0.4 - 3.0 * s, 0.4 - s, 0.4 + s, 0.4 + 3.0 * s];
        let mut g = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(xs
                .iter()
                .map(|x| -(x - t[0]).powi(2) / (2.0 * 4.0 * s * s))
                .collect())
        };
        let fit = maximise(&[0.5], Options::default(), &|_| {}, &mut g).unwrap();
        assert!((fit.internal[0] - 0.4).abs() < 1e-6);
        // A = 4/(4s²) = 1/s²; B = Σ (x_u − x̄)²/(4s²)² = 20s²/16s⁴ = 1.25/s²: A⁻¹BA⁻¹ = 1.25 s².
        let cov = sandwich(&fit, 1.0).unwrap();
        assert!((cov[(0, 0)] / (s * s) - 1.25).abs() < 1e-6, "{cov}");
        let (mean_eig, per) = adjustments(&fit).unwrap();
        assert!((mean_eig - 1.25).abs() < 1e-6 && (per[0] - 1.25).abs() < 1e-6);
        let iv = wald_intervals(&fit, &[p], 1.0);
        let s = s * 1.25f64.sqrt();
        assert!((iv[0].lower.unwrap() - (0.4 - 1.96 * s)).abs() < 1e-3);
        assert!((iv[0].upper.unwrap() - (0.4 + 1.96 * s)).abs() < 1e-3);
    }

    /// A maximum on a curved constraint: ℓ = −(x − 1)²/(2·0.01²) − (y − 0.7)²/(2·0.2²) on
    /// the disc |t − (½, ½)| ≤ ½ (a curved feasible set in internal coordinates), started on the
    /// circle at (1, ½), where the unconstrained step points out of the disc. The method
    /// slides along the circle to the constrained maximum, found here by a fine scan of the
    /// angle (the reference).
    #[test]
    fn slides_along_a_curved_constraint() {
        let ell = |x: f64, y: f64| {
            -(x - 1.0).powi(2) / (2.0 * 0.01f64.powi(2)) - (y - 0.7).powi(2) / (2.0 * 0.04)
        };
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> { Ok(vec![ell(t[0], t[1])]) };
        let disc = |t: &mut [f64]| {
            let (dx, dy) = (t[0] - 0.5, t[1] - 0.5);
            let r = (dx * dx + dy * dy).sqrt();
            if r > 0.5 {
                t[0] = 0.5 + 0.5 * dx / r;
                t[1] = 0.5 + 0.5 * dy / r;
            }
        };
        let fit = maximise(&[1.0, 0.5], Options::default(), &disc, &mut f).unwrap();
        let best = (0..=200_000)
            .map(|i| -0.5 + 1.0 * f64::from(i) / 200_000.0)
            .map(|phi| (0.5 + 0.5 * phi.cos(), 0.5 + 0.5 * phi.sin()))
            .max_by(|a, b| ell(a.0, a.1).total_cmp(&ell(b.0, b.1)))
            .unwrap();
        assert!(
            ell(fit.internal[0], fit.internal[1]) > ell(best.0, best.1) - 2.0 * TOLERANCE,
            "{:?} (ℓ {}) vs {best:?} (ℓ {})",
            fit.internal,
            fit.log_likelihood,
            ell(best.0, best.1)
        );
        assert!(
            (fit.internal[1] - best.1).abs() < 0.02,
            "{:?} vs {best:?}",
            fit.internal
        );
    }

    /// The SR1 update by hand: in 2-D with the diagonal exact and the mixed entry off by `e`,
    /// `r = y − h s = −e·(s₂, s₁)`, `rᵀs = −2e·s₁s₂`, so the update adds `r₁r₂/(rᵀs) = −e/2`
    /// to the mixed entry: its error halves, whatever the step; the diagonal is kept.
    #[test]
    fn sr1_halves_a_mixed_error() {
        let truth = DMatrix::from_row_slice(2, 2, &[-4.0, 1.5, 1.5, -9.0]);
        let e = 0.8;
        let h = DMatrix::from_row_slice(2, 2, &[-4.0, 1.5 + e, 1.5 + e, -9.0]);
        for s in [[0.3, -0.1], [0.05, 0.7]] {
            let s = DVector::from_row_slice(&s);
            let next = sr1_mixed(&h, &s, &(&truth * &s));
            assert!((next[(0, 1)] - (1.5 + e / 2.0)).abs() < 1e-12, "{next}");
            assert_eq!(next[(0, 1)], next[(1, 0)]);
            assert_eq!((next[(0, 0)], next[(1, 1)]), (-4.0, -9.0));
        }
        // Nothing to learn along a step where the model is already right.
        let s = DVector::from_row_slice(&[1.0, 0.0]);
        let y = &h * &s;
        assert_eq!(sr1_mixed(&h, &s, &y), h);
    }

    /// A coupled, non-quadratic ℓ of five parameters (a quadratic plus a quartic, so that
    /// Newton takes several steps and the quasi-Newton updates are used): the maximum is
    /// found, the curvature returned is the fully measured one at that maximum (equal to a
    /// fresh [`derivatives`] there), and the fit costs fewer evaluations than a full Hessian
    /// at every iteration would.
    #[test]
    fn quasi_newton_steps_end_on_the_measured_maximum() {
        let m = [0.41, 0.63, 0.27, 0.55, 0.48];
        let q = |x: &[f64]| -> f64 {
            let d: Vec<f64> = x.iter().zip(&m).map(|(a, b)| (a - b) / 0.05).collect();
            let mut v = 0.0;
            for i in 0..5 {
                v += d[i] * d[i] + 0.25 * d[i].powi(4) / 10.0;
                if i > 0 {
                    v += 0.6 * d[i] * d[i - 1];
                }
            }
            -0.5 * v
        };
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> { Ok(vec![q(t)]) };
        let fit = maximise(&[0.5; 5], Options::default(), &|_| {}, &mut f).unwrap();
        for (x, y) in fit.internal.iter().zip(&m) {
            assert!((x - y).abs() < 5e-3, "{:?}", fit.internal);
        }
        let mut n = 0;
        let at = vec![q(&fit.internal)];
        let d = derivatives(&fit.internal, &at, &fit.steps, None, &mut f, &mut n).unwrap();
        assert_eq!(
            fit.curvature, -d.hessian,
            "the returned A is the measured one"
        );
        assert!(fit.iterations >= 2, "{} iterations", fit.iterations);
        // A full Hessian per iteration costs 2k + k(k−1)/2 = 20 new evaluations, plus the
        // step's own: 84 in this fit's 4 iterations with the full Hessian every time (measured
        // with the updates turned off); with them, 74.
        assert!(
            fit.evaluations <= 20 * fit.iterations,
            "{} evaluations in {} iterations",
            fit.evaluations,
            fit.iterations
        );
    }

    /// A rough likelihood: ℓ = −(t − m)²/(2s²) plus a triangle wave of amplitude 0.3 and
    /// period 0.37·s (a kink wherever the wave turns, as a sample's contact state switches
    /// with a clearance). Hand derivation: the wave adds at most 4·0.3 = 1.2 to a central
    /// second difference, against the quadratic's own h²/s²: about 1 at the adapted steps
    /// (h ≈ s), so `A` there may be off by as much as the curvature itself; 16 at
    /// [`SMOOTHING`] = 4 standard errors (h = 4s), off by at most 1.2/16 = 7.5 %. With
    /// `rough`, the curvature at the maximum is within that of the true 1/s²; without, the
    /// same fit's is further off (21.5 % against 3.9 %: the case the option exists for).
    #[test]
    fn kinks_on_the_scale_of_the_standard_error_are_smoothed_over_where_rough() {
        let (m, s) = (0.4137, 0.01);
        let wave = |t: f64| {
            let x = (t / (0.37 * s)).rem_euclid(1.0);
            0.3 * (4.0 * (x - 0.5).abs() - 1.0)
        };
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(vec![-(t[0] - m).powi(2) / (2.0 * s * s) + wave(t[0])])
        };
        let truth = 1.0 / (s * s);
        let error = |options: Options, f: &mut Objective| {
            let fit = maximise(&[0.5], options, &|_| {}, f).unwrap();
            assert!((fit.internal[0] - m).abs() < s, "{:?}", fit.internal);
            (fit.curvature[(0, 0)] / truth - 1.0).abs()
        };
        let rough = Options {
            rough: true,
            ..Options::default()
        };
        let smoothed = error(rough, &mut f);
        let plain = error(Options::default(), &mut f);
        assert!(smoothed <= 0.075, "A off by {smoothed} at the longer steps");
        assert!(
            plain > 2.0 * smoothed,
            "A off by {plain} at the adapted steps, {smoothed} longer"
        );
    }
}
