//! The `mc-shard` binary as users run it: crash and resume, conflicts, reproduce, status,
//! batch-system environments, and exit codes.

use crate::common::*;
use std::path::Path;
use std::process::{Command, Output};

fn mc_shard(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mc-shard"));
    c.args(args);
    for k in mc_shard::select::VARIABLES {
        c.env_remove(k);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

fn run(job: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        "--job",
        job.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    mc_shard(&args, &[])
}

fn only_file(dir: &Path) -> std::path::PathBuf {
    let files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

/// A run killed with SIGKILL mid-shard, run again with the same command, gives a file
/// byte-identical to an uninterrupted run.
#[test]
fn kill_9_then_rerun_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(3000));
    let reference = dir.path().join("reference");
    assert!(run(&job, &reference, &["--threads", "2"]).status.success());
    let expected = std::fs::read(only_file(&reference)).unwrap();

    let out = dir.path().join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mc-shard"))
        .args([
            "run",
            "--job",
            job.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--threads",
            "1",
        ])
        .spawn()
        .unwrap();
    // Wait until some samples are written, then kill without warning.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    loop {
        let len = std::fs::read_dir(&out)
            .ok()
            .and_then(|mut d| d.next())
            .and_then(|e| e.ok())
            .and_then(|e| e.metadata().ok())
            .map_or(0, |m| m.len());
        if len > expected.len() as u64 / 5 {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the run wrote nothing"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = std::fs::read(only_file(&out)).unwrap();
    assert!(
        partial.len() < expected.len(),
        "killed too late to test anything"
    );
    // What the killed run left, up to its last complete line, is what the full run wrote.
    let whole_lines = partial
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    assert!(whole_lines > 0 && expected.starts_with(&partial[..whole_lines]));

    let again = run(&job, &out, &["--threads", "2"]);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(String::from_utf8_lossy(&again.stdout).contains("kept from before"));
    assert_eq!(std::fs::read(only_file(&out)).unwrap(), expected);
}

/// A torn last line (the writer stopped mid-line) is cut off and the shard completed; a
/// complete shard is verified and left alone.
#[test]
fn torn_tail_is_repaired_and_complete_shards_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(50));
    let out = dir.path().join("out");
    assert!(run(&job, &out, &[]).status.success());
    let file = only_file(&out);
    let expected = std::fs::read(&file).unwrap();
    let again = run(&job, &out, &[]);
    assert!(String::from_utf8_lossy(&again.stdout).contains("already complete and verified"));
    assert_eq!(std::fs::read(&file).unwrap(), expected);
    // Cut in the middle of line 30.
    let cut = expected
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(29)
        .unwrap()
        .0
        + 20;
    std::fs::write(&file, &expected[..cut]).unwrap();
    assert!(run(&job, &out, &[]).status.success());
    assert_eq!(std::fs::read(&file).unwrap(), expected);
}

/// A shard file of another job is never appended to: exit 5, file untouched. A shard whose
/// lock another process holds: exit 5.
#[test]
fn another_jobs_file_and_a_held_lock_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = write(dir.path(), "a.json", &small_job(20));
    let b = write(
        dir.path(),
        "b.json",
        &small_job(20).replace("\"seed\": 7", "\"seed\": 8"),
    );
    let out = dir.path().join("out");
    let first = run(&a, &out, &["--range", "0..10"]);
    assert!(first.status.success());
    let file = only_file(&out);
    let bytes = std::fs::read(&file).unwrap();
    let other = run(&b, &out, &["--range", "0..10"]);
    assert_eq!(other.status.code(), Some(5));
    assert!(String::from_utf8_lossy(&other.stderr).contains("never appended to"));
    assert_eq!(std::fs::read(&file).unwrap(), bytes);

    let locked_path = out.join(shard_record::ShardRange::new(10, 40).file_name());
    let holder = std::fs::File::create(&locked_path).unwrap();
    holder.lock().unwrap();
    let blocked = run(&a, &out, &["--range", "10..40"]);
    assert_eq!(blocked.status.code(), Some(5));
    assert!(String::from_utf8_lossy(&blocked.stderr).contains("another process is writing"));
    drop(holder);
    // Another test of this binary may have forked a child while `holder` was open: the
    // child shares the lock until it execs (the descriptor is close-on-exec). Wait until
    // the lock is free, as the next writer would find it.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
    while std::fs::File::open(&locked_path)
        .unwrap()
        .try_lock()
        .is_err()
    {
        assert!(
            std::time::Instant::now() < deadline,
            "the lock was never released"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let after = run(&a, &out, &["--range", "10..40"]);
    assert!(
        after.status.success(),
        "{}",
        String::from_utf8_lossy(&after.stderr)
    );
}

/// `reproduce` prints exactly the shard's line; `--detail` carries that line, the draws and
/// the iteration log.
#[test]
fn reproduce_prints_the_shards_line() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(40));
    let out = dir.path().join("out");
    assert!(run(&job, &out, &[]).status.success());
    let lines = sample_lines(&out);
    for (case, k, index) in [("normal", 0, 0), ("normal", 39, 39), ("uniform", 17, 57)] {
        let r = mc_shard(
            &[
                "reproduce",
                "--job",
                job.to_str().unwrap(),
                "--case",
                case,
                "--sample",
                &k.to_string(),
            ],
            &[],
        );
        assert!(r.status.success());
        assert_eq!(
            String::from_utf8(r.stdout).unwrap(),
            format!("{}\n", lines[index])
        );
    }
    let r = mc_shard(
        &[
            "reproduce",
            "--job",
            job.to_str().unwrap(),
            "--case",
            "uniform",
            "--sample",
            "17",
            "--detail",
        ],
        &[],
    );
    let d: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(d["line"].as_str().unwrap(), lines[57]);
    assert!(d["length_errors"]["longeron.1.0"].as_f64().unwrap().abs() <= 0.02);
    assert_eq!(d["length_errors"]["batten.0.0"], 0.0);
    assert!(!d["iterations"].as_array().unwrap().is_empty());
    assert!(d["displacements"]["n2.0"].is_array());
    let bad = mc_shard(
        &[
            "reproduce",
            "--job",
            job.to_str().unwrap(),
            "--case",
            "nope",
            "--sample",
            "0",
        ],
        &[],
    );
    assert_eq!(bad.status.code(), Some(2));
    let bad = mc_shard(
        &[
            "reproduce",
            "--job",
            job.to_str().unwrap(),
            "--case",
            "normal",
            "--sample",
            "40",
        ],
        &[],
    );
    assert_eq!(bad.status.code(), Some(2));
}

/// Shards chosen by Slurm's or Kubernetes' variables land where --shard puts them, and
/// `status --missing` lists what is left.
#[test]
fn batch_system_environments_select_the_shard() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(15));
    let out = dir.path().join("out");
    let j = job.to_str().unwrap();
    let o = out.to_str().unwrap();
    let status = || {
        String::from_utf8(
            mc_shard(
                &[
                    "status",
                    "--job",
                    j,
                    "--out",
                    o,
                    "--shards",
                    "3",
                    "--missing",
                ],
                &[],
            )
            .stdout,
        )
        .unwrap()
    };
    assert_eq!(status(), "0,1,2\n");
    let r = mc_shard(
        &["run", "--job", j, "--out", o, "--quiet"],
        &[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(out.join("shard-0000000010-0000000020.jsonl").exists());
    assert_eq!(status(), "0,2\n");
    let r = mc_shard(
        &["run", "--job", j, "--out", o, "--quiet"],
        &[("JOB_COMPLETION_INDEX", "2"), ("MC_SHARD_COUNT", "3")],
    );
    assert!(r.status.success());
    let r = mc_shard(
        &["run", "--job", j, "--out", o, "--quiet", "--shard", "0/3"],
        &[],
    );
    assert!(r.status.success());
    assert_eq!(status(), "\n");
    let text = String::from_utf8(
        mc_shard(&["status", "--job", j, "--out", o, "--shards", "3"], &[]).stdout,
    )
    .unwrap();
    assert_eq!(text.matches("complete").count(), 3, "{text}");
    let r = mc_shard(
        &["run", "--job", j, "--out", o, "--quiet"],
        &[("JOB_COMPLETION_INDEX", "2")],
    );
    assert_eq!(r.status.code(), Some(2));
}

#[test]
fn exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let good = write(dir.path(), "good.json", &small_job(5));
    let bad = write(
        dir.path(),
        "bad.json",
        &small_job(5).replace("\"samples\": 5", "\"samples\": 0"),
    );
    let out = dir.path().join("out");
    assert_eq!(run(&bad, &out, &[]).status.code(), Some(3));
    assert_eq!(
        run(&dir.path().join("none.json"), &out, &[]).status.code(),
        Some(4)
    );
    assert_eq!(
        run(&good, &out, &["--range", "5..99"]).status.code(),
        Some(2)
    );
    assert_eq!(run(&good, &out, &["--shard", "3/3"]).status.code(), Some(2));
    let plan = mc_shard(&["plan", "--job", good.to_str().unwrap()], &[]);
    assert!(plan.status.success());
    let id = mc_shard_job_id(&good);
    assert!(String::from_utf8_lossy(&plan.stdout).contains(&id));
}

fn mc_shard_job_id(job: &Path) -> String {
    mc_shard::Job::read(job).unwrap().id
}

/// `plan` on a job of milliseconds advises this machine and no cluster, in good grammar;
/// its JSON says so too.
#[test]
fn plan_advises_no_cluster_for_a_small_job() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(20));
    let plan = mc_shard(&["plan", "--job", job.to_str().unwrap()], &[]);
    assert!(plan.status.success());
    let text = String::from_utf8_lossy(&plan.stdout);
    let advice = text.lines().last().unwrap();
    assert!(
        advice.starts_with("suggested: this machine, about "),
        "{advice}"
    );
    assert!(advice.ends_with("; no cluster needed"), "{advice}");
    assert!(
        !text.contains("1 shards") && !text.contains("cluster,"),
        "{text}"
    );
    let json = mc_shard(&["plan", "--job", job.to_str().unwrap(), "--json"], &[]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["suggested"]["cluster_advised"], false);
}
