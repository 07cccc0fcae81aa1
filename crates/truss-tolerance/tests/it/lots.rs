//! Production lots in the study (`GROUP.lot`, see `truss_tolerance::setup` and
//! `truss_tolerance::sensitivity`).
//!
//! - A lot of σ 0 is the study without the lot: its draws are zero, so every sample, the
//!   regression and the allocation are the same, and the lot part's share is 0.
//! - A lot on one side of the truss dominates: on the 2-stage prism (units mm) the battens
//!   and the longerons' own parts have σ = 0.002 and each of the three longeron columns
//!   (`longeron.1.j`, `longeron.2.j`) is one lot with σ_L = 0.006: one side's longerons
//!   lengthen together, which tilts the top. The lot part's share from the regression
//!   (`σ_L² Σ_L |B_L|² / Var t`) is checked against a direct Monte Carlo that needs no
//!   regression: the tilt variance `Var tan θ_x + Var tan θ_y` of a run with only the lot
//!   parts drawn (every own σ 0) over that of the full run. Both runs share their draws (the
//!   lot parts come from a stream of their own), so the ratio's sampling error is that of
//!   the linear model's residual only; they agree within 0.03 (the shares' own 95 %
//!   interval is about ±0.02 at 4,000 samples). And the part left by the lots, `1 −
//!   Var(own parts only)/Var(full)`, matches too.

use crate::common::job;
use truss_tolerance::setup::Study;
use truss_tolerance::simulate::run_case;
use truss_tolerance::{Options, TargetAngle, Tolerance, run};

fn options(path: std::path::PathBuf, out: std::path::PathBuf, n: usize, arcsec: f64) -> Options {
    Options {
        sensitivity_samples: n,
        samples: 2000,
        plots: false,
        quiet: true,
        ..Options::new(path, "c", TargetAngle::Arcsec(arcsec), out)
    }
}

fn study(errors: &str, n: usize) -> Tolerance {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 2, &[("c", errors)]);
    run(&options(path, dir.path().join("out"), n, 20.0)).unwrap()
}

#[test]
fn a_lot_of_sigma_zero_is_the_study_without_it() {
    let plain = study(
        r#"{"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}"#,
        1500,
    );
    let lot = study(
        r#"{"batten": {"normal": {"sigma": 0.0063}, "lot": {"by": "level", "normal": {"sigma": 0}}}, "longeron": {"normal": {"sigma": 0.0063}}}"#,
        1500,
    );
    assert_eq!(lot.groups.len(), 3);
    let l = &lot.groups[2];
    assert_eq!(l.name, "batten.lot");
    assert!(l.lot && l.fixed);
    assert_eq!(l.members, 3, "one lot per level of battens");
    assert_eq!((l.sigma, l.share.0, l.derivative), (0.0, 0.0, 0.0));
    // A lot's covariance comes from the own parts' β, whatever its σ.
    assert!(l.sensitivity > 0.0);
    for (a, b) in plain.groups.iter().zip(&lot.groups) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.sigma, b.sigma, "{}", a.name);
        assert_eq!(a.share, b.share, "{}", a.name);
        assert_eq!(a.sensitivity, b.sensitivity, "{}", a.name);
        assert_eq!(a.derivative, b.derivative, "{}", a.name);
    }
    assert_eq!(plain.input, lot.input);
    assert_eq!(plain.uniform_sigma, lot.uniform_sigma);
    assert_eq!(plain.cost, lot.cost);
    assert_eq!(plain.runs.last().unwrap().1, lot.runs.last().unwrap().1);
    assert!(lot.verified);
}

/// Var tan θ_x + Var tan θ_y of a run.
fn tilt_variance(tilt: &[[f64; 2]]) -> f64 {
    let n = tilt.len() as f64;
    (0..2)
        .map(|a| {
            let mean = tilt.iter().map(|t| t[a]).sum::<f64>() / n;
            tilt.iter().map(|t| (t[a] - mean).powi(2)).sum::<f64>() / n
        })
        .sum()
}

#[test]
fn a_one_sided_lot_has_the_share_a_direct_monte_carlo_gives() {
    let errors = r#"{"batten": {"normal": {"sigma": 0.002}},
        "longeron": {"normal": {"sigma": 0.002}, "lot": {"by": [
            ["longeron.1.0", "longeron.2.0"], ["longeron.1.1", "longeron.2.1"], ["longeron.1.2", "longeron.2.2"]],
            "normal": {"sigma": 0.006}}}}"#;
    let n = 4000;
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 2, &[("c", errors)]);
    // The lot alone gives θ_P95 ≈ 22″: a target of 40″ leaves the own parts room.
    let t = run(&options(path.clone(), dir.path().join("out"), n, 40.0)).unwrap();
    let names: Vec<&str> = t.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["batten", "longeron", "longeron.lot"]);
    let lot = &t.groups[2];
    assert_eq!((lot.members, lot.sigma), (3, 0.006));

    // Direct Monte Carlo on the same draws: full, lot parts only, own parts only.
    let s = Study::read(&path, "c", &[], &[]).unwrap();
    let variance = |sigmas: &[f64]| {
        let r = run_case(&s.job_with(sigmas, n as u64).unwrap(), &[], 2, "direct").unwrap();
        tilt_variance(&r.tilt)
    };
    let full = variance(&[0.002, 0.002, 0.006]);
    let lots_only = variance(&[0.0, 0.0, 0.006]);
    let own_only = variance(&[0.002, 0.002, 0.0]);
    let direct = lots_only / full;
    let (share, (lo, hi)) = lot.share;
    assert!(direct > 0.5, "the lot dominates: direct share {direct}");
    assert!(lo <= share && share <= hi, "{share} [{lo}, {hi}]");
    assert!(
        (share - direct).abs() < 0.03,
        "regression {share} [{lo}, {hi}], direct {direct}"
    );
    let left = 1.0 - own_only / full;
    assert!(
        (share - left).abs() < 0.03,
        "regression {share}, 1 − own/full {left}"
    );
    // The own parts' shares and the lot's add up to the part a linear model explains.
    let sum: f64 = t.groups.iter().map(|g| g.share.0).sum();
    let explained = 1.0 - t.sensitivity.nonlinear.0;
    assert!((sum - explained).abs() < 0.05, "{sum} vs {explained}");
    // The allocation holds the lot at its σ and still meets the target on runs that draw it.
    assert!(t.verified);
    for (sigmas, _, _) in &t.runs {
        assert_eq!(sigmas[2], 0.006);
    }
    // tolerance.json and tolerance.md name the lot part as one.
    let out = dir.path().join("out");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tolerance.json")).unwrap())
            .unwrap();
    let g = &doc["groups"]["longeron.lot"];
    assert_eq!(
        (g["lot"].as_bool(), g["fixed"].as_bool()),
        (Some(true), Some(true))
    );
    assert_eq!(doc["groups"]["longeron"]["lot"], false);
    assert_eq!(g["share"].as_f64(), Some(share));
    let md = std::fs::read_to_string(out.join("tolerance.md")).unwrap();
    assert!(
        md.contains("| longeron.lot | 3 |") && md.contains("lot part, held at its σ"),
        "{md}"
    );
    // The lot's covariance per unit σ_L² is what the share says: S_lot σ_L² / (Var t / 2).
    let from_sensitivity = lot.sensitivity * 0.006 * 0.006 / (0.5 * t.sensitivity.fit.total);
    assert!((from_sensitivity / share - 1.0).abs() < 1e-9);
}

/// A lot spread symmetrically: `"by": "level"` makes each stage's three longerons one lot, so
/// a lot's draw changes the stage's height evenly (despace) and tilts nothing; its share is
/// near 0 however large σ_L, and the allocation is the own parts'.
#[test]
fn a_lot_around_the_axis_adds_no_tilt() {
    let t = study(
        r#"{"batten": {"normal": {"sigma": 0.002}}, "longeron": {"normal": {"sigma": 0.002}, "lot": {"by": "level", "normal": {"sigma": 0.006}}}}"#,
        4000,
    );
    let lot = &t.groups[2];
    assert_eq!((lot.name.as_str(), lot.members), ("longeron.lot", 2));
    let (share, (_, hi)) = lot.share;
    assert!(share < 0.01 && hi < 0.02, "{share}, up to {hi}");
    assert!(
        t.groups[1].share.0 > 0.9,
        "the longerons' own parts: {:?}",
        t.groups[1].share
    );
    assert!(t.verified);
}
