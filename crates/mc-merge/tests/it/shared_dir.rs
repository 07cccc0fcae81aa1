//! A shared run directory (crate `run-dir`): no output goes through a planted link, a rerun
//! removes only files it wrote, the export never lands on the shards, two merges into one
//! directory do not mix, files named on the command line are read only if they are regular
//! files, and a θ_P that cannot be an angle is refused naming its line.

use crate::common::{SynthCase, SynthJob};
use crate::hostile::{assert_untouched, code, fifo, precious, run_bounded, run_into_full};
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn job(seed: u64) -> SynthJob {
    SynthJob::new(
        seed,
        vec![SynthCase::rayleigh("a", 200, 3e-5, &[("stages", 5.0)])],
    )
}

fn mc_merge(args: &[&Path], extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mc-merge"))
        .args(args)
        .args(["--replicates", "50", "--gof-replicates", "19"])
        .args(extra)
        .output()
        .unwrap()
}

fn merge_into(shards: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut all = vec!["--out", out.to_str().unwrap()];
    all.extend_from_slice(extra);
    mc_merge(&[shards], &all)
}

/// A link named like a plot, in a new report directory or in one mc-merge wrote before, is
/// refused naming it (exit 5), and the file it points at keeps its bytes; so is a link
/// named `report.json`, `report.md` or `report.html`.
#[test]
fn links_named_like_outputs_are_refused() {
    let shards = tempfile::tempdir().unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let target = precious(elsewhere.path());
    job(1).write_split(shards.path(), 1);
    for (name, merged_before) in [
        ("theta_p-a.svg", false),
        ("qq-a.png", true),
        ("report.json", false),
        ("report.md", false),
        ("report.html", true),
    ] {
        let out = tempfile::tempdir().unwrap();
        if merged_before {
            assert_eq!(code(&merge_into(shards.path(), out.path(), &[])).0, Some(0));
            std::fs::remove_file(out.path().join(name)).unwrap();
        }
        std::os::unix::fs::symlink(&target, out.path().join(name)).unwrap();
        let (status, stderr) = code(&merge_into(shards.path(), out.path(), &[]));
        assert_eq!(status, Some(5), "{name}: {stderr}");
        assert!(stderr.contains(name), "{stderr}");
        assert_untouched(&target);
    }
}

/// A merge run again removes only the files it wrote: a user's `theta_p-annotated.svg` and
/// `qq-notes.png` and a diagnosis's `theta_p-ecdf-before.svg` in the report directory stay,
/// with plots and without.
#[test]
fn a_rerun_removes_only_its_own_files() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(2).write_split(shards.path(), 1);
    assert_eq!(code(&merge_into(shards.path(), out.path(), &[])).0, Some(0));
    let theirs = [
        "theta_p-annotated.svg",
        "qq-notes.png",
        "theta_p-ecdf-before.svg",
    ];
    for name in theirs {
        std::fs::write(out.path().join(name), "not mc-merge's").unwrap();
    }
    for extra in [&[][..], &["--no-plots"][..]] {
        let (status, stderr) = code(&merge_into(shards.path(), out.path(), extra));
        assert_eq!(status, Some(0), "{stderr}");
        for name in theirs {
            let text = std::fs::read_to_string(out.path().join(name)).unwrap();
            assert_eq!(text, "not mc-merge's", "{name}");
        }
    }
    // Our own earlier plots went with --no-plots.
    assert!(!out.path().join("theta_p-a.svg").exists());
    assert!(out.path().join("report.json").exists());
}

/// `--export` onto an input shard, or into a directory scanned for shards, is refused
/// (usage, exit 2) before anything is written; the shards still merge.
#[test]
fn exports_never_land_on_the_shards() {
    let shards = tempfile::tempdir().unwrap();
    let files = job(3).write_split(shards.path(), 2);
    let before: Vec<Vec<u8>> = files.iter().map(|f| std::fs::read(f).unwrap()).collect();
    let into_dir = shards.path().join("samples.jsonl");
    let into_dir_csv = shards.path().join("samples.csv");
    for (inputs, export) in [
        (
            vec![files[0].as_path(), files[1].as_path()],
            files[1].as_path(),
        ),
        (vec![shards.path()], files[0].as_path()),
        (vec![shards.path()], into_dir.as_path()),
        (vec![shards.path()], into_dir_csv.as_path()),
    ] {
        let o = mc_merge(&inputs, &["--export", export.to_str().unwrap()]);
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(2), "{}: {stderr}", export.display());
        assert!(stderr.contains("--export"), "{stderr}");
        assert!(!into_dir.exists() && !into_dir_csv.exists());
    }
    let after: Vec<Vec<u8>> = files.iter().map(|f| std::fs::read(f).unwrap()).collect();
    assert_eq!(before, after);
    let out = tempfile::tempdir().unwrap();
    assert_eq!(code(&merge_into(shards.path(), out.path(), &[])).0, Some(0));
}

/// The export's temporary file has an unpredictable name: a link planted at the old fixed
/// name `samples.csv.partial` is not followed, and a link at the export's own name is
/// refused (exit 5), its target untouched.
#[test]
fn the_export_never_writes_through_a_link() {
    let shards = tempfile::tempdir().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let target = precious(elsewhere.path());
    job(4).write_split(shards.path(), 1);
    let csv = dir.path().join("samples.csv");
    std::os::unix::fs::symlink(&target, dir.path().join("samples.csv.partial")).unwrap();
    let o = mc_merge(&[shards.path()], &["--export", csv.to_str().unwrap()]);
    assert_eq!(code(&o).0, Some(0), "{}", code(&o).1);
    assert_untouched(&target);
    assert!(std::fs::read_to_string(&csv).unwrap().starts_with("index,"));
    std::fs::remove_file(&csv).unwrap();
    std::os::unix::fs::symlink(&target, &csv).unwrap();
    let (status, stderr) = code(&mc_merge(
        &[shards.path()],
        &["--export", csv.to_str().unwrap()],
    ));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(stderr.contains("samples.csv"), "{stderr}");
    assert_untouched(&target);
}

/// A report directory being written by another process is refused at once (exit 5),
/// naming the holder's pid; two merges started together into one directory each either
/// finish or are refused so, and leave a complete report.
#[test]
fn one_merge_at_a_time_per_report_directory() {
    let shards = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    job(5).write_split(shards.path(), 1);
    let lock = std::fs::File::create(out.path().join(".truss-mc.lock")).unwrap();
    lock.lock().unwrap();
    let (status, stderr) = code(&merge_into(shards.path(), out.path(), &[]));
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "another process is writing this directory (pid {}): wait for it or stop it",
            std::process::id()
        )),
        "{stderr}"
    );
    assert!(!out.path().join("report.json").exists());
    drop(lock);
    for _ in 0..2 {
        let start = || {
            Command::new(env!("CARGO_BIN_EXE_mc-merge"))
                .arg(shards.path())
                .args([
                    "--replicates",
                    "50",
                    "--gof-replicates",
                    "19",
                    "-q",
                    "--out",
                ])
                .arg(out.path())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (start(), start());
        let results = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
        for o in &results {
            let (status, stderr) = code(o);
            assert!(
                status == Some(0) || status == Some(5),
                "{status:?}: {stderr}"
            );
            if status == Some(5) {
                assert!(stderr.contains("wait for it or stop it"), "{stderr}");
            }
        }
        assert!(results.iter().any(|o| o.status.success()));
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["cases"][0]["name"], "a");
        for plot in ["theta_p-a.svg", "qq-a.png", "running-a.svg"] {
            assert!(out.path().join(plot).is_file(), "{plot}");
        }
    }
}

/// Runs mc-merge on `path`, bounded (see `hostile::run_bounded`).
fn merge_bounded(path: &Path) -> (Option<i32>, String) {
    run_bounded(Path::new(env!("CARGO_BIN_EXE_mc-merge")), &[path])
}

/// `/dev/zero`, a link to it and a FIFO named on the command line are refused at once
/// (invalid input, exit 3), naming the path.
#[test]
fn named_inputs_must_be_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("zero.jsonl");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let fifo = fifo(dir.path(), "fifo.jsonl");
    for path in [Path::new("/dev/zero"), &link, &fifo] {
        let (status, stderr) = merge_bounded(path);
        assert_eq!(status, Some(3), "{}: {stderr}", path.display());
        assert!(stderr.contains(&path.display().to_string()), "{stderr}");
        assert!(stderr.contains("not a regular file"), "{stderr}");
    }
    // A regular file of 8 GiB of zeros (sparse) after a shard's begin line is refused at its
    // second line, which is longer than a shard line may be (shard_record::MAX_LINE_BYTES),
    // not read into memory.
    let j = job(7);
    let range = shard_record::ShardRange::new(0, j.samples());
    let bytes = j.shard_bytes(range);
    let header = &bytes[..=bytes.iter().position(|&b| b == b'\n').unwrap()];
    let sparse = dir.path().join(range.file_name());
    std::fs::write(&sparse, header).unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&sparse)
        .unwrap()
        .set_len(8 << 30)
        .unwrap();
    let (status, stderr) = merge_bounded(&sparse);
    assert_eq!(status, Some(6), "{stderr}");
    assert!(stderr.contains(":2: a line longer than"), "{stderr}");
}

/// A θ_P outside [0, π/2] in a line whose digests were recomputed (so the file verifies on
/// its own) is refused (exit 6), naming the file and the line.
#[test]
fn angles_outside_a_right_angle_are_refused_naming_the_line() {
    let j = job(6);
    for bad in [1e308, 2.0] {
        let shards = tempfile::tempdir().unwrap();
        let range = shard_record::ShardRange::new(0, j.samples());
        let bytes = j.shard_bytes_with(range, |s| {
            if s.index == 5 {
                s.theta_p = Some(bad);
            }
        });
        let path = SynthJob::write_bytes(shards.path(), &range.file_name(), &bytes);
        let (status, stderr) = code(&mc_merge(&[shards.path()], &[]));
        assert_eq!(status, Some(6), "{stderr}");
        assert!(
            stderr.contains(&format!("{}:7:", path.display())),
            "{stderr}"
        );
        assert!(stderr.contains("theta_p"), "{stderr}");
    }
}

/// A completion script or man page that cannot be written (`/dev/full`) is an I/O error
/// (exit 4), not a panic (clap's generator panics when its writer fails).
#[test]
fn unwritable_output_is_an_io_error() {
    for args in [["completions", "bash"].as_slice(), ["man"].as_slice()] {
        let (status, stderr) = run_into_full(Path::new(env!("CARGO_BIN_EXE_mc-merge")), args);
        assert_eq!(status, Some(4), "{args:?}: {stderr}");
        assert!(stderr.starts_with("mc-merge: error: "), "{stderr}");
    }
}
