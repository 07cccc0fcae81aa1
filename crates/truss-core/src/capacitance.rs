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
//!
//! Row `i` of `L` depends only on the leading `(i+1)×(i+1)` block of `C`. So when a new
//! matrix shares its leading rows with the last one factorised (the active-set method's
//! next slack set keeps its first cables), [`Capacitance::factor_from`] keeps those rows
//! of the factor and computes only the others: the factor is the same, bit for bit, as a
//! factorisation from the first row.

use crate::block::PIVOT_TOLERANCE;

/// A symmetric positive-definite matrix of order at most `capacity`, factorisable in place.
#[derive(Debug, Clone)]
pub(crate) struct Capacitance {
    stride: usize,
    m: usize,
    a: Vec<f64>,
    inv_diag: Vec<f64>,
    /// Each row's pivot relative to its diagonal entry.
    pivot_ratio: Vec<f64>,
    /// The number of leading rows that hold a valid factor.
    valid: usize,
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
            pivot_ratio: vec![0.0; capacity],
            valid: 0,
        }
    }

    /// Makes the matrix of order `m`, row `i`'s lower-triangle entries (columns `0 ..= i`)
    /// written by `fill(i, row)`, except the first `keep` rows, which are those of the last
    /// factorised one (at most [`Capacitance::valid_rows`]). Then [`Capacitance::factor_from`]`(keep)` factorises it.
    pub fn set_from(&mut self, keep: usize, m: usize, mut fill: impl FnMut(usize, &mut [f64])) {
        assert!(m <= self.stride, "capacitance matrix beyond its capacity");
        assert!(keep <= self.valid.min(m), "kept rows that hold no factor");
        self.m = m;
        self.valid = keep;
        for (i, row) in self
            .a
            .chunks_exact_mut(self.stride)
            .enumerate()
            .take(m)
            .skip(keep)
        {
            fill(i, &mut row[..=i]);
        }
    }

    /// The number of leading rows that hold a valid factor: all after a successful
    /// factorisation, those before the failed pivot after a failed one.
    pub fn valid_rows(&self) -> usize {
        self.valid
    }

    /// Factorises in place, `C = L·Lᵀ`, the first `keep` rows being already factorised
    /// (see [`Capacitance::set_from`]); fails at the first pivot not above
    /// [`PIVOT_TOLERANCE`] times its diagonal entry.
    pub fn factor_from(&mut self, keep: usize) -> Result<(), NotPositiveDefinite> {
        let (m, w) = (self.m, self.stride);
        assert!(keep <= self.valid, "kept rows that hold no factor");
        self.valid = keep;
        let mut i = keep;
        // Two rows at a time where there are two: row i + 1's entries left of column i need
        // only the rows above i, so the two rows' chains of dependent inner products
        // interleave. Each entry is the same expression, in the same order, as one row at
        // a time: the same bits.
        while i + 1 < m {
            let (done, rest) = self.a.split_at_mut(i * w);
            let (row, next) = rest.split_at_mut(w);
            let (row, next) = (&mut row[..=i], &mut next[..=i + 1]);
            for (j, (row_j, inv)) in done.chunks_exact(w).zip(&self.inv_diag).enumerate() {
                let s = row[j] - dot(&row[..j], &row_j[..j]);
                let t = next[j] - dot(&next[..j], &row_j[..j]);
                row[j] = s * inv;
                next[j] = t * inv;
            }
            pivot(i, row, &mut self.pivot_ratio, &mut self.inv_diag)?;
            self.valid = i + 1;
            let t = next[i] - dot(&next[..i], &row[..i]);
            next[i] = t * self.inv_diag[i];
            pivot(i + 1, next, &mut self.pivot_ratio, &mut self.inv_diag)?;
            self.valid = i + 2;
            i += 2;
        }
        if i < m {
            let (done, rest) = self.a.split_at_mut(i * w);
            let row = &mut rest[..=i];
            for (j, (row_j, inv)) in done.chunks_exact(w).zip(&self.inv_diag).enumerate() {
                let s = row[j] - dot(&row[..j], &row_j[..j]);
                row[j] = s * inv;
            }
            pivot(i, row, &mut self.pivot_ratio, &mut self.inv_diag)?;
            self.valid = i + 1;
        }
        Ok(())
    }

    /// The number of rows of the last factorisation whose pivot is below `ratio` times its
    /// diagonal entry: each marks one soft direction of `C`.
    pub fn soft_rows(&self, ratio: f64) -> usize {
        self.pivot_ratio[..self.valid]
            .iter()
            .filter(|&&p| p < ratio)
            .count()
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

/// Row `i`'s pivot, its entries left of the diagonal factorised: `L_ii`, its inverse and its
/// ratio to the diagonal entry; fails at a pivot not above [`PIVOT_TOLERANCE`] times it.
#[inline(always)]
fn pivot(
    i: usize,
    row: &mut [f64],
    pivot_ratio: &mut [f64],
    inv_diag: &mut [f64],
) -> Result<(), NotPositiveDefinite> {
    let diag = row[i];
    let s = diag - dot(&row[..i], &row[..i]);
    if s.partial_cmp(&(PIVOT_TOLERANCE * diag)) != Some(std::cmp::Ordering::Greater) {
        return Err(NotPositiveDefinite);
    }
    pivot_ratio[i] = s / diag;
    let d = s.sqrt();
    row[i] = d;
    inv_diag[i] = 1.0 / d;
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Row `i`, column `j ≤ i` of a symmetric positive-definite test matrix: `B·Bᵀ + n·I`
    /// with `B` of pseudo-random entries in (−1, 1) drawn per `(i, j)` from `seed`.
    fn entry(seed: u64, i: usize, j: usize, n: usize) -> f64 {
        let b = |r: usize, k: usize| {
            let mut x = seed ^ ((r as u64) << 32 | k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            x = (x ^ (x >> 31)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x ^= x >> 29;
            (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let dot: f64 = (0..n).map(|k| b(i, k) * b(j, k)).sum();
        dot + if i == j { n as f64 } else { 0.0 }
    }

    /// A factor of order `m` whose first `keep` rows come from the matrix of `seed_a`
    /// (which holds rows `0..keep` of the result) and the others from `seed_b`.
    fn matrix(keep: usize, seed_a: u64, seed_b: u64) -> impl Fn(usize, &mut [f64]) {
        move |i, row: &mut [f64]| {
            for (j, x) in row.iter_mut().enumerate() {
                *x = entry(if i < keep { seed_a } else { seed_b }, i, j, 12);
            }
        }
    }

    #[test]
    fn a_kept_leading_block_gives_the_same_factor_bit_for_bit() {
        let mut reused = Capacitance::new(12);
        reused.set_from(0, 10, matrix(10, 1, 1));
        reused.factor_from(0).unwrap();
        // The next matrix shares its first 6 rows and differs after them.
        let next = |i: usize, row: &mut [f64]| {
            for (j, x) in row.iter_mut().enumerate() {
                *x = entry(if i < 6 { 1 } else { 2 }, i, j, 12);
            }
        };
        reused.set_from(6, 11, next);
        reused.factor_from(6).unwrap();
        let mut fresh = Capacitance::new(12);
        fresh.set_from(0, 11, next);
        fresh.factor_from(0).unwrap();
        for i in 0..11 {
            for j in 0..=i {
                let (a, b) = (reused.a[i * 12 + j], fresh.a[i * 12 + j]);
                assert_eq!(a.to_bits(), b.to_bits(), "L[{i}][{j}]: {a} vs {b}");
            }
        }
        assert_eq!(reused.pivot_ratio[..11], fresh.pivot_ratio[..11]);
        let mut x = (0..11).map(|i| i as f64 - 4.5).collect::<Vec<_>>();
        let mut y = x.clone();
        reused.solve_in_place(&mut x);
        fresh.solve_in_place(&mut y);
        assert_eq!(x, y);
    }

    /// The factor, one row at a time as the module doc writes it: the reference that
    /// [`Capacitance::factor_from`]'s two rows at a time must match bit for bit.
    fn one_row_at_a_time(c: &mut [f64], m: usize) {
        for i in 0..m {
            for j in 0..i {
                let s = c[i * m + j] - dot(&c[i * m..i * m + j], &c[j * m..j * m + j]);
                c[i * m + j] = s * (1.0 / c[j * m + j]);
            }
            let s = c[i * m + i] - dot(&c[i * m..i * m + i], &c[i * m..i * m + i]);
            c[i * m + i] = s.sqrt();
        }
    }

    #[test]
    fn two_rows_at_a_time_give_the_one_row_factor_bit_for_bit() {
        for m in [1, 2, 5, 8, 11, 12] {
            let mut c = Capacitance::new(12);
            c.set_from(0, m, matrix(m, 4, 4));
            c.factor_from(0).unwrap();
            let mut reference = vec![0.0; m * m];
            for i in 0..m {
                matrix(m, 4, 4)(i, &mut reference[i * m..i * m + i + 1]);
            }
            one_row_at_a_time(&mut reference, m);
            for i in 0..m {
                for j in 0..=i {
                    let (a, b) = (c.a[i * 12 + j], reference[i * m + j]);
                    assert_eq!(a.to_bits(), b.to_bits(), "m {m}: L[{i}][{j}] {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn a_failed_pivot_leaves_the_rows_before_it_valid() {
        let mut c = Capacitance::new(12);
        // Row 4's diagonal is made too small: the factorisation stops there.
        c.set_from(0, 8, |i, row: &mut [f64]| {
            matrix(8, 3, 3)(i, row);
            if i == 4 {
                row[4] = 1e-3;
            }
        });
        assert_eq!(c.factor_from(0), Err(NotPositiveDefinite));
        assert_eq!(c.valid_rows(), 4);
        c.set_from(4, 8, matrix(8, 3, 3));
        c.factor_from(4).unwrap();
        let mut fresh = Capacitance::new(12);
        fresh.set_from(0, 8, matrix(8, 3, 3));
        fresh.factor_from(0).unwrap();
        assert_eq!(c.a[..8 * 12], fresh.a[..8 * 12]);
        assert_eq!(c.valid_rows(), 8);
    }
}
