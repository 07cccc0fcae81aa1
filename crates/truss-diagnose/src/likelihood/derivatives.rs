//! Finite-difference derivatives of ℓ on the unit cube, with a step per parameter adapted to
//! the likelihood's own scale.
//!
//! ## Stencil
//!
//! At a centre `t` (moved inside the cube by at least the step, so that no evaluation leaves
//! the plausible range) with steps `hᵢ`:
//!
//! ```text
//! gᵢ   = (ℓ(t + hᵢeᵢ) − ℓ(t − hᵢeᵢ)) / 2hᵢ                              central
//! Hᵢᵢ  = (ℓ(t + hᵢeᵢ) − 2ℓ(t) + ℓ(t − hᵢeᵢ)) / hᵢ²                      central
//! Hᵢⱼ  = (ℓ(t + hᵢeᵢ + hⱼeⱼ) − ℓ(t + hᵢeᵢ) − ℓ(t + hⱼeⱼ) + ℓ(t)) / hᵢhⱼ   forward
//! ```
//!
//! (`1 + 2k + k(k−1)/2` evaluations for `k` parameters when no step changes), the per-unit
//! scores `g_u` by the same central differences of the unit terms, and the score variability
//! over independent clusters of units (Liang & Zeger 1986): `B = Σ_c (g_c − ḡ)(g_c − ḡ)ᵀ`,
//! `g_c = Σ_{u ∈ c} g_u` (a specimen's node term and its own measured members are one
//! cluster: they come from the same truss; without clusters every unit is its own). When the
//! centre had to be moved, the gradient is carried back to `t` with the Hessian.
//!
//! ## Step
//!
//! A fixed step cannot serve every likelihood: with many specimens, member measurements or a
//! nearly singular response, ℓ can fall by hundreds of units within a step of 0.02, and the
//! "curvature" measured is then the chord's, not the peak's (a fit sitting on such a peak
//! gets an interval set by the step). So the step along each axis is chosen where the
//! likelihood decides intervals: `hᵢ` such that the central second difference
//! `Δ²ᵢ = ℓ(t + hᵢeᵢ) − 2ℓ(t) + ℓ(t − hᵢeᵢ)` is about one unit of ℓ, i.e. `hᵢ ≈ 1/√Aᵢᵢ`, the
//! likelihood's own standard error along that axis. Starting from the previous step (at
//! first [`INITIAL_STEP`]), while `|Δ²ᵢ|` lies outside [`SECOND_DIFFERENCE`] (the step off
//! the standard error by more than a factor 4) the step is
//! rescaled by `1/√|Δ²ᵢ|` (by at most a factor 1000 down or 4 up at a time), within
//! [[`MIN_STEP`], [`MAX_STEP`]], at most [`REFINEMENTS`] times. Flat directions keep
//! `MAX_STEP` (their Δ² is small, but large against ℓ's rounding, about 1e-9); a direction
//! that is still too sharp at `MIN_STEP` (a kink of ℓ) keeps `MIN_STEP`. Steps carry over
//! from one call to the next ([`Derivatives::steps`]), so the search costs evaluations only
//! where the scale changes.

use crate::errors::DiagnoseError;
use nalgebra::{DMatrix, DVector};

/// Per-unit values of ℓ at a point: its terms (one per specimen, and per member
/// observation); ℓ is their sum.
pub type Terms = Vec<f64>;

/// ℓ's terms as a function of internal coordinates.
pub type Objective<'a> = dyn FnMut(&[f64]) -> Result<Terms, DiagnoseError> + 'a;

/// First step in internal coordinates (a fiftieth of the range).
pub const INITIAL_STEP: f64 = 0.02;
/// Smallest step in internal coordinates.
pub const MIN_STEP: f64 = 1e-7;
/// Largest step in internal coordinates.
pub const MAX_STEP: f64 = 0.05;
/// The accepted range of `|Δ²ᵢ|` in units of ℓ (module doc).
pub const SECOND_DIFFERENCE: [f64; 2] = [1.0 / 16.0, 16.0];
/// Most step changes per axis and call.
pub const REFINEMENTS: usize = 8;

/// ℓ, the sum of its terms.
pub fn total(t: &Terms) -> f64 {
    t.iter().sum()
}

/// Derivatives of ℓ at a point.
#[derive(Debug, Clone)]
pub struct Derivatives {
    /// ∂ℓ/∂t.
    pub gradient: DVector<f64>,
    /// ∂²ℓ/∂t².
    pub hessian: DMatrix<f64>,
    /// `B = Σ_c (g_c − ḡ)(g_c − ḡ)ᵀ` of the per-cluster scores (module doc).
    pub variability: DMatrix<f64>,
    /// The steps used, per axis (internal coordinates).
    pub steps: Vec<f64>,
}

/// Evaluations of the objective within one call, each point evaluated once.
struct Memo<'f, 'a> {
    f: &'f mut Objective<'a>,
    seen: Vec<(Vec<f64>, Terms)>,
    evaluations: usize,
}

impl Memo<'_, '_> {
    fn at(&mut self, p: &[f64]) -> Result<&Terms, DiagnoseError> {
        let i = match self.seen.iter().position(|(q, _)| q == p) {
            Some(i) => i,
            None => {
                self.evaluations += 1;
                let terms = (self.f)(p)?;
                self.seen.push((p.to_vec(), terms));
                self.seen.len() - 1
            }
        };
        Ok(&self.seen[i].1)
    }

    fn total_at(&mut self, p: &[f64]) -> Result<f64, DiagnoseError> {
        Ok(total(self.at(p)?))
    }
}

/// The centre of an axis's stencil: `x` moved inside `[h, 1 − h]`.
fn inside(x: f64, h: f64) -> f64 {
    x.clamp(h, 1.0 - h)
}

/// Adapts the step of axis `i` at `t` (module doc).
fn adapt(memo: &mut Memo, t: &[f64], i: usize, mut h: f64) -> Result<f64, DiagnoseError> {
    let [lo, hi] = SECOND_DIFFERENCE;
    for _ in 0..REFINEMENTS {
        let mut c = t.to_vec();
        c[i] = inside(t[i], h);
        let f0 = memo.total_at(&c)?;
        c[i] += h;
        let fp = memo.total_at(&c)?;
        c[i] -= 2.0 * h;
        let fm = memo.total_at(&c)?;
        let d2 = (fp - 2.0 * f0 + fm).abs();
        if (lo..=hi).contains(&d2) {
            break;
        }
        let factor = if d2 > 0.0 {
            (1.0 / d2).sqrt().clamp(1e-3, 4.0)
        } else {
            4.0
        };
        let next = (h * factor).clamp(MIN_STEP, MAX_STEP);
        if next == h {
            break;
        }
        h = next;
    }
    Ok(h)
}

/// Derivatives of ℓ at `t` (ℓ's terms there `f_t`), starting from `steps` (module doc);
/// `clusters` gives each unit term's cluster (`None`: each its own); `evaluations` counts
/// the calls of `f`.
pub fn derivatives(
    t: &[f64],
    f_t: &Terms,
    steps: &[f64],
    clusters: Option<&[usize]>,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    stencil(t, f_t, steps, clusters, None, f, evaluations)
}

/// [`derivatives`] without the mixed second differences: the gradient, the diagonal of the
/// Hessian and `B` from the central stencil alone (`1 + 2k` evaluations when no step
/// changes), the Hessian's off-diagonal entries taken from `cross` (a quasi-Newton
/// estimate, [`crate::likelihood::fit`]).
pub fn derivatives_along_axes(
    t: &[f64],
    f_t: &Terms,
    steps: &[f64],
    clusters: Option<&[usize]>,
    cross: &DMatrix<f64>,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    stencil(t, f_t, steps, clusters, Some(cross), f, evaluations)
}

/// [`derivatives`] at exactly `steps`, none adapted (each clamped to
/// [[`MIN_STEP`], [`MAX_STEP`]]): for a curvature measured again at a longer scale than
/// the likelihood's standard error ([`crate::likelihood::fit`]).
pub fn derivatives_at_steps(
    t: &[f64],
    f_t: &Terms,
    steps: &[f64],
    clusters: Option<&[usize]>,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    let fixed: Vec<f64> = steps.iter().map(|h| h.clamp(MIN_STEP, MAX_STEP)).collect();
    stencil_with(t, f_t, &fixed, clusters, None, false, f, evaluations)
}

/// The stencil of the module doc; the mixed differences from `cross` where it is given.
fn stencil(
    t: &[f64],
    f_t: &Terms,
    steps: &[f64],
    clusters: Option<&[usize]>,
    cross: Option<&DMatrix<f64>>,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    stencil_with(t, f_t, steps, clusters, cross, true, f, evaluations)
}

/// [`stencil`], each step adapted to the likelihood's scale first where `adapt_steps`.
#[allow(clippy::too_many_arguments)]
fn stencil_with(
    t: &[f64],
    f_t: &Terms,
    steps: &[f64],
    clusters: Option<&[usize]>,
    cross: Option<&DMatrix<f64>>,
    adapt_steps: bool,
    f: &mut Objective,
    evaluations: &mut usize,
) -> Result<Derivatives, DiagnoseError> {
    let k = t.len();
    let mut memo = Memo {
        f,
        seen: vec![(t.to_vec(), f_t.clone())],
        evaluations: 0,
    };
    let mut h = steps.to_vec();
    if adapt_steps {
        for (i, hi) in h.iter_mut().enumerate() {
            *hi = adapt(&mut memo, t, i, *hi)?;
        }
    }
    let centre: Vec<f64> = t.iter().zip(&h).map(|(&x, &hi)| inside(x, hi)).collect();
    let f0 = memo.at(&centre)?.clone();
    let units = f0.len();
    let s0 = total(&f0);
    let mut g = DVector::zeros(k);
    let mut hess = DMatrix::zeros(k, k);
    let mut plus = vec![0.0; k];
    let mut unit_grad = DMatrix::zeros(units, k);
    for i in 0..k {
        let mut p = centre.clone();
        p[i] += h[i];
        let tp = memo.at(&p)?.clone();
        p[i] -= 2.0 * h[i];
        let tm = memo.at(&p)?;
        for u in 0..units {
            unit_grad[(u, i)] = (tp[u] - tm[u]) / (2.0 * h[i]);
        }
        let (fp, fm) = (total(&tp), total(tm));
        plus[i] = fp;
        g[i] = (fp - fm) / (2.0 * h[i]);
        hess[(i, i)] = (fp - 2.0 * s0 + fm) / (h[i] * h[i]);
    }
    for i in 0..k {
        for j in 0..i {
            if let Some(cross) = cross {
                hess[(i, j)] = cross[(i, j)];
                hess[(j, i)] = cross[(i, j)];
                continue;
            }
            let mut p = centre.clone();
            p[i] += h[i];
            p[j] += h[j];
            let fij = memo.total_at(&p)?;
            let v = (fij - plus[i] - plus[j] + s0) / (h[i] * h[j]);
            hess[(i, j)] = v;
            hess[(j, i)] = v;
        }
    }
    *evaluations += memo.evaluations;
    if centre != t {
        let shift = DVector::from_iterator(k, t.iter().zip(&centre).map(|(a, b)| a - b));
        g += &hess * shift;
    }
    let variability = variability(&unit_grad, clusters);
    Ok(Derivatives {
        gradient: g,
        hessian: hess,
        variability,
        steps: h,
    })
}

/// `B = Σ_c (g_c − ḡ)(g_c − ḡ)ᵀ` from the per-unit scores (rows of `unit_grad`) summed over
/// the clusters given, one id per unit (ids need not be consecutive: each id used is one
/// cluster).
fn variability(unit_grad: &DMatrix<f64>, clusters: Option<&[usize]>) -> DMatrix<f64> {
    let k = unit_grad.ncols();
    let grad = match clusters {
        None => unit_grad.clone(),
        Some(c) => {
            debug_assert_eq!(c.len(), unit_grad.nrows(), "one cluster id per unit");
            let mut ids: Vec<usize> = c.to_vec();
            ids.sort_unstable();
            ids.dedup();
            let mut g = DMatrix::zeros(ids.len(), k);
            for (u, ci) in c.iter().enumerate() {
                if let Ok(row) = ids.binary_search(ci) {
                    for i in 0..k {
                        g[(row, i)] += unit_grad[(u, i)];
                    }
                }
            }
            g
        }
    };
    let mean = grad.row_mean();
    let mut b = DMatrix::zeros(k, k);
    for r in grad.row_iter() {
        let r = r - &mean;
        b += r.transpose() * r;
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A peak far narrower than the initial step (ℓ = −(t − ½)²/(2s²), s = 1e-4, so ℓ falls
    /// by 20 000 within the initial step): the step shrinks to the peak's own scale and the
    /// curvature is exact; a wide parabola keeps the largest step. Hand derivation: for a
    /// quadratic, the central second difference is exact at any step, and Δ² = −h²/s² lies
    /// in [1/16, 16] for h in [s/4, 4s].
    #[test]
    fn the_step_follows_the_scale_of_the_likelihood() {
        let s = 1e-4;
        let mut sharp = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(vec![-(t[0] - 0.5).powi(2) / (2.0 * s * s)])
        };
        let mut n = 0;
        let d = derivatives(
            &[0.5],
            &vec![0.0],
            &[INITIAL_STEP],
            None,
            &mut sharp,
            &mut n,
        )
        .unwrap();
        assert!(
            d.steps[0] >= 0.25 * s && d.steps[0] <= 4.0 * s,
            "{:?}",
            d.steps
        );
        assert!(
            (d.hessian[(0, 0)] * s * s + 1.0).abs() < 1e-6,
            "{}",
            d.hessian
        );
        let mut wide =
            |t: &[f64]| -> Result<Terms, DiagnoseError> { Ok(vec![-(t[0] - 0.5).powi(2) / 2.0]) };
        let d = derivatives(
            &[0.3],
            &vec![-0.02],
            &[INITIAL_STEP],
            None,
            &mut wide,
            &mut n,
        )
        .unwrap();
        assert_eq!(d.steps[0], MAX_STEP);
        assert!((d.gradient[0] - 0.2).abs() < 1e-9);
    }

    /// The score variability over clusters, by hand: units with ℓ_u = a_u·t have scores
    /// g_u = a_u; with a = (1, 2, 4, 7) and clusters {units 0, 1}, {2}, {3} (ids 5, 5, 9, 2)
    /// the cluster scores are 3, 4, 7, mean 14/3, and B = (1/9)(25 + 4 + 49) = 78/9; without
    /// clusters B = Σ (a_u − 3.5)² = 21.
    #[test]
    fn variability_sums_scores_within_clusters() {
        let a = [1.0, 2.0, 4.0, 7.0];
        let mut f = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(a.iter().map(|&x| x * t[0]).collect())
        };
        let at = |t: f64| a.iter().map(|&x| x * t).collect::<Vec<f64>>();
        let mut n = 0;
        let d = derivatives(
            &[0.5],
            &at(0.5),
            &[0.01],
            Some(&[5, 5, 9, 2]),
            &mut f,
            &mut n,
        )
        .unwrap();
        assert!(
            (d.variability[(0, 0)] - 78.0 / 9.0).abs() < 1e-9,
            "{}",
            d.variability
        );
        assert!((d.gradient[0] - 14.0).abs() < 1e-9);
        let d = derivatives(&[0.5], &at(0.5), &[0.01], None, &mut f, &mut n).unwrap();
        assert!(
            (d.variability[(0, 0)] - 21.0).abs() < 1e-9,
            "{}",
            d.variability
        );
    }

    /// A kink (ℓ = −1000·|t − ½|) has no curvature scale: the step lands where ℓ falls by
    /// 1/32 to 8 units to each side (|Δ²| = 2000·h in [1/16, 16]). A jump (ℓ falls by 100
    /// off a point) is sharper than any step: the step stops at `MIN_STEP`.
    #[test]
    fn kinks_and_jumps() {
        let mut kink =
            |t: &[f64]| -> Result<Terms, DiagnoseError> { Ok(vec![-1000.0 * (t[0] - 0.5).abs()]) };
        let mut n = 0;
        let d = derivatives(&[0.5], &vec![0.0], &[INITIAL_STEP], None, &mut kink, &mut n).unwrap();
        assert!(
            (SECOND_DIFFERENCE[0] / 2000.0..=SECOND_DIFFERENCE[1] / 2000.0).contains(&d.steps[0]),
            "{:?}",
            d.steps
        );
        let mut jump = |t: &[f64]| -> Result<Terms, DiagnoseError> {
            Ok(vec![if (t[0] - 0.5).abs() < 1e-9 {
                0.0
            } else {
                -100.0
            }])
        };
        let mut n = 0;
        let d = derivatives(&[0.5], &vec![0.0], &[INITIAL_STEP], None, &mut jump, &mut n).unwrap();
        assert_eq!(d.steps[0], MIN_STEP);
        assert!(n <= 2 * REFINEMENTS + 3, "{n} evaluations");
    }
}
