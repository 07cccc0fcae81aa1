//! The shares against brute force. With group g's σ set to 0 the linear model says
//! Var(tilt) loses g's share, and by the Rayleigh law (θ_Pq ∝ σ_t)
//!
//! ```text
//! share_g = 1 − (θ_P95 without g / θ_P95)²
//! ```
//!
//! Both runs draw the same z (sample k at any σ), and both percentiles are bootstrapped with
//! the same Poisson weights (keyed by seed, replicate and sample index), so the ratio's
//! replicates give a tight interval for the brute-force share. It must overlap the
//! regression's share interval, for each group zeroed in turn.

use crate::common::{both, job};
use truss_stats::bootstrap::{
    BootstrapConfig, SortedSample, bootstrap_quantiles, percentile_interval,
};
use truss_tolerance::setup::Study;
use truss_tolerance::simulate::run_case;
use truss_tolerance::{Options, TargetAngle, run};

/// The 95th-percentile replicates of `theta` (Poisson bootstrap, fixed seed, B = 400).
fn replicates(theta: &[f64]) -> Vec<Option<f64>> {
    let sample = SortedSample::new(
        theta
            .iter()
            .enumerate()
            .map(|(k, &t)| (t, k as u64))
            .collect(),
    );
    let config = BootstrapConfig {
        replicates: 400,
        seed: 17,
        threads: 2,
    };
    bootstrap_quantiles(&sample, &[0.95], &config).quantiles[0].clone()
}

#[test]
fn zeroing_a_group_changes_theta_p95_as_the_shares_predict() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 2, &[("c", &both(0.0063))]);
    let n = 4000;
    let options = Options {
        sensitivity_samples: n,
        samples: 1000,
        plots: false,
        ..Options::new(
            path.clone(),
            "c",
            TargetAngle::Arcsec(20.0),
            dir.path().join("out"),
        )
    };
    let t = run(&options).unwrap();
    let study = Study::read(&path, "c", &[], &[]).unwrap();
    let names: Vec<&str> = study.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["batten", "longeron"]);
    let full = run_case(
        &study.job_with(&study.input_sigmas(), n as u64).unwrap(),
        &[],
        2,
        "full",
    )
    .unwrap();
    let full_reps = replicates(&full.theta_p);
    for zero in 0..2 {
        let mut sigmas = study.input_sigmas();
        sigmas[zero] = 0.0;
        let r = run_case(&study.job_with(&sigmas, n as u64).unwrap(), &[], 2, "brute").unwrap();
        let mut implied: Vec<f64> = full_reps
            .iter()
            .zip(replicates(&r.theta_p))
            .filter_map(|(a, b)| Some(1.0 - (b? / (*a)?).powi(2)))
            .collect();
        implied.sort_by(f64::total_cmp);
        let (lo, hi) = percentile_interval(&implied, 0.95).unwrap();
        let (share, (s_lo, s_hi)) = t.groups[zero].share;
        println!(
            "{}: regression share {share:.4} [{s_lo:.4}, {s_hi:.4}], brute force [{lo:.4}, {hi:.4}]",
            names[zero]
        );
        assert!(
            s_lo <= hi && lo <= s_hi,
            "{}: the regression's share {share:.4} [{s_lo:.4}, {s_hi:.4}], brute force [{lo:.4}, {hi:.4}]",
            names[zero]
        );
    }
    // The check has teeth: the longerons carry almost all the variance, the battens little.
    assert!(t.groups[0].share.0 < 0.05 && t.groups[1].share.0 > 0.9);
}
