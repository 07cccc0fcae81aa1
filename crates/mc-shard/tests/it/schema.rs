//! The standalone JSON Schema of shard records (`docs/shard-record.schema.json`) matches
//! what mc-shard writes: every line of real shards (converged samples with and without
//! backlash joints, a failed sample, checkpoints, a stop checkpoint, begin and end lines)
//! validates, and lines that break the format do not.
//!
//! The validator is a small structural one for the keywords the schema uses (`$ref` into
//! `$defs`, `oneOf`, `type`, `const`, `required`, `properties`, `additionalProperties`,
//! `items`, `minimum`, `maximum`, and the one `pattern`, 64 lower-case hex digits); it
//! panics on any other keyword, so the schema cannot grow a rule the test ignores. A full
//! validator crate (`jsonschema`) would pull an HTTP client and a regex engine into the
//! default test build for these few rules.

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

/// The errors of `value` against `node` (empty when it validates).
fn validate(root: &Value, node: &Value, value: &Value, at: &str) -> Vec<String> {
    let mut errors = Vec::new();
    let Value::Object(rules) = node else {
        panic!("schema node at {at} is not an object")
    };
    for (key, rule) in rules {
        match key.as_str() {
            "description" | "title" | "$schema" | "$id" | "$defs" => {}
            "$ref" => {
                let name = rule.as_str().unwrap().strip_prefix("#/$defs/").unwrap();
                errors.extend(validate(root, &root["$defs"][name], value, at));
            }
            "oneOf" => {
                let passing = rule
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|r| validate(root, r, value, at).is_empty())
                    .count();
                if passing != 1 {
                    errors.push(format!("{at}: {passing} of oneOf match"));
                }
            }
            "type" => {
                let ok = match rule.as_str().unwrap() {
                    "object" => value.is_object(),
                    "array" => value.is_array(),
                    "string" => value.is_string(),
                    "number" => value.is_number(),
                    "integer" => value.is_u64() || value.is_i64(),
                    "boolean" => value.is_boolean(),
                    other => panic!("type {other}"),
                };
                if !ok {
                    errors.push(format!("{at}: not of type {rule}"));
                }
            }
            "const" => {
                if value != rule {
                    errors.push(format!("{at}: {value} is not {rule}"));
                }
            }
            "required" => {
                for name in rule.as_array().unwrap() {
                    if value.get(name.as_str().unwrap()).is_none() {
                        errors.push(format!("{at}: {name} missing"));
                    }
                }
            }
            "properties" => {
                if let Value::Object(fields) = value {
                    for (name, v) in fields {
                        if let Some(r) = rule.get(name) {
                            errors.extend(validate(root, r, v, &format!("{at}.{name}")));
                        }
                    }
                }
            }
            "additionalProperties" => {
                if let Value::Object(fields) = value {
                    let known = node.get("properties");
                    for (name, v) in fields {
                        if known.and_then(|k| k.get(name)).is_some() {
                            continue;
                        }
                        match rule {
                            Value::Bool(false) => {
                                errors.push(format!("{at}: unknown field {name}"))
                            }
                            Value::Bool(true) => {}
                            r => errors.extend(validate(root, r, v, &format!("{at}.{name}"))),
                        }
                    }
                }
            }
            "items" => {
                if let Value::Array(items) = value {
                    for (i, v) in items.iter().enumerate() {
                        errors.extend(validate(root, rule, v, &format!("{at}[{i}]")));
                    }
                }
            }
            "minimum" | "maximum" => {
                if let Some(x) = value.as_f64() {
                    let bound = rule.as_f64().unwrap();
                    if (key == "minimum" && x < bound) || (key == "maximum" && x > bound) {
                        errors.push(format!("{at}: {x} beyond {key} {bound}"));
                    }
                }
            }
            "pattern" => {
                assert_eq!(rule, "^[0-9a-f]{64}$", "unsupported pattern");
                let s = value.as_str().unwrap_or("");
                if s.len() != 64
                    || !s
                        .bytes()
                        .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
                {
                    errors.push(format!("{at}: {value} is not 64 lower-case hex digits"));
                }
            }
            other => panic!("the schema uses {other:?}, which this validator does not check"),
        }
    }
    errors
}

#[test]
fn real_shard_lines_validate_against_the_schema() {
    let root = schema();
    let dir = tempfile::tempdir().unwrap();
    let text = small_job(120).replace(
        r#"{"name": "uniform", "samples": 120,"#,
        r#"{"name": "uniform", "samples": 120, "model": {"prism": {"stages": 2, "backlash": true}},"#,
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
            s.reason = Some("Newton did not converge in 60 iterations".into());
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
        let errors = validate(&root, &root, &value, "$");
        assert!(errors.is_empty(), "line {}: {errors:?}\n{line}", n + 1);
        let kind = format!(
            "{}{}{}",
            value["record"],
            value["status"],
            value.get("loose_joints").is_some()
        );
        kinds.insert(kind);
    }
    // begin, end, checkpoint; converged with and without loose_joints; failed.
    assert_eq!(kinds.len(), 6, "{kinds:?}");
    // Lines of the backlash case say whether a stage floats.
    assert!(
        lines.iter().any(|l| l.contains("\"floating\":")),
        "no line says floating"
    );

    // Lines that break the format are refused.
    let sample = lines.iter().find(|l| l.contains("\"converged\"")).unwrap();
    for bad in [
        sample.replace("\"converged\"", "\"ok\""),
        sample.replace("\"index\":", "\"indx\":"),
        sample.replace("\"theta_p\":", "\"reason\":\"x\",\"theta_p\":"),
        lines[0].replace("\"format_version\":2", "\"format_version\":1"),
        lines
            .last()
            .unwrap()
            .replace("\"sha256\":\"", "\"sha256\":\"A"),
    ] {
        let value: Value = serde_json::from_str(&bad).unwrap();
        assert!(!validate(&root, &root, &value, "$").is_empty(), "{bad}");
    }
}
