//! A symmetric positive-definite banded matrix and its Cholesky factorisation `A = L·Lᵀ`.
//!
//! A truss numbered level by level (see the `ordering` module) has a stiffness matrix whose
//! non-zeros lie within a half-bandwidth `p` of the diagonal (`p` = 17 for the paper's
//! prism), so factorising costs about `n·p²/2` multiply-adds and solving `2·n·p`: linear in
//! the number of stages, where a dense factorisation is cubic.
//!
//! Storage is row-major: row `i` holds columns `i−p ..= i` in `p + 1` consecutive slots, the
//! slots before column 0 being zero padding, so that every inner product is between two
//! contiguous slices. The inner products use four interleaved partial sums in a fixed order:
//! the result is the same on every machine and every run (no run-time SIMD dispatch).

/// The factorisation met a pivot that is not safely positive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite {
    /// Row (degree of freedom) of the pivot.
    pub index: usize,
    /// The pivot's value before the square root \[N/mm\].
    pub pivot: f64,
    /// The row's diagonal entry before factorisation \[N/mm\].
    pub diagonal: f64,
}

/// A pivot is refused when it is at most this fraction of its row's original diagonal: the
/// rounding noise of a singular (mechanism) direction is about 1e-15 of the diagonal, while
/// the softest physical direction of our models (a panel held only by slack cables with a
/// compression ratio of 1e-6) is above 1e-10.
pub const PIVOT_TOLERANCE: f64 = 1e-12;

/// A symmetric banded matrix, stored as its lower band, that can be factorised in place.
#[derive(Debug, Clone)]
pub struct BandMatrix {
    n: usize,
    p: usize,
    a: Vec<f64>,
    diag: Vec<f64>,
    inv_diag: Vec<f64>,
    factored: bool,
    min_pivot_ratio: f64,
}

impl BandMatrix {
    /// A zero `n × n` matrix of half-bandwidth `p`.
    pub fn new(n: usize, p: usize) -> Self {
        Self {
            n,
            p,
            a: vec![0.0; n * (p + 1)],
            diag: vec![0.0; n],
            inv_diag: vec![0.0; n],
            factored: false,
            min_pivot_ratio: f64::INFINITY,
        }
    }

    /// Order of the matrix.
    pub fn size(&self) -> usize {
        self.n
    }

    /// Half-bandwidth.
    pub fn bandwidth(&self) -> usize {
        self.p
    }

    /// Index in storage of entry `(i, j)`, `j ≤ i ≤ j + p`.
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(j <= i && i - j <= self.p, "({i}, {j}) outside the band");
        i * (self.p + 1) + j + self.p - i
    }

    /// Sets every entry to zero, ready for assembly.
    pub fn clear(&mut self) {
        self.a.fill(0.0);
        self.factored = false;
    }

    /// The storage, for assembly by precomputed indices (see [`BandMatrix::index`]).
    pub fn storage_mut(&mut self) -> &mut [f64] {
        self.factored = false;
        &mut self.a
    }

    /// Adds `v` to entry `(i, j)` (and so to `(j, i)`); `i, j` in either order.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        let k = self.index(i, j);
        self.a[k] += v;
        self.factored = false;
    }

    /// Entry `(i, j)` of the matrix (before factorisation), zero outside the band.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i - j > self.p {
            0.0
        } else {
            self.a[self.index(i, j)]
        }
    }

    /// Whether [`BandMatrix::factor`] has succeeded since the last change.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Factorises in place into `L` with `A = L·Lᵀ`.
    ///
    /// Row by row: `L_ij = (A_ij − Σ_k L_ik·L_jk) / L_jj` for `j < i`, and
    /// `L_ii = √(A_ii − Σ_k L_ik²)`, sums over `max(0, i−p) ≤ k < j`. Fails, naming the row,
    /// at the first pivot not above [`PIVOT_TOLERANCE`] times the row's diagonal.
    pub fn factor(&mut self) -> Result<(), NotPositiveDefinite> {
        let (n, p) = (self.n, self.p);
        let w = p + 1;
        for i in 0..n {
            self.diag[i] = self.a[i * w + p];
        }
        self.min_pivot_ratio = f64::INFINITY;
        for i in 0..n {
            let ri = i * w;
            let t0 = p.saturating_sub(i);
            for t in t0..p {
                let j = i + t - p;
                let rj = j * w;
                let s = self.a[ri + t]
                    - dot(&self.a[ri + t0..ri + t], &self.a[rj + t0 + p - t..rj + p]);
                self.a[ri + t] = s * self.inv_diag[j];
            }
            let row = &self.a[ri + t0..ri + p];
            let s = self.a[ri + p] - dot(row, row);
            if s.partial_cmp(&(PIVOT_TOLERANCE * self.diag[i])) != Some(std::cmp::Ordering::Greater)
            {
                return Err(NotPositiveDefinite {
                    index: i,
                    pivot: s,
                    diagonal: self.diag[i],
                });
            }
            self.min_pivot_ratio = self.min_pivot_ratio.min(s / self.diag[i]);
            let d = s.sqrt();
            self.a[ri + p] = d;
            self.inv_diag[i] = 1.0 / d;
        }
        self.factored = true;
        Ok(())
    }

    /// The smallest pivot of the last factorisation relative to its row's diagonal: near 1
    /// for a well-conditioned matrix, small where some direction is soft.
    pub fn min_pivot_ratio(&self) -> f64 {
        self.min_pivot_ratio
    }

    /// Solves `A·x = b` in place with the factor: `L·y = b`, then `Lᵀ·x = y`.
    ///
    /// # Panics
    /// If the matrix is not factorised, or `b` has the wrong length: both are bugs.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert!(self.factored, "solve with an unfactorised band matrix");
        assert_eq!(b.len(), self.n);
        let (n, p) = (self.n, self.p);
        let w = p + 1;
        for i in 0..n {
            let ri = i * w;
            let t0 = p.saturating_sub(i);
            let s = dot(&self.a[ri + t0..ri + p], &b[i + t0 - p..i]);
            b[i] = (b[i] - s) * self.inv_diag[i];
        }
        for i in (0..n).rev() {
            let ri = i * w;
            let t0 = p.saturating_sub(i);
            let x = b[i] * self.inv_diag[i];
            b[i] = x;
            for (bk, l) in b[i + t0 - p..i].iter_mut().zip(&self.a[ri + t0..ri + p]) {
                *bk -= l * x;
            }
        }
    }

    /// After [`BandMatrix::factor`] failed at row `i` with pivot `s ≤ 0`, writes into `v` the
    /// vector `[−A⁻¹b; 1; 0 …]` for which `vᵀKv = s` (`A` the leading `i × i` block, already
    /// factorised, `b` the column above the pivot): a direction of negative curvature when
    /// `s < 0`. Uses the failed row `i`, which holds `L⁻¹b`, and back-substitutes with `Lᵀ`.
    pub fn failed_pivot_direction(&self, i: usize, v: &mut [f64]) {
        let (n, p) = (self.n, self.p);
        assert!(!self.factored && i < n && v.len() >= n);
        let w = p + 1;
        v.fill(0.0);
        let ri = i * w;
        let t0 = p.saturating_sub(i);
        // y = L⁻¹b sits in row i, columns i−p+t0 .. i.
        v[i + t0 - p..i].copy_from_slice(&self.a[ri + t0..ri + p]);
        // Lᵀw = y, rows i−1 down to 0.
        for r in (0..i).rev() {
            let rr = r * w;
            let x = v[r] * self.inv_diag[r];
            v[r] = x;
            let t0r = p.saturating_sub(r);
            for (vk, l) in v[r + t0r - p..r].iter_mut().zip(&self.a[rr + t0r..rr + p]) {
                *vk -= l * x;
            }
        }
        for x in &mut v[..i] {
            *x = -*x;
        }
        v[i] = 1.0;
    }

    /// `y = A·x` with the matrix before factorisation (for tests and residual checks).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        assert!(!self.factored, "multiply with a factorised band matrix");
        y.fill(0.0);
        for i in 0..self.n {
            let lo = i.saturating_sub(self.p);
            for j in lo..=i {
                let v = self.a[self.index(i, j)];
                y[i] += v * x[j];
                if j != i {
                    y[j] += v * x[i];
                }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A random SPD band matrix: diagonally dominant with random off-diagonal entries.
    fn spd(n: usize, p: usize, seed: u64) -> BandMatrix {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        let mut m = BandMatrix::new(n, p);
        for i in 0..n {
            for j in i.saturating_sub(p)..i {
                m.add(i, j, next());
            }
        }
        for i in 0..n {
            let row: f64 = (0..n).map(|j| m.get(i, j).abs()).sum();
            m.add(i, i, row + 1.0 + next().abs());
        }
        m
    }

    /// Solve against the product: A·(A⁻¹b) = b, for bands narrower and wider than n.
    #[test]
    fn solves_match_products() {
        for (n, p) in [
            (1usize, 0usize),
            (5, 0),
            (9, 3),
            (45, 17),
            (30, 40),
            (200, 17),
        ] {
            let a = spd(n, p.min(n.saturating_sub(1)), n as u64 * 31 + p as u64);
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut f = a.clone();
            f.factor().unwrap();
            let mut x = b.clone();
            f.solve_in_place(&mut x);
            let mut ax = vec![0.0; n];
            a.mul(&x, &mut ax);
            for (u, v) in ax.iter().zip(&b) {
                assert!((u - v).abs() < 1e-12, "n={n} p={p}: {u} vs {v}");
            }
        }
    }

    /// Agrees with faer's dense Cholesky solve, an independent implementation.
    #[test]
    fn agrees_with_faer_dense() {
        use faer::Mat;
        use faer::linalg::solvers::Solve;
        let (n, p) = (45, 17);
        let a = spd(n, p, 7);
        let dense = Mat::<f64>::from_fn(n, n, |i, j| a.get(i, j));
        let llt = dense.llt(faer::Side::Lower).unwrap();
        let rhs = Mat::<f64>::from_fn(n, 1, |i, _| 1.0 + i as f64);
        let x_faer = llt.solve(&rhs);
        let mut f = a.clone();
        f.factor().unwrap();
        let mut x = (0..n).map(|i| 1.0 + i as f64).collect::<Vec<_>>();
        f.solve_in_place(&mut x);
        for i in 0..n {
            assert!((x[i] - x_faer[(i, 0)]).abs() < 1e-13 * x_faer[(i, 0)].abs().max(1.0));
        }
    }

    /// The direction from a failed pivot has exactly the pivot as its curvature.
    #[test]
    fn failed_pivot_direction_has_the_pivot_as_curvature() {
        let (n, p) = (12, 4);
        let mut a = spd(n, p, 3);
        a.add(7, 7, -a.get(7, 7) * 1.5);
        let original = a.clone();
        let err = a.factor().unwrap_err();
        let mut v = vec![0.0; n];
        a.failed_pivot_direction(err.index, &mut v);
        let mut av = vec![0.0; n];
        original.mul(&v, &mut av);
        let curvature: f64 = v.iter().zip(&av).map(|(x, y)| x * y).sum();
        assert!(err.pivot < 0.0);
        assert!(
            (curvature - err.pivot).abs() < 1e-9 * err.pivot.abs(),
            "{curvature} vs {}",
            err.pivot
        );
    }

    /// A singular matrix (a zero-stiffness direction) is refused at the right row.
    #[test]
    fn singular_is_refused_with_its_row() {
        // Two springs in series, 0–1–2, the middle node's y direction unrestrained.
        let mut m = BandMatrix::new(3, 2);
        m.add(0, 0, 2.0);
        m.add(1, 0, 0.0);
        m.add(2, 0, -1.0);
        m.add(2, 2, 2.0);
        let err = m.factor().unwrap_err();
        assert_eq!(err.index, 1);
    }
}
