//! `truss-mc`: `run-all` from the command line (shards as concurrent processes of this
//! binary, then the merge), mc-shard's commands through it, and the exit code of a failed
//! shard process.

// The job builders of mc-shard's tests: the same small job, shard-file reader and writer.
#[path = "../../mc-shard/tests/it/common/mod.rs"]
mod common;

use common::{sample_lines, small_job, write};
use std::path::Path;
use std::process::{Command, Output};

fn truss_mc(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_truss-mc"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().unwrap()
}

/// `run-all` runs every shard as concurrent processes, then merges: the sample lines are the
/// single run's, and the report is written.
#[test]
fn run_all_runs_every_shard_then_merges() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(60));
    let single = dir.path().join("single");
    let r = truss_mc(
        &[
            "run",
            "--job",
            job.to_str().unwrap(),
            "--out",
            single.to_str().unwrap(),
            "--quiet",
        ],
        &[],
    );
    assert!(r.status.success());
    let all = dir.path().join("all");
    let r = truss_mc(
        &[
            "run-all",
            "--job",
            job.to_str().unwrap(),
            "--out",
            all.to_str().unwrap(),
            "--shards",
            "5",
            "--workers",
            "3",
            "--quiet",
        ],
        &[],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("run-all: 120 samples in 5 shards on 3 workers"),
        "{stdout}"
    );
    assert_eq!(sample_lines(&all), sample_lines(&single));
    assert!(all.join("report/report.json").exists());
    assert!(all.join("report/theta_p-normal.svg").exists());
}

/// Exit codes of `run-all`: an invalid job is refused with mc-shard's code 3 before anything
/// starts, bad arguments with 2, and a shard process that fails (here: its file is in the
/// way, a damaged file of no job) with 6, naming the shard, while the other shard completes.
#[test]
fn run_all_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let bad = write(
        dir.path(),
        "bad.json",
        r#"{"model": {"prism": {"stages": 0}}, "seed": 1, "cases": []}"#,
    );
    let args = |job: &Path, extra: &[&str]| {
        let mut a = vec![
            "run-all".to_string(),
            "--job".into(),
            job.display().to_string(),
        ];
        a.extend(["--out".into(), out.display().to_string(), "--quiet".into()]);
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let call = |a: Vec<String>| truss_mc(&a.iter().map(String::as_str).collect::<Vec<_>>(), &[]);
    let r = call(args(&bad, &[]));
    assert_eq!(
        r.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let job = write(dir.path(), "job.json", &small_job(10));
    assert_eq!(call(args(&job, &["--workers", "0"])).status.code(), Some(2));
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(
        out.join("shard-0000000000-0000000010.jsonl"),
        "not a shard\n",
    )
    .unwrap();
    let r = call(args(&job, &["--shards", "2", "--workers", "2"]));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(6), "{stderr}");
    assert!(stderr.contains("shard 0/2"), "{stderr}");
    assert_eq!(sample_lines(&out).len(), 10, "the other shard completed");
}
