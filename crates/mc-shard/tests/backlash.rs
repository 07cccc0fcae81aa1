//! Backlash in jobs: the model option, the per-case clearance distribution, its faults, and
//! its draws joining each sample's deterministic stream.

mod common;
use common::*;
use mc_shard::{Job, RunOptions, run_shard};
use shard_record::ShardRange;
use std::path::Path;

const CLEARANCE: &str = r#""backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}}"#;

fn backlash_job(n: u64, compression_ratio: f64) -> String {
    format!(
        r#"{{
  "model": {{"prism": {{"stages": 2, "backlash": {{"compression_ratio": {compression_ratio}}}}}}},
  "seed": 11,
  "cases": [
    {{"name": "paper", "samples": {n}, {CLEARANCE},
      "length_errors": {{"batten": {{"normal": {{"sigma": 0.0067}}}}, "longeron": {{"normal": {{"sigma": 0.0067}}}},
                        "diagonal": {{"uniform": {{"low": -0.02, "high": 0}}}}}}}},
    {{"name": "rigid", "samples": {n}, "model": {{"prism": {{"stages": 2}}}},
      "length_errors": {{"batten": {{"normal": {{"sigma": 0.0067}}}}, "longeron": {{"normal": {{"sigma": 0.0067}}}},
                        "diagonal": {{"uniform": {{"low": -0.02, "high": 0}}}}}}}}
  ]
}}"#
    )
}

fn error(text: &str) -> String {
    Job::from_json(text, Path::new("."))
        .unwrap_err()
        .to_string()
}

#[test]
fn backlash_faults_are_named_by_their_json_path() {
    let rigid = format!(
        r#"{{"model": {{"prism": {{"stages": 1}}}}, "seed": 1, "cases": [{{"name": "a", "samples": 1, {CLEARANCE}}}]}}"#
    );
    let m = error(&rigid);
    assert!(
        m.starts_with("cases[0].backlash: the model has no joints"),
        "{m}"
    );
    let negative = r#"{"model": {"prism": {"stages": 1, "backlash": true}}, "seed": 1, "cases": [
        {"name": "a", "samples": 1, "backlash": {"clearance": {"uniform": {"low": -0.001, "high": 0.01}}}}]}"#;
    let m = error(negative);
    assert!(
        m.starts_with("cases[0].backlash.clearance: a clearance cannot be negative"),
        "{m}"
    );
    let normal = r#"{"model": {"prism": {"stages": 1, "backlash": true}}, "seed": 1, "cases": [
        {"name": "a", "samples": 1, "backlash": {"clearance": {"normal": {"mean": 0.01, "sigma": 0.001}}}}]}"#;
    assert!(
        error(normal).starts_with("cases[0].backlash.clearance: a clearance cannot be negative")
    );
    let typo = r#"{"model": {"prism": {"stages": 1, "backlash": {"clearence": 0.01}}}, "seed": 1, "cases": [
        {"name": "a", "samples": 1}]}"#;
    assert!(error(typo).starts_with("model.prism"), "{}", error(typo));
}

#[test]
fn backlash_shows_in_the_id_and_the_parameters() {
    let job = Job::from_json(&backlash_job(3, 1e-5), Path::new(".")).unwrap();
    let other = Job::from_json(&backlash_job(3, 1e-6), Path::new(".")).unwrap();
    assert_ne!(job.id, other.id, "the regularisation is part of the model");
    assert_eq!(job.cases[0].parameters.get("backlash"), Some(&1.0));
    assert_eq!(job.cases[1].parameters.get("backlash"), None);
    assert_eq!(
        job.cases[0].parameters.get("joint_compression_ratio"),
        Some(&1e-5)
    );
    assert_eq!(job.cases[0].model.joints().len(), 9);
}

/// Clearances are drawn after the members' words: the members' errors are those of the same
/// case without backlash, and each clearance lies in its range.
#[test]
fn clearances_follow_the_member_draws() {
    let job = Job::from_json(&backlash_job(20, 1e-5), Path::new(".")).unwrap();
    let mut worker = mc_shard::worker::Worker::new(&job);
    let mut rigid = job.clone();
    rigid.cases[0].backlash = None;
    let mut plain = mc_shard::worker::Worker::new(&rigid);
    let mut seen = Vec::new();
    for k in 0..20 {
        let line = worker.sample(k);
        assert_eq!(
            line.status,
            shard_record::Status::Converged,
            "{:?}",
            line.reason
        );
        assert!(line.loose_joints.is_some());
        plain.sample(k);
        assert_eq!(worker.last_errors(), plain.last_errors());
        assert!(plain.last_clearances().is_empty());
        let c = worker.last_clearances();
        assert_eq!(c.len(), 9);
        assert!(c.iter().all(|&g| (0.004..=0.017).contains(&g)), "{c:?}");
        seen.extend_from_slice(c);
    }
    seen.sort_by(f64::total_cmp);
    seen.dedup();
    assert_eq!(
        seen.len(),
        180,
        "every joint and sample draws its own clearance"
    );
}

/// One shard against three, one thread against two: the same bytes with backlash.
#[test]
fn backlash_samples_do_not_depend_on_the_split() {
    let job = Job::from_json(&backlash_job(24, 1e-5), Path::new(".")).unwrap();
    let (one, many) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let options = |threads| RunOptions {
        threads,
        quiet: true,
    };
    run_shard(&job, one.path(), ShardRange::new(0, 48), &options(1)).unwrap();
    for (a, b) in [(0, 7), (7, 30), (30, 48)] {
        run_shard(&job, many.path(), ShardRange::new(a, b), &options(2)).unwrap();
    }
    let (x, y) = (sample_lines(one.path()), sample_lines(many.path()));
    assert_eq!(x.len(), 48);
    assert_eq!(x, y);
    assert!(x[0].contains("\"loose_joints\""));
}
