//! Step 1, *where*: the statistics of the measured specimens against a simulated case, each
//! with a 95 % confidence interval, a p-value and a sentence.
//!
//! ## Statistics (measured `y`, n specimens; simulated with the instrument's noise, N samples)
//!
//! | id | statistic | interval and p-value |
//! |---|---|---|
//! | `mean NODE AXIS`, `mean piston`, `mean tan_theta_x`, `mean tan_theta_y` | difference of means | Welch: `ȳ − x̄ ± t·√(s_y²/n + s_x²/N)`, t from Student's law with the Welch–Satterthwaite degrees of freedom (about n − 1 when N ≫ n); p under "no difference": `z = (ȳ − x̄)/√(s_x²(1/n + 1/N))`, normal |
//! | `sd …` (same columns) | ratio of standard deviations (divisor n − 1) | `ln(s_y/s_x) ± t·√((κ_y − 1)/4n + (κ_x − 1)/4N)`, κ the sample kurtosis m₄/m₂² (the large-sample variance of ln s, valid without normality); t as for the means, p with the simulated κ_x for both parts |
//! | `cov A / B` (every pair of compared coordinates, and tan θ_x / tan θ_y) | difference of covariances | `± t·√(V_y/n + V_x/N)`, `V = mean((a − ā)²(b − b̄)²) − s_ab²`; t as for the means, p with the simulated V_x for both parts |
//! | `p50 theta_p`, `p90 …`, `p95 …`, `p99 …` (each only with at least [`MIN_IN_TAIL`] specimens beyond it: 50, 100 and 500 for the tails) | ratio of percentiles (Hyndman–Fan definition 1, `truss_stats::quantile`) | Poisson bootstrap of both samples (`truss_stats::bootstrap`, B = 1000, seeds 1 and 2), percentile interval of the ratio; p from the normal approximation of ln ratio with the replicates' standard deviation |
//! | `ks theta_p` | two-sample Kolmogorov–Smirnov D | asymptotic Kolmogorov p with Stephens' correction λ = (√nₑ + 0.12 + 0.11/√nₑ)·D, nₑ = nN/(n + N) |
//! | `energy displacements` | energy distance (Székely & Rizzo 2004, unbiased U-statistic) of the displacement vectors, each coordinate divided by the measured standard deviation (floored at the noise) | permutation p with R = 199 (seeded), on the first ≤ 2000 specimens and ≤ 1000 samples |
//!
//! "piston" is the mean z displacement of the three top-surface nodes (the top surface's
//! height). A statistic *disagrees* when its Holm-adjusted p-value (over every statistic of
//! the comparison) is below 0.05.
//!
//! ## Tolerance
//!
//! The baseline *agrees within tolerance* when the 95 % intervals show every coordinate's
//! mean within ±[`TOL_MEAN`] predicted standard deviations, every coordinate's scatter and the
//! median and 95th percentile of θ_P within a factor [`TOL_RATIO`] of the prediction.

use crate::comparison::measured::{Coordinate, Measured};
use crate::comparison::simulate::{RESOLUTION, Simulation};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
use truss_stats::bootstrap::{BootstrapConfig, SortedSample, bootstrap_quantiles};
use truss_stats::rng::mix64;
use truss_stats::two_sample::{self, kolmogorov_smirnov, moments};
use truss_units::{ARCSEC_PER_RAD, MICROMETRE_PER_MM, MICRORAD_PER_RAD};

/// Mean tolerance, in predicted standard deviations.
pub const TOL_MEAN: f64 = 0.5;
/// Ratio tolerance for scatter and θ_P percentiles.
pub const TOL_RATIO: f64 = 1.3;
const Z95: f64 = 1.959_963_984_540_054;
const PERCENTILES: [f64; 4] = [0.5, 0.9, 0.95, 0.99];
/// Fewest measured specimens beyond a percentile for its statistic: the bootstrap interval
/// of a tail percentile needs some specimens in the tail (with n(1 − q) < 5 the measured
/// percentile is one of the few largest values, whose bootstrap distribution is a handful of
/// points and whose interval undercovers, as 30 specimens' "99th percentile" with
/// "p = 8e-13" on null data showed). So θ_P's 90th percentile needs 50 specimens, the 95th
/// 100 and the 99th 500; below that the statistic is left out.
pub const MIN_IN_TAIL: f64 = 5.0;

/// A value with its 95 % interval.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Estimate {
    /// The estimate.
    pub value: f64,
    /// Lower end.
    pub lower: f64,
    /// Upper end.
    pub upper: f64,
}

/// One compared statistic.
#[derive(Debug, Clone, Serialize)]
pub struct Statistic {
    /// Identifier, stable across runs (`mean n5.1 z`).
    pub id: String,
    /// `mean`, `sd`, `cov`, `percentile`, `ks`, `energy`.
    pub kind: &'static str,
    /// Unit of `measured` and `simulated`.
    pub unit: &'static str,
    /// Measured value.
    pub measured: f64,
    /// Simulated value.
    pub simulated: f64,
    /// `difference` (measured − simulated) or `ratio` (measured / simulated); for `ks` and
    /// `energy`, the statistic itself.
    pub comparison: &'static str,
    /// The comparison with its 95 % interval.
    pub estimate: Estimate,
    /// p-value of "no difference".
    pub p_value: f64,
    /// Holm-adjusted p-value over the comparison's statistics.
    pub p_holm: f64,
    /// Whether it disagrees (p_holm < 0.05).
    pub disagrees: bool,
    /// The sentence for engineers.
    pub words: String,
}

/// Whether the baseline agrees within the stated tolerance, and what fails it.
#[derive(Debug, Clone, Serialize)]
pub struct Tolerance {
    /// Every tolerance statistic's interval lies within its band.
    pub within: bool,
    /// Ids of the statistics whose interval leaves the band.
    pub outside: Vec<String>,
    /// The bands, in words.
    pub bands: String,
}

/// Measured against one simulated case.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// Specimens n.
    pub specimens: usize,
    /// Simulated samples N (converged).
    pub samples: usize,
    /// Every statistic.
    pub statistics: Vec<Statistic>,
    /// The energy distance (the overall discrepancy).
    pub energy: f64,
    /// Its permutation p-value.
    pub energy_p: f64,
    /// Its noise level, the permutations' RMS ([`EnergyTest::noise`]).
    pub energy_noise: f64,
    /// Tolerance check.
    pub tolerance: Tolerance,
}

fn normal_p(z: f64) -> f64 {
    if !z.is_finite() {
        return if z.is_nan() { 1.0 } else { 0.0 };
    }
    2.0 * Normal::standard().sf(z.abs())
}

/// The 95 % interval of a Welch-type difference, whose `se² = a + b` adds the measured part
/// `a` (from n specimens) and the simulated part `b` (from N samples), each estimated:
/// Student's t with the Welch–Satterthwaite degrees of freedom
/// `ν = (a + b)² / (a²/(n − 1) + b²/(N − 1))`, about n − 1 when N ≫ n (the normal's 1.96
/// treated the estimated `se` as exact, too narrow at n = 30).
#[derive(Debug, Clone, Copy)]
struct Welch {
    /// `se` = √(a + b).
    se: f64,
    t: Option<StudentsT>,
}

impl Welch {
    fn new(a: f64, n: usize, b: f64, big_n: usize) -> Self {
        let se = (a + b).sqrt();
        let denominator = a * a / (n as f64 - 1.0).max(1.0) + b * b / (big_n as f64 - 1.0).max(1.0);
        let nu = (a + b).powi(2) / denominator;
        let t = (nu.is_finite() && nu > 0.0)
            .then(|| StudentsT::new(0.0, 1.0, nu).ok())
            .flatten();
        Welch { se, t }
    }

    /// The 97.5 % quantile (the half-width of a 95 % interval in units of `se`).
    fn q975(&self) -> f64 {
        self.t.map_or(Z95, |t| t.inverse_cdf(0.975))
    }
}

/// The p-value of "no difference" under that hypothesis itself: the measured specimens are
/// then n draws from the simulated distribution, so the estimate's variance is the simulated
/// part's per-draw variance `v_sim` times `(1/n + 1/N)`, known to the precision of N ≫ n
/// samples, and the statistic is referred to the normal law.
///
/// The measured moments are not used here: at n = 30 a fourth moment (a covariance's or a
/// standard deviation's variance) is underestimated more often than not, and on data made
/// from the baseline itself (the null check) the top nodes' x/y covariances reached
/// p ≈ 7e-5 from 30 specimens, where their variance under the model gives p ≈ 3e-3. The
/// 95 % intervals stay Welch's (measured and simulated moments, [`Welch`]): they describe
/// the size of a difference where one exists.
fn null_p(estimate: f64, v_sim: f64, n: usize, big_n: usize) -> f64 {
    normal_p(estimate / (v_sim * (1.0 / n as f64 + 1.0 / big_n as f64)).sqrt())
}

fn column(x: &[f64], d: usize, j: usize) -> Vec<f64> {
    x.iter().skip(j).step_by(d).copied().collect()
}

/// How a column is described in words.
#[derive(Clone)]
struct Column {
    id: String,
    unit: &'static str,
    /// Factor from mm (or 1) to the unit shown.
    scale: f64,
    /// Sentence subject and the words for a positive / negative difference.
    subject: String,
    more: String,
    less: String,
    /// Whether it enters the tolerance check.
    tolerance: bool,
}

fn coordinate_column(c: &Coordinate) -> Column {
    let axis = ["x", "y", "z"][c.axis];
    let (more, less) = if c.axis == 2 {
        ("higher".to_string(), "lower".to_string())
    } else {
        (format!("further in +{axis}"), format!("further in −{axis}"))
    };
    Column {
        id: c.label(),
        unit: "µm",
        scale: MICROMETRE_PER_MM,
        subject: format!("node {} ({axis})", c.node_id),
        more,
        less,
        tolerance: true,
    }
}

fn fmt(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 0.1 {
        format!("{v:.2}")
    } else {
        format!("{v:.2e}")
    }
}

fn mean_statistic(col: &Column, y: &[f64], x: &[f64]) -> Statistic {
    let (my, mx) = (moments(y), moments(x));
    let diff = my.mean - mx.mean;
    let w = Welch::new(
        my.sd.powi(2) / y.len() as f64,
        y.len(),
        mx.sd.powi(2) / x.len() as f64,
        x.len(),
    );
    let half = w.q975() * w.se;
    let est = Estimate {
        value: diff * col.scale,
        lower: (diff - half) * col.scale,
        upper: (diff + half) * col.scale,
    };
    let (dir, lo, hi) = if diff >= 0.0 {
        (&col.more, est.lower, est.upper)
    } else {
        (&col.less, -est.upper, -est.lower)
    };
    let words = format!(
        "{} is {} {} {dir} on average than predicted (95 % CI {}–{} {})",
        col.subject,
        fmt(est.value.abs()),
        col.unit,
        fmt(lo),
        fmt(hi),
        col.unit
    );
    Statistic {
        id: format!("mean {}", col.id),
        kind: "mean",
        unit: col.unit,
        measured: my.mean * col.scale,
        simulated: mx.mean * col.scale,
        comparison: "difference",
        estimate: est,
        p_value: null_p(diff, mx.sd.powi(2), y.len(), x.len()),
        p_holm: 1.0,
        disagrees: false,
        words,
    }
}

fn sd_statistic(col: &Column, y: &[f64], x: &[f64]) -> Statistic {
    let (my, mx) = (moments(y), moments(x));
    let ratio = my.sd / mx.sd;
    let w = Welch::new(
        (my.kurtosis - 1.0) / (4.0 * y.len() as f64),
        y.len(),
        (mx.kurtosis - 1.0) / (4.0 * x.len() as f64),
        x.len(),
    );
    let half = w.q975() * w.se;
    let est = Estimate {
        value: ratio,
        lower: ratio * (-half).exp(),
        upper: ratio * half.exp(),
    };
    let words = format!(
        "{} scatters {} times as much as predicted (95 % CI {}–{}): SD {} against {} {}",
        col.subject,
        fmt(ratio),
        fmt(est.lower),
        fmt(est.upper),
        fmt(my.sd * col.scale),
        fmt(mx.sd * col.scale),
        col.unit
    );
    Statistic {
        id: format!("sd {}", col.id),
        kind: "sd",
        unit: col.unit,
        measured: my.sd * col.scale,
        simulated: mx.sd * col.scale,
        comparison: "ratio",
        estimate: est,
        p_value: null_p(ratio.ln(), (mx.kurtosis - 1.0) / 4.0, y.len(), x.len()),
        p_holm: 1.0,
        disagrees: false,
        words,
    }
}

fn cov_parts(a: &[f64], b: &[f64]) -> (f64, f64) {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut s, mut s2) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let p = (x - ma) * (y - mb);
        s += p;
        s2 += p * p;
    }
    let cov = s / (n - 1.0).max(1.0);
    (cov, (s2 / n - (s / n).powi(2)).max(0.0))
}

fn cov_statistic(
    ca: &Column,
    cb: &Column,
    ya: &[f64],
    yb: &[f64],
    xa: &[f64],
    xb: &[f64],
) -> Statistic {
    let (cy, vy) = cov_parts(ya, yb);
    let (cx, vx) = cov_parts(xa, xb);
    let scale = ca.scale * cb.scale;
    let unit = if ca.unit == "µm" { "µm²" } else { "µrad²" };
    let diff = cy - cx;
    let w = Welch::new(
        vy / ya.len() as f64,
        ya.len(),
        vx / xa.len() as f64,
        xa.len(),
    );
    let half = w.q975() * w.se;
    let est = Estimate {
        value: diff * scale,
        lower: (diff - half) * scale,
        upper: (diff + half) * scale,
    };
    let words = format!(
        "the covariance of {} and {} is {} {unit} {} than predicted (95 % CI {}–{} {unit}): {} against {}",
        ca.id,
        cb.id,
        fmt(diff.abs() * scale),
        if diff >= 0.0 { "more" } else { "less" },
        fmt(est.lower),
        fmt(est.upper),
        fmt(cy * scale),
        fmt(cx * scale)
    );
    Statistic {
        id: format!("cov {} / {}", ca.id, cb.id),
        kind: "cov",
        unit,
        measured: cy * scale,
        simulated: cx * scale,
        comparison: "difference",
        estimate: est,
        p_value: null_p(diff, vx, ya.len(), xa.len()),
        p_holm: 1.0,
        disagrees: false,
        words,
    }
}

fn percentile_statistics(y: &[f64], x: &[f64], threads: usize) -> Vec<Statistic> {
    let sorted = |v: &[f64], offset: u64| {
        SortedSample::new(
            v.iter()
                .enumerate()
                .map(|(i, &t)| (t, i as u64 + offset))
                .collect(),
        )
    };
    let (sy, sx) = (sorted(y, 0), sorted(x, 0));
    let percentiles: Vec<f64> = PERCENTILES
        .iter()
        .copied()
        .filter(|p| y.len() as f64 * (1.0 - p) >= MIN_IN_TAIL)
        .collect();
    let config = |seed| BootstrapConfig {
        replicates: 1000,
        seed,
        threads,
    };
    let by = bootstrap_quantiles(&sy, &percentiles, &config(1));
    let bx = bootstrap_quantiles(&sx, &percentiles, &config(2));
    percentiles
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let qy = truss_stats::quantile::quantile_sorted(&sy.values, p).unwrap_or(f64::NAN);
            let qx = truss_stats::quantile::quantile_sorted(&sx.values, p).unwrap_or(f64::NAN);
            let mut logs: Vec<f64> = by.quantiles[j]
                .iter()
                .zip(&bx.quantiles[j])
                .filter_map(|(a, b)| match (a, b) {
                    (Some(a), Some(b)) if *a > 0.0 && *b > 0.0 => Some((a / b).ln()),
                    _ => None,
                })
                .collect();
            logs.sort_by(f64::total_cmp);
            let ratio = qy / qx;
            let (lo, hi) = truss_stats::bootstrap::percentile_interval(&logs, 0.95)
                .map_or((f64::NAN, f64::NAN), |(a, b)| (a.exp(), b.exp()));
            let m = logs.iter().sum::<f64>() / logs.len().max(1) as f64;
            let sd = (logs.iter().map(|v| (v - m).powi(2)).sum::<f64>()
                / (logs.len().max(2) - 1) as f64)
                .sqrt();
            let pct = (p * 100.0).round() as u32;
            let words = format!(
                "the {pct}th percentile of θ_P is {} times the predicted (95 % CI {}–{}): {} µrad ({}″) measured against {} µrad",
                fmt(ratio),
                fmt(lo),
                fmt(hi),
                fmt(qy * MICRORAD_PER_RAD),
                fmt(qy * ARCSEC_PER_RAD),
                fmt(qx * MICRORAD_PER_RAD)
            );
            Statistic {
                id: format!("p{pct} theta_p"),
                kind: "percentile",
                unit: "µrad",
                measured: qy * MICRORAD_PER_RAD,
                simulated: qx * MICRORAD_PER_RAD,
                comparison: "ratio",
                estimate: Estimate {
                    value: ratio,
                    lower: lo,
                    upper: hi,
                },
                p_value: normal_p(ratio.ln() / sd),
                p_holm: 1.0,
                disagrees: false,
                words,
            }
        })
        .collect()
}

fn ks_statistic(y: &[f64], x: &[f64]) -> Statistic {
    let (d, p) = kolmogorov_smirnov(y, x);
    Statistic {
        id: "ks theta_p".into(),
        kind: "ks",
        unit: "-",
        measured: d,
        simulated: 0.0,
        comparison: "statistic",
        estimate: Estimate {
            value: d,
            lower: d,
            upper: d,
        },
        p_value: p,
        p_holm: 1.0,
        disagrees: false,
        words: format!(
            "θ_P's distribution: largest gap between the measured and predicted ECDFs {} (two-sample KS p = {})",
            fmt(d),
            fmt(p)
        ),
    }
}

/// The energy distance of two samples and what chance alone gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyTest {
    /// The energy distance (unbiased U-statistic; dimensionless, the rows standardised).
    pub statistic: f64,
    /// Its permutation p-value.
    pub p_value: f64,
    /// Its noise: the root mean square of the statistic over the permutations, √(Σ Eᵣ²/R),
    /// the standard deviation of the U-statistic (mean 0) when both samples come from one
    /// distribution. Two models compared with the same measurements differ in their
    /// energy distances by chance by about √(noise₁² + noise₂²) or less.
    pub noise: f64,
}

/// The energy distance (U-statistic) of standardised rows, its permutation p-value and its
/// noise level under the permutations ([`EnergyTest`]).
pub fn energy_test(y: &[f64], x: &[f64], d: usize, scale: &[f64]) -> EnergyTest {
    let n = (y.len() / d).min(2000);
    let m = (x.len() / d).min(1000);
    let total = n + m;
    let rows: Vec<&[f64]> = y
        .chunks_exact(d)
        .take(n)
        .chain(x.chunks_exact(d).take(m))
        .collect();
    let mut dist = vec![0.0f64; total * (total - 1) / 2];
    let mut k = 0;
    for a in 0..total {
        for b in (a + 1)..total {
            let mut s = 0.0;
            for j in 0..d {
                let v = (rows[a][j] - rows[b][j]) / scale[j];
                s += v * v;
            }
            dist[k] = s.sqrt();
            k += 1;
        }
    }
    let statistic = |label: &[bool]| {
        let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
        let mut k = 0;
        for a in 0..total {
            for b in (a + 1)..total {
                match (label[a], label[b]) {
                    (true, true) => xx += dist[k],
                    (false, false) => yy += dist[k],
                    _ => xy += dist[k],
                }
                k += 1;
            }
        }
        let (nf, mf) = (n as f64, m as f64);
        2.0 * xy / (nf * mf) - 2.0 * xx / (nf * (nf - 1.0)) - 2.0 * yy / (mf * (mf - 1.0))
    };
    let mut label: Vec<bool> = (0..total).map(|i| i < n).collect();
    let observed = statistic(&label);
    let replicates = 199;
    let mut exceed = 0;
    let mut squares = 0.0;
    let mut state = 0x5eed_u64;
    for _ in 0..replicates {
        for i in (1..total).rev() {
            state = state.wrapping_add(truss_stats::rng::GAMMA);
            let j = (mix64(state) % (i as u64 + 1)) as usize;
            label.swap(i, j);
        }
        let e = statistic(&label);
        squares += e * e;
        if e >= observed {
            exceed += 1;
        }
    }
    EnergyTest {
        statistic: observed,
        p_value: (1 + exceed) as f64 / (replicates + 1) as f64,
        noise: (squares / replicates as f64).sqrt(),
    }
}

/// The comparison's family-wise level: a statistic disagrees when its Holm-adjusted p is
/// below it. Half of the verdict's α = 0.05 ([`crate::settings::Settings::alpha`]): a verdict other
/// than "the model agrees" on data that miss nothing can come from either of two families
/// of tests (the comparison here, which alone can say `unexplained`, and the candidates'
/// likelihood-ratio tests, which name an effect), so each family gets α/2 and their union
/// α (Bonferroni). The null check counts both.
pub const LEVEL: f64 = 0.025;

/// Holm's step-down adjustment over the comparison's statistics.
fn holm(stats: &mut [Statistic]) {
    let p: Vec<f64> = stats.iter().map(|s| s.p_value).collect();
    for (s, adjusted) in stats.iter_mut().zip(two_sample::holm(&p)) {
        s.p_holm = adjusted;
        s.disagrees = adjusted < LEVEL;
    }
}

/// Compares the measured data with a simulation that carries the instrument's noise; the
/// bootstraps run on `threads` threads (the result does not depend on them).
pub fn compare(
    measured: &Measured,
    sim: &Simulation,
    top: [[usize; 3]; 3],
    sigma_m: f64,
    threads: usize,
) -> Comparison {
    let d = measured.d();
    let mut stats = Vec::new();
    let mut columns: Vec<(Column, Vec<f64>, Vec<f64>)> = measured
        .coords
        .iter()
        .enumerate()
        .map(|(j, c)| {
            (
                coordinate_column(c),
                column(&measured.y, d, j),
                column(&sim.x_noisy, d, j),
            )
        })
        .collect();
    let piston = |x: &[f64]| -> Vec<f64> {
        x.chunks_exact(d)
            .map(|r| (r[top[0][2]] + r[top[1][2]] + r[top[2][2]]) / 3.0)
            .collect()
    };
    let derived = |id: &str, unit, scale, subject: &str, more: &str, less: &str| Column {
        id: id.into(),
        unit,
        scale,
        subject: subject.into(),
        more: more.into(),
        less: less.into(),
        tolerance: false,
    };
    let coords = columns.len();
    columns.push((
        derived(
            "piston",
            "µm",
            MICROMETRE_PER_MM,
            "the top surface",
            "higher",
            "lower",
        ),
        piston(&measured.y),
        piston(&sim.x_noisy),
    ));
    columns.push((
        derived(
            "tan_theta_x",
            "µrad",
            MICRORAD_PER_RAD,
            "tan θ_x",
            "larger",
            "smaller",
        ),
        measured.tan_x.clone(),
        sim.tan_x.clone(),
    ));
    columns.push((
        derived(
            "tan_theta_y",
            "µrad",
            MICRORAD_PER_RAD,
            "tan θ_y",
            "larger",
            "smaller",
        ),
        measured.tan_y.clone(),
        sim.tan_y.clone(),
    ));
    for (col, y, x) in &columns {
        stats.push(mean_statistic(col, y, x));
        stats.push(sd_statistic(col, y, x));
    }
    for a in 0..coords {
        for b in (a + 1)..coords {
            let (ca, ya, xa) = &columns[a];
            let (cb, yb, xb) = &columns[b];
            stats.push(cov_statistic(ca, cb, ya, yb, xa, xb));
        }
    }
    let t = columns.len();
    let (ca, ya, xa) = &columns[t - 2];
    let (cb, yb, xb) = &columns[t - 1];
    stats.push(cov_statistic(ca, cb, ya, yb, xa, xb));
    stats.extend(percentile_statistics(
        &measured.theta_p,
        &sim.theta_p,
        threads,
    ));
    stats.push(ks_statistic(&measured.theta_p, &sim.theta_p));
    let floor = (sigma_m * sigma_m + RESOLUTION.powi(2)).sqrt();
    let scale: Vec<f64> = (0..d)
        .map(|j| moments(&columns[j].1).sd.max(floor))
        .collect();
    let EnergyTest {
        statistic: energy,
        p_value: energy_p,
        noise: energy_noise,
    } = energy_test(&measured.y, &sim.x_noisy, d, &scale);
    stats.push(Statistic {
        id: "energy displacements".into(),
        kind: "energy",
        unit: "-",
        measured: energy,
        simulated: 0.0,
        comparison: "statistic",
        estimate: Estimate {
            value: energy,
            lower: energy,
            upper: energy,
        },
        p_value: energy_p,
        p_holm: 1.0,
        disagrees: false,
        words: format!(
            "the joint distribution of the displacements differs from the predicted: energy distance {} (standardised; permutation p = {})",
            fmt(energy),
            fmt(energy_p)
        ),
    });
    holm(&mut stats);
    // Tolerance.
    let mut outside = Vec::new();
    let lr = TOL_RATIO.ln();
    for (i, (col, _, x)) in columns.iter().enumerate().take(coords) {
        let _ = i;
        if !col.tolerance {
            continue;
        }
        let sd_pred = moments(x).sd * col.scale;
        let mean = stats
            .iter()
            .find(|s| s.id == format!("mean {}", col.id))
            .expect("computed");
        if mean.estimate.lower < -TOL_MEAN * sd_pred || mean.estimate.upper > TOL_MEAN * sd_pred {
            outside.push(mean.id.clone());
        }
        let sd = stats
            .iter()
            .find(|s| s.id == format!("sd {}", col.id))
            .expect("computed");
        if !(sd.estimate.lower.ln() >= -lr && sd.estimate.upper.ln() <= lr) {
            outside.push(sd.id.clone());
        }
    }
    for id in ["p50 theta_p", "p95 theta_p"] {
        // The 95th percentile only where it is computed (100 specimens or more).
        let Some(s) = stats.iter().find(|s| s.id == id) else {
            continue;
        };
        if !(s.estimate.lower.ln() >= -lr && s.estimate.upper.ln() <= lr) {
            outside.push(id.to_string());
        }
    }
    Comparison {
        specimens: measured.n(),
        samples: sim.n,
        statistics: stats,
        energy,
        energy_p,
        energy_noise,
        tolerance: Tolerance {
            within: outside.is_empty(),
            outside,
            bands: format!(
                "every coordinate's mean within ±{TOL_MEAN} predicted SD, its SD and θ_P's median and 95th percentile within a factor {TOL_RATIO} of the prediction (95 % intervals)"
            ),
        },
    }
}

/// A comparison with no statistics, agreeing within tolerance, of the given energy distance,
/// permutation p and noise (200 specimens, N = 4000): the selection's tests of its rules.
#[cfg(test)]
impl Comparison {
    pub(crate) fn of_energy(energy: f64, energy_p: f64, energy_noise: f64) -> Self {
        Self {
            specimens: 200,
            samples: 4000,
            statistics: Vec::new(),
            energy,
            energy_p,
            energy_noise,
            tolerance: Tolerance {
                within: true,
                outside: Vec::new(),
                bands: String::new(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy distance: zero-mean under the null (same distribution), large for a shift.
    #[test]
    fn energy_distance_sees_a_shift_and_not_noise() {
        let gauss = |seed: u64, n: usize, shift: f64| -> Vec<f64> {
            (0..n * 2)
                .map(|i| crate::comparison::simulate::noise_normal(seed, i as u64, 0) + shift)
                .collect()
        };
        let y = gauss(1, 100, 0.0);
        let x = gauss(2, 400, 0.0);
        let t0 = energy_test(&y, &x, 2, &[1.0, 1.0]);
        let (e0, p0) = (t0.statistic, t0.p_value);
        assert!(p0 > 0.01, "null rejected: e = {e0}, p = {p0}");
        assert!(e0.abs() < 3.0 * t0.noise, "e = {e0}, noise {}", t0.noise);
        let z = gauss(3, 100, 0.8);
        let t1 = energy_test(&z, &x, 2, &[1.0, 1.0]);
        let (e1, p1) = (t1.statistic, t1.p_value);
        assert!(
            p1 < 0.01 && e1 > 5.0 * e0.abs() && e1 > 10.0 * t1.noise,
            "shift missed: e = {e1}, p = {p1}, noise {}",
            t1.noise
        );
    }

    /// The noise level is the statistic's spread under the null: over 40 independent pairs
    /// of samples from one distribution (30 against 100 rows), the standard deviation of the
    /// energy distance is within a factor 1.5 of the mean permutation noise (both estimate
    /// the same SD; 40 draws give it to about ±11 %).
    #[test]
    fn energy_noise_is_the_spread_under_the_null() {
        let gauss = |seed: u64, n: usize| -> Vec<f64> {
            (0..n * 2)
                .map(|i| crate::comparison::simulate::noise_normal(seed, i as u64, 0))
                .collect()
        };
        let tests: Vec<EnergyTest> = (0..40)
            .map(|k| energy_test(&gauss(100 + k, 30), &gauss(200 + k, 100), 2, &[1.0, 1.0]))
            .collect();
        let sd = (tests.iter().map(|t| t.statistic.powi(2)).sum::<f64>() / 40.0).sqrt();
        let noise = tests.iter().map(|t| t.noise).sum::<f64>() / 40.0;
        assert!(
            sd < 1.5 * noise && noise < 1.5 * sd,
            "spread {sd} against noise {noise}"
        );
    }
}
