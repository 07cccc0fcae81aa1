//! The `truss` binary, run as a user would: generated models, solve output, exit codes.

use crate::{json, truss};
use std::path::Path;

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
        Some(2)
    );
    assert_eq!(truss(&["frobnicate"]).status.code(), Some(2));
}

#[test]
fn a_failed_solve_prints_why_and_exits_7() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.json");
    // A load of 10⁹ N on a top node: far beyond what the members carry, no equilibrium
    // near the nominal shape (a length error that large is refused before solving).
    let mut model = json(&truss(&["model", "prism", "--stages", "1"]));
    model["loads"] = serde_json::json!([{"node": "n1.0", "force": [0.0, 0.0, -1e9]}]);
    std::fs::write(&path, model.to_string()).unwrap();
    let out = truss(&["solve", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(7), "failed samples (truss-exit)");
    let r = json(&out);
    assert_eq!(r["converged"], false);
    assert!(r["error"].as_str().unwrap().contains("did not converge"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("truss: error: the solve failed: Newton did not converge"),
        "{err}"
    );
}

fn job_path() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../jobs/diagnose-baseline.json"
    )
    .to_string()
}

/// `synth-measured` then `diagnose`, as a user runs them: a strong hidden pretension on 40
/// specimens, tried against the effects it is most easily confused with (`--candidates`), is
/// named, every output file is written, and the updated job is a valid job whose case
/// carries the fitted diagonal length error.
#[test]
fn synth_measured_then_diagnose_names_the_hidden_effect() {
    let dir = tempfile::tempdir().unwrap();
    let job = job_path();
    let out = truss(&[
        "synth-measured",
        "--job",
        &job,
        "--case",
        "as-built",
        "--specimens",
        "40",
        "--seed",
        "5",
        "--effect",
        "diagonal_pretension:length_error=-0.08",
        "--measurement-sigma",
        "0.001",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("specimen,node,x,y,z\n"));
    assert_eq!(text.lines().count(), 1 + 40 * 3);
    let measured = dir.path().join("m.csv");
    std::fs::write(&measured, text).unwrap();
    let report = dir.path().join("report");
    let out = truss(&[
        "diagnose",
        "--job",
        &job,
        "--case",
        "as-built",
        "--measured",
        measured.to_str().unwrap(),
        "--measurement-sigma",
        "0.001",
        "--samples",
        "600",
        // The pretension and the scatter it is most easily confused with; backlash, whose
        // every evaluation solves the pin-jointed truss, made this CLI check a 10 s one.
        "--candidates",
        "diagonal_pretension,length_sigma,length_bias",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with("named_effect: diagonal_pretension\n"),
        "{stdout}"
    );
    // Progress went to stderr.
    assert!(String::from_utf8_lossy(&out.stderr).contains("fitting length_sigma"));
    for f in [
        "diagnosis.json",
        "diagnosis.md",
        "updated-job.json",
        "theta_p-ecdf-before.svg",
        "theta_p-ecdf-after.svg",
        "top-scatter-before.svg",
        "top-scatter-after.svg",
    ] {
        assert!(report.join(f).is_file(), "{f} missing");
    }
    let d: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("diagnosis.json")).unwrap())
            .unwrap();
    assert_eq!(d["named_effect"], "diagonal_pretension");
    assert!(d["indistinguishable"].is_array());
    assert!(d["statistics"]["after"]["statistics"].is_array());
    assert!(d["discrepancy_after"].as_f64().unwrap() < d["discrepancy_before"].as_f64().unwrap());
    let updated = truss_diagnose::comparison::baseline::Baseline::read(
        &report.join("updated-job.json"),
        "as-built",
    )
    .unwrap();
    let fitted = d["parameters"][0]["value"].as_f64().unwrap();
    match updated.distributions().get("diagonal") {
        Some(mc_dist) => assert!((mc_dist.mean() - fitted).abs() < 1e-12),
        None => panic!("the updated case has no diagonal length error"),
    }
    assert_eq!(updated.case().samples, 4000);
    the_three_reports_give_one_answer(&d, &stdout, &report);
}

/// diagnosis.json's `answer`, the lines diagnosis.md opens with and the console summary
/// are one answer: the same lines (the console's without Markdown's `**` and backticks),
/// and the record they are written from agrees with the rest of diagnosis.json (the
/// verdict, the effects added, the final fit's values in µm).
fn the_three_reports_give_one_answer(d: &serde_json::Value, stdout: &str, report: &Path) {
    let answer = &d["answer"];
    let lines: Vec<&str> = answer["lines"]
        .as_array()
        .expect("answer.lines")
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert!(lines.len() >= 3, "{lines:?}");
    assert_eq!(answer["verdict"], d["verdict"]);
    assert_eq!(
        lines[0],
        format!(
            "**Verdict: {}.**",
            stdout
                .lines()
                .find_map(|l| l.strip_prefix("verdict: named ("))
                .and_then(|l| l.strip_suffix(')'))
                .expect("the verdict line")
        )
    );
    // diagnosis.md: the title, then the answer, before any reasoning.
    let md = std::fs::read_to_string(report.join("diagnosis.md")).unwrap();
    let mut expected = vec![lines[0], ""];
    expected.extend(&lines[1..]);
    let opening: Vec<&str> = md.lines().skip(2).take(expected.len()).collect();
    assert_eq!(opening, expected, "{md}");
    assert!(md.lines().nth(2 + expected.len()) == Some(""), "{md}");
    // The console: the same lines, plain.
    let plain: Vec<String> = lines
        .iter()
        .map(|l| l.replace("**", "").replace('`', ""))
        .collect();
    let printed: Vec<&str> = stdout
        .lines()
        .skip_while(|l| !l.starts_with("Verdict: "))
        .take_while(|l| !l.starts_with("wrote "))
        .collect();
    assert_eq!(printed, plain, "{stdout}");
    // The record: the effects added, each parameter as the final fit has it.
    let missing = answer["missing"].as_array().unwrap();
    let named: Vec<&serde_json::Value> = missing.iter().map(|m| &m["effect"]).collect();
    assert_eq!(
        named,
        d["named_effects"]
            .as_array()
            .unwrap()
            .iter()
            .collect::<Vec<_>>()
    );
    for (m, f) in missing.iter().zip(d["final_fit"].as_array().unwrap()) {
        for (a, p) in m["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .zip(f["parameters"].as_array().unwrap())
        {
            assert_eq!(a["name"], p["name"]);
            let scale = if p["unit"] == "mm" { 1e3 } else { 1.0 };
            assert_eq!(a["value"].as_f64(), p["value"].as_f64().map(|v| v * scale));
            let name = a["name"].as_str().unwrap();
            assert!(lines[1].contains(name), "{name} missing from {}", lines[1]);
        }
    }
    assert!(
        lines.iter().any(|l| l.starts_with("- **Next:** ")),
        "{lines:?}"
    );
}

/// A bad row is an invalid-data error (exit 3) naming the file and line.
#[test]
fn diagnose_reports_a_bad_row_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let measured = dir.path().join("m.csv");
    std::fs::write(
        &measured,
        "specimen,node,x,y,z\r\nA,n5.0,0,0,1900\r\nA,n5.1,380,zero,1900\r\n",
    )
    .unwrap();
    let out = truss(&[
        "diagnose",
        "--job",
        &job_path(),
        "--case",
        "as-built",
        "--measured",
        measured.to_str().unwrap(),
        "--out",
        dir.path().join("r").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("m.csv:3: y = \"zero\" is not a finite number"),
        "{err}"
    );
}

/// `truss tolerance` prints each group's variance share with its bootstrap interval, as
/// `tolerance.json` holds them (the console gave the share alone, 1.0019, where the
/// interval [0.970, 1.034] says it is 1 within its noise).
#[test]
fn tolerance_prints_each_share_with_its_interval() {
    let dir = tempfile::tempdir().unwrap();
    let job = crate::one_stage_job(dir.path());
    let out = dir.path().join("t");
    let o = crate::small_tolerance(&job, &out, &["--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tolerance.json")).unwrap())
            .unwrap();
    let groups = t["groups"].as_object().unwrap();
    assert!(!groups.is_empty());
    for (name, g) in groups {
        let f = |v: &serde_json::Value| v.as_f64().unwrap();
        let i = g["share_interval"].as_array().unwrap();
        let want = format!(
            "{name}: sigma {:.4e} mm (variance share {:.4} [{:.4}, {:.4}]",
            f(&g["sigma"]),
            f(&g["share"]),
            f(&i[0]),
            f(&i[1])
        );
        assert!(stdout.contains(&want), "{want:?} not in {stdout}");
    }
}
