//! `mc-shard run` placed by a batch scheduler: the binary started with each scheduler's
//! environment (Slurm, AWS Batch, Google Cloud Batch, Kubernetes, the generic pair for
//! HTCondor and others) writes exactly the shard it names, and an environment that does not
//! say one shard (half a pair, two schedulers, disagreeing counts) is refused with exit 2
//! and the variables named. The variables are the ones the submit files in `jobs/` rely on.

use crate::common::*;
use std::path::Path;
use std::process::Output;

/// `mc-shard run` of `job` into `out` with exactly the scheduler variables `env` (every
/// other one removed) and the extra flags `extra`.
fn run_with(job: &Path, out: &Path, env: &[(&str, &str)], extra: &[&str]) -> Output {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_mc-shard"));
    c.args(["run", "--job", job.to_str().unwrap()])
        .args(["--out", out.to_str().unwrap(), "--quiet", "--threads", "1"])
        .args(extra);
    for k in mc_shard::select::VARIABLES {
        c.env_remove(k);
    }
    c.envs(env.iter().copied());
    c.output().unwrap()
}

/// The shard files in `dir`, by name.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// Each scheduler's variables pick shard 1 of 3 of a 30-sample job (indices 10..20), and
/// the run says which variable it followed.
#[test]
fn each_scheduler_runs_the_shard_it_names() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(15));
    for (name, env, extra) in [
        (
            "slurm",
            &[
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ][..],
            &[][..],
        ),
        (
            "aws-batch",
            &[
                ("AWS_BATCH_JOB_ARRAY_INDEX", "1"),
                ("AWS_BATCH_JOB_ARRAY_SIZE", "3"),
            ],
            &[],
        ),
        (
            "google-batch",
            &[("BATCH_TASK_INDEX", "1"), ("BATCH_TASK_COUNT", "3")],
            &[],
        ),
        (
            "kubernetes",
            &[("JOB_COMPLETION_INDEX", "1"), ("MC_SHARD_COUNT", "3")],
            &[],
        ),
        (
            "htcondor",
            &[("MC_SHARD_INDEX", "1"), ("MC_SHARD_COUNT", "3")],
            &[],
        ),
        (
            "generic-with-flag",
            &[("MC_SHARD_INDEX", "1")],
            &["--shards", "3"],
        ),
        (
            "generic-over-slurm",
            &[
                ("MC_SHARD_INDEX", "1"),
                ("MC_SHARD_COUNT", "3"),
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            &[],
        ),
    ] {
        let out = dir.path().join(name);
        let r = run_with(&job, &out, env, extra);
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        assert_eq!(
            files(&out),
            ["shard-0000000010-0000000020.jsonl"],
            "{name}: {stdout}"
        );
        let followed = env[0].0;
        assert!(
            stdout.contains(&format!("(range from {followed})")),
            "{name}: {stdout}"
        );
    }
    // The same bytes whichever scheduler ran it.
    let bytes = |name: &str| {
        std::fs::read(
            dir.path()
                .join(name)
                .join("shard-0000000010-0000000020.jsonl"),
        )
        .unwrap()
    };
    assert_eq!(bytes("slurm"), bytes("aws-batch"));
    assert_eq!(bytes("slurm"), bytes("google-batch"));
    assert_eq!(bytes("slurm"), bytes("htcondor"));
}

/// An environment that does not name one shard runs nothing: exit 2, and the message names
/// the variables to set.
#[test]
fn unclear_environments_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(15));
    for (env, extra, words) in [
        (
            &[("AWS_BATCH_JOB_ARRAY_INDEX", "1")][..],
            &[][..],
            &["AWS_BATCH_JOB_ARRAY_INDEX", "AWS_BATCH_JOB_ARRAY_SIZE"][..],
        ),
        (
            &[("BATCH_TASK_COUNT", "3")],
            &[],
            &["BATCH_TASK_COUNT", "BATCH_TASK_INDEX"],
        ),
        (
            &[("MC_SHARD_INDEX", "1")],
            &[],
            &["MC_SHARD_INDEX", "MC_SHARD_COUNT"],
        ),
        (
            &[("MC_SHARD_COUNT", "3")],
            &[],
            &["MC_SHARD_COUNT", "MC_SHARD_INDEX"],
        ),
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
                ("AWS_BATCH_JOB_ARRAY_INDEX", "2"),
                ("AWS_BATCH_JOB_ARRAY_SIZE", "3"),
            ],
            &[],
            &["SLURM_ARRAY_TASK_ID=1", "AWS_BATCH_JOB_ARRAY_INDEX=2"],
        ),
        (
            &[("BATCH_TASK_INDEX", "1"), ("BATCH_TASK_COUNT", "3")],
            &["--shards", "4"],
            &["--shards 4", "BATCH_TASK_COUNT=3"],
        ),
        (
            &[("BATCH_TASK_INDEX", "3"), ("BATCH_TASK_COUNT", "3")],
            &[],
            &["shard 3 of 3"],
        ),
    ] {
        let out = dir.path().join("refused");
        let r = run_with(&job, &out, env, extra);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{env:?}: {stderr}");
        for w in words {
            assert!(stderr.contains(w), "{env:?}: {stderr} names {w}");
        }
        assert!(files(&out).is_empty(), "{env:?} wrote nothing");
    }
}

/// The submit files in `jobs/` run `mc-shard run` without `--shard` or `--range`, so the
/// scheduler's variables decide; HTCondor's passes `$(Process)` and the count it queues.
#[test]
fn submit_files_leave_the_shard_to_the_environment() {
    let jobs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs");
    let json = |path: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(jobs.join(path)).unwrap()).unwrap()
    };
    let words = |v: &serde_json::Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap().to_string())
            .collect()
    };
    let aws = json("aws-batch/shards.json");
    let aws_command = words(&aws["containerOverrides"]["command"]);
    assert_eq!(aws_command[..2], ["mc-shard", "run"]);
    assert!(aws["arrayProperties"]["size"].as_u64().unwrap() > 1);
    let google = json("google-batch/job.json");
    let container = &google["taskGroups"][0]["taskSpec"]["runnables"][0]["container"];
    assert_eq!(container["entrypoint"], "mc-shard");
    let google_command = words(&container["commands"]);
    assert_eq!(google_command[0], "run");
    for command in [&aws_command, &google_command] {
        assert!(
            !command.iter().any(|w| w == "--shard" || w == "--range"),
            "{command:?}"
        );
    }
    json("aws-batch/job-definition.json");
    json("aws-batch/merge.json");
    let condor = std::fs::read_to_string(jobs.join("htcondor/shards.sub")).unwrap();
    for line in [
        "environment = \"MC_SHARD_INDEX=$(Process) MC_SHARD_COUNT=$(Shards)\"",
        "queue $(Shards)",
    ] {
        assert!(condor.lines().any(|l| l == line), "shards.sub has {line}");
    }
    assert!(!condor.contains("--shard ") && !condor.contains("--range"));
}
