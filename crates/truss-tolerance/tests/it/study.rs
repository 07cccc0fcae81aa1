//! The whole study end to end: the files and fields the crate doc lists, the allocation meeting
//! the target at its upper bound after the homogeneity rescale, results independent of the
//! thread count; the paper's 5-stage case with 20,000 samples in the slow tier.

use crate::common::{both, job};
use truss_job::Job;
use truss_tolerance::study::MARGIN;
use truss_tolerance::{Options, TargetAngle, run};

fn small(path: std::path::PathBuf, out: std::path::PathBuf) -> Options {
    Options {
        sensitivity_samples: 1500,
        samples: 3000,
        ..Options::new(path, "c", TargetAngle::Arcsec(20.0), out)
    }
}

#[test]
fn the_study_writes_what_the_crate_doc_lists_and_verifies() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 2, &[("c", &both(0.0063)), ("other", &both(0.01))]);
    let out = dir.path().join("out");
    let t = run(&small(path.clone(), out.clone())).unwrap();
    assert!(t.verified);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tolerance.json")).unwrap())
            .unwrap();
    let target = doc["target_rad"].as_f64().unwrap();
    assert!((target * truss_units::ARCSEC_PER_RAD - 20.0).abs() < 1e-9);
    assert_eq!(doc["percentile"], 95.0);
    for g in ["batten", "longeron"] {
        let group = &doc["groups"][g];
        assert!(group["sigma"].as_f64().unwrap() > 0.0, "{group}");
        let share = group["share"].as_f64().unwrap();
        let interval = group["share_interval"].as_array().unwrap();
        assert!(interval[0].as_f64().unwrap() <= share && share <= interval[1].as_f64().unwrap());
        assert_eq!(group["fixed"], false);
    }
    assert_eq!(doc["groups"]["batten"]["members"], 9);
    assert_eq!(doc["groups"]["longeron"]["members"], 6);
    let v = &doc["verified"];
    let upper = v["interval"][1].as_f64().unwrap();
    let theta = v["theta_p"].as_f64().unwrap();
    assert_eq!(v["samples"], 3000);
    assert!(upper <= target && theta >= 0.9 * target, "{v}");
    // No group fixed: the rescale is homogeneity (approximate: the diagonals' fixed
    // pre-tension), so the upper end lands on θ*(1 − MARGIN) to well within the margin.
    assert!(
        (upper / (target * (1.0 - MARGIN)) - 1.0).abs() < 0.5 * MARGIN,
        "{upper} vs {target}"
    );
    // The allocation relaxes the insensitive battens and is cheaper than one common σ.
    let (sb, sl) = (t.groups[0].sigma, t.groups[1].sigma);
    assert!(sb > 3.0 * sl, "batten σ {sb}, longeron σ {sl}");
    // The free groups' ratio is the closed form's, (n_b S_l / (n_l S_b))^{1/3}, with the
    // sensitivities the study measured and reported.
    let s = |g: &str| doc["groups"][g]["sensitivity"].as_f64().unwrap();
    let closed = (9.0 * s("longeron") / (6.0 * s("batten"))).cbrt();
    assert!(
        (sb / sl / closed - 1.0).abs() < 1e-9,
        "{} vs {closed}",
        sb / sl
    );
    let ratio = doc["cost_ratio"].as_f64().unwrap();
    assert!(ratio > 0.0 && ratio < 1.0, "{ratio}");
    assert!(doc["uniform_sigma"].as_f64().unwrap() > sl);
    // The group derivatives obey Euler's relation for a degree-1 homogeneous θ_P95:
    // Σ σ_g ∂θ/∂σ_g = θ_P95 at the input σ (the calibrated model's finite differences).
    let euler: f64 = t.groups.iter().map(|g| g.input_sigma * g.derivative).sum();
    assert!(
        (euler / t.input.theta - 1.0).abs() < 1e-6,
        "{euler} vs {}",
        t.input.theta
    );
    // The allocated job: the input job with this case's σ replaced, runnable from anywhere.
    let allocated = Job::read(&out.join("allocated-job.json")).unwrap();
    assert_eq!(allocated.cases.len(), 2);
    let case = &allocated.cases[0];
    assert_eq!(case.length_errors["batten"].std_dev(), sb);
    assert_eq!(case.length_errors["longeron"].std_dev(), sl);
    assert_eq!(allocated.cases[1].length_errors["batten"].std_dev(), 0.01);
    for f in ["tolerance.md", "shares-groups.svg", "shares-members.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let md = std::fs::read_to_string(out.join("tolerance.md")).unwrap();
    assert!(md.contains("meets the target"), "{md}");
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 1, &[("c", &both(0.0063))]);
    let text = |threads: usize| {
        let out = dir.path().join(format!("out-{threads}"));
        let o = Options {
            threads: Some(threads),
            sensitivity_samples: 1000,
            samples: 1000,
            plots: false,
            fixes: vec!["batten=0.01".into()],
            ..Options::new(path.clone(), "c", TargetAngle::Arcsec(20.0), out.clone())
        };
        // A fixed group: verified or not, the files are written.
        let _ = run(&o);
        std::fs::read_to_string(out.join("tolerance.json")).unwrap()
    };
    assert_eq!(text(1), text(3));
}

/// Truncated normal length errors are scaled along their σ with the limit in proportion:
/// the allocated job keeps each group's shape limit/σ = 2 and gives it the allocated
/// standard deviation (the truncated one, which the study reports as the group's σ).
#[test]
fn truncated_normals_are_scaled_with_their_limit() {
    let dir = tempfile::tempdir().unwrap();
    let truncated = r#"{"truncated_normal": {"sigma": 0.0063, "limit": 0.0126}}"#;
    let errors = format!(r#"{{"batten": {truncated}, "longeron": {truncated}}}"#);
    let path = job(&dir, 1, &[("c", &errors)]);
    let out = dir.path().join("out");
    let o = Options {
        sensitivity_samples: 1000,
        samples: 1000,
        plots: false,
        ..Options::new(path, "c", TargetAngle::Arcsec(20.0), out.clone())
    };
    let t = match run(&o) {
        Ok(t) => t,
        Err(e) => panic!("{e}"),
    };
    let input = Job::read(&dir.path().join("job.json")).unwrap();
    let allocated = Job::read(&out.join("allocated-job.json")).unwrap();
    for g in &t.groups {
        assert_eq!(
            g.input_sigma,
            input.cases[0].length_errors[&g.name].std_dev()
        );
        let d = allocated.cases[0].length_errors[&g.name];
        let truss_job::distribution::DistributionSpec::TruncatedNormal(d) = d else {
            panic!("{}: {d:?}", g.name)
        };
        assert!((d.limit / d.sigma - 2.0).abs() < 1e-12, "{d:?}");
        let sd = allocated.cases[0].length_errors[&g.name].std_dev();
        assert!(
            (sd / g.sigma - 1.0).abs() < 1e-12,
            "{}: {sd} vs {}",
            g.name,
            g.sigma
        );
    }
}

/// The paper's 5-stage truss, σ = 0.0063 mm on battens and longerons, 20″ at the 95th
/// percentile, the default 20,000 verification samples: verifies, the battens' share is
/// small (the paper: battens alone give about 4 % of θ_P95, so about 0.2 % of the variance),
/// and the battens get the wider tolerance.
#[test]
#[ignore = "slow: 64,000 solves of the 5-stage truss (run optimised by scripts/test.sh)"]
fn the_paper_case_allocation_verifies() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tempfile::tempdir().unwrap();
    let o = Options::new(
        root.join("jobs/paper-3.1.json"),
        "sigma-0.0063",
        TargetAngle::Arcsec(20.0),
        dir.path().to_path_buf(),
    );
    let t = run(&o).unwrap();
    let (_, last, _) = t.verified_run();
    assert_eq!(last.samples, 20_000);
    assert!(last.interval.1 <= t.target_rad && last.theta >= 0.9 * t.target_rad);
    let batten = &t.groups[0];
    assert!(batten.share.1.1 < 0.01, "batten share {:?}", batten.share);
    assert!(batten.sigma > 5.0 * t.groups[1].sigma);
    assert!(t.cost_ratio() < 1.0);
    // The first (model) run was within 5 % of the target: the linear Gaussian model holds.
    let (_, first, model) = &t.runs[0];
    assert!((first.theta / model - 1.0).abs() < 0.05);
}

/// A job with an alignment budget: the allocation is held to every line on the last
/// verification run's samples (its θ_P line is that run's θ_Pq, to the bit), the common
/// factor starts at the least limit/percentile with its line named and is corrected by runs
/// until the binding line sits on its limit, and `tolerance.json` and `tolerance.md` say so; a job without one has
/// `"budget": null`.
#[test]
fn the_allocation_is_held_to_the_jobs_budget() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 2, &[("c", &both(0.0063))]);
    let plain_out = dir.path().join("plain");
    run(&small(path.clone(), plain_out.clone())).unwrap();
    let plain: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(plain_out.join("tolerance.json")).unwrap())
            .unwrap();
    assert!(plain["budget"].is_null());
    let text = std::fs::read_to_string(&path).unwrap().replace(
        r#""seed": 20210325,"#,
        r#""seed": 20210325, "budget": {"theta_p": {"arcsec": 20}, "decenter": {"um": 50}, "despace": {"mm": 0.03}, "percentile": 95},"#,
    );
    std::fs::write(&path, text).unwrap();
    let out = dir.path().join("out");
    let t = run(&small(path.clone(), out.clone())).unwrap();
    let b = t.budget.as_ref().expect("a budget check");
    let (sigmas, last, _) = t.verified_run();
    let names: Vec<&str> = b.lines.iter().map(|l| l.0).collect();
    assert_eq!(names, ["theta_p", "decenter", "despace"]);
    assert_eq!(b.lines[0].2.theta.to_bits(), last.theta.to_bits());
    let ratios: Vec<f64> = b.lines.iter().map(|l| l.1 / l.2.theta).collect();
    let least = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    assert_eq!(
        b.binding,
        names[ratios.iter().position(|r| *r == least).unwrap()]
    );
    for (s, c) in sigmas.iter().zip(&b.sigmas) {
        assert_eq!(*c, s * b.scale);
    }
    for (_, limit, p, passes) in &b.lines {
        assert_eq!(*passes, p.interval.1 <= *limit);
    }
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tolerance.json")).unwrap())
            .unwrap();
    assert_eq!(doc["budget"]["binding"], b.binding);
    assert_eq!(doc["budget"]["lines"].as_array().unwrap().len(), 3);
    let md = std::fs::read_to_string(out.join("tolerance.md")).unwrap();
    assert!(md.contains(&format!("binds: {}", b.binding)), "{md}");
    // At the θ_P allocation of this 2-stage prism decenter is near 83 µm: it binds, by far.
    assert_eq!(b.binding, "decenter");
    assert!(b.scale > 0.4 && b.scale < 0.8, "{}", b.scale);
    // The correction by runs: at c·σ the binding line sits at most 2 % below its limit, and
    // the rescale moved c from the homogeneity value (the pretension, the slack set).
    let at = b.scaled.iter().find(|l| l.0 == b.binding).unwrap();
    let r = at.1 / at.2.theta;
    assert!((1.0..=1.02).contains(&r), "{at:?}");
    assert!(b.scale > least, "{} vs {least}", b.scale);
    assert!(b.scaled.iter().all(|l| l.2.theta <= l.1), "{:?}", b.scaled);
    // Rebuilt from the job file through the public API (the same job at c·σ, its own
    // bootstrap seed): decenter's 95th percentile is within 2 % below its 50 µm limit.
    let study = truss_tolerance::setup::Study::read(&path, "c", &[], &[]).unwrap();
    let job = study.job_with(&b.sigmas, 3000).unwrap();
    let r = truss_tolerance::simulate::run_case(&job, &[], 2, "check").unwrap();
    let p = truss_tolerance::verify::percentile(&r.decenter, 0.95, 7, 2).unwrap();
    assert!(
        p.theta <= 0.05 && p.theta > 0.98 * 0.05,
        "decenter95 {} mm",
        p.theta
    );
}
