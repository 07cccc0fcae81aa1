//! The cron round script, `scripts/cron/work.sh`, run as cron would (the real script, real
//! worker processes and file locks): a damaged shard is quarantined while the other shards
//! complete and the round exits 5; once the damage is moved away the next round finishes the
//! pool, audits and merges once; a further round does nothing.
//!
//! Like the README test, it uses the binaries `cargo test --workspace` builds beside this
//! test's executable.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().unwrap().parent().unwrap().join(name);
    assert!(
        path.exists(),
        "{} not built: run `cargo test --workspace` (it builds every binary)",
        path.display()
    );
    path
}

fn round(job: &Path, dir: &Path) -> Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/cron/work.sh");
    Command::new(script)
        .arg(job)
        .arg(dir)
        .args(["3", "--threads", "1"])
        .env("MC_SHARD", binary("mc-shard"))
        .env("MC_MERGE", binary("mc-merge"))
        .output()
        .unwrap()
}

#[test]
fn cron_rounds_quarantine_damage_then_finish_audit_and_merge_once() {
    let tmp = tempfile::tempdir().unwrap();
    let job = tmp.path().join("job.json");
    std::fs::write(
        &job,
        r#"{"model": {"prism": {"stages": 2}}, "seed": 5, "cases": [
  {"name": "a", "samples": 60,
   "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}}}]}"#,
    )
    .unwrap();
    let dir = tmp.path().join("shared");
    std::fs::create_dir_all(&dir).unwrap();
    // Shard 1 of 3 (20..40): a header and a line no crash produces.
    let damaged = dir.join("shard-0000000020-0000000040.jsonl");
    std::fs::write(&damaged, "garbage\n{\"record\":\"sample\"}\n").unwrap();

    let o = round(&job, &dir);
    let log = std::fs::read_to_string(dir.join("work.log")).unwrap();
    assert_eq!(o.status.code(), Some(5), "{log}");
    assert!(log.contains(r#""action":"quarantined""#), "{log}");
    assert!(log.contains("1 shard(s) quarantined"), "{log}");
    assert_eq!(log.matches(r#""action":"completed""#).count(), 2, "{log}");
    assert!(!dir.join("report").exists());

    std::fs::remove_file(&damaged).unwrap();
    std::fs::remove_file(dir.join("quarantine/shard-1-of-3.json")).unwrap();
    let o = round(&job, &dir);
    let log = std::fs::read_to_string(dir.join("work.log")).unwrap();
    assert!(o.status.success(), "{log}");
    assert!(log.contains("audit: 32 of 60 sample lines"), "{log}");
    assert!(dir.join("report/report.json").exists());
    assert!(dir.join("audit.json").exists());

    let before = log.len();
    let o = round(&job, &dir);
    assert!(o.status.success());
    let log = std::fs::read_to_string(dir.join("work.log")).unwrap();
    assert!(
        !log[before..].contains("audit"),
        "merged once: {}",
        &log[before..]
    );
}

/// A link planted at the round's own files (`work.log`, `merge.lock`) or at `report` in the
/// shared directory: the round refuses it (exit 5), naming it, and writes nothing through
/// it (the shell's `>>` and `>` follow links; `merge.lock` used to truncate its target).
#[test]
fn cron_rounds_write_nothing_through_a_link() {
    let tmp = tempfile::tempdir().unwrap();
    let job = tmp.path().join("job.json");
    std::fs::write(
        &job,
        r#"{"model": {"prism": {"stages": 1}}, "seed": 5, "cases": [
  {"name": "a", "samples": 6,
   "length_errors": {"batten": {"normal": {"sigma": 0.0063}}}}]}"#,
    )
    .unwrap();
    let target = tmp.path().join("precious.txt");
    for name in ["work.log", "merge.lock", "report"] {
        std::fs::write(&target, "the user's own file").unwrap();
        let dir = tmp.path().join(format!("shared-{name}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::os::unix::fs::symlink(&target, dir.join(name)).unwrap();
        let o = round(&job, &dir);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(5), "{name}: {stderr}");
        assert!(
            stderr.contains(name) && stderr.contains("symbolic link"),
            "{stderr}"
        );
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "the user's own file",
            "{name}"
        );
    }
}
