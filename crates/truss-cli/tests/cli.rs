//! The `truss` binary, run as a user would: generated models, solve output, exit codes.

use std::process::Command;

fn truss(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_truss"))
        .args(args)
        .output()
        .unwrap()
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout)))
}

#[test]
fn prism_model_has_the_papers_counts_and_overrides_apply() {
    let out = truss(&["model", "prism", "--stages", "5"]);
    assert!(out.status.success());
    let m = json(&out);
    assert_eq!(m["nodes"].as_array().unwrap().len(), 18);
    assert_eq!(m["members"].as_array().unwrap().len(), 63);
    let out = truss(&[
        "model",
        "prism",
        "--stages",
        "2",
        "--exact-diagonals",
        "--diagonal-area",
        "4.5",
    ]);
    let m = json(&out);
    let d = m["members"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["group"] == "diagonal")
        .unwrap();
    assert_eq!(d["area"], 4.5);
    assert!((d["natural_length"].as_f64().unwrap() - 380.0 * 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn solve_prints_the_result_with_ids_and_units() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.json");
    std::fs::write(&path, truss(&["model", "prism", "--stages", "3"]).stdout).unwrap();
    let out = truss(&[
        "solve",
        path.to_str().unwrap(),
        "--length-error",
        "longeron.1.0=0.01",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = json(&out);
    assert_eq!(r["converged"], true);
    let theta = r["theta_p"].as_f64().unwrap();
    // The hand estimate of the one-longeron test, within 5 % below.
    let estimate = 0.01 / (3f64.sqrt() / 2.0 * 380.0);
    assert!(theta < estimate && theta > 0.95 * estimate, "{theta}");
    assert_eq!(r["units"]["length"], "mm");
    assert!(r["displacements"]["n3.0"][2].as_f64().unwrap() > 0.008);
    assert!(r["forces"]["longeron.1.0"].as_f64().unwrap() < 0.0);
    assert!(r["slack_cables"].is_array());
}

#[test]
fn exit_codes_distinguish_usage_model_and_io_errors() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope.json");
    let out = truss(&["solve", missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(4));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope.json"));

    let bad = dir.path().join("bad.json");
    let text = String::from_utf8(truss(&["model", "prism", "--stages", "1"]).stdout)
        .unwrap()
        .replacen("\"n1.0\"", "\"n9.9\"", 1);
    std::fs::write(&bad, text).unwrap();
    let out = truss(&["solve", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown node") && err.contains("\"n1.0\""),
        "{err}"
    );

    let good = dir.path().join("good.json");
    std::fs::write(&good, truss(&["model", "prism", "--stages", "1"]).stdout).unwrap();
    let out = truss(&[
        "solve",
        good.to_str().unwrap(),
        "--length-error",
        "nosuch=1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no member \"nosuch\""));
    assert_eq!(
        truss(&["model", "prism", "--stages", "0"]).status.code(),
        Some(3)
    );
    assert_eq!(truss(&["frobnicate"]).status.code(), Some(2));
}

#[test]
fn a_failed_solve_prints_why_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.json");
    std::fs::write(&path, truss(&["model", "prism", "--stages", "1"]).stdout).unwrap();
    // A longeron shortened to nothing: its natural length would not be positive.
    let out = truss(&[
        "solve",
        path.to_str().unwrap(),
        "--length-error",
        "longeron.1.0=-400",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let r = json(&out);
    assert_eq!(r["converged"], false);
    assert!(r["error"].as_str().unwrap().contains("natural length"));
}
