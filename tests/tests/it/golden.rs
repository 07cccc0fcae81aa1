//! Golden reproducibility: the promise that the same job gives the same bytes, forever,
//! unless the numerics version changes. Pinned here: a job's id; the SHA-256 of a small
//! shard's sample lines for a rigid case, a case with backlash and a case with effects
//! (self-weight and a temperature field); and the SHA-256 of the merged `report.json`.
//!
//! If one of these fails, the change moved results: bump `NUMERICS_VERSION` in
//! `crates/truss-job/src/job.rs` in the same commit (which changes every job id, so that old
//! and new shards never mix), say why in the commit message, and update the values here.

use mc_shard::{Job, RunOptions, run_shard};
use sha2::{Digest, Sha256};
use shard_record::ShardRange;
use std::path::Path;

const JOB: &str = r#"{
  "model": {"prism": {"stages": 3}},
  "seed": 20210325,
  "cases": [
    {"name": "rigid", "samples": 60,
     "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}, "diagonal": {"uniform": {"low": -0.02, "high": 0}}}},
    {"name": "backlash", "samples": 60, "model": {"prism": {"stages": 3, "backlash": true}},
     "backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}},
     "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}, "diagonal": {"uniform": {"low": -0.02, "high": 0}}}},
    {"name": "effects", "samples": 60,
     "effects": {"gravity": {"direction": [1, 0, 0]}, "thermal_gradient": {"gradient": [0.001, 0, 0], "offset": 2}},
     "length_errors": {"batten": {"normal": {"sigma": 0.0067}}, "longeron": {"normal": {"sigma": 0.0067}}}}
  ]
}"#;

const MESSAGE: &str =
    "results moved: bump NUMERICS_VERSION in the same commit (see this file's doc)";

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 of the sample lines of case `name` in the shard files of `dir`.
fn case_digest(dir: &Path, name: &str) -> String {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    files.sort();
    let mut hash = Sha256::new();
    let tag = format!(r#""case":"{name}""#);
    for f in files {
        for line in std::fs::read_to_string(f).unwrap().lines() {
            if line.starts_with(r#"{"record":"sample""#) && line.contains(&tag) {
                hash.update(line.as_bytes());
                hash.update(b"\n");
            }
        }
    }
    hex(&hash.finalize())
}

#[test]
fn golden_job_shards_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let job = Job::from_json(JOB, dir.path()).unwrap();
    for r in ShardRange::partition(2, job.samples()).unwrap() {
        let options = RunOptions {
            threads: 2,
            quiet: true,
        };
        run_shard(&job, dir.path(), r, &options).unwrap();
    }
    let out = dir.path().join("report");
    let options = mc_merge::Options {
        paths: vec![dir.path().to_path_buf()],
        out: Some(out.clone()),
        plots: false,
        progress: false,
        settings: mc_merge::Settings {
            replicates: 200,
            gof_replicates: 100,
            ..Default::default()
        },
    };
    mc_merge::run(&options, &mut Vec::new()).unwrap();
    let report = hex(&Sha256::digest(
        std::fs::read(out.join("report.json")).unwrap(),
    ));
    let got = [
        job.id.clone(),
        case_digest(dir.path(), "rigid"),
        case_digest(dir.path(), "backlash"),
        case_digest(dir.path(), "effects"),
        report,
    ];
    let want = [
        "16b2ae44ed7d9f651f0d6a789b98578c90bec62eb3db8d5548287afda231ed6b",
        "94ce944399e4677c5705bde025cc92a70f975a9f2ab7c855a7e8f13ecf665d24",
        "546cf9d696c4c41815489fa90b763f7db5a7158a8fe8896316e035a3f1ee86a1",
        "7b94c46945c2820f627e0bdcc5aa42e331a0f6fe76f9a1cbbfa384b72441d183",
        "b2d6d0b9a68bae26b6af79ee68e9ab37330a68d67bf1f61fc46b378585fb46d1",
    ];
    for (what, (g, w)) in [
        "job id",
        "rigid lines",
        "backlash lines",
        "effects lines",
        "report.json",
    ]
    .iter()
    .zip(got.iter().zip(want))
    {
        assert_eq!(g, w, "{what}: {MESSAGE}");
    }
}

/// The case parameters the job crate writes into a shard's header are the wire format's
/// named keys, which the merge's sweeps read (`shard_record::parameters`); a case whose
/// cables have another compression ratio than the default gets its own key (and so its own
/// series), the others none.
#[test]
fn case_parameters_use_the_wire_formats_keys() {
    let with_ratio = JOB.replace(
        r#"{"prism": {"stages": 3, "backlash": true}}"#,
        r#"{"prism": {"stages": 3, "backlash": true, "compression_ratio": 1e-8}}"#,
    );
    assert_ne!(with_ratio, JOB);
    let mut written = std::collections::BTreeSet::new();
    for text in [JOB, &with_ratio] {
        let job = Job::from_json(text, Path::new(".")).unwrap();
        for c in &job.cases {
            let ratio = c.parameters.get("cable_compression_ratio");
            let expected = (text != JOB && c.name == "backlash").then_some(&1e-8);
            assert_eq!(ratio, expected, "case {}", c.name);
            written.extend(c.parameters.keys().cloned());
        }
    }
    let known: std::collections::BTreeSet<String> = shard_record::parameters::ALL
        .into_iter()
        .map(String::from)
        .collect();
    assert!(
        written.is_subset(&known),
        "{written:?} not all in {known:?}"
    );
    assert!(written.contains("backlash") && written.contains("uniform"));
}
