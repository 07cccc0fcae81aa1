//! No corruption passes verification: a changed digit in a kept line of a partial shard, a
//! changed header parameter of a complete one, and a forged shard (fresh digests over a
//! changed number) are each found, by `run`, by the merge, or by `audit`, with the file and
//! line named and the right exit code.

use crate::binary::{mc_shard, run_shard};
use crate::common::*;
use std::path::Path;
use std::process::Output;

/// A 2-stage job of 300 samples in one case with sigma 0.5 (so a header edit to 0.05 is a
/// real parameter change).
fn job_text() -> String {
    r#"{"model": {"prism": {"stages": 2}}, "seed": 7, "cases": [
  {"name": "normal", "samples": 300,
   "length_errors": {"batten": {"normal": {"sigma": 0.5}}, "longeron": {"normal": {"sigma": 0.0063}}}}]}"#
        .to_string()
}

fn run(job: &Path, out: &Path) -> Output {
    mc_shard(&[
        "run",
        "--job",
        job.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ])
}

/// Changes the last digit of line `line`'s θ_P (1-based line number).
fn change_theta(text: &str, line: usize) -> String {
    let mut lines: Vec<String> = text.split_inclusive('\n').map(String::from).collect();
    let l = &mut lines[line - 1];
    let at = l.find("\"theta_p\":").unwrap() + 10;
    let end = at + l[at..].find(',').unwrap();
    let last = end - 1;
    let digit = l.as_bytes()[last];
    assert!(digit.is_ascii_digit(), "{l}");
    let new = if digit == b'9' {
        '8'
    } else {
        (digit + 1) as char
    };
    l.replace_range(last..end, &new.to_string());
    lines.concat()
}

#[test]
fn a_resume_verifies_the_lines_it_keeps_and_the_header() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &job_text());
    let out = dir.path().join("s");
    assert!(run(&job, &out).status.success());
    let path = only_shard(&out);
    let whole = std::fs::read_to_string(&path).unwrap();
    // Cut mid-way (header, 250 lines with two checkpoints) and change θ_P in line 101.
    let cut: String = whole.split_inclusive('\n').take(251).collect();
    std::fs::write(&path, change_theta(&cut, 101)).unwrap();
    let o = run(&job, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains(":102: checkpoint: sha256") && stderr.contains("a sample line was changed"),
        "{stderr}"
    );
    // A change after the last checkpoint is not kept: the line is solved again.
    std::fs::write(&path, change_theta(&cut, 240)).unwrap();
    let o = run(&job, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("100 computed now, 200 kept from before"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert_eq!(std::fs::read_to_string(&path).unwrap(), whole);

    // A header parameter changed in a complete shard: run refuses it, status calls it bad,
    // and the merge does not verify it.
    let edited = whole.replacen("\"sigma\":0.5", "\"sigma\":0.05", 1);
    assert_ne!(edited, whole);
    std::fs::write(&path, &edited).unwrap();
    let o = run(&job, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("the header was changed"), "{stderr}");
    let merged = mc_merge::run(
        &mc_merge::Options {
            paths: vec![out.clone()],
            out: None,
            plots: false,
            progress: false,
            settings: Default::default(),
        },
        &mut Vec::new(),
    );
    let err = merged.unwrap_err();
    assert!(err.to_string().contains("header was changed"), "{err}");
    assert_eq!(err.exit_code(), 6);
    // A header edited and its digests forged: the job comparison still refuses it.
    forge_shard(&path, |_| {});
    let forged = std::fs::read_to_string(&path).unwrap();
    assert!(forged.contains("\"sigma\":0.05"));
    let o = run(&job, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("differ from the job's"), "{stderr}");
}

#[test]
fn audit_replays_a_seeded_sample_and_names_a_forged_line() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &job_text());
    let out = dir.path().join("s");
    for shard in ["0/3", "1/3", "2/3"] {
        run_shard(&job, &out, shard);
    }
    let audit = |samples: &str, seed: &str| {
        mc_shard(&[
            "audit",
            "--job",
            job.to_str().unwrap(),
            out.to_str().unwrap(),
            "--samples",
            samples,
            "--seed",
            seed,
        ])
    };
    let o = audit("40", "3");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("audit.json")).unwrap()).unwrap();
    assert_eq!(report["samples_checked"], 40);
    assert_eq!(report["lines_in_shards"], 300);
    assert_eq!(report["mismatches"].as_array().unwrap().len(), 0);
    // Forge every θ_P of the middle shard (fresh digests, so the merge would accept it).
    let middle = out.join(shard_record::ShardRange::new(100, 200).file_name());
    forge_shard(&middle, |s| {
        if let Some(t) = s.theta_p.as_mut() {
            *t *= 1.0 + 1e-12;
        }
    });
    let o = audit("40", "3");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(6), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("audit.json")).unwrap()).unwrap();
    let mismatches = report["mismatches"].as_array().unwrap();
    assert!(!mismatches.is_empty());
    for m in mismatches {
        let index = m["index"].as_u64().unwrap();
        assert!((100..200).contains(&index), "{m}");
        assert!(
            m["file"]
                .as_str()
                .unwrap()
                .ends_with(&middle.file_name().unwrap().to_string_lossy().to_string())
        );
        // Line numbers count the header and the checkpoint lines before the sample.
        assert_eq!(
            m["line"].as_u64().unwrap(),
            index - 100 + 2 + (index - 100) / 100
        );
        assert_ne!(m["found"], m["expected"]);
    }
    assert!(stderr.contains("index"), "{stderr}");
    // The same seed chooses the same lines; bounds are refused with the usage code.
    let o2 = audit("40", "3");
    assert_eq!(o2.status.code(), Some(6));
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("audit.json")).unwrap()).unwrap();
    assert_eq!(again["mismatches"], report["mismatches"]);
    assert_eq!(audit("0", "1").status.code(), Some(2));
    assert_eq!(audit("1000001", "1").status.code(), Some(2));
}

/// An incomplete shard of format version 1 (no checkpoints: its lines cannot be verified)
/// is not resumed (5) and `status` says why; a complete one whose header matches the job is
/// still accepted as complete.
#[test]
fn a_version_1_partial_shard_is_not_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let job_path = write(dir.path(), "job.json", &job_text());
    let job = mc_shard::Job::read(&job_path).unwrap();
    let out = dir.path().join("s");
    assert!(run(&job_path, &out).status.success());
    let path = only_shard(&out);
    let whole = std::fs::read_to_string(&path).unwrap();
    let samples: Vec<&str> = whole
        .split_inclusive('\n')
        .filter(|l| l.starts_with(r#"{"record":"sample""#))
        .collect();
    let range = shard_record::ShardRange::new(0, 300);
    let mut v1 = mc_shard::shard::begin(&job, range);
    (v1.format_version, v1.checkpoint_every) = (1, None);
    let header = shard_record::to_line(&shard_record::Record::Begin(v1));
    std::fs::write(&path, format!("{header}{}", samples[..5].concat())).unwrap();
    let o = run(&job_path, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("format version 1"), "{stderr}");
    let o = mc_shard(&[
        "status",
        "--job",
        job_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--shards",
        "1",
    ]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("bad: an incomplete shard of format version 1")
    );
    // Complete in version 1 (its end line's digest covers the samples): accepted as is.
    let mut digest = shard_record::SampleDigest::new();
    for l in &samples {
        digest.add_line(l.as_bytes(), false);
    }
    let end = shard_record::to_line(&shard_record::Record::End(digest.end()));
    std::fs::write(&path, format!("{header}{}{end}", samples.concat())).unwrap();
    let o = run(&job_path, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("already complete and verified"));
}
