//! `docs/report.schema.json`, the standalone JSON Schema of `report.json` for readers who do
//! not read Rust, checked against real reports: a complete job with σ and stages sweeps and a
//! budget, and a
//! partial one with failed samples excluded and degenerate cases (0, 1, 2 samples, all angles
//! zero), where figures are null with reasons. The check is `schema-check`'s (shared with
//! mc-shard's shard-record schema test), which refuses any keyword it does not check, so the
//! schema cannot say more than is checked.

use crate::common::{SynthCase, SynthJob};
use serde_json::Value;

const SCHEMA: &str = include_str!("../../../../docs/report.schema.json");

fn errors(report: &Value) -> Vec<String> {
    let schema: Value = serde_json::from_str(SCHEMA).unwrap();
    schema_check::errors(&schema, report)
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
    let mut sweeps = SynthJob::new(
        5,
        vec![
            SynthCase::rayleigh("s1", 300, 2e-5, &[("sigma", 0.0033), ("stages", 5.0)]),
            SynthCase::rayleigh("s2", 300, 4e-5, &[("sigma", 0.0066), ("stages", 5.0)]),
            SynthCase::rayleigh("s3", 300, 3e-5, &[("sigma", 0.0066), ("stages", 2.0)]),
        ],
    );
    sweeps.budget = Some(shard_record::Budget {
        percentile: 97.5,
        theta_p: Some(9.7e-5),
        decenter: Some(0.05),
        despace: Some(0.03),
    });
    let complete = report(&sweeps, None, false);
    assert_eq!(complete["budget"]["cases"].as_array().unwrap().len(), 3);
    assert!(complete["cases"][0]["decenter"]["law"]["sigma"].is_object());
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
