//! Job validation (errors name the JSON path of the fault) and the job id (a canonical form).

use crate::common::*;
use mc_shard::Job;
use std::path::Path;

fn error(text: &str) -> String {
    Job::from_json(text, Path::new("."))
        .unwrap_err()
        .to_string()
}

fn with_case(case: &str) -> String {
    format!(r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 1, "cases": [{case}]}}"#)
}

#[test]
fn faults_are_named_by_their_json_path() {
    let m = error(&with_case(
        r#"{"name": "a", "samples": 5, "length_errors": {"longron": {"normal": {"sigma": 0.1}}}}"#,
    ));
    assert!(
        m.starts_with("cases[0].length_errors.longron: the model has no group \"longron\""),
        "{m}"
    );
    let m = error(&with_case(
        r#"{"name": "a", "samples": 5, "length_errors": {"longeron": {"normal": {"sigma": -0.1}}}}"#,
    ));
    assert_eq!(
        m,
        "cases[0].length_errors.longeron: sigma must not be negative, got -0.1"
    );
    let m = error(&with_case(r#"{"name": "a", "samples": 0}"#));
    assert_eq!(m, "cases[0].samples: must be at least 1");
    let m = error(&with_case(
        r#"{"name": "a", "samples": 1}, {"name": "a", "samples": 2}"#,
    ));
    assert_eq!(m, "cases[1].name: \"a\" is also the name of cases[0]");
    let m = error(&with_case(r#"{"name": "a", "samples": "many"}"#));
    assert!(m.starts_with("cases[0].samples: invalid type"), "{m}");
    let m = error(&with_case(
        r#"{"name": "a", "samples": 3, "lenght_errors": {}}"#,
    ));
    assert!(
        m.starts_with("cases[0]: unknown field `lenght_errors`") || m.contains("lenght_errors"),
        "{m}"
    );
    let m = error(&with_case(
        r#"{"name": "a", "samples": 3, "length_errors": {"batten": {"uniform": {"low": 1, "high": 0}}}}"#,
    ));
    assert!(m.contains("low (1) must not exceed high (0)"), "{m}");
    let m =
        error(r#"{"model": "nowhere.json", "seed": 1, "cases": [{"name": "a", "samples": 1}]}"#);
    assert!(
        m.starts_with("model: cannot read model file") && m.contains("nowhere.json"),
        "{m}"
    );
    let m = error(
        r#"{"model": {"prism": {"stages": 2, "sides": 3}}, "seed": 1, "cases": [{"name": "a", "samples": 1}]}"#,
    );
    assert!(
        m.starts_with("model.prism.sides: unknown field `sides`"),
        "{m}"
    );
    let m = error(
        r#"{"model": {"prism": {"stages": 2}}, "seed": -1, "cases": [{"name": "a", "samples": 1}]}"#,
    );
    assert!(m.starts_with("seed:"), "{m}");
    let m = error(r#"{"model": {"prism": {"stages": 2}}, "seed": 1, "cases": []}"#);
    assert_eq!(m, "cases: a job needs at least one case");
}

#[test]
fn job_file_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "j.json",
        &with_case(r#"{"name": "a", "samples": 0}"#),
    );
    let m = Job::read(&p).unwrap_err().to_string();
    assert!(
        m.starts_with(&format!("{}: cases[0].samples", p.display())),
        "{m}"
    );
}

/// The id does not depend on key order, number spelling, whitespace or how the model is
/// given (generator or a file with the same content, wherever it is); it changes with any
/// number that matters.
#[test]
fn the_job_id_is_of_the_canonical_form() {
    let dir = tempfile::tempdir().unwrap();
    let a = Job::from_json(&small_job(10), dir.path()).unwrap();
    let respelled = small_job(10)
        .replace("0.0063", "6.3e-3")
        .replace("\"seed\": 7", "\"seed\":7")
        .replace("\n", " ");
    let b = Job::from_json(&respelled, dir.path()).unwrap();
    assert_eq!(a.id, b.id);
    let mut v: serde_json::Value = serde_json::from_str(&small_job(10)).unwrap();
    let model_file = truss_core::prism::PrismOptions::with_stages(2)
        .model()
        .unwrap()
        .to_file();
    std::fs::create_dir(dir.path().join("models")).unwrap();
    write(
        dir.path(),
        "models/p2.json",
        &serde_json::to_string(&model_file).unwrap(),
    );
    v["model"] = serde_json::json!("models/p2.json");
    let c = Job::from_json(&v.to_string(), dir.path()).unwrap();
    assert_eq!(a.id, c.id, "the same model given as a file");
    v["model"] = serde_json::json!({"file": "models/p2.json"});
    assert_eq!(Job::from_json(&v.to_string(), dir.path()).unwrap().id, a.id);
    for changed in [
        small_job(10).replace("\"seed\": 7", "\"seed\": 8"),
        small_job(11),
        small_job(10).replace("0.0063", "0.0064"),
        small_job(10).replace("\"normal\", \"samples\"", "\"normal2\", \"samples\""),
        small_job(10).replace(
            "\"stages\": 2",
            "\"stages\": 2, \"diagonal_length\": \"exact\"",
        ),
    ] {
        assert_ne!(
            Job::from_json(&changed, dir.path()).unwrap().id,
            a.id,
            "{changed}"
        );
    }
}

#[test]
fn case_parameters_describe_the_case_for_sweeps() {
    let job = Job::from_json(&small_job(3), Path::new(".")).unwrap();
    let p = &job.cases[0].parameters;
    assert_eq!(p["sigma"], 0.0063);
    assert_eq!(p["stages"], 2.0);
    assert!(!p.contains_key("uniform"));
    let p = &job.cases[1].parameters;
    assert!((p["sigma"] - 0.04 / 12f64.sqrt()).abs() < 1e-15);
    assert_eq!(p["uniform"], 1.0);
}

/// `plan` refuses before any work what the job reader refuses: a prism whose
/// `diagonal_length` would start the cables 25 % strained (3), a model file that is missing
/// (an I/O failure, 4, as the README's exit-code table says), and a case name holding an
/// escape sequence (3), whose refusal shows it escaped: no raw control character reaches
/// the terminal.
#[test]
fn plan_refuses_before_any_work() {
    use crate::binary::mc_shard;
    let dir = tempfile::tempdir().unwrap();
    let plan = |text: &str| {
        let job = write(dir.path(), "job.json", text);
        mc_shard(&["plan", "--job", job.to_str().unwrap()])
    };
    let o = plan(
        r#"{"model": {"prism": {"stages": 5, "diagonal_length": 400}}, "seed": 1,
           "cases": [{"name": "a", "samples": 10}]}"#,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("model.prism.diagonal_length: 400 mm is more than 1%"),
        "{stderr}"
    );
    let o = plan(r#"{"model": "absent.json", "seed": 1, "cases": [{"name": "a", "samples": 10}]}"#);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{stderr}");
    assert!(
        stderr.contains("cannot read model file") && stderr.contains("absent.json"),
        "{stderr}"
    );
    let o = plan(
        "{\"model\": {\"prism\": {\"stages\": 1}}, \"seed\": 1, \
         \"cases\": [{\"name\": \"\\u001b]0;owned\\u0007\\u001b[2J\", \"samples\": 10}]}",
    );
    assert_eq!(o.status.code(), Some(3));
    assert!(o.stdout.is_empty());
    assert!(
        !o.stderr.iter().any(|&b| b == 0x1b || b == 0x07),
        "raw escape in {:?}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("cases[0].name: \"\\u{1b}]0;owned"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
