//! Where a rival could take over part of what a model's effects explain: the flat
//! directions of a joint fit's curvature that the confounding tests
//! ([`crate::selection::confound`]) probe on ℓ itself.
//!
//! ## Equations
//!
//! The joint fit of the model's effects M and a rival R has the curvature
//! `A = −∂²ℓ/∂t²` (internal coordinates, M's parameters first), in blocks `A_MM`, `A_MR`,
//! `A_RR`. Moving R by `r` with M's parameters following it to their maximum given R moves
//! them by `−X·r`, `X = A_MM⁻¹·A_MR`, and costs `½·rᵀSr` in ℓ, with the Schur complement
//! `S = A_RR − A_RMX` (R's curvature given M). Parameter j of M moves by `−xⱼᵀr` (`xⱼ` row
//! j of X); it moves by δ most cheaply along `r ∝ S⁻¹xⱼ`, at a cost `½δ²/(xⱼᵀS⁻¹xⱼ)`.
//! Its variance with R added is `(A⁻¹)ⱼⱼ = (A_MM⁻¹)ⱼⱼ + xⱼᵀS⁻¹xⱼ`, so with `hⱼ` its
//! interval's half-width without R (`1.96·√(A_MM⁻¹)ⱼⱼ` where ℓ is quadratic) its interval
//! widens `√(1 + 1.96²·xⱼᵀS⁻¹xⱼ/hⱼ²)`-fold.
//!
//! A flat or negative curvature of R given M is what is looked for, so S is inverted as
//! `|S|` with its eigenvalues floored at 1e-9 of the largest: a direction along which ℓ does
//! not fall at all (or rises: the joint fit stopped short of a maximum) counts as very flat.

use nalgebra::{DMatrix, DVector};

/// The 97.5th percentile of the standard normal.
const Z_975: f64 = 1.959_963_984_540_054;

/// A direction along which the rival takes over part of what parameter `parameter` of the
/// model explains.
#[derive(Debug, Clone)]
pub struct Ridge {
    /// The model's parameter (index among the joint fit's, M's first).
    pub parameter: usize,
    /// The predicted widening of its interval with the rival added (module doc).
    pub widening: f64,
    /// The direction, every parameter of the joint fit (internal coordinates): `(−X·r, r)`.
    pub direction: DVector<f64>,
    /// How far the parameter moves per unit of `direction`: `−xⱼᵀr`.
    pub per_unit: f64,
}

/// The ridges of the joint curvature `a` (`k_r` rival parameters last) for each of the
/// model's parameters with an interval half-width `half[j]` (internal coordinates; `None`:
/// no interval, not probed), widest first; `None` where `A_MM` is not positive definite.
pub fn ridges(a: &DMatrix<f64>, k_r: usize, half: &[Option<f64>]) -> Option<Vec<Ridge>> {
    let total = a.nrows();
    let k_m = total.checked_sub(k_r).filter(|&k| k > 0 && k_r > 0)?;
    let a_mm = a.view((0, 0), (k_m, k_m)).into_owned();
    let a_mr = a.view((0, k_m), (k_m, k_r)).into_owned();
    let a_rr = a.view((k_m, k_m), (k_r, k_r)).into_owned();
    let x = nalgebra::Cholesky::new(a_mm)?.solve(&a_mr);
    let eig = nalgebra::SymmetricEigen::new(&a_rr - a_mr.transpose() * &x);
    let floor = 1e-9 * eig.eigenvalues.amax().max(1e-300);
    let solve = |c: &DVector<f64>| -> DVector<f64> {
        let mut r = DVector::zeros(k_r);
        for (i, l) in eig.eigenvalues.iter().enumerate() {
            let v = eig.eigenvectors.column(i);
            r += v * (v.dot(c) / l.abs().max(floor));
        }
        r
    };
    let mut out: Vec<Ridge> = half
        .iter()
        .take(k_m)
        .enumerate()
        .filter_map(|(j, h)| {
            let h = (*h)?;
            let row = x.row(j).transpose();
            let r = solve(&row);
            let reach = row.dot(&r) / (h * h).max(1e-300);
            let direction =
                DVector::from_iterator(total, (-&x * &r).iter().chain(r.iter()).copied());
            Some(Ridge {
                parameter: j,
                widening: (1.0 + Z_975.powi(2) * reach).sqrt(),
                direction,
                per_unit: -row.dot(&r),
            })
        })
        .collect();
    out.sort_by(|a, b| b.widening.total_cmp(&a.widening));
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadratic ℓ = −½tᵀAt of three model parameters and two rival ones, A positive
    /// definite with the rival coupled to the model. Against the equations of the module
    /// doc, derived independently here from A⁻¹:
    /// - the predicted widening is the ratio of the joint and model-only standard errors,
    ///   √((A⁻¹)ⱼⱼ/(A_MM⁻¹)ⱼⱼ), when hⱼ is the model-only Wald half-width;
    /// - along each ridge the model's parameters stay at their maximum given the rival
    ///   (∂ℓ/∂t_M = 0), and moving parameter j by δ costs ½δ²/((A⁻¹)ⱼⱼ − (A_MM⁻¹)ⱼⱼ).
    #[test]
    fn ridges_of_a_quadratic() {
        #[rustfmt::skip]
        let l: DMatrix<f64> = DMatrix::from_row_slice(5, 5, &[
            2.0, 0.0, 0.0, 0.0, 0.0,
            0.3, 1.5, 0.0, 0.0, 0.0,
            -0.4, 0.2, 1.0, 0.0, 0.0,
            0.9, -0.5, 0.6, 0.4, 0.0,
            0.1, 0.7, -0.3, 0.2, 0.8,
        ]);
        let a = &l * l.transpose();
        let inv = a.clone().try_inverse().unwrap();
        let inv_mm = a.view((0, 0), (3, 3)).into_owned().try_inverse().unwrap();
        let half: Vec<Option<f64>> = (0..3)
            .map(|j| Some(Z_975 * inv_mm[(j, j)].sqrt()))
            .collect();
        let found = ridges(&a, 2, &half).unwrap();
        assert_eq!(found.len(), 3);
        assert!(found.windows(2).all(|w| w[0].widening >= w[1].widening));
        for ridge in &found {
            let j = ridge.parameter;
            let expected = (inv[(j, j)] / inv_mm[(j, j)]).sqrt();
            assert!(
                (ridge.widening - expected).abs() < 1e-10 * expected,
                "{ridge:?} vs {expected}"
            );
            assert!((ridge.direction[j] - ridge.per_unit).abs() < 1e-12);
            // Parameter j moved by δ = 0.3 along the ridge.
            let t = &ridge.direction * (0.3 / ridge.per_unit);
            let gradient = -(&a * &t);
            assert!(gradient.rows(0, 3).amax() < 1e-12, "{gradient}");
            let cost = 0.5 * t.dot(&(&a * &t));
            let expected = 0.5 * 0.3 * 0.3 / (inv[(j, j)] - inv_mm[(j, j)]);
            assert!(
                (cost - expected).abs() < 1e-10 * expected,
                "{cost} vs {expected}"
            );
        }
    }

    /// A rival that duplicates a model parameter exactly (a flat ridge: A singular) gives
    /// that parameter an unbounded widening, and one that is independent of the model
    /// (A block diagonal) widens nothing; without a positive definite A_MM there is no
    /// answer.
    #[test]
    fn a_duplicate_widens_without_bound_and_an_independent_rival_not_at_all() {
        // ℓ depends on t₀ + t₂ only along the first axis: the rival t₂ duplicates t₀.
        #[rustfmt::skip]
        let duplicate: DMatrix<f64> = DMatrix::from_row_slice(3, 3, &[
            4.0, 0.0, 4.0,
            0.0, 1.0, 0.0,
            4.0, 0.0, 4.0,
        ]);
        let half = [Some(0.5), Some(1.0)];
        let found = ridges(&duplicate, 1, &half).unwrap();
        assert_eq!(found[0].parameter, 0);
        assert!(found[0].widening > 1e3, "{:?}", found[0]);
        let independent = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 1.0, 2.0]));
        for ridge in ridges(&independent, 1, &half).unwrap() {
            assert!((ridge.widening - 1.0).abs() < 1e-12, "{ridge:?}");
        }
        let mut indefinite = independent.clone();
        indefinite[(0, 0)] = -1.0;
        assert!(ridges(&indefinite, 1, &half).is_none());
    }
}
