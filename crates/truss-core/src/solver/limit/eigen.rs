//! Eigenvalues and eigenvectors of a small symmetric matrix (the reduced problems of the
//! limit solver, a few to a few dozen rows), by cyclic Jacobi rotations: plain IEEE
//! arithmetic in a fixed order, so the same bits on every machine.

/// Most sweeps; a sweep that leaves the off-diagonal at most `1e-30` of the matrix's
/// squared norm ends the iteration first (a few sweeps for the sizes met).
const MAX_SWEEPS: usize = 60;

/// Overwrites `a` (row-major `p×p`, symmetric) with the diagonal of its eigenvalues and
/// writes the eigenvectors into `v` (row-major, column `i` the vector of eigenvalue
/// `a[i*p+i]`); returns the eigenvalues in `values`.
pub(super) fn symmetric_eigen(a: &mut [f64], v: &mut [f64], values: &mut [f64], p: usize) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Against nalgebra's symmetric eigen-decomposition on random matrices of the sizes
    /// met, definite and indefinite, with a zero eigenvalue: `A·v = λ·v` to 1e-12 of `‖A‖`,
    /// and the same spectrum.
    #[test]
    fn agrees_with_nalgebra() {
        let mut x = 12345u64;
        let mut next = move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        for p in [1, 2, 3, 5, 9, 17] {
            let b: Vec<f64> = (0..p * p).map(|_| next()).collect();
            let mut a = vec![0.0; p * p];
            for i in 0..p {
                for j in 0..p {
                    a[i * p + j] = (0..p).map(|k| b[i * p + k] * b[j * p + k]).sum::<f64>();
                }
            }
            // Shift by one diagonal entry's worth to make it indefinite.
            for i in 0..p {
                a[i * p + i] -= 0.3;
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
