//! The capacitance matrix of the linearised problem's Woodbury updates, `C = W⁻¹ − G_SS`
//! over the slack set `S` (see the `linearised` module), and its dense Cholesky factor.
//!
//! `C` is at most `n_c × n_c` (`n_c` the cables of the model) and changes size with the
//! slack set, so it lives in storage sized once for `n_c`: row `i` at `i·n_c`, columns
//! `0 ..= i`. The factorisation is row by row,
//!
//! ```text
//! L_ij = (C_ij − Σ_{k<j} L_ik·L_jk) / L_jj   (j < i),     L_ii = √(C_ii − Σ_{k<i} L_ik²)
//! ```
//!
//! with inner products of four interleaved partial sums ([`dot`], in a fixed summation
//! order), so the factor is the one of a banded Cholesky of full bandwidth, without its
//! padding and without allocating when the slack set changes.

use crate::block::PIVOT_TOLERANCE;

/// A symmetric positive-definite matrix of order at most `capacity`, factorisable in place.
#[derive(Debug, Clone)]
pub(crate) struct Capacitance {
    stride: usize,
    m: usize,
    a: Vec<f64>,
    inv_diag: Vec<f64>,
    min_pivot_ratio: f64,
}

/// `C` is not positive definite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NotPositiveDefinite;

impl Capacitance {
    /// Storage for orders up to `capacity`.
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            stride: capacity,
            m: 0,
            a: vec![0.0; capacity * capacity],
            inv_diag: vec![0.0; capacity],
            min_pivot_ratio: f64::INFINITY,
        }
    }

    /// Makes the matrix of order `m`, row `i`'s lower-triangle entries (columns `0 ..= i`)
    /// written by `fill(i, row)`.
    pub fn set(&mut self, m: usize, mut fill: impl FnMut(usize, &mut [f64])) {
        assert!(m <= self.stride, "capacitance matrix beyond its capacity");
        self.m = m;
        for (i, row) in self.a.chunks_exact_mut(self.stride).take(m).enumerate() {
            fill(i, &mut row[..=i]);
        }
    }

    /// Factorises in place, `C = L·Lᵀ`; fails at the first pivot not above
    /// [`PIVOT_TOLERANCE`] times its diagonal entry.
    pub fn factor(&mut self) -> Result<(), NotPositiveDefinite> {
        let (m, w) = (self.m, self.stride);
        self.min_pivot_ratio = f64::INFINITY;
        for i in 0..m {
            let (done, rest) = self.a.split_at_mut(i * w);
            let row = &mut rest[..=i];
            for (j, (row_j, inv)) in done.chunks_exact(w).zip(&self.inv_diag).enumerate() {
                let s = row[j] - dot(&row[..j], &row_j[..j]);
                row[j] = s * inv;
            }
            let diag = row[i];
            let s = diag - dot(&row[..i], &row[..i]);
            if s.partial_cmp(&(PIVOT_TOLERANCE * diag)) != Some(std::cmp::Ordering::Greater) {
                return Err(NotPositiveDefinite);
            }
            self.min_pivot_ratio = self.min_pivot_ratio.min(s / diag);
            let d = s.sqrt();
            row[i] = d;
            self.inv_diag[i] = 1.0 / d;
        }
        Ok(())
    }

    /// The smallest pivot of the last factorisation relative to its diagonal entry.
    pub fn min_pivot_ratio(&self) -> f64 {
        self.min_pivot_ratio
    }

    /// Solves `C·x = b` in place with the factor (`b` of the order of the matrix):
    /// `L·y = b`, then `Lᵀ·x = y`.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let (m, w) = (self.m, self.stride);
        assert_eq!(b.len(), m);
        for (i, (row, inv)) in self
            .a
            .chunks_exact(w)
            .zip(&self.inv_diag)
            .enumerate()
            .take(m)
        {
            let (done, at) = b.split_at_mut(i);
            at[0] = (at[0] - dot(&row[..i], done)) * inv;
        }
        for (i, (row, inv)) in self
            .a
            .chunks_exact(w)
            .zip(&self.inv_diag)
            .enumerate()
            .take(m)
            .rev()
        {
            let (below, at) = b.split_at_mut(i);
            let x = at[0] * inv;
            at[0] = x;
            for (bk, l) in below.iter_mut().zip(&row[..i]) {
                *bk -= l * x;
            }
        }
    }
}

/// Inner product with four interleaved partial sums, summed in a fixed order.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut s = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    for (x, y) in ra.iter().zip(rb) {
        s[0] += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}
