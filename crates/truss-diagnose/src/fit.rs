//! Maximising a candidate's likelihood over its parameters, and Wald intervals.
//!
//! ## Method
//!
//! The parameters are mapped onto the unit cube ([`Parameter::internal`]: linear, or
//! logarithmic for a scale), where the log-likelihood is smooth because every evaluation uses
//! the same random numbers. From the best of the null point (the baseline) and a scan along
//! each axis (`diagnose::SCAN`), a trust-region Newton method:
//! gradient and Hessian by finite differences of step `h` = [`STEP`] (central for the
//! gradient and the diagonal, forward for the cross terms: `1 + 2k + k(k−1)/2` evaluations for
//! `k` parameters), the step `s = (A + μI)⁻¹g` with `A = −H` and the smallest `μ ≥ 0` that
//! makes `A + μI` positive definite and `|s|` at most the trust radius (0.3 at first, doubled
//! after a good step, quartered after a failed one), clipped to the cube (and projected where
//! the box is not the whole constraint). It stops when a step gains less than
//! [`TOLERANCE`] in ℓ, the radius falls below 1e-4, or after [`MAX_ITERATIONS`].
//!
//! ## Intervals
//!
//! ℓ is a sum of per-unit terms ℓ_u (one per specimen, one per member observation). With
//! `A = −∂²ℓ/∂t²` at the optimum and `B = Σ_u (g_u − ḡ)(g_u − ḡ)ᵀ` the variability of the
//! per-unit scores `g_u = ∂ℓ_u/∂t` (central differences), the covariance of the internal
//! coordinates is the sandwich `c·A⁻¹BA⁻¹` (Huber 1967; White 1982), valid when the Gaussian
//! approximation is not the true distribution of a specimen, with `c = 1 + n/N` for the
//! simulation's own noise in μ and Σ (it adds to the data's in proportion to the sample
//! sizes). The 95 % interval of each is `t̂ ± 1.96·√covᵢᵢ` mapped back to the parameter (so a
//! scale's interval is symmetric in its logarithm). Where `A` is not positive definite the
//! interval is undetermined.

use crate::candidates::Parameter;
use crate::errors::DiagnoseError;
use nalgebra::{DMatrix, DVector};

/// Finite-difference step in internal coordinates.
pub const STEP: f64 = 0.02;
/// Smallest gain in ℓ that counts as progress.
pub const TOLERANCE: f64 = 0.02;
/// Most Newton iterations.
pub const MAX_ITERATIONS: usize = 12;

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The same in internal coordinates.
    pub internal: Vec<f64>,
    /// ℓ there.
    pub log_likelihood: f64,
    /// A = −∂²ℓ/∂t² there (internal coordinates).
    pub curvature: DMatrix<f64>,
    /// B, the variability of the per-unit scores there (module doc).
    pub variability: DMatrix<f64>,
    /// Evaluations of ℓ.
    pub evaluations: usize,
    /// Newton iterations.
    pub iterations: usize,
}

/// A 95 % Wald interval, or why there is none.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Interval {
    /// Lower end, if determined.
    pub lower: Option<f64>,
    /// Upper end, if determined.
    pub upper: Option<f64>,
    /// Whether an end reaches the plausible range's end (then it is cut there).
    pub at_range_end: bool,
}

/// Per-unit values of ℓ at a point: its terms (one per specimen, and per member
/// observation); ℓ is their sum.
pub type Terms = Vec<f64>;

fn total(t: &Terms) -> f64 {
    t.iter().sum()
}

/// Gradient, Hessian, and `B = Σ_u (g_u − ḡ)(g_u − ḡ)ᵀ` of the per-unit gradients `g_u`.
type Derivatives = (DVector<f64>, DMatrix<f64>, DMatrix<f64>);

/// Derivatives at `t`, from a stencil centred at `t` moved inside the cube by at least `h`
/// (so no evaluation leaves the plausible range); the gradient is carried from the centre
/// to `t` with the Hessian.
fn derivatives(
    t: &[f64],
    f_t: &Terms,
    f: &mut dyn FnMut(&[f64]) -> Result<Terms, DiagnoseError>,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    let k = t.len();
    let h = STEP;
    let centre: Vec<f64> = t.iter().map(|x| x.clamp(h, 1.0 - h)).collect();
    let moved = centre != t;
    let owned;
    let f0 = if moved {
        *evaluations += 1;
        owned = f(&centre)?;
        &owned
    } else {
        f_t
    };
    let t_at = t;
    let t = &centre[..];
    let units = f0.len();
    let s0 = total(f0);
    let mut g = DVector::zeros(k);
    let mut hess = DMatrix::zeros(k, k);
    let mut plus = vec![0.0; k];
    let mut unit_grad = DMatrix::zeros(units, k);
    let mut at = |p: &[f64], evaluations: &mut usize| {
        *evaluations += 1;
        f(p)
    };
    for i in 0..k {
        let mut p = t.to_vec();
        p[i] += h;
        let tp = at(&p, evaluations)?;
        p[i] -= 2.0 * h;
        let tm = at(&p, evaluations)?;
        let (fp, fm) = (total(&tp), total(&tm));
        for u in 0..units {
            unit_grad[(u, i)] = (tp[u] - tm[u]) / (2.0 * h);
        }
        plus[i] = fp;
        g[i] = (fp - fm) / (2.0 * h);
        hess[(i, i)] = (fp - 2.0 * s0 + fm) / (h * h);
    }
    for i in 0..k {
        for j in 0..i {
            let mut p = t.to_vec();
            p[i] += h;
            p[j] += h;
            let fij = total(&at(&p, evaluations)?);
            let v = (fij - plus[i] - plus[j] + s0) / (h * h);
            hess[(i, j)] = v;
            hess[(j, i)] = v;
        }
    }
    if moved {
        let shift = DVector::from_iterator(k, t_at.iter().zip(t).map(|(a, b)| a - b));
        g += &hess * shift;
    }
    let mean = unit_grad.row_mean();
    let mut b = DMatrix::zeros(k, k);
    for u in 0..units {
        let r = unit_grad.row(u) - &mean;
        b += r.transpose() * r;
    }
    Ok((g, hess, b))
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

/// Maximises `f` (ℓ as a function of internal coordinates) over the unit cube from `start`;
/// `project` maps internal coordinates onto the feasible set.
pub fn maximise(
    start: &[f64],
    project: &dyn Fn(&mut [f64]),
    f: &mut dyn FnMut(&[f64]) -> Result<Terms, DiagnoseError>,
) -> Result<Fit, DiagnoseError> {
    let mut t = start.to_vec();
    let mut evaluations = 1;
    let mut terms = f(&t)?;
    let mut f0 = total(&terms);
    let mut radius = 0.3;
    let mut iterations = 0;
    let (mut _g, mut hess, mut b) = derivatives(&t, &terms, f, &mut evaluations)?;
    let mut fresh = true;
    while iterations < MAX_ITERATIONS && radius > 1e-4 {
        iterations += 1;
        if !fresh {
            (_g, hess, b) = derivatives(&t, &terms, f, &mut evaluations)?;
        }
        let a = -&hess;
        let s = trust_step(&_g, &a, radius);
        let mut next: Vec<f64> = t
            .iter()
            .zip(s.iter())
            .map(|(x, d)| (x + d).clamp(0.0, 1.0))
            .collect();
        project(&mut next);
        let step = DVector::from_iterator(t.len(), next.iter().zip(&t).map(|(a, b)| a - b));
        let predicted = _g.dot(&step) - 0.5 * step.dot(&(&a * &step));
        evaluations += 1;
        let next_terms = f(&next)?;
        let f1 = total(&next_terms);
        let gain = f1 - f0;
        if gain > 0.0 {
            let ratio = gain / predicted.max(1e-300);
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
            fresh = true;
            radius = 0.25 * step.norm().min(radius);
            if predicted < TOLERANCE {
                break;
            }
        }
    }
    if !fresh {
        (_g, hess, b) = derivatives(&t, &terms, f, &mut evaluations)?;
    }
    Ok(Fit {
        internal: t,
        log_likelihood: f0,
        curvature: -hess,
        variability: b,
        evaluations,
        iterations,
    })
}

/// The robust (sandwich) covariance `c·A⁻¹BA⁻¹` of the internal coordinates, `c = 1 + n/N`,
/// and the mean eigenvalue `tr(A⁻¹B)/k` of the misspecification (1 when the Gaussian model
/// is right); `None` when `A` is not positive definite.
pub fn sandwich(fit: &Fit, inflation: f64) -> Option<(DMatrix<f64>, f64)> {
    let k = fit.internal.len();
    let a_inv = nalgebra::Cholesky::new(fit.curvature.clone())?.inverse();
    let ab = &a_inv * &fit.variability;
    let cov = &ab * &a_inv * inflation;
    Some((cov, ab.trace() / k as f64))
}

/// Wald intervals of the parameters from the sandwich covariance (module doc); `inflation`
/// is `c = 1 + n/N`.
pub fn intervals(fit: &Fit, parameters: &[Parameter], inflation: f64) -> Vec<Interval> {
    let k = parameters.len();
    let undetermined = || Interval {
        lower: None,
        upper: None,
        at_range_end: false,
    };
    let Some((cov, _)) = sandwich(fit, inflation) else {
        return vec![undetermined(); k];
    };
    (0..k)
        .map(|i| {
            let half = 1.959_963_984_540_054 * cov[(i, i)].sqrt();
            let (lo, hi) = (fit.internal[i] - half, fit.internal[i] + half);
            let p = &parameters[i];
            Interval {
                lower: Some(p.value(lo.max(0.0))),
                upper: Some(p.value(hi.min(1.0))),
                at_range_end: lo < 0.0 || hi > 1.0,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let fit = maximise(&[0.5, 0.5], &|_| {}, &mut f).unwrap();
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
        let fit = maximise(&[0.5], &|_| {}, &mut g).unwrap();
        assert!((fit.internal[0] - 0.4).abs() < 1e-6);
        // A = 4/(4s²) = 1/s²; B = Σ (x_u − x̄)²/(4s²)² = 20s²/16s⁴ = 1.25/s²: A⁻¹BA⁻¹ = 1.25 s².
        let (cov, mean_eig) = sandwich(&fit, 1.0).unwrap();
        assert!((cov[(0, 0)] / (s * s) - 1.25).abs() < 1e-6, "{cov}");
        assert!((mean_eig - 1.25).abs() < 1e-6);
        let iv = intervals(&fit, &[p], 1.0);
        let s = s * 1.25f64.sqrt();
        assert!((iv[0].lower.unwrap() - (0.4 - 1.96 * s)).abs() < 1e-3);
        assert!((iv[0].upper.unwrap() - (0.4 + 1.96 * s)).abs() < 1e-3);
    }
}
