//! Eigenvalues and eigenvectors of a small symmetric matrix (the reduced problems of the
//! limit solver, a few to a few hundred rows): plain IEEE arithmetic in a fixed order (and
//! the pure-Rust `libm` for `hypot`), so the same bits on every machine.
//!
//! Up to [`JACOBI_MAX`] rows, by cyclic Jacobi rotations (each sweep about `9p³` flops with
//! the vectors, a handful of sweeps). Above, where a tall truss with free play meets reduced
//! problems of up to 256 directions, by Householder reduction to tridiagonal form and the
//! implicit QL iteration (Wilkinson 1971, EISPACK's `tred2` and `tql2`, as in JAMA's
//! `EigenvalueDecomposition`): about `9p³` flops in all with the vectors, several times
//! fewer than Jacobi's sweeps.

/// The largest problem solved by Jacobi rotations: every model with at most this many
/// unknowns (the paper's prisms with free play have 27 to 45) keeps the bits it had before
/// the QL iteration was added.
pub(super) const JACOBI_MAX: usize = 64;

/// Most sweeps; a sweep that leaves the off-diagonal at most `1e-30` of the matrix's
/// squared norm ends the iteration first (a few sweeps for the sizes met).
const MAX_SWEEPS: usize = 60;

/// Most QL iterations for one eigenvalue (two or three are usual).
const MAX_QL_ITERATIONS: usize = 60;

/// Overwrites `a` (row-major `p×p`, symmetric) with the diagonal of its eigenvalues and
/// writes the eigenvectors into `v` (row-major, column `i` the vector of eigenvalue
/// `a[i*p+i]`); returns the eigenvalues in `values`.
pub(super) fn symmetric_eigen(a: &mut [f64], v: &mut [f64], values: &mut [f64], p: usize) {
    if p <= JACOBI_MAX {
        jacobi(a, v, values, p);
    } else {
        tridiagonal_ql(a, v, values, p);
    }
}

/// [`symmetric_eigen`] by cyclic Jacobi rotations (Golub & Van Loan, Algorithm 8.4.3).
fn jacobi(a: &mut [f64], v: &mut [f64], values: &mut [f64], p: usize) {
    // The eigenvectors are accumulated transposed in `v` (row i the vector of column i),
    // so that a rotation updates two contiguous rows, and transposed at the end; the
    // arithmetic is the same.
    let vt = &mut v[..p * p];
    vt.fill(0.0);
    for i in 0..p {
        vt[i * p + i] = 1.0;
    }
    for _ in 0..MAX_SWEEPS {
        let mut off = 0.0;
        let mut total = 0.0;
        for i in 0..p {
            for j in 0..p {
                let x = a[i * p + j] * a[i * p + j];
                total += x;
                if i != j {
                    off += x;
                }
            }
        }
        if off <= 1e-30 * total {
            break;
        }
        for i in 0..p {
            for j in i + 1..p {
                let aij = a[i * p + j];
                if aij == 0.0 {
                    continue;
                }
                // The rotation that zeroes a[i][j] (Golub & Van Loan, Algorithm 8.4.1).
                let theta = (a[j * p + j] - a[i * p + i]) / (2.0 * aij);
                let t = if theta >= 0.0 {
                    1.0 / (theta + (theta * theta + 1.0).sqrt())
                } else {
                    -1.0 / (-theta + (theta * theta + 1.0).sqrt())
                };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..p {
                    let (aki, akj) = (a[k * p + i], a[k * p + j]);
                    a[k * p + i] = c * aki - s * akj;
                    a[k * p + j] = s * aki + c * akj;
                }
                for k in 0..p {
                    let (aik, ajk) = (a[i * p + k], a[j * p + k]);
                    a[i * p + k] = c * aik - s * ajk;
                    a[j * p + k] = s * aik + c * ajk;
                }
                let (head, tail) = vt.split_at_mut(j * p);
                let (vi, vj) = (&mut head[i * p..i * p + p], &mut tail[..p]);
                for (vki, vkj) in vi.iter_mut().zip(vj.iter_mut()) {
                    let (x, y) = (*vki, *vkj);
                    *vki = c * x - s * y;
                    *vkj = s * x + c * y;
                }
            }
        }
    }
    for i in 0..p {
        values[i] = a[i * p + i];
        for k in 0..i {
            v.swap(i * p + k, k * p + i);
        }
    }
}

/// [`symmetric_eigen`] by Householder tridiagonalisation (`tred2`) and the implicit QL
/// iteration with the transformations accumulated (`tql2`). `v` holds the orthogonal matrix
/// row-major throughout: `v[r·p + c]`, column `c` the vector of eigenvalue `c`.
fn tridiagonal_ql(a: &mut [f64], v: &mut [f64], values: &mut [f64], p: usize) {
    let n = p;
    let v = &mut v[..n * n];
    v.copy_from_slice(&a[..n * n]);
    let d = &mut values[..n];
    let mut e = vec![0.0; n];
    // Householder reduction to tridiagonal form: diagonal in d, subdiagonal in e[1..].
    for j in 0..n {
        d[j] = v[(n - 1) * n + j];
    }
    for i in (1..n).rev() {
        let mut scale = 0.0;
        let mut h = 0.0;
        for dk in &d[..i] {
            scale += dk.abs();
        }
        if scale == 0.0 {
            e[i] = d[i - 1];
            for j in 0..i {
                d[j] = v[(i - 1) * n + j];
                v[i * n + j] = 0.0;
                v[j * n + i] = 0.0;
            }
        } else {
            for dk in &mut d[..i] {
                *dk /= scale;
                h += *dk * *dk;
            }
            let mut f = d[i - 1];
            let mut g = h.sqrt();
            if f > 0.0 {
                g = -g;
            }
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            e[..i].fill(0.0);
            for j in 0..i {
                f = d[j];
                v[j * n + i] = f;
                g = e[j] + v[j * n + j] * f;
                for k in j + 1..i {
                    g += v[k * n + j] * d[k];
                    e[k] += v[k * n + j] * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for j in 0..i {
                e[j] /= h;
                f += e[j] * d[j];
            }
            let hh = f / (h + h);
            for j in 0..i {
                e[j] -= hh * d[j];
            }
            for j in 0..i {
                f = d[j];
                g = e[j];
                for k in j..i {
                    v[k * n + j] -= f * e[k] + g * d[k];
                }
                d[j] = v[(i - 1) * n + j];
                v[i * n + j] = 0.0;
            }
        }
        d[i] = h;
    }
    // Accumulate the transformations.
    for i in 0..n - 1 {
        v[(n - 1) * n + i] = v[i * n + i];
        v[i * n + i] = 1.0;
        let h = d[i + 1];
        if h != 0.0 {
            for k in 0..=i {
                d[k] = v[k * n + i + 1] / h;
            }
            for j in 0..=i {
                let mut g = 0.0;
                for k in 0..=i {
                    g += v[k * n + i + 1] * v[k * n + j];
                }
                for k in 0..=i {
                    v[k * n + j] -= g * d[k];
                }
            }
        }
        for k in 0..=i {
            v[k * n + i + 1] = 0.0;
        }
    }
    for j in 0..n {
        d[j] = v[(n - 1) * n + j];
        v[(n - 1) * n + j] = 0.0;
    }
    v[(n - 1) * n + n - 1] = 1.0;
    // The implicit QL iteration on the tridiagonal matrix, its rotations applied to the
    // columns of v.
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let mut f = 0.0;
    let mut tst1: f64 = 0.0;
    for l in 0..n {
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        let mut m = l;
        while m < n - 1 && e[m].abs() > f64::EPSILON * tst1 {
            m += 1;
        }
        if m > l {
            for _ in 0..MAX_QL_ITERATIONS {
                let g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = libm::hypot(p, 1.0);
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let mut h = g - d[l];
                for di in &mut d[l + 2..] {
                    *di -= h;
                }
                f += h;
                p = d[m];
                let (mut c, mut c2, mut c3) = (1.0, 1.0, 1.0);
                let el1 = e[l + 1];
                let (mut s, mut s2) = (0.0, 0.0);
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    h = c * p;
                    r = libm::hypot(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    for row in v.chunks_exact_mut(n) {
                        let h = row[i + 1];
                        row[i + 1] = s * row[i] + c * h;
                        row[i] = c * row[i] - s * h;
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if e[l].abs() <= f64::EPSILON * tst1 {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] = if i == j { d[i] } else { 0.0 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against nalgebra's symmetric eigen-decomposition on random matrices of the sizes
    /// met (both methods: up to [`JACOBI_MAX`] rows and above), indefinite, and singular
    /// with a zero eigenvalue of high multiplicity (a reduced problem's free directions):
    /// `A·v = λ·v` to 1e-12 of `‖A‖`, the vectors orthonormal to 1e-12, and the same
    /// spectrum.
    #[test]
    fn agrees_with_nalgebra() {
        let mut x = 12345u64;
        let mut next = move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        for (p, singular) in [
            (1, false),
            (2, false),
            (3, false),
            (5, false),
            (9, false),
            (17, false),
            (17, true),
            (JACOBI_MAX + 1, false),
            (100, true),
            (200, false),
        ] {
            let b: Vec<f64> = (0..p * p).map(|_| next()).collect();
            // Singular: rank p/2, the other half of the spectrum exactly zero in exact
            // arithmetic.
            let rank = if singular { p / 2 } else { p };
            let mut a = vec![0.0; p * p];
            for i in 0..p {
                for j in 0..p {
                    a[i * p + j] = (0..rank).map(|k| b[i * p + k] * b[j * p + k]).sum::<f64>();
                }
            }
            // Shift by one diagonal entry's worth to make it indefinite (the singular ones
            // keep their zero eigenvalues).
            if !singular {
                for i in 0..p {
                    a[i * p + i] -= 0.3;
                }
            }
            let reference = nalgebra::DMatrix::from_row_slice(p, p, &a).symmetric_eigen();
            let mut work = a.clone();
            let (mut v, mut values) = (vec![0.0; p * p], vec![0.0; p]);
            symmetric_eigen(&mut work, &mut v, &mut values, p);
            let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            for i in 0..p {
                for r in 0..p {
                    let av: f64 = (0..p).map(|k| a[r * p + k] * v[k * p + i]).sum();
                    assert!((av - values[i] * v[r * p + i]).abs() <= 1e-12 * norm);
                }
            }
            for i in 0..p {
                for j in 0..p {
                    let dot: f64 = (0..p).map(|k| v[k * p + i] * v[k * p + j]).sum();
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (dot - expected).abs() <= 1e-12,
                        "p={p}: vᵢ·vⱼ = {dot} for {i}, {j}"
                    );
                }
            }
            let mut ours = values.clone();
            let mut theirs: Vec<f64> = reference.eigenvalues.iter().copied().collect();
            ours.sort_by(f64::total_cmp);
            theirs.sort_by(f64::total_cmp);
            for (o, t) in ours.iter().zip(&theirs) {
                assert!((o - t).abs() <= 1e-12 * norm, "{o} vs {t}");
            }
        }
    }
}
