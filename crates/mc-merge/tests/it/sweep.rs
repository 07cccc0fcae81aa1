//! Sweeps through the whole merge: a σ-series whose slopes are proportional to σ recovers the
//! known slope of θ_P95 against σ and the allowable σ = target/slope (paper section 3.1, Fig. 3);
//! a stages series recovers known ratios and its peak (section 3.4, Fig. 9).
//!
//! Known values: with tan θ_x, tan θ_y ~ N(0, σ_t²) and σ_t = c·σ, θ_P ≈ Rayleigh(σ_t), so the
//! 95th percentile is σ_t·√(−2 ln 0.05) (eq. 28) and the slope is c·√(−2 ln 0.05). The paper's
//! numbers fix c: σ_t = 3.96e-5 at σ = 6.30e-3 mm.

use crate::common::{SynthCase, SynthJob};
use mc_merge::Settings;

fn settings() -> Settings {
    Settings {
        replicates: 400,
        gof_replicates: 99,
        ..Settings::default()
    }
}

#[test]
fn sigma_series_recovers_slope_and_allowable_sigma() {
    let c = 3.96e-5 / 6.30e-3;
    let k95 = (-2.0 * 0.05f64.ln()).sqrt();
    let true_slope = c * k95;
    let cases = [0.0033, 0.0067, 0.017, 0.033, 0.067]
        .iter()
        .map(|&s| {
            SynthCase::rayleigh(
                &format!("sigma-{s}"),
                5000,
                c * s,
                &[("sigma", s), ("stages", 5.0)],
            )
        })
        .collect();
    let job = SynthJob::new(11, cases);
    let dir = tempfile::tempdir().unwrap();
    job.write_split(dir.path(), 3);
    let merge = mc_merge::merge(&[dir.path().to_path_buf()], &settings()).unwrap();
    let series = &merge.report.sweep.sigma_series;
    assert_eq!(series.len(), 1);
    let s = &series[0];
    let slope = s.through_origin.slope.get().unwrap();
    let (lo, hi) = s.through_origin.slope.interval().unwrap();
    assert!(
        (slope / true_slope - 1.0).abs() < 0.03,
        "{slope} vs {true_slope}"
    );
    // The interval is honest: the truth lies within a few half-widths.
    assert!(
        (slope - true_slope).abs() < 4.0 * (hi - lo) / 2.0,
        "[{lo}, {hi}]"
    );
    assert!(s.through_origin.r_squared.get().unwrap() > 0.999);
    let target = merge.report.settings.target_angle;
    let allow = s.allowable_sigma.through_origin.get().unwrap();
    assert!(
        (allow - target / slope).abs() < 1e-15,
        "σ_a = target/slope exactly"
    );
    // The paper: σ_a = 6.30e-3 mm for 9.69e-5 rad.
    assert!((allow / 6.30e-3 - 1.0).abs() < 0.03, "{allow}");
    let (alo, ahi) = s.allowable_sigma.through_origin.interval().unwrap();
    assert!(alo < allow && allow < ahi);
    assert!(!s.allowable_sigma.extrapolated);
    // The line with intercept: intercept near 0 within a few interval half-widths.
    let b = s.with_intercept.intercept.get().unwrap();
    let (blo, bhi) = s.with_intercept.intercept.interval().unwrap();
    assert!(
        b.abs() < 4.0 * (bhi - blo) / 2.0 + 1e-7,
        "{b} [{blo}, {bhi}]"
    );
}

#[test]
fn stages_series_recovers_ratios_and_peak() {
    // σ_t ratios 1, 1.2, 1.35, 1.1, 1.05 for 1..=5 stages: the peak is at 3 stages.
    let ratios = [1.0, 1.2, 1.35, 1.1, 1.05];
    let cases = ratios
        .iter()
        .enumerate()
        .map(|(k, &r)| {
            SynthCase::rayleigh(
                &format!("stages-{}", k + 1),
                8000,
                1e-4 * r,
                &[("sigma", 0.067), ("stages", (k + 1) as f64)],
            )
        })
        .collect();
    let job = SynthJob::new(12, cases);
    let dir = tempfile::tempdir().unwrap();
    job.write_split(dir.path(), 2);
    let merge = mc_merge::merge(&[dir.path().to_path_buf()], &settings()).unwrap();
    let st = &merge.report.sweep.stages_series;
    assert_eq!(st.len(), 1);
    assert_eq!(st[0].reference_stages.0, 1.0);
    assert_eq!(st[0].peak_stages.map(|r| r.0), Some(3.0));
    for (p, &r) in st[0].points.iter().zip(&ratios) {
        let v = p.normalised.get().unwrap();
        assert!(
            (v / r - 1.0).abs() < 0.05,
            "{} stages: {v} vs {r}",
            p.stages.0
        );
        let (lo, hi) = p.normalised.interval().unwrap();
        assert!(lo <= v && v <= hi);
    }
    // The reference's own ratio is exactly 1.
    assert_eq!(st[0].points[0].normalised.get(), Some(1.0));
    assert!(merge.report.sweep.sigma_series.is_empty());
}
