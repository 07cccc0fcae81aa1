//! Files in a shared run directory (crate `run-dir`): `truss diagnose` and `truss tolerance`
//! never write through a planted link, and refuse it before any work; files named on the
//! command line are read only if they are regular files; output that cannot be written is
//! an I/O error.

use crate::truss;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn code(o: &Output) -> (Option<i32>, String) {
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn job_path() -> &'static str {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../jobs/diagnose-baseline.json"
    )
}

/// A file outside the output directory that a planted link points at.
fn precious(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("precious.txt");
    std::fs::write(&p, "the user's own file").unwrap();
    p
}

fn untouched(p: &Path) {
    assert_eq!(std::fs::read_to_string(p).unwrap(), "the user's own file");
}

/// Measured data of 30 specimens, as `synth-measured` writes it.
fn measured(dir: &Path) -> std::path::PathBuf {
    let out = truss(&[
        "synth-measured",
        "--job",
        job_path(),
        "--case",
        "as-built",
        "--specimens",
        "30",
        "--seed",
        "3",
        "--effect",
        "none",
        "--measurement-sigma",
        "0.001",
    ]);
    assert!(out.status.success(), "{}", code(&out).1);
    let path = dir.join("m.csv");
    std::fs::write(&path, out.stdout).unwrap();
    path
}

/// Runs `truss` with `args` under a 2 GB address-space limit and a 30 s deadline.
fn truss_bounded(args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2000000; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_truss"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            panic!("truss {args:?} did not finish in 30 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    code(&child.wait_with_output().unwrap())
}

/// A link at `diagnosis.md` or at a diagnosis plot's name is refused (exit 5), naming it,
/// before the diagnosis runs; what it points at keeps its bytes.
#[test]
fn diagnose_never_writes_through_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let target = precious(dir.path());
    let m = measured(dir.path());
    for name in ["diagnosis.md", "theta_p-ecdf-before.svg"] {
        let out = dir.path().join(format!("out-{name}"));
        std::fs::create_dir(&out).unwrap();
        std::os::unix::fs::symlink(&target, out.join(name)).unwrap();
        let started = Instant::now();
        let o = truss(&[
            "diagnose",
            "--job",
            job_path(),
            "--case",
            "as-built",
            "--measured",
            m.to_str().unwrap(),
            "--measurement-sigma",
            "0.001",
            "--samples",
            "400",
            "--out",
            out.to_str().unwrap(),
        ]);
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(5), "{name}: {stderr}");
        assert!(
            stderr.contains(name) && stderr.contains("symbolic link"),
            "{stderr}"
        );
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "refused before the work"
        );
        untouched(&target);
    }
}

/// `--measured` and `--measured-members` as a FIFO, `/dev/zero` or a link to it are refused
/// at once (invalid input, exit 3), naming the file.
#[test]
fn diagnose_reads_only_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let m = measured(dir.path());
    let fifo = dir.path().join("fifo.csv");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let zero = dir.path().join("zero.csv");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let out = dir.path().join("d");
    for bad in [fifo.as_path(), Path::new("/dev/zero"), zero.as_path()] {
        for (flag, measured) in [("--measured", bad), ("--measured-members", bad)] {
            let measured_arg = if flag == "--measured" {
                bad
            } else {
                m.as_path()
            };
            let mut args = vec![
                "diagnose",
                "--job",
                job_path(),
                "--case",
                "as-built",
                "--measured",
                measured_arg.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ];
            if flag == "--measured-members" {
                args.extend(["--measured-members", measured.to_str().unwrap()]);
            }
            let (status, stderr) = truss_bounded(&args);
            assert_eq!(status, Some(3), "{flag} {}: {stderr}", bad.display());
            assert!(
                stderr.contains(&bad.display().to_string())
                    && stderr.contains("not a regular file"),
                "{stderr}"
            );
        }
    }
}

/// A link at `tolerance.md` is refused (exit 5) before the study runs; a FIFO given as the
/// job is refused at once (exit 3), as every job reader refuses it.
#[test]
fn tolerance_never_writes_through_a_link_nor_reads_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let target = precious(dir.path());
    let job = dir.path().join("job.json");
    std::fs::write(
        &job,
        r#"{"model": {"prism": {"stages": 1}}, "seed": 1, "cases": [{"name": "c", "samples": 1000,
  "length_errors": {"batten": {"normal": {"sigma": 0.01}}, "longeron": {"normal": {"sigma": 0.01}}}}]}"#,
    )
    .unwrap();
    let out = dir.path().join("t");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&target, out.join("tolerance.md")).unwrap();
    let args = |job: &Path| {
        vec![
            "tolerance".to_string(),
            "--job".into(),
            job.display().to_string(),
            "--case".into(),
            "c".into(),
            "--target-arcsec".into(),
            "20".into(),
            "--samples".into(),
            "1000".into(),
            "--sensitivity-samples".into(),
            "1000".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let started = Instant::now();
    let a = args(&job);
    let (status, stderr) = truss_bounded(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(status, Some(5), "{stderr}");
    assert!(
        stderr.contains("tolerance.md") && stderr.contains("symbolic link"),
        "{stderr}"
    );
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "refused before the work"
    );
    untouched(&target);
    std::fs::remove_file(out.join("tolerance.md")).unwrap();
    let fifo = dir.path().join("job.fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let a = args(&fifo);
    let (status, stderr) = truss_bounded(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(status, Some(3), "{stderr}");
    assert!(stderr.contains("not a regular file"), "{stderr}");
}

/// Output that cannot be written (`/dev/full`) is an I/O error (exit 4) for a result and
/// for a completion script alike (clap's generator used to panic, 101, in the other
/// binaries: see their tests).
#[test]
fn unwritable_output_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("p.json");
    std::fs::write(&model, truss(&["model", "prism", "--stages", "1"]).stdout).unwrap();
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    for args in [
        vec!["solve", model.to_str().unwrap()],
        vec!["completions", "bash"],
        vec!["man"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_truss"))
            .args(&args)
            .stdout(full())
            .output()
            .unwrap();
        let (status, stderr) = code(&o);
        assert_eq!(status, Some(4), "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("truss: error: cannot write output"),
            "{stderr}"
        );
    }
}
