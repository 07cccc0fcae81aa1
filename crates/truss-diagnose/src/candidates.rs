//! The library of candidate effects: physical mechanisms the baseline may lack, each with a
//! few parameters in a plausible range, applied to a case through the job format of
//! `truss-job`. Each lives in a file of its own, which says what it does, its parameters
//! and their ranges:
//!
//! | name | home |
//! |---|---|
//! | `backlash` | [`backlash::Backlash`]: clearance at pin joints, the joints' mean clearance and (members measured) its spread |
//! | `gravity` | [`gravity::Gravity`]: self-weight of a ground test, `g_x`, `g_y`, `g_z` \[g\] |
//! | `thermal_gradient` | [`thermal::Thermal`]: a linear temperature field, three gradients \[K/mm\] and a uniform offset \[K\] |
//! | `length_bias` | [`length_bias::LengthBias`]: a length offset \[mm\] per bar group |
//! | `length_sigma` | [`length_sigma::LengthSigma`]: the manufacturing σ \[mm\] per group with a stated spread |
//! | `diagonal_pretension` | [`pretension::DiagonalPretension`]: a common length error \[mm\] of the diagonals |
//!
//! They register once, in [`REGISTRY`] (in this order): the library of a baseline
//! ([`library_for`]), the names `--candidates` and `--effect` accept and their error
//! messages ([`names`]), and the reports all read it. A new mechanism is one more
//! implementation of [`Candidate`] in a file of its own and one more entry there.
//!
//! Every candidate reduces to the baseline at its *null* parameters (zero, or the stated σ),
//! so the baseline is nested in it and a likelihood-ratio test applies.

pub mod backlash;
pub mod candidate;
pub mod gravity;
pub mod length_bias;
pub mod length_sigma;
pub mod parameter;
pub mod pretension;
pub mod thermal;

pub use candidate::{Candidate, Registration, Trace, separating_measurement};
pub use parameter::Parameter;

use crate::comparison::baseline::Baseline;
use crate::errors::DiagnoseError;

/// Every candidate effect, in the order the library lists them.
pub const REGISTRY: [Registration; 6] = [
    backlash::Backlash::REGISTRATION,
    gravity::Gravity::REGISTRATION,
    thermal::Thermal::REGISTRATION,
    length_bias::LengthBias::REGISTRATION,
    length_sigma::LengthSigma::REGISTRATION,
    pretension::DiagonalPretension::REGISTRATION,
];

/// The registered names, comma separated (`backlash, gravity, …`).
pub fn names() -> String {
    REGISTRY
        .iter()
        .map(|r| r.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The applicable candidates, and the (name, reason) of those that are not.
pub type Library = (Vec<Box<dyn Candidate>>, Vec<(String, String)>);

/// The candidates that apply to the baseline case, and the names of those that do not,
/// with why.
pub fn library(baseline: &Baseline) -> Library {
    library_for(baseline, true)
}

/// [`library`], `with_members` saying whether member lengths were measured one by one
/// (`backlash` fits its spread only then, [`backlash::Backlash`]).
pub fn library_for(baseline: &Baseline, with_members: bool) -> Library {
    let mut out: Vec<Box<dyn Candidate>> = Vec::new();
    let mut skipped = Vec::new();
    for r in &REGISTRY {
        match (r.make)(baseline, with_members) {
            Ok(c) => out.push(c),
            Err(why) => skipped.push((r.name.to_string(), why)),
        }
    }
    (out, skipped)
}

/// Parses `NAME:P=V,P=V` or `NAME:V,V,…` (positional) into the candidate's index in
/// `candidates` and a full parameter vector (unnamed parameters take their null values);
/// `none` gives `None`.
pub fn parse_effect(
    text: &str,
    candidates: &[Box<dyn Candidate>],
) -> Result<Option<(usize, Vec<f64>)>, DiagnoseError> {
    let text = text.trim();
    if text == "none" {
        return Ok(None);
    }
    let (name, rest) = text.split_once(':').unwrap_or((text, ""));
    let names = || {
        candidates
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let i = candidates
        .iter()
        .position(|c| c.name() == name)
        .ok_or_else(|| {
            DiagnoseError::Usage(format!(
                "--effect: no candidate effect {name:?} for this case (available: none, {})",
                names()
            ))
        })?;
    let params = candidates[i].parameters();
    let mut values: Vec<f64> = params.iter().map(|p| p.null).collect();
    for (k, item) in rest.split(',').filter(|s| !s.trim().is_empty()).enumerate() {
        let (key, value) = match item.split_once('=') {
            Some((k, v)) => (Some(k.trim()), v.trim()),
            None => (None, item.trim()),
        };
        let j = match key {
            Some(key) => params.iter().position(|p| p.name == key).ok_or_else(|| {
                DiagnoseError::Usage(format!(
                    "--effect {name}: no parameter {key:?} (its parameters: {})",
                    params
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?,
            None if k < params.len() => k,
            None => {
                return Err(DiagnoseError::Usage(format!(
                    "--effect {name}: more values than its {} parameters",
                    params.len()
                )));
            }
        };
        let v: f64 = value.parse().map_err(|_| {
            DiagnoseError::Usage(format!("--effect {name}: {value:?} is not a number"))
        })?;
        let p = &params[j];
        if !(v.is_finite() && p.low <= v && v <= p.high) {
            return Err(DiagnoseError::Usage(format!(
                "--effect {name}: {} = {value} is outside its plausible range [{}, {}] {}",
                p.name, p.low, p.high, p.unit
            )));
        }
        values[j] = v;
    }
    Ok(Some((i, values)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use truss_job::distribution::{Constant, DistributionSpec, Uniform};

    /// Every registration makes the candidate of its own name, once.
    #[test]
    fn each_registration_makes_its_own_candidate() {
        let baseline = Baseline::of_test();
        let (candidates, skipped) = library(&baseline);
        let listed: Vec<&str> = candidates.iter().map(|c| c.name()).collect();
        assert_eq!(listed.len() + skipped.len(), REGISTRY.len());
        for (r, c) in REGISTRY.iter().zip(&candidates) {
            assert_eq!(r.name, c.name());
        }
        assert_eq!(
            names(),
            "backlash, gravity, thermal_gradient, length_bias, length_sigma, diagonal_pretension"
        );
    }

    /// The pairs the crate doc names get their own measurement, either way round.
    #[test]
    fn each_confusable_pair_names_its_measurement() {
        let baseline = Baseline::of_test();
        let (candidates, _) = library(&baseline);
        let pick = |n: &str| {
            candidates
                .iter()
                .find(|c| c.name() == n)
                .map(|c| c.as_ref())
                .unwrap()
        };
        let between = |a: &str, b: &str| separating_measurement(pick(a), pick(b));
        let m = between("thermal_gradient", "length_bias");
        assert!(m.contains("temperature"), "{m}");
        assert_eq!(m, between("length_bias", "thermal_gradient"));
        assert!(between("diagonal_pretension", "length_bias").contains("--measured-members"));
        assert!(between("backlash", "length_bias").contains("--measured-members"));
        assert!(between("length_sigma", "gravity").contains("another orientation"));
        assert!(between("length_bias", "length_sigma").contains("scatter is measured"));
        assert!(between("backlash", "thermal_gradient").starts_with("a measurement that only"));
    }

    /// The interactions the candidates declare: each names a registered candidate other
    /// than itself, and [`candidate::interact`] finds it from either side; the one pair is
    /// backlash with the diagonal pretension (the pretension pulls the joints into
    /// contact), and no other two interact.
    #[test]
    fn interactions_name_registered_candidates_and_read_from_either_side() {
        let baseline = Baseline::of_test();
        let (candidates, _) = library(&baseline);
        let mut pairs = Vec::new();
        for a in &candidates {
            for &b in a.interacts_with() {
                assert!(
                    REGISTRY.iter().any(|r| r.name == b),
                    "{b} is not registered"
                );
                assert_ne!(a.name(), b, "declares itself");
                let other = candidates.iter().find(|c| c.name() == b).unwrap();
                assert!(candidate::interact(a.as_ref(), other.as_ref()));
                assert!(candidate::interact(other.as_ref(), a.as_ref()));
            }
            for b in &candidates {
                if a.name() < b.name() && candidate::interact(a.as_ref(), b.as_ref()) {
                    pairs.push((a.name(), b.name()));
                }
            }
            assert!(!candidate::interact(a.as_ref(), a.as_ref()));
        }
        assert_eq!(pairs, [("backlash", "diagonal_pretension")]);
    }

    fn paper_job(case: &str) -> Baseline {
        let job =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs/paper-4.2.3.json");
        Baseline::read(&job, case).unwrap()
    }

    /// `length_sigma` scales any distribution through its own method: a truncated normal's
    /// σ and limit together, so the group's standard deviation becomes the parameter.
    #[test]
    fn length_sigma_scales_a_truncated_normal() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("job.json");
        let text = r#"{"model": {"prism": {"stages": 1}}, "seed": 1, "cases": [{"name": "c",
            "samples": 10, "length_errors": {"longeron":
            {"truncated_normal": {"mean": 0.001, "sigma": 0.01, "limit": 0.02}}}}]}"#;
        std::fs::write(&path, text).unwrap();
        let baseline = Baseline::read(&path, "c").unwrap();
        let (candidates, _) = library(&baseline);
        let c = candidates
            .iter()
            .find(|c| c.name() == "length_sigma")
            .unwrap();
        let s0 = baseline.case().length_errors["longeron"].std_dev();
        assert_eq!(c.parameters()[0].null, s0);
        let mut edit = baseline.derived_case();
        c.apply(&[2.0 * s0], &mut edit).unwrap();
        let job = baseline.job_of(&edit, 10, None).unwrap();
        let d = job.cases[0].length_errors["longeron"];
        assert!((d.std_dev() / (2.0 * s0) - 1.0).abs() < 1e-12);
        assert_eq!((d.mean(), d.highest()), (0.001, 0.001 + 0.04));
    }

    /// On the rigid prism of section 4.2.3, `backlash` makes every node a pin joint with the
    /// fitted clearance, validated by the job crate, keeping the baseline's node and member ids
    /// where they were (measured coordinates and members are found by id either way) and the
    /// baseline's member distributions; at its null it leaves the case as it is.
    #[test]
    fn backlash_makes_the_prism_pin_jointed_with_the_clearance() {
        let baseline = paper_job("rigid-sigma-0.033");
        let (candidates, skipped) = library(&baseline);
        assert!(skipped.iter().all(|(n, _)| n != "backlash"), "{skipped:?}");
        let c = candidates.iter().find(|c| c.name() == "backlash").unwrap();
        let mut null = baseline.derived_case();
        c.apply(&[0.0, 0.0], &mut null).unwrap();
        assert!(!null.model_edited);
        assert_eq!(null.case, baseline.derived_case().case);
        let mut edit = baseline.derived_case();
        c.apply(&[0.012, 0.0], &mut edit).unwrap();
        let job = baseline.job_of(&edit, 10, None).unwrap();
        let case = &job.cases[0];
        let (rigid, pinned) = (baseline.model(), &case.model);
        // One joint per longeron end: two at every node but those of the end levels.
        assert_eq!(pinned.joints().len(), 2 * rigid.nodes().len() - 6);
        assert_eq!(
            case.backlash.unwrap().clearance,
            DistributionSpec::from(Constant { value: 0.012 })
        );
        for (i, n) in rigid.nodes().iter().enumerate() {
            assert_eq!(pinned.nodes()[i].id, n.id);
        }
        for (i, m) in rigid.members().iter().enumerate() {
            assert_eq!(pinned.members()[i].id, m.id);
            assert_eq!(case.member_errors[i], baseline.case().member_errors[i]);
        }
        assert_eq!(job.seed, baseline.seed);
    }

    /// The spread h maps the joints' clearances to U\[mean − h, mean + h\] through the job's
    /// own sampler: over 200 samples of the 5-stage prism's 30 joints (6000 draws) at mean
    /// 0.0105 and h 0.0065 (the paper's U\[0.004, 0.017\]), every clearance lies in the
    /// interval, their mean is 0.0105 within 4 standard errors (h/√3/√6000 = 4.8e-5 mm) and
    /// their SD h/√3 within 5 %; each clearance is mean + h·(2u − 1) with the u the same at
    /// every (mean, h) (common random numbers: the draws at h and at 1.5h differ from the mean
    /// by exactly a factor 1.5); and at h = 0 the case is exactly the one-parameter candidate's.
    #[test]
    fn backlash_spread_draws_the_papers_uniform_clearances_with_common_random_numbers() {
        let baseline = paper_job("rigid-sigma-0.033");
        let (candidates, _) = library(&baseline);
        let c = candidates.iter().find(|c| c.name() == "backlash").unwrap();
        let draws = |mean: f64, h: f64| {
            let mut edit = baseline.derived_case();
            c.apply(&[mean, h], &mut edit).unwrap();
            let job = baseline.job_of(&edit, 200, None).unwrap();
            let case = &job.cases[0];
            let key = truss_job::sampler::stream_key(job.seed, &case.name);
            let (mut errors, mut clearances, mut all) = (Vec::new(), Vec::new(), Vec::new());
            for k in 0..200 {
                truss_job::sampler::draw_sample(&key, case, k, &mut errors, &mut clearances);
                all.extend_from_slice(&clearances);
            }
            (case.backlash.unwrap().clearance, all)
        };
        let (mean, h) = (0.0105, 0.0065);
        let (d, x) = draws(mean, h);
        assert_eq!(
            d,
            DistributionSpec::from(Uniform {
                low: mean - h,
                high: mean + h
            })
        );
        assert_eq!(x.len(), 200 * 30);
        assert!(x.iter().all(|&c| mean - h <= c && c <= mean + h));
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        let sd = (x.iter().map(|c| (c - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let se = h / 3f64.sqrt() / n.sqrt();
        assert!((m - mean).abs() < 4.0 * se, "mean {m}");
        assert!((sd / (h / 3f64.sqrt()) - 1.0).abs() < 0.05, "sd {sd}");
        let (_, x2) = draws(mean, 1.5 * h);
        for (a, b) in x.iter().zip(&x2) {
            assert!(((b - mean) - 1.5 * (a - mean)).abs() < 1e-15, "{a} {b}");
        }
        let (d0, x0) = draws(mean, 0.0);
        assert_eq!(d0, DistributionSpec::from(Constant { value: mean }));
        assert!(x0.iter().all(|&c| c == mean));
        let (mut one, mut two) = (baseline.derived_case(), baseline.derived_case());
        c.apply(&[mean], &mut one).unwrap();
        c.apply(&[mean, 0.0], &mut two).unwrap();
        assert_eq!(one.case, two.case);
        // A spread beyond the mean would make clearances negative: held to the mean.
        let mut v = [0.004, 0.006];
        c.project(&mut v, None);
        assert_eq!(v, [0.004, 0.004]);
        let mut v = [0.004, 0.006];
        c.project(&mut v, Some(1));
        assert_eq!(v, [0.006, 0.006]);
    }

    /// A baseline whose model already has joints does not get the candidate, and says why.
    #[test]
    fn backlash_is_skipped_where_the_baseline_has_joints() {
        let (candidates, skipped) = library(&paper_job("backlash-sigma-0.033"));
        assert!(candidates.iter().all(|c| c.name() != "backlash"));
        let (_, why) = skipped.iter().find(|(n, _)| n == "backlash").unwrap();
        assert!(why.contains("already has pin joints"), "{why}");
    }
}
