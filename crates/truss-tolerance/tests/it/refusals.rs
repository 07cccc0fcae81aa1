//! What the study refuses, each with a clear error naming the cause.

use crate::common::{both, job};
use truss_tolerance::{Options, TargetAngle, ToleranceError, run};

fn options(path: std::path::PathBuf, case: &str, dir: &tempfile::TempDir) -> Options {
    Options {
        sensitivity_samples: 1000,
        samples: 1000,
        plots: false,
        ..Options::new(
            path,
            case,
            TargetAngle::Arcsec(20.0),
            dir.path().join("out"),
        )
    }
}

fn error(o: &Options) -> ToleranceError {
    match run(o) {
        Ok(_) => panic!("expected a refusal"),
        Err(e) => e,
    }
}

#[test]
fn a_case_without_length_errors_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 1, &[("none", "{}")]);
    let e = error(&options(path, "none", &dir));
    assert!(matches!(e, ToleranceError::NoLengthErrors { .. }), "{e}");
    assert!(
        e.to_string().contains("no member group a length error"),
        "{e}"
    );
}

#[test]
fn groups_that_cannot_be_scaled_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "zero",
            r#"{"batten": {"normal": {"sigma": 0}}, "longeron": {"normal": {"sigma": 0.01}}}"#,
        ),
        (
            "biased",
            r#"{"longeron": {"normal": {"mean": 0.01, "sigma": 0.01}}}"#,
        ),
        ("constant", r#"{"longeron": {"constant": {"value": 0.01}}}"#),
        (
            "skew",
            r#"{"longeron": {"uniform": {"low": 0, "high": 0.01}}}"#,
        ),
        (
            "biased-truncated",
            r#"{"longeron": {"truncated_normal": {"mean": 0.01, "sigma": 0.01, "limit": 0.02}}}"#,
        ),
        (
            "constant-lot",
            r#"{"longeron": {"normal": {"sigma": 0.01}, "lot": {"by": "level", "constant": {"value": 0.005}}}}"#,
        ),
    ];
    let path = job(&dir, 1, &cases);
    for (case, _) in cases {
        let e = error(&options(path.clone(), case, &dir));
        assert!(
            matches!(e, ToleranceError::NotScalable { .. }),
            "{case}: {e}"
        );
        assert!(!e.is_usage());
        if case == "constant-lot" {
            // A lot part is a group of the study; its distribution must scale as a group's.
            let text = e.to_string();
            assert!(
                text.contains("longeron.lot") && text.contains("production lot's shared part"),
                "{e}"
            );
        }
    }
}

#[test]
fn an_unreachable_target_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 1, &[("c", &both(0.0063))]);
    let mut o = options(path, "c", &dir);
    o.fixes = vec!["longeron=0.1".into()];
    let e = error(&o);
    assert!(matches!(e, ToleranceError::Unreachable { .. }), "{e}");
    assert!(e.to_string().contains("longeron"), "{e}");
    // Every group fixed: nothing to allocate.
    o.fixes = vec!["longeron=0.001".into(), "batten=0.001".into()];
    assert!(matches!(error(&o), ToleranceError::BadValue { .. }));
}

#[test]
fn unknown_groups_and_bad_numbers_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = job(&dir, 1, &[("c", &both(0.0063))]);
    let base = options(path, "c", &dir);
    let with = |costs: &[&str], fixes: &[&str]| Options {
        costs: costs.iter().map(|s| s.to_string()).collect(),
        fixes: fixes.iter().map(|s| s.to_string()).collect(),
        ..base.clone()
    };
    for (costs, fixes, word) in [
        (&["diagonal=2"][..], &[][..], "diagonal"),
        (&["battens=2"], &[], "battens"),
        (&[], &["longron=0.01"], "longron"),
    ] {
        let e = error(&with(costs, fixes));
        assert!(matches!(e, ToleranceError::UnknownGroup { .. }), "{e}");
        assert!(e.is_usage() && e.to_string().contains(word), "{e}");
    }
    for (costs, fixes) in [
        (&["batten=abc"][..], &[][..]),
        (&["batten"], &[]),
        (&["batten=0"], &[]),
        (&["batten=-1"], &[]),
        (&["batten=inf"], &[]),
        (&[], &["batten=-0.01"]),
        (&[], &["batten=NaN"]),
    ] {
        let e = error(&with(costs, fixes));
        assert!(
            matches!(e, ToleranceError::BadValue { .. }),
            "{costs:?} {fixes:?}: {e}"
        );
    }
    for (target, pct) in [
        (0.0, 95.0),
        (-1.0, 95.0),
        (f64::NAN, 95.0),
        (20.0, 100.0),
        (20.0, 0.0),
    ] {
        let o = Options {
            target: TargetAngle::Arcsec(target),
            percentile: pct,
            ..base.clone()
        };
        assert!(error(&o).is_usage(), "target {target}, percentile {pct}");
    }
    let e = error(&Options {
        case: "nope".into(),
        ..base.clone()
    });
    assert!(matches!(e, ToleranceError::NoCase { .. }), "{e}");
}

#[test]
fn cases_with_effects_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"{"model": {"prism": {"stages": 1}}, "seed": 1, "cases": [
        {"name": "g", "samples": 10, "effects": {"gravity": {"direction": [0, 0, -1]}},
         "length_errors": {"longeron": {"normal": {"sigma": 0.01}}}}]}"#;
    let path = dir.path().join("job.json");
    std::fs::write(&path, text).unwrap();
    let e = error(&options(path, "g", &dir));
    assert!(matches!(e, ToleranceError::Unsupported { .. }), "{e}");
}

/// Finite but extreme inputs (σ = 1e-300 mm, `--cost batten=1e300`) make the study's own σ
/// overflow: refused naming the group, not as the job's "sigma is not a finite number".
#[test]
fn extreme_sigmas_and_costs_are_refused_naming_the_group() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "tiny",
            r#"{"batten": {"normal": {"sigma": 1e-300}}, "longeron": {"normal": {"sigma": 0.01}}}"#,
        ),
        (
            "plain",
            r#"{"batten": {"normal": {"sigma": 0.01}}, "longeron": {"normal": {"sigma": 0.01}}}"#,
        ),
    ];
    let path = job(&dir, 1, &cases);
    let mut costly = options(path.clone(), "plain", &dir);
    costly.costs = vec!["batten=1e300".into()];
    for o in [options(path, "tiny", &dir), costly] {
        let e = error(&o);
        assert!(matches!(e, ToleranceError::NotScalable { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains("group \"batten\"") && text.contains("not a number"),
            "{text}"
        );
    }
}
