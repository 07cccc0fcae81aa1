//! `mc-shard work`: four concurrent workers share a directory; one is killed with SIGKILL in
//! the middle of a shard; one more worker started later takes its stale claim over. Every
//! shard is completed exactly once, every sample computed once (the line in flight at the
//! kill at most twice), and the merged report is byte-identical to a single run's.

use crate::common::*;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const SHARDS: u64 = 8;

fn worker(job: &Path, out: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_mc-shard"))
        .args([
            "work",
            "--job",
            job.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--shards", &SHARDS.to_string(), "--threads", "1", "--quiet"])
        .args(["--heartbeat", "0.2", "--stale-after", "1.5"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap()
}

fn actions(child: Child) -> Vec<serde_json::Value> {
    let out = child.wait_with_output().unwrap();
    BufReader::new(&out.stdout[..])
        .lines()
        .map(|l| serde_json::from_str(&l.unwrap()).unwrap())
        .collect()
}

fn merged_report(dir: &Path) -> Vec<u8> {
    let report = dir.join("report");
    let options = mc_merge::Options {
        paths: vec![dir.to_path_buf()],
        out: Some(report.clone()),
        plots: false,
        progress: false,
        settings: mc_merge::Settings {
            replicates: 200,
            gof_replicates: 100,
            ..Default::default()
        },
    };
    mc_merge::run(&options, &mut Vec::new()).unwrap();
    std::fs::read(report.join("report.json")).unwrap()
}

#[test]
fn concurrent_workers_with_one_killed_finish_every_shard_exactly_once() {
    let dir = tempfile::tempdir().unwrap();
    let text = small_job(1).replace(
        r#""model": {"prism": {"stages": 2}}"#,
        r#""model": {"prism": {"stages": 5}}"#,
    );
    let text = text.replace(r#""samples": 1,"#, r#""samples": 3000,"#);
    let job = write(dir.path(), "job.json", &text);
    let total = mc_shard::Job::read(&job).unwrap().samples();

    let single = dir.path().join("single");
    let r = Command::new(env!("CARGO_BIN_EXE_mc-shard"))
        .args([
            "run",
            "--job",
            job.to_str().unwrap(),
            "--out",
            single.to_str().unwrap(),
            "--quiet",
        ])
        .status()
        .unwrap();
    assert!(r.success());

    let shared = dir.path().join("shared");
    let mut workers: Vec<Child> = (0..4).map(|_| worker(&job, &shared)).collect();
    // Find a worker in the middle of a shard: its claim exists and its shard file has lines
    // up to a checkpoint.
    let claims = shared.join("claims");
    let deadline = Instant::now() + Duration::from_secs(120);
    let victim_pid = loop {
        assert!(Instant::now() < deadline, "no worker got to work");
        let found = std::fs::read_dir(&claims).ok().and_then(|entries| {
            entries.filter_map(|e| e.ok()).find_map(|e| {
                let name = e.file_name().into_string().ok()?;
                let i: u64 = name
                    .strip_prefix("shard-")?
                    .split('-')
                    .next()?
                    .parse()
                    .ok()?;
                let range = shard_record::ShardRange::for_shard(i, SHARDS, total).ok()?;
                let len = std::fs::metadata(shared.join(range.file_name()))
                    .ok()?
                    .len();
                let claim: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(e.path()).ok()?).ok()?;
                // Past the first checkpoint (100 lines of about 250 bytes), so that the
                // killed worker leaves verified lines for the takeover to keep.
                (len > 40_000).then(|| claim["pid"].as_u64().unwrap() as u32)
            })
        });
        if let Some(pid) = found {
            break pid;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let index = workers
        .iter()
        .position(|w| w.id() == victim_pid)
        .expect("the claim names one of ours");
    let mut victim = workers.remove(index);
    victim.kill().unwrap();
    let victim_actions = actions(victim);
    let mut all: Vec<serde_json::Value> = victim_actions;
    for w in workers {
        all.extend(actions(w));
    }
    // The killed worker's shard is still claimed (by a dead worker) and incomplete.
    let status = |dir: &Path| -> String {
        let o = Command::new(env!("CARGO_BIN_EXE_mc-shard"))
            .args([
                "status",
                "--job",
                job.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
            ])
            .args(["--shards", &SHARDS.to_string(), "--missing"])
            .output()
            .unwrap();
        String::from_utf8(o.stdout).unwrap()
    };
    assert_ne!(
        status(&shared).trim(),
        "",
        "the killed shard should be unfinished"
    );
    // One more worker, after the dead claim has gone stale, finishes it.
    std::thread::sleep(Duration::from_millis(1600));
    let last = actions(worker(&job, &shared));
    assert!(last.iter().any(|a| a["action"] == "took-over"), "{last:?}");
    all.extend(last);
    assert_eq!(status(&shared).trim(), "");

    // Every shard completed exactly once, and by lines computed once: those its completer
    // computed plus those kept from the killed worker (a line torn at the kill is not kept,
    // so it is computed again, once) make up the shard.
    for (i, range) in shard_record::ShardRange::partition(SHARDS, total)
        .unwrap()
        .iter()
        .enumerate()
    {
        let done: Vec<_> = all
            .iter()
            .filter(|a| a["shard"] == i as u64 && a["action"] == "completed")
            .collect();
        assert_eq!(done.len(), 1, "shard {i}: {all:?}");
        let (computed, kept) = (
            done[0]["computed"].as_u64().unwrap(),
            done[0]["kept"].as_u64().unwrap(),
        );
        assert_eq!(computed + kept, range.len(), "shard {i}");
    }
    assert!(
        all.iter().any(|a| a["kept"].as_u64().unwrap_or(0) > 0),
        "the taken-over shard kept its lines"
    );
    assert_eq!(merged_report(&shared), merged_report(&single));
}
