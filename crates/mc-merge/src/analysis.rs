//! The statistics of one case: percentiles with three kinds of interval, the Rayleigh law and
//! its goodness of fit, loose joints. Turns verified samples into a [`CaseReport`].

use crate::bootstrap::{
    self, BootstrapConfig, QuantileReplicates, SortedSample, bootstrap_quantiles,
};
use crate::definitions::LOOSE_HOLDING_FORCE;
use crate::gof::{self, CalibrationCache, GofConfig};
use crate::load::CaseData;
use crate::quantile::{order_statistic_interval, quantile_sorted};
use crate::rayleigh::{self, ComponentStats};
use crate::report::*;
use crate::settings::Settings;
use statrs::distribution::{Beta, ContinuousCDF};

/// A case's report plus what the sweeps and the budget need: the target percentile, its
/// interval and its bootstrap replicates, and every percentile's, of θ_P, decenter and
/// |despace|.
#[derive(Debug, Clone)]
pub struct CaseAnalysis {
    /// The case's section of the report.
    pub report: CaseReport,
    /// The target percentile (rad) with its BCa (else percentile) interval.
    pub target: Figure,
    /// The target percentile of each bootstrap replicate (`None`: empty replicate, or no bootstrap).
    pub target_replicates: Vec<Option<f64>>,
    /// θ_P at every percentile of the settings.
    pub theta: Levels,
    /// Decenter at every percentile, where the samples record it ([`crate::merge`] fills
    /// it in from [`crate::placement`], as the decenter and despace of `report`).
    pub decenter: Option<Levels>,
    /// |despace| at every percentile, where the samples record it.
    pub despace: Option<Levels>,
}

/// A quantity's percentiles at every level of the settings, with their bootstrap replicates.
#[derive(Debug, Clone, Default)]
pub struct Levels {
    /// The levels, in percent.
    pub percentiles: Vec<f64>,
    /// Per level, the estimate with its BCa (else percentile) interval.
    pub primary: Vec<Figure>,
    /// Per level, the estimate of each bootstrap replicate (empty without a bootstrap).
    pub replicates: Vec<Vec<Option<f64>>>,
}

impl Levels {
    /// The figure and replicates at percentile `pct`, if it is one of the levels.
    pub fn at(&self, pct: f64) -> Option<(&Figure, &[Option<f64>])> {
        let j = self.percentiles.iter().position(|&p| p == pct)?;
        Some((
            &self.primary[j],
            self.replicates.get(j).map_or(&[][..], |r| &r[..]),
        ))
    }
}

/// The holding forces of a case's converged samples (see [`HoldingForces`]); `target` is
/// the empirical target percentile of θ_P \[rad\], if any, whose tail is summarised apart.
pub fn holding_forces(case: &CaseData, target: Option<f64>, conf: f64) -> HoldingForces {
    let (mut forces, mut loose, mut tail_recorded, mut tail_loose) = (Vec::new(), 0, 0, 0);
    for p in case.points().filter(|p| !p.holding.is_nan()) {
        let is_loose = u64::from(p.holding < LOOSE_HOLDING_FORCE);
        forces.push(p.holding);
        loose += is_loose;
        if target.is_some_and(|t| p.theta > t) {
            tail_recorded += 1;
            tail_loose += is_loose;
        }
    }
    forces.sort_by(f64::total_cmp);
    let recorded = forces.len() as u64;
    HoldingForces {
        recorded,
        percentiles: [5.0, 50.0, 95.0]
            .iter()
            .map(|&pct| {
                let value = quantile_sorted(&forces, pct / 100.0).and_then(real);
                HoldingPercentile {
                    percentile: Real(pct),
                    reason: value.is_none().then(|| {
                        "no converged sample records a holding force (models whose bars \
                         frame the tilt do not)"
                            .into()
                    }),
                    value,
                }
            })
            .collect(),
        loose_below: Real(LOOSE_HOLDING_FORCE),
        loose,
        loose_fraction: clopper_pearson(loose, recorded, conf),
        tail_recorded,
        tail_loose,
        tail_loose_fraction: clopper_pearson(tail_loose, tail_recorded, conf),
    }
}

/// The caveats every figure of a case carries; `tail` is the fraction of samples above the
/// target percentile (0.05 for P95), `holding` the case's holding forces.
pub fn caveats(case: &CaseData, tail: f64, holding: &HoldingForces) -> Vec<String> {
    let mut out = vec![];
    if holding.tail_loose > 0 {
        out.push(format!(
            "{} of the {} samples above the target percentile are held by less than 1 µN \
             on a top node (holding force): a force that small, or a joint's friction the \
             model leaves out, moves their θ_P by 1 % or more, so the target percentile \
             rests on how the model resolves loose joints and slack cables",
            holding.tail_loose, holding.tail_recorded
        ));
    }
    let (recorded, floating) = case.floating();
    if recorded > 0 && floating as f64 > tail * recorded as f64 {
        out.push(format!(
            "floating stages in {floating} of {recorded} samples ({:.1} %, more than the {:.0} % \
             tail the target percentile reads): some stage's tilt is held by pretension alone, \
             so θ_P's upper percentiles depend on what the model leaves out (friction, the \
             diagonals' bending stiffness, the assembly); more diagonal pretension or smaller \
             clearances frame the stages",
            100.0 * floating as f64 / recorded as f64,
            100.0 * tail
        ));
    }
    let (stages, largest) = case.limit_stages();
    if stages > 0 {
        out.push(format!(
            "in {stages} of {} converged samples the solve at the limit (slack members carrying \
             nothing) did not converge, and the equilibrium recorded is the last stage of the \
             continuation towards it, where the slack members keep a compression ratio of at \
             most {largest:.1e} (`limit_ratio`): their θ_P is the limit's only as far as that \
             stiffness holds nothing (see the README, \"Slack cables\")",
            case.converged()
        ));
    }
    if case.present < case.info.samples {
        out.push(format!(
            "partial: {} of {} samples of this case present ({:.1} %)",
            case.present,
            case.info.samples,
            100.0 * case.present as f64 / case.info.samples.max(1) as f64
        ));
    }
    if case.failed > 0 {
        out.push(format!(
            "{} failed samples excluded: computed on the {} converged samples; if failures are more likely for large distortions the upper percentiles are biased low",
            case.failed,
            case.converged()
        ));
    }
    out
}

/// Formats a p-value, showing the Monte Carlo floor `1/(M+1)` as a bound.
pub fn format_p(p: f64, replicates: usize) -> String {
    let floor = 1.0 / (replicates as f64 + 1.0);
    if p <= floor * (1.0 + 1e-9) {
        format!("p ≤ {floor:.1e}")
    } else if p < 0.01 {
        format!("p = {p:.4}")
    } else {
        // Three decimals, the resolution of 1000 null samples: 0.047 is not shown as 0.05,
        // the level it is compared with.
        format!("p = {p:.3}")
    }
}

pub(crate) fn component_report(stats: Option<ComponentStats>) -> ComponentReport {
    let Some(s) = stats else {
        let none = || Figure::null("no converged sample");
        return ComponentReport {
            mean: none(),
            std: none(),
            rms: none(),
        };
    };
    let with = |v: f64, b: Option<rayleigh::Bounds>, why: &str| match b {
        Some(b) => Figure::new(v, b.lower, b.upper),
        None => Figure::without_interval(v, why),
    };
    ComponentReport {
        mean: with(s.mean, s.mean_interval, "n = 1: no interval"),
        std: match s.std {
            Some(sd) => with(sd, s.std_interval, "no interval"),
            None => Figure::null("n = 1: no standard deviation"),
        },
        rms: with(s.rms, s.rms_interval, "no interval"),
    }
}

/// The Clopper–Pearson interval of a binomial fraction k/n (Clopper & Pearson 1934).
pub fn clopper_pearson(k: u64, n: u64, confidence: f64) -> Figure {
    if n == 0 {
        return Figure::null("no sample records the field");
    }
    let tail = (1.0 - confidence) / 2.0;
    let (kf, nf) = (k as f64, n as f64);
    let lower = if k == 0 {
        0.0
    } else {
        Beta::new(kf, nf - kf + 1.0).map_or(f64::NAN, |b| b.inverse_cdf(tail))
    };
    let upper = if k == n {
        1.0
    } else {
        Beta::new(kf + 1.0, nf - kf).map_or(f64::NAN, |b| b.inverse_cdf(1.0 - tail))
    };
    Figure::new(kf / nf, lower, upper)
}

/// The percentile-method interval of replicate values (unsorted, `None`s skipped).
pub fn replicate_interval(
    values: impl Iterator<Item = f64>,
    confidence: f64,
) -> Option<(f64, f64)> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    bootstrap::percentile_interval(&v, confidence)
}

pub(crate) struct Percentiles {
    pub(crate) reports: Vec<PercentileReport>,
    /// Per level: point estimate and primary (BCa, else percentile) interval.
    pub(crate) primary: Vec<Figure>,
}

pub(crate) fn percentiles(
    sample: &SortedSample,
    boot: Option<&QuantileReplicates>,
    settings: &Settings,
    caveats: &[String],
) -> Percentiles {
    let conf = settings.confidence;
    let n = sample.len();
    let mut reports = vec![];
    let mut primary = vec![];
    for (j, &pct) in settings.percentiles.iter().enumerate() {
        let p = pct / 100.0;
        let value = quantile_sorted(&sample.values, p);
        let no_boot = if n == 0 {
            "no converged sample".to_string()
        } else {
            format!("n = {n}: the bootstrap needs at least 2 samples")
        };
        let (pb, bca) = match (value, boot) {
            (Some(q), Some(b)) => {
                let reps = b.sorted_level(j);
                let pb = match bootstrap::percentile_interval(&reps, conf) {
                    Some((lo, hi)) => Interval::new(lo, hi),
                    None => Interval::null("no non-empty bootstrap replicate"),
                };
                let bca = match bootstrap::quantile_acceleration(&sample.values, p, q)
                    .ok_or_else(|| "acceleration undefined".to_string())
                    .and_then(|a| bootstrap::bca_interval(&reps, q, a, conf))
                {
                    Ok(i) => BcaReport {
                        lower: real(i.lower),
                        upper: real(i.upper),
                        z0: real(i.z0),
                        acceleration: real(i.acceleration),
                        reason: None,
                    },
                    Err(reason) => BcaReport {
                        reason: Some(reason),
                        ..Default::default()
                    },
                };
                (pb, bca)
            }
            _ => (
                Interval::null(no_boot.clone()),
                BcaReport {
                    reason: Some(no_boot.clone()),
                    ..Default::default()
                },
            ),
        };
        let os = match order_statistic_interval(&sample.values, p, conf) {
            Ok(i) => OrderStatisticReport {
                lower: real(i.lower),
                upper: real(i.upper),
                lower_rank: Some(i.lower_rank),
                upper_rank: Some(i.upper_rank),
                coverage: real(i.coverage),
                reason: None,
            },
            Err(reason) => OrderStatisticReport {
                reason: Some(reason),
                ..Default::default()
            },
        };
        primary.push(match value {
            None => Figure::null("no converged sample"),
            Some(q) => match (bca.lower, bca.upper, pb.get()) {
                (Some(lo), Some(hi), _) => Figure::new(q, lo.0, hi.0),
                (_, _, Some((lo, hi))) => Figure {
                    reason: Some("percentile-bootstrap interval (BCa undefined)".into()),
                    ..Figure::new(q, lo, hi)
                },
                _ => Figure::without_interval(q, no_boot),
            },
        });
        reports.push(PercentileReport {
            percentile: Real(pct),
            value: value.and_then(real),
            reason: value.is_none().then(|| "no converged sample".into()),
            percentile_bootstrap: pb,
            bca,
            order_statistic: os,
            caveats: caveats.to_vec(),
        });
    }
    Percentiles { reports, primary }
}

/// Relative difference (Rayleigh − empirical)/empirical at level `p`, with its bootstrap interval.
pub(crate) fn relative_difference(
    sigma: f64,
    empirical: Option<f64>,
    p: f64,
    j: usize,
    boot: Option<&QuantileReplicates>,
    confidence: f64,
) -> Figure {
    let Some(q) = empirical.filter(|q| *q > 0.0) else {
        return Figure::null("empirical percentile is zero or undefined");
    };
    let value = (rayleigh::percentile(sigma, p) - q) / q;
    let Some(b) = boot else {
        return Figure::without_interval(value, "no bootstrap");
    };
    let reps = b
        .replicates
        .iter()
        .zip(&b.quantiles[j])
        .filter_map(|(r, qs)| {
            let qs = (*qs)?;
            (r.total_weight > 0 && qs > 0.0).then(|| {
                let s = (r.weighted_sum_sq / (2.0 * r.total_weight as f64)).sqrt();
                (rayleigh::percentile(s, p) - qs) / qs
            })
        });
    match replicate_interval(reps, confidence) {
        Some((lo, hi)) => Figure::new(value, lo, hi),
        None => Figure::without_interval(value, "no usable bootstrap replicate"),
    }
}

/// The goodness-of-fit settings of `settings`.
pub(crate) fn gof_config(settings: &Settings) -> GofConfig {
    GofConfig {
        replicates: settings.gof_replicates,
        seed: settings.bootstrap_seed,
        threads: settings.threads,
    }
}

/// The report of a goodness-of-fit test of law `law` ("Rayleigh", "normal"), whose
/// percentile at the target percentile is `law_target`.
pub(crate) fn gof_report(
    result: Result<gof::RayleighGof, String>,
    law: &str,
    law_target: Option<f64>,
    empirical_target: Option<f64>,
    target_rel: &Figure,
    settings: &Settings,
    caveats: &[String],
) -> GofReport {
    let level = settings.gof_level;
    let pct = settings.target_percentile;
    let g = match result {
        Ok(g) => g,
        Err(reason) => {
            return GofReport {
                verdict: None,
                summary: format!("{law} law not tested: {reason}"),
                level: Real(level),
                ks: None,
                ad: None,
                null_calibration: None,
                effect: None,
                reason: Some(reason),
                caveats: caveats.to_vec(),
            };
        }
    };
    let holds = g.ks_p >= level && g.ad_p >= level;
    let m = g.calibration_replicates;
    let effect = match (law_target, empirical_target) {
        (Some(l), Some(q)) => Some(EffectReport {
            percentile: Real(pct),
            rayleigh: Real(l),
            empirical: Real(q),
            relative_difference: target_rel.clone(),
            max_cdf_gap: Real(g.statistics.ks),
        }),
        _ => None,
    };
    let mut summary = format!(
        "{law} law {} (KS {}, AD {})",
        if holds { "holds" } else { "rejected" },
        format_p(g.ks_p, m),
        format_p(g.ad_p, m)
    );
    if let Some(rel) = target_rel.get() {
        let pct_txt = format!("{pct}th percentile");
        if holds {
            summary.push_str(&format!(
                "; {law} {pct_txt} within {:.1} % of the empirical one",
                rel.abs() * 100.0
            ));
        } else {
            summary.push_str(&format!(
                "; {law} {pct_txt} {:.1} % {} the empirical one",
                rel.abs() * 100.0,
                if rel >= 0.0 { "above" } else { "below" }
            ));
        }
    }
    summary.push_str(&format!(", max CDF gap {:.4}", g.statistics.ks));
    GofReport {
        verdict: Some(if holds { "holds" } else { "rejected" }),
        summary,
        level: Real(level),
        ks: Some(TestReport {
            statistic: Real(g.statistics.ks),
            modified: Real(g.statistics.ks_modified),
            p_value: Real(g.ks_p),
            p_value_se: Real(g.ks_p_se),
        }),
        ad: Some(TestReport {
            statistic: Real(g.statistics.ad),
            modified: Real(g.statistics.ad_modified),
            p_value: Real(g.ad_p),
            p_value_se: Real(g.ad_p_se),
        }),
        null_calibration: Some(NullCalibrationReport {
            sample_size: g.calibration_n,
            replicates: m,
        }),
        effect,
        reason: None,
        caveats: caveats.to_vec(),
    }
}

/// Computes every statistic of one case.
pub fn analyse_case(
    case: &CaseData,
    settings: &Settings,
    cache: &mut CalibrationCache,
) -> CaseAnalysis {
    let conf = settings.confidence;
    let sample = SortedSample::new(case.points().map(|p| (p.theta, p.index)).collect());
    let empirical_target = quantile_sorted(&sample.values, settings.target_percentile / 100.0);
    let holding = holding_forces(case, empirical_target, conf);
    let caveats = caveats(case, 1.0 - settings.target_percentile / 100.0, &holding);
    let n = sample.len();
    let levels: Vec<f64> = settings.percentiles.iter().map(|p| p / 100.0).collect();
    let boot = (n >= 2).then(|| {
        bootstrap_quantiles(
            &sample,
            &levels,
            &BootstrapConfig {
                replicates: settings.replicates,
                seed: settings.bootstrap_seed,
                threads: settings.threads,
            },
        )
    });
    let pcts = percentiles(&sample, boot.as_ref(), settings, &caveats);
    // `Settings::validate` adds the target percentile; without it, the sweeps use the last one.
    let target_j = settings
        .percentiles
        .iter()
        .position(|&p| p == settings.target_percentile)
        .unwrap_or(settings.percentiles.len().saturating_sub(1));

    // Rayleigh law, sums in global index order.
    let points = case.points();
    let sum_sq_theta: f64 = points.clone().map(|p| p.theta * p.theta).sum();
    let tx = rayleigh::component_stats(points.clone().map(|p| p.tan_x), conf);
    let ty = rayleigh::component_stats(points.clone().map(|p| p.tan_y), conf);
    let fit = (n > 0).then(|| rayleigh::fit_from_sum_sq(n, sum_sq_theta, conf));
    let sigma_t = match (tx, ty) {
        (Some(x), Some(y)) => {
            let s = x.sum_sq + y.sum_sq;
            let v = (s / (2.0 * n as f64)).sqrt();
            match rayleigh::chi2_scale_interval(s, 2.0 * n as f64, conf) {
                Ok(b) => Figure::new(v, b.lower, b.upper),
                Err(e) => Figure::without_interval(v, e),
            }
        }
        _ => Figure::null("no converged sample"),
    };
    let mut rel_target = Figure::null("no converged sample");
    let rayleigh_pcts: Vec<RayleighPercentile> = settings
        .percentiles
        .iter()
        .enumerate()
        .map(|(j, &pct)| {
            let p = pct / 100.0;
            let empirical = quantile_sorted(&sample.values, p);
            let (value, rel) = match fit {
                Some(f) => (
                    Figure::new(
                        rayleigh::percentile(f.sigma, p),
                        rayleigh::percentile(f.sigma_interval.lower, p),
                        rayleigh::percentile(f.sigma_interval.upper, p),
                    ),
                    relative_difference(f.sigma, empirical, p, j, boot.as_ref(), conf),
                ),
                None => (
                    Figure::null("no converged sample"),
                    Figure::null("no converged sample"),
                ),
            };
            if j == target_j {
                rel_target = rel.clone();
            }
            RayleighPercentile {
                percentile: Real(pct),
                value,
                empirical: empirical.and_then(real),
                relative_difference: rel,
                reason: empirical.is_none().then(|| "no converged sample".into()),
            }
        })
        .collect();
    let rayleigh = RayleighReport {
        tan_theta_x: component_report(tx),
        tan_theta_y: component_report(ty),
        sigma_t,
        sigma: match fit {
            Some(f) => Figure::new(f.sigma, f.sigma_interval.lower, f.sigma_interval.upper),
            None => Figure::null("no converged sample"),
        },
        percentiles: rayleigh_pcts,
        caveats: caveats.clone(),
    };
    let gof = gof_report(
        gof::rayleigh_gof(&sample.values, cache, &gof_config(settings)),
        "Rayleigh",
        fit.map(|f| rayleigh::percentile(f.sigma, settings.target_percentile / 100.0)),
        empirical_target,
        &rel_target,
        settings,
        &caveats,
    );

    let (recorded, with_loose) = case.loose_joints();
    let (floating_recorded, floating) = case.floating();
    let failed_ranges = case.failed_ranges();
    let report = CaseReport {
        name: case.info.name.clone(),
        parameters: case
            .info
            .parameters
            .iter()
            .filter_map(|(k, v)| real(*v).map(|r| (k.clone(), r)))
            .collect(),
        expected: case.info.samples,
        present: case.present,
        n: n as u64,
        failed: FailedCaseReport {
            count: case.failed,
            ranges: failed_ranges
                .iter()
                .take(100)
                .map(|r| [r.start, r.end])
                .collect(),
            reasons: case
                .failed_reasons
                .iter()
                .map(|(i, r)| FailedReason {
                    index: *i,
                    reason: r.clone(),
                })
                .collect(),
        },
        caveats: caveats.clone(),
        loose_joints: LooseJoints {
            recorded,
            with_loose,
            fraction: clopper_pearson(with_loose, recorded, conf),
        },
        floating: Floating {
            recorded: floating_recorded,
            floating,
            fraction: clopper_pearson(floating, floating_recorded, conf),
        },
        holding_force: holding,
        bootstrap: BootstrapCase {
            replicates: if boot.is_some() {
                settings.replicates
            } else {
                0
            },
            empty_replicates: boot.as_ref().map_or(0, |b| b.empty()),
        },
        percentiles: pcts.reports,
        rayleigh,
        gof,
        // Filled in by the caller from `crate::placement::analyse`.
        decenter: None,
        despace: None,
    };
    CaseAnalysis {
        report,
        target: pcts.primary[target_j].clone(),
        target_replicates: boot
            .as_ref()
            .map(|b| b.quantiles[target_j].clone())
            .unwrap_or_default(),
        theta: Levels {
            percentiles: settings.percentiles.clone(),
            primary: pcts.primary,
            replicates: boot.map(|b| b.quantiles).unwrap_or_default(),
        },
        decenter: None,
        despace: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clopper–Pearson by hand: k = 0 of n gives upper 1 − (α/2)^{1/n} (the "rule of three"
    /// family); n = 10, 95 %: 1 − 0.025^{0.1} = 0.3085.
    #[test]
    fn clopper_pearson_zero_successes_by_hand() {
        let f = clopper_pearson(0, 10, 0.95);
        assert_eq!(f.get(), Some(0.0));
        let (lo, hi) = f.interval().unwrap();
        assert_eq!(lo, 0.0);
        assert!((hi - (1.0 - 0.025f64.powf(0.1))).abs() < 1e-6, "{hi}");
        assert!(clopper_pearson(0, 0, 0.95).get().is_none());
    }

    #[test]
    fn p_value_floor_is_shown_as_bound() {
        assert_eq!(format_p(1.0 / 1001.0, 1000), "p ≤ 1.0e-3");
        assert_eq!(format_p(0.41, 1000), "p = 0.410");
        // Not rounded onto the level it is compared with.
        assert_eq!(format_p(0.047, 1000), "p = 0.047");
    }
}
