//! The stiffness matrix as a banded matrix of 3×3 node blocks, and its block Cholesky
//! factorisation `A = L·Lᵀ`.
//!
//! Every node has three directions, so the tangent stiffness of a truss is naturally a matrix
//! of 3×3 blocks, non-zero where two nodes share a member. With the nodes numbered by
//! reverse Cuthill–McKee (see the `ordering` module) the blocks lie within a block
//! half-bandwidth `q` of the diagonal (`q` = 5 for the paper's prism: each level's three
//! nodes meet all of the next level's), so factorising costs about `N·q²/2` block products
//! of 27 multiply-adds and solving `2·N·q` block-vector products: linear in the number of
//! stages. Fixed-size blocks let the compiler unroll every block product, which is what
//! makes this several times faster than a scalar band of the same width. The factorisation
//! computes the three rows of a block side by side (a block row's blocks kept as padded
//! columns while the row is factorised: one AVX2 operation per column where the processor
//! has it), each entry by the same expression in the same order as one entry at a time, so
//! the bits do not depend on the instruction set.
//!
//! A fixed direction of a node that has free ones keeps its row, as an identity row with no
//! coupling, so that all blocks are 3×3.
//!
//! Block row `I` stores blocks `J = I − q ..= I` in `q + 1` consecutive slots (slots before
//! block 0 are zero padding). All arithmetic is in a fixed order: the same bits on every
//! machine and every run.

/// A 3×3 block, row-major.
pub type Block = [[f64; 3]; 3];

/// The factorisation met a pivot that is not safely positive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PivotFailure {
    /// Scalar row (3·node + direction) of the pivot.
    pub index: usize,
    /// The pivot's value before the square root \[N/mm\].
    pub pivot: f64,
}

/// A pivot is refused when it is at most this fraction of its row's original diagonal: the
/// rounding noise of a singular (mechanism) direction is about 1e-15 of the diagonal, while
/// the softest physical direction of our models (a panel held only by slack cables with a
/// compression ratio of 1e-6) is above 1e-10.
pub const PIVOT_TOLERANCE: f64 = 1e-12;

/// A symmetric block-banded matrix, stored as its lower block band, factorisable in place.
#[derive(Debug)]
pub struct BlockBandMatrix {
    nb: usize,
    q: usize,
    a: Vec<Block>,
    diag: Vec<[f64; 3]>,
    inv_diag: Vec<[f64; 3]>,
    factored: bool,
    /// A pivot at most this fraction of its row's diagonal fails (default
    /// [`PIVOT_TOLERANCE`]).
    tolerance: f64,
    /// Which matrix this is, and how many times its numbers changed: a batched solve's
    /// copy of the factor is reused while both match (see `solver::lanes`).
    id: u64,
    version: u64,
}

/// The next matrix's number (see `BlockBandMatrix::id`).
static MATRICES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn next_id() -> u64 {
    MATRICES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Clone for BlockBandMatrix {
    /// A copy with the same numbers, and a number of its own.
    fn clone(&self) -> Self {
        Self {
            nb: self.nb,
            q: self.q,
            a: self.a.clone(),
            diag: self.diag.clone(),
            inv_diag: self.inv_diag.clone(),
            factored: self.factored,
            tolerance: self.tolerance,
            id: next_id(),
            version: 0,
        }
    }
}

const ZERO: Block = [[0.0; 3]; 3];

impl BlockBandMatrix {
    /// A zero matrix of `nb` block rows and block half-bandwidth `q`.
    pub fn new(nb: usize, q: usize) -> Self {
        Self {
            nb,
            q,
            a: vec![ZERO; nb * (q + 1)],
            diag: vec![[0.0; 3]; nb],
            inv_diag: vec![[0.0; 3]; nb],
            factored: false,
            tolerance: PIVOT_TOLERANCE,
            id: next_id(),
            version: 0,
        }
    }

    /// Sets the fraction of its row's diagonal at or below which a pivot fails.
    pub(crate) fn set_pivot_tolerance(&mut self, tolerance: f64) {
        self.tolerance = tolerance;
    }

    /// The fraction of its row's diagonal at or below which a pivot fails.
    pub(crate) fn pivot_tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The numbers changed: not factorised, and a new version.
    #[inline]
    fn touched(&mut self) {
        self.factored = false;
        self.version += 1;
    }

    /// This matrix's number and version: the same pair, the same numbers.
    pub(crate) fn identity(&self) -> (u64, u64) {
        (self.id, self.version)
    }

    /// The blocks (the factor once factorised), and the factor's inverse pivots.
    pub(crate) fn factor_parts(&self) -> (&[Block], &[[f64; 3]]) {
        (&self.a, &self.inv_diag)
    }

    /// Installs a factor computed elsewhere (the batched factorisation, bit for bit
    /// [`BlockBandMatrix::factor_collecting`]'s): `fill` writes the blocks, each row's
    /// original diagonal and the inverse pivots; the matrix is then factorised unless some
    /// pivot failed (`failed`), as `factor_collecting` leaves it.
    pub(crate) fn install_factor(
        &mut self,
        failed: bool,
        fill: impl FnOnce(&mut [Block], &mut [[f64; 3]], &mut [[f64; 3]]),
    ) {
        fill(&mut self.a, &mut self.diag, &mut self.inv_diag);
        self.touched();
        self.factored = !failed;
    }

    /// Number of block rows.
    pub fn blocks(&self) -> usize {
        self.nb
    }

    /// Scalar order, `3·blocks`.
    pub fn size(&self) -> usize {
        3 * self.nb
    }

    /// Block half-bandwidth.
    pub fn bandwidth(&self) -> usize {
        self.q
    }

    /// Slot of block `(i, j)`, `j ≤ i ≤ j + q`.
    #[inline]
    pub fn slot(&self, i: usize, j: usize) -> usize {
        debug_assert!(
            j <= i && i - j <= self.q,
            "block ({i}, {j}) outside the band"
        );
        i * (self.q + 1) + j + self.q - i
    }

    /// Sets every entry to zero, ready for assembly.
    pub fn clear(&mut self) {
        self.a.as_flattened_mut().as_flattened_mut().fill(0.0);
        self.touched();
    }

    /// The blocks, for assembly by precomputed slots (see [`BlockBandMatrix::slot`]).
    #[inline]
    pub fn storage_mut(&mut self) -> &mut [Block] {
        self.touched();
        &mut self.a
    }

    /// Multiplies every diagonal entry by `factor` (a Levenberg shift `1 + μ`).
    pub fn scale_diagonal(&mut self, factor: f64) {
        self.scale_diagonal_from(0, factor);
    }

    /// Multiplies the diagonal entries of block rows `from ..` by `factor` (rows assembled
    /// again before [`BlockBandMatrix::refactor_collecting`]).
    pub fn scale_diagonal_from(&mut self, from: usize, factor: f64) {
        let w = self.q + 1;
        for i in from..self.nb {
            let d = &mut self.a[i * w + self.q];
            for (k, row) in d.iter_mut().enumerate() {
                row[k] *= factor;
            }
        }
        self.touched();
    }

    /// Block `(i, j)`, `j ≤ i`, for assembly.
    #[inline]
    pub fn block_mut(&mut self, i: usize, j: usize) -> &mut Block {
        self.touched();
        let s = self.slot(i, j);
        &mut self.a[s]
    }

    /// Scalar entry `(r, c)` of the matrix (before factorisation), zero outside the band.
    pub fn get(&self, r: usize, c: usize) -> f64 {
        let (r, c) = if r >= c { (r, c) } else { (c, r) };
        let (i, j) = (r / 3, c / 3);
        if i - j > self.q {
            return 0.0;
        }
        let b = &self.a[self.slot(i, j)];
        if i == j {
            // Only the lower triangle of a diagonal block is meaningful.
            let (rr, cc) = (r % 3, c % 3);
            b[rr.max(cc)][rr.min(cc)]
        } else {
            b[r % 3][c % 3]
        }
    }

    /// Whether [`BlockBandMatrix::factor`] has succeeded since the last change.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Factorises in place into `L` with `A = L·Lᵀ`, block row by block row:
    /// `L_IJ = (A_IJ − Σ_K L_IK·L_JKᵀ)·L_JJ⁻ᵀ` for `J < I`, and
    /// `L_II = chol(A_II − Σ_K L_IK·L_IKᵀ)`, sums over `max(0, I−q) ≤ K < J`. Only the lower
    /// triangles of diagonal blocks are read. Fails, naming the scalar row, at the first
    /// pivot not above [`PIVOT_TOLERANCE`] times the row's diagonal.
    pub fn factor(&mut self) -> Result<(), PivotFailure> {
        let mut failures = Vec::new();
        self.factor_collecting(&mut failures, 1);
        match failures.first() {
            None => Ok(()),
            Some(&f) => Err(f),
        }
    }

    /// Like [`BlockBandMatrix::factor`], but goes on past pivots that fail, replacing each by
    /// its row's original diagonal, and records up to `max` failures in `failures` (cleared
    /// first); stops at the `max`-th. The matrix counts as factorised only if none failed;
    /// after failures, [`BlockBandMatrix::failed_pivot_direction`] works for each of them.
    pub fn factor_collecting(&mut self, failures: &mut Vec<PivotFailure>, max: usize) {
        self.factor_collecting_with(arch(), 0, failures, max);
    }

    /// [`BlockBandMatrix::factor_collecting`] again after only block rows `from ..` were
    /// assembled again (each written whole, as an assembly writes it, into the storage of
    /// the last factorisation, whose rows before `from` are kept): those rows are
    /// factorised, the others' factor and inverse pivots kept, and of `failures` (on entry,
    /// the last factorisation's) those before row `from` are kept and the later ones found
    /// again. Row `i` of the factor depends only on rows `..= i` of the matrix, so the
    /// result is bit for bit that of factorising the whole matrix, failures included,
    /// provided the last factorisation was of this matrix's rows before `from` with the same
    /// pivot tolerance, and was made by `factor_collecting` or this.
    ///
    /// (Where the last factorisation stopped at its `max`-th failure before `from`, so would
    /// the whole one: the rows it left are the matrix's, as assembled, in both.)
    pub fn refactor_collecting(
        &mut self,
        from: usize,
        failures: &mut Vec<PivotFailure>,
        max: usize,
    ) {
        self.factor_collecting_with(arch(), from, failures, max);
    }

    /// [`BlockBandMatrix::factor_collecting`] with the kernels compiled for `arch`, from
    /// block row `from` (see [`BlockBandMatrix::refactor_collecting`]; 0: the whole
    /// matrix): the same bits with any.
    fn factor_collecting_with(
        &mut self,
        arch: pulp::Arch,
        from: usize,
        failures: &mut Vec<PivotFailure>,
        max: usize,
    ) {
        let from = from.min(self.nb);
        let kept = failures.partition_point(|f| f.index < 3 * from);
        failures.truncate(kept);
        self.touched();
        let q = self.q;
        let w = q + 1;
        for (d, row) in self.diag[from..]
            .iter_mut()
            .zip(self.a[from * w..].chunks_exact(w))
        {
            let a = &row[q];
            *d = [a[0][0], a[1][1], a[2][2]];
        }
        debug_assert!(
            max >= 1 || from == 0,
            "a refactorisation collects at least one failure"
        );
        if from > 0 && failures.len() >= max {
            // The whole factorisation stops before `from` too.
            self.factored = false;
            return;
        }
        let done = arch.dispatch(Factorise {
            q,
            from,
            a: &mut self.a,
            diag: &self.diag,
            inv_diag: &mut self.inv_diag,
            tolerance: self.tolerance,
            failures,
            max,
        });
        self.factored = done && failures.is_empty();
    }

    /// After [`BlockBandMatrix::factor_collecting`] with failures: the factor is that of the
    /// matrix with each failed pivot's diagonal raised to its row's original diagonal (a
    /// spring on that row); marks it usable for solves.
    pub(crate) fn force_factored(&mut self) {
        self.factored = true;
    }

    /// Solves `A·x = b` in place with the factor: `L·y = b`, then `Lᵀ·x = y`.
    ///
    /// # Panics
    /// If the matrix is not factorised, or `b` is shorter than `3·blocks`: both are bugs.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert!(self.factored, "solve with an unfactorised matrix");
        let q = self.q;
        let w = q + 1;
        let (x, _) = b[..3 * self.nb].as_chunks_mut::<3>();
        let rows = self.a.chunks_exact(w).zip(&self.inv_diag);
        for (i, (row, inv)) in rows.clone().enumerate() {
            let j0 = i.saturating_sub(q);
            let (done, at) = x.split_at_mut(i);
            let mut y = at[0];
            for (l, xk) in row[q - (i - j0)..q].iter().zip(&done[j0..]) {
                for (r, yr) in y.iter_mut().enumerate() {
                    *yr -= l[r][0] * xk[0] + l[r][1] * xk[1] + l[r][2] * xk[2];
                }
            }
            let l = &row[q];
            let y0 = y[0] * inv[0];
            let y1 = (y[1] - l[1][0] * y0) * inv[1];
            let y2 = (y[2] - l[2][0] * y0 - l[2][1] * y1) * inv[2];
            at[0] = [y0, y1, y2];
        }
        for (i, (row, inv)) in rows.enumerate().rev() {
            let j0 = i.saturating_sub(q);
            let (below, at) = x.split_at_mut(i);
            let l = &row[q];
            let y = at[0];
            let x2 = y[2] * inv[2];
            let x1 = (y[1] - l[2][1] * x2) * inv[1];
            let x0 = (y[0] - l[1][0] * x1 - l[2][0] * x2) * inv[0];
            at[0] = [x0, x1, x2];
            for (l, xk) in row[q - (i - j0)..q].iter().zip(&mut below[j0..]) {
                for (c, xc) in xk.iter_mut().enumerate() {
                    *xc -= l[0][c] * x0 + l[1][c] * x1 + l[2][c] * x2;
                }
            }
        }
    }

    /// After a factorisation failed at scalar row `i` with pivot `s ≤ 0`, writes into `v` the
    /// vector `[−A⁻¹b; 1; 0 …]` for which `vᵀKv = s` (`A` the leading `i × i` part, already
    /// factorised, `b` the column above the pivot): a direction of negative curvature when
    /// `s < 0`. Row `i` of the factor holds `L⁻¹b`; back-substitutes with `Lᵀ`, block by
    /// block. (After [`BlockBandMatrix::factor_collecting`] passed earlier failures, `A` is
    /// the leading part with those pivots replaced.)
    pub fn failed_pivot_direction(&self, i: usize, v: &mut [f64]) {
        assert!(!self.factored && i < 3 * self.nb && v.len() >= 3 * self.nb);
        let q = self.q;
        let w = q + 1;
        let (bi, di) = (i / 3, i % 3);
        v.fill(0.0);
        let (x, _) = v[..3 * self.nb].as_chunks_mut::<3>();
        // y = L⁻¹b: row i of L, over blocks bi−q .. bi (the diagonal block's first di columns).
        let row = &self.a[bi * w..(bi + 1) * w];
        let j0 = bi.saturating_sub(q);
        for (xk, l) in x[j0..bi].iter_mut().zip(&row[q - (bi - j0)..q]) {
            *xk = l[di];
        }
        x[bi][..di].copy_from_slice(&row[q][di][..di]);
        // Lᵀw = y over rows i−1 … 0: block b's own rows first (from its last up), then its
        // rows' parts in the blocks left of it, row by row from the last up, so that every
        // entry takes the same subtractions in the same order as one scalar row at a time.
        for b in (0..=bi).rev() {
            let row = &self.a[b * w..(b + 1) * w];
            let lbb = &row[q];
            let rows = if b == bi { di } else { 3 };
            let mut xb = x[b];
            for rr in (0..rows).rev() {
                let t = xb[rr] / lbb[rr][rr];
                xb[rr] = t;
                for c in 0..rr {
                    xb[c] -= lbb[rr][c] * t;
                }
            }
            x[b] = xb;
            let j0 = b.saturating_sub(q);
            for (xk, l) in x[j0..b].iter_mut().zip(&row[q - (b - j0)..q]) {
                for rr in (0..rows).rev() {
                    for c in 0..3 {
                        xk[c] -= l[rr][c] * xb[rr];
                    }
                }
            }
        }
        for x in &mut v[..i] {
            *x = -*x;
        }
        v[i] = 1.0;
    }

    /// `y = A·x` with the matrix before factorisation (for tests).
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        assert!(!self.factored, "multiply with a factorised matrix");
        let n = 3 * self.nb;
        for (r, yr) in y[..n].iter_mut().enumerate() {
            *yr = x[..n]
                .iter()
                .enumerate()
                .map(|(c, xc)| self.get(r, c) * xc)
                .sum();
        }
    }
}

/// The instruction set of the vector kernels (the factorisation here, and the batched
/// kernels of `solver::lanes`): the best this processor has, unless `TRUSS_KERNELS=baseline`
/// asks for baseline x86-64 (for the test that both give the same bytes, and for
/// benchmarks). Every kernel performs the same IEEE operations in the same order with any.
pub(crate) fn arch() -> pulp::Arch {
    use std::sync::OnceLock;
    static ARCH: OnceLock<pulp::Arch> = OnceLock::new();
    *ARCH.get_or_init(|| {
        if std::env::var_os("TRUSS_KERNELS").is_some_and(|v| v == "baseline") {
            pulp::Arch::Scalar
        } else {
            pulp::Arch::new()
        }
    })
}

/// A block's columns, each padded to four entries (`t[c][r] = b[r][c]`, `t[c][3]` padding): the
/// factorisation computes a block's three rows side by side, one column at a time, as one
/// vector operation per column on AVX2.
type Columns = [[f64; 4]; 3];

/// The columns of `b`. The fourth lane is padding, never read back (`b₂ − b₂`, zero for
/// finite entries): with a literal zero LLVM may zero the lane with a `vmovq` form that
/// valgrind 3.19 cannot decode (`scripts/bench-instructions.sh` then fails), and with a copy
/// of the third row the factorisation of the 300-stage prism cost 3 % more instructions.
#[inline(always)]
#[allow(
    clippy::eq_op,
    reason = "b₂ − b₂ is the padding, on purpose: see the doc"
)]
fn columns(b: &Block) -> Columns {
    std::array::from_fn(|c| [b[0][c], b[1][c], b[2][c], b[2][c] - b[2][c]])
}

/// The block whose columns are `t`.
#[inline(always)]
fn block_of(t: &Columns) -> Block {
    std::array::from_fn(|r| [t[0][r], t[1][r], t[2][r]])
}

/// `s −= x·yᵀ` with `s` and `x` as columns: entry `(r, c)` is
/// `s_rc − ((x_r0·y_c0 + x_r1·y_c1) + x_r2·y_c2)`, each row `r` in a lane of its own.
#[inline(always)]
fn sub_mul_t(s: &mut Columns, x: &Columns, y: &Block) {
    for (sc, yc) in s.iter_mut().zip(y) {
        for r in 0..4 {
            sc[r] -= x[0][r] * yc[0] + x[1][r] * yc[1] + x[2][r] * yc[2];
        }
    }
}

/// The block Cholesky factorisation's arguments, for `pulp`'s dispatch (compiled once per
/// instruction set).
struct Factorise<'m> {
    q: usize,
    /// The first block row factorised (the rows before hold their factor already).
    from: usize,
    a: &'m mut [Block],
    diag: &'m [[f64; 3]],
    inv_diag: &'m mut [[f64; 3]],
    tolerance: f64,
    failures: &'m mut Vec<PivotFailure>,
    max: usize,
}

impl pulp::WithSimd for Factorise<'_> {
    /// Whether every block row was factorised (false: stopped at the `max`-th failure).
    type Output = bool;

    /// Block row by block row, as the module doc writes it (see
    /// [`BlockBandMatrix::factor_collecting`]): each block of row `i` by its three rows side
    /// by side, kept as columns while the row is factorised (its blocks are the left factors
    /// of the row's later products); row `j`'s finished blocks are read as they are stored.
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> bool {
        let (q, w) = (self.q, self.q + 1);
        let nb = self.diag.len();
        let zero: Columns = [[0.0; 4]; 3];
        let mut cols: [Columns; STACK_COLUMNS] = [zero; STACK_COLUMNS];
        let mut heap: Vec<Columns> = Vec::new();
        let cols: &mut [Columns] = if w <= cols.len() {
            &mut cols[..w]
        } else {
            heap.resize(w, zero);
            &mut heap
        };
        for i in self.from..nb {
            let j0 = i.saturating_sub(q);
            let first = q - (i - j0);
            let (done, from_i) = self.a.split_at_mut(i * w);
            let row = &mut from_i[..w];
            // L_ij = (A_ij − Σ_k L_ik·L_jkᵀ)·L_jj⁻ᵀ, k from j0 up.
            for (n, (row_j, inv)) in done[j0 * w..]
                .chunks_exact(w)
                .zip(&self.inv_diag[j0..i])
                .enumerate()
            {
                let mut s = columns(&row[first + n]);
                for (x, y) in cols[first..first + n].iter().zip(&row_j[q - n..q]) {
                    sub_mul_t(&mut s, x, y);
                }
                // x·L_jjᵀ = s, column by column: L_jj·xᵀ = sᵀ for every row at once.
                let ljj = &row_j[q];
                let mut x = zero;
                for r in 0..4 {
                    x[0][r] = s[0][r] * inv[0];
                }
                for r in 0..4 {
                    x[1][r] = (s[1][r] - ljj[1][0] * x[0][r]) * inv[1];
                }
                for r in 0..4 {
                    x[2][r] = (s[2][r] - ljj[2][0] * x[0][r] - ljj[2][1] * x[1][r]) * inv[2];
                }
                cols[first + n] = x;
                row[first + n] = block_of(&x);
            }
            // L_ii = chol(A_ii − Σ_k L_ik·L_ikᵀ); only the lower triangle is read.
            let mut s = columns(&row[q]);
            for (x, y) in cols[first..q].iter().zip(&row[first..q]) {
                sub_mul_t(&mut s, x, y);
            }
            // s[c][r] is entry (r, c).
            let (l, inv) = cholesky_block(
                |r, c| s[c][r],
                i,
                self.diag[i],
                self.tolerance,
                self.failures,
            );
            row[q] = l;
            self.inv_diag[i] = inv;
            if self.failures.len() >= self.max {
                return false;
            }
        }
        true
    }
}

/// `L_ii = chol(S)` for a diagonal block whose lower triangle is `s(r, c)`, `c ≤ r` (the
/// sum `A_ii − Σ_k L_ik·L_ikᵀ`), with the inverse pivots. A pivot not above `tolerance`
/// times its row's original diagonal `diag` (NaN included) is recorded in `failures` (scalar
/// row `3·i + k`) and replaced by that diagonal's magnitude.
#[inline(always)]
fn cholesky_block(
    s: impl Fn(usize, usize) -> f64,
    i: usize,
    diag: [f64; 3],
    tolerance: f64,
    failures: &mut Vec<PivotFailure>,
) -> (Block, [f64; 3]) {
    let mut pivot = |k: usize, p: f64| -> f64 {
        if p > tolerance * diag[k] {
            p
        } else {
            failures.push(PivotFailure {
                index: 3 * i + k,
                pivot: p,
            });
            diag[k].abs().max(f64::MIN_POSITIVE)
        }
    };
    let mut l = ZERO;
    l[0][0] = pivot(0, s(0, 0)).sqrt();
    let i0 = 1.0 / l[0][0];
    l[1][0] = s(1, 0) * i0;
    l[2][0] = s(2, 0) * i0;
    l[1][1] = pivot(1, s(1, 1) - l[1][0] * l[1][0]).sqrt();
    let i1 = 1.0 / l[1][1];
    l[2][1] = (s(2, 1) - l[2][0] * l[1][0]) * i1;
    l[2][2] = pivot(2, s(2, 2) - l[2][0] * l[2][0] - l[2][1] * l[2][1]).sqrt();
    (l, [i0, i1, 1.0 / l[2][2]])
}

/// The blocks of one block row the factorisation keeps as columns on the stack (a block
/// half-bandwidth up to 15; a wider band's go on the heap).
const STACK_COLUMNS: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;

    /// Block `(i, j)` of the factor, `j = j0 + n`, in row `i`'s slots (`row[first ..]` holds
    /// blocks `j0 ..= i`): `L_ij = (A_ij − Σ_k L_ik·L_jkᵀ)·L_jj⁻ᵀ`, `k` from `j0` up, with row
    /// `j` (`row_j`, its diagonal's inverse pivots `inv`) already factorised.
    #[inline(always)]
    fn off_diagonal(
        row: &mut [Block],
        first: usize,
        n: usize,
        row_j: &[Block],
        inv: &[f64; 3],
        q: usize,
    ) {
        let (left, at) = row.split_at_mut(first + n);
        let mut s = at[0];
        for (x, y) in left[first..].iter().zip(&row_j[q - n..q]) {
            sub_mul_t(&mut s, x, y);
        }
        let ljj = &row_j[q];
        // Row by row: x·L_JJᵀ = s, i.e. L_JJ·xᵀ = sᵀ.
        for r in &mut s {
            let x0 = r[0] * inv[0];
            let x1 = (r[1] - ljj[1][0] * x0) * inv[1];
            let x2 = (r[2] - ljj[2][0] * x0 - ljj[2][1] * x1) * inv[2];
            *r = [x0, x1, x2];
        }
        at[0] = s;
    }

    /// The diagonal block of row `i` (its other blocks factorised, from slot `first`):
    /// `L_ii = chol(A_ii − Σ_k L_ik·L_ikᵀ)`; a failed pivot is recorded and replaced by the row's
    /// original diagonal `diag`. Returns whether `max` failures are reached, and the inverse
    /// pivots.
    #[inline(always)]
    fn diagonal(
        row: &mut [Block],
        first: usize,
        i: usize,
        diag: [f64; 3],
        tolerance: f64,
        failures: &mut Vec<PivotFailure>,
        max: usize,
    ) -> (bool, [f64; 3]) {
        let q = row.len() - 1;
        let (left, at) = row.split_at_mut(q);
        let mut s = at[0];
        for l in &left[first..] {
            sub_mul_t_lower(&mut s, l);
        }
        let (l, inv) = cholesky_block(|r, c| s[r][c], i, diag, tolerance, failures);
        at[0] = l;
        (failures.len() >= max, inv)
    }

    /// The lower triangle of `s −= l·lᵀ` for 3×3 blocks (the upper one is never read).
    #[inline(always)]
    fn sub_mul_t_lower(s: &mut Block, l: &Block) {
        for r in 0..3 {
            for c in 0..=r {
                s[r][c] -= l[r][0] * l[c][0] + l[r][1] * l[c][1] + l[r][2] * l[c][2];
            }
        }
    }

    /// `s −= x·yᵀ` for 3×3 blocks.
    #[inline(always)]
    fn sub_mul_t(s: &mut Block, x: &Block, y: &Block) {
        for r in 0..3 {
            for c in 0..3 {
                s[r][c] -= x[r][0] * y[c][0] + x[r][1] * y[c][1] + x[r][2] * y[c][2];
            }
        }
    }

    /// A random SPD block-band matrix: diagonally dominant with random couplings.
    fn spd(nb: usize, q: usize, seed: u64) -> BlockBandMatrix {
        let mut state = seed;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        let mut m = BlockBandMatrix::new(nb, q);
        for i in 0..nb {
            for j in i.saturating_sub(q)..i {
                let b = m.block_mut(i, j);
                for row in b.iter_mut() {
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
            let row: f64 = (0..n).filter(|&c| c != r).map(|c| m.get(r, c).abs()).sum();
            m.block_mut(r / 3, r / 3)[r % 3][r % 3] = row + 1.0 + next().abs();
        }
        m
    }

    /// Solve against the product: A·(A⁻¹b) = b, for bands narrower and wider than the matrix.
    #[test]
    fn solves_match_products() {
        for (nb, q) in [
            (1usize, 0usize),
            (5, 0),
            (4, 1),
            (15, 5),
            (10, 12),
            (100, 5),
        ] {
            let q = q.min(nb.saturating_sub(1));
            let a = spd(nb, q, nb as u64 * 31 + q as u64);
            let n = 3 * nb;
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut f = a.clone();
            f.factor().unwrap();
            let mut x = b.clone();
            f.solve_in_place(&mut x);
            let mut ax = vec![0.0; n];
            a.mul(&x, &mut ax);
            for (u, v) in ax.iter().zip(&b) {
                assert!((u - v).abs() < 1e-12, "nb={nb} q={q}: {u} vs {v}");
            }
        }
    }

    /// The factor one block row at a time and one entry at a time, as the module doc writes
    /// it: the reference that [`BlockBandMatrix::factor_collecting`]'s column kernels must
    /// match bit for bit.
    fn one_row_at_a_time(m: &mut BlockBandMatrix, failures: &mut Vec<PivotFailure>, max: usize) {
        failures.clear();
        let (q, w) = (m.q, m.q + 1);
        let diag: Vec<[f64; 3]> =
            m.a.chunks_exact(w)
                .map(|row| [row[q][0][0], row[q][1][1], row[q][2][2]])
                .collect();
        for (i, &d) in diag.iter().enumerate() {
            let j0 = i.saturating_sub(q);
            let (done, from_i) = m.a.split_at_mut(i * w);
            let row = &mut from_i[..w];
            for (n, (row_j, inv)) in done[j0 * w..]
                .chunks_exact(w)
                .zip(&m.inv_diag[j0..i])
                .enumerate()
            {
                off_diagonal(row, q - (i - j0), n, row_j, inv, q);
            }
            let (stop, inv) = diagonal(row, q - (i - j0), i, d, PIVOT_TOLERANCE, failures, max);
            m.inv_diag[i] = inv;
            if stop {
                return;
            }
        }
    }

    #[test]
    fn the_column_kernels_give_the_one_entry_factor_bit_for_bit() {
        for (nb, q, indefinite) in [
            (1usize, 0usize, false),
            (5, 0, false),
            (4, 1, false),
            (15, 5, false),
            (16, 5, false),
            (10, 9, false),
            (20, 17, false),
            (15, 5, true),
        ] {
            let mut a = spd(nb, q, nb as u64 * 7 + q as u64);
            if indefinite {
                // Two negative pivots: the collecting factorisation goes on past the first.
                a.block_mut(4, 4)[1][1] = -50.0;
                a.block_mut(9, 9)[0][0] = -50.0;
            }
            let mut slow = a.clone();
            let mut fs = Vec::new();
            one_row_at_a_time(&mut slow, &mut fs, 2);
            for arch in [pulp::Arch::Scalar, pulp::Arch::new()] {
                let mut fast = a.clone();
                let mut ff = Vec::new();
                fast.factor_collecting_with(arch, 0, &mut ff, 2);
                assert_eq!(ff, fs, "nb={nb} q={q}");
                assert_eq!(ff.len(), if indefinite { 2 } else { 0 });
                let rows = ff.last().map_or(nb, |f| f.index / 3 + 1);
                for (k, (x, y)) in fast.a.iter().zip(&slow.a).take(rows * (q + 1)).enumerate() {
                    for (r, (xr, yr)) in x.iter().zip(y).enumerate() {
                        for (c, (u, v)) in xr.iter().zip(yr).enumerate() {
                            assert_eq!(
                                u.to_bits(),
                                v.to_bits(),
                                "nb={nb} q={q} slot {k} [{r}][{c}]"
                            );
                        }
                    }
                }
                assert_eq!(fast.inv_diag[..rows], slow.inv_diag[..rows]);
            }
        }
    }

    /// A factorisation again from a block row, after only the rows from there on changed
    /// ([`BlockBandMatrix::refactor_collecting`]), against factorising the changed matrix
    /// whole: the same factor, inverse pivots (up to where it stopped), original diagonals
    /// and failed pivots, bit for bit, with both kernels. Positive definite and indefinite
    /// matrices, collecting one failure or three (so that a factorisation stops before, at
    /// or after the row it restarts from), restarting from the first row, a middle one, the
    /// last and past the end. It fails if the kernel starts a row early.
    #[test]
    fn a_factorisation_again_from_a_row_is_the_whole_one_bit_for_bit() {
        let (nb, q) = (9, 3);
        let w = q + 1;
        let mut cases = 0;
        for (seed, negative) in [(1u64, false), (2, true), (3, true)] {
            let indefinite = |mut m: BlockBandMatrix, at: usize| {
                if negative {
                    m.block_mut(at, at)[1][1] = -50.0;
                    m.block_mut((at + 4) % nb, (at + 4) % nb)[0][0] = -50.0;
                }
                m
            };
            let before = indefinite(spd(nb, q, seed), 2);
            for from in [0, 3, 6, 8, 12] {
                let fresh = indefinite(spd(nb, q, seed + 100 + from as u64), 5);
                let mut changed = before.clone();
                let at = from.min(nb) * w;
                changed.a[at..].copy_from_slice(&fresh.a[at..]);
                for max in [1, 3] {
                    for arch in [pulp::Arch::Scalar, pulp::Arch::new()] {
                        let mut want = changed.clone();
                        let mut want_f = Vec::new();
                        want.factor_collecting_with(arch, 0, &mut want_f, max);
                        let mut got = before.clone();
                        let mut got_f = Vec::new();
                        got.factor_collecting_with(arch, 0, &mut got_f, max);
                        got.a[at..].copy_from_slice(&changed.a[at..]);
                        got.factor_collecting_with(arch, from, &mut got_f, max);
                        let what = format!("seed {seed} from {from} max {max} {arch:?}");
                        assert_eq!(got_f, want_f, "{what}");
                        assert_eq!(got.factored, want.factored, "{what}");
                        let bits = |m: &BlockBandMatrix| -> Vec<u64> {
                            m.a.as_flattened()
                                .as_flattened()
                                .iter()
                                .map(|x| x.to_bits())
                                .collect()
                        };
                        assert_eq!(bits(&got), bits(&want), "{what}: blocks");
                        assert_eq!(got.diag, want.diag, "{what}: original diagonals");
                        // Rows past a stop keep whatever inverse pivots they had: never read.
                        let rows = if want_f.len() >= max {
                            want_f[max - 1].index / 3 + 1
                        } else {
                            nb
                        };
                        assert_eq!(got.inv_diag[..rows], want.inv_diag[..rows], "{what}");
                        cases += 1;
                    }
                }
            }
        }
        assert_eq!(cases, 3 * 5 * 2 * 2);
    }

    /// Agrees with nalgebra's dense Cholesky solve, an independent implementation, on five
    /// sizes and bandwidths (block diagonal to full): a block left out of the update or a
    /// transposed block moves the solution far beyond the 1e-13 allowed. nalgebra is already
    /// built for the default tests (truss-diagnose uses it); the same check against faer is
    /// [`agrees_with_faer_dense`], behind `--features cross-checks`.
    #[test]
    fn agrees_with_nalgebra_dense() {
        for (nb, q, seed) in [(1, 0, 1), (4, 1, 2), (15, 5, 7), (40, 3, 11), (30, 29, 13)] {
            let a = spd(nb, q, seed);
            let n = 3 * nb;
            let dense = nalgebra::DMatrix::from_fn(n, n, |i, j| a.get(i, j));
            assert_eq!(dense, dense.transpose(), "get() is symmetric");
            let rhs = nalgebra::DVector::from_fn(n, |i, _| 1.0 + i as f64);
            let x_dense = dense.cholesky().expect("positive definite").solve(&rhs);
            let mut f = a.clone();
            f.factor().unwrap();
            let mut x: Vec<f64> = rhs.iter().copied().collect();
            f.solve_in_place(&mut x);
            for i in 0..n {
                assert!(
                    (x[i] - x_dense[i]).abs() < 1e-13 * x_dense[i].abs().max(1.0),
                    "nb {nb}, q {q}: x[{i}] = {} (band) against {} (dense)",
                    x[i],
                    x_dense[i]
                );
            }
        }
    }

    /// Agrees with faer's dense Cholesky solve, an independent implementation (with
    /// `--features cross-checks`; the default tests run the same check against nalgebra,
    /// [`agrees_with_nalgebra_dense`]).
    #[cfg(feature = "cross-checks")]
    #[test]
    fn agrees_with_faer_dense() {
        use faer::Mat;
        use faer::linalg::solvers::Solve;
        let (nb, q) = (15, 5);
        let a = spd(nb, q, 7);
        let n = 3 * nb;
        let dense = Mat::<f64>::from_fn(n, n, |i, j| a.get(i, j));
        let llt = dense.llt(faer::Side::Lower).unwrap();
        let rhs = Mat::<f64>::from_fn(n, 1, |i, _| 1.0 + i as f64);
        let x_faer = llt.solve(&rhs);
        let mut f = a.clone();
        f.factor().unwrap();
        let mut x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        f.solve_in_place(&mut x);
        for i in 0..n {
            assert!((x[i] - x_faer[(i, 0)]).abs() < 1e-13 * x_faer[(i, 0)].abs().max(1.0));
        }
    }

    /// The direction from a failed pivot has exactly the pivot as its curvature, for a
    /// failure in each of the three rows of a block.
    /// [`BlockBandMatrix::failed_pivot_direction`] one scalar row at a time: the reference its
    /// block rows must match bit for bit.
    fn failed_pivot_direction_scalar(m: &BlockBandMatrix, i: usize, v: &mut [f64]) {
        assert!(!m.factored && i < 3 * m.nb && v.len() >= 3 * m.nb);
        let q = m.q;
        let w = q + 1;
        let (bi, di) = (i / 3, i % 3);
        v.fill(0.0);
        // y = L⁻¹b: row i of L, over blocks bi−q .. bi (the diagonal block's first di columns).
        let ri = bi * w;
        for k in bi.saturating_sub(q)..bi {
            let l = &m.a[ri + k + q - bi];
            v[3 * k..3 * k + 3].copy_from_slice(&l[di]);
        }
        let lii = &m.a[ri + q];
        v[3 * bi..3 * bi + di].copy_from_slice(&lii[di][..di]);
        // Lᵀw = y over rows i−1 … 0.
        for b in (0..=bi).rev() {
            let rb = b * w;
            let lbb = &m.a[rb + q];
            let rows = if b == bi { di } else { 3 };
            for rr in (0..rows).rev() {
                let x = v[3 * b + rr] / lbb[rr][rr];
                v[3 * b + rr] = x;
                for c in 0..rr {
                    v[3 * b + c] -= lbb[rr][c] * x;
                }
                for k in b.saturating_sub(q)..b {
                    let l = &m.a[rb + k + q - b];
                    for c in 0..3 {
                        v[3 * k + c] -= l[rr][c] * x;
                    }
                }
            }
        }
        for x in &mut v[..i] {
            *x = -*x;
        }
        v[i] = 1.0;
    }

    #[test]
    fn failed_pivot_direction_has_the_pivot_as_curvature() {
        for row in [21, 22, 23] {
            let (nb, q) = (12, 3);
            let mut a = spd(nb, q, 3);
            let d = a.get(row, row);
            a.block_mut(row / 3, row / 3)[row % 3][row % 3] = -0.5 * d;
            let original = a.clone();
            let err = a.factor().unwrap_err();
            // Also from a factorisation that went on past the failure.
            let mut b = original.clone();
            let mut failures = vec![];
            b.factor_collecting(&mut failures, usize::MAX);
            assert_eq!(failures[0], err);
            let mut vb = vec![0.0; 3 * nb];
            b.failed_pivot_direction(err.index, &mut vb);
            assert_eq!(err.index, row);
            let n = 3 * nb;
            let mut v = vec![0.0; n];
            a.failed_pivot_direction(err.index, &mut v);
            let mut av = vec![0.0; n];
            original.mul(&v, &mut av);
            let curvature: f64 = v.iter().zip(&av).map(|(x, y)| x * y).sum();
            assert_eq!(v, vb);
            assert!(err.pivot < 0.0);
            assert!(
                (curvature - err.pivot).abs() < 1e-9 * err.pivot.abs(),
                "{curvature} vs {}",
                err.pivot
            );
        }
    }

    /// The block rows give the scalar rows' direction bit for bit: at every scalar row of a
    /// block, in the first block, and with bandwidths 0 to the whole matrix.
    #[test]
    fn failed_pivot_direction_by_block_rows_is_the_scalar_one_bit_for_bit() {
        for (nb, q) in [(1usize, 0usize), (6, 0), (12, 3), (16, 5), (9, 8)] {
            for row in [0, 1, 2, 3 * nb / 2, 3 * nb / 2 + 1, 3 * nb - 1] {
                let mut a = spd(nb, q, 5 + row as u64);
                let d = a.get(row, row);
                a.block_mut(row / 3, row / 3)[row % 3][row % 3] = -0.5 * d;
                let mut failures = vec![];
                a.factor_collecting(&mut failures, usize::MAX);
                let f = failures[0];
                let (mut fast, mut slow) = (vec![7.0; 3 * nb], vec![7.0; 3 * nb]);
                a.failed_pivot_direction(f.index, &mut fast);
                failed_pivot_direction_scalar(&a, f.index, &mut slow);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&slow), "nb={nb} q={q} row={row}");
            }
        }
    }

    /// A singular direction is refused at its row.
    #[test]
    fn singular_is_refused_with_its_row() {
        let mut m = BlockBandMatrix::new(2, 1);
        for (i, v) in [2.0, 3.0, 0.0, 4.0, 5.0, 6.0].into_iter().enumerate() {
            m.block_mut(i / 3, i / 3)[i % 3][i % 3] = v;
        }
        assert_eq!(m.factor().unwrap_err().index, 2);
    }
}
