//! The block-band Cholesky ([`BlockBandMatrix`]) against an independent dense one:
//! nalgebra's `Cholesky` of the same matrix, on random symmetric positive definite block-band
//! matrices of the tangent's shape (3×3 blocks) over several sizes and bandwidths, both
//! solving one right-hand side. A bug in the band's bookkeeping (a block left out of the
//! update, a transposed block) changes the solution far beyond the 1e-13 allowed here.
//!
//! nalgebra is already built for the default tests (truss-diagnose uses it), so this check
//! costs the default run nothing to build; the same check against faer's dense Cholesky is
//! `block::tests::agrees_with_faer_dense` behind `--features cross-checks`.

use nalgebra::{DMatrix, DVector};
use truss_core::block::BlockBandMatrix;
use truss_stats::rng::SplitMix64;

/// A random symmetric block-band matrix of `nb` 3×3 blocks and block bandwidth `q`, made
/// positive definite by diagonal dominance (each diagonal entry exceeds its row's other
/// entries' absolute sum by 1 to 2).
fn spd(nb: usize, q: usize, seed: u64) -> BlockBandMatrix {
    let mut rng = SplitMix64::new(seed);
    let mut next = || rng.uniform() - 0.5;
    let mut m = BlockBandMatrix::new(nb, q);
    for i in 0..nb {
        for j in i.saturating_sub(q)..i {
            for row in m.block_mut(i, j).iter_mut() {
                for x in row.iter_mut() {
                    *x = next();
                }
            }
        }
        let d = m.block_mut(i, i);
        d[1][0] = next();
        d[2][0] = next();
        d[2][1] = next();
    }
    let n = 3 * nb;
    for r in 0..n {
        let off: f64 = (0..n).filter(|&c| c != r).map(|c| m.get(r, c).abs()).sum();
        m.block_mut(r / 3, r / 3)[r % 3][r % 3] = off + 1.0 + next().abs() * 2.0;
    }
    m
}

#[test]
fn block_band_cholesky_agrees_with_nalgebra_dense() {
    for (nb, q, seed) in [(1, 0, 1), (4, 1, 2), (15, 5, 7), (40, 3, 11), (30, 29, 13)] {
        let a = spd(nb, q, seed);
        let n = 3 * nb;
        let dense = DMatrix::from_fn(n, n, |i, j| a.get(i, j));
        assert_eq!(dense, dense.transpose(), "get() is symmetric");
        let rhs = DVector::from_fn(n, |i, _| 1.0 + i as f64);
        let x_dense = dense.cholesky().expect("positive definite").solve(&rhs);
        let mut f = a.clone();
        f.factor().unwrap();
        let mut x: Vec<f64> = rhs.iter().copied().collect();
        f.solve_in_place(&mut x);
        for i in 0..n {
            let scale = x_dense[i].abs().max(1.0);
            assert!(
                (x[i] - x_dense[i]).abs() < 1e-13 * scale,
                "nb {nb}, q {q}: x[{i}] = {} (band) against {} (dense)",
                x[i],
                x_dense[i]
            );
        }
    }
}
