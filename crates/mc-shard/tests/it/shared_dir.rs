//! A shared run directory (crate `run-dir`): a shard's name, the quarantine and claims
//! directories and every file written never go through a planted link; a file at a shard's
//! name that is not a shard is refused, not truncated; `inputs -o` is written whole or not at
//! all; `audit` reads only regular files; a shard locked by a live process names it; a
//! shard with a second hard link is never resumed through it.

use crate::binary::mc_shard;
use crate::common::*;
use crate::hostile::{assert_untouched, code, fifo, precious, run_bounded, run_into_full};
use std::ffi::OsStr;
use std::path::Path;
use std::process::{Command, Output};

fn run_range(job: &Path, out: &Path, range: &str) -> Output {
    mc_shard(&[
        "run",
        "--job",
        job.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--range",
        range,
        "--threads",
        "1",
        "-q",
    ])
}

/// A link at the shard's name is refused (exit 5) naming it, and what it points at keeps its
/// bytes.
#[test]
fn a_link_at_a_shards_name_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let target = precious(dir.path());
    let out = dir.path().join("runs");
    std::fs::create_dir(&out).unwrap();
    let name = shard_record::ShardRange::new(0, 20).file_name();
    std::os::unix::fs::symlink(&target, out.join(&name)).unwrap();
    let (status, stderr) = code(&run_range(&job, &out, "0..20"));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains(&name) && stderr.contains("symbolic link"),
        "{stderr}"
    );
    assert_untouched(&target);
}

/// A regular file at a shard's name that does not begin with a begin record (one
/// unterminated line "my data") is not ours: refused (exit 5) and left as it is. An empty
/// file is still taken (nothing to lose), and the run completes.
#[test]
fn a_file_that_is_not_a_shard_is_refused_not_truncated() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let out = dir.path().join("runs");
    std::fs::create_dir(&out).unwrap();
    let path = out.join(shard_record::ShardRange::new(0, 20).file_name());
    for mine in ["my data", "my data\n", "{\"record\":\"sample\""] {
        std::fs::write(&path, mine).unwrap();
        let (status, stderr) = code(&run_range(&job, &out, "0..20"));
        assert_eq!(status, Some(5), "{mine:?}: {stderr}");
        assert!(stderr.contains(&path.display().to_string()), "{stderr}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), mine);
    }
    std::fs::write(&path, "").unwrap();
    let (status, stderr) = code(&run_range(&job, &out, "0..20"));
    assert_eq!(status, Some(0), "{stderr}");
    assert_eq!(sample_lines(&out).len(), 20);
}

/// A partial shard that is also a hard link of the user's backup copy is not resumed
/// through it (the backup would be cut and grown too): refused (exit 5) naming the file,
/// and the backup keeps its bytes.
#[test]
fn a_hard_linked_shard_is_not_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let out = dir.path().join("runs");
    let (status, stderr) = code(&run_range(&job, &out, "0..20"));
    assert_eq!(status, Some(0), "{stderr}");
    let path = out.join(shard_record::ShardRange::new(0, 20).file_name());
    let whole = std::fs::read_to_string(&path).unwrap();
    let partial: String = whole.split_inclusive('\n').take(6).collect();
    std::fs::write(&path, &partial).unwrap();
    let backup = dir.path().join("backup.jsonl");
    std::fs::hard_link(&path, &backup).unwrap();
    let (status, stderr) = code(&run_range(&job, &out, "0..20"));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains(&path.display().to_string()) && stderr.contains("hard links"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&backup).unwrap(), partial);
}

/// Shard 1 of 2 damaged, and `quarantine/` (or `claims/`) a link to another directory: the
/// worker refuses to write its marker (or claims) through the link, naming it (exit 5), and
/// nothing appears where the link points.
#[test]
fn linked_work_directories_are_refused() {
    for linked in ["quarantine", "claims"] {
        let dir = tempfile::tempdir().unwrap();
        let job = write(dir.path(), "job.json", &small_job(10));
        let out = dir.path().join("shared");
        std::fs::create_dir(&out).unwrap();
        // Shard 1 of 2 (10..20) is not a shard.
        let damaged = out.join(shard_record::ShardRange::new(10, 20).file_name());
        std::fs::write(&damaged, "{\"not\": \"a shard\"}\n").unwrap();
        let elsewhere = dir.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, out.join(linked)).unwrap();
        let o = mc_shard(&[
            "work",
            "--job",
            job.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--shards",
            "2",
            "--threads",
            "1",
            "-q",
        ]);
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(5), "{linked}: {stderr}");
        assert!(
            stderr.contains(&out.join(linked).display().to_string())
                && stderr.contains("symbolic link"),
            "{stderr}"
        );
        assert_eq!(
            std::fs::read_dir(&elsewhere).unwrap().count(),
            0,
            "{linked}"
        );
    }
}

/// `inputs -o` that fails part-way (a file-size limit, as a full disk) exits 4 and leaves
/// the file at its name as it was, with no temporary file behind; a link at that name is
/// refused (exit 5).
#[test]
fn inputs_are_written_whole_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(2000));
    let csv = dir.path().join("inputs.csv");
    std::fs::write(&csv, "old\n").unwrap();
    // SIGXFSZ ignored (as it is inherited across exec), so the write fails with EFBIG.
    let o = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 64; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_mc-shard"))
        .args(["inputs", "--job"])
        .arg(&job)
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    let (status, stderr) = code(&o);
    assert_eq!(status, Some(4), "{stderr}");
    assert!(stderr.contains("inputs.csv"), "{stderr}");
    let kept = std::fs::read_to_string(&csv).unwrap();
    assert!(
        kept == "old\n",
        "the old inputs.csv was replaced ({} bytes)",
        kept.len()
    );
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // Without the limit it is written; through a link it is not.
    let ok = mc_shard(&[
        "inputs",
        "--job",
        job.to_str().unwrap(),
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code(&ok).0, Some(0), "{}", code(&ok).1);
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 4001);
    let target = precious(dir.path());
    let link = dir.path().join("linked.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = mc_shard(&[
        "inputs",
        "--job",
        job.to_str().unwrap(),
        "-o",
        link.to_str().unwrap(),
    ]);
    assert_eq!(code(&o).0, Some(5), "{}", code(&o).1);
    assert_untouched(&target);
}

/// `audit` given `/dev/zero`, a link to it or a FIFO refuses it at once (exit 3), naming
/// it; a link at `audit.json` is refused (exit 5), not followed.
#[test]
fn audit_reads_only_regular_files_and_writes_no_link() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let link = dir.path().join("zero.jsonl");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let fifo = fifo(dir.path(), "fifo.jsonl");
    for path in [Path::new("/dev/zero"), &link, &fifo] {
        let args = [
            OsStr::new("audit"),
            "--job".as_ref(),
            job.as_os_str(),
            path.as_os_str(),
        ];
        let (status, stderr) = run_bounded(Path::new(env!("CARGO_BIN_EXE_mc-shard")), &args);
        assert_eq!(status, Some(3), "{}: {stderr}", path.display());
        assert!(
            stderr.contains(&path.display().to_string()) && stderr.contains("not a regular file"),
            "{stderr}"
        );
    }
    let out = dir.path().join("runs");
    assert_eq!(code(&run_range(&job, &out, "0..20")).0, Some(0));
    let target = precious(dir.path());
    std::os::unix::fs::symlink(&target, out.join("audit.json")).unwrap();
    let o = mc_shard(&[
        "audit",
        "--job",
        job.to_str().unwrap(),
        out.to_str().unwrap(),
        "--samples",
        "3",
    ]);
    assert_eq!(code(&o).0, Some(5), "{}", code(&o).1);
    assert_untouched(&target);
}

/// A shard whose lock another process holds is refused (exit 5) with that process's pid and
/// the advice to wait for it or stop it.
#[test]
fn a_live_lock_names_its_holder() {
    let dir = tempfile::tempdir().unwrap();
    let job = write(dir.path(), "job.json", &small_job(10));
    let out = dir.path().join("runs");
    std::fs::create_dir(&out).unwrap();
    let path = out.join(shard_record::ShardRange::new(0, 20).file_name());
    let held = std::fs::File::create(&path).unwrap();
    held.lock().unwrap();
    let (status, stderr) = code(&run_range(&job, &out, "0..20"));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "another process is writing this shard (pid {}): wait for it or stop it",
            std::process::id()
        )),
        "{stderr}"
    );
    drop(held);
    assert_eq!(code(&run_range(&job, &out, "0..20")).0, Some(0));
}

/// A completion script or man page that cannot be written (`/dev/full`) is an I/O error
/// (exit 4), not a panic (clap's generator panics when its writer fails).
#[test]
fn unwritable_output_is_an_io_error() {
    for args in [["completions", "bash"].as_slice(), ["man"].as_slice()] {
        let (status, stderr) = run_into_full(Path::new(env!("CARGO_BIN_EXE_mc-shard")), args);
        assert_eq!(status, Some(4), "{args:?}: {stderr}");
        assert!(stderr.starts_with("mc-shard: error: "), "{stderr}");
    }
}
