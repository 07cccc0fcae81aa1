//! Two-sample comparisons: sample moments, the Kolmogorov–Smirnov statistic with its
//! asymptotic p-value, and Holm's step-down adjustment of a family of p-values.

/// Mean, standard deviation and kurtosis of a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    /// `x̄ = Σx/n`.
    pub mean: f64,
    /// `s = √(Σ(x − x̄)²/(n − 1))` (with `n − 1` at least 1).
    pub sd: f64,
    /// `m₄/m₂²` with central moments over `n`, at least 1; 3 (the normal's) for a sample
    /// without spread.
    pub kurtosis: f64,
}

/// The [`Moments`] of `v` (non-empty).
pub fn moments(v: &[f64]) -> Moments {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let (mut m2, mut m4) = (0.0, 0.0);
    for x in v {
        let c = (x - mean) * (x - mean);
        m2 += c;
        m4 += c * c;
    }
    let var = m2 / (n - 1.0).max(1.0);
    let (m2n, m4n) = (m2 / n, m4 / n);
    Moments {
        mean,
        sd: var.sqrt(),
        kurtosis: if m2n > 0.0 {
            (m4n / (m2n * m2n)).max(1.0)
        } else {
            3.0
        },
    }
}

/// The two-sample Kolmogorov–Smirnov statistic `D = sup |F_y − F_x|` of the samples `y` and
/// `x` (non-empty) and its asymptotic p-value `Q_KS(λ)`, `λ = (√nₑ + 0.12 + 0.11/√nₑ)·D`,
/// `nₑ = nm/(n + m)`, `Q_KS(λ) = 2 Σ_{k≥1} (−1)^{k−1} e^{−2k²λ²}` (Stephens' small-sample
/// correction, as in Numerical Recipes §14.3); `p = 1` for `λ < 0.2`, where the series does
/// not converge and the samples agree.
pub fn kolmogorov_smirnov(y: &[f64], x: &[f64]) -> (f64, f64) {
    let mut a = y.to_vec();
    let mut b = x.to_vec();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() && j < b.len() {
        let v = a[i].min(b[j]);
        while i < a.len() && a[i] <= v {
            i += 1;
        }
        while j < b.len() && b[j] <= v {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    let ne = n * m / (n + m);
    let lambda = (ne.sqrt() + 0.12 + 0.11 / ne.sqrt()) * d;
    if lambda < 0.2 {
        return (d, 1.0);
    }
    let mut p = 0.0;
    for k in 1..=100 {
        let k = k as f64;
        p += 2.0 * (-1f64).powf(k - 1.0) * (-2.0 * k * k * lambda * lambda).exp();
    }
    (d, p.clamp(0.0, 1.0))
}

/// Holm's step-down adjustment: with the p-values sorted, `p₍ₖ₎` becomes
/// `max_{j ≤ k} min(1, (m − j + 1)·p₍ⱼ₎)`; returned in the input's order. It controls the
/// family-wise error rate at the level each adjusted value is compared with.
pub fn holm(p_values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..p_values.len()).collect();
    order.sort_by(|&a, &b| p_values[a].total_cmp(&p_values[b]));
    let m = p_values.len();
    let mut adjusted = vec![1.0; m];
    let mut running = 0.0f64;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((m - rank) as f64 * p_values[i]).min(1.0));
        adjusted[i] = running;
    }
    adjusted
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Holm by hand: p = (0.01, 0.04, 0.03, 0.2) sorted 0.01, 0.03, 0.04, 0.2 → 4·0.01,
    /// 3·0.03, max(2·0.04, 0.09), max(0.2, 0.09).
    #[test]
    fn holm_by_hand() {
        let a = holm(&[0.01, 0.04, 0.03, 0.2]);
        let want = [0.04, 0.09, 0.09, 0.2];
        for (x, y) in a.iter().zip(want) {
            assert!((x - y).abs() < 1e-15, "{a:?}");
        }
    }

    /// KS: identical samples give D = 0 and p = 1; disjoint ones D = 1 and a tiny p.
    #[test]
    fn ks_extremes() {
        let x: Vec<f64> = (0..50).map(f64::from).collect();
        assert_eq!(kolmogorov_smirnov(&x, &x), (0.0, 1.0));
        let y: Vec<f64> = (100..150).map(f64::from).collect();
        let (d, p) = kolmogorov_smirnov(&y, &x);
        assert_eq!(d, 1.0);
        assert!(p < 1e-10, "{p}");
    }

    /// Moments of 1..=4 by hand: mean 2.5, s² = 5/3, m₂ = 1.25, m₄ = 2.5625.
    #[test]
    fn moments_by_hand() {
        let m = moments(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(m.mean, 2.5);
        assert!((m.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((m.kurtosis - 2.5625 / 1.5625).abs() < 1e-15);
        assert_eq!(moments(&[2.0, 2.0]).kurtosis, 3.0);
    }
}
