//! Cron workers route around damage: a damaged shard is quarantined with its reason while
//! real worker processes (real claims, real file locks) complete the others; the worker
//! exits 5 at the end, `status` lists the quarantined shard, a later worker skips it, and a
//! worker with another `--shards` count on the directory is refused. Also the bounds of
//! `work`'s and `run`'s flags.

use crate::binary::{mc_shard, run_shard};
use crate::common::*;
use std::path::Path;
use std::process::Output;

fn work(job: &Path, out: &Path, shards: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "work",
        "--job",
        job.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--shards",
        shards,
        "--threads",
        "1",
        "-q",
    ];
    args.extend_from_slice(extra);
    mc_shard(&args)
}

#[test]
fn a_damaged_shard_is_quarantined_and_the_pool_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(30));
    let out = dir.path().join("shared");
    // Shard 1 of 3 (20..40) holds a line no crash produces: a corrupt line mid-file.
    std::fs::create_dir_all(&out).unwrap();
    let damaged = out.join(shard_record::ShardRange::new(20, 40).file_name());
    run_shard(&job, &out, "1/3");
    let text = std::fs::read_to_string(&damaged).unwrap();
    let mut lines: Vec<&str> = text.split_inclusive('\n').collect();
    lines.truncate(8);
    lines[4] = "{\"record\":\"sample\",\"index\":\n";
    std::fs::write(&damaged, lines.concat()).unwrap();

    let o = work(&job, &out, "3", &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains("1 shard(s) quarantined") && stderr.contains("shard 1:"),
        "{stderr}"
    );
    let actions: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let of = |i: u64| -> Vec<&str> {
        actions
            .iter()
            .filter(|a| a["shard"] == i)
            .map(|a| a["action"].as_str().unwrap())
            .collect()
    };
    assert_eq!(of(0), ["completed"]);
    assert_eq!(of(1), ["quarantined"]);
    assert_eq!(of(2), ["completed"]);
    let marker: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("quarantine/shard-1-of-3.json")).unwrap(),
    )
    .unwrap();
    assert!(
        marker["reason"]
            .as_str()
            .unwrap()
            .contains(":5: not a valid record"),
        "{marker}"
    );
    assert_eq!(
        std::fs::read_to_string(&damaged).unwrap(),
        lines.concat(),
        "left untouched"
    );
    assert!(
        !out.join("claims/shard-1-of-3.claim").exists(),
        "its claim is released"
    );

    // status lists it; --missing names it; a second worker skips it and exits 5 again.
    let status = |extra: &[&str]| {
        let mut args = vec![
            "status",
            "--job",
            job.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--shards",
            "3",
        ];
        args.extend_from_slice(extra);
        String::from_utf8(mc_shard(&args).stdout).unwrap()
    };
    assert!(
        status(&[]).contains("shard 1/3 20..40: quarantined: "),
        "{}",
        status(&[])
    );
    assert_eq!(status(&["--missing"]).trim(), "1");
    let json: serde_json::Value = serde_json::from_str(&status(&["--json"])).unwrap();
    assert_eq!(json["status"][1]["state"], "quarantined");
    assert_eq!(json["status"][0]["state"], "complete");
    let o = work(&job, &out, "3", &[]);
    assert_eq!(o.status.code(), Some(5));
    assert!(String::from_utf8_lossy(&o.stdout).contains(r#""action":"skipped-quarantined""#));

    // Another split on the same directory is refused before it claims anything.
    let o = work(&job, &out, "4", &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("3 shards") && stderr.contains("--shards 4"),
        "{stderr}"
    );
    assert!(!out.join("claims/shard-0-of-4.claim").exists());

    // Repaired (file moved away, marker deleted), the pool finishes.
    std::fs::remove_file(&damaged).unwrap();
    std::fs::remove_file(out.join("quarantine/shard-1-of-3.json")).unwrap();
    let o = work(&job, &out, "3", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(sample_lines(&out).len(), 60);
}

#[test]
fn a_worker_refuses_a_directory_of_another_split_and_absurd_durations() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(5));
    let out = dir.path().join("o");
    run_shard(&job, &out, "0/2");
    // No pool record yet, but a shard file of a 2-way split: a 3-way worker is refused.
    let o = work(&job, &out, "3", &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("not one of 3 shards"), "{stderr}");
    for (flag, value) in [
        ("--heartbeat", "1e300"),
        ("--heartbeat", "nan"),
        ("--stale-after", "0"),
        ("--heartbeat", "100"),
    ] {
        let o = work(&job, &out, "2", &[flag, value]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(stderr.contains(flag), "{stderr}");
    }
    assert_eq!(work(&job, &out, "0", &[]).status.code(), Some(2));
    let o = mc_shard(&[
        "run",
        "--job",
        job.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--threads",
        "5000",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--threads must be 1 to 1024"));
}

/// `inputs` writes the draws `reproduce --detail` shows, keyed by index, at full precision.
#[test]
fn inputs_regenerates_each_samples_draws() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(4));
    let csv = dir.path().join("inputs.csv");
    let o = mc_shard(&[
        "inputs",
        "--job",
        job.to_str().unwrap(),
        "--range",
        "2..7",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    let header = &rows[0];
    assert_eq!(&header[..3], ["index", "case", "sample"]);
    assert!(header[3..].iter().all(|h| h.starts_with("length_error:")));
    assert_eq!(rows.len(), 6, "five samples");
    assert_eq!(
        rows[1..]
            .iter()
            .map(|r| (r[0], r[1], r[2]))
            .collect::<Vec<_>>(),
        [
            ("2", "normal", "2"),
            ("3", "normal", "3"),
            ("4", "uniform", "0"),
            ("5", "uniform", "1"),
            ("6", "uniform", "2")
        ]
    );
    // Sample 1 of case "uniform" (index 5): the same numbers, bit for bit.
    let o = mc_shard(&[
        "reproduce",
        "--job",
        job.to_str().unwrap(),
        "--case",
        "uniform",
        "--sample",
        "1",
        "--detail",
    ]);
    let detail: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for (h, cell) in header[3..].iter().zip(&rows[4][3..]) {
        let id = h.strip_prefix("length_error:").unwrap();
        let drawn = detail["length_errors"][id].as_f64().unwrap();
        assert_eq!(
            cell.parse::<f64>().unwrap().to_bits(),
            drawn.to_bits(),
            "{id}"
        );
    }
    assert!(
        rows[4][3..]
            .iter()
            .any(|c| c.parse::<f64>().unwrap() != 0.0)
    );
}

/// Completions and man pages come from the same definitions as `--help`.
#[test]
fn completions_and_man_page() {
    for shell in ["bash", "zsh", "fish"] {
        let o = mc_shard(&["completions", shell]);
        assert!(o.status.success());
        let text = String::from_utf8(o.stdout).unwrap();
        assert!(
            text.contains("audit") && text.contains("heartbeat"),
            "{shell}"
        );
    }
    let o = mc_shard(&["man"]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.starts_with(".ie") || text.contains(".TH mc-shard"),
        "{}",
        &text[..200]
    );
    assert!(text.contains(".TH mc-shard-audit") && text.contains("Exit codes"));
    assert_eq!(mc_shard(&["completions", "tcsh"]).status.code(), Some(2));
}
