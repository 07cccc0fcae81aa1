//! Decenter and despace of one case: their percentiles with the same three intervals as
//! θ_P's, and the law each follows under small errors with its goodness of fit.
//!
//! Under small errors the top centroid's displacement δ is linear in the length errors, so
//! decenter_x, decenter_y and despace are nearly normal (sums of many independent errors).
//! Where the truss is symmetric under a rotation about its axis (the prism's 120°),
//! decenter_x and decenter_y have one spread σ and no correlation, and decenter =
//! √(decenter_x² + decenter_y²) is **Rayleigh(σ)**: the paper's eq. 26–28 argument for θ_P
//! (from tan θ_x and tan θ_y) applied to the centroid's two components. So:
//!
//! - **decenter**: percentiles (Hyndman–Fan definition 1) with the Poisson-bootstrap
//!   percentile and BCa intervals and the order-statistic interval, exactly as θ_P's; each
//!   component's mean, standard deviation and zero-mean scale; the ML Rayleigh fit
//!   `σ̂² = Σ decenter²/2n` with its χ²(2n) interval and the Rayleigh percentiles
//!   `σ̂√(−2 ln(1 − α))`; KS and AD of decenter² against the exponential, as for θ_P
//!   ([`crate::gof::rayleigh_gof`]).
//! - **despace** is signed (the top moving away from the bottom or toward it), and a budget
//!   bounds its size either way: the percentiles are of `|despace|`, with the same intervals.
//!   Its law is **normal**, N(μ, s²) with the sample mean and standard deviation (Student-t and
//!   χ²(n−1) intervals); the law's percentile of |despace| is the folded normal's, the `q` with
//!   `Φ((q − μ)/s) − Φ((−q − μ)/s) = α` (found by bisection); KS and AD of despace against the
//!   normal with μ and s estimated ([`crate::gof::normal_gof`]). The relative difference of
//!   the law's and the empirical percentile gets its interval from the same Poisson replicates
//!   (weights keyed by global index, so the replicate means and spreads pair with the
//!   replicate percentiles).
//!
//! Samples that do not record them (shards of numerics version 7 or earlier) are left out;
//! a case none of whose samples records them has no decenter or despace section.

use crate::analysis::{
    Levels, component_report, gof_config, gof_report, percentiles, relative_difference,
    replicate_interval,
};
use crate::bootstrap::{
    BootstrapConfig, QuantileReplicates, SortedSample, bootstrap_quantiles, bootstrap_statistic,
};
use crate::gof::{self, CalibrationCache};
use crate::load::CaseData;
use crate::quantile::quantile_sorted;
use crate::rayleigh;
use crate::report::*;
use crate::settings::Settings;
use std::collections::BTreeMap;

/// One quantity's report and its percentiles for the budget.
#[derive(Debug, Clone)]
pub struct Quantity {
    /// The report's section.
    pub report: QuantityReport,
    /// The percentiles at every level, with their replicates.
    pub levels: Levels,
}

/// `Φ(z)`.
fn phi(z: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-z * std::f64::consts::FRAC_1_SQRT_2)
}

/// The `alpha`-quantile of |X| for X ~ N(mean, sd²) (the folded normal), by bisection.
pub fn folded_normal_quantile(mean: f64, sd: f64, alpha: f64) -> f64 {
    if sd <= 0.0 {
        return mean.abs();
    }
    let cdf = |q: f64| phi((q - mean) / sd) - phi((-q - mean) / sd);
    truss_stats::bisect::bisect(cdf, alpha, (0.0, mean.abs() + 40.0 * sd))
}

/// The percentiles of `sample` with their bootstrap.
fn bootstrapped(
    sample: &SortedSample,
    settings: &Settings,
) -> (Option<QuantileReplicates>, BootstrapConfig) {
    let config = BootstrapConfig {
        replicates: settings.replicates,
        seed: settings.bootstrap_seed,
        threads: settings.threads,
    };
    let levels: Vec<f64> = settings.percentiles.iter().map(|p| p / 100.0).collect();
    let boot = (sample.len() >= 2).then(|| bootstrap_quantiles(sample, &levels, &config));
    (boot, config)
}

fn levels(settings: &Settings, primary: Vec<Figure>, boot: Option<QuantileReplicates>) -> Levels {
    Levels {
        percentiles: settings.percentiles.clone(),
        primary,
        replicates: boot.map(|b| b.quantiles).unwrap_or_default(),
    }
}

/// The decenter and |despace| analyses of `case` (see the module doc); `None` for each where
/// no converged sample records it.
pub fn analyse(
    case: &CaseData,
    settings: &Settings,
    cache: &mut CalibrationCache,
    caveats: &[String],
) -> (Option<Quantity>, Option<Quantity>) {
    let placed = || case.points().filter(|p| p.placed());
    if placed().next().is_none() {
        return (None, None);
    }
    (
        Some(decenter(case, settings, cache, caveats)),
        Some(despace(case, settings, cache, caveats)),
    )
}

fn decenter(
    case: &CaseData,
    settings: &Settings,
    cache: &mut CalibrationCache,
    caveats: &[String],
) -> Quantity {
    let conf = settings.confidence;
    let points = case.points().filter(|p| p.placed());
    let sample = SortedSample::new(points.clone().map(|p| (p.decenter(), p.index)).collect());
    let n = sample.len();
    let (boot, _) = bootstrapped(&sample, settings);
    let pcts = percentiles(&sample, boot.as_ref(), settings, caveats);
    let sum_sq: f64 = points.clone().map(|p| p.decenter() * p.decenter()).sum();
    let fit = rayleigh::fit_from_sum_sq(n, sum_sq, conf);
    let pct = settings.target_percentile;
    let empirical_target = quantile_sorted(&sample.values, pct / 100.0);
    let mut rel_target = Figure::null("no sample records decenter");
    let law_percentiles = settings
        .percentiles
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let a = p / 100.0;
            let empirical = quantile_sorted(&sample.values, a);
            let rel = relative_difference(fit.sigma, empirical, a, j, boot.as_ref(), conf);
            if p == pct {
                rel_target = rel.clone();
            }
            RayleighPercentile {
                percentile: Real(p),
                value: Figure::new(
                    rayleigh::percentile(fit.sigma, a),
                    rayleigh::percentile(fit.sigma_interval.lower, a),
                    rayleigh::percentile(fit.sigma_interval.upper, a),
                ),
                empirical: empirical.and_then(real),
                relative_difference: rel,
                reason: empirical
                    .is_none()
                    .then(|| "no sample records decenter".into()),
            }
        })
        .collect();
    let components = BTreeMap::from([
        (
            "decenter_x",
            component_report(rayleigh::component_stats(
                points.clone().map(|p| p.decenter_x),
                conf,
            )),
        ),
        (
            "decenter_y",
            component_report(rayleigh::component_stats(
                points.clone().map(|p| p.decenter_y),
                conf,
            )),
        ),
    ]);
    let gof = gof_report(
        gof::rayleigh_gof(&sample.values, cache, &gof_config(settings)),
        "Rayleigh",
        Some(rayleigh::percentile(fit.sigma, pct / 100.0)),
        empirical_target,
        &rel_target,
        settings,
        caveats,
    );
    Quantity {
        report: QuantityReport {
            quantity: "decenter",
            of: "decenter",
            unit: "mm",
            n: n as u64,
            percentiles: pcts.reports,
            law: LawReport {
                law: "rayleigh",
                components,
                sigma: Some(Figure::new(
                    fit.sigma,
                    fit.sigma_interval.lower,
                    fit.sigma_interval.upper,
                )),
                mean: None,
                std: None,
                percentiles: law_percentiles,
                caveats: caveats.to_vec(),
            },
            gof,
        },
        levels: levels(settings, pcts.primary, boot),
    }
}

fn despace(
    case: &CaseData,
    settings: &Settings,
    cache: &mut CalibrationCache,
    caveats: &[String],
) -> Quantity {
    let conf = settings.confidence;
    let points = case.points().filter(|p| p.placed());
    let sample = SortedSample::new(points.clone().map(|p| (p.despace.abs(), p.index)).collect());
    let n = sample.len();
    let (boot, config) = bootstrapped(&sample, settings);
    let pcts = percentiles(&sample, boot.as_ref(), settings, caveats);
    let stats = rayleigh::component_stats(points.clone().map(|p| p.despace), conf);
    let (mean, sd) = match stats {
        Some(s) => (s.mean, s.std.unwrap_or(0.0)),
        None => (0.0, 0.0),
    };
    // Each replicate's weighted mean and standard deviation of the signed despace, with the
    // weights of the replicate percentiles (keyed by the global indices).
    let indices: Vec<u64> = points.clone().map(|p| p.index).collect();
    let values: Vec<f64> = points.clone().map(|p| p.despace).collect();
    let moments: Vec<Option<(f64, f64)>> = if boot.is_some() {
        bootstrap_statistic(&indices, &config, |w, total| {
            let t = total as f64;
            (total >= 2).then(|| {
                let m = w
                    .iter()
                    .zip(&values)
                    .map(|(w, x)| f64::from(*w) * x)
                    .sum::<f64>()
                    / t;
                let ss = w
                    .iter()
                    .zip(&values)
                    .map(|(w, x)| f64::from(*w) * (x - m) * (x - m))
                    .sum::<f64>();
                (m, (ss / (t - 1.0)).sqrt())
            })
        })
    } else {
        Vec::new()
    };
    let pct = settings.target_percentile;
    let empirical_target = quantile_sorted(&sample.values, pct / 100.0);
    let mut rel_target = Figure::null("no sample records despace");
    let law_percentiles = settings
        .percentiles
        .iter()
        .enumerate()
        .map(|(j, &p)| {
            let a = p / 100.0;
            let empirical = quantile_sorted(&sample.values, a);
            let law = folded_normal_quantile(mean, sd, a);
            let rel = match empirical.filter(|q| *q > 0.0) {
                None => Figure::null("empirical percentile is zero or undefined"),
                Some(q) => {
                    let value = (law - q) / q;
                    let reps = boot.iter().flat_map(|b| {
                        b.quantiles[j].iter().zip(&moments).filter_map(|(qs, m)| {
                            let (qs, (m, s)) = ((*qs)?, (*m)?);
                            (qs > 0.0).then(|| (folded_normal_quantile(m, s, a) - qs) / qs)
                        })
                    });
                    match replicate_interval(reps, conf) {
                        Some((lo, hi)) => Figure::new(value, lo, hi),
                        None => Figure::without_interval(value, "no usable bootstrap replicate"),
                    }
                }
            };
            if p == pct {
                rel_target = rel.clone();
            }
            let interval = stats.and_then(|s| s.std_interval);
            RayleighPercentile {
                percentile: Real(p),
                value: match interval {
                    Some(b) => Figure::new(
                        law,
                        folded_normal_quantile(mean, b.lower, a),
                        folded_normal_quantile(mean, b.upper, a),
                    ),
                    None => Figure::without_interval(law, "no interval of the spread"),
                },
                empirical: empirical.and_then(real),
                relative_difference: rel,
                reason: empirical
                    .is_none()
                    .then(|| "no sample records despace".into()),
            }
        })
        .collect();
    let component = component_report(stats);
    let mut signed: Vec<f64> = values.clone();
    signed.sort_by(f64::total_cmp);
    let gof = gof_report(
        gof::normal_gof(&signed, cache, &gof_config(settings)),
        "normal",
        Some(folded_normal_quantile(mean, sd, pct / 100.0)),
        empirical_target,
        &rel_target,
        settings,
        caveats,
    );
    Quantity {
        report: QuantityReport {
            quantity: "despace",
            of: "|despace|",
            unit: "mm",
            n: n as u64,
            percentiles: pcts.reports,
            law: LawReport {
                law: "normal",
                mean: Some(component.mean.clone()),
                std: Some(component.std.clone()),
                components: BTreeMap::from([("despace", component)]),
                sigma: None,
                percentiles: law_percentiles,
                caveats: caveats.to_vec(),
            },
            gof,
        },
        levels: levels(settings, pcts.primary, boot),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The folded normal's quantile: at mean 0 it is the two-sided normal quantile
    /// (Φ⁻¹(0.975) = 1.959964 for α = 0.95); far from 0 it is the normal's own (μ + 1.644854 s).
    #[test]
    fn folded_normal_quantiles_by_hand() {
        assert!((folded_normal_quantile(0.0, 2.0, 0.95) - 2.0 * 1.959_964).abs() < 1e-5);
        let far = folded_normal_quantile(100.0, 1.0, 0.95);
        assert!((far - 101.644_854).abs() < 1e-5, "{far}");
        assert_eq!(folded_normal_quantile(-3.0, 0.0, 0.5), 3.0);
    }
}
