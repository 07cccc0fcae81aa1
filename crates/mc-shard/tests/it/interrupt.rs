//! Interrupts with real signals: `mc-shard run` and `mc-shard work` stop on SIGTERM and
//! SIGINT with the shell's codes (143, 130) and the "interrupted" line, keep every finished
//! line, and a rerun resumes to the bytes of an uninterrupted run.
//!
//! The job is sized so that a run lasts seconds; the signal is sent as soon as the shard
//! file holds sample lines (polled, not timed), long before the run could end.

use crate::common::{sample_lines, write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A 30-stage job of `n` samples (about 0.1 ms of one core each in the test profile).
fn job(n: u64) -> String {
    format!(
        r#"{{"model": {{"prism": {{"stages": 30}}}}, "seed": 11, "cases": [
  {{"name": "normal", "samples": {n},
    "length_errors": {{"batten": {{"normal": {{"sigma": 0.0063}}}},
                      "longeron": {{"normal": {{"sigma": 0.0063}}}}}}}}]}}"#
    )
}

/// The bytes of the `.jsonl` files in `dir`.
fn bytes_in(dir: &Path) -> u64 {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "jsonl"))
        .map(|e| e.metadata().map_or(0, |m| m.len()))
        .sum()
}

fn mc_shard(args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mc-shard"));
    cmd.args(args).stdout(Stdio::piped()).stderr(Stdio::piped());
    cmd
}

/// Waits until the `.jsonl` files in `dir` have grown by a few sample lines: the run is
/// writing (so its signal handler is installed).
fn wait_for_lines(dir: &Path, child: &mut Child) {
    let before = bytes_in(dir);
    let started = Instant::now();
    loop {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was interrupted: make the job bigger"
        );
        if bytes_in(dir) > before + 2000 {
            return;
        }
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no sample line appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Sends `signal` (`TERM`, `INT`) to `pid` with the system's `kill`.
pub fn kill(signal: &str, pid: u32) {
    let s = Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
        .unwrap();
    assert!(s.success());
}

/// Runs `args` to completion; panics unless it succeeds.
fn run_ok(args: &[&str]) {
    let o = mc_shard(args).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `mc-shard run`: SIGTERM gives 143 and the line; SIGINT on the rerun gives 130; a third
/// run completes the shard, byte for byte the uninterrupted file.
#[test]
fn run_stops_on_sigterm_and_sigint_and_resumes_to_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &job(12_000));
    let job = job.to_str().unwrap();
    let (cut, whole) = (dir.path().join("cut"), dir.path().join("whole"));
    let args = |out: &Path| -> Vec<String> {
        [
            "run",
            "--job",
            job,
            "--out",
            out.to_str().unwrap(),
            "--threads",
            "2",
            "--quiet",
        ]
        .map(String::from)
        .to_vec()
    };
    let cut_args = args(&cut);
    let cut_args: Vec<&str> = cut_args.iter().map(String::as_str).collect();
    let mut kept = 0;
    for (signal, code) in [("TERM", 143), ("INT", 130)] {
        let mut child = mc_shard(&cut_args).spawn().unwrap();
        wait_for_lines(&cut, &mut child);
        kill(signal, child.id());
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{stderr}");
        let lines = sample_lines(&cut).len() as u64;
        assert!(lines > kept && lines < 12_000, "{lines}");
        assert_eq!(
            stderr.trim(),
            format!("interrupted: {lines} samples kept; rerun the same command to resume")
        );
        kept = lines;
    }
    run_ok(&cut_args);
    let whole_args = args(&whole);
    run_ok(&whole_args.iter().map(String::as_str).collect::<Vec<_>>());
    let name = "shard-0000000000-0000012000.jsonl";
    assert!(
        std::fs::read(cut.join(name)).unwrap() == std::fs::read(whole.join(name)).unwrap(),
        "the resumed shard differs from the uninterrupted one"
    );
}

/// `mc-shard work`: SIGTERM stops the worker with 143, releases its claim, and a rerun
/// finishes every shard.
#[test]
fn work_stops_on_sigterm_and_releases_its_claim() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &job(12_000));
    let out = dir.path().join("out");
    let args = [
        "work",
        "--job",
        job.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--shards",
        "2",
        "--threads",
        "2",
        "--quiet",
    ];
    let mut child = mc_shard(&args).spawn().unwrap();
    wait_for_lines(&out, &mut child);
    kill("TERM", child.id());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(143), "{stderr}");
    let lines = sample_lines(&out).len();
    assert!(
        stderr.contains(&format!(
            "interrupted: {lines} samples kept; rerun the same command to resume"
        )),
        "{stderr}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains(r#""action":"interrupted""#));
    let claims = std::fs::read_dir(out.join("claims"))
        .unwrap()
        .filter(|e| {
            let name = e.as_ref().unwrap().file_name();
            name.to_string_lossy().ends_with(".claim")
        })
        .count();
    assert_eq!(claims, 0, "the interrupted shard's claim is released");
    run_ok(&args);
    assert_eq!(sample_lines(&out).len(), 12_000);
}
