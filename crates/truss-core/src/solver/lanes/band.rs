//! The block-banded Cholesky factorisation and its triangular solves for `W` samples at once
//! (see [`crate::block`]): every block a 3×3 block of lanes, `[[[f64; W]; 3]; 3]`.
//!
//! Each lane performs exactly the IEEE operations of [`BlockBandMatrix::factor`] and
//! [`BlockBandMatrix::solve_in_place`], in the same order (the one-sample factorisation
//! computes a block's three rows side by side, but each entry by the same expression as one
//! entry at a time, as this one does). A lane whose factorisation meets a pivot that is not safely
//! positive is factorised again by the one-sample code from its own, untouched matrix: that
//! rare case (a negative curvature, a damped step) keeps the one-sample path's bits and its
//! record of failed pivots by construction.
//!
//! A lane's factor stays in the lanes after its factorisation, so the solves with it (a
//! step reuses its factorisation while the steps contract) gather only the right-hand
//! side; a factor made elsewhere is gathered once, known by its matrix's identity.
//!
//! Units as in [`crate::block`]: stiffness entries \[N/mm\], right-hand sides \[N\],
//! solutions \[mm\].

use super::lane::lanes;
use crate::block::{BlockBandMatrix, PIVOT_TOLERANCE, PivotFailure};

/// A 3×3 block of `W` lanes.
type BlockLanes<const W: usize> = [[[f64; W]; 3]; 3];

/// The lanes' band, factors and right-hand sides, kept between calls.
#[derive(Debug)]
pub(super) struct BandLanes<const W: usize> {
    arch: pulp::Arch,
    nb: usize,
    q: usize,
    diag: Vec<[[f64; W]; 3]>,
    /// The factors the lanes hold, for their solves (a lane's band while it is factorised).
    a: Vec<BlockLanes<W>>,
    inv: Vec<[[f64; W]; 3]>,
    x: Vec<[[f64; W]; 3]>,
    /// The identity of the matrix whose factor each lane holds.
    holds: [Option<(u64, u64)>; W],
    /// Each lane's failed pivots of the last factorisation.
    records: [Vec<PivotFailure>; W],
}

/// A factorisation a lane waits for: its matrix, where its failed pivots go, and how many
/// to collect (see [`BlockBandMatrix::factor_collecting`]).
pub(super) type FactorLane<'a> = (&'a mut BlockBandMatrix, &'a mut Vec<PivotFailure>, usize);

/// A solve a lane waits for: its factorised matrix and its right-hand side (the first
/// `3·blocks` entries are solved).
pub(super) type SolveLane<'a> = (&'a BlockBandMatrix, &'a mut [f64]);

impl<const W: usize> BandLanes<W> {
    /// Buffers for matrices of `nb` block rows and block half-bandwidth `q`; every lane
    /// starts as the identity (so that an empty lane computes finite numbers).
    pub(super) fn new(nb: usize, q: usize, arch: pulp::Arch) -> Self {
        let mut a = vec![[[[0.0; W]; 3]; 3]; nb * (q + 1)];
        for row in a.chunks_exact_mut(q + 1) {
            for (d, r) in row[q].iter_mut().enumerate() {
                r[d] = [1.0; W];
            }
        }
        Self {
            arch,
            nb,
            q,
            a,
            diag: vec![[[1.0; W]; 3]; nb],
            inv: vec![[[1.0; W]; 3]; nb],
            x: vec![[[0.0; W]; 3]; nb],
            holds: [None; W],
            records: std::array::from_fn(|_| Vec::new()),
        }
    }

    /// Factorises each lane's matrix (see the module doc); a lane's result is its
    /// matrix's, and its failed pivots, as [`BlockBandMatrix::factor_collecting`] leaves
    /// them.
    pub(super) fn factor(&mut self, lanes: &mut [Option<FactorLane<'_>>; W]) {
        let w = self.q + 1;
        let mut mask = [false; W];
        let mut tolerance = [PIVOT_TOLERANCE; W];
        let mut max = [0usize; W];
        for (l, lane) in lanes.iter().enumerate() {
            let Some((m, _, most)) = lane else {
                continue;
            };
            gather(&mut self.a, m.factor_parts().0, l);
            mask[l] = true;
            tolerance[l] = m.pivot_tolerance();
            max[l] = *most;
            self.holds[l] = None;
        }
        for (d, row) in self.diag.iter_mut().zip(self.a.chunks_exact(w)) {
            let a = &row[self.q];
            *d = [a[0][0], a[1][1], a[2][2]];
        }
        for record in &mut self.records {
            record.clear();
        }
        let rows = self.arch.dispatch(Factor {
            nb: self.nb,
            q: self.q,
            mask,
            tolerance,
            max,
            records: &mut self.records,
            a: &mut self.a,
            diag: &self.diag,
            inv: &mut self.inv,
        });
        for (l, lane) in lanes.iter_mut().enumerate() {
            let Some((m, failures, _)) = lane else {
                continue;
            };
            failures.clear();
            failures.extend_from_slice(&self.records[l]);
            let (a, diag, inv) = (&self.a, &self.diag, &self.inv);
            let done = rows[l];
            m.install_factor(!failures.is_empty(), |blocks, d, i| {
                scatter(blocks, a, l);
                for (dk, dl) in d.iter_mut().zip(diag) {
                    *dk = [dl[0][l], dl[1][l], dl[2][l]];
                }
                // The rows after a stop keep their inverse pivots, as the one-sample code
                // leaves them.
                for (ik, il) in i.iter_mut().zip(inv).take(done) {
                    *ik = [il[0][l], il[1][l], il[2][l]];
                }
            });
            self.holds[l] = Some(m.identity());
        }
    }

    /// Lane `l` holds the factor of `m` (factorised).
    fn hold(&mut self, m: &BlockBandMatrix, l: usize) {
        let (blocks, inv) = m.factor_parts();
        gather(&mut self.a, blocks, l);
        for (il, i) in self.inv.iter_mut().zip(inv) {
            for k in 0..3 {
                il[k][l] = i[k];
            }
        }
        self.holds[l] = Some(m.identity());
    }

    /// The lane that holds the factor of the matrix whose identity is `id`, if one does.
    pub(super) fn lane_holding(&self, id: (u64, u64)) -> Option<usize> {
        self.holds.iter().position(|&h| h == Some(id))
    }

    /// Solves each lane's system with its matrix's factor, in place.
    ///
    /// # Panics
    /// If a lane's matrix is not factorised (a bug in the caller).
    pub(super) fn solve(&mut self, lanes: &mut [Option<SolveLane<'_>>; W]) {
        for (l, lane) in lanes.iter().enumerate() {
            let Some((m, b)) = lane else {
                continue;
            };
            assert!(m.is_factored(), "solve with an unfactorised matrix");
            if self.holds[l] != Some(m.identity()) {
                self.hold(m, l);
            }
            for (xl, bk) in self.x.iter_mut().zip(b.chunks_exact(3)) {
                for k in 0..3 {
                    xl[k][l] = bk[k];
                }
            }
        }
        self.arch.dispatch(Solve {
            nb: self.nb,
            q: self.q,
            a: &self.a,
            inv: &self.inv,
            x: &mut self.x,
        });
        for (l, lane) in lanes.iter_mut().enumerate() {
            let Some((_, b)) = lane else {
                continue;
            };
            for (xl, bk) in self.x.iter().zip(b.chunks_exact_mut(3)) {
                for k in 0..3 {
                    bk[k] = xl[k][l];
                }
            }
        }
    }
}

/// Lane `l` of `lanes` = `blocks`.
fn gather<const W: usize>(lanes: &mut [BlockLanes<W>], blocks: &[crate::block::Block], l: usize) {
    let to = lanes.as_flattened_mut().as_flattened_mut();
    for (x, b) in to.iter_mut().zip(blocks.as_flattened().as_flattened()) {
        x[l] = *b;
    }
}

/// `blocks` = lane `l` of `lanes`.
fn scatter<const W: usize>(blocks: &mut [crate::block::Block], lanes: &[BlockLanes<W>], l: usize) {
    let from = lanes.as_flattened().as_flattened();
    for (b, x) in blocks
        .as_flattened_mut()
        .as_flattened_mut()
        .iter_mut()
        .zip(from)
    {
        *b = x[l];
    }
}

/// The factorisation's arguments, for `pulp`'s dispatch (compiled once per instruction set).
struct Factor<'k, const W: usize> {
    nb: usize,
    q: usize,
    /// The lanes factorised: the others keep the factors they hold. A lane that has met
    /// its most failures stops after that block row, as the one-sample factorisation does.
    mask: [bool; W],
    /// Each lane's pivot tolerance (see [`BlockBandMatrix::factor_collecting`]).
    tolerance: [f64; W],
    /// Each lane's most failures to record before it stops.
    max: [usize; W],
    /// Each lane's failed pivots, in order.
    records: &'k mut [Vec<PivotFailure>; W],
    a: &'k mut [BlockLanes<W>],
    diag: &'k [[[f64; W]; 3]],
    inv: &'k mut [[[f64; W]; 3]],
}

impl<const W: usize> pulp::WithSimd for Factor<'_, W> {
    /// Each lane's block rows factorised (all, unless it stopped).
    type Output = [usize; W];

    /// [`BlockBandMatrix::factor_collecting`] one block row at a time, lane by lane: a
    /// pivot not above its lane's tolerance times its row's diagonal is recorded and
    /// replaced by that diagonal, as the one-sample code does.
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> [usize; W] {
        let (q, w) = (self.q, self.q + 1);
        let mut mask = self.mask;
        let mut rows = [self.nb; W];
        for i in 0..self.nb {
            if !mask.iter().any(|&m| m) {
                break;
            }
            let j0 = i.saturating_sub(q);
            let first = q - (i - j0);
            let (done, from_i) = self.a.split_at_mut(i * w);
            let row = &mut from_i[..w];
            for (n, row_j) in done[j0 * w..].chunks_exact(w).enumerate() {
                off_diagonal(row, first, n, row_j, &self.inv[j0 + n], q, &mask);
            }
            let inv = diagonal(
                row,
                first,
                i,
                &self.diag[i],
                &self.tolerance,
                self.records,
                &mask,
            );
            self.inv[i] = select3(&mask, inv, self.inv[i]);
            for (l, m) in mask.iter_mut().enumerate() {
                if *m && self.records[l].len() >= self.max[l] {
                    *m = false;
                    rows[l] = i + 1;
                }
            }
        }
        rows
    }
}

/// `L_ij = (A_ij − Σ_k L_ik·L_jkᵀ)·L_jj⁻ᵀ` (see `block::off_diagonal`).
#[inline(always)]
fn off_diagonal<const W: usize>(
    row: &mut [BlockLanes<W>],
    first: usize,
    n: usize,
    row_j: &[BlockLanes<W>],
    inv: &[[f64; W]; 3],
    q: usize,
    mask: &[bool; W],
) {
    let (left, at) = row.split_at_mut(first + n);
    let old = at[0];
    let mut s = at[0];
    for (x, y) in left[first..].iter().zip(&row_j[q - n..q]) {
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] = lanes(|l| {
                    s[r][c][l]
                        - (x[r][0][l] * y[c][0][l]
                            + x[r][1][l] * y[c][1][l]
                            + x[r][2][l] * y[c][2][l])
                });
            }
        }
    }
    let ljj = &row_j[q];
    for r in &mut s {
        let x0 = lanes(|l| r[0][l] * inv[0][l]);
        let x1 = lanes(|l| (r[1][l] - ljj[1][0][l] * x0[l]) * inv[1][l]);
        let x2 = lanes(|l| (r[2][l] - ljj[2][0][l] * x0[l] - ljj[2][1][l] * x1[l]) * inv[2][l]);
        *r = [x0, x1, x2];
    }
    at[0] = [
        select3(mask, s[0], old[0]),
        select3(mask, s[1], old[1]),
        select3(mask, s[2], old[2]),
    ];
}

/// Lane by lane, `new` where `mask`, else `old`.
#[inline(always)]
fn select3<const W: usize>(
    mask: &[bool; W],
    new: [[f64; W]; 3],
    old: [[f64; W]; 3],
) -> [[f64; W]; 3] {
    std::array::from_fn(|k| lanes(|l| if mask[l] { new[k][l] } else { old[k][l] }))
}

/// `L_ii = chol(A_ii − Σ_k L_ik·L_ikᵀ)` (see `block::diagonal`): a lane's pivot not above
/// its tolerance times its row's diagonal (NaN included, as the one-sample test reads) is
/// recorded for that lane and replaced by the diagonal's magnitude; returns the inverse
/// pivots.
#[inline(always)]
fn diagonal<const W: usize>(
    row: &mut [BlockLanes<W>],
    first: usize,
    i: usize,
    diag: &[[f64; W]; 3],
    tolerance: &[f64; W],
    records: &mut [Vec<PivotFailure>; W],
    mask: &[bool; W],
) -> [[f64; W]; 3] {
    let q = row.len() - 1;
    let (left, at) = row.split_at_mut(q);
    let old = at[0];
    let mut s = at[0];
    for x in &left[first..] {
        for r in 0..3 {
            for c in 0..=r {
                s[r][c] = lanes(|l| {
                    s[r][c][l]
                        - (x[r][0][l] * x[c][0][l]
                            + x[r][1][l] * x[c][1][l]
                            + x[r][2][l] * x[c][2][l])
                });
            }
        }
    }
    let mut pivot = |k: usize, mut p: [f64; W]| -> [f64; W] {
        for l in 0..W {
            let above = p[l] > tolerance[l] * diag[k][l];
            if mask[l] && !above {
                records[l].push(PivotFailure {
                    index: 3 * i + k,
                    pivot: p[l],
                });
                p[l] = diag[k][l].abs().max(f64::MIN_POSITIVE);
            }
        }
        p
    };
    let p0 = pivot(0, s[0][0]);
    let l00 = p0.map(f64::sqrt);
    let i0 = l00.map(|x| 1.0 / x);
    let l10 = lanes(|l| s[1][0][l] * i0[l]);
    let l20 = lanes(|l| s[2][0][l] * i0[l]);
    let p1 = pivot(1, lanes(|l| s[1][1][l] - l10[l] * l10[l]));
    let l11 = p1.map(f64::sqrt);
    let i1 = l11.map(|x| 1.0 / x);
    let l21 = lanes(|l| (s[2][1][l] - l20[l] * l10[l]) * i1[l]);
    let p2 = pivot(2, lanes(|l| s[2][2][l] - l20[l] * l20[l] - l21[l] * l21[l]));
    let l22 = p2.map(f64::sqrt);
    let zero = [0.0; W];
    let l = [[l00, zero, zero], [l10, l11, zero], [l20, l21, l22]];
    at[0] = [
        select3(mask, l[0], old[0]),
        select3(mask, l[1], old[1]),
        select3(mask, l[2], old[2]),
    ];
    [i0, i1, l22.map(|x| 1.0 / x)]
}

/// The solve's arguments, for `pulp`'s dispatch.
struct Solve<'k, const W: usize> {
    nb: usize,
    q: usize,
    a: &'k [BlockLanes<W>],
    inv: &'k [[[f64; W]; 3]],
    x: &'k mut [[[f64; W]; 3]],
}

impl<const W: usize> pulp::WithSimd for Solve<'_, W> {
    type Output = ();

    /// [`BlockBandMatrix::solve_in_place`], lane by lane: `L·y = b`, then `Lᵀ·x = y`.
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let (q, w) = (self.q, self.q + 1);
        let x = self.x;
        for i in 0..self.nb {
            let row = &self.a[i * w..(i + 1) * w];
            let inv = &self.inv[i];
            let j0 = i.saturating_sub(q);
            let (done, at) = x.split_at_mut(i);
            let mut y = at[0];
            for (l, xk) in row[q - (i - j0)..q].iter().zip(&done[j0..]) {
                for (r, yr) in y.iter_mut().enumerate() {
                    *yr = lanes(|k| {
                        yr[k]
                            - (l[r][0][k] * xk[0][k]
                                + l[r][1][k] * xk[1][k]
                                + l[r][2][k] * xk[2][k])
                    });
                }
            }
            let d = &row[q];
            let y0 = lanes(|k| y[0][k] * inv[0][k]);
            let y1 = lanes(|k| (y[1][k] - d[1][0][k] * y0[k]) * inv[1][k]);
            let y2 = lanes(|k| (y[2][k] - d[2][0][k] * y0[k] - d[2][1][k] * y1[k]) * inv[2][k]);
            at[0] = [y0, y1, y2];
        }
        for i in (0..self.nb).rev() {
            let row = &self.a[i * w..(i + 1) * w];
            let inv = &self.inv[i];
            let j0 = i.saturating_sub(q);
            let (below, at) = x.split_at_mut(i);
            let d = &row[q];
            let y = at[0];
            let x2 = lanes(|k| y[2][k] * inv[2][k]);
            let x1 = lanes(|k| (y[1][k] - d[2][1][k] * x2[k]) * inv[1][k]);
            let x0 = lanes(|k| (y[0][k] - d[1][0][k] * x1[k] - d[2][0][k] * x2[k]) * inv[0][k]);
            at[0] = [x0, x1, x2];
            for (l, xk) in row[q - (i - j0)..q].iter().zip(&mut below[j0..]) {
                for (c, xc) in xk.iter_mut().enumerate() {
                    *xc = lanes(|k| {
                        xc[k] - (l[0][c][k] * x0[k] + l[1][c][k] * x1[k] + l[2][c][k] * x2[k])
                    });
                }
            }
        }
    }
}
