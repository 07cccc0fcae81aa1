//! `truss-mc`: `run-all` from the command line (shards as concurrent processes of this
//! binary, then the merge), mc-shard's commands through it, and the exit code of a failed
//! shard process.

// The job builders of mc-shard's tests: the same small job, shard-file reader and writer.
#[path = "../../mc-shard/tests/it/common/mod.rs"]
mod common;
#[path = "../../run-dir/tests/support/hostile.rs"]
mod hostile;

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

/// The reference: the whole job as one shard by `truss-mc run`, into `dir/single`.
fn single_run(dir: &Path, job: &Path) -> std::path::PathBuf {
    let single = dir.join("single");
    let r = truss_mc(
        &[
            "run",
            "--job",
            job.to_str().unwrap(),
            "--out",
            single.to_str().unwrap(),
            "--threads",
            "2",
            "--quiet",
        ],
        &[],
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    single
}

/// `run-all` runs every shard as concurrent processes, then merges: the sample lines are the
/// single run's, and the report is written.
#[test]
fn run_all_runs_every_shard_then_merges() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(60));
    let single = single_run(dir.path(), &job);
    let all = dir.path().join("all");
    let run_all = |extra: &[&str]| {
        let mut args = vec![
            "run-all",
            "--job",
            job.to_str().unwrap(),
            "--out",
            all.to_str().unwrap(),
            "--shards",
            "5",
            "--workers",
            "3",
        ];
        args.extend(extra);
        truss_mc(&args, &[])
    };
    let r = run_all(&["--quiet"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        !String::from_utf8_lossy(&r.stderr).contains("mc-merge: "),
        "--quiet: no progress"
    );
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("run-all: 120 samples in 5 shards on 3 workers"),
        "{stdout}"
    );
    assert_eq!(sample_lines(&all), sample_lines(&single));
    assert!(all.join("report/report.json").exists());
    assert!(all.join("report/theta_p-normal.svg").exists());
    // Without --quiet: the audit and the merge say when they start, a rerun says what it
    // reused, and the last line names report.html.
    let again = run_all(&[]);
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let stderr = String::from_utf8_lossy(&again.stderr);
    for said in [
        format!(
            "run-all: reusing 120 samples already in {}: all 5 shards complete (verified, not rerun)",
            all.display()
        ),
        "run-all: auditing: re-solving".to_string(),
        "run-all: merging: verifying every shard".to_string(),
        // The merge's own progress, stage by stage.
        "mc-merge: 120 samples in 5 shard files verified (".to_string(),
        "mc-merge: case 2 of 2 (uniform): percentiles, bootstrap, Rayleigh test (".to_string(),
        "mc-merge: drawing the plots into ".to_string(),
        "mc-merge: writing report.md and report.html (".to_string(),
    ] {
        assert!(stderr.contains(&said), "{said:?} not in {stderr}");
    }
    let stdout = String::from_utf8_lossy(&again.stdout);
    assert_eq!(
        stdout.lines().last(),
        Some(format!("report: {}", all.join("report/report.html").display()).as_str()),
        "{stdout}"
    );
    // With shard 1's file gone, the rerun names the shards it reuses, and runs shard 1 again.
    let mut files: Vec<_> = std::fs::read_dir(&all)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
        .collect();
    files.sort();
    std::fs::remove_file(&files[1]).unwrap();
    let third = run_all(&[]);
    assert!(third.status.success());
    let stderr = String::from_utf8_lossy(&third.stderr);
    assert!(
        stderr.contains("shards complete (verified, not rerun): 0, 2-4\n"),
        "{stderr}"
    );
    assert_eq!(sample_lines(&all), sample_lines(&single));
}

/// Exit codes of `run-all`: an invalid job is refused with mc-shard's code 3 before anything
/// starts, bad arguments with 2 (`--shards 0` at once), and a shard process that fails
/// because its file is in the way (a damaged file of no job, another job's shard) with 5,
/// naming the shard and advising to move the file, while the other shard completes.
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
    let started = std::time::Instant::now();
    let r = call(args(&job, &["--shards", "0"]));
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--shards must be 1 to"));
    assert!(started.elapsed().as_secs_f64() < 5.0);
    assert!(!out.exists(), "nothing started");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(
        out.join("shard-0000000000-0000000010.jsonl"),
        "not a shard\n",
    )
    .unwrap();
    let r = call(args(&job, &["--shards", "2", "--workers", "2"]));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("shard 0/2"), "{stderr}");
    assert!(stderr.contains("move it away"), "{stderr}");
    assert!(
        !stderr.contains("run the same command again to resume them"),
        "{stderr}"
    );
    assert_eq!(sample_lines(&out).len(), 10, "the other shard completed");

    // Another job's shards in the directory: 5 and the same advice.
    let other = dir.path().join("other");
    let job2 = write(
        dir.path(),
        "job2.json",
        &small_job(10).replace("\"seed\": 7", "\"seed\": 8"),
    );
    let r = truss_mc(
        &[
            "run",
            "--job",
            job2.to_str().unwrap(),
            "-o",
            other.to_str().unwrap(),
            "--shard",
            "0/2",
            "-q",
        ],
        &[],
    );
    assert!(r.status.success());
    let r = truss_mc(
        &[
            "run-all",
            "--job",
            job.to_str().unwrap(),
            "-o",
            other.to_str().unwrap(),
            "--shards",
            "2",
            "-q",
        ],
        &[],
    );
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains("holds a shard of job") && stderr.contains("move it away"),
        "{stderr}"
    );
}

/// Failed samples: the merge's code 7 with advice `run-all` accepts (`--allow-failed`),
/// which then merges. The failed samples are forged into a complete shard (fresh digests),
/// so the audit before the merge, on by default, finds the forgery first (6).
#[test]
fn run_all_failed_samples_advice_and_audit() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(20));
    let out = dir.path().join("o");
    let base = |extra: &[&str]| {
        let mut a = vec![
            "run-all",
            "--job",
            job.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--shards",
            "1",
            "-q",
        ];
        a.extend_from_slice(extra);
        truss_mc(&a, &[])
    };
    let r = base(&["--no-merge"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    common::forge_shard(&common::only_shard(&out), |s| {
        if s.index == 3 {
            s.status = shard_record::Status::Failed;
            s.theta_p = None;
            s.tan_theta_x = None;
            s.tan_theta_y = None;
            s.residual = None;
            s.slack_cables = None;
            s.reason = Some("forged".into());
        }
    });
    // The default audit re-solves 32 of the 40 lines: whether it meets index 3 depends on
    // the seed, so all 40 are audited here.
    let r = base(&["--audit-samples", "40"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(6), "{stderr}");
    assert!(
        stderr.contains("index 3 (case \"normal\", sample 3)"),
        "{stderr}"
    );
    let r = base(&["--audit-samples", "0"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(7), "{stderr}");
    assert!(stderr.contains("run-all takes --allow-failed"), "{stderr}");
    let r = base(&["--audit-samples", "0", "--allow-failed"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(out.join("report/report.json").exists());
}

/// Completions and the man page of truss-mc name its own run-all.
#[test]
fn truss_mc_completions_and_man() {
    let r = truss_mc(&["completions", "bash"], &[]);
    assert!(r.status.success());
    assert!(String::from_utf8_lossy(&r.stdout).contains("run-all"));
    let r = truss_mc(&["man"], &[]);
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(
        text.contains(".TH truss-mc-run-all") && text.contains("audit"),
        "{text}"
    );
}

/// The pids whose parent is `pid` (from /proc).
fn children_of(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // "pid (comm) state ppid …": comm may hold spaces, so split after its ')'.
        let Some(rest) = stat.rfind(')').map(|i| &stat[i + 1..]) else {
            continue;
        };
        let mut fields = rest.split_whitespace();
        let ppid = fields.nth(1).and_then(|p| p.parse::<u32>().ok());
        if ppid == Some(pid) {
            out.extend(
                entry
                    .file_name()
                    .to_str()
                    .and_then(|s| s.parse::<u32>().ok()),
            );
        }
    }
    out
}

/// Whether `pid` is a live process (not gone, not a zombie).
fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|stat| {
        let state = stat
            .rfind(')')
            .map(|i| stat[i + 1..].trim_start().chars().next());
        state != Some(Some('Z'))
    })
}

/// A job of one case of `samples` samples of the 30-stage prism (about 150 µs a sample).
fn thirty_stage_job(dir: &Path, seed: u64, samples: u64) -> std::path::PathBuf {
    write(
        dir,
        "job.json",
        &format!(
            r#"{{"model": {{"prism": {{"stages": 30}}}}, "seed": {seed}, "cases": [
  {{"name": "normal", "samples": {samples},
   "length_errors": {{"batten": {{"normal": {{"sigma": 0.0063}}}},
                     "longeron": {{"normal": {{"sigma": 0.0063}}}}}}}}]}}"#
        ),
    )
}

/// Waits (polling, not timing) until `run-all` (`child`) runs two workers and its shard
/// files in `out` hold more than `lines` sample lines; returns the workers' pids.
fn two_workers_running(child: &mut std::process::Child, out: &Path, lines: usize) -> Vec<u32> {
    use std::time::{Duration, Instant};
    let started = Instant::now();
    loop {
        assert!(
            child.try_wait().unwrap().is_none(),
            "run-all ended too soon"
        );
        let workers = children_of(child.id());
        if workers.len() == 2 && sample_lines(out).len() > lines {
            return workers;
        }
        assert!(started.elapsed() < Duration::from_secs(120), "no workers");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// SIGTERM to `run-all`'s pid alone (`kill PID`, as a supervisor or Slurm's time limit
/// sends it): it stops its workers (none survives it), prints the "interrupted" line, exits
/// 143; running the same command again resumes to the sample lines of an uninterrupted run.
#[test]
fn run_all_stops_its_workers_on_sigterm_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let job = thirty_stage_job(dir.path(), 11, 12000);
    let out = dir.path().join("all");
    let args = [
        "run-all",
        "--job",
        job.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--shards",
        "2",
        "--workers",
        "2",
        "--quiet",
        "--no-merge",
    ];
    let mut child = Command::new(env!("CARGO_BIN_EXE_truss-mc"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let workers = two_workers_running(&mut child, &out, 20);
    let s = Command::new("kill").arg(pid.to_string()).status().unwrap();
    assert!(s.success());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{stderr}");
    for w in &workers {
        assert!(!alive(*w), "worker {w} survived run-all");
    }
    let kept = sample_lines(&out).len();
    assert!(kept > 0 && kept < 12000, "{kept}");
    assert_eq!(
        stderr.trim(),
        format!("interrupted: {kept} samples kept; rerun the same command to resume")
    );
    let r = truss_mc(&args, &[]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let single = single_run(dir.path(), &job);
    assert!(
        sample_lines(&out) == sample_lines(&single),
        "resumed lines differ"
    );
}

/// `kill -9` of `run-all` (as the out-of-memory killer sends it): its shard processes stop
/// too (a parent-death signal gives them SIGTERM, so each keeps its finished lines), and
/// no shard stays locked, so a rerun is not told a file is in the way.
#[test]
fn run_all_killed_leaves_no_worker_running() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    // 100,000 samples of a 30-stage truss per shard: far longer than the test waits.
    let job = thirty_stage_job(dir.path(), 12, 200_000);
    let out = dir.path().join("all");
    let mut child = Command::new(env!("CARGO_BIN_EXE_truss-mc"))
        .args(["run-all", "--job", job.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(["--shards", "2", "--workers", "2", "--quiet", "--no-merge"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let workers = two_workers_running(&mut child, &out, 200);
    child.kill().unwrap();
    child.wait().unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while workers.iter().any(|w| alive(*w)) && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let survivors: Vec<u32> = workers.iter().copied().filter(|w| alive(*w)).collect();
    for w in &survivors {
        let _ = Command::new("kill").args(["-9", &w.to_string()]).status();
    }
    assert!(
        survivors.is_empty(),
        "workers {survivors:?} outlived run-all"
    );
    // Every shard's lock is free, and each kept its lines (a stop checkpoint).
    for entry in std::fs::read_dir(&out).unwrap().flatten() {
        let f = std::fs::File::open(entry.path()).unwrap();
        f.try_lock().expect("no shard stays locked");
    }
    let status = truss_mc(
        &[
            "status",
            "--job",
            job.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--shards",
            "2",
        ],
        &[],
    );
    let text = String::from_utf8_lossy(&status.stdout);
    assert_eq!(text.matches(": partial (").count(), 2, "{text}");
}

/// `truss-mc run-all --job JOB -o OUT -q EXTRA…`.
fn run_all_quiet(job: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run-all", "--job", job.to_str().unwrap()];
    args.extend(["-o", out.to_str().unwrap(), "-q"]);
    args.extend_from_slice(extra);
    truss_mc(&args, &[])
}

/// A shard locked by a live process: `run-all` says to wait for it or stop it, with its pid,
/// not to move the file away (exit 5).
#[test]
fn run_all_advice_for_a_live_lock_is_to_wait() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let out = dir.path().join("o");
    std::fs::create_dir_all(&out).unwrap();
    let held = std::fs::File::create(out.join("shard-0000000000-0000000020.jsonl")).unwrap();
    held.lock().unwrap();
    let r = run_all_quiet(&job, &out, &["--shards", "1"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "another process is writing this shard (pid {}): wait for it or stop it",
            std::process::id()
        )),
        "{stderr}"
    );
    assert!(!stderr.contains("move it away"), "{stderr}");
}

/// `DIR/report` a symbolic link: refused before any shard runs (exit 5), naming it; where
/// it points stays empty.
#[test]
fn run_all_refuses_a_linked_report_directory() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let out = dir.path().join("o");
    std::fs::create_dir_all(&out).unwrap();
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("report")).unwrap();
    let r = run_all_quiet(&job, &out, &[]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains(&out.join("report").display().to_string()),
        "{stderr}"
    );
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
    assert!(sample_lines(&out).is_empty(), "nothing ran");
}

/// A completion script that cannot be written (`/dev/full`) is an I/O error (exit 4), not
/// a panic (clap's generator panics when its writer fails).
#[test]
fn unwritable_output_is_an_io_error() {
    let truss_mc = Path::new(env!("CARGO_BIN_EXE_truss-mc"));
    let (status, stderr) = hostile::run_into_full(truss_mc, &["completions", "bash"]);
    assert_eq!(status, Some(4), "{stderr}");
    assert!(stderr.starts_with("truss-mc: error: "), "{stderr}");
}
