//! `docs/report.schema.json`, the standalone JSON Schema of `report.json` for readers who do
//! not read Rust, checked against real reports: a complete job with σ and stages sweeps, and a
//! partial one with failed samples excluded and degenerate cases (0, 1, 2 samples, all angles
//! zero), where figures are null with reasons. A small validator of the keywords the schema
//! uses (draft 2020-12: type, properties, required, additionalProperties, items, minItems,
//! maxItems, minimum, const, enum, $ref) does the check and refuses any other keyword, so the
//! schema cannot say more than is checked. Without a `jsonschema` dependency: that crate would
//! add a regex engine, an HTTP client's worth of features and a minute to the test build.

use crate::common::{SynthCase, SynthJob};
use serde_json::Value;

const SCHEMA: &str = include_str!("../../../../docs/report.schema.json");

/// The keywords the validator understands; annotations are allowed and ignored.
const KEYWORDS: [&str; 11] = [
    "type",
    "properties",
    "required",
    "additionalProperties",
    "items",
    "minItems",
    "maxItems",
    "minimum",
    "const",
    "enum",
    "$ref",
];
const ANNOTATIONS: [&str; 5] = ["$schema", "$id", "title", "description", "$defs"];

/// Errors of `value` against `schema` (JSON pointers and what is wrong).
fn validate(root: &Value, schema: &Value, value: &Value, at: &str, errors: &mut Vec<String>) {
    let s = schema.as_object().expect("a schema is an object");
    for k in s.keys() {
        assert!(
            KEYWORDS.contains(&k.as_str()) || ANNOTATIONS.contains(&k.as_str()),
            "schema keyword {k} at {at} is not checked by this validator"
        );
    }
    if let Some(r) = s.get("$ref").and_then(Value::as_str) {
        let name = r.strip_prefix("#/$defs/").expect("local $ref");
        let target = &root["$defs"][name];
        assert!(target.is_object(), "unresolved $ref {r}");
        validate(root, target, value, at, errors);
    }
    if let Some(t) = s.get("type") {
        let types: Vec<&str> = match t {
            Value::String(one) => vec![one.as_str()],
            Value::Array(many) => many.iter().map(|v| v.as_str().unwrap()).collect(),
            _ => panic!("bad type at {at}"),
        };
        let is = |t: &str| match t {
            "object" => value.is_object(),
            "array" => value.is_array(),
            "string" => value.is_string(),
            "number" => value.is_number(),
            "integer" => value.is_u64() || value.is_i64(),
            "boolean" => value.is_boolean(),
            "null" => value.is_null(),
            other => panic!("unknown type {other}"),
        };
        if !types.iter().any(|t| is(t)) {
            errors.push(format!("{at}: {value} is not of type {types:?}"));
            return;
        }
    }
    if let Some(c) = s.get("const")
        && value != c
    {
        errors.push(format!("{at}: {value} is not {c}"));
    }
    if let Some(Value::Array(options)) = s.get("enum")
        && !options.contains(value)
    {
        errors.push(format!("{at}: {value} is not one of {options:?}"));
    }
    if let (Some(min), Some(v)) = (s.get("minimum").and_then(Value::as_f64), value.as_f64())
        && v < min
    {
        errors.push(format!("{at}: {v} is below {min}"));
    }
    if let Value::Object(map) = value {
        let props = s.get("properties").and_then(Value::as_object);
        if let Some(Value::Array(required)) = s.get("required") {
            for r in required {
                if !map.contains_key(r.as_str().unwrap()) {
                    errors.push(format!("{at}: missing {r}"));
                }
            }
        }
        for (k, v) in map {
            let path = format!("{at}/{k}");
            match props.and_then(|p| p.get(k)) {
                Some(sub) => validate(root, sub, v, &path, errors),
                None => match s.get("additionalProperties") {
                    Some(Value::Bool(false)) => errors.push(format!("{path}: not in the schema")),
                    Some(sub @ Value::Object(_)) => validate(root, sub, v, &path, errors),
                    _ => {}
                },
            }
        }
    }
    if let Value::Array(items) = value {
        let len = items.len() as u64;
        if s.get("minItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| len < m)
            || s.get("maxItems")
                .and_then(Value::as_u64)
                .is_some_and(|m| len > m)
        {
            errors.push(format!("{at}: {len} items"));
        }
        if let Some(sub) = s.get("items") {
            for (i, v) in items.iter().enumerate() {
                validate(root, sub, v, &format!("{at}/{i}"), errors);
            }
        }
    }
}

fn errors(report: &Value) -> Vec<String> {
    let schema: Value = serde_json::from_str(SCHEMA).unwrap();
    let mut errors = vec![];
    validate(&schema, &schema, report, "", &mut errors);
    errors
}

fn report(job: &SynthJob, drop_shard: Option<usize>, allow: bool) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let mut files = job.write_split(dir.path(), 3);
    if let Some(k) = drop_shard {
        std::fs::remove_file(files.remove(k)).unwrap();
    }
    let settings = mc_merge::Settings {
        replicates: 50,
        gof_replicates: 19,
        allow_failed: allow,
        allow_partial: allow,
        ..Default::default()
    };
    let merge = mc_merge::merge(&[dir.path().to_path_buf()], &settings).unwrap();
    serde_json::from_str(&mc_merge::report_json(&merge.report).unwrap()).unwrap()
}

#[test]
fn real_reports_match_the_schema() {
    let sweeps = SynthJob::new(
        5,
        vec![
            SynthCase::rayleigh("s1", 300, 2e-5, &[("sigma", 0.0033), ("stages", 5.0)]),
            SynthCase::rayleigh("s2", 300, 4e-5, &[("sigma", 0.0066), ("stages", 5.0)]),
            SynthCase::rayleigh("s3", 300, 3e-5, &[("sigma", 0.0066), ("stages", 2.0)]),
        ],
    );
    let complete = report(&sweeps, None, false);
    assert_eq!(
        complete["sweep"]["sigma_series"].as_array().unwrap().len(),
        1
    );
    assert_eq!(errors(&complete), Vec::<String>::new());

    let mut failing = SynthCase::rayleigh("failing", 300, 2e-5, &[("sigma", 0.01)]);
    failing.fail_every = Some(7);
    failing.loose = true;
    failing.floating_every = Some(10);
    let degenerate = SynthJob::new(
        6,
        vec![
            failing,
            SynthCase::rayleigh("one", 1, 1e-5, &[]),
            SynthCase::rayleigh("pair", 2, 1e-5, &[("sigma", 0.02)]),
            SynthCase::rayleigh("empty", 0, 1e-5, &[]),
            SynthCase::rayleigh("late", 300, 1e-5, &[]),
        ],
    );
    let partial = report(&degenerate, Some(2), true);
    assert_eq!(partial["coverage"]["complete"], false);
    assert!(partial["failed"]["total"].as_u64().unwrap() > 0);
    assert!(partial["cases"][1]["percentiles"][0]["bca"]["reason"].is_string());
    assert_eq!(errors(&partial), Vec::<String>::new());

    // The check can fail: a wrong type, a missing field, an unknown field, a wrong constant.
    let mut bad = complete.clone();
    bad["cases"][0]["n"] = Value::from(-1);
    bad["coverage"].as_object_mut().unwrap().remove("present");
    bad["sweep"]["extra"] = Value::from(1);
    bad["format_version"] = Value::from(2);
    bad["cases"][0]["gof"]["verdict"] = Value::from("Named");
    assert_eq!(errors(&bad).len(), 5, "{:?}", errors(&bad));
}
