//! # schema-check: the project's JSON Schemas, checked against real output
//!
//! `docs/shard-record.schema.json` (the shard lines `mc-shard` writes) and
//! `docs/report.schema.json` (the merge's `report.json`) are for readers who do not read
//! Rust. The tests of `mc-shard` and `mc-merge` check real output against them with
//! [`errors`], a small structural validator of the JSON Schema (draft 2020-12) keywords the
//! schemas use, and nothing more:
//!
//! | keyword | checked |
//! |---|---|
//! | `type` | one name or a list: `object`, `array`, `string`, `number`, `integer`, `boolean`, `null` |
//! | `const`, `enum` | equality |
//! | `minimum`, `maximum` | numbers, inclusive |
//! | `exclusiveMinimum` | numbers, exclusive |
//! | `required`, `properties`, `additionalProperties` | objects (`additionalProperties` `false`, `true` or a schema) |
//! | `items`, `minItems`, `maxItems` | arrays |
//! | `$ref` | `#/$defs/NAME` only |
//! | `oneOf` | exactly one sub-schema matches |
//! | `pattern` | only `^[0-9a-f]{64}$` (a SHA-256 in lower-case hex) |
//!
//! `$schema`, `$id`, `title`, `description` and `$defs` are annotations. Any other keyword,
//! or another pattern, panics: a schema cannot say more than its test checks.
//!
//! ## Why not a validator crate
//!
//! A full validator (`jsonschema`) links, even without its default features (an HTTP client
//! and TLS for remote `$ref`s), two regex engines, a reference resolver, big-number
//! fractions and e-mail, IDN and UUID format checkers: some twenty crates in the default
//! test build, for a dozen keywords that fit in this file.

use serde_json::Value;

/// The keywords [`errors`] checks.
pub const KEYWORDS: [&str; 16] = [
    "type",
    "const",
    "enum",
    "minimum",
    "exclusiveMinimum",
    "maximum",
    "required",
    "properties",
    "additionalProperties",
    "items",
    "minItems",
    "maxItems",
    "$ref",
    "oneOf",
    "pattern",
    // Annotations and definitions, not checks.
    "$defs",
];

/// Keywords that only annotate.
pub const ANNOTATIONS: [&str; 4] = ["$schema", "$id", "title", "description"];

/// The one pattern the schemas use: a SHA-256 digest in lower-case hex.
pub const HEX_64: &str = "^[0-9a-f]{64}$";

/// What is wrong with `value` against the schema `root` (its root schema, whose `$defs`
/// `$ref`s name), one line each, starting with the JSON pointer of the value (`/cases/0/n`;
/// the empty pointer is the root); empty when it validates. Where a value is of the wrong
/// type, that is its one error.
pub fn errors(root: &Value, value: &Value) -> Vec<String> {
    let mut errors = Vec::new();
    check(root, root, value, "", &mut errors);
    errors
}

fn check(root: &Value, schema: &Value, value: &Value, at: &str, errors: &mut Vec<String>) {
    let s = schema
        .as_object()
        .unwrap_or_else(|| panic!("the schema at {at:?} is not an object"));
    for k in s.keys() {
        assert!(
            KEYWORDS.contains(&k.as_str()) || ANNOTATIONS.contains(&k.as_str()),
            "schema keyword {k} at {at:?} is not checked by this validator"
        );
    }
    if let Some(r) = s.get("$ref").and_then(Value::as_str) {
        let name = r.strip_prefix("#/$defs/").expect("a local $ref");
        let target = &root["$defs"][name];
        assert!(target.is_object(), "unresolved $ref {r}");
        check(root, target, value, at, errors);
    }
    if let Some(t) = s.get("type") {
        let types: Vec<&str> = match t {
            Value::String(one) => vec![one.as_str()],
            Value::Array(many) => many.iter().map(|v| v.as_str().unwrap()).collect(),
            _ => panic!("bad type at {at:?}"),
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
    if let Some(options) = s.get("oneOf") {
        let passing = options
            .as_array()
            .expect("oneOf is a list")
            .iter()
            .filter(|option| {
                let mut e = Vec::new();
                check(root, option, value, at, &mut e);
                e.is_empty()
            })
            .count();
        if passing != 1 {
            errors.push(format!("{at}: {passing} of oneOf match"));
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
    if let Some(v) = value.as_f64() {
        if let Some(min) = s.get("minimum").and_then(Value::as_f64)
            && v < min
        {
            errors.push(format!("{at}: {v} is below {min}"));
        }
        if let Some(min) = s.get("exclusiveMinimum").and_then(Value::as_f64)
            && v <= min
        {
            errors.push(format!("{at}: {v} is not above {min}"));
        }
        if let Some(max) = s.get("maximum").and_then(Value::as_f64)
            && v > max
        {
            errors.push(format!("{at}: {v} is above {max}"));
        }
    }
    if let Some(pattern) = s.get("pattern") {
        assert_eq!(pattern, HEX_64, "unsupported pattern at {at:?}");
        let hex = value.as_str().is_some_and(|h| {
            h.len() == 64
                && h.bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
        });
        if value.is_string() && !hex {
            errors.push(format!("{at}: {value} is not 64 lower-case hex digits"));
        }
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
                Some(sub) => check(root, sub, v, &path, errors),
                None => match s.get("additionalProperties") {
                    Some(Value::Bool(false)) => errors.push(format!("{path}: not in the schema")),
                    Some(sub @ Value::Object(_)) => check(root, sub, v, &path, errors),
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
                check(root, sub, v, &format!("{at}/{i}"), errors);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::errors;
    use serde_json::json;

    /// Each keyword finds what it should, and only that.
    #[test]
    fn each_keyword_finds_its_fault() {
        let schema = json!({
            "$defs": {"digest": {"type": "string", "pattern": "^[0-9a-f]{64}$"}},
            "type": "object",
            "required": ["n", "kind"],
            "additionalProperties": false,
            "properties": {
                "n": {"type": "integer", "minimum": 0, "maximum": 10},
                "kind": {"enum": ["a", "b"]},
                "v": {"const": 1},
                "x": {"type": ["number", "null"]},
                "r": {"type": "number", "exclusiveMinimum": 0},
                "list": {"type": "array", "minItems": 1, "maxItems": 2, "items": {"type": "string"}},
                "sha": {"$ref": "#/$defs/digest"},
                "either": {"oneOf": [{"type": "string"}, {"type": "integer"}]}
            }
        });
        let good = json!({"n": 3, "kind": "a", "v": 1, "x": null, "r": 1e-9, "list": ["s"],
                          "sha": "0".repeat(64), "either": 2});
        assert_eq!(errors(&schema, &good), Vec::<String>::new());
        for (bad, at) in [
            (json!({"kind": "a"}), ": missing \"n\""),
            (json!({"n": 11, "kind": "a"}), "/n: 11 is above 10"),
            (json!({"n": -1, "kind": "a"}), "/n: -1 is below 0"),
            (json!({"n": 1.5, "kind": "a"}), "/n: 1.5 is not of type"),
            (json!({"n": 1, "kind": "c"}), "/kind: \"c\" is not one of"),
            (json!({"n": 1, "kind": "a", "v": 2}), "/v: 2 is not 1"),
            (
                json!({"n": 1, "kind": "a", "r": 0.0}),
                "/r: 0 is not above 0",
            ),
            (
                json!({"n": 1, "kind": "a", "x": "s"}),
                "/x: \"s\" is not of type",
            ),
            (json!({"n": 1, "kind": "a", "list": []}), "/list: 0 items"),
            (
                json!({"n": 1, "kind": "a", "list": [1]}),
                "/list/0: 1 is not of type",
            ),
            (
                json!({"n": 1, "kind": "a", "sha": "A".repeat(64)}),
                "/sha: \"AAAA",
            ),
            (
                json!({"n": 1, "kind": "a", "either": true}),
                "/either: 0 of oneOf match",
            ),
            (
                json!({"n": 1, "kind": "a", "extra": 0}),
                "/extra: not in the schema",
            ),
        ] {
            let e = errors(&schema, &bad);
            assert!(e.len() == 1 && e[0].starts_with(at), "{bad}: {e:?}");
        }
    }

    /// A keyword the validator does not check is refused, not ignored.
    #[test]
    #[should_panic(expected = "not checked by this validator")]
    fn an_unknown_keyword_is_refused() {
        errors(&json!({"format": "email"}), &json!("x"));
    }
}
