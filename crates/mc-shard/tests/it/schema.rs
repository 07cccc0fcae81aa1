//! The standalone JSON Schema of shard records (`docs/shard-record.schema.json`) matches
//! what mc-shard writes: every line of real shards (converged samples with and without
//! backlash joints, a failed sample, checkpoints, a stop checkpoint, begin (with a budget)
//! and end lines)
//! validates, and lines that break the format do not.
//!
//! The check is `schema-check`'s, shared with mc-merge's report schema test.

use crate::common::*;
use serde_json::Value;
use std::process::Command;

fn schema() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/shard-record.schema.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn real_shard_lines_validate_against_the_schema() {
    let root = schema();
    let dir = tempfile::tempdir().unwrap();
    let text = small_job(120)
        .replace(
            r#"{"name": "uniform", "samples": 120,"#,
            r#"{"name": "uniform", "samples": 120, "model": {"prism": {"stages": 2, "backlash": true}},"#,
        )
        .replace(
            r#""seed": 7,"#,
            r#""seed": 7, "budget": {"theta_p": {"arcsec": 20}, "decenter": {"um": 50}, "despace": {"mm": 0.03}},"#,
        );
    assert_ne!(text, small_job(120));
    let job = write(dir.path(), "job.json", &text);
    let run = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "run",
            "--job",
            job.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ];
        args.extend_from_slice(extra);
        let o = Command::new(env!("CARGO_BIN_EXE_mc-shard"))
            .args(&args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let out = dir.path().join("s");
    run(&out, &[]);
    let path = only_shard(&out);
    // One failed sample, with fresh digests (the line mc-shard writes for a failed solve).
    forge_shard(&path, |s| {
        if s.index == 5 {
            s.status = shard_record::Status::Failed;
            (
                s.theta_p,
                s.tan_theta_x,
                s.tan_theta_y,
                s.residual,
                s.slack_cables,
            ) = (None, None, None, None, None);
            (s.decenter_x, s.decenter_y, s.decenter, s.despace) = (None, None, None, None);
            s.reason = Some("Newton did not converge in 60 iterations".into());
        }
        // A converged sample whose limit stands at a stage of the continuation.
        if s.index == 6 {
            s.limit_ratio = Some(2.0e-7);
        }
    });
    let mut lines: Vec<String> = std::fs::read_to_string(&path)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // A stop checkpoint, from an encoder stopped after 7 lines.
    let Ok(shard_record::Record::Begin(begin)) = shard_record::parse_record(lines[0].as_bytes())
    else {
        panic!()
    };
    let (mut encoder, mut bytes) = shard_record::ShardEncoder::new(&begin);
    for line in &lines[1..8] {
        encoder.push(format!("{line}\n").as_bytes(), false, &mut bytes);
    }
    lines.push(
        String::from_utf8(encoder.stop_checkpoint().unwrap())
            .unwrap()
            .trim_end()
            .to_string(),
    );
    let mut kinds = std::collections::BTreeSet::new();
    for (n, line) in lines.iter().enumerate() {
        let value: Value = serde_json::from_str(line).unwrap();
        let errors = schema_check::errors(&root, &value);
        assert!(errors.is_empty(), "line {}: {errors:?}\n{line}", n + 1);
        let kind = format!(
            "{}{}{}",
            value["record"],
            value["status"],
            value.get("loose_joints").is_some()
        );
        kinds.insert(kind);
    }
    // The begin line carries the budget in rad and mm; converged lines their placement.
    assert!(
        lines[0].contains(r#""budget":{"percentile":95.0,"theta_p":"#),
        "{}",
        lines[0]
    );
    assert!(
        lines[0].contains(r#""decenter":0.05,"despace":0.03}"#),
        "{}",
        lines[0]
    );
    assert!(lines[1].contains(r#""decenter_x":"#) && lines[1].contains(r#""despace":"#));
    // begin, end, checkpoint; converged with and without loose_joints; failed.
    assert_eq!(kinds.len(), 6, "{kinds:?}");
    // Lines of the backlash case say whether a stage floats.
    assert!(
        lines.iter().any(|l| l.contains("\"floating\":")),
        "no line says floating"
    );

    let staged = lines
        .iter()
        .find(|l| l.contains("\"limit_ratio\":2e-7"))
        .expect("no line with limit_ratio");

    // Lines that break the format are refused.
    let sample = lines.iter().find(|l| l.contains("\"converged\"")).unwrap();
    for bad in [
        sample.replace("\"converged\"", "\"ok\""),
        sample.replace("\"index\":", "\"indx\":"),
        sample.replace("\"theta_p\":", "\"reason\":\"x\",\"theta_p\":"),
        staged.replace("\"limit_ratio\":2e-7", "\"limit_ratio\":0.0"),
        lines[0].replace("\"format_version\":2", "\"format_version\":1"),
        lines
            .last()
            .unwrap()
            .replace("\"sha256\":\"", "\"sha256\":\"A"),
    ] {
        let value: Value = serde_json::from_str(&bad).unwrap();
        assert!(!schema_check::errors(&root, &value).is_empty(), "{bad}");
    }
}
