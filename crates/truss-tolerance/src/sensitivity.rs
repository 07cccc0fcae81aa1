//! Which members drive the tilt: each member's share of the variance of tan θ_x and tan θ_y,
//! by least-squares regression of the Monte Carlo tilts on the drawn length errors, with
//! Poisson-bootstrap intervals.
//!
//! ## Why regression on the draws
//!
//! The tilt `t(e) = (tan θ_x, tan θ_y)` is positively homogeneous of degree 1 in the length
//! errors `e` and piecewise smooth: within one set of slack diagonals it is, to first order
//! in `e/L`, linear, `t = J_s·e`, and the set `s` changes with `e`. A derivative at the nominal
//! state sees one set only. The regression over the draws instead fits the best linear
//! predictor over the actual mix of slack sets, weighted as they occur at the case's σ:
//!
//! ```text
//! t_x,k = a_x + Σ_i b_x,i z_i,k + r_x,k,     z_i,k = e_i,k / σ_i   (standardised errors)
//! ```
//!
//! by ordinary least squares (normal equations, Cholesky) over the samples `k`, and likewise
//! for `t_y`. With independent errors of unit variance, member `i` explains
//! `b_x,i²` of Var(tan θ_x) and `b_y,i²` of Var(tan θ_y); its **share** is
//!
//! ```text
//! share_i = (b_x,i² + b_y,i²) / (Var tan θ_x + Var tan θ_y)        [-]
//! ```
//!
//! (and `share_x,i = b_x,i² / Var tan θ_x`, `share_y,i` likewise). A group's share is the sum
//! over its members. The shares sum to the regression's R² up to the sampling noise of the
//! errors' empirical covariance (so a sum can exceed 1 by a few %); `1 − R²`, from the
//! residual sum of squares, is the part no linear model explains (the slack-set
//! nonlinearity), reported as `nonlinear`. Per unit σ², member `i` adds
//! `β_i β_iᵀ` with `β_i = b_i / σ_i` \[mm⁻¹\] to the tilt's covariance, which is what the
//! allocation ([`crate::allocate`]) uses.
//!
//! ## Production lots
//!
//! Where a group's members share a lot part, `e_i = p_i + s_L` (`Var p_i = σ_i²`, `Var s_L
//! = σ_L²`, all independent), the regressors are correlated within a lot, and the regression
//! still estimates the linear model `t ≈ a + Σ_i β_i e_i` (σ_i is the own part's σ, so
//! `z_i = e_i/σ_i` and `b_i = β_i σ_i`). Its variance splits into the own parts' and the lots':
//!
//! ```text
//! Var t = Σ_i β_i β_iᵀ σ_i²  +  Σ_L B_L B_Lᵀ σ_L²,      B_L = Σ_{i ∈ L} β_i   [mm⁻¹]
//! share_i = |b_i|² / (Var tan θ_x + Var tan θ_y),   share_lot = σ_L² Σ_L |B_L|² / (…)
//! ```
//!
//! so a member's share is its own part's, and each group's lot part is a group of its own
//! (`GROUP.lot`, [`crate::setup`]) with covariance `Σ_L B_L B_Lᵀ` per unit σ_L², whatever
//! σ_L is (0 included: the β come from the own parts' scatter). A lot on one side of the
//! truss adds to the tilt (its members' β add up); a lot spread symmetrically cancels.
//!
//! ## Intervals
//!
//! Poisson bootstrap (`truss_stats::bootstrap`, weights keyed by the job seed and the sample
//! index, so the intervals do not depend on the thread count): each replicate refits the
//! weighted regression and recomputes every share; the intervals are the 2.5 % and 97.5 %
//! definition-1 quantiles of the replicates (percentile method), B = 200.

use crate::errors::ToleranceError;
use crate::percentile::Covariance;
use crate::simulate::Run;
use truss_stats::bootstrap::{BootstrapConfig, bootstrap_statistic, percentile_interval};

/// Bootstrap replicates of the shares.
pub const REPLICATES: u32 = 200;

/// One fit: shares and the per-unit-σ² covariance of every member.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Fit {
    /// Per member (column) the share of Var tan θ_x + Var tan θ_y \[-\].
    pub share: Vec<f64>,
    /// Per member the share of Var tan θ_x \[-\].
    pub share_x: Vec<f64>,
    /// Per member the share of Var tan θ_y \[-\].
    pub share_y: Vec<f64>,
    /// Per member `β_i β_iᵀ` \[mm⁻²\] (the tilt's covariance per unit σ_i²).
    pub covariance: Vec<Covariance>,
    /// Per member `β_i = (∂tan θ_x/∂e_i, ∂tan θ_y/∂e_i)` \[mm⁻¹\].
    pub beta: Vec<[f64; 2]>,
    /// The tilt's variances `Var tan θ_x + Var tan θ_y` \[-\], the shares' denominator.
    pub total: f64,
    /// The tilt's sample variances (Var tan θ_x, Var tan θ_y) \[-\].
    pub variance: [f64; 2],
    /// The residual share `(SSR_x + SSR_y) / (SST_x + SST_y)` = 1 − R²: the variance the
    /// linear model leaves \[-\].
    pub residual: f64,
}

/// Shares with intervals.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivity {
    /// The fit on all samples.
    pub fit: Fit,
    /// Per member the 95 % interval of its share.
    pub share_interval: Vec<(f64, f64)>,
    /// Per group (in the order of `group_of`'s indices) its share and interval.
    pub group_share: Vec<(f64, (f64, f64))>,
    /// The part of the variance the linear model leaves, `1 − R²`, with its interval.
    pub nonlinear: (f64, (f64, f64)),
    /// Samples fitted.
    pub samples: usize,
}

/// Solves the symmetric positive definite system `a·x = b` (n×n row-major) in place by
/// Cholesky; `None` if `a` is not positive definite.
fn cholesky_solve(a: &mut [f64], n: usize, rhs: &mut [Vec<f64>]) -> Option<()> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for b in rhs.iter_mut() {
        for i in 0..n {
            let mut s = b[i];
            for k in 0..i {
                s -= a[i * n + k] * b[k];
            }
            b[i] = s / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for k in i + 1..n {
                s -= a[k * n + i] * b[k];
            }
            b[i] = s / a[i * n + i];
        }
    }
    Some(())
}

/// The weighted regression of the run's tilts on its standardised errors (`sigma`: each
/// column's σ \[mm\]); `weights` `None` for all ones.
pub fn fit(run: &Run, sigma: &[f64], weights: Option<&[u8]>) -> Option<Fit> {
    let m = run.columns.len();
    let n = m + 1;
    let mut a = vec![0.0; n * n];
    let mut bx = vec![0.0; n];
    let mut by = vec![0.0; n];
    let mut x = vec![0.0; n];
    let (mut w_total, mut sx, mut sy, mut sxx, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..run.len() {
        let w = weights.map_or(1.0, |w| f64::from(w[k]));
        if w == 0.0 {
            continue;
        }
        x[0] = 1.0;
        for (j, (e, s)) in run.errors_of(k).iter().zip(sigma).enumerate() {
            x[j + 1] = e / s;
        }
        let [tx, ty] = run.tilt[k];
        for i in 0..n {
            let wi = w * x[i];
            for j in 0..=i {
                a[i * n + j] += wi * x[j];
            }
            bx[i] += wi * tx;
            by[i] += wi * ty;
        }
        w_total += w;
        sx += w * tx;
        sy += w * ty;
        sxx += w * tx * tx;
        syy += w * ty * ty;
    }
    if w_total <= n as f64 {
        return None;
    }
    for i in 0..n {
        for j in i + 1..n {
            a[i * n + j] = a[j * n + i];
        }
    }
    let mut rhs = vec![bx.clone(), by.clone()];
    cholesky_solve(&mut a, n, &mut rhs)?;
    // OLS with an intercept: SSR = Σ w y² − βᵀ(Xᵀ W y).
    let dot = |b: &[f64], beta: &[f64]| b.iter().zip(beta).map(|(u, v)| u * v).sum::<f64>();
    let ssr = (sxx - dot(&bx, &rhs[0])).max(0.0) + (syy - dot(&by, &rhs[1])).max(0.0);
    let var_x = (sxx - sx * sx / w_total) / w_total;
    let var_y = (syy - sy * sy / w_total) / w_total;
    let total = var_x + var_y;
    if total <= 0.0 || !total.is_finite() {
        return None;
    }
    let mut f = Fit {
        variance: [var_x, var_y],
        total,
        residual: ssr / (total * w_total),
        ..Fit::default()
    };
    for j in 0..m {
        let (b_x, b_y) = (rhs[0][j + 1], rhs[1][j + 1]);
        f.share.push((b_x * b_x + b_y * b_y) / total);
        f.share_x
            .push(if var_x > 0.0 { b_x * b_x / var_x } else { 0.0 });
        f.share_y
            .push(if var_y > 0.0 { b_y * b_y / var_y } else { 0.0 });
        let (px, py) = (b_x / sigma[j], b_y / sigma[j]);
        f.covariance.push([px * px, px * py, py * py]);
        f.beta.push([px, py]);
    }
    Some(f)
}

/// A group's lots as the regression's columns: the group index its lot part has in the
/// study, the columns (indices into the run's columns) of each lot's members, and the lot
/// part's σ_L \[mm\].
#[derive(Debug, Clone, PartialEq)]
pub struct LotColumns {
    /// The lot part's group index.
    pub group: usize,
    /// Per lot, its members' columns.
    pub lots: Vec<Vec<usize>>,
    /// σ_L \[mm\].
    pub sigma: f64,
}

impl LotColumns {
    /// `Σ_L B_L B_Lᵀ` \[mm⁻²\] of `fit` (see the module doc): the tilt's covariance per
    /// unit σ_L².
    pub fn covariance(&self, fit: &Fit) -> Covariance {
        let mut c = [0.0; 3];
        for lot in &self.lots {
            let (bx, by) = lot.iter().fold((0.0, 0.0), |(x, y), &j| {
                (x + fit.beta[j][0], y + fit.beta[j][1])
            });
            c[0] += bx * bx;
            c[1] += bx * by;
            c[2] += by * by;
        }
        c
    }

    /// The lot part's share of `Var tan θ_x + Var tan θ_y`, `σ_L² tr(Σ_L B_L B_Lᵀ) / total`.
    pub fn share(&self, fit: &Fit) -> f64 {
        let c = self.covariance(fit);
        self.sigma * self.sigma * (c[0] + c[2]) / fit.total
    }
}

/// Shares of every member and group with bootstrap intervals. `group_of[j]`: the group index
/// of column `j`; `groups`: their number (lot parts included); `lots`: the lot parts;
/// `seed`: the bootstrap's seed.
pub fn sensitivity(
    run: &Run,
    sigma: &[f64],
    group_of: &[usize],
    groups: usize,
    lots: &[LotColumns],
    seed: u64,
    threads: usize,
) -> Result<Sensitivity, ToleranceError> {
    let m = run.columns.len();
    let fit_all = fit(run, sigma, None).ok_or_else(|| {
        ToleranceError::Statistics(format!(
            "the regression of the tilt on {m} members' errors failed with {} samples \
             (need well over {} samples, and a tilt that varies)",
            run.len(),
            m + 1
        ))
    })?;
    let group_sums = |f: &Fit| -> Vec<f64> {
        let mut s = vec![0.0; groups];
        for (j, v) in f.share.iter().enumerate() {
            s[group_of[j]] += v;
        }
        for lot in lots {
            s[lot.group] = lot.share(f);
        }
        s
    };
    let indices: Vec<u64> = (0..run.len() as u64).collect();
    let config = BootstrapConfig {
        replicates: REPLICATES,
        seed,
        threads,
    };
    // Each replicate: member shares, then group shares (empty if the refit failed).
    let replicates: Vec<Vec<f64>> = bootstrap_statistic(&indices, &config, |w, _| {
        fit(run, sigma, Some(w))
            .map(|f| {
                let mut v = f.share.clone();
                v.extend(group_sums(&f));
                v.push(f.residual);
                v
            })
            .unwrap_or_default()
    });
    let good: Vec<&Vec<f64>> = replicates.iter().filter(|r| !r.is_empty()).collect();
    if good.len() < REPLICATES as usize / 2 {
        return Err(ToleranceError::Statistics(format!(
            "only {} of {REPLICATES} bootstrap refits of the regression succeeded",
            good.len()
        )));
    }
    let interval = |j: usize| -> (f64, f64) {
        let mut v: Vec<f64> = good.iter().map(|r| r[j]).collect();
        v.sort_by(f64::total_cmp);
        percentile_interval(&v, 0.95).unwrap_or((f64::NAN, f64::NAN))
    };
    let share_interval = (0..m).map(interval).collect();
    let totals = group_sums(&fit_all);
    let group_share = (0..groups).map(|g| (totals[g], interval(m + g))).collect();
    let nonlinear = (fit_all.residual, interval(m + groups));
    Ok(Sensitivity {
        fit: fit_all,
        share_interval,
        group_share,
        nonlinear,
        samples: run.len(),
    })
}
